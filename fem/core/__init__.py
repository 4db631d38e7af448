"""The finite-element method itself: materials, the mesh's discretisation, the material-bearing
model with its stiffness and factorised systems, fields and measures at points, the sparse
linear algebra (PARDISO), the large-deformation neo-Hookean solver, and viscoelastic layers.

Modules: materials (Material, the mABCDE code), discretisation (P2/P1 spaces of a mesh), model
(Model), system (LinearSystem), linalg (PARDISO, SaddleFactor, BLAS threads), fields (Solution,
point operators), measures (MEASURES), neohookean (NeoHookean), viscoelastic (Prony).
"""
from fingertip.lazy import lazy_exports

_EXPORTS = {
    "Material": "fem.core.materials", "DEFAULT_CODE": "fem.core.materials", "DEFAULT_NU": "fem.core.materials",
    "BONE_LAYER": "fem.core.materials", "FLUID_LAYER": "fem.core.materials",
    "Discretisation": "fem.core.discretisation", "SurfaceNodes": "fem.core.discretisation",
    "Model": "fem.core.model", "LinearSystem": "fem.core.system", "Solution": "fem.core.fields",
    "MEASURES": "fem.core.measures", "State": "fem.core.measures", "SaddleFactor": "fem.core.linalg",
    "blas_threads": "fem.core.linalg", "NeoHookean": "fem.core.neohookean",
    "NonlinearResult": "fem.core.neohookean", "Prony": "fem.core.viscoelastic"
}
"""Public name -> the module that defines it (imported at first use: `fingertip.lazy`)."""
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
