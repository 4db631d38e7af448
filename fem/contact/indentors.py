"""Rigid indentors: the thesis catalogue as height profiles, placed in the finger frame.

An indentor is described in its own frame (u along its length axis, v across it, w along the
approach direction) by a height profile h(u, v) >= 0: how far its surface lies behind its
foremost point (the tip), measured against the approach direction; h = +inf where the indentor
has no surface (outside its footprint). Placed in the finger frame (mm; finger axis z, volar +y,
approach along -y by default), a body point X has the *standoff*

    standoff(X) = (X - origin) . a + h(u, v),   u = (X - origin) . e1,  v = (X - origin) . e2

which is the gap, measured along the approach direction a, to the indentor whose tip sits at the
origin. When the tip has travelled t mm along a, the gap is standoff - t (negative = overlap).
The indentor's outward normal (towards the body) is a + h_u e1 + h_v e2, normalised.

In 2D plane-strain models (points (n, 2) in the x-y plane) the indentor is its z = 0 section,
extruded along z: use orientation "parallel" so that bars, cylinders and steps run along z.

    ind = make_indentor("cylinder:C5", orientation="perpendicular", position_mm=(0.0, 2.0))
    g = ind.gap(points, travel_mm=1.0)          # (n,) mm
    n = ind.normal(points)                      # (n, 3)

Catalogue (thesis 4.3-4.5, 6.2.3, 6.3.3 and table 5.1): cylinders C1-C8, rectangular flats R1-R2,
steps 0-5, bars, aperiodic gratings, wedge, cone, punch, plate, sphere, ellipsoid, two points.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from fingertip.errors import InputError

CYLINDERS_MM = {"C1": 1.59, "C2": 3.18, "C3": 4.76, "C4": 6.35, "C5": 9.52, "C6": 12.7,
                "C7": 19.05, "C8": 25.4}
"""Cylinder diameters in mm by code (thesis table 5.1)."""
RECTANGULAR_MM = {"R1": 12.7, "R2": 38.1}
"""Widths in mm of the flat rectangular indentors R1, R2 (thesis table 5.1)."""
STEP_HALF_WAVELENGTH_MM = (0.0, 0.450, 1.195, 1.230, 3.038, 3.134)
"""Half-wavelengths in mm of the sinusoidal ramp of steps 0-5 (Srinivasan and LaMotte 1987)."""
STEP_HEIGHT_MM = 0.5
DEFAULT_GRATING_GAPS_MM = (0.5, 0.75, 1.0, 1.5, 2.0, 3.0, 5.0)
"""Default gap list of an aperiodic grating (equal bars, growing gaps); pass your own list."""
CONE_BASE_RADIUS_MM, CONE_HEIGHT_MM = 3.175, 2.4
PUNCH_DIAMETER_MM = 6.35
PLATE_SIZE_MM = 20.0
WEDGE_HALF_ANGLE_DEG = 15.0


# --------------------------------------------------------------------------- shapes
def _footprint(h, hu, hv, outside):
    h = np.where(outside, np.inf, h)
    return h, np.where(outside, 0.0, hu), np.where(outside, 0.0, hv)


def _beyond_length(u, length_mm):
    return np.abs(u) > 0.5 * length_mm


@dataclass(frozen=True)
class Cylinder:
    """Circular cylinder lying with its axis along u; diameter and length in mm."""
    diameter_mm: float
    length_mm: float = math.inf

    def height(self, u, v):
        r = 0.5 * self.diameter_mm
        outside = (np.abs(v) >= r) | _beyond_length(u, self.length_mm)
        root = np.sqrt(np.clip(r * r - v * v, 1e-300, None))
        return _footprint(r - root, 0.0 * u, v / root, outside)


@dataclass(frozen=True)
class Flat:
    """Flat rectangular face, width across (v) and length along (u) in mm: bars, R1/R2, plate."""
    width_mm: float
    length_mm: float = math.inf

    def height(self, u, v):
        outside = (np.abs(v) > 0.5 * self.width_mm) | _beyond_length(u, self.length_mm)
        return _footprint(0.0 * v, 0.0 * v, 0.0 * v, outside)


@dataclass(frozen=True)
class Grating:
    """Aperiodic grating: equal flat bars (width in mm) separated by the listed gaps (mm).

    The first bar spans v in [0, bar_mm]; each gap and the next bar follow towards +v. Points
    over a gap see the groove floor `groove_mm` behind the bar faces (inf: no floor).
    """
    bar_mm: float
    gaps_mm: tuple[float, ...] = DEFAULT_GRATING_GAPS_MM
    length_mm: float = math.inf
    groove_mm: float = math.inf

    def bar_edges_mm(self):
        """(n_bars, 2) start and end of every bar along v."""
        starts = np.concatenate([[0.0], np.cumsum(np.asarray(self.gaps_mm) + self.bar_mm)])
        return np.column_stack([starts, starts + self.bar_mm])

    def height(self, u, v):
        edges = self.bar_edges_mm()
        on_bar = np.zeros(np.shape(v), bool)
        for a, b in edges:
            on_bar |= (v >= a) & (v <= b)
        outside = (v < 0) | (v > edges[-1, 1]) | _beyond_length(u, self.length_mm)
        h = np.where(on_bar, 0.0, self.groove_mm)
        return _footprint(h, 0.0 * v, 0.0 * v, outside)


@dataclass(frozen=True)
class Step:
    """Step shape: flat at v < 0 (the tip), a half sinusoid rising `height_mm` over v in [0, L],
    flat again at v > L (L = half-wavelength in mm; L = 0 is a sharp step)."""
    half_wavelength_mm: float
    height_mm: float = STEP_HEIGHT_MM
    length_mm: float = math.inf

    def height(self, u, v):
        lam, hs = self.half_wavelength_mm, self.height_mm
        if lam > 0:
            t = np.clip(v / lam, 0.0, 1.0)
            h = 0.5 * hs * (1.0 - np.cos(np.pi * t))
            hv = np.where((v > 0) & (v < lam), 0.5 * hs * np.pi / lam * np.sin(np.pi * t), 0.0)
        else:
            h = np.where(v > 0, hs, 0.0)
            hv = 0.0 * v
        return _footprint(h, 0.0 * v, hv, _beyond_length(u, self.length_mm))


@dataclass(frozen=True)
class Wedge:
    """Sharp wedge (line load) with its edge along u; half-angle between a flank and the approach."""
    half_angle_deg: float = WEDGE_HALF_ANGLE_DEG
    length_mm: float = math.inf

    def height(self, u, v):
        k = 1.0 / math.tan(math.radians(self.half_angle_deg))
        return _footprint(k * np.abs(v), 0.0 * v, k * np.sign(v), _beyond_length(u, self.length_mm))


@dataclass(frozen=True)
class Cone:
    """Sharp cone (point load) of base radius and height in mm, on a cylinder of that radius."""
    base_radius_mm: float = CONE_BASE_RADIUS_MM
    height_mm: float = CONE_HEIGHT_MM

    def height(self, u, v):
        r = np.hypot(u, v)
        k = self.height_mm / self.base_radius_mm
        safe = np.where(r > 0, r, 1.0)
        return _footprint(k * r, k * u / safe, k * v / safe, r > self.base_radius_mm)


@dataclass(frozen=True)
class Punch:
    """Flat circular punch, diameter in mm."""
    diameter_mm: float = PUNCH_DIAMETER_MM

    def height(self, u, v):
        outside = np.hypot(u, v) > 0.5 * self.diameter_mm
        return _footprint(0.0 * u, 0.0 * u, 0.0 * u, outside)


@dataclass(frozen=True)
class Ellipsoid:
    """Ellipsoid with semi-axes along u, v and the approach direction w, in mm (sphere: all equal)."""
    semi_u_mm: float
    semi_v_mm: float
    semi_w_mm: float

    @property
    def is_sphere(self) -> bool:
        return self.semi_u_mm == self.semi_v_mm == self.semi_w_mm

    def height(self, u, v):
        a, b, c = self.semi_u_mm, self.semi_v_mm, self.semi_w_mm
        rho2 = (u / a) ** 2 + (v / b) ** 2
        root = np.sqrt(np.clip(1.0 - rho2, 1e-300, None))
        return _footprint(c * (1.0 - root), c * u / (a * a * root), c * v / (b * b * root), rho2 >= 1.0)


def sphere(radius_mm: float) -> Ellipsoid:
    return Ellipsoid(radius_mm, radius_mm, radius_mm)


# --------------------------------------------------------------------------- placement
@dataclass(frozen=True)
class Indentor:
    """One or more rigid parts placed in the finger frame.

    parts: shapes with a `height(u, v) -> (h, h_u, h_v)` method; offsets_mm: (n_parts, 2) shift of
    each part's tip in (u, v); origin_mm: (3,) tip position (travel 0) of the indentor datum;
    approach, e1, e2: (3,) unit vectors (approach, length axis, across axis).
    """
    name: str
    parts: tuple
    offsets_mm: np.ndarray
    origin_mm: np.ndarray
    approach: np.ndarray
    e1: np.ndarray
    e2: np.ndarray

    @property
    def n_parts(self) -> int:
        return len(self.parts)

    def shifted(self, offset_mm) -> "Indentor":
        """The same indentor with its origin moved by offset_mm (3,) (a sweep position)."""
        return replace(self, origin_mm=self.origin_mm + np.asarray(offset_mm, float))

    def _local(self, points):
        x = _as_3d(points) - self.origin_mm
        return x @ self.e1, x @ self.e2, x @ self.approach

    def part_standoff(self, points) -> np.ndarray:
        """(n, n_parts) standoff in mm of every point from every part (inf outside its footprint)."""
        u, v, w = self._local(points)
        out = np.empty((len(u), self.n_parts))
        for k, (shape, (du, dv)) in enumerate(zip(self.parts, self.offsets_mm)):
            out[:, k] = w + shape.height(u - du, v - dv)[0]
        return out

    def standoff(self, points) -> np.ndarray:
        """(n,) gap in mm along the approach direction at travel 0 (min over parts)."""
        return self.part_standoff(points).min(axis=1)

    def gap(self, points, travel_mm: float) -> np.ndarray:
        """(n,) gap in mm along the approach direction when the tip has travelled travel_mm."""
        return self.standoff(points) - travel_mm

    def normal(self, points) -> np.ndarray:
        """(n, 3) unit outward normal of the nearest part's surface at each point's projection
        along the approach direction (the approach direction where a point misses every part)."""
        u, v, _ = self._local(points)
        nearest = np.argmin(self.part_standoff(points), axis=1)
        grad = np.zeros((len(u), 2))
        for k, (shape, (du, dv)) in enumerate(zip(self.parts, self.offsets_mm)):
            sel = nearest == k
            h, hu, hv = shape.height(u[sel] - du, v[sel] - dv)
            ok = np.isfinite(h)
            grad[np.flatnonzero(sel)[ok]] = np.column_stack([hu, hv])[ok]
        n = self.approach + grad[:, :1] * self.e1 + grad[:, 1:] * self.e2
        return n / np.linalg.norm(n, axis=1, keepdims=True)


def _as_3d(points) -> np.ndarray:
    p = np.atleast_2d(np.asarray(points, float))
    if p.shape[1] == 2:
        p = np.column_stack([p, np.zeros(len(p))])
    if p.shape[1] != 3:
        raise InputError(f"points must be (n, 2) or (n, 3) in mm, got shape {p.shape}")
    return p


def approach_direction(incline_deg: float = 0.0) -> np.ndarray:
    """(3,) approach along -y, tilted by incline_deg about x (the finger on an inclined support).

    As `vertical_up` of fem.geometry.layered (support plane at incline_deg to the horizontal, distal end
    lower): the approach is minus vertical-up, a = (0, -cos i, +sin i). The thesis
    force-displacement experiments used a 30 deg platform with the distal end up: -30.
    """
    i = math.radians(incline_deg)
    return np.array([0.0, -math.cos(i), math.sin(i)])


def orientation_deg(orientation) -> float:
    """Angle (deg) of an indentor's length axis to the finger axis: "parallel" 0, "perpendicular"
    90, or a number (or its text); anything else is an InputError."""
    named = {"parallel": 0.0, "perpendicular": 90.0}
    if isinstance(orientation, str):
        if orientation in named:
            return named[orientation]
        try:
            deg = float(orientation)
        except ValueError:
            deg = math.nan
    else:
        deg = float(orientation)
    if not math.isfinite(deg):
        raise InputError(f"unknown orientation '{orientation}': use parallel, perpendicular "
                         f"or an angle in degrees to the finger axis")
    return deg


def place(parts, name="indentor", *, offsets_mm=None, position_mm=(0.0, 0.0), orientation="parallel",
          approach=None, incline_deg: float = 0.0) -> Indentor:
    """Place shapes in the finger frame.

    position_mm: (x, z) in mm on the finger mid-plane y = 0, or a full (3,) point; the tip moves
    along the approach line through it. orientation: "parallel" (length axis along the finger
    axis z), "perpendicular" (along x), or the angle in degrees between the length axis and the
    finger axis. approach: (3,) direction of travel (default -y, tilted by incline_deg about x).
    The across axis e2 is +x for parallel and +z for perpendicular.
    """
    a = approach_direction(incline_deg) if approach is None else np.asarray(approach, float)
    if a.shape != (3,) or not np.linalg.norm(a) > 0:
        raise InputError("approach must be a non-zero 3-vector, e.g. 0,-1,0")
    a = a / np.linalg.norm(a)
    z = np.array([0.0, 0.0, 1.0]) - a[2] * a
    if np.linalg.norm(z) < 1e-9:
        raise InputError("approach along the finger axis is not supported: indent the pad (e.g. -y)")
    z /= np.linalg.norm(z)
    x = np.cross(z, a)
    th = math.radians(orientation_deg(orientation))
    e1 = math.cos(th) * z - math.sin(th) * x
    e2 = math.sin(th) * z + math.cos(th) * x
    pos = np.asarray(position_mm, float)
    if pos.shape == (2,):
        pos = np.array([pos[0], 0.0, pos[1]])
    if pos.shape != (3,):
        raise InputError("position must be (x, z) or (x, y, z) in mm")
    parts = tuple(parts)
    off = np.zeros((len(parts), 2)) if offsets_mm is None else np.asarray(offsets_mm, float)
    return Indentor(name, parts, off, pos, a, e1, e2)


# --------------------------------------------------------------------------- catalogue
def _number(text: str, what: str, unit: str = "mm", zero: bool = False) -> float:
    """A positive finite number (zero: >= 0) from an indentor code's argument."""
    try:
        value = float(text.removesuffix(unit))
    except ValueError:
        raise InputError(f"bad {what} '{text}': give a number in {unit}") from None
    if not math.isfinite(value) or not (value >= 0 if zero else value > 0):
        raise InputError(f"{what} must be {'>= 0' if zero else 'positive'} {unit}, got {text}")
    return value


