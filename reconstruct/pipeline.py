"""The image stage end to end: turntable folder -> sections.json, surface.stl, report.png."""
from __future__ import annotations

import hashlib
import json
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import NamedTuple

import numpy as np
from threadpoolctl import threadpool_limits

from fingertip.errors import InputError
from fingertip.progress import as_progress
from fingertip.staging import staged_output, write_json
from reconstruct.calibrate import Frame, estimate_axis, sample_borders, template_scale
from reconstruct.camera import Camera, border_tables, perspective_fit, proximal_cut
from reconstruct.checks import (
    CUT_SEARCH_PX,
    CUT_TOL_PX,
    ROD_MARGIN_PX,
    TANGENT_TOL_PX,
    check_parallel,
    consistent_sections,
)
from reconstruct.lens import Lens, calibrate_lens, undistort_borders
from reconstruct.report import write_report
from reconstruct.sections import (
    N_POINTS,
    choose_levels,
    convex_section,
    fit_support,
    harmonics_for,
    support_curve,
    support_samples,
    support_values,
    tangent_polygon,
)
from reconstruct.silhouette import Borders, extract_borders
from reconstruct.surface import loft
from reconstruct.turntable import Turntable, load_turntable


@dataclass
class Reconstruction:
    """Everything the image stage found; `summary()` is the one-screen report."""

    table: Turntable
    frame: Frame
    z_mm: np.ndarray                      # (m,) section positions, 0 at the proximal end
    sections: list[np.ndarray]            # m arrays (N_POINTS, 2), CCW, finger frame, mm
    polygons: list[np.ndarray]            # tangent polygons at the same z
    surface: object                       # trimesh.Trimesh
    z_offset_mm: float                    # s (mm along the axis from the bottom edge) of z = 0
    trims: dict
    axis_fit: dict
    timings_s: dict
    turned_180: bool = False              # the rod entered from the top: images were turned
    warnings: list[str] = field(default_factory=list)
    camera: dict = field(default_factory=dict)   # pinhole camera and lens (empty: parallel projection)

    def summary(self) -> str:
        sc, fr, t = self.frame.scale, self.frame, self.table
        dz = np.diff(self.z_mm)
        lines = [
            f"views used      {len(t.image_paths)} over {t.coverage_deg:.1f} deg",
            f"scale           {sc.sx_mm * 1000:.3f} x {sc.sy_mm * 1000:.3f} um/px (aspect {sc.aspect:.4f}, "
            f"template fit {sc.rms_px:.3f} px rms)",
            f"rotation axis   offset {fr.offset_px(t.shape_px[1]):+.2f} px "
            f"from centre, tilt {fr.tilt_deg:+.3f} deg "
            f"(fit rms {self.axis_fit.get('axis_fit_rms_mm', 0) * 1000:.1f} um)",
            f"sections        {len(self.z_mm)}, z {self.z_mm[0]:.2f} .. {self.z_mm[-1]:.2f} mm, "
            f"spacing {dz.min():.2f} .. {dz.max():.2f} mm",
            f"camera          {self.camera_text()}",
            "trimmed         " + "; ".join(f"{k}: {v}" for k, v in self.trims.items()),
            f"surface         {len(self.surface.faces)} triangles, volume {self.surface.volume:.1f} mm^3, "
            f"watertight {self.surface.is_watertight}",
            "timings         " + ", ".join(f"{k} {v:.2f} s" for k, v in self.timings_s.items()),
        ]
        return "\n".join(lines + [f"warning: {w}" for w in self.warnings])


    def camera_text(self) -> str:
        """One line: the camera model used and where its distance came from."""
        c = self.camera
        if not c:
            return "parallel projection (no camera_distance_mm, no checkerboard/)"
        text = f"pinhole, {c['camera_distance_mm']:.1f} mm from the rotation axis ({c['camera_distance_source']})"
        if "distortion" in c:
            k1, k2, p1, p2 = c["distortion"][:4]
            text += (f"; lens from {c['lens_photos']} checkerboard photos ({c['lens_rms_px']:.3f} px rms): "
                     f"focal length {c['camera_matrix_px'][0][0]:.1f} px, k1 {k1:+.4f}, k2 {k2:+.4f}, "
                     f"p1 {p1:+.5f}, p2 {p2:+.5f}")
        return text


