"""Frictionless contact of rigid indentors with the linear elastic body: the indentor catalogue
as height profiles, the compliance of the contact candidates, and the contact solver (one LCP
per indentation; force control, sweeps).

Modules: indentors (make_indentor, the thesis catalogue), compliance (condensed and lazy
compliance), facets (the surface's areas, pressure recovery and node neighbours), linear
(ContactModel, solve_lcp, reach).
"""
from fingertip.lazy import lazy_exports

_EXPORTS = {
    "make_indentor": "fem.contact.indentors", "CYLINDERS_MM": "fem.contact.indentors",
    "approach_direction": "fem.contact.indentors", "orientation_deg": "fem.contact.indentors",
    "ContactModel": "fem.contact.linear", "ContactResult": "fem.contact.linear", "reach": "fem.contact.linear",
    "MAX_DEPTH_MM": "fem.contact.linear"
}
"""Public name -> the module that defines it (imported at first use: `fingertip.lazy`)."""
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
