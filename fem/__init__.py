"""Finite-element stage: layered model, mesh, solver, indentation and receptor analysis."""
from reconstruct.errors import InputError

__all__ = ["InputError"]
