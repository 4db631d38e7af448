"""Rigid indentors as closed-form surfaces for large-deformation contact (`fem.contact.finite`):
the signed distance of points to the indentor's solid, its gradient (the contact normal, from the
indentor towards the point) and the curvature of its level set at the point (the contact's
geometric stiffness): the Hessian of the distance is k (I - n n^T - t t^T), k the curvature and
t the level set's straight direction (a cylinder's axis, the line of a bar's edge, a step's length
axis; zero where the level set curves every way, around a sphere or a plate's corner).

An indentor is the union of the solids of its pieces, so its gap is the smallest of their signed
distances, with that piece's normal and curvature. Pieces, each placed at its tip (the part's
foremost point) and moving with the indentor's travel along the approach a:

- `Round`: a cylinder of unbounded length (distance to its axis) or a sphere (to its centre),
  minus the radius;
- `Box`: a flat face with the solid behind it, bounded sideways by a bar's two sides, a plate's
  rectangle, a punch's circle, or one side only (the edge of a sharp step); the gap is to the
  face, to a side or to the edge, whichever is nearest (the signed distance to a semi-infinite box);
- `Setback`: the half-space behind a plane a fixed distance behind the tip (a sharp step's far
  level);
- `Ramp`: a smooth step's profile, flat, a half cosine rising to the step's height, flat again,
  extruded along the step's length axis: the closest point on the profile (sampled, then Newton).

Catalogue codes built from them (`RigidSurface`): cylinders, spheres, bars and R1-R2, plates,
punches, gratings (one `Box` per bar), steps 0-5 (step 0: `Box` + `Setback`; 1-5: `Ramp`) and
two-point stimuli with spherical tips. Wedges, cones (sharp edges and tips: the edge passes between
the nodes, measured in docs/indentation.md), finite cylinders and general ellipsoids are refused.

    surf = RigidSurface(make_indentor("step:2", orientation="parallel"))
    gap_mm, normal, curvature, straight = surf.distance(x, travel_mm=0.5)   # x (n, 3) mm
"""
from __future__ import annotations

import math

import numpy as np

from fem.contact.indentors import Cylinder, Ellipsoid, Flat, Grating, Punch, Step, shapes_for
from fingertip.errors import InputError

RAMP_SAMPLES = 65
"""Points of a ramp's profile from which the closest point's Newton search starts."""


class Round:
    """A cylinder along `axis` (unit (3,)) or a sphere (axis None) of radius_mm, tip foremost."""

    def __init__(self, radius_mm: float, axis=None):
        self.radius_mm, self.axis = radius_mm, axis

    def distance(self, rel, a):
        r = rel + self.radius_mm * a                          # from the axis or centre
        straight = np.zeros_like(r)
        if self.axis is not None:
            r = r - np.outer(r @ self.axis, self.axis)
            straight[:] = self.axis
        rho = np.linalg.norm(r, axis=1)
        return rho - self.radius_mm, r / rho[:, None], 1.0 / rho, straight


