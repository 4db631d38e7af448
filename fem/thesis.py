"""The source thesis's claims (chapters 4-7) in thesis order, as run by `pipeline.py reproduce`
(commands/reproduce.py): each is a function of a `fem.findings.Workshop` returning `Finding`s;
fem.thesis2d holds chapter 4 and the appendices, fem.thesis3d chapters 5-7.
"""
from __future__ import annotations

from fem.thesis2d import appendices, cylinders, flamant_block, line_load_order
from fem.thesis3d import dorsal_half, layer_effects

#: (name, function, what it needs) in thesis order; `pipeline.py reproduce` runs them all.
CLAIMS = (("flamant", flamant_block), ("cylinders", cylinders), ("line_load", line_load_order),
          ("dorsal", dorsal_half), ("layers", layer_effects), ("appendices", appendices))

#: Thesis figures with no run here, and why.
NOT_RUN = (
    ("4.6, figure 4-26", "Predicted against recorded SA discharge under cylinders: the recordings "
     "(Srinivasan and LaMotte 1991) are printed as curves only."),
    ("4.7, figure 4-27 (data points)", "The monkey wedge data (Srinivasan 1989) are printed as points "
     "on a curve only; the model profiles are compared above."),
    ("5.2, figures 5-14 and 6-30", "Contact area against indentor diameter on the 3D human fingertip: "
     "the 3D cylinder series (`pipeline.py biomech cylinder-series`) is not part of this report yet."),
    ("6.3", "3D receptive-field maps over the pad: not part of this report yet."),
    ("7.1, figures 7-1 to 7-4", "2D section against 3D model comparison: not part of this report yet."),
)
