"""The sections a layered model is built from: a sections.json of the image stage or a preset's
sections, each checked (closed, simple, convex, counter-clockwise), and the z range of the body
and the length of the rounded tip beyond it (thesis 6.1).

    z, polygons, sha = load_sections("out/sample")        # or preset_sections("human")
    polygons = [check_polygon(p, f"section at z={zi:g} mm") for zi, p in zip(z, polygons)]
    curve = smooth_polygon(polygons[0], spacing_mm=0.005)  # a section without corners (2D meshes)
"""
from __future__ import annotations

import hashlib
import json
from pathlib import Path

import numpy as np
from scipy.interpolate import CubicSpline
from scipy.spatial import ConvexHull

from fem.geometry.presets import make_shape
from fingertip.errors import InputError


def check_polygon(points: np.ndarray, where: str) -> np.ndarray:
    """Validate one section polygon (n, 2) mm; return it counter-clockwise, last point not repeated."""
    try:
        p = np.asarray(points, float)
    except (ValueError, TypeError):
        raise InputError(f"{where}: points must be a list of finite [x, y] pairs") from None
    if p.ndim != 2 or p.shape[1] != 2 or not np.all(np.isfinite(p)):
        raise InputError(f"{where}: points must be a list of finite [x, y] pairs")
    if len(p) > 3 and np.allclose(p[0], p[-1]):
        p = p[:-1]
    if len(p) < 3:
        raise InputError(f"{where}: a closed section needs at least 3 points, got {len(p)}")
    edges = np.linalg.norm(np.roll(p, -1, axis=0) - p, axis=1)
    if edges[-1] > 10 * np.median(edges) and edges[-1] > 0.2 * edges.sum():
        raise InputError(f"{where}: the section is not closed (gap of {edges[-1]:.2f} mm between the "
                         "last and first point); give a closed outline")
    if _self_intersects(p):
        raise InputError(f"{where}: the section outline intersects itself; give a simple closed polygon")
    area = _area(p)
    if abs(area) < 1e-9:
        raise InputError(f"{where}: the section has zero area")
    if area < 0:
        p = p[::-1]

    hull = ConvexHull(p)
    if hull.volume > 1.01 * abs(area):
        raise InputError(f"{where}: the section is not convex (its area is {100 * (1 - abs(area) / hull.volume):.1f} % "
                         "below its convex hull); the model builder needs convex sections as the image stage writes")
    return p[hull.vertices]


