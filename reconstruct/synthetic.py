"""Turntable renderer (parallel projection or pinhole camera) of a solid with known sections
(fem.geometry.presets shapes), for tests, benchmarks and sample_images/, and the comparison of
reconstructed sections with that solid.

The solid is any object with `name`, `params` (JSON-ready dict), `z_range_mm`, `rod_radius_mm`,
`extent_table(z_mm, directions)` and, for the comparison, `convex_section(z_mm, n)` and
`volume_mm3(z_lo, z_hi)`.

Geometry and conventions (the same ones `reconstruct` inverts):
- Finger frame: rotation axis = z (proximal -> distal), volar pad towards +y, x lateral; the
  rotation axis passes through the origin of every section.
- View angle theta: the object is turned counter-clockwise about +z (seen from the distal tip) by
  theta; the camera looks along -y of the turntable, so theta = 0 looks straight at the pad.
  Image right is -x of the turned object, image up is +z (the axis is vertical, tip at the top,
  rod entering from the bottom edge).
- So at view theta the right border is the support function h(n) of the section in direction
  n = (-cos theta, sin theta) and the left border is -h(-n), both measured from the axis.
- Image geometry: the axis crosses the bottom image edge at column `W/2 + axis_offset_px` and
  leans by `tilt_deg` (positive: top of the axis to the right). `s_mm` is the distance along the
  axis from that crossing point; shape z = s_mm - `z0_s_mm`.
"""
from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np

from fingertip.errors import InputError
from fingertip.progress import as_progress
from fingertip.staging import staged_output, write_json
from reconstruct.lens import Lens

BACKGROUND, OBJECT = 245.0, 25.0   # grey levels at full illumination


def _interval_image(a_mm, b_mm, s_grid_mm, u_px, s_px, sx, sy, sub=4):
    """Coverage (H, W) in [0, 1] of an object that spans u in [a(s), b(s)] at axial position s.

    a_mm, b_mm: tables over s_grid_mm (b < a where nothing is there); u_px, s_px: (H, W) pixel
    centre coordinates in mm. Exact box-filter overlap along u, `sub` sub-rows along s.
    """
    cov = np.zeros(u_px.shape)
    for k in range(sub):
        s = s_px + ((k + 0.5) / sub - 0.5) * sy
        a = np.interp(s, s_grid_mm, a_mm, left=np.inf, right=np.inf)
        b = np.interp(s, s_grid_mm, b_mm, left=-np.inf, right=-np.inf)
        lo = np.maximum(a, u_px - 0.5 * sx)
        hi = np.minimum(b, u_px + 0.5 * sx)
        cov += np.clip(hi - lo, 0.0, None) / sx
    return cov / sub


class _Camera:
    """Pixel centres -> (u, s) mm in the axis frame; see the module docstring."""

    def __init__(self, size_px, mm_per_px, aspect, axis_offset_px, tilt_deg, ideal=None):
        w, h = size_px
        self.sx, self.sy = mm_per_px, mm_per_px * aspect
        rows, cols = np.mgrid[0:h, 0:w].astype(float)
        r2 = ((cols - w / 2) / (w / 2)) ** 2 + ((rows - h / 2) / (h / 2)) ** 2
        self.light = 1.0 - r2 / 2.0   # 1 at the centre, 0 at the corners before scaling
        if ideal is not None:         # a lens with distortion: where each pixel looks in the ideal image
            c, r = ideal(cols.ravel(), rows.ravel())
            cols, rows = c.reshape(cols.shape), r.reshape(rows.shape)
        dx = (cols - (w / 2 + axis_offset_px)) * self.sx
        dy = (h - 0.5 - rows) * self.sy
        ta = np.deg2rad(tilt_deg)
        self.u = dx * np.cos(ta) - dy * np.sin(ta)
        self.s = dx * np.sin(ta) + dy * np.cos(ta)


