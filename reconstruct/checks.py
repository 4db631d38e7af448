"""Consistency of the sections before anything is written, and whether the parallel projection holds.

A section is refused when its outline folds back on itself (the fitted support function has a
negative radius of curvature beyond noise), when its tangents disagree (rms residual of the
support-function fit), or when its size jumps against its neighbours. Refused sections at either
end are trimmed with a warning naming the z range; one in the middle is an InputError.
"""
from __future__ import annotations

import numpy as np
from scipy.spatial import ConvexHull

from fingertip.errors import InputError
from reconstruct.calibrate import sample_borders
from reconstruct.camera import Camera, border_tables, perspective_fit, proximal_cut
from reconstruct.sections import (
    fit_support,
    support_curve,
    support_samples,
    support_values,
)

TANGENT_TOL_PX = 0.3        # rms disagreement of a section's tangents above which it is refused
FOLD_TOL_PX = 1.0           # depth of a fold of the outline (inside its own hull) that is refused
JUMP_TOL = 0.12             # relative size change against the neighbours' interpolation
PARALLEL_RMS_PX = 0.12      # median tangent disagreement that a parallel projection does not explain
CUT_TOL_PX = 1.0            # pinhole camera: the proximal cut is where the rim's disagreement ends
PARALLEL_ERR_PX = 0.5       # error of the parallel projection below which it is not worth a warning
CUT_SEARCH_PX = 40          # pinhole camera: how far below the first section the cut is sought
ROD_MARGIN_PX = 5           # rows skipped after the rod-to-finger step (blurred corner)


def fold_depth(curve: np.ndarray) -> float:
    """How far (same unit as curve (k, 2)) the outline runs inside its own convex hull: 0 for a
    convex curve, the depth of the swallowtail where it folds back on itself."""
    hull = ConvexHull(curve)
    d = -(curve @ hull.equations[:, :2].T + hull.equations[:, 2]).max(axis=1)
    return float(max(d.max(), 0.0))


def consistent_sections(z_mm: np.ndarray, curves: np.ndarray, rms_px: np.ndarray,
                        mm_per_px: float | None = None) -> tuple[np.ndarray, str | None]:
    """Which sections to keep (m,) bool and a warning naming what was trimmed (or None).

    z_mm: (m,) positions; curves: (m, k, 2) outlines from the support function (mm);
    rms_px: (m,) rms residual of each section's tangent fit in px.
    """
    m = len(z_mm)
    tol = max(TANGENT_TOL_PX, 4.0 * float(np.nanmedian(rms_px)))
    why = {}
    for i in range(m):
        if not np.isfinite(rms_px[i]) or rms_px[i] > tol:
            why[i] = f"tangents disagree by {rms_px[i]:.2f} px rms"
    px = mm_per_px if mm_per_px is not None else 1.0
    for i in range(m):
        if i not in why and fold_depth(curves[i]) > FOLD_TOL_PX * px:
            why[i] = "outline folds back on itself"
    size = np.sqrt(np.abs([0.5 * np.sum(c[:, 0] * np.roll(c[:, 1], -1) - c[:, 1] * np.roll(c[:, 0], -1))
                           for c in curves]))
    while True:               # the worst jump first, so that its neighbours are judged without it
        rest = np.array([i for i in range(m) if i not in why])
        if len(rest) < 3:
            break
        dev = np.zeros(len(rest))
        for j, i in enumerate(rest):
            a, b = (j - 1, j + 1) if 0 < j < len(rest) - 1 else ((1, 2) if j == 0 else (j - 2, j - 1))
            a, b = rest[a], rest[b]
            pred = size[a] + (size[b] - size[a]) * (z_mm[i] - z_mm[a]) / (z_mm[b] - z_mm[a])
            dev[j] = abs(size[i] - pred) / max(pred, 1e-9)
        if dev.max() <= JUMP_TOL:
            break
        why[int(rest[np.argmax(dev)])] = "size jumps against its neighbours"
    keep = np.ones(m, bool)
    if not why:
        return keep, None
    bad = np.zeros(m, bool)
    bad[list(why)] = True
    if bad.all():
        raise InputError(f"no consistent section ({why[0]} at z {z_mm[0]:.2f} mm): check the images "
                         f"and camera_distance_mm in turntable.toml")
    lo = int(np.argmax(~bad))
    hi = m - int(np.argmax(~bad[::-1]))
    if bad[lo:hi].any():
        i = lo + int(np.argmax(bad[lo:hi]))
        raise InputError(f"the section at z {z_mm[i]:.2f} mm is inconsistent ({why[i]}): check that view "
                         f"images and angles belong together, and camera_distance_mm in turntable.toml")
    keep[:lo] = False
    keep[hi:] = False
    parts = [f"z {z_mm[a]:.2f} .. {z_mm[b]:.2f} mm ({why[a]})" for a, b in ((0, lo - 1), (hi, m - 1)) if b >= a]
    return keep, "sections dropped as inconsistent: " + "; ".join(parts)