class Box:
    """A flat face through the tip with the solid behind it, bounded sideways: kind "bar" (half
    width half_mm along e2, unbounded along e1), "plate" (half_mm: half sides along e1 and e2),
    "punch" (radius half_mm) or "edge" (one side: the plane v = 0, the solid at v <= 0, v along e2)."""

    def __init__(self, kind: str, e1, e2, half_mm=0.0):
        self.kind, self.e1, self.e2, self.half_mm = kind, e1, e2, half_mm

    def distance(self, rel, a):
        ahead = rel @ a                                      # beyond the face, along the approach
        lateral = rel - np.outer(ahead, a)
        side, out_dir, k_side, rim = self._beyond_sides(lateral)
        corner = (ahead > 0) & (side > 0)
        g = np.where(corner, np.hypot(ahead, side), np.maximum(ahead, side))
        n = np.where((ahead >= side)[:, None], a, out_dir)
        k = np.where(ahead >= side, 0.0, k_side)
        straight = np.where((ahead >= side)[:, None], 0.0, a)  # beside: the sides' level sets run along a
        if corner.any():                                     # around the rim: a tube along it
            n[corner] = (ahead[corner, None] * a + side[corner, None] * out_dir[corner]) / g[corner, None]
            k[corner] = 1.0 / g[corner]
            straight[corner] = rim[corner]
        return g, n, k, straight

    def _beyond_sides(self, lateral):
        """(signed distance (n,) beyond the sides in the face's plane, unit direction (n, 3) out
        of them, curvature (n,) of that distance's level set in the plane: 1 / distance around a
        plate's corner or a punch's axis, else 0; the direction (n, 3) of the face's rim nearest:
        e1 along a bar or an edge, the circle's tangent around a punch (whose own curvature, at
        most 1 / radius, the tube around it leaves out), zero at a plate's corner) of lateral
        offsets (n, 3) from the tip."""
        n = len(lateral)
        if self.kind == "edge":
            return lateral @ self.e2, np.tile(self.e2, (n, 1)), np.zeros(n), np.tile(self.e1, (n, 1))
        if self.kind == "plate":
            return self._beyond_rectangle(lateral)
        if self.kind == "bar":
            lateral = np.outer(lateral @ self.e2, self.e2)
        dist = np.linalg.norm(lateral, axis=1)
        out = lateral / np.maximum(dist, 1e-300)[:, None]
        if self.kind == "bar":
            return dist - self.half_mm, out, np.zeros(n), np.tile(self.e1, (n, 1))
        return dist - self.half_mm, out, 1.0 / np.maximum(dist, 1e-300), np.cross(np.cross(self.e1, self.e2), out)

    def _beyond_rectangle(self, lateral):
        (hl, hw), e1, e2 = self.half_mm, self.e1, self.e2
        p, q = lateral @ e1, lateral @ e2
        dx, dy = np.abs(p) - hl, np.abs(q) - hw
        ex = np.where(p >= 0, 1.0, -1.0)[:, None] * e1
        ey = np.where(q >= 0, 1.0, -1.0)[:, None] * e2
        both = (dx > 0) & (dy > 0)
        side = np.where(both, np.hypot(dx, dy), np.maximum(dx, dy))
        out_dir = np.where((dx >= dy)[:, None], ex, ey)
        out_dir[both] = (dx[both, None] * ex[both] + dy[both, None] * ey[both]) / side[both, None]
        rim = np.where((dx >= dy)[:, None], e2, e1)
        rim[both] = 0.0
        return side, out_dir, np.where(both, 1.0 / np.where(both, side, 1.0), 0.0), rim


class Setback:
    """The half-space behind the plane setback_mm behind the tip."""

    def __init__(self, setback_mm: float):
        self.setback_mm = setback_mm

    def distance(self, rel, a):
        n = len(rel)
        return rel @ a + self.setback_mm, np.tile(a, (n, 1)), np.zeros(n), np.zeros((n, 3))


class Ramp:
    """A smooth step (`fem.contact.indentors.Step`, half-wavelength L > 0, height H): the surface
    lies h(v) behind the tip, h = 0 for v <= 0, H (1 - cos(pi v / L)) / 2 on [0, L], H beyond,
    v along e2; the solid is behind it."""

    def __init__(self, step: Step, e2):
        self.L, self.H, self.e2 = step.half_wavelength_mm, step.height_mm, e2

    def _h(self, s):
        """h, h', h'' at s (n,) in [0, L]."""
        c = 0.5 * self.H * math.pi / self.L
        t = math.pi * s / self.L
        return 0.5 * self.H * (1.0 - np.cos(t)), c * np.sin(t), c * math.pi / self.L * np.cos(t)

    def _foot_on_ramp(self, v, w):
        """(s (n,), squared distance (n,)) of the closest point of the ramp's curved part s in
        [0, L] to points (v, w): the best of RAMP_SAMPLES samples, then Newton on d/ds of the
        squared distance, kept in [0, L]."""
        grid = np.linspace(0.0, self.L, RAMP_SAMPLES)
        hg = self._h(grid)[0]
        d2 = (grid[None, :] - v[:, None]) ** 2 + (hg[None, :] + w[:, None]) ** 2
        s = grid[np.argmin(d2, axis=1)]
        for _ in range(8):
            h, h1, h2 = self._h(s)
            grad = (s - v) + (h + w) * h1
            hess = 1.0 + h1 * h1 + (h + w) * h2
            s = np.clip(s - np.where(hess > 0, grad / np.where(hess > 0, hess, 1.0), 0.0), 0.0, self.L)
        h = self._h(s)[0]
        return s, (s - v) ** 2 + (h + w) ** 2

    def distance(self, rel, a):
        v, w = rel @ self.e2, rel @ a
        s_ramp, d_ramp = self._foot_on_ramp(v, w)
        s_low, s_high = np.minimum(v, 0.0), np.maximum(v, self.L)
        d_low, d_high = (s_low - v) ** 2 + w ** 2, (s_high - v) ** 2 + (w + self.H) ** 2
        piece = np.argmin(np.stack([d_low, d_ramp, d_high]), axis=0)
        s = np.choose(piece, [s_low, s_ramp, s_high])
        h, h1, h2 = self._h(np.clip(s, 0.0, self.L))
        on_ramp = piece == 1
        h = np.where(piece == 0, 0.0, np.where(on_ramp, h, self.H))
        h1, h2 = np.where(on_ramp, h1, 0.0), np.where(on_ramp, h2, 0.0)
        norm = np.sqrt(1.0 + h1 * h1)
        nv, nw = h1 / norm, 1.0 / norm
        g = (v - s) * nv + (w + h) * nw
        kappa = h2 / norm ** 3                                # > 0 where the solid is convex
        bend = 1.0 + kappa * g
        k = np.where(bend > 0.1, kappa / np.where(bend > 0.1, bend, 1.0), 0.0)
        return g, nv[:, None] * self.e2 + nw[:, None] * a, k, np.tile(np.cross(self.e2, a), (len(v), 1))