def _camera(table: Turntable, lens, scale, turned: bool) -> tuple[Camera | None, dict]:
    """The pinhole camera (None: parallel projection) and its record for the summary and
    sections.json. The distance is the manifest's camera_distance_mm or, without it, the
    checkerboard focal length (px) times the template's mm/px in the plane of the axis."""
    if lens is None:
        if table.camera_distance_mm is None:
            return None, {}
        return Camera(table.camera_distance_mm), {"camera_distance_mm": table.camera_distance_mm,
                                                  "camera_distance_source": "camera_distance_mm in turntable.toml"}
    (fx, fy) = lens.focal_px
    from_lens = 0.5 * (fx * scale.sx_mm + fy * scale.sy_mm)
    if table.camera_distance_mm is None:
        distance, source = from_lens, "checkerboard focal length x template scale"
    else:
        distance = table.camera_distance_mm
        source = f"camera_distance_mm in turntable.toml; the checkerboard gives {from_lens:.1f} mm"
    record = {"camera_distance_mm": distance, "camera_distance_source": source,
              "camera_distance_from_lens_mm": from_lens, "camera_matrix_px": lens.matrix.tolist(),
              "distortion": lens.dist.tolist(), "lens_rms_px": lens.rms_px, "lens_photos": lens.photos}
    return Camera(distance, (lens.turned180() if turned else lens).principal_px), record


def _rotate180(b: Borders, width_px: int) -> Borders:
    """Borders of the same view turned by 180 degrees in the image plane."""
    return Borders(width_px - 1 - b.right_px[::-1], width_px - 1 - b.left_px[::-1], b.frame_rows[::-1],
                   b.touches_bottom, b.touches_top, b.threshold, b.background, b.object)


def extract_all(table: Turntable, progress=None) -> list[Borders]:
    """Borders of every view (two threads: OpenCV and NumPy release the GIL; BLAS is kept to one
    thread each, its own threads would only compete with ours). progress: a `fingertip.progress`
    object, True (on stderr) or None (silent)."""
    def one(path):
        b = extract_borders(table.read(path), name=path.name)
        if not np.isfinite(b.left_px).any():
            raise InputError(f"the finger touches the image frame on every row of {path.name}: "
                             f"zoom out or re-centre it")
        return b

    # the bar appears only after a short delay and is closed on any error, so a refusal found in
    # the first views prints nothing but its error line
    with ThreadPoolExecutor(max_workers=2) as pool, threadpool_limits(limits=1, user_api="blas"):
        return list(as_progress(progress).bar(pool.map(one, table.image_paths), total=len(table.image_paths),
                                              desc="silhouettes", unit="view", delay=0.5))


def _trim(s: np.ndarray, width: np.ndarray, rod: bool, tip_fraction: float, ds: float,
          sy: float, margin_px: float = ROD_MARGIN_PX) -> tuple[float, float, dict]:
    """Axial range [s_lo, s_hi] to keep, from the widest-view width profile (NaN: not usable);
    margin_px: rows skipped after the rod-to-finger step."""
    valid = np.isfinite(width)
    if not valid.any():
        raise InputError("the finger touches the image frame on every row: zoom out or re-centre it")
    # largest contiguous run of usable rows
    edges = np.flatnonzero(np.diff(np.concatenate([[0], valid.astype(int), [0]])))
    runs = edges.reshape(-1, 2)
    a, b = runs[np.argmax(runs[:, 1] - runs[:, 0])]
    s, width = s[a:b], width[a:b]
    trims = {}
    if a > 0 or b < len(valid):
        trims["seen whole in every view"] = f"s {s[0]:.2f} .. {s[-1]:.2f} mm along the axis"
    w_max = width.max()
    lo = 0
    if rod:
        rod_w = np.median(width[: max(3, int(0.3 / ds))])
        if rod_w < 0.5 * w_max:
            body = np.flatnonzero(width > 1.5 * rod_w)
            lo = body[0] + int(np.ceil(margin_px * sy / ds))
            if lo >= len(s):
                raise InputError("too little of the finger beyond the rod is seen whole in every view: zoom out "
                                 "or re-centre it so that it is inside the image")
            trims["rod"] = f"{rod_w:.2f} mm wide, below s {s[lo]:.2f} mm"
    if lo == 0 and tip_fraction > 0:
        wide = np.flatnonzero(width >= tip_fraction * w_max)
        lo = wide[0]
        if lo > 0:
            trims["proximal end"] = f"narrower than {tip_fraction:.0%} of the widest section"
    hi = len(s) - 1
    if tip_fraction > 0:
        wide = np.flatnonzero(width[lo:] >= tip_fraction * w_max)
        hi = lo + wide[-1]
        if hi < len(s) - 1:
            trims["tip"] = f"beyond z {s[hi] - s[lo]:.2f} mm (narrower than {tip_fraction:.0%} of the widest)"
    if s[hi] - s[lo] < 2 * ds:
        raise InputError("nothing of the finger is left after trimming the rod and tip: check the images")
    return float(s[lo]), float(s[hi]), trims