def _chains(shape, z_tab, z0_s, n_dirs: int = 360):
    """Tangent-polygon vertices (len(z_tab), n_dirs, 2) of the body's sections (NaN where there
    is none) and each vertex's outward normal angle (n_dirs,)."""
    phi = np.linspace(0.0, 2 * np.pi, n_dirs, endpoint=False)
    h = shape.extent_table(z_tab - z0_s, np.column_stack([np.cos(phi), np.sin(phi)]))
    h = np.where(np.isfinite(h), h, np.nan)
    h1, p1 = np.roll(h, -1, axis=1), np.roll(phi, -1)
    det = np.sin(2 * np.pi / n_dirs)
    x = (h * np.sin(p1) - h1 * np.sin(phi)) / det
    y = (np.cos(phi) * h1 - np.cos(p1) * h) / det
    return np.stack([x, y], axis=-1), phi + np.pi / n_dirs


def _chord_table(verts, normal, theta, w_grid, side):
    """(n_z, n_w) outermost u of each section on the lines w = w_grid in the view frame of
    view theta (rad): max u (side +1) or min u (side -1); -/+inf where the line misses it."""
    n_r = np.array([-np.cos(theta), np.sin(theta)])
    m = np.array([-np.sin(theta), -np.cos(theta)])
    psi = np.mod(normal - (np.pi - theta) + np.pi, 2 * np.pi) - np.pi       # view-frame normal angle
    idx = np.flatnonzero(np.abs(psi) < np.pi / 2) if side > 0 else np.flatnonzero(np.abs(psi) >= np.pi / 2)
    key = psi[idx] if side > 0 else np.mod(psi[idx], 2 * np.pi)
    idx = idx[np.argsort(key)]
    if side < 0:
        idx = idx[::-1]                                  # increasing w along the chain
    u, w = verts[:, idx] @ n_r, verts[:, idx] @ m
    empty = ~np.isfinite(u).all(axis=1)
    u, w = np.where(empty[:, None], 0.0, u), np.where(empty[:, None], np.arange(len(idx)) * 1e-3, w)
    w = np.maximum.accumulate(w, axis=1)
    big = 4 * (np.abs(w).max() + np.abs(w_grid).max()) + 10.0
    off = np.arange(len(u))[:, None] * big
    out = np.interp((w_grid[None] + off).ravel(), (w + off).ravel(), u.ravel()).reshape(len(u), len(w_grid))
    miss = empty[:, None] | (w_grid[None] < w[:, :1]) | (w_grid[None] > w[:, -1:])
    return np.where(miss, -side * np.inf, out)


def _perspective_borders(verts, normal, theta, z_tab, s_grid, w_grid, distance_mm, u_c, s_c):
    """Left and right silhouette border u (mm, axis plane) at axial positions s_grid of view theta
    (rad) seen by a pinhole camera at (u_c, s_c, -distance_mm); +inf / -inf where nothing is seen.
    The ray through (u, s) runs at height s_c + (s - s_c)(D + w)/D at depth w."""
    D, dz = distance_mm, z_tab[1] - z_tab[0]
    scale = D / (D + w_grid)                                          # (n_w,)
    f = (s_c + (s_grid[:, None] - s_c) / scale[None] - z_tab[0]) / dz
    i0 = np.clip(np.floor(f).astype(int), 0, len(z_tab) - 2)
    t = np.clip(f - i0, 0.0, 1.0)
    j = np.arange(len(w_grid))[None]
    out = []
    for side in (-1, 1):
        x = _chord_table(verts, normal, theta, w_grid, side)
        v0, v1 = x[i0, j], x[i0 + 1, j]
        both = np.isfinite(v0) & np.isfinite(v1)
        with np.errstate(invalid="ignore"):
            v = np.where(both, v0 + t * np.where(both, v1 - v0, 0.0), np.where(t < 0.5, v0, v1))
        img = u_c + (v - u_c) * scale[None]
        out.append(img.min(axis=1) if side < 0 else img.max(axis=1))
    return out[0], out[1]


