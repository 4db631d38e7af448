"""Calibration: scale and pixel aspect from the template; rotation axis offset and tilt from the views.

Image frame: pixel centres (row, col); physical image coordinates dx = col * sx, dy = (H - 0.5 - row)
* sy in mm (origin at the bottom-left, dy up). Axis frame: the rotation axis crosses the bottom
edge at dx = x0_mm and leans by tilt (positive: top to the right); u (mm) is the distance from
the axis across it, s (mm) the distance along it from the bottom edge.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fingertip.errors import InputError
from reconstruct.silhouette import Borders


@dataclass
class Scale:
    """mm per pixel across (sx) and along (sy) the columns; rms_px: template fit residual."""

    sx_mm: float
    sy_mm: float
    rms_px: float
    diameter_px: tuple[float, float]

    @property
    def aspect(self) -> float:
        """Pixel aspect ratio: pixel height / pixel width."""
        return self.sy_mm / self.sx_mm


@dataclass
class Frame:
    """Image -> axis frame map. height_px: image height; x0_mm, tilt_deg: the rotation axis."""

    scale: Scale
    height_px: int
    x0_mm: float = 0.0
    tilt_deg: float = 0.0

    def to_axis(self, rows: np.ndarray, cols: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(u, s) in mm of pixel positions (row, col) (arrays of one shape)."""
        dx = cols * self.scale.sx_mm - self.x0_mm
        dy = (self.height_px - 0.5 - rows) * self.scale.sy_mm
        t = np.deg2rad(self.tilt_deg)
        return dx * np.cos(t) - dy * np.sin(t), dx * np.sin(t) + dy * np.cos(t)

    def axis_col_px(self, rows: np.ndarray) -> np.ndarray:
        """Column of the rotation axis on the given rows."""
        dy = (self.height_px - 0.5 - rows) * self.scale.sy_mm
        return (self.x0_mm + dy * np.tan(np.deg2rad(self.tilt_deg))) / self.scale.sx_mm

    def offset_px(self, width_px: int) -> float:
        """Axis column at the bottom edge relative to the image centre column W/2."""
        return self.x0_mm / self.scale.sx_mm - width_px / 2


def template_scale(borders: Borders, diameter_mm: float) -> Scale:
    """Scale from the template disc: fit an axis-aligned ellipse to its row borders.

    Only the rows around the widest one that are wider than half of it are used (|y| < 0.87 R of
    the disc), so a shaft narrower than half the diameter is left out. A template that is not a
    disc (residual over 0.5 px rms, or an aspect far from 1) is an InputError.
    """
    if borders.frame_rows.any() or borders.touches_top:
        raise InputError("the calibration template touches the image frame: photograph the whole disc")
    w = np.nan_to_num(borders.width_px, nan=0.0)
    wide = np.concatenate([[False], w > 0.5 * w.max(), [False]])
    starts, ends = np.flatnonzero(~wide[:-1] & wide[1:]), np.flatnonzero(wide[:-1] & ~wide[1:])
    run = np.searchsorted(ends, int(np.argmax(w)), side="right")     # the run holding the widest row
    ok = np.zeros(len(w), bool)
    ok[starts[run]:ends[run]] = True
    rows = np.flatnonzero(ok).astype(float)
    if len(rows) < 20:
        raise InputError("the calibration template is too small in the image (under 20 rows): zoom in")
    x = np.concatenate([borders.left_px[ok], borders.right_px[ok]])
    y = np.concatenate([rows, rows])
    xm, ym = x.mean(), y.mean()
    xc, yc = x - xm, y - ym
    # A x^2 + B y^2 + C x + D y = 1 (axis-aligned conic)
    coef, *_ = np.linalg.lstsq(np.column_stack([xc**2, yc**2, xc, yc]), np.ones_like(xc), rcond=None)
    a_, b_, c_, d_ = coef
    if a_ <= 0 or b_ <= 0:
        raise InputError("the calibration image does not show a disc: photograph the round template")
    x0, y0 = -c_ / (2 * a_), -d_ / (2 * b_)
    f = 1 + a_ * x0**2 + b_ * y0**2
    ra, rb = np.sqrt(f / a_), np.sqrt(f / b_)
    resid = np.sqrt(((xc - x0) / ra) ** 2 + ((yc - y0) / rb) ** 2) - 1.0
    rms_px = float(np.sqrt(np.mean(resid**2)) * np.sqrt(ra * rb))
    if rms_px > 0.5 or not 0.5 < rb / ra < 2.0:
        raise InputError(f"the calibration image does not show a disc (ellipse fit residual {rms_px:.2f} px, "
                         f"axes {2 * ra:.1f} x {2 * rb:.1f} px): photograph the round template")
    return Scale(diameter_mm / (2 * ra), diameter_mm / (2 * rb), rms_px, (2 * ra, 2 * rb))


