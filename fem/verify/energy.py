"""The work of a rigid indentor from its force-depth course: what frictionless quasi-static contact
stores as strain energy (the step table's `energy_Nmm`), with either kinematics.

    work = indentation_work_Nmm(depth_mm, force_N)      # (n,) N mm (2D: per mm of length)
    np.abs(work / energy_Nmm - 1).max()                 # the energy balance at every depth
"""
from __future__ import annotations

import numpy as np
from scipy.integrate import cumulative_simpson


def indentation_work_Nmm(depth_mm, force_N) -> np.ndarray:
    """(n,) integral of the force over depth from first touch (depth 0, force 0) to each of the
    increasing depths (n,) [mm] with their forces (n,) [N; N/mm in 2D], n >= 2. On [0, d1] the
    force is taken as the power law a d^p through the first two points (it starts from zero, where
    a trapezoid is 10-25 % off for 1 < p < 1.5), then cumulative Simpson."""
    d, f = np.asarray(depth_mm, float), np.asarray(force_N, float)
    p = np.log(f[1] / f[0]) / np.log(d[1] / d[0])
    return f[0] * d[0] / (p + 1.0) + np.r_[0.0, cumulative_simpson(f, x=d)]
