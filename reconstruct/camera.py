"""Camera model of the image stage: parallel projection (the default) or a pinhole camera.

Pinhole: the camera centre C lies `distance_mm` from the rotation axis, on the normal of the
plane through the axis that the template calibrates (the "axis plane", where mm_per_px holds);
its principal point (image centre by default) maps to (u_c, s_c) in the axis frame
(reconstruct.calibrate). A point at depth w behind the axis plane (w > 0 away from the camera)
and at (X, Z) across/along the axis is seen at u = u_c + (X - u_c) D / (D + w),
s = s_c + (Z - s_c) D / (D + w). D -> infinity is the parallel projection.

Each silhouette point (u_i, s_i) with border slope du/ds defines a plane through C that is tangent
to the surface where the ray touches it. Its intersection with the section plane z is a support
line of that section, exact where the ray touches at height z: the silhouette row used for
section z is s_i = s_c + (z - s_c) D / (D + w*), with w* the depth of the touching point,
refined from the sections themselves (`perspective_fit`).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from reconstruct.calibrate import Frame, border_points
from reconstruct.sections import _design

_BLOCK = 64                      # sections per batched least-squares solve


@dataclass
class Camera:
    """distance_mm: camera centre to rotation axis (None: parallel projection);
    principal_px: (col, row) of the principal point, default the image centre."""

    distance_mm: float | None = None
    principal_px: tuple[float, float] | None = None

    @property
    def orthographic(self) -> bool:
        return self.distance_mm is None

    def centre(self, frame: Frame, width_px: int) -> tuple[float, float]:
        """(u_c, s_c) mm: where the principal point lies in the axis frame."""
        col, row = self.principal_px or ((width_px - 1) / 2, (frame.height_px - 1) / 2)
        u, s = frame.to_axis(np.array([row], float), np.array([col], float))
        return float(u[0]), float(s[0])


def border_tables(views, frame: Frame, smooth_px: int = 2):
    """Per view and side: (s, u, du/ds) sorted by s; du/ds from a centred difference over
    2 smooth_px + 1 samples."""
    out = []
    for b in views:
        sides = []
        for side in ("left", "right"):
            u, s = border_points(b, frame, side)
            k = smooth_px
            du = np.full(len(s), np.nan)
            if len(s) > 2 * k:
                du[k:-k] = (u[2 * k:] - u[:-2 * k]) / np.maximum(s[2 * k:] - s[:-2 * k], 1e-12)
            sides.append((s, u, du))
        out.append(sides)
    return out


def support_lines(tables, frame: Frame, camera: Camera, width_px: int, theta_deg: np.ndarray,
                  z_mm: np.ndarray, w_star: np.ndarray):
    """Support lines of the sections at z from the silhouettes under the pinhole camera.

    tables: border_tables(views); theta_deg: (n,) view angles relative to the volar view;
    z_mm: (m,) section positions (axis frame s); w_star: (2n, m) depth of the touching point
    (rows: right borders of all views, then left borders, as sections.support_samples).
    Returns phi (2n, m) rad (finger frame) and h (2n, m) mm, NaN where a view has no border.
    """
    D = float(camera.distance_mm)
    u_c, s_c = camera.centre(frame, width_px)
    n, m = len(theta_deg), len(z_mm)
    gap = 3 * max(frame.scale.sy_mm, frame.scale.sx_mm)
    phi, h = np.full((2 * n, m), np.nan), np.full((2 * n, m), np.nan)
    theta = np.deg2rad(theta_deg)
    for k, (side, sign) in enumerate((("right", -1.0), ("left", 1.0))):
        for i in range(n):
            s, u, du = tables[i][1 if side == "right" else 0]
            if len(s) < 2:
                continue
            row = k * n + i
            si = s_c + (z_mm - s_c) * D / (D + w_star[row])
            ui = np.interp(si, s, u, left=np.nan, right=np.nan)
            ti = np.interp(si, s, du, left=np.nan, right=np.nan)
            far = np.interp(si, s[1:], np.diff(s)) > gap
            ui[far] = np.nan
            ru, rs = ui - u_c, si - s_c
            # plane normal N = r x t, r = (ru, rs, D) the ray, t = (ti, 1, 0) the border direction
            nu, ns, nw = -D * np.ones(m), D * ti, ru - rs * ti
            c = nu * u_c - ns * (z_mm - s_c) - nw * D
            nu, nw, c = sign * nu, sign * nw, sign * c          # outward normal
            norm = np.hypot(nu, nw)
            psi = np.arctan2(nw, nu)
            phi[row] = np.mod(np.pi - theta[i] + psi, 2 * np.pi)
            h[row] = c / norm
    return phi, h


def fit_support_each(phi: np.ndarray, h: np.ndarray, k_max: int, smooth: float = 1e-9):
    """Fourier coefficients (2 k_max + 1, m) of each section's own tangent set, and the rms fit
    residual (m,) mm. phi, h: (2n, m); NaN entries are left out (same penalty as fit_support)."""
    n2, m = phi.shape
    kk = np.concatenate([[0.0], np.repeat(np.arange(1, k_max + 1), 2)])
    coef = np.full((2 * k_max + 1, m), np.nan)
    rms = np.full(m, np.nan)
    for a in range(0, m, _BLOCK):
        sl = slice(a, min(a + _BLOCK, m))
        p, y = phi[:, sl].T, h[:, sl].T                          # (b, 2n)
        ok = np.isfinite(p) & np.isfinite(y)
        A = _design(np.where(ok, p, 0.0).ravel(), k_max).reshape(p.shape[0], n2, -1) * ok[..., None]
        yv = np.where(ok, y, 0.0)
        pen = smooth * ok.sum(axis=1)[:, None] * np.where(kk >= 2, kk**4, 0.0)[None]
        AtA = np.einsum("bip,biq->bpq", A, A) + pen[:, :, None] * np.eye(len(kk))[None]
        good = ok.sum(axis=1) > len(kk)
        c = np.full((p.shape[0], len(kk)), np.nan)
        if good.any():
            c[good] = np.linalg.solve(AtA[good], np.einsum("bip,bi->bp", A[good], yv[good])[..., None])[..., 0]
        r = np.where(ok, np.einsum("bip,bp->bi", A, np.nan_to_num(c)) - yv, np.nan)
        coef[:, sl] = c.T
        with np.errstate(invalid="ignore", divide="ignore"):
            rms[sl] = np.where(good, np.sqrt(np.nansum(r**2, axis=1) / np.maximum(ok.sum(axis=1), 1)), np.nan)
    return coef, rms


def touching_depth(coef: np.ndarray, phi: np.ndarray, theta_deg: np.ndarray) -> np.ndarray:
    """(2n, m) depth w (mm) of the point where each support line touches its section (view
    frame of its view; rows ordered as support_lines)."""
    n2, m = phi.shape
    k_max = (coef.shape[0] - 1) // 2
    t = np.deg2rad(np.concatenate([theta_deg, theta_deg]))[:, None]
    p = np.nan_to_num(phi)
    h = np.einsum("imp,pm->im", _design(p.ravel(), k_max).reshape(n2, m, -1), np.nan_to_num(coef))
    dh = np.einsum("imp,pm->im", _design(p.ravel(), k_max, 1).reshape(n2, m, -1), np.nan_to_num(coef))
    x = h * np.cos(p) - dh * np.sin(p)
    y = h * np.sin(p) + dh * np.cos(p)
    return -x * np.sin(t) - y * np.cos(t)


def perspective_fit(views, frame: Frame, camera: Camera, width_px: int, theta_deg: np.ndarray,
                    z_mm: np.ndarray, k_max: int, iterations: int = 3, tables=None):
    """Sections at z under the pinhole camera: coefficients (2K+1, m), phi and h (2n, m) of the
    support lines used, and the rms residual (m,) mm of each section's fit."""
    tables = tables if tables is not None else border_tables(views, frame)
    w = np.zeros((2 * len(theta_deg), len(z_mm)))
    for it in range(iterations):
        phi, h = support_lines(tables, frame, camera, width_px, theta_deg, z_mm, w)
        coef, rms = fit_support_each(phi, h, k_max)
        if it < iterations - 1:
            # a touching point lies within the section: |w| <= its largest support value
            reach = np.nan_to_num(np.nanmax(np.abs(h), axis=0, initial=0.0))[None]
            w = np.where(np.isfinite(phi), touching_depth(coef, phi, theta_deg), 0.0)
            w = np.nan_to_num(np.clip(w, -reach, reach))
    return coef, phi, h, rms