def check_parallel(views, frame, theta_deg, levels, k_max, rms_mm, width_px, s_lo: float,
                   rod: bool) -> str | None:
    """Without camera_distance_mm: a warning when a parallel projection misplaces the sections by
    more than PARALLEL_ERR_PX, with the camera distance that fits the views and that error (None
    when the parallel projection holds).

    levels: (m,) section positions s (mm) of the parallel reconstruction, rms_mm (m,) its tangent
    disagreement, s_lo its z = 0. The distance is the one (of a log grid, refined once) whose
    pinhole fit makes the tangents agree best; the error is the largest support-function
    difference (the Hausdorff distance of convex sections) between the parallel section at s and
    the pinhole one at the same s (below the pinhole's first consistent section: that section);
    with a rod the warning also gives how far the parallel z = 0 lies from the cut that the
    pinhole camera finds (camera.proximal_cut).
    """
    px = frame.scale.sx_mm
    med = float(np.nanmedian(rms_mm)) / px
    if not med > PARALLEL_RMS_PX:
        return None
    step = max(1, len(levels) // 8)
    # every section next to the cut (the rim is seen there), every step-th one above, not the tip
    sub = np.concatenate([levels[:4], levels[4:-1:step]]) if len(levels) > 6 else levels
    tables = border_tables(views, frame)

    def score(d):
        rms = perspective_fit(views, frame, Camera(d), width_px, theta_deg, sub, k_max, iterations=2,
                              tables=tables)[3]
        return float(np.nanmedian(rms)) / px

    grid = [30.0, 45.0, 60.0, 90.0, 120.0, 180.0, 250.0, 400.0, 700.0, 1200.0]
    scores = [score(d) for d in grid]
    j = int(np.argmin(scores))
    for k in (j - 1, j + 1):                  # refine once between the best and its neighbours
        if 0 <= k < len(grid):
            d = float(np.sqrt(grid[j] * grid[k]))
            grid.append(d)
            scores.append(score(d))
    j = int(np.argmin(scores))
    d, best = grid[j], scores[j]
    if best > 0.5 * med:                   # no camera distance explains it
        return (f"the views' tangents disagree by {med:.2f} px rms: check the images, the view angles "
                f"and the rotation axis")
    camera = Camera(d)
    sub_rms = rms_mm[np.searchsorted(levels, sub)] / px          # the parallel fit's disagreement
    coef, _, _, rms = perspective_fit(views, frame, camera, width_px, theta_deg, sub, k_max, tables=tables)
    ok = np.flatnonzero(rms / px <= TANGENT_TOL_PX)
    z0, corner = "", np.zeros(len(sub), bool)
    if rod and len(ok):
        cut = proximal_cut(tables, frame, camera, width_px, theta_deg, support_curve(coef[:, ok[0]:ok[0] + 1])[0],
                           float(sub[ok[0]]), float(sub[ok[0]]) - s_lo + CUT_SEARCH_PX * px)
        if cut is not None:
            z0 = f" and z = 0 by {(s_lo - cut) / px:+.1f} px"
            lowest = max(float(sub[ok[0]]), cut + ROD_MARGIN_PX * px)
            # next to the cut the pinhole sections are not trusted (blurred corner); parallel sections
            # there whose tangents disagree beyond the body's (the rim is seen) and those below the
            # cut are compared with the first trusted one, the others left out
            rim = sub_rms - med > TANGENT_TOL_PX
            corner = (sub >= cut) & (sub < lowest) & ~rim
            low = (sub < cut) | ((sub < lowest) & rim)
            if low.any():
                coef, _, _, rms = perspective_fit(views, frame, camera, width_px, theta_deg,
                                                  np.where(low, lowest, sub), k_max, tables=tables)
    left, right = sample_borders(views, frame, sub)
    phi, h = support_samples(left, right, theta_deg)
    dirs = np.linspace(0.0, 2 * np.pi, 720, endpoint=False)
    moved = np.abs(support_values(fit_support(phi, h, k_max), dirs) - support_values(coef, dirs)).max(axis=1) / px
    # sections the fitted camera explains, of those the parallel reconstruction keeps (consistent_sections)
    kept = sub_rms <= max(TANGENT_TOL_PX, 4.0 * med)
    good = (rms / px <= TANGENT_TOL_PX) & kept & ~corner
    err = float(np.max(moved[good])) if good.any() else float(np.nanmedian(moved))
    if err <= PARALLEL_ERR_PX:
        return None
    return (f"the views' tangents disagree by {med:.2f} px rms, more than a parallel projection explains: "
            f"they fit a camera about {d:.0f} mm from the rotation axis, at which the parallel projection "
            f"misplaces the sections by up to {err:.1f} px{z0}; set camera_distance_mm (measured) in turntable.toml")
