"""Finite-element stage: layered model, mesh, solver, indentation and receptor analysis.

`from fem import Model, Material` loads the solver lazily, so `import fem` stays light.
"""
from fingertip.errors import InputError

__all__ = ["InputError", "Model", "Material", "Solution", "LinearSystem", "MEASURES"]

_LAZY = {"Model": "fem.core.model", "Solution": "fem.core.fields", "LinearSystem": "fem.core.system",
         "Material": "fem.core.materials", "MEASURES": "fem.core.measures"}


def __getattr__(name):
    if name in _LAZY:
        import importlib

        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'fem' has no attribute '{name}'")