def render_checkerboards(lens, n: int, inner_corners=(9, 6), square_mm: float = 3.0,
                         distance_mm: float = 120.0, blur_px: float = 0.8, noise: float = 2.0, rng=None):
    """n grey photos (H, W) uint8 of a flat checkerboard (inner_corners inner corners, squares of
    square_mm, a white margin of one square) seen through `lens` (reconstruct.lens.Lens): the
    board about distance_mm in front of the camera, tilted by 25-40 deg about axes that turn
    round from photo to photo, long side along the longer image side; every other photo is
    moved towards an image corner (as one calibrates a lens: fill the frame, corners too)."""
    rng = rng if rng is not None else np.random.default_rng(0)
    w, h = lens.size_px
    (fx, fy), (cx, cy) = lens.focal_px, lens.principal_px
    nx, ny = inner_corners
    cols, rows = np.meshgrid(np.arange(w, dtype=float), np.arange(h, dtype=float))
    ic, ir = lens.undistort(cols.ravel(), rows.ravel())
    sub = (np.arange(4) + 0.5) / 4 - 0.5                       # 4 x 4 samples per pixel
    centre = np.array([(nx - 1) / 2, (ny - 1) / 2, 0.0]) * square_mm
    half_w, half_h = 0.5 * w / fx * distance_mm, 0.5 * h / fy * distance_mm
    long_, short = (nx + 1) * square_mm, (ny + 1) * square_mm
    span = (short, long_) if h > w else (long_, short)                  # board extent in the image, mm
    photos = []
    for i in range(n):
        a = 2 * np.pi * i / n
        tilt = np.deg2rad(25.0 + 15.0 * (i % 3) / 2)
        spin = (np.pi / 2 if h > w else 0.0) + np.deg2rad(8.0 * np.sin(3 * a))
        rot = cv2.Rodrigues(np.array([np.cos(a), np.sin(a), 0.0]) * tilt)[0] @ \
            cv2.Rodrigues(np.array([0.0, 0.0, spin]))[0]
        reach = np.array([max(half_w - 0.5 * span[0], 0.0), max(half_h - 0.5 * span[1], 0.0)])
        corner = np.array([np.sign(np.cos(a + 0.4)), np.sign(np.sin(a + 0.4))]) if i % 2 else np.zeros(2)
        where = np.array([*(0.8 * reach * corner), distance_mm * (1.0 + 0.05 * np.cos(a))])
        t = where - rot @ centre
        normal = rot[:, 2]
        d = np.column_stack([(ic - cx) / fx, (ir - cy) / fy, np.ones(len(ic))])
        q = ((d * ((normal @ t) / (d @ normal))[:, None] - t) @ rot / square_mm)[:, :2].reshape(h, w, 2)
        q_col, q_row = np.gradient(q, axis=1), np.gradient(q, axis=0)     # board squares per px
        val = np.zeros((h, w))
        for du in sub:                   # the board is smooth over a pixel: linear within it
            for dv in sub:
                a, b = (q[..., k] + du * q_col[..., k] + dv * q_row[..., k] for k in (0, 1))
                black = (np.floor(a) + np.floor(b)) % 2 == 0
                board = (a >= -1) & (a < nx) & (b >= -1) & (b < ny)
                paper = (a >= -2) & (a < nx + 1) & (b >= -2) & (b < ny + 1)
                val += np.where(board & black, 0.1, np.where(paper, 0.92, 0.45))
        img = 255.0 * val / len(sub) ** 2
        if blur_px > 0:
            img = cv2.GaussianBlur(img, (0, 0), blur_px)
        img = img + rng.normal(0.0, noise, img.shape) if noise > 0 else img
        photos.append(np.clip(np.rint(img), 0, 255).astype(np.uint8))
    return photos


def _photograph(coverage, cam, blur_px, noise, vignetting, rng):
    """Grey uint8 image of a dark object (coverage) on a bright background."""
    radiance = BACKGROUND + (OBJECT - BACKGROUND) * coverage
    if blur_px > 0:
        radiance = cv2.GaussianBlur(radiance, (0, 0), blur_px)
    img = radiance * (1.0 - vignetting * (1.0 - cam.light))
    img = img + rng.normal(0.0, noise, img.shape) if noise > 0 else img
    return np.clip(np.rint(img), 0, 255).astype(np.uint8)


