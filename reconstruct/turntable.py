"""Load a turntable folder: images, view angles, calibration template, manifest; validate up front.

Folder contract: images (png/tif/tiff/jpg/jpeg/bmp) of one size; `calibration.*`
(template image); optional `turntable.toml` with `start_deg` + `step_deg` (angle of the i-th
view in sorted name order) or an `[angles]` table (file name -> degrees),
`template_diameter_mm` (default 12.7), `axis` ("vertical" or "horizontal"), `volar_view_deg`
(default 0), `camera_distance_mm` (a pinhole camera that far from the rotation axis; default: a
parallel projection). Without a manifest the angles come from names like `view_012.6deg.png`.
An optional `checkerboard/` folder holds photos of a printed checkerboard taken with the same
camera and lens (lens calibration, reconstruct.lens); it needs `checkerboard_inner_corners`
([per row, per column]) and `checkerboard_square_mm` in the manifest.
"""
from __future__ import annotations

import re
import tomllib
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
from PIL import Image

from fingertip.errors import InputError
from reconstruct.lens import MIN_PHOTOS

IMAGE_SUFFIXES = {".png", ".tif", ".tiff", ".jpg", ".jpeg", ".bmp"}
_ANGLE_IN_NAME = re.compile(r"(-?\d+(?:\.\d+)?)\s*deg", re.IGNORECASE)
_NUMBER, _TEXT, _TABLE, _PAIR = "a number", "a text in quotes", "a table of file name = degrees", \
    "a list of two whole numbers, e.g. [9, 6]"
#: every manifest key and the TOML type it must have
_MANIFEST_TYPES = {"start_deg": _NUMBER, "step_deg": _NUMBER, "angles": _TABLE,
                   "template_diameter_mm": _NUMBER, "axis": _TEXT, "volar_view_deg": _NUMBER,
                   "axis_offset_px": _NUMBER, "tilt_deg": _NUMBER, "camera_distance_mm": _NUMBER,
                   "checkerboard_inner_corners": _PAIR, "checkerboard_square_mm": _NUMBER}
_MANIFEST_KEYS = set(_MANIFEST_TYPES)


