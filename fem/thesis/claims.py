"""The source thesis's claims (chapters 4-7) in thesis order, as run by `pipeline.py reproduce`
(fingertip/jobs/reproduce.py): each is a function of a `fem.thesis.findings.Workshop` returning `Finding`s;
fem.thesis.chapter4_mechanics (4.1, 4.6, 4.7 and the appendices), fem.thesis.chapter4_receptors (4.2-4.4) and
fem.thesis.chapter4_gratings (4.5) hold chapter 4, fem.thesis.chapters5_7 chapters 5-7, and
fem.thesis.kinematics the depth-dependent ones with finite kinematics.
"""
from __future__ import annotations

from fem.thesis.chapter4_gratings import aperiodic_gratings, gap_detection
from fem.thesis.chapter4_mechanics import (
          appendices,
          cylinders,
          flamant_block,
          line_load_order,
)
from fem.thesis.chapter4_receptors import (
          point_load_fields,
          rectangular_bars,
          two_point_resolution,
)
from fem.thesis.chapters5_7 import (
          bars_3d,
          contact_vs_diameter,
          dorsal_half,
          layer_effects,
          sections_2d_3d,
          steps_3d,
)
from fem.thesis.kinematics import finite_claims

#: (name, function) in thesis order, then the depth-dependent claims again with finite kinematics
#: (fem.thesis.kinematics); `pipeline.py reproduce` runs them all.
CLAIMS = (("flamant", flamant_block), ("receptive_fields", point_load_fields), ("two_point", two_point_resolution),
          ("bars", rectangular_bars), ("gratings", aperiodic_gratings), ("gaps", gap_detection),
          ("cylinders", cylinders), ("line_load", line_load_order),
          ("contact_3d", contact_vs_diameter), ("dorsal", dorsal_half), ("layers", layer_effects),
          ("bars_3d", bars_3d), ("steps_3d", steps_3d), ("sections_2d_3d", sections_2d_3d),
          ("appendices", appendices), ("kinematics", finite_claims))

#: Thesis figures with no run here, and why.
NOT_RUN = (
    ("4.5.2-4.5.3, figures 4-8, 4-11, 4-13 to 4-17, tables 4.1-4.4", "Recorded SA responses to "
     "gratings and the fits of each strain measure to them (Phillips and Johnson 1981): printed as "
     "curves only; the model-side statements are compared above."),
    ("4.5.5, figure 4-20", "Human gap-detection thresholds (d'): printed as curves only."),
    ("4.6, figure 4-26", "Predicted against recorded SA discharge under cylinders: the recordings "
     "(Srinivasan and LaMotte 1991) are printed as curves only."),
    ("4.7, figure 4-27 (data points)", "The monkey wedge data (Srinivasan 1989) are printed as points "
     "on a curve only; the model profiles are compared above."),
    ("6.2.2, 6.2.3, figures 6-15 to 6-23", "Surface profiles and forces of human fingertips in vivo "
     "under cylinders and flat indentors: the recordings are printed as curves only (`pipeline.py "
     "fit-material` fits a model to recorded profiles and forces)."),
    ("6.3.3, figures 6-31 to 6-35", "Surface, pressure and strain-energy maps under steps 1, 3 and 5 "
     "at chosen positions: pictures without numbers to compare; the step-5 sweep's contact area, "
     "peak pressure and the spatial response profiles of figs. 6-36 to 6-38 are compared above. "
     "`pipeline.py indent` with a step sweep and receptors writes the population response maps."),
    ("6.3.1, figures 6-26 to 6-28; 6.3.2, figure 6-29; 6.3.3, figure 6-40", "Predicted against recorded "
     "SA discharge under bars, cylinders and steps (Phillips and Johnson 1981, Srinivasan and LaMotte "
     "1987, 1991): the recordings are printed as curves only (`pipeline.py analyze` fits the receptor "
     "model to recorded rates)."),
)
