"""Tangent-envelope axial sections (thesis 5.1.3).

At an axial position each view gives two border points; their distances from the axis are the
support function h(phi) of the section in two opposite directions: a tangent line
{p : p . n(phi) = h(phi)}. All tangents bound a convex polygon; the section is the smooth closed
curve tangent to all its sides, built from a Fourier fit of h (a smooth support function):
x = h cos(phi) - h'(phi) sin(phi), y = h sin(phi) + h'(phi) cos(phi).
Concavities (nail fold, ridges) cannot be seen: the result is the convex hull of the section.

View geometry (see reconstruct.synthetic): at view angle theta (relative to the volar view),
the right border lies at distance h(pi - theta) and the left border at h(-theta).
"""
from __future__ import annotations

import numpy as np
from scipy.optimize import linprog
from scipy.signal import savgol_filter
from scipy.spatial import ConvexHull, HalfspaceIntersection

from fingertip.errors import InputError

N_POINTS = 360            # points per output section (uniform in the normal angle)


def support_samples(left_u: np.ndarray, right_u: np.ndarray, theta_deg: np.ndarray):
    """Tangent directions phi (2n,) rad and support values h (2n, m) mm from border positions.

    left_u, right_u: (n_views, m) border u (mm, axis frame) at m axial positions;
    theta_deg: (n_views,) view angles relative to the volar view.
    """
    t = np.deg2rad(theta_deg)
    phi = np.mod(np.concatenate([np.pi - t, -t]), 2 * np.pi)
    return phi, np.vstack([right_u, -left_u])


def _design(phi: np.ndarray, k_max: int, deriv: int = 0) -> np.ndarray:
    """(len(phi), 2 k_max + 1) Fourier basis [1, cos k phi, sin k phi] or its derivative."""
    cols = [np.full_like(phi, 1.0 if deriv == 0 else 0.0)]
    for k in range(1, k_max + 1):
        c, s = np.cos(k * phi), np.sin(k * phi)
        if deriv == 0:
            cols += [c, s]
        elif deriv == 1:
            cols += [-k * s, k * c]
        else:
            cols += [-k * k * c, -k * k * s]
    return np.column_stack(cols)


def harmonics_for(phi: np.ndarray) -> int:
    """Highest harmonic a set of tangent directions supports (about half the distinct ones)."""
    n_dir = len(np.unique(np.round(np.mod(phi, 2 * np.pi), 6)))
    if n_dir < 6:
        raise InputError(f"only {n_dir} distinct tangent directions: take more views")
    return min((n_dir - 1) // 2, 60)


def fit_support(phi: np.ndarray, h: np.ndarray, k_max: int, smooth: float = 1e-9) -> np.ndarray:
    """Fourier coefficients (2 k_max + 1, m) of h(phi) for m sections at once.

    Least squares with a small penalty smooth * k^4 on harmonic k >= 2 (tames noise in the
    highest harmonics without pulling the curve off its tangents).
    """
    a = _design(phi, k_max)
    k = np.concatenate([[0.0], np.repeat(np.arange(1, k_max + 1), 2)])
    penalty = smooth * len(phi) * np.where(k >= 2, k**4, 0.0)
    return np.linalg.solve(a.T @ a + np.diag(penalty), a.T @ h)


def support_values(coef: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """(m, len(phi)) support function of m sections (coefficients (2K+1, m)) in directions phi."""
    return (_design(phi, (coef.shape[0] - 1) // 2) @ coef).T


def support_curve(coef: np.ndarray, n_points: int = N_POINTS) -> np.ndarray:
    """(m, n_points, 2) closed CCW curves from support-function coefficients (2K+1, m)."""
    k_max = (coef.shape[0] - 1) // 2
    phi = np.linspace(0.0, 2 * np.pi, n_points, endpoint=False)
    h, dh = _design(phi, k_max) @ coef, _design(phi, k_max, 1) @ coef
    c, s = np.cos(phi)[:, None], np.sin(phi)[:, None]
    return np.stack([h * c - dh * s, h * s + dh * c], axis=-1).transpose(1, 0, 2)


def convex_section(curve: np.ndarray) -> np.ndarray:
    """The curve itself if it is convex (every point a hull vertex, in order), else its convex
    hull resampled by arc length to the same point count.

    A support function fitted to noisy data can have a slightly negative radius of curvature in
    places; the envelope curve then forms a tiny swallowtail, which the hull removes.
    """
    v = ConvexHull(curve).vertices                    # CCW
    if len(v) == len(curve) and np.all(np.diff(np.roll(v, -int(np.argmin(v)))) == 1):
        return curve
    closed = np.vstack([curve[v], curve[v[:1]]])
    arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(closed, axis=0), axis=1))])
    t = np.linspace(0.0, arc[-1], len(curve), endpoint=False)
    return np.column_stack([np.interp(t, arc, closed[:, 0]), np.interp(t, arc, closed[:, 1])])


