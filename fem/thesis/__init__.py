"""The source thesis, claim by claim: what a claim becomes when run (Finding), the Workshop that
meshes the models the claims run on, and the claims of chapter 4 (the 2D models), appendices A-B
and chapters 5-7 (the 3D models), listed in thesis order.

Modules: findings (Check, Finding, Workshop, the mesh levels), quotes (the thesis's words per
finding), claims (CLAIMS, NOT_RUN), chapter4_mechanics (4.1, 4.6,
4.7, appendices), chapter4_receptors (4.2-4.4), chapter4_gratings (4.5), chapters5_7.
"""
from fingertip.lazy import lazy_exports

_EXPORTS = {
    "Finding": "fem.thesis.findings", "Series": "fem.thesis.findings", "Workshop": "fem.thesis.findings",
    "REPRODUCED": "fem.thesis.findings", "DIFFERS": "fem.thesis.findings", "UNCERTAIN": "fem.thesis.findings",
    "Check": "fem.thesis.findings", "MeshLevel": "fem.thesis.findings", "LEVELS": "fem.thesis.findings",
    "levels": "fem.thesis.findings", "with_coarse": "fem.thesis.findings", "QUOTES": "fem.thesis.quotes",
    "CLAIMS": "fem.thesis.claims",
    "NOT_RUN": "fem.thesis.claims"
}
"""Public name -> the module that defines it (imported at first use: `fingertip.lazy`)."""
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