def _check_render_options(n_views: int, span_deg: float, size_px, mm_per_px: float, aspect: float,
                          camera_distance_mm: float | None, write_camera: bool, distortion, checkerboard: int) -> None:
    """Refuse render_turntable's options out of range or that need a camera distance (InputError)."""
    if n_views < 1 or span_deg <= 0 or mm_per_px <= 0 or aspect <= 0 or min(size_px) < 16:
        raise InputError("render needs views >= 1, span > 0, mm-per-px > 0, aspect > 0 and images >= 16 px")
    if camera_distance_mm is not None and not camera_distance_mm > 0:
        raise InputError(f"--camera-distance-mm must be positive, got {camera_distance_mm}")
    if write_camera and camera_distance_mm is None:
        raise InputError("--write-camera needs --camera-distance-mm")
    if (distortion is not None or checkerboard) and camera_distance_mm is None:
        raise InputError("--distortion and --checkerboard need --camera-distance-mm (the lens's focal length)")
    if checkerboard and checkerboard < 5:
        raise InputError(f"--checkerboard needs at least 5 photos, got {checkerboard}")


def _pinhole_lens(size_px, mm_per_px: float, aspect: float, camera_distance_mm: float, distortion) -> Lens:
    """The rendering camera's lens: focal length camera_distance_mm / mm_per_px px (over aspect
    vertically), principal point at the image centre, radial distortion (k1[, k2]) or none."""
    w_px, h_px = size_px
    matrix = np.array([[camera_distance_mm / mm_per_px, 0.0, (w_px - 1) / 2],
                       [0.0, camera_distance_mm / (mm_per_px * aspect), (h_px - 1) / 2], [0.0, 0.0, 1.0]])
    k = [float(x) for x in (distortion or ())][:2]
    return Lens(matrix, np.array(k + [0.0] * (5 - len(k))), 0.0, 0, tuple(size_px))


def _view_borders(shape, cam: _Camera, size_px, axis_offset_px: float, tilt_deg: float,
                  camera_distance_mm: float | None, z0_s: float, s_grid: np.ndarray, thetas: np.ndarray):
    """A function of the view index i giving the silhouette's left and right borders u (mm) on
    s_grid at view thetas[i] (deg): from the shape's extent table in parallel projection
    (camera_distance_mm None), else seen by the pinhole camera that far from the axis."""
    n_views = len(thetas)
    n_dirs = np.column_stack([-np.cos(np.deg2rad(thetas)), np.sin(np.deg2rad(thetas))])
    if camera_distance_mm is None:
        h = shape.extent_table(s_grid - z0_s, np.vstack([n_dirs, -n_dirs]))
        return lambda i: (-h[:, n_views + i], h[:, i])
    w_px, h_px = size_px
    ta = np.deg2rad(tilt_deg)
    dx, dy = ((w_px - 1) / 2 - (w_px / 2 + axis_offset_px)) * cam.sx, (h_px - 0.5 - (h_px - 1) / 2) * cam.sy
    u_c, s_c = dx * np.cos(ta) - dy * np.sin(ta), dx * np.sin(ta) + dy * np.cos(ta)
    ext = shape.extent_table(np.linspace(*shape.z_range_mm, 9), n_dirs)
    reach = 1.2 * max(np.abs(ext[np.isfinite(ext)]).max(), 1.0)
    if reach >= 0.5 * camera_distance_mm:
        raise InputError(f"--camera-distance-mm {camera_distance_mm} is inside or too close to the body: "
                         f"give at least {2 * reach:.0f} mm")
    dz = s_grid[1] - s_grid[0]
    margin = np.ceil((np.abs(s_grid - s_c).max() * reach / (camera_distance_mm - reach) + 0.5) / dz)
    z_tab = s_grid[0] + dz * np.arange(-margin, len(s_grid) + margin)       # s_grid extended
    verts, normal = _chains(shape, z_tab, z0_s)
    w_grid = np.arange(-reach, reach, min(0.04, 0.5 * min(cam.sx, cam.sy)))
    return lambda i: _perspective_borders(verts, normal, np.deg2rad(thetas[i]), z_tab, s_grid, w_grid,
                                          camera_distance_mm, u_c, s_c)


def _template_coverage(shape, cam: _Camera, s_grid: np.ndarray, template_diameter_mm: float) -> np.ndarray:
    """Coverage (H, W) of the calibration template: a disc on a shaft of the rod's diameter, axis at
    the same place."""
    r_t = template_diameter_mm / 2
    sc = cam.s.max() / 2 + 1.0
    ss = s_grid - sc
    half = np.sqrt(np.clip(r_t**2 - ss**2, 0, None))
    half = np.where(np.abs(ss) < r_t, half, -np.inf)
    shaft = max(shape.rod_radius_mm, 0.5)
    half = np.where(ss < 0, np.maximum(half, shaft), half)
    return _interval_image(-half, half, s_grid, cam.u, cam.s, cam.sx, cam.sy)


