"""Measured biomechanics inputs: the CSV files of surface deflection profiles and force-depth
curves that material fits are fitted to (`fem.biomech.fit`). Deflection profiles (`read_deflection_csv` -> [fem.biomech.deflection.Profile])
and force-depth curves (`read_force_csv`); header optional (columns in any order when given), `#` comments allowed:

    deflection: distance_mm, deflection_mm, depth_mm   (distances increasing within each depth)
    force:      depth_mm, force_N                      (N per mm of thickness for 2D models)
"""
from __future__ import annotations

import numpy as np

from fem.biomech.deflection import Profile
from fingertip.errors import InputError
from fingertip.tables import read_numbers


def read_deflection_csv(path) -> list[Profile]:
    """Measured deflection profiles: CSV distance_mm, deflection_mm, depth_mm -> one Profile per
    depth (in order of depth). Distances must be >= 0 and strictly increasing within a depth."""
    t = read_numbers(path, ("distance_mm", "deflection_mm", "depth_mm"))
    if np.any(t[:, 0] < 0) or np.any(t[:, 2] <= 0):
        raise InputError(f"'{path}': distances must be >= 0 mm and depths > 0 mm")
    out = []
    for d in np.unique(t[:, 2]):
        rows = t[t[:, 2] == d]
        if len(rows) < 2:
            raise InputError(f"'{path}': depth {d:g} mm has a single point; give at least 2 per depth")
        bad = np.flatnonzero(np.diff(rows[:, 0]) <= 0)
        if bad.size:
            raise InputError(f"'{path}': distances are not increasing at depth {d:g} mm "
                             f"({rows[bad[0], 0]:g} then {rows[bad[0] + 1, 0]:g}); sort each depth's rows by distance")
        out.append(Profile(float(d), rows[:, 0], rows[:, 1]))
    return out


def read_force_csv(path) -> tuple[np.ndarray, np.ndarray]:
    """Measured force-depth curve: CSV depth_mm, force_N -> (depths (k,) mm, forces (k,) N)."""
    t = read_numbers(path, ("depth_mm", "force_N"))
    if np.any(t[:, 0] <= 0) or np.any(t[:, 1] < 0):
        raise InputError(f"'{path}': depths must be > 0 mm and forces >= 0 N")
    if np.any(np.diff(t[:, 0]) <= 0):
        raise InputError(f"'{path}': depths are not increasing; sort the rows by depth")
    return t[:, 0], t[:, 1]