def tangent_polygon(phi: np.ndarray, h: np.ndarray) -> np.ndarray:
    """(k, 2) CCW vertices of the polygon bounded by the tangent lines p . n(phi) <= h(phi)."""
    normals = np.column_stack([np.cos(phi), np.sin(phi)])
    halfspaces = np.column_stack([normals, -h])
    # the rotation axis (origin) is inside the section when every h > 0; else find a centre
    inner = np.zeros(2) if h.min() > 0 else _chebyshev_centre(normals, h)
    poly = HalfspaceIntersection(halfspaces, inner).intersections
    centre = poly.mean(axis=0)
    order = np.argsort(np.arctan2(poly[:, 1] - centre[1], poly[:, 0] - centre[0]))
    return poly[order]


def _chebyshev_centre(normals: np.ndarray, h: np.ndarray) -> np.ndarray:
    res = linprog([0, 0, -1], A_ub=np.column_stack([normals, np.ones(len(h))]), b_ub=h,
                  bounds=[(None, None), (None, None), (0, None)])
    if not res.success or res.x[2] <= 0:
        raise InputError("the tangent lines of a section enclose no area: check the view angles")
    return res.x[:2]


def choose_levels(s_mm: np.ndarray, h_fine: np.ndarray, spacing_mm=(0.5, 2.0),
                  tol_mm: float = 0.02) -> np.ndarray:
    """Axial positions of the sections between s_mm[0] and s_mm[-1].

    h_fine: (len(s_mm), n_dirs) support values on a fine uniform s grid. The spacing is chosen
    so that linear interpolation between sections errs by at most tol_mm
    (error ~ spacing^2 / 8 * |d2h/ds2|), clipped to spacing_mm = (min, max).
    """
    lo, hi = spacing_mm
    ds = s_mm[1] - s_mm[0]
    window = max(5, int(round(1.0 / ds)) | 1)                 # curvature measured over ~1 mm
    if len(s_mm) > window:
        curv = np.abs(savgol_filter(h_fine, window, 2, deriv=2, delta=ds, axis=0)).max(axis=1)
    else:
        curv = np.zeros(len(s_mm))
    want = np.clip(np.sqrt(8 * tol_mm / np.maximum(curv, 1e-12)), lo, hi)
    levels = [s_mm[0]]
    while levels[-1] < s_mm[-1] - 1e-9:
        here = levels[-1]
        step = hi
        # the smallest wanted spacing over the next interval decides
        while step > lo:
            seg = (s_mm >= here) & (s_mm <= here + step)
            if want[seg].min() >= step:
                break
            step = max(lo, step * 0.8)
        levels.append(min(here + step, s_mm[-1]))
    levels = np.array(levels)
    if len(levels) > 2 and levels[-1] - levels[-2] < lo:      # spread the short last gap evenly
        for k in range(2, len(levels)):                       # over the last k gaps
            if (levels[-1] - levels[-k - 1]) / k >= lo:
                levels[-k - 1:] = np.linspace(levels[-k - 1], levels[-1], k + 1)
                break
    return levels