def _area(p: np.ndarray) -> float:
    x, y = p[:, 0], p[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


def _self_intersects(p: np.ndarray) -> bool:
    """True if two non-adjacent edges of the closed polygon (n, 2) cross (O(n^2), n <= a few 1000)."""
    a, b = p, np.roll(p, -1, axis=0)
    n = len(p)

    def orient(p1, p2, q):
        return np.sign((p2[..., 0] - p1[..., 0]) * (q[..., 1] - p1[..., 1])
                       - (p2[..., 1] - p1[..., 1]) * (q[..., 0] - p1[..., 0]))

    A, B = a[:, None], b[:, None]
    C, D = a[None, :], b[None, :]
    cross = (orient(A, B, C) * orient(A, B, D) < 0) & (orient(C, D, A) * orient(C, D, B) < 0)
    i, j = np.triu_indices(n, k=2)
    keep = ~((i == 0) & (j == n - 1))
    return bool(cross[i[keep], j[keep]].any())


def load_sections(path: str | Path) -> tuple[np.ndarray, list[np.ndarray], str]:
    """Read sections.json -> (z (K,), [polygon (n_k, 2)], sha256 of the file)."""
    path = Path(path)
    if path.is_dir():
        path = path / "sections.json"
    if not path.is_file():
        raise InputError(f"no sections file at {path}: run `pipeline.py reconstruct` first or use --preset")
    raw = path.read_bytes()
    try:
        data = json.loads(raw)
        secs = data["sections"]
        z = [float(s["z"]) for s in secs]
        pts = [s["points"] for s in secs]
    except (ValueError, KeyError, TypeError) as exc:
        raise InputError(f"{path}: not a sections.json ({exc}); expected "
                         '{"units": "mm", "sections": [{"z": .., "points": [[x, y], ..]}, ..]}') from None
    if data.get("units", "mm") != "mm":
        raise InputError(f"{path}: units must be mm, got {data.get('units')}")
    for s in secs:
        if s.get("closed", True) is False:
            raise InputError(f"{path}: section at z={s['z']} is marked as not closed")
    try:
        pts = [np.asarray(p, float) for p in pts]
    except (ValueError, TypeError):
        pts = [np.zeros((0, 2))]
    if (len(z) < 2 or not np.isfinite(z).all() or len(set(z)) != len(z)
            or any(p.ndim != 2 or p.shape[1:] != (2,) or len(p) < 3 or not np.isfinite(p).all() for p in pts)):
        raise InputError(f"{path}: expected two or more sections at distinct finite z, each with three or more "
                         "finite [x, y] points; re-run `pipeline.py reconstruct`")
    return np.array(z), pts, hashlib.sha256(raw).hexdigest()


def preset_sections(preset: str, dz_mm: float = 1.0, n: int = 720):
    """Sections of the parametric fingertip between its proximal cut and the start of the tip.

    Returns (z (K,), [polygon (n, 2)], sha256 of the preset parameters)."""
    shape = make_shape("fingertip", preset=preset, rod=False)
    z0 = shape.z_range_mm[0]
    z1 = shape.params["length"] - shape.params["cap"]       # start of the rounded tip
    z = np.linspace(z0, z1, int(round((z1 - z0) / dz_mm)) + 1)
    polys = [shape.convex_section(zi, n) for zi in z]
    digest = hashlib.sha256(json.dumps({"preset": preset, "shape": shape.params, "dz_mm": dz_mm, "n": n},
                                       sort_keys=True, default=str).encode()).hexdigest()
    return z, polys, digest


def tip_length(z: np.ndarray, polys: list, k: int) -> float:
    """Length (mm) of the rounded tip beyond section k: the quarter ellipse from section k's width
    (its half-axis) through the last section's width, w = W sqrt(1 - ((z - z_k) / h)^2)."""
    if k + 1 >= len(z):
        raise InputError(f"no sections beyond z={z[k]:g} mm to measure the rounded tip from; give its "
                         "length (--tip MM) or a shorter z range")
    w_ratio = np.ptp(polys[-1][:, 0]) / np.ptp(polys[k][:, 0])
    if w_ratio >= 1:
        raise InputError(f"the sections beyond z={z[k]:g} mm do not narrow into a tip; give its length "
                         "(--tip MM)")
    return float((z[-1] - z[k]) / np.sqrt(1.0 - w_ratio**2))


def body_z_range(z: np.ndarray, polys: list, tip_width_frac: float) -> tuple[float, float]:
    """z range from the first section to the last one, distal of the widest, still at least
    tip_width_frac of the widest width. Beyond it the model ends in a flat cut (thesis 6.1) or, with
    ModelParams.tip_mm, in domes."""
    if not 0 < tip_width_frac <= 1:
        raise InputError(f"tip_width_frac must be in (0, 1]; got {tip_width_frac}")
    width = np.array([np.ptp(p[:, 0]) for p in polys])
    k = int(np.argmax(width))
    while k + 1 < len(z) and width[k + 1] >= tip_width_frac * width.max():
        k += 1
    return float(z[0]), float(z[k])


def smooth_polygon(p: np.ndarray, spacing_mm: float) -> np.ndarray:
    """(N, 2) the closed convex polygon p (n, 2, CCW) as a smooth curve: the periodic cubic spline
    through its vertices (chord-length parameter) sampled every spacing_mm or closer, and of
    those samples their convex hull (CCW; a spline can bulge inwards by round-off between nearly
    collinear vertices). A polygon's vertices are corners that a fine enough mesh resolves (on a
    720-vertex preset section, every 0.03 mm on the pad); the spline's are not."""
    p = np.asarray(p, float)
    closed = np.vstack([p, p[:1]])
    s = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(closed, axis=0), axis=1))]
    spline = CubicSpline(s, closed, bc_type="periodic")
    t = np.linspace(0.0, s[-1], int(np.ceil(s[-1] / spacing_mm)), endpoint=False)
    q = spline(t)
    return q[ConvexHull(q).vertices]
