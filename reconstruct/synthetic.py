"""Orthographic turntable renderer of a solid with known sections (fem.presets shapes), for tests,
benchmarks and sample_images/, and the comparison of reconstructed sections with that solid.

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
from tqdm import tqdm

from common.errors import InputError
from common.staging import staged_output, write_json

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

    def __init__(self, size_px, mm_per_px, aspect, axis_offset_px, tilt_deg):
        w, h = size_px
        self.sx, self.sy = mm_per_px, mm_per_px * aspect
        rows, cols = np.mgrid[0:h, 0:w].astype(float)
        dx = (cols - (w / 2 + axis_offset_px)) * self.sx
        dy = (h - 0.5 - rows) * self.sy
        ta = np.deg2rad(tilt_deg)
        self.u = dx * np.cos(ta) - dy * np.sin(ta)
        self.s = dx * np.sin(ta) + dy * np.cos(ta)
        r2 = ((cols - w / 2) / (w / 2)) ** 2 + ((rows - h / 2) / (h / 2)) ** 2
        self.light = 1.0 - r2 / 2.0   # 1 at the centre, 0 at the corners before scaling


def _photograph(coverage, cam, blur_px, noise, vignetting, rng):
    """Grey uint8 image of a dark object (coverage) on a bright background."""
    radiance = BACKGROUND + (OBJECT - BACKGROUND) * coverage
    if blur_px > 0:
        radiance = cv2.GaussianBlur(radiance, (0, 0), blur_px)
    img = radiance * (1.0 - vignetting * (1.0 - cam.light))
    img = img + rng.normal(0.0, noise, img.shape) if noise > 0 else img
    return np.clip(np.rint(img), 0, 255).astype(np.uint8)


def render_turntable(shape, out_dir, n_views: int = 100, span_deg: float = 360.0,
                     size_px=(700, 900), mm_per_px: float = 0.04, aspect: float = 1.0,
                     blur_px: float = 0.8, noise: float = 2.0, vignetting: float = 0.25,
                     axis_offset_px: float = 0.0, tilt_deg: float = 0.0, seed: int = 0,
                     template_diameter_mm: float = 12.7, progress: bool = False,
                     image_format: str = "png") -> dict:
    """Render a turntable folder: `view_XXX.XXdeg.png` images, `calibration.png` (a dark disc of
    `template_diameter_mm` on its shaft), `turntable.toml`, and `truth.json`.

    size_px: (W, H). Views at theta_i = i * span_deg / n_views. The body is placed with z = 0 at
    2.5 mm above the bottom edge (rod below it). Returns the truth dictionary.
    """
    if n_views < 1 or span_deg <= 0 or mm_per_px <= 0 or aspect <= 0 or min(size_px) < 16:
        raise InputError("render needs views >= 1, span > 0, mm-per-px > 0, aspect > 0 and images >= 16 px")
    rng = np.random.default_rng(seed)
    cam = _Camera(size_px, mm_per_px, aspect, axis_offset_px, tilt_deg)
    z0_s = 2.5 - shape.z_range_mm[0]            # the body starts 2.5 mm above the bottom edge
    s_grid = np.arange(-2.0, cam.s.max() + 2.0, min(mm_per_px, mm_per_px * aspect) / 4)
    thetas = np.arange(n_views) * span_deg / n_views
    n_dirs = np.column_stack([-np.cos(np.deg2rad(thetas)), np.sin(np.deg2rad(thetas))])
    h = shape.extent_table(s_grid - z0_s, np.vstack([n_dirs, -n_dirs]))

    names = []
    with staged_output(out_dir) as tmp:
        for i in tqdm(range(n_views), desc="render", unit="view", disable=not progress):
            cov = _interval_image(-h[:, n_views + i], h[:, i], s_grid, cam.u, cam.s, cam.sx, cam.sy)
            name = f"view_{i:03d}_{thetas[i]:07.3f}deg.{image_format}"
            cv2.imwrite(str(tmp / name), _photograph(cov, cam, blur_px, noise, vignetting, rng))
            names.append(name)
        # calibration template: a disc on a shaft of the rod's diameter, axis at the same place
        r_t = template_diameter_mm / 2
        sc = cam.s.max() / 2 + 1.0
        ss = s_grid - sc
        half = np.sqrt(np.clip(r_t**2 - ss**2, 0, None))
        half = np.where(np.abs(ss) < r_t, half, -np.inf)
        shaft = max(shape.rod_radius_mm, 0.5)
        half = np.where(ss < 0, np.maximum(half, shaft), half)
        cov = _interval_image(-half, half, s_grid, cam.u, cam.s, cam.sx, cam.sy)
        cv2.imwrite(str(tmp / f"calibration.{image_format}"),
                    _photograph(cov, cam, blur_px, noise, vignetting, rng))
        (tmp / "turntable.toml").write_text(
            f"# synthetic turntable set rendered by reconstruct.synthetic\n"
            f"start_deg = 0.0\nstep_deg = {span_deg / n_views!r}\n"
            f"template_diameter_mm = {template_diameter_mm!r}\naxis = \"vertical\"\n"
            f"volar_view_deg = 0.0\n")
        truth = {
            "shape": shape.name, "params": {k: v for k, v in shape.params.items()},
            "z_range_mm": list(shape.z_range_mm), "rod_radius_mm": shape.rod_radius_mm,
            "views": n_views, "span_deg": span_deg, "size_px": list(size_px),
            "mm_per_px": mm_per_px, "aspect": aspect, "blur_px": blur_px, "noise": noise,
            "vignetting": vignetting, "axis_offset_px": axis_offset_px, "tilt_deg": tilt_deg,
            "z0_s_mm": z0_s, "seed": seed, "template_diameter_mm": template_diameter_mm,
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
    to the true convex section, in mm and px, and the volume of the lofted sections vs the true
    (convex) volume over the same z range.
    """
    shift = doc["calibration"]["z_offset_mm"] - truth["z0_s_mm"]     # shape z = z + shift
    dists = []
    for sec in doc["sections"]:
        dists.append(point_polygon_distance(np.array(sec["points"]),
                                            shape.convex_section(sec["z"] + shift, 720)))
    d = np.concatenate(dists)
    z = np.array([sec["z"] for sec in doc["sections"]])
    px = truth["mm_per_px"]
    return {"mean_px": float(d.mean() / px), "max_px": float(d.max() / px),
            "mean_mm": float(d.mean()), "max_mm": float(d.max()),
            "per_section_max_px": [float(x.max() / px) for x in dists],
            "true_volume_mm3": shape.volume_mm3(z[0] + shift, z[-1] + shift),
            "z_shift_mm": shift}
