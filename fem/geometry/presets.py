"""Parametric solids with known axial sections: the model builder's 3D presets and the test shapes
the turntable renderer (reconstruct.synthetic) photographs.

Finger frame: z along the finger (proximal -> distal), volar pad towards +y, x lateral; every
section is given about the z axis (the turntable's rotation axis), lengths in mm.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.integrate import simpson
from scipy.spatial import ConvexHull

from fingertip.errors import InputError

#: Shapes make_shape builds.
SHAPES = ("fingertip", "sphere", "ellipsoid")

#: 2D plane-strain presets (thesis ch. 4), built by fem.geometry.mesh2d.preset_domain.
PRESETS_2D = ("block", "square", "cylinder8", "cylinder16")

#: Fingertip presets, mm. a: half width, b_volar / b_dorsal: half heights on the pad and nail
#: sides, p_dorsal: superellipse exponent of the flattened nail side, centre: section centre
#: relative to the rotation axis, length: body length (proximal cut to tip), cap: tip length,
#: taper: relative widening at mid-length, rod_radius: mounting rod radius.
FINGERTIP_PRESETS = {
    "human": dict(a=8.0, b_volar=6.5, b_dorsal=5.0, p_dorsal=3.0, centre=(0.6, 0.8),
                  length=22.0, cap=7.0, taper=0.08, rod_radius=1.0),
    "monkey": dict(a=4.0, b_volar=3.25, b_dorsal=2.5, p_dorsal=3.0, centre=(0.3, 0.4),
                   length=11.0, cap=3.5, taper=0.08, rod_radius=0.5),
}


@dataclass
class Shape:
    """A solid with known axial sections. Subclasses give `scale(z)` and `_outline(z, s, t)`.

    z_range_mm: (z0, z1) of the body; rod_radius_mm: mounting rod radius (0: none), the rod runs
    along the axis from below the body into it.
    """
    name: str
    z_range_mm: tuple[float, float]
    rod_radius_mm: float = 0.0
    params: dict = field(default_factory=dict)

    def scale(self, z) -> np.ndarray:
        """Section size factor in [0, 1] at z (array), 0 outside the body."""
        raise NotImplementedError

    def _outline(self, z: float, s: float, t: np.ndarray) -> np.ndarray:
        """(len(t), 2) section points at z with size factor s, parameter t in [0, 2 pi), mm."""
        raise NotImplementedError

    def section(self, z_mm: float, n: int = 360) -> np.ndarray:
        """(n, 2) counter-clockwise section polygon at z in the finger frame; (0, 2) outside."""
        t = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
        s = float(self.scale(np.array([z_mm]))[0])
        if s <= 0:
            return np.zeros((0, 2))
        return self._outline(z_mm, s, t)

    def convex_section(self, z_mm: float, n: int = 720) -> np.ndarray:
        """Convex hull of the section, CCW: what tangent-envelope reconstruction can recover."""
        pts = self.section(z_mm, n)
        if len(pts) < 3:
            return pts
        return pts[ConvexHull(pts).vertices]

    def area_mm2(self, z_mm: float, n: int = 720, convex: bool = True) -> float:
        """Section area (of the convex hull by default) at z."""
        p = self.convex_section(z_mm, n) if convex else self.section(z_mm, n)
        if len(p) < 3:
            return 0.0
        x, y = p[:, 0], p[:, 1]
        return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))

    def volume_mm3(self, z_lo: float, z_hi: float, convex: bool = True, n_z: int = 201) -> float:
        """Volume between two axial positions (Simpson's rule on section areas)."""
        z = np.linspace(z_lo, z_hi, n_z)
        return float(simpson([self.area_mm2(zi, convex=convex) for zi in z], x=z))

    def extent_table(self, z_mm: np.ndarray, directions: np.ndarray, n: int = 720) -> np.ndarray:
        """Support function h(z, n) of the body (rod included if it has one), mm.

        z_mm: (m,); directions: (k, 2) unit vectors. Returns (m, k); -inf where nothing is at z.
        The rod runs along the axis from far below the body to its middle.
        """
        h = np.full((len(z_mm), len(directions)), -np.inf)
        t = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
        for i, (z, s) in enumerate(zip(z_mm, self.scale(z_mm))):
            if s > 0:
                h[i] = (self._outline(z, s, t) @ directions.T).max(axis=0)
        if self.rod_radius_mm > 0:
            rod = z_mm < 0.5 * (self.z_range_mm[0] + self.z_range_mm[1])
            h[rod] = np.maximum(h[rod], self.rod_radius_mm)
        return h


class Fingertip(Shape):
    """Parametric fingertip: elliptic pad side, flattened (superellipse) nail side, section centre
    off the rotation axis, slight taper along z, ellipsoidal distal cap; optional concave dorsal
    groove (a nail-fold-like dent) that tangent-envelope reconstruction cannot see."""
    def __init__(self, preset: str = "human", groove: bool = False):
        if preset not in FINGERTIP_PRESETS:
            raise InputError(f"unknown fingertip preset '{preset}': use one of {sorted(FINGERTIP_PRESETS)}")
        p = dict(FINGERTIP_PRESETS[preset], preset=preset, groove=groove)
        super().__init__("fingertip", (0.0, p["length"]), p["rod_radius"], p)

    def scale(self, z):
        p, z = self.params, np.asarray(z, float)
        L, cap = p["length"], p["cap"]
        body = (z >= 0) & (z <= L)
        taper = 1.0 + p["taper"] * np.sin(np.pi * np.clip(z / L, 0, 1))
        u = np.clip((z - (L - cap)) / cap, 0.0, 1.0)
        return np.where(body, taper * np.sqrt(np.clip(1.0 - u**2, 0.0, None)), 0.0)

    def _outline(self, z, s, t):
        p = self.params
        c, sn = np.cos(t), np.sin(t)
        dorsal = sn < 0
        e = 2.0 / np.where(dorsal, p["p_dorsal"], 2.0)
        x = p["a"] * np.sign(c) * np.abs(c) ** e
        y = np.where(dorsal, p["b_dorsal"], p["b_volar"]) * np.sign(sn) * np.abs(sn) ** e
        if p["groove"]:
            w = 0.2 * p["a"]
            y = np.where(dorsal, y + 0.08 * p["b_dorsal"] * np.exp(-(x / w) ** 2), y)
        return np.column_stack([s * x + p["centre"][0], s * y + p["centre"][1]])


class Ellipsoid(Shape):
    """Ellipsoid with semi-axes (a, b, c) along x, y, z, centred at (cx, cy, 0); a sphere if a=b=c."""
    def __init__(self, name, a, b, c, centre=(0.0, 0.0), rod_radius=0.0):
        super().__init__(name, (-c, c), rod_radius, dict(a=a, b=b, c=c, centre=centre))

    def scale(self, z):
        z = np.asarray(z, float) / self.params["c"]
        return np.sqrt(np.clip(1.0 - z**2, 0.0, None)) * (np.abs(z) < 1)

    def _outline(self, z, s, t):
        p = self.params
        return np.column_stack([s * p["a"] * np.cos(t) + p["centre"][0],
                                s * p["b"] * np.sin(t) + p["centre"][1]])


def make_shape(name: str, preset: str = "human", groove: bool = False, rod: bool = True) -> Shape:
    """One of SHAPES. Sphere: R 7 mm, ellipsoid: 8 x 6 x 10 mm; both 0.5 mm off the axis."""
    if name == "fingertip":
        shape = Fingertip(preset, groove)
    elif name == "sphere":
        shape = Ellipsoid("sphere", 7.0, 7.0, 7.0, centre=(0.5, -0.3), rod_radius=1.0)
    elif name == "ellipsoid":
        shape = Ellipsoid("ellipsoid", 8.0, 6.0, 10.0, centre=(-0.4, 0.5), rod_radius=1.0)
    else:
        raise InputError(f"unknown shape '{name}': use one of {', '.join(SHAPES)}")
    if not rod:
        shape.rod_radius_mm = 0.0
    return shape


def shape_from_truth(truth: dict) -> Shape:
    """The Shape a rendered folder shows, from its truth dictionary (reconstruct.synthetic.load_truth)."""
    p = truth["params"]
    if truth["shape"] == "fingertip":
        shape = Fingertip(p["preset"], p["groove"])
    else:
        shape = Ellipsoid(truth["shape"], p["a"], p["b"], p["c"], tuple(p["centre"]))
    shape.rod_radius_mm = truth["rod_radius_mm"]
    return shape