class _Options(NamedTuple):
    """The section options of `reconstruct`: spacing_mm (min, max) and tol_mm for choose_levels,
    tip_fraction for _trim."""
    spacing_mm: tuple
    tol_mm: float
    tip_fraction: float


def _checked_options(spacing_mm, tol_mm: float, tip_fraction: float) -> _Options:
    """The options, refused (InputError) when out of range."""
    lo, hi = spacing_mm
    if not 0 < lo <= hi:
        raise InputError(f"section spacing must satisfy 0 < min <= max, got {lo} .. {hi} mm")
    if not tol_mm > 0:
        raise InputError(f"--tol-mm must be positive, got {tol_mm}")
    if not 0 <= tip_fraction < 1:
        raise InputError(f"--tip-fraction must be in [0, 1), got {tip_fraction}")
    return _Options(spacing_mm, tol_mm, tip_fraction)


def _silhouettes(table: Turntable, progress, timings: dict) -> tuple[Lens | None, Borders, list[Borders]]:
    """The lens calibrated on the checkerboard photos (None without them), the calibration
    template's borders and every view's, undistorted with the lens; each step's time (s) goes
    into timings ("lens", "silhouettes")."""
    lens = None
    if table.checkerboard_paths:
        t0 = time.perf_counter()
        lens = calibrate_lens([(p.name, table.read(p)) for p in table.checkerboard_paths],
                              table.checkerboard_inner_corners, table.checkerboard_square_mm)
        timings["lens"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    calib = extract_borders(table.read(table.calibration_path), name=table.calibration_path.name)
    views = extract_all(table, progress)
    if lens is not None:                  # border points into the ideal pinhole image
        calib = undistort_borders(calib, lens)
        views = [undistort_borders(b, lens) for b in views]
    timings["silhouettes"] = time.perf_counter() - t0
    return lens, calib, views


def _upright(views: list[Borders], calib: Borders, width_px: int) -> tuple[list[Borders], Borders, bool, bool]:
    """The views' and the template's borders turned by 180 deg when the rod enters from the top;
    whether they were turned, and whether there is a rod (more than half the views touch an edge)."""
    top = sum(b.touches_top for b in views)
    bottom = sum(b.touches_bottom for b in views)
    turned = top > bottom                     # rod enters from the top: turn everything by 180 deg
    if turned:
        views = [_rotate180(b, width_px) for b in views]
        calib = _rotate180(calib, width_px)
    rod = max(top, bottom) > len(views) // 2
    return views, calib, turned, rod


def _axis(table: Turntable, views: list[Borders], scale) -> tuple[Frame, dict]:
    """The finger frame, its rotation axis from turntable.toml when given there, else estimated from
    the views; and the record of the axis fit."""
    height_px, width_px = table.shape_px
    frame = Frame(scale, height_px)
    if table.axis_offset_px is not None or table.tilt_deg is not None:
        frame.x0_mm = (width_px / 2 + float(table.axis_offset_px or 0.0)) * scale.sx_mm
        frame.tilt_deg = float(table.tilt_deg or 0.0)
        axis_fit = {"source": "turntable.toml"}
    else:
        frame, axis_fit = estimate_axis(views, table.angles_deg, frame)
    return frame, axis_fit


class _Levels(NamedTuple):
    """Support-function fits of the sections at the chosen axial positions: levels (m,) s in mm;
    coef (2K+1, m); phi, h (2n, m) tangent directions (rad) and support values (mm); rms (m,) mm
    tangent disagreement; s_lo: s (mm) of z = 0; trims: what was cut off, for the summary."""
    levels: np.ndarray
    coef: np.ndarray
    phi: np.ndarray
    h: np.ndarray
    rms: np.ndarray
    s_lo: float
    trims: dict


def _sampling(table: Turntable, scale) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Axial positions s (mm) one pixel row apart, the view angles from the volar view (deg) and
    180 directions (rad) in which choose_levels compares the sections."""
    ds = scale.sy_mm
    s_fine = np.arange(0.0, table.shape_px[0] * scale.sy_mm, ds)
    theta = table.angles_deg - table.volar_view_deg
    dirs = np.linspace(0, 2 * np.pi, 180, endpoint=False)
    return s_fine, theta, dirs


def _parallel_levels(table: Turntable, views: list[Borders], frame: Frame, scale, rod: bool, opts: _Options,
                     warnings: list[str]) -> _Levels:
    """The sections under a parallel projection; check_parallel's warning, if any, goes into warnings."""
    s_fine, theta, dirs = _sampling(table, scale)
    ds = scale.sy_mm
    left, right = sample_borders(views, frame, s_fine)
    width = np.where(np.isfinite(left).all(axis=0) & np.isfinite(right).all(axis=0),
                     np.max(right - left, axis=0), np.nan)
    s_lo, s_hi, trims = _trim(s_fine, width, rod, opts.tip_fraction, ds, scale.sy_mm)
    inside = (s_fine >= s_lo) & (s_fine <= s_hi)
    phi, h = support_samples(left[:, inside], right[:, inside], theta)
    k_max = harmonics_for(phi)
    coef_fine = fit_support(phi, h, k_max)
    levels = choose_levels(s_fine[inside], support_values(coef_fine, dirs), opts.spacing_mm, opts.tol_mm)
    left_l, right_l = sample_borders(views, frame, levels)
    phi, h_l = support_samples(left_l, right_l, theta)
    coef_l = fit_support(phi, h_l, k_max)
    rms_l = np.sqrt(np.mean((support_values(coef_l, phi).T - h_l) ** 2, axis=0))
    phi_l = np.repeat(phi[:, None], len(levels), axis=1)
    parallel = check_parallel(views, frame, theta, levels, k_max, rms_l, table.shape_px[1], s_lo, rod)
    if parallel:
        warnings.append(parallel)
    return _Levels(levels, coef_l, phi_l, h_l, rms_l, s_lo, trims)


def _pinhole_levels(table: Turntable, views: list[Borders], frame: Frame, scale, camera: Camera, rod: bool,
                    opts: _Options) -> _Levels:
    """The sections under the pinhole camera, from where the views' tangents agree."""
    s_fine, theta, dirs = _sampling(table, scale)
    ds = scale.sy_mm
    width_px = table.shape_px[1]
    k_max = harmonics_for(support_samples(np.zeros((len(views), 1)), np.zeros((len(views), 1)), theta)[0])
    tables = border_tables(views, frame)
    coef_f, phi_f, h_f, rms_f = perspective_fit(views, frame, camera, width_px, theta, s_fine, k_max,
                                                tables=tables)
    n = len(views)
    width = np.where(np.isfinite(h_f).all(axis=0), np.max(h_f[:n] + h_f[n:], axis=0), np.nan)
    s_lo, s_hi, trims = _trim(s_fine, width, rod, opts.tip_fraction, ds, scale.sy_mm, margin_px=0.0)
    # the rim of the proximal cut is seen below the cut in perspective, and its tangents
    # disagree by many px: the first section lies ROD_MARGIN_PX past where they stop doing so
    # (as in the parallel path: closer to the blurred corner of the cut the tangents agree but
    # are off by up to 1 px) where the tangents agree to TANGENT_TOL_PX; with a rod, the cut
    # itself (z = 0) comes from the rim's shadow (camera.proximal_cut)
    rms_px = np.nan_to_num(rms_f / scale.sx_mm, nan=np.inf)
    ok = rms_px <= TANGENT_TOL_PX
    i_lo, i_hi = np.searchsorted(s_fine, s_lo), np.searchsorted(s_fine, s_hi, side="right") - 1
    while i_lo < i_hi and rms_px[i_lo] > CUT_TOL_PX:
        i_lo += 1
    i_first = i_lo + int(np.ceil(ROD_MARGIN_PX * scale.sy_mm / ds))     # past the blurred corner
    while i_first < i_hi and not ok[i_first:i_first + 3].all():
        i_first += 1
    while i_hi > i_first and not ok[i_hi - 2:i_hi + 1].all():
        i_hi -= 1
    parts = [f"s {a:.2f} .. {b:.2f} mm" for a, b in ((s_lo, s_fine[i_first]), (s_fine[i_hi], s_hi)) if b > a]
    if parts:
        trims["tangents disagree"] = " and ".join(parts) + " along the axis"
    s_lo, s_first, s_hi = float(s_fine[i_lo]), float(s_fine[i_first]), float(s_fine[i_hi])
    if s_hi - s_first < 2 * ds:
        raise InputError("the tangents of the views disagree on every section: check camera_distance_mm "
                         "in turntable.toml and the images")
    if rod:                       # z = 0 at the cut: fit the rim's shadow to the borders below
        cut = proximal_cut(tables, frame, camera, width_px, theta, support_curve(coef_f[:, i_first:i_first + 1])[0],
                           s_first, CUT_SEARCH_PX * scale.sy_mm)
        if cut is not None and cut < s_first:
            s_lo = cut
    inside = (s_fine >= s_first) & (s_fine <= s_hi)
    levels = choose_levels(s_fine[inside], support_values(coef_f[:, inside], dirs), opts.spacing_mm, opts.tol_mm)
    coef_l, phi_l, h_l, rms_l = perspective_fit(views, frame, camera, width_px, theta, levels, k_max,
                                                tables=tables)
    return _Levels(levels, coef_l, phi_l, h_l, rms_l, s_lo, trims)


def _sections(fit: _Levels, scale, warnings: list[str]) -> tuple[np.ndarray, list, list, object]:
    """z (m,) mm, the convex sections, their tangent polygons and the lofted surface
    (trimesh.Trimesh) of the sections consistent_sections keeps; its warning goes into warnings."""
    curves = support_curve(fit.coef, N_POINTS)
    keep, note = consistent_sections(fit.levels - fit.s_lo, curves, fit.rms / scale.sx_mm, scale.sx_mm)
    if note:
        warnings.append(note)
    levels, curves, phi_l, h_l = fit.levels[keep], curves[keep], fit.phi[:, keep], fit.h[:, keep]
    sections = [convex_section(c) for c in curves]
    polygons = []
    for i in range(len(levels)):
        ok = np.isfinite(phi_l[:, i]) & np.isfinite(h_l[:, i])
        polygons.append(tangent_polygon(phi_l[ok, i], h_l[ok, i]))
    z = levels - fit.s_lo
    return z, sections, polygons, loft(z, sections)


def reconstruct(table: Turntable, spacing_mm=(0.5, 2.0), tol_mm: float = 0.02,
                tip_fraction: float = 0.5, progress=None) -> Reconstruction:
    """Run the image stage on a loaded turntable folder (nothing is written)."""
    opts = _checked_options(spacing_mm, tol_mm, tip_fraction)
    timings, warnings = {}, []
    lens, calib, views = _silhouettes(table, progress, timings)

    t0 = time.perf_counter()
    views, calib, turned, rod = _upright(views, calib, table.shape_px[1])
    scale = template_scale(calib, table.template_diameter_mm)
    camera, camera_record = _camera(table, lens, scale, turned)
    frame, axis_fit = _axis(table, views, scale)
    if table.coverage_deg < 360.0 - 1e-6:
        warnings.append(f"the views cover {table.coverage_deg:.0f} deg, not 360: each tangent is seen once, "
                        f"so noise is not averaged and the axis estimate is less certain")
    timings["calibration"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    if camera is None:
        fit = _parallel_levels(table, views, frame, scale, rod, opts, warnings)
    else:
        fit = _pinhole_levels(table, views, frame, scale, camera, rod, opts)
    z, sections, polygons, surface = _sections(fit, scale, warnings)
    timings["sections"] = time.perf_counter() - t0
    return Reconstruction(table, frame, z, sections, polygons, surface, fit.s_lo, fit.trims, axis_fit,
                          timings, turned, warnings, camera_record)


def sections_document(rec: Reconstruction) -> dict:
    """The sections.json document of a reconstruction: sections (mm, finger frame), calibration, views."""
    sc, fr, t = rec.frame.scale, rec.frame, rec.table
    return {
        "units": "mm",
        "frame": "finger frame: rotation axis at the origin, volar towards +y, z distal from the "
                 "proximal end; points are closed CCW polygons (first point not repeated)",
        "sections": [{"z": round(float(z), 5), "points": np.round(p, 5).tolist()}
                     for z, p in zip(rec.z_mm, rec.sections)],
        "calibration": {
            "mm_per_px_x": sc.sx_mm, "mm_per_px_y": sc.sy_mm, "aspect": sc.aspect,
            "template_diameter_mm": t.template_diameter_mm, "template_fit_rms_px": sc.rms_px,
            "axis_x0_mm": fr.x0_mm, "axis_tilt_deg": fr.tilt_deg, **rec.axis_fit,
            "z_offset_mm": rec.z_offset_mm,
            "z_offset_note": "z = 0 lies z_offset_mm along the axis from where it crosses the bottom "
                             "image edge (after turning the images so the rod is at the bottom)",
            **rec.camera,
        },
        "views": len(t.image_paths),
        "angles_deg": t.angles_deg.tolist(),
        "coverage_deg": t.coverage_deg,
        "volar_view_deg": t.volar_view_deg,
        "trims": rec.trims,
        "warnings": rec.warnings,
        "source": str(t.folder),
    }


def input_hash(table: Turntable, options: dict) -> str:
    """Hash of every input file's bytes and the options: outputs with this hash are current."""
    digest = hashlib.sha256(repr(sorted(options.items())).encode())
    manifest = table.folder / "turntable.toml"
    for path in [*table.image_paths, table.calibration_path, *table.checkerboard_paths] + \
            ([manifest] if manifest.exists() else []):
        digest.update(path.name.encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()[:16]


def _current(out_dir: Path, key: str) -> bool:
    """Whether out_dir holds every output, written from inputs and options with this input_hash."""
    try:
        doc = json.loads((out_dir / "sections.json").read_text())
    except (OSError, ValueError):
        return False
    return doc.get("input_hash") == key and all((out_dir / f).exists() for f in ("surface.stl", "report.png"))


def reconstruct_folder(images, out_dir, spacing_mm=(0.5, 2.0), tol_mm: float = 0.02,
                       tip_fraction: float = 0.5, progress=None, force: bool = False):
    """Reconstruct a turntable folder and write sections.json, surface.stl, report.png to out_dir.

    Returns the Reconstruction, or None when out_dir already holds outputs of the same inputs and
    options (unless force).
    """
    table = load_turntable(images)
    key = input_hash(table, {"spacing_mm": tuple(spacing_mm), "tol_mm": tol_mm, "tip_fraction": tip_fraction})
    if not force and _current(Path(out_dir), key):
        return None
    rec = reconstruct(table, spacing_mm, tol_mm, tip_fraction, progress)
    if not rec.surface.is_watertight:
        raise InputError("the lofted surface is not watertight (sections degenerate): "
                         "raise --tip-fraction or check the images")
    t0 = time.perf_counter()
    with staged_output(out_dir) as tmp:
        write_json(Path(tmp) / "sections.json", {**sections_document(rec), "input_hash": key})
        rec.surface.export(Path(tmp) / "surface.stl")
        write_report(rec, Path(tmp) / "report.png")
    rec.timings_s["writing"] = time.perf_counter() - t0
    return rec