def _manifest(step_deg: float, template_diameter_mm: float, camera_distance_mm: float | None = None,
              board=None) -> str:
    """turntable.toml of a rendered folder: camera_distance_mm when given, the checkerboard keys when
    board = (inner corners, square mm) is given."""
    return (f"# synthetic turntable set rendered by reconstruct.synthetic\n"
            f"start_deg = 0.0\nstep_deg = {step_deg!r}\n"
            f"template_diameter_mm = {template_diameter_mm!r}\naxis = \"vertical\"\n"
            f"volar_view_deg = 0.0\n"
            + (f"camera_distance_mm = {camera_distance_mm!r}\n" if camera_distance_mm is not None else "")
            + (f"checkerboard_inner_corners = {list(board[0])}\n"
               f"checkerboard_square_mm = {board[1]!r}\n" if board is not None else ""))


def render_turntable(shape, out_dir, n_views: int = 100, span_deg: float = 360.0,
                     size_px=(700, 900), mm_per_px: float = 0.04, aspect: float = 1.0,
                     blur_px: float = 0.8, noise: float = 2.0, vignetting: float = 0.25,
                     axis_offset_px: float = 0.0, tilt_deg: float = 0.0, seed: int = 0,
                     template_diameter_mm: float = 12.7, progress=None,
                     image_format: str = "png", camera_distance_mm: float | None = None,
                     write_camera: bool = False, distortion: tuple[float, ...] | None = None,
                     checkerboard: int = 0, checkerboard_inner_corners: tuple[int, int] = (9, 6),
                     checkerboard_square_mm: float = 3.0) -> dict:
    """Render a turntable folder: `view_XXX.XXdeg.png` images, `calibration.png` (a dark disc of
    `template_diameter_mm` on its shaft), `turntable.toml`, and `truth.json`.

    size_px: (W, H). Views at theta_i = i * span_deg / n_views. The body is placed with z = 0 at
    2.5 mm above the bottom edge (rod below it). camera_distance_mm: a pinhole camera that far
    from the rotation axis, looking at the image centre (None: parallel projection); mm_per_px
    holds in the plane of the axis, where the flat template disc stands. write_camera: also
    write camera_distance_mm into turntable.toml. distortion: (k1[, k2]) radial Brown distortion
    of the lens (needs camera_distance_mm; focal length distance / mm_per_px px, principal point
    at the image centre): every image is rendered through it by mapping each output pixel to
    where it looks in the ideal image. checkerboard: also render that many photos of a printed
    board (checkerboard_inner_corners, checkerboard_square_mm) at different tilts, about the
    camera distance away, into checkerboard/, and the board keys into turntable.toml.
    Returns the truth dictionary.
    """
    _check_render_options(n_views, span_deg, size_px, mm_per_px, aspect, camera_distance_mm, write_camera,
                          distortion, checkerboard)
    rng = np.random.default_rng(seed)
    lens = (None if camera_distance_mm is None else
            _pinhole_lens(size_px, mm_per_px, aspect, camera_distance_mm, distortion))
    cam = _Camera(size_px, mm_per_px, aspect, axis_offset_px, tilt_deg,
                  lens.undistort if distortion is not None else None)
    z0_s = 2.5 - shape.z_range_mm[0]            # the body starts 2.5 mm above the bottom edge
    s_grid = np.arange(-2.0, cam.s.max() + 2.0, min(mm_per_px, mm_per_px * aspect) / 4)
    thetas = np.arange(n_views) * span_deg / n_views
    borders = _view_borders(shape, cam, size_px, axis_offset_px, tilt_deg, camera_distance_mm, z0_s, s_grid,
                            thetas)

    with staged_output(out_dir) as tmp:
        for i in as_progress(progress).bar(range(n_views), desc="render", unit="view"):
            a, b = borders(i)
            cov = _interval_image(a, b, s_grid, cam.u, cam.s, cam.sx, cam.sy)
            name = f"view_{i:03d}_{thetas[i]:07.3f}deg.{image_format}"
            cv2.imwrite(str(tmp / name), _photograph(cov, cam, blur_px, noise, vignetting, rng))
        cov = _template_coverage(shape, cam, s_grid, template_diameter_mm)
        cv2.imwrite(str(tmp / f"calibration.{image_format}"), _photograph(cov, cam, blur_px, noise, vignetting, rng))
        (tmp / "turntable.toml").write_text(_manifest(
            span_deg / n_views, template_diameter_mm, camera_distance_mm if write_camera else None,
            (checkerboard_inner_corners, checkerboard_square_mm) if checkerboard else None))
        if checkerboard:
            (tmp / "checkerboard").mkdir()
            for i, img in enumerate(render_checkerboards(lens, checkerboard, checkerboard_inner_corners,
                                                         checkerboard_square_mm, camera_distance_mm,
                                                         blur_px, noise, rng)):
                cv2.imwrite(str(tmp / "checkerboard" / f"board_{i:02d}.{image_format}"), img)
        truth = {
            "shape": shape.name, "params": {k: v for k, v in shape.params.items()},
            "z_range_mm": list(shape.z_range_mm), "rod_radius_mm": shape.rod_radius_mm,
            "views": n_views, "span_deg": span_deg, "size_px": list(size_px),
            "mm_per_px": mm_per_px, "aspect": aspect, "blur_px": blur_px, "noise": noise,
            "vignetting": vignetting, "axis_offset_px": axis_offset_px, "tilt_deg": tilt_deg,
            "z0_s_mm": z0_s, "seed": seed, "template_diameter_mm": template_diameter_mm,
            "camera_distance_mm": camera_distance_mm,
            "distortion": None if distortion is None else [float(x) for x in distortion],
            "camera_matrix": None if lens is None else lens.matrix.tolist(),
            "checkerboard": checkerboard,
            "note": "shape z = s_mm - z0_s_mm; s_mm: distance along the axis from where it "
                    "crosses the bottom image edge",
        }
        write_json(tmp / "truth.json", truth)
    return truth


