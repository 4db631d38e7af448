"""Consistency of the sections before anything is written, and whether the parallel projection holds.

A section is refused when its outline folds back on itself (the fitted support function has a
negative radius of curvature beyond noise), when its tangents disagree (rms residual of the
support-function fit), or when its size jumps against its neighbours. Refused sections at either
end are trimmed with a warning naming the z range; one in the middle is an InputError.
"""
from __future__ import annotations

import numpy as np
from scipy.spatial import ConvexHull

from common.errors import InputError

TANGENT_TOL_PX = 0.3        # rms disagreement of a section's tangents above which it is refused
FOLD_TOL_PX = 1.0           # depth of a fold of the outline (inside its own hull) that is refused
JUMP_TOL = 0.12             # relative size change against the neighbours' interpolation
PARALLEL_RMS_PX = 0.12      # median tangent disagreement that a parallel projection does not explain
CUT_TOL_PX = 1.0            # pinhole camera: the proximal cut is where the rim's disagreement ends


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


def check_parallel(views, frame, theta_deg, levels, k_max, rms_mm, width_px) -> str | None:
    """Without camera_distance_mm: a warning when the tangents disagree more than a parallel
    projection explains, with the error it causes and the camera distance that fits the views
    (None when the parallel projection holds)."""
    from reconstruct.camera import Camera, border_tables, perspective_fit
    from reconstruct.sections import support_curve

    px = frame.scale.sx_mm
    med = float(np.nanmedian(rms_mm)) / px
    if not med > PARALLEL_RMS_PX:
        return None
    sub = levels[1:-1:max(1, len(levels) // 8)] if len(levels) > 4 else levels
    tables = border_tables(views, frame)
    best = (np.inf, None, None, None)
    for d in (30.0, 45.0, 60.0, 90.0, 120.0, 180.0, 250.0, 400.0, 700.0, 1200.0):
        coef, _, _, rms = perspective_fit(views, frame, Camera(d), width_px, theta_deg, sub, k_max,
                                          iterations=2, tables=tables)
        score = float(np.nanmedian(rms)) / px
        if score < best[0]:
            best = (score, d, coef, rms / px)
    score, d, coef, rms_px = best
    if score > 0.5 * med:                   # no camera distance explains it
        return (f"the views' tangents disagree by {med:.2f} px rms: check the images, the view angles "
                f"and the rotation axis")
    from reconstruct.sections import fit_support, support_samples
    from reconstruct.calibrate import sample_borders
    left, right = sample_borders(views, frame, sub)
    phi, h = support_samples(left, right, theta_deg)
    ortho = support_curve(fit_support(phi, h, k_max))
    persp = support_curve(coef)
    good = rms_px <= TANGENT_TOL_PX                 # sections the fitted camera explains
    moved = np.linalg.norm(ortho - persp, axis=-1).max(axis=1) / px
    err = float(np.max(moved[good])) if good.any() else float(np.nanmedian(moved))
    return (f"the views' tangents disagree by {med:.2f} px rms, more than a parallel projection explains: "
            f"they fit a camera about {d:.0f} mm from the rotation axis, which moves the sections by up to "
            f"{err:.1f} px; set camera_distance_mm (measured) in turntable.toml")
