"""Silhouette borders with sub-pixel accuracy, robust to uneven lighting, noise and blur.

Method: Otsu threshold (OpenCV) for a coarse mask of the dark object; a smooth background
illumination map fitted to the background pixels (a polynomial in x, y); the image divided by
it and mapped to 0 (object) .. 1 (background); the border is where that normalised image crosses
0.5, i.e. the local 50 % level between background and object, found on each row by linear
interpolation between the two pixels that straddle it.
"""
from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from reconstruct.errors import InputError

MIN_CONTRAST = 40.0          # grey levels between background and object below which "no object"
_POLY_DEGREE = 4             # illumination model: polynomial in x, y of this total degree
_SEARCH_PX = 4               # the 0.5 crossing is searched this far around the coarse mask edge


@dataclass
class Borders:
    """Row-wise borders of one view, in pixel-centre coordinates (column index 0 = first pixel).

    left_px, right_px: (H,) sub-pixel column of the outermost left/right 0.5 crossing; NaN on
    rows without object. frame_rows: (H,) bool, the object touches the left or right image
    edge on that row. touches_top / touches_bottom: the object reaches that image edge.
    threshold: Otsu level (grey); background, object: median grey levels (for the report).
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


def _poly_terms(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """(n, k) monomials x^i y^j with i + j <= _POLY_DEGREE, coordinates scaled to [-1, 1]."""
    return x[:, None] ** _POWERS[:, 0] * y[:, None] ** _POWERS[:, 1]


def illumination(img: np.ndarray, background_mask: np.ndarray, step: int = 12) -> np.ndarray:
    """Smooth background brightness map (H, W) fitted to pixels where background_mask is True
    (fitted on every `step`-th pixel, evaluated everywhere as Y @ C @ X.T)."""
    h, w = img.shape
    ys, xs = np.mgrid[0:h:step, 0:w:step]
    keep = background_mask[::step, ::step]
    if keep.sum() < 50:
        raise InputError("the object fills the image: leave background visible around the finger")
    sx, sy = 2.0 / max(w - 1, 1), 2.0 / max(h - 1, 1)
    coef, *_ = np.linalg.lstsq(_poly_terms(xs[keep] * sx - 1, ys[keep] * sy - 1),
                               img[::step, ::step][keep].astype(float), rcond=None)
    c = np.zeros((_POLY_DEGREE + 1, _POLY_DEGREE + 1))      # c[i, j] multiplies x^i y^j
    c[_POWERS[:, 0], _POWERS[:, 1]] = coef
    xp = (np.arange(w) * sx - 1)[:, None] ** np.arange(_POLY_DEGREE + 1)
    yp = (np.arange(h) * sy - 1)[:, None] ** np.arange(_POLY_DEGREE + 1)
    return yp @ c.T @ xp.T


def object_mask(img: np.ndarray, name: str = "image") -> tuple[np.ndarray, float]:
    """Largest dark connected region with holes filled (H, W bool), and the Otsu level."""
    level, dark = cv2.threshold(img, 0, 1, cv2.THRESH_BINARY_INV + cv2.THRESH_OTSU)
    dark = dark.astype(bool)
    if dark.sum() < 0.001 * img.size or (~dark).sum() < 0.001 * img.size:
        raise InputError(f"no object found in {name}: the finger must be dark on a bright background")
    contrast = float(np.median(img[~dark])) - float(np.median(img[dark]))
    if contrast < MIN_CONTRAST:
        raise InputError(f"no object found in {name} (contrast {contrast:.0f} grey levels): "
                         f"the finger must be dark on a bright background")
    n, labels, stats, _ = cv2.connectedComponentsWithStats(dark.astype(np.uint8), connectivity=8)
    biggest = 1 + int(np.argmax(stats[1:, cv2.CC_STAT_AREA]))
    mask = (labels == biggest).astype(np.uint8)
    # fill holes: background = what is reachable from outside the mask
    flood = np.pad(1 - mask, 1, constant_values=1)
    cv2.floodFill(flood, None, (0, 0), 2)
    mask = np.pad(mask, 1) | (flood == 1)
    return mask[1:-1, 1:-1].astype(bool), float(level)


def normalise(img: np.ndarray, mask: np.ndarray) -> tuple[np.ndarray, float, float]:
    """Image mapped to 0 (object) .. 1 (background) by the local illumination; also the median
    background and object grey levels."""
    k = np.ones((7, 7), np.uint8)
    outside = cv2.dilate(mask.astype(np.uint8), k, iterations=2) == 0
    inside = cv2.erode(mask.astype(np.uint8), k, iterations=1).astype(bool)
    if inside.sum() < 10:
        inside = mask
    light = illumination(img, outside)
    ratio = img / np.maximum(light, 1.0)
    sub = (slice(None, None, 3), slice(None, None, 3))      # medians from every 9th pixel
    r_obj = float(np.median(ratio[sub][inside[sub]]))
    norm = (ratio - r_obj) / max(1.0 - r_obj, 1e-6)
    return norm, float(np.median(img[sub][outside[sub]])), float(np.median(img[sub][inside[sub]]))


def _crossings(norm: np.ndarray, edge: np.ndarray, rows: np.ndarray, side: int) -> np.ndarray:
    """Sub-pixel column of the outermost 0.5 crossing near `edge` (coarse mask edge) per row.

    side -1: left border (background on the left), +1: right border.
    """
    h, w = norm.shape
    offsets = np.arange(-_SEARCH_PX, _SEARCH_PX + 1) * -side   # outermost first
    out = np.full(len(rows), np.nan)
    for off in offsets[::-1]:               # later (more outward) hits overwrite earlier ones
        j_in = edge + off                   # candidate pixel inside (< 0.5)
        j_out = j_in + side                 # its outer neighbour (>= 0.5)
        ok = (j_out >= 0) & (j_out < w) & (j_in >= 0) & (j_in < w)
        jo, ji = np.clip(j_out, 0, w - 1), np.clip(j_in, 0, w - 1)
        v_out, v_in = norm[rows, jo], norm[rows, ji]
        hit = ok & (v_out >= 0.5) & (v_in < 0.5)
        frac = (v_out - 0.5) / np.where(hit, v_out - v_in, 1.0)
        out = np.where(hit, jo - side * frac, out)
    return out


def extract_borders(img: np.ndarray, name: str = "image") -> Borders:
    """Sub-pixel left/right borders on every row of a grey image (H, W) uint8."""
    mask, level = object_mask(img, name)
    norm, bg, obj = normalise(img, mask)
    h, w = img.shape
    rows = np.flatnonzero(mask.any(axis=1))
    left = np.full(h, np.nan)
    right = np.full(h, np.nan)
    m = mask[rows]
    first = m.argmax(axis=1)
    last = w - 1 - m[:, ::-1].argmax(axis=1)
    left[rows] = _crossings(norm, first, rows, -1)
    right[rows] = _crossings(norm, last, rows, +1)
    frame = np.zeros(h, bool)
    frame[rows] = (first == 0) | (last == w - 1)
    left[frame] = np.nan
    right[frame] = np.nan
    return Borders(left, right, frame, bool(mask[0].any()), bool(mask[-1].any()), level, bg, obj)