def load_truth(folder) -> dict:
    """The truth dictionary render_turntable wrote to a rendered folder (truth.json)."""
    return json.loads((Path(folder) / "truth.json").read_text())


def point_polygon_distance(points: np.ndarray, polygon: np.ndarray) -> np.ndarray:
    """(n,) distance in mm from each point (n, 2) to a closed polygon's boundary (k, 2)."""
    a = polygon
    b = np.roll(polygon, -1, axis=0)
    ab = b - a
    ap = points[:, None, :] - a[None]
    t = np.clip((ap * ab).sum(-1) / np.maximum((ab * ab).sum(-1), 1e-300), 0.0, 1.0)
    d = ap - t[..., None] * ab
    return np.sqrt((d * d).sum(-1)).min(axis=1)


def compare_to_truth(doc: dict, shape, truth: dict) -> dict:
    """Errors of a sections.json document against the shape a folder was rendered from.

    truth: that folder's truth dictionary (load_truth). Distances from reconstructed section points
    to the true convex section (the nearest end section for one placed outside the body), in mm
    and px, and the volume of the lofted sections vs the true
    (convex) volume over the same z range.
    """
    shift = doc["calibration"]["z_offset_mm"] - truth["z0_s_mm"]     # shape z = z + shift
    lo, hi = shape.z_range_mm
    dists = []
    for sec in doc["sections"]:
        # a section placed outside the body is compared with the body's nearest end section
        z = min(max(sec["z"] + shift, lo + 1e-6), hi - 1e-3)
        dists.append(point_polygon_distance(np.array(sec["points"]), shape.convex_section(z, 720)))
    d = np.concatenate(dists)
    z = np.array([sec["z"] for sec in doc["sections"]])
    px = truth["mm_per_px"]
    return {"mean_px": float(d.mean() / px), "max_px": float(d.max() / px),
            "mean_mm": float(d.mean()), "max_mm": float(d.max()),
            "per_section_max_px": [float(x.max() / px) for x in dists],
            "true_volume_mm3": shape.volume_mm3(z[0] + shift, z[-1] + shift),
            "z_shift_mm": shift}