def _is_number(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and bool(np.isfinite(v))


def _check_types(manifest: dict, path: Path) -> None:
    """One InputError naming the first key whose value has the wrong TOML type."""
    for key, want in _MANIFEST_TYPES.items():
        if key not in manifest:
            continue
        v = manifest[key]
        if want == _NUMBER:
            ok = _is_number(v)
        elif want == _TEXT:
            ok = isinstance(v, str)
        elif want == _PAIR:
            ok = (isinstance(v, list) and len(v) == 2
                  and all(isinstance(x, int) and not isinstance(x, bool) for x in v))
        else:
            ok = isinstance(v, dict) and all(_is_number(x) for x in v.values())
        if not ok:
            raise InputError(f"{path}: {key} must be {want}, not {v!r}")


@dataclass
class Turntable:
    """A validated turntable folder. angles_deg: (n,) view angles, sorted as `image_paths`."""

    folder: Path
    image_paths: list[Path]
    angles_deg: np.ndarray
    calibration_path: Path
    template_diameter_mm: float = 12.7
    axis: str = "vertical"
    volar_view_deg: float = 0.0
    size_px: tuple[int, int] = (0, 0)       # (W, H) as stored on disk
    axis_offset_px: float | None = None     # manifest override of the estimated axis
    tilt_deg: float | None = None
    camera_distance_mm: float | None = None  # pinhole camera this far from the axis; None: parallel
    checkerboard_paths: tuple[Path, ...] = ()     # photos of the lens-calibration board
    checkerboard_inner_corners: tuple[int, int] | None = None
    checkerboard_square_mm: float | None = None

    @property
    def coverage_deg(self) -> float:
        """Angle covered by the views: 360 minus the largest gap between neighbouring views."""
        a = np.sort(np.mod(self.angles_deg, 360.0))
        gaps = np.diff(np.concatenate([a, [a[0] + 360.0]]))
        return float(360.0 - gaps.max()) + float(np.median(gaps)) if len(a) > 1 else 0.0

    @property
    def shape_px(self) -> tuple[int, int]:
        """(rows, cols) of the images as read, i.e. after turning the finger axis vertical."""
        w, h = self.size_px
        return (w, h) if self.axis == "horizontal" else (h, w)

    def read(self, path: Path) -> np.ndarray:
        """Grey image (H, W) uint8, rotated so that the finger axis is vertical."""
        img = read_grey(path)
        return np.ascontiguousarray(np.rot90(img, 1)) if self.axis == "horizontal" else img


def read_grey(path: Path) -> np.ndarray:
    """Read any supported image as 8-bit grey (16-bit images are scaled)."""
    img = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    if img is None:
        raise InputError(f"cannot read image '{path}': replace or remove the file")
    if img.ndim == 3:
        img = cv2.cvtColor(img, cv2.COLOR_BGRA2GRAY if img.shape[2] == 4 else cv2.COLOR_BGR2GRAY)
    if img.dtype == np.uint16:
        img = (img / 257.0).round().astype(np.uint8)
    elif img.dtype != np.uint8:
        raise InputError(f"image '{path}' has pixel type {img.dtype}: save it as 8- or 16-bit grey")
    return img


def _images(folder: Path) -> list[Path]:
    """The image files of a folder in name order; dotfiles (macOS `._view_000.png` resource forks,
    `.DS_Store`, hidden files) are not images of the set."""
    return sorted(p for p in folder.iterdir() if p.suffix.lower() in IMAGE_SUFFIXES and not p.name.startswith("."))


def image_size(path: Path) -> tuple[int, int]:
    """(W, H) of an image from its header; InputError for a file that is not a readable image or
    ends before its image data does (a truncated copy), before any decoder reads its pixels."""
    try:
        with Image.open(path) as img:
            size, kind = img.size, img.format
    except (OSError, ValueError):
        raise InputError(f"cannot read image '{path}': replace or remove the file") from None
    if _truncated(path, kind):
        raise InputError(f"image '{path}' is truncated (the file ends before its image data does): copy it "
                         f"again from the camera, or remove it")
    return size


def _truncated(path: Path, kind: str | None) -> bool:
    """Whether a JPEG lacks its end-of-image marker after its last scan, or a PNG its IEND chunk."""
    if kind not in ("JPEG", "PNG"):
        return False
    try:
        data = path.read_bytes()
    except OSError:
        return True
    if kind == "PNG":
        return b"IEND" not in data[-64:]
    return data.rfind(b"\xff\xd9") < data.rfind(b"\xff\xda")


def _read_manifest(folder: Path) -> dict:
    path = folder / "turntable.toml"
    if not path.exists():
        return {}
    try:
        manifest = tomllib.loads(path.read_text())
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise InputError(f"{path} is not valid TOML ({exc}): fix the syntax") from None
    unknown = set(manifest) - _MANIFEST_KEYS
    if unknown:
        raise InputError(f"{path}: unknown key(s) {sorted(unknown)}; known keys: {sorted(_MANIFEST_KEYS)}")
    _check_types(manifest, path)
    return manifest


def load_turntable(folder) -> Turntable:
    """Validate a turntable folder and return it; every problem is an InputError naming the fix."""
    folder = Path(folder)
    if folder.exists() and not folder.is_dir():
        raise InputError(f"turntable folder '{folder}' is a file, not a folder: give the folder of the images")
    if not folder.is_dir():
        raise InputError(f"turntable folder '{folder}' does not exist: give the folder of the images")
    files = _images(folder)
    calib = [p for p in files if p.stem.lower() == "calibration"]
    views = [p for p in files if p.stem.lower() != "calibration"]
    if not views:
        raise InputError(f"no images (png/tif/jpg/bmp) in '{folder}': put the turntable views there")
    if not calib:
        raise InputError(f"no calibration image in '{folder}': add the template photo as calibration.png "
                         f"(or .tif/.jpg), taken at the same zoom")
    if len(calib) > 1:
        raise InputError(f"several calibration images in '{folder}' ({', '.join(p.name for p in calib)}): keep one")
    manifest = _read_manifest(folder)
    angles = _angles(views, manifest, folder)

    order = np.argsort(angles, kind="stable")
    views, angles = [views[i] for i in order], angles[order]
    wrapped = np.mod(angles, 360.0)
    uniq, counts = np.unique(np.round(wrapped, 6), return_counts=True)
    if (counts > 1).any():
        dup = [p.name for p, a in zip(views, np.round(wrapped, 6)) if a in uniq[counts > 1]]
        raise InputError(f"duplicated view angle(s) {uniq[counts > 1].tolist()} deg ({', '.join(dup[:4])}): "
                         f"remove the duplicate images or fix the angles")

    sizes = {}
    for p in views + calib:                  # headers only: the pixels are decoded once, later
        sizes.setdefault(image_size(p), []).append(p.name)
    if len(sizes) > 1:
        desc = "; ".join(f"{w}x{h}: {', '.join(n[:2])}{' ...' if len(n) > 2 else ''}"
                         for (w, h), n in sizes.items())
        raise InputError(f"images differ in size ({desc}): all views and the template must have one size")

    axis = manifest.get("axis", "vertical")
    if axis not in ("vertical", "horizontal"):
        raise InputError(f"turntable.toml: axis must be \"vertical\" or \"horizontal\", not {axis!r}")
    diameter = float(manifest.get("template_diameter_mm", 12.7))
    if not diameter > 0:
        raise InputError(f"turntable.toml: template_diameter_mm must be positive, not {diameter}")
    table = Turntable(folder, views, angles, calib[0], diameter, axis,
                      float(manifest.get("volar_view_deg", 0.0)), next(iter(sizes)),
                      manifest.get("axis_offset_px"), manifest.get("tilt_deg"),
                      manifest.get("camera_distance_mm"))
    if table.camera_distance_mm is not None and not table.camera_distance_mm > 0:
        raise InputError(f"turntable.toml: camera_distance_mm must be positive (mm from the camera's "
                         f"centre to the rotation axis), not {table.camera_distance_mm}")
    table.checkerboard_paths, table.checkerboard_inner_corners, table.checkerboard_square_mm = \
        _checkerboard(folder, manifest, next(iter(sizes)))
    if len(views) < 4:
        raise InputError(f"only {len(views)} view(s) in '{folder}': take at least 4 (about 100 over 360 deg)")
    if table.coverage_deg < 180.0 - 1e-6:
        raise InputError(f"the views cover only {table.coverage_deg:.1f} deg of rotation: at least 180 deg "
                         f"are needed (360 recommended)")
    return table


def _checkerboard(folder: Path, manifest: dict, size: tuple[int, int]):
    """Photos, inner corners and square size of the lens-calibration board (checkerboard/), or
    ((), None, None) without one; every problem is an InputError."""
    keys = ("checkerboard_inner_corners", "checkerboard_square_mm")
    sub = folder / "checkerboard"
    if not sub.is_dir():
        if any(k in manifest for k in keys):
            raise InputError(f"turntable.toml gives {' and '.join(k for k in keys if k in manifest)} but "
                             f"'{folder}' has no checkerboard/ folder: add the board photos there or remove the key(s)")
        return (), None, None
    missing = [k for k in keys if k not in manifest]
    if missing:
        raise InputError(f"'{sub}' needs {' and '.join(missing)} in {folder}/turntable.toml, e.g. "
                         f"checkerboard_inner_corners = [9, 6] (inner corners per row and column) and "
                         f"checkerboard_square_mm = 2.0")
    corners = tuple(manifest["checkerboard_inner_corners"])
    square = float(manifest["checkerboard_square_mm"])
    if min(corners) < 2 or not square > 0:
        raise InputError(f"turntable.toml: checkerboard_inner_corners must be at least [2, 2] and "
                         f"checkerboard_square_mm positive, not {list(corners)} and {square}")
    photos = _images(sub)
    if len(photos) < MIN_PHOTOS:
        raise InputError(f"only {len(photos)} photo(s) in '{sub}': take at least {MIN_PHOTOS} (about 10) of the "
                         f"board, tilted differently in each")
    for p in photos:
        other = image_size(p)
        if other != size:
            raise InputError(f"checkerboard photo '{p.name}' is {other[0]}x{other[1]} px, the views "
                             f"{size[0]}x{size[1]}: take the board photos with the same camera settings")
    return tuple(photos), corners, square


def _angles(views: list[Path], manifest: dict, folder: Path) -> np.ndarray:
    """View angles in degrees from the manifest (start/step or [angles]) or the file names."""
    if "angles" in manifest:
        table = manifest["angles"]
        missing = [p.name for p in views if p.name not in table]
        if missing:
            raise InputError(f"turntable.toml [angles] has no angle for {', '.join(missing[:4])}"
                             f"{' ...' if len(missing) > 4 else ''}: add them")
        extra = sorted(set(table) - {p.name for p in views})
        if extra:
            raise InputError(f"turntable.toml [angles] names missing image(s) {', '.join(extra[:4])}: "
                             f"remove those lines or add the images")
        if "step_deg" in manifest or "start_deg" in manifest:
            raise InputError("turntable.toml gives both [angles] and start_deg/step_deg: keep one")
        return np.array([float(table[p.name]) for p in views])
    if "step_deg" in manifest:
        step = float(manifest["step_deg"])
        if step == 0:
            raise InputError("turntable.toml: step_deg must not be 0")
        return float(manifest.get("start_deg", 0.0)) + step * np.arange(len(views))
    if "start_deg" in manifest:
        raise InputError("turntable.toml gives start_deg without step_deg: add step_deg")
    angles = []
    for p in views:
        found = _ANGLE_IN_NAME.findall(p.stem)
        if not found:
            raise InputError(f"no view angle for '{p.name}': name files like view_012.6deg.png or add "
                             f"start_deg/step_deg (or an [angles] table) to {folder}/turntable.toml")
        angles.append(float(found[-1]))
    return np.array(angles)
