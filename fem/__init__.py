"""Finite-element stage: layered model, mesh, solver, indentation and receptor analysis.

`from fem import Model, Material` loads the solver lazily, so `import fem` stays light.
"""
from common.errors import InputError

__all__ = ["InputError", "Model", "Material", "Solution", "LinearSystem", "MEASURES"]

_LAZY = {"Model": "fem.solver", "Solution": "fem.fields", "LinearSystem": "fem.system",
         "Material": "fem.materials", "MEASURES": "fem.measures"}


def __getattr__(name):
    if name in _LAZY:
        import importlib

        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'fem' has no attribute '{name}'")