class RigidSurface:
    """The closed-form surface of an indentor (`fem.contact.indentors.Indentor`) as the union of
    its pieces (module docstring), each at its part's tip. InputError for shapes it does not model."""

    def __init__(self, indentor):
        self.approach = indentor.approach
        e1, e2 = indentor.e1, indentor.e2
        self.pieces = []                                    # (tip (3,), piece)
        tips = indentor.origin_mm + indentor.offsets_mm @ np.stack([e1, e2])
        for shape, tip in zip(indentor.parts, tips):
            for off_v, piece in _pieces(indentor.name, shape, e1, e2):
                self.pieces.append((tip + off_v * e2, piece))
        self.tip = tips[0]                                  # the first part's (its frame's origin)

    def distance(self, x, travel_mm: float):
        """(gap (n,) mm, normal (n, 3) from the indentor towards the point, curvature (n,) [1/mm]
        of the gap's level set at the point, its straight direction (n, 3) (unit, or zero: the
        module docstring)) of points x (n, 3) when the tips have travelled travel_mm along the
        approach: the nearest piece's."""
        a = self.approach
        parts = [piece.distance(x - (tip + travel_mm * a), a) for tip, piece in self.pieces]
        if len(parts) == 1:
            return parts[0]
        g = np.stack([p[0] for p in parts])
        near = np.argmin(g, axis=0)
        rows = np.arange(g.shape[1])
        return (g[near, rows], *(np.stack([p[k] for p in parts])[near, rows] for k in (1, 2, 3)))


def check_modelled(spec: str) -> None:
    """InputError unless `RigidSurface` models the indentor code `spec` (before any placement)."""
    name, parts, _ = shapes_for(spec)
    for shape in parts:
        _pieces(name, shape, np.array([0.0, 0.0, 1.0]), np.array([1.0, 0.0, 0.0]))


def _pieces(name: str, shape, e1, e2) -> list:
    """[(offset along e2 (mm) of the piece's tip from the part's, piece)] of one part's shape."""
    if isinstance(shape, Cylinder) and not math.isfinite(shape.length_mm):
        return [(0.0, Round(0.5 * shape.diameter_mm, e1))]
    if isinstance(shape, Ellipsoid) and shape.is_sphere:
        return [(0.0, Round(shape.semi_u_mm))]
    if isinstance(shape, Flat):
        if math.isfinite(shape.length_mm):
            return [(0.0, Box("plate", e1, e2, (0.5 * shape.length_mm, 0.5 * shape.width_mm)))]
        return [(0.0, Box("bar", e1, e2, 0.5 * shape.width_mm))]
    if isinstance(shape, Punch):
        return [(0.0, Box("punch", e1, e2, 0.5 * shape.diameter_mm))]
    if isinstance(shape, Grating) and not math.isfinite(shape.length_mm) and not math.isfinite(shape.groove_mm):
        return [(0.5 * (lo + hi), Box("bar", e1, e2, 0.5 * shape.bar_mm)) for lo, hi in shape.bar_edges_mm()]
    if isinstance(shape, Step) and not math.isfinite(shape.length_mm):
        if shape.half_wavelength_mm == 0:
            return [(0.0, Box("edge", e1, e2)), (0.0, Setback(shape.height_mm))]
        return [(0.0, Ramp(shape, e2))]
    raise InputError(f"indentor {name}: finite kinematics takes cylinders (C1-C8, cylinder:<d>), spheres, "
                     f"bars (bar:<w>, R1, R2), plates, punches, gratings, steps (step:0-5) and two-point "
                     f"stimuli with spherical tips so far; use the linear kinematics for the others (wedges "
                     f"and cones: their sharp edge passes between the nodes)")
