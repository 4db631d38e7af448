"""Package faces whose names live in submodules and are imported at first use.

    _EXPORTS = {"Model": "fem.core.model", "Material": "fem.core.materials"}
    __all__ = sorted(_EXPORTS)
    __getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)

The science behind the faces takes 1.3 s to import in full; a face that imported it eagerly
would make every command, `--help` included, pay for all of it (a command needs 0.1-0.7 s).
"""
from __future__ import annotations

import importlib
import sys


def lazy_exports(package: str, names: dict[str, str]):
    """(__getattr__, __dir__) for a package: attribute `name` is `getattr(import_module(
    names[name]), name)`, imported on first access and then kept in the package."""
    def __getattr__(name):
        if name not in names:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(names[name]), name)
        setattr(sys.modules[package], name, value)
        return value

    def __dir__():
        return sorted(set(names) | set(vars(sys.modules[package])))

    return __getattr__, __dir__
