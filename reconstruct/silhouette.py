"""Silhouette borders with sub-pixel accuracy, robust to uneven lighting, noise and blur.

Method: Otsu threshold (OpenCV) for a coarse mask of the dark object (largest connected part);
a smooth illumination map fitted to the background (a polynomial in x, y); grey levels divided
by it and mapped to 0 (object) .. 1 (background); the border is where that crosses 0.5, i.e.
the local 50 % level between background and object, found on each row near the coarse edge by
linear interpolation between the two pixels that straddle it. The model is evaluated only at
the pixels the search looks at.
"""
from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from fingertip.errors import InputError

MIN_CONTRAST = 40.0          # grey levels between background and object below which "no object"
_POLY_DEGREE = 4             # illumination model: polynomial in x, y of this total degree
_SEARCH_PX = 4               # the 0.5 crossing is searched this far around the coarse mask edge


@dataclass
class Borders:
    """Row-wise borders of one view, in pixel-centre coordinates (column index 0 = first pixel).

    left_px, right_px: (H,) sub-pixel column of the outermost left/right 0.5 crossing; NaN on
    rows without object. frame_rows: (H,) bool, the object touches the left or right image
    edge on that row. touches_top / touches_bottom: the object reaches that image edge.
    threshold: Otsu level (grey); background, object: grey levels of the lighting model at the
    image centre (for the report).
    """

    left_px: np.ndarray
    right_px: np.ndarray
    frame_rows: np.ndarray
    touches_top: bool
    touches_bottom: bool
    threshold: float
    background: float
    object: float

    @property
    def width_px(self) -> np.ndarray:
        return self.right_px - self.left_px


_POWERS = np.array([(i, j) for i in range(_POLY_DEGREE + 1) for j in range(_POLY_DEGREE + 1 - i)])


def _powers(v: np.ndarray) -> np.ndarray:
    """(n, _POLY_DEGREE + 1) powers 0.. of v."""
    return np.vander(v, _POLY_DEGREE + 1, increasing=True)


