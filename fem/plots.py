"""Every figure the FE stage writes, drawn on `matplotlib.figure.Figure` objects (no pyplot, no
global backend switch: importing or calling this module changes no matplotlib state).

Each `*_figure` function takes result objects and arrays and returns a Figure; `save` writes one.
"""
from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure


def save(fig: Figure, path, dpi: int = 110) -> None:
    """Lay out and write a figure (PNG by the path's suffix)."""
    fig.tight_layout()
    fig.savefig(path, dpi=dpi)


# --------------------------------------------------------------------------- indentation runs


# --------------------------------------------------------------------------- biomechanics


# --------------------------------------------------------------------------- receptor analysis
