"""Shapes and meshes: the parametric presets, the layered fingertip model (thesis 6.1), its 3D
tetrahedral mesh, the 2D plane-strain meshes of thesis chapter 4, and the model folder built from
them.

Modules: presets (shapes with known sections), sections (sections.json and preset sections,
checked), layered (ModelParams, LayeredModel), mesh3d
(Sizing, pytetwild, the mesh cache), mesh2d (Sizing2D, Domain2D), build (MeshSpec, build_folder).
"""
from fingertip.lazy import lazy_exports

_EXPORTS = {
    "SHAPES": "fem.geometry.presets", "PRESETS_2D": "fem.geometry.presets",
    "make_shape": "fem.geometry.presets", "load_sections": "fem.geometry.sections",
    "preset_sections": "fem.geometry.sections", "ModelParams": "fem.geometry.layered",
    "LayeredModel": "fem.geometry.layered", "model_from_args": "fem.geometry.layered",
    "params_for": "fem.geometry.layered", "N_LAYERS": "fem.geometry.layered", "Sizing": "fem.geometry.mesh3d",
    "TetMesh": "fem.geometry.mesh3d", "Sizing2D": "fem.geometry.mesh2d", "Domain2D": "fem.geometry.mesh2d",
    "preset_domain": "fem.geometry.mesh2d", "section_domain": "fem.geometry.mesh2d",
    "MeshSpec": "fem.geometry.build", "build_folder": "fem.geometry.build",
    "SIZE_FIELDS": "fem.geometry.build"
}
"""Public name -> the module that defines it (imported at first use: `fingertip.lazy`)."""
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