@dataclass
class Lighting:
    """Illumination model of one image: background brightness is a polynomial in (x, y) (degree
    _POLY_DEGREE, coordinates scaled to [-1, 1]); the object reflects a fixed fraction r_object
    of it. `normalised(img, rows, cols)` maps grey levels to 0 (object) .. 1 (background)."""

    coef: np.ndarray           # (d+1, d+1), coef[i, j] multiplies x^i y^j
    shape: tuple[int, int]
    r_object: float

    @classmethod
    def fit(cls, img: np.ndarray, mask: np.ndarray, step: int = 12) -> "Lighting":
        """Fit to the background (pixels well outside the mask) on every step-th pixel."""
        k = np.ones((7, 7), np.uint8)
        sub = (slice(None, None, step // 2), slice(None, None, step // 2))
        outside = (cv2.dilate(mask.astype(np.uint8), k, iterations=2) == 0)[sub]
        inside = cv2.erode(mask.astype(np.uint8), k, iterations=1).astype(bool)[sub]
        if outside.sum() < 50:
            raise InputError("the object fills the image: leave background visible around the finger")
        rows, cols = np.mgrid[0:img.shape[0]:step // 2, 0:img.shape[1]:step // 2]
        x, y = cls._xy(img.shape, rows[outside], cols[outside])
        coef, *_ = np.linalg.lstsq(_powers(x)[:, _POWERS[:, 0]] * _powers(y)[:, _POWERS[:, 1]],
                                   img[sub][outside].astype(float), rcond=None)
        c = np.zeros((_POLY_DEGREE + 1, _POLY_DEGREE + 1))
        c[_POWERS[:, 0], _POWERS[:, 1]] = coef
        light = cls(c, img.shape, 0.0)
        if inside.sum() < 10:
            inside = mask[sub]
        ratio = img[sub][inside] / light.brightness(rows[inside], cols[inside])
        light.r_object = float(np.median(ratio))
        return light

    @staticmethod
    def _xy(shape, rows, cols):
        h, w = shape
        return cols * (2.0 / max(w - 1, 1)) - 1, rows * (2.0 / max(h - 1, 1)) - 1

    def brightness(self, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """Background grey level at pixels (rows, cols) (1-D arrays)."""
        x, y = self._xy(self.shape, rows, cols)
        return np.maximum(((_powers(x) @ self.coef) * _powers(y)).sum(axis=1), 1.0)

    def normalised(self, img: np.ndarray, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """Grey levels at (rows, cols) mapped to 0 (object) .. 1 (background)."""
        ratio = img[rows, cols] / self.brightness(rows, cols)
        return (ratio - self.r_object) / max(1.0 - self.r_object, 1e-6)


def object_mask(img: np.ndarray, name: str = "image") -> tuple[np.ndarray, float]:
    """Largest dark connected region (H, W bool) and the Otsu level. Holes are kept: only the
    outermost border on each row matters."""
    level, dark = cv2.threshold(img, 0, 1, cv2.THRESH_BINARY_INV + cv2.THRESH_OTSU)
    n_dark = int(dark.sum())
    if n_dark < 0.001 * img.size or n_dark > 0.999 * img.size:
        raise InputError(f"no object found in {name}: the finger must be dark on a bright background")
    sub = dark[::3, ::3].astype(bool)
    contrast = float(np.median(img[::3, ::3][~sub])) - float(np.median(img[::3, ::3][sub]))
    if contrast < MIN_CONTRAST:
        raise InputError(f"no object found in {name} (contrast {contrast:.0f} grey levels): "
                         f"the finger must be dark on a bright background")
    n, labels, stats, _ = cv2.connectedComponentsWithStats(dark, connectivity=8)
    biggest = 1 + int(np.argmax(stats[1:, cv2.CC_STAT_AREA]))
    return labels == biggest, float(level)


def _crossings(img: np.ndarray, light: Lighting, edge: np.ndarray, rows: np.ndarray, side: int) -> np.ndarray:
    """Sub-pixel column of the outermost 0.5 crossing within _SEARCH_PX of `edge` (the coarse
    mask edge) on each row; NaN where there is none. side -1: left border, +1: right border."""
    w = img.shape[1]
    window = np.arange(-_SEARCH_PX - 1, _SEARCH_PX + 2)                  # columns edge + window
    cols = np.clip(edge[:, None] + window, 0, w - 1)
    vals = light.normalised(img, np.repeat(rows, len(window)), cols.ravel()).reshape(cols.shape)
    out = np.full(len(rows), np.nan)
    # candidate inside pixel edge + off (< 0.5) next to its outer neighbour (>= 0.5); going
    # outwards, so that the outermost crossing is the one kept
    for off in sorted(range(-_SEARCH_PX, _SEARCH_PX + 1), key=lambda o: o * side):
        j_out = edge + off + side
        v_in, v_out = vals[:, off + _SEARCH_PX + 1], vals[:, off + side + _SEARCH_PX + 1]
        hit = (j_out >= 0) & (j_out < w) & (edge + off >= 0) & (edge + off < w) & (v_out >= 0.5) & (v_in < 0.5)
        frac = (v_out - 0.5) / np.where(hit, v_out - v_in, 1.0)
        out = np.where(hit, j_out - side * frac, out)
    return out


SIDE_ROWS_MAX = 2 / 3
"""Largest fraction of the object's rows on which it may touch the left or right image edge
(those rows are trimmed; beyond it too little of the finger is seen whole)."""


def _check_inside(mask: np.ndarray, frame: np.ndarray, rows: np.ndarray, name: str) -> None:
    """InputError when the object leaves the image through its left or right edge on more than
    SIDE_ROWS_MAX of its rows (the rows where it does are not seen whole)."""
    if frame.sum() > SIDE_ROWS_MAX * len(rows):
        side = "left" if mask[rows, 0].sum() >= mask[rows, -1].sum() else "right"
        raise InputError(f"the finger touches the {side} image frame of {name} on {int(frame.sum())} of its "
                         f"{len(rows)} rows: zoom out or re-centre it so that it is inside the image")


def extract_borders(img: np.ndarray, name: str = "image") -> Borders:
    """Sub-pixel left/right borders on every row of a grey image (H, W) uint8."""
    mask, level = object_mask(img, name)
    light = Lighting.fit(img, mask)
    h, w = img.shape
    rows = np.flatnonzero(mask.any(axis=1))
    left = np.full(h, np.nan)
    right = np.full(h, np.nan)
    m = mask[rows]
    first = m.argmax(axis=1)
    last = w - 1 - m[:, ::-1].argmax(axis=1)
    left[rows] = _crossings(img, light, first, rows, -1)
    right[rows] = _crossings(img, light, last, rows, +1)
    frame = np.zeros(h, bool)
    frame[rows] = (first == 0) | (last == w - 1)
    _check_inside(mask, frame, rows, name)
    left[frame] = np.nan
    right[frame] = np.nan
    mid = h // 2
    background = float(light.brightness(np.array([mid]), np.array([w // 2]))[0])
    return Borders(left, right, frame, bool(mask[0].any()), bool(mask[-1].any()), level,
                   background, background * light.r_object)