def proximal_cut(tables, frame: Frame, camera: Camera, width_px: int, theta_deg: np.ndarray,
                 outline: np.ndarray, s_first: float, search_mm: float) -> float | None:
    """Axial position s (mm) of the proximal cut under the pinhole camera, or None.

    In perspective the rim of the cut is seen below the cut's row (its near side lower still)
    and meets the body's outline smoothly, so no row marks the cut. The body between the cut and
    the first good section is taken as a prism of that section's outline (finger frame, (k, 2)
    mm) standing on the cut: its shadow in view i has, in each row s, the border
    max {u_k : s_k <= s} over the outline points projected at a trial cut z, or the rod's border
    below. Each border of each view gives the z in [s_first - search_mm, s_first] that fits its
    measured rows best (least squares; grid of 0.25 px, then 0.02 px); the cut is their median.
    """
    D = float(camera.distance_mm)
    u_c, s_c = camera.centre(frame, width_px)
    px = frame.scale.sy_mm
    if s_first >= s_c:
        return None
    t = np.deg2rad(theta_deg)
    x, y = outline[:, 0], outline[:, 1]
    z_lo = s_first - search_mm
    found = []
    for i in range(len(t)):
        X = -x * np.cos(t[i]) + y * np.sin(t[i])
        w = -x * np.sin(t[i]) - y * np.cos(t[i])
        sc = D / (D + w)
        order = np.argsort(-sc)                    # lowest in the image first (the cut is below s_c)
        sc_desc = sc[order]
        u_k = (u_c + (X - u_c) * sc)[order]
        bottom = s_c + (z_lo - s_c) * sc_desc[0]
        for side, sign in ((0, -1.0), (1, 1.0)):
            s, u, _ = tables[i][side]
            fin = np.isfinite(u)
            rows = fin & (s <= s_first) & (s >= bottom - 3 * px)
            if rows.sum() < 5:
                continue
            ss, uu = s[rows], sign * u[rows]
            below = fin & (s < bottom - 3 * px)
            rod = np.median(sign * u[below][-max(3, int(round(1.0 / px))):]) if below.sum() >= 3 else uu.min()
            reach = np.maximum.accumulate(sign * u_k)             # border of the prism's shadow

            def cost(z):
                # outline point k lies at or below row s when sc_k >= (s - s_c) / (z - s_c)
                need = (ss[None] - s_c) / (z[:, None] - s_c)
                j = np.searchsorted(-sc_desc, -need, side="right") - 1
                pred = np.maximum(np.where(j >= 0, reach[np.maximum(j, 0)], -np.inf), rod)
                return ((pred - uu[None]) ** 2).sum(axis=1)

            grid = np.arange(z_lo, s_first + 1e-9, 0.25 * px)
            z0 = grid[int(np.argmin(cost(grid)))]
            fine = z0 + np.arange(-0.3, 0.3 + 1e-9, 0.02) * px
            found.append(fine[int(np.argmin(cost(fine)))])
    return float(np.median(found)) if found else None