def border_points(borders: Borders, frame: Frame, side: str) -> tuple[np.ndarray, np.ndarray]:
    """(u, s) mm of one border ('left' or 'right') of one view, sorted by s."""
    cols = borders.left_px if side == "left" else borders.right_px
    rows = np.flatnonzero(np.isfinite(cols))
    u, s = frame.to_axis(rows.astype(float), cols[rows])
    order = np.argsort(s)
    return u[order], s[order]


def sample_borders(views: list[Borders], frame: Frame, s_mm: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Left and right border u (mm) of every view at axial positions s: two (n_views, len(s))
    arrays, NaN where a view has no border at that s."""
    out = np.full((2, len(views), len(s_mm)), np.nan)
    for i, b in enumerate(views):
        for k, side in enumerate(("left", "right")):
            u, s = border_points(b, frame, side)
            if len(s) > 1:
                out[k, i] = np.interp(s_mm, s, u, left=np.nan, right=np.nan)
                gaps = np.interp(s_mm, s[1:], np.diff(s)) > 3 * max(frame.scale.sy_mm, frame.scale.sx_mm)
                out[k, i, gaps] = np.nan
    return out[0], out[1]


def _odd_harmonics(theta_rad: np.ndarray, n_views: int) -> np.ndarray:
    """Design matrix [1, cos k theta, sin k theta for odd k]: the border midpoint of a convex body
    has only odd harmonics in the view angle; an axis offset adds the constant."""
    k_max = max(1, min(15, (n_views - 2) // 4 * 2 - 1))
    cols = [np.ones_like(theta_rad)]
    for k in range(1, k_max + 1, 2):
        cols += [np.cos(k * theta_rad), np.sin(k * theta_rad)]
    return np.column_stack(cols)


def estimate_axis(views: list[Borders], angles_deg: np.ndarray, frame: Frame,
                  iterations: int = 4) -> tuple[Frame, dict]:
    """Rotation axis (offset and tilt) from the views themselves.

    At each axial position, the midpoint between the left and right border as a function of view
    angle is fitted by a constant plus odd harmonics; the constant is where the axis is (for
    views theta and theta + 180 this reduces to (right(theta) + left(theta + 180)) / 2). A line
    through those constants along s gives offset and tilt; repeated in the corrected frame so
    tilt and offset do not bias each other. Returns the new frame and fit diagnostics.
    """
    design = _odd_harmonics(np.deg2rad(angles_deg), len(views))
    if design.shape[1] >= len(views):
        raise InputError("too few views to estimate the rotation axis: take more views or give "
                         "axis_offset_px and tilt_deg in turntable.toml")
    pinv_row0 = np.linalg.pinv(design)[0]          # weights giving the constant term
    cond = float(np.linalg.cond(design))
    frame = Frame(frame.scale, frame.height_px, frame.x0_mm, frame.tilt_deg)
    if frame.x0_mm == 0.0:                          # start from the mean border midpoint
        mids = [np.nanmean((b.left_px + b.right_px) / 2) for b in views]
        frame.x0_mm = float(np.nanmean(mids)) * frame.scale.sx_mm
    step = 2 * max(frame.scale.sx_mm, frame.scale.sy_mm)
    for _ in range(iterations):
        s_all = np.arange(0.0, frame.height_px * frame.scale.sy_mm, step)
        left, right = sample_borders(views, frame, s_all)
        # usable: every view has both borders, and they run steeply along the axis (|du/ds| < 0.5)
        # here and at both neighbours, away from the rod-to-finger step and the rounded tip
        slope = np.fmax(np.abs(np.gradient(left, step, axis=1)), np.abs(np.gradient(right, step, axis=1)))
        steep = np.nan_to_num(slope, nan=np.inf).max(axis=0) < 0.5
        good = steep & np.roll(steep, 1) & np.roll(steep, -1)
        if good.sum() < 10:
            raise InputError("the finger is not seen whole in enough rows of every view to find the "
                             "rotation axis: keep it inside the frame in all views")
        s = s_all[good]
        centre = pinv_row0 @ ((left[:, good] + right[:, good]) / 2)      # (n_s,) mm, u of the axis
        fit = np.polyfit(s, centre, 1)
        resid = centre - np.polyval(fit, s)
        keep = np.abs(resid) < 4 * np.median(np.abs(resid)) + 1e-9
        d1, d0 = np.polyfit(s[keep], centre[keep], 1)
        # move the frame so that the fitted axis line u = d0 + d1 s becomes u = 0
        t = np.deg2rad(frame.tilt_deg)
        t_cross = d0 * np.sin(t) / (np.cos(t) - d1 * np.sin(t))       # s where the new axis hits dy = 0
        u_cross = d0 + d1 * t_cross
        frame.x0_mm += u_cross * np.cos(t) + t_cross * np.sin(t)
        frame.tilt_deg += float(np.rad2deg(np.arctan(d1)))
        if abs(d0) < 1e-5 and abs(d1) < 1e-7:
            break
    rms = float(np.sqrt(np.mean(resid[keep] ** 2)))
    return frame, {"axis_fit_rms_mm": rms, "axis_rows_used": int(good.sum()), "design_condition": cond}