def _numbers(text: str, what: str) -> list[float]:
    return [_number(t, what) for t in text.replace(",", " ").split()]


def shapes_for(spec: str):
    """Parse an indentor code into (name, parts, offsets_mm or None).

    Codes: C1-C8, R1-R2, `cylinder:C5|<diameter>`, `rect:R1|<width>`, `step:0-5` or
    `step:<half-wavelength mm>[,<height mm>]`, `bar:<width>`, `grating:<bar>[:<gap>,<gap>,...]`,
    `wedge[:<half-angle deg>]`, `cone`, `punch[:<diameter>]`, `plate[:<size>]`,
    `sphere:<radius>`, `ellipsoid:<a_u>,<a_v>,<a_w>`, `two-point:<separation>[:<tip radius>]`.
    """
    spec = spec.strip()
    kind, _, arg = spec.partition(":")
    kind = kind.lower()
    code = spec.upper()
    if code in CYLINDERS_MM:
        return code, (Cylinder(CYLINDERS_MM[code]),), None
    if code in RECTANGULAR_MM:
        return code, (Flat(RECTANGULAR_MM[code]),), None
    if kind == "cylinder" and arg:
        d = CYLINDERS_MM.get(arg.upper()) or _number(arg, "cylinder diameter")
        return spec, (Cylinder(d),), None
    if kind == "rect" and arg:
        w = RECTANGULAR_MM.get(arg.upper()) or _number(arg, "rectangular width")
        return spec, (Flat(w),), None
    if kind == "step" and arg:
        if arg.isdigit():
            i = int(arg)
            if i >= len(STEP_HALF_WAVELENGTH_MM):
                raise InputError(f"unknown step shape {i}: steps 0-5 exist (or give the half-wavelength in mm)")
            return spec, (Step(STEP_HALF_WAVELENGTH_MM[i]),), None
        vals = [float(t) for t in arg.split(",")] if _is_numbers(arg) else None
        if not vals or len(vals) > 2 or not all(map(math.isfinite, vals)) or vals[0] < 0:
            raise InputError(f"bad step '{arg}': give 0-5, or half-wavelength[,height] in mm")
        return spec, (Step(*vals),), None
    if kind == "bar" and arg:
        return spec, (Flat(_number(arg, "bar width")),), None
    if kind == "grating" and arg:
        bar, _, gaps = arg.partition(":")
        g = tuple(_numbers(gaps, "grating gap")) if gaps else DEFAULT_GRATING_GAPS_MM
        return spec, (Grating(_number(bar, "grating bar width"), g),), None
    if kind == "wedge":
        ang = _number(arg, "wedge half-angle", "deg") if arg else WEDGE_HALF_ANGLE_DEG
        if not 0 < ang < 90:
            raise InputError(f"wedge half-angle must be in (0, 90) deg, got {arg}")
        return spec, (Wedge(ang),), None
    if kind == "cone" and not arg:
        return spec, (Cone(),), None
    if kind == "punch":
        return spec, (Punch(_number(arg, "punch diameter") if arg else PUNCH_DIAMETER_MM),), None
    if kind == "plate":
        s = _number(arg, "plate size") if arg else PLATE_SIZE_MM
        return spec, (Flat(s, s),), None
    if kind == "sphere" and arg:
        return spec, (sphere(_number(arg, "sphere radius")),), None
    if kind == "ellipsoid" and arg:
        semi = _numbers(arg, "ellipsoid semi-axis")
        if len(semi) != 3:
            raise InputError(f"ellipsoid needs three semi-axes a_u,a_v,a_w in mm, got '{arg}'")
        return spec, (Ellipsoid(*semi),), None
    if kind == "two-point" and arg:
        sep, _, tip = arg.partition(":")
        s = _number(sep, "two-point separation", zero=True)
        shape = sphere(_number(tip, "tip radius")) if tip else Cone()
        if s == 0:
            return spec, (shape,), None
        return spec, (shape, shape), np.array([[0.0, -0.5 * s], [0.0, 0.5 * s]])
    raise InputError(f"unknown indentor '{spec}': use C1-C8, R1-R2, cylinder:<d>, step:0-5, bar:<w>, "
                     f"grating:<bar>[:<gaps>], wedge, cone, punch, plate, sphere:<r>, "
                     f"ellipsoid:<a,b,c>, two-point:<separation>")


def _is_numbers(text: str) -> bool:
    try:
        [float(t) for t in text.split(",")]
    except ValueError:
        return False
    return True


def make_indentor(spec: str, **placement) -> Indentor:
    """Catalogue indentor from its code (see `shapes_for`), placed with `place(**placement)`."""
    name, parts, offsets = shapes_for(spec)
    return place(parts, name, offsets_mm=offsets, **placement)
