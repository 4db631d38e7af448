"""Lens calibration from checkerboard photos and undistortion of silhouette borders.

Intrinsics (focal lengths fx, fy and principal point cx, cy in px) and Brown distortion
(k1, k2, p1, p2; k3 fixed at 0) come from OpenCV's standard routine: findChessboardCorners,
cornerSubPix, calibrateCamera, on photos of a flat printed checkerboard taken with the same
camera, lens, zoom and focus as the turntable views. Pixel coordinates are OpenCV's: (col, row)
with the centre of the first pixel at 0.

Silhouette borders (one sub-pixel column per row) are undistorted with cv2.undistortPoints with
P = the camera matrix, so they stay in pixels of an ideal pinhole image of the same size, and
resampled onto whole rows, so everything downstream reads them as before.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import cv2
import numpy as np

from fingertip.errors import InputError
from reconstruct.silhouette import Borders

MIN_PHOTOS = 5               # fewest usable checkerboard photos
MAX_RMS_PX = 1.0             # largest acceptable reprojection error of the calibration
_FLAGS = cv2.CALIB_FIX_K3    # k1, k2, p1, p2: enough for a macro or standard lens
_ITER = (cv2.TERM_CRITERIA_COUNT + cv2.TERM_CRITERIA_EPS, 40, 1e-9)


@dataclass
class Lens:
    """Calibrated camera: matrix (3, 3) px, dist (5,) = k1, k2, p1, p2, k3; rms_px: reprojection
    error of the calibration over `photos` photos; size_px: (W, H) of the photos."""

    matrix: np.ndarray
    dist: np.ndarray
    rms_px: float
    photos: int
    size_px: tuple[int, int]

    @property
    def focal_px(self) -> tuple[float, float]:
        return float(self.matrix[0, 0]), float(self.matrix[1, 1])

    @property
    def principal_px(self) -> tuple[float, float]:
        """(col, row) of the principal point."""
        return float(self.matrix[0, 2]), float(self.matrix[1, 2])

    def undistort(self, cols: np.ndarray, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Ideal-pinhole pixel positions (cols, rows) of measured ones (1-D arrays of one length)."""
        if len(cols) == 0:
            return cols.astype(float), rows.astype(float)
        pts = np.column_stack([cols, rows]).astype(np.float64)[:, None, :]
        out = cv2.undistortPoints(pts, self.matrix, self.dist, None, None, self.matrix, _ITER)[:, 0]
        return out[:, 0], out[:, 1]

    def distort(self, cols: np.ndarray, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Measured pixel positions of ideal-pinhole ones (the Brown model, forwards)."""
        return distort_points(cols, rows, self.matrix, self.dist)

    def turned180(self) -> "Lens":
        """The same lens for images turned by 180 degrees (principal point mirrored; the
        tangential terms change sign, the radial ones do not)."""
        w, h = self.size_px
        m = self.matrix.copy()
        m[0, 2], m[1, 2] = w - 1 - m[0, 2], h - 1 - m[1, 2]
        d = self.dist.copy()
        d[2:4] *= -1
        return replace(self, matrix=m, dist=d)


def distort_points(cols, rows, matrix, dist):
    """Brown model: pixel positions (cols, rows) of an ideal pinhole camera `matrix` (3, 3) as
    seen through a lens with distortion `dist` (k1, k2, p1, p2[, k3])."""
    k1, k2, p1, p2, k3 = (list(np.ravel(dist)) + [0.0] * 5)[:5]
    x = (np.asarray(cols, float) - matrix[0, 2]) / matrix[0, 0]
    y = (np.asarray(rows, float) - matrix[1, 2]) / matrix[1, 1]
    r2 = x * x + y * y
    radial = 1 + r2 * (k1 + r2 * (k2 + r2 * k3))
    xd = x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x)
    yd = y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y
    return xd * matrix[0, 0] + matrix[0, 2], yd * matrix[1, 1] + matrix[1, 2]


def find_corners(img: np.ndarray, inner_corners: tuple[int, int]) -> np.ndarray | None:
    """(n, 2) sub-pixel inner corners of the checkerboard in a grey image, or None."""
    flags = cv2.CALIB_CB_ADAPTIVE_THRESH + cv2.CALIB_CB_NORMALIZE_IMAGE
    found, corners = cv2.findChessboardCorners(img, tuple(inner_corners), flags=flags)
    if not found:
        return None
    corners = cv2.cornerSubPix(img, corners, (5, 5), (-1, -1),
                               (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_COUNT, 50, 1e-4))
    return corners.reshape(-1, 2).astype(np.float64)


def calibrate_lens(images: list[tuple[str, np.ndarray]], inner_corners: tuple[int, int],
                   square_mm: float) -> Lens:
    """Calibrate from named grey photos [(name, (H, W) uint8), ...] of a board with
    inner_corners = (per row, per column) inner corners and squares of square_mm.
    Every problem is an InputError naming the photo(s) and the fix."""
    nx, ny = inner_corners
    obj = np.zeros((nx * ny, 3), np.float32)
    obj[:, :2] = np.mgrid[0:nx, 0:ny].T.reshape(-1, 2) * square_mm
    found, missing = [], []
    for name, img in images:
        c = find_corners(img, (nx, ny))
        (missing if c is None else found).append(name if c is None else (name, c))
    if missing:
        raise InputError(f"no {nx} x {ny} checkerboard found in checkerboard/{', '.join(missing[:4])}"
                         f"{' ...' if len(missing) > 4 else ''}: check checkerboard_inner_corners (inner corners "
                         f"per row and column, not squares), or retake or remove those photos")
    if len(found) < MIN_PHOTOS:
        raise InputError(f"only {len(found)} checkerboard photo(s) in checkerboard/: take at least {MIN_PHOTOS} "
                         f"(about 10), the board tilted differently in each")
    h, w = images[0][1].shape
    rms, matrix, dist, rvecs, tvecs = cv2.calibrateCamera(
        [obj] * len(found), [c.astype(np.float32) for _, c in found], (w, h), None, None,
        flags=_FLAGS, criteria=(cv2.TERM_CRITERIA_COUNT + cv2.TERM_CRITERIA_EPS, 100, 1e-12))
    if not rms <= MAX_RMS_PX:
        per = []
        for (name, c), r, t in zip(found, rvecs, tvecs):
            p, _ = cv2.projectPoints(obj, r, t, matrix, dist)
            per.append((float(np.sqrt(np.mean(np.sum((p.reshape(-1, 2) - c) ** 2, axis=1)))), name))
        worst = ", ".join(f"{n} ({e:.1f} px)" for e, n in sorted(per, reverse=True)[:3])
        raise InputError(f"the checkerboard calibration fits to {rms:.2f} px rms (at most {MAX_RMS_PX:g} px), "
                         f"worst photos: checkerboard/{worst}: retake or remove blurred or bent-board photos")
    return Lens(matrix, np.ravel(dist)[:5].astype(float), float(rms), len(found), (w, h))


def undistort_borders(b: Borders, lens: Lens) -> Borders:
    """The borders of one view in the ideal pinhole image: each border point undistorted and the
    border resampled onto whole rows (not across rows where it had none)."""
    h = len(b.left_px)
    out = []
    for cols in (b.left_px, b.right_px):
        rows = np.flatnonzero(np.isfinite(cols))
        new = np.full(h, np.nan)
        if len(rows) > 1:
            c, r = lens.undistort(cols[rows], rows.astype(float))
            order = np.argsort(r, kind="stable")
            c, r, src = c[order], r[order], rows[order]
            target = np.arange(int(np.ceil(r[0])), int(np.floor(r[-1])) + 1)
            target = target[(target >= 0) & (target < h)]
            k = np.clip(np.searchsorted(r, target, side="right"), 1, len(r) - 1)
            adjacent = np.abs(src[k] - src[k - 1]) == 1
            new[target[adjacent]] = np.interp(target[adjacent], r, c)
        out.append(new)
    return Borders(out[0], out[1], b.frame_rows, b.touches_top, b.touches_bottom, b.threshold,
                   b.background, b.object)
