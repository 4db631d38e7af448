"""Biomechanical verification (thesis 4.7, 6.2, appendix B): surface deflection under a line
load, the layer study, material fits to measured deflection and force, cylinder series, and the
line load with large deformation.

Modules: deflection (DeflectionExperiment, layer_study, cylinder_series), fit (fit_material,
fit_force_scale), measured (the deflection and force CSVs), line_load (compare_line_load).
"""
from fingertip.lazy import lazy_exports

_EXPORTS = {
    "DeflectionExperiment": "fem.biomech.deflection", "Profile": "fem.biomech.deflection",
    "layer_study": "fem.biomech.deflection", "cylinder_series": "fem.biomech.deflection",
    "fit_material": "fem.biomech.fit", "fit_force_scale": "fem.biomech.fit",
    "read_deflection_csv": "fem.biomech.measured", "read_force_csv": "fem.biomech.measured",
    "compare_line_load": "fem.biomech.line_load"
}
"""Public name -> the module that defines it (imported at first use: `fingertip.lazy`)."""
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
