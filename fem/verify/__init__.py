"""References the solver is verified against: closed-form elasticity solutions (Hertz, Lame,
Flamant, Boussinesq, Sneddon, the waterbed and beam profiles of thesis 6.2) with the structured
meshes they are checked on, a half-space block under a flat punch, and the work of an indentor
(what frictionless contact stores).

Modules: closed_forms, halfspace (flat_block_model), energy (indentation_work_Nmm).
"""
from fingertip.lazy import lazy_exports

_EXPORTS = {
    "hertz_sphere": "fem.verify.closed_forms", "hertz_cylinder": "fem.verify.closed_forms",
    "lame_sphere": "fem.verify.closed_forms", "flamant": "fem.verify.closed_forms",
    "boussinesq": "fem.verify.closed_forms", "sneddon_punch_force_N": "fem.verify.closed_forms",
    "waterbed_deflection": "fem.verify.closed_forms", "beam_deflection": "fem.verify.closed_forms",
    "flat_block_model": "fem.verify.halfspace", "indentation_work_Nmm": "fem.verify.energy",
}
"""Public name -> the module that defines it (imported at first use: `fingertip.lazy`)."""
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
