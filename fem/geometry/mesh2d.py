"""2D plane-strain meshes (thesis ch. 4 and the reduced multilayer model of 8.5), triangles.

Domains: semi-infinite block 40 x 18 mm (top surface at y = 0, bottom and side edges fixed) and
square 8 x 8 mm (bottom edge fixed), cylinders of 8 and 16 mm diameter centred at the origin,
optionally with a concentric 2 mm bone (layer 5) or a fluid core inside 1 mm of solid (layer 6),
bottom third of the circumference fixed, and the five-layer cross-section of the 3D model at a
given z (nail span fixed).

Mesher: graded nested triangular lattices (spacing size_mm * 2^l, the level l of a point from the
target size there, like the thesis's factor-2 transition layers), points near a boundary or
interface replaced by samples along it at the local size, then Delaunay. Interface samples are
spaced so that every interface segment is a Delaunay edge; this is verified, and the mesh is
refused otherwise. Points are written as (x, y, 0).
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, field

import meshio
import numpy as np
from matplotlib.path import Path as MplPath
from scipy.spatial import Delaunay, cKDTree

from fem.core.materials import DEFAULT_NU, FLUID_LAYER, default_code
from fem.geometry.mesh3d import check_sizes, in_proportion, sizes_achieved
from fingertip.declare import declared, positive
from fingertip.errors import InputError
from fingertip.progress import as_progress
from fingertip.staging import staged_output, write_json

#: Solid layer around the fluid core of the solid-fluid cylinders (thesis 4.6), mm.
SOLID_FLUID_SHELL_MM = 1.0
PROPORTIONAL_2D = {"coarse_mm": (8.0, 1.0), "growth": (4.0, 0.5)}
"""2D sizes that follow size_mm when not given (`fem.geometry.mesh3d.in_proportion`): coarse_mm 8
size_mm, at most 1 mm; growth 4 size_mm per mm, at most 0.5 (the defaults at the default 0.125 mm;
the lattice's factor-2 steps spoil triangles where the size grows faster)."""
CAP_SIZE_MM = 0.125
"""The size_mm (the default) down to which each layer's elements are capped by its thinnest part;
below it the caps shrink in proportion to size_mm, so a finer mesh refines the thin layers too."""
SECTION_FACET_MM = 0.015
"""Longest facet of the curves of a cross-section of the 3D model (`section_domain`): as smooth as
the presets' circles (2048 points), so the 2D mesher's sampling sets the resolution."""
SECTION_SMOOTH_MM = 0.005
"""Spacing at which a cross-section's outline is sampled from the smooth curve through its
polygon's vertices before the rays (`fem.geometry.sections.smooth_polygon`): the 720-vertex
preset polygons have a corner every 0.03 mm on the pad, which meshes of 0.015625 mm resolve
(peak pressure +0.40 % there; docs/benchmarks.md)."""


@dataclass(frozen=True)
class Sizing2D:
    """size_mm in the top fine_depth_mm under the contact surface, growing by `growth` mm per mm
    of distance from that zone up to coarse_mm (also capped by each layer's thickness); coarse_mm
    and growth in proportion to size_mm unless given."""
    size_mm: float = declared(0.125, "mm", "target edge length on the volar skin (3D) or top surface (2D)", text=positive)
    coarse_mm: float | None = declared(None, "mm", "largest edge length", text=positive,
                                       default_text="8 x size, at most 1")
    growth: float | None = declared(None, "mm per mm", "edge length growth per mm away from the fine zone",
                                    text=positive, default_text="4 x size per mm, at most 0.5")
    fine_depth_mm: float = declared(1.0, "mm", "depth of the fine zone below the volar (3D) or top (2D) surface", text=positive)

    def __post_init__(self):
        in_proportion(self, PROPORTIONAL_2D)

    def check(self) -> None:
        check_sizes(self, 0.01, "2D")


@dataclass
class Domain2D:
    """curves: nested closed CCW polygons (n_i, 2), outermost first; layers[i] is the layer
    number between curve i and curve i+1 (the last: inside the last curve).
    surface(points) / fixed(points) -> bool masks for boundary points; depth(points) -> mm below
    the contact surface (inf where not under it); breaks: points of the outer curve where a region
    begins or ends, which the mesher makes mesh vertices (so a region's extent does not depend on
    the element size there)."""
    name: str
    curves: list
    layers: list
    surface: object
    fixed: object
    depth: object
    params: dict = field(default_factory=dict)
    breaks: list = field(default_factory=list)


# ---------------------------------------------------------------------- domains
def _circle(r, c=(0.0, 0.0), n=2048):
    t = 2 * np.pi * np.arange(n) / n
    return np.column_stack([c[0] + r * np.cos(t), c[1] + r * np.sin(t)])


def _angle_mask(points, centre_xy, direction, span_deg):
    d = points - centre_xy
    theta = np.arctan2(d[:, 1], d[:, 0])
    return np.abs(np.angle(np.exp(1j * (theta - direction)))) <= np.deg2rad(span_deg) / 2 + 1e-9


def _span_marks(poly, centre_xy, direction, span_deg) -> list:
    """The points of the closed polygon (star-shaped about centre_xy) at the two ends and the middle
    of the span `_angle_mask` selects (the middle only for a whole turn): mesh vertices there make a
    region's extent and its apex (where an indentor first touches) independent of the element size."""
    half = np.deg2rad(min(span_deg, 360.0)) / 2
    angles = [direction] if span_deg >= 360 else [direction - half, direction, direction + half]
    a, e = poly, np.roll(poly, -1, axis=0) - poly
    r = a - np.asarray(centre_xy, float)
    out = []
    for angle in angles:
        u = np.array([np.cos(angle), np.sin(angle)])
        den = u[0] * e[:, 1] - u[1] * e[:, 0]                  # c + t u = a + s e, solved for t and s
        with np.errstate(divide="ignore", invalid="ignore"):
            t, s = (r[:, 0] * e[:, 1] - r[:, 1] * e[:, 0]) / den, (r[:, 0] * u[1] - r[:, 1] * u[0]) / den
        t = np.where((s >= 0) & (s <= 1) & (t > 0), t, np.inf)
        out.append(np.asarray(centre_xy, float) + t.min() * u)
    return out


def preset_domain(name: str, bone: bool = False, solid_fluid: bool = False) -> Domain2D:
    """One of the thesis's 2D models: block, square, cylinder8, cylinder16. Cylinders only: bone
    adds the concentric 2 mm bone (layer 5); solid_fluid makes the core inside 1 mm of solid an
    incompressible fluid (layer 6, thesis 4.6)."""
    if (bone or solid_fluid) and name not in ("cylinder8", "cylinder16"):
        raise InputError(f"the bone and the fluid core are for the 2D cylinders, not '{name}'")
    if bone and solid_fluid:
        raise InputError("a solid-fluid cylinder has no bone (thesis 4.6): give one of bone, solid_fluid")
    if name == "block":
        return rectangle_domain("block", 40.0, 18.0, held_sides=True)
    if name == "square":
        return rectangle_domain("square", 8.0, 8.0, held_sides=False)
    if name in ("cylinder8", "cylinder16"):
        R = 4.0 if name == "cylinder8" else 8.0
        core = [_circle(1.0, n=512)] if bone else [_circle(R - SOLID_FLUID_SHELL_MM)] if solid_fluid else []
        up = lambda p: _angle_mask(p, (0, 0), np.pi / 2, 180.0)  # noqa: E731
        layers = [1, 5] if bone else [1, FLUID_LAYER] if solid_fluid else [1]
        outer = _circle(R)
        return Domain2D(name + ("_bone" if bone else "_fluid" if solid_fluid else ""), [outer] + core, layers,
                        surface=up, fixed=lambda p: _angle_mask(p, (0, 0), -np.pi / 2, 120.0),
                        depth=lambda p: np.where(up(p), R - np.hypot(p[:, 0], p[:, 1]), np.inf),
                        params={"diameter_mm": 2 * R, "bone_diameter_mm": 2.0 if bone else None,
                                "fluid_core_diameter_mm": 2 * (R - SOLID_FLUID_SHELL_MM) if solid_fluid else None,
                                "fixed": "bottom third of the circumference (120 deg about -y)",
                                "surface": "upper half of the circumference"},
                        breaks=_span_marks(outer, (0, 0), -np.pi / 2, 120.0) + _span_marks(outer, (0, 0), np.pi / 2, 180.0))
    raise InputError(f"unknown 2D preset '{name}': use block, square, cylinder8 or cylinder16")


def rectangle_domain(name: str, width_mm: float, height_mm: float, held_sides: bool) -> Domain2D:
    """Rectangle with its top edge (y = 0) the contact surface and its bottom edge held; held_sides
    also holds both side edges. The thesis's semi-infinite model (block, 40 x 18 mm) holds them:
    a half-space is at rest far from the load. With free sides that block is 17 % off Flamant's
    radial stress at r = 3 mm, 60 deg from the load; with held sides 4 % (docs/verification.md)."""
    w, h = float(width_mm), float(height_mm)
    rect = np.array([[-w / 2, -h], [w / 2, -h], [w / 2, 0.0], [-w / 2, 0.0]])
    bottom = lambda p: np.abs(p[:, 1] + h) < 1e-9  # noqa: E731
    sides = lambda p: np.abs(np.abs(p[:, 0]) - w / 2) < 1e-9  # noqa: E731
    return Domain2D(name, [rect], [1], surface=lambda p: np.abs(p[:, 1]) < 1e-9,
                    fixed=(lambda p: bottom(p) | sides(p)) if held_sides else bottom,
                    depth=lambda p: -p[:, 1],
                    params={"width_mm": w, "height_mm": h, "top_y_mm": 0.0,
                            "fixed": "bottom and side edges" if held_sides else "bottom edge",
                            "surface": "top edge"})


def section_domain(model, z_mm: float) -> Domain2D:
    """Five-layer cross-section of the 3D model at z: its rings, from its sections as smooth curves
    (SECTION_SMOOTH_MM), on rays dense enough for facets of at most SECTION_FACET_MM
    (`fem.geometry.layered.LayeredModel.section_rings`)."""
    z = model.z_mm
    if not z[0] <= z_mm <= z[-1]:
        raise InputError(f"--section-z {z_mm} is outside the model ({z[0]:g} to {z[-1]:g} mm)")
    rings, c = model.section_rings(z_mm, model.rays_for(SECTION_FACET_MM), smooth_mm=SECTION_SMOOTH_MM)
    p = model.params
    volar = lambda q: _angle_mask(q, c, np.pi / 2, p.volar_span_deg)  # noqa: E731

    def depth(q):

        d = _polyline_distance(q, rings[0])
        return np.where(volar(q) & MplPath(rings[0]).contains_points(q, radius=1e-9), d, np.inf)

    return Domain2D(f"section_z{z_mm:g}", list(rings), [1, 2, 3, 4, 5], surface=volar,
                    fixed=lambda q: _angle_mask(q, c, -np.pi / 2, p.nail_span_deg), depth=depth,
                    params={"section_z_mm": z_mm, "centroid_mm": c.tolist(), "preset": model.preset,
                            "fixed": f"nail span {p.nail_span_deg} deg about -y",
                            "surface": f"volar span {p.volar_span_deg} deg about +y",
                            "model": {k: v for k, v in model.to_json().items() if k != "regions"}},
                    breaks=_span_marks(rings[0], c, -np.pi / 2, p.nail_span_deg)
                    + _span_marks(rings[0], c, np.pi / 2, p.volar_span_deg))


# ---------------------------------------------------------------------- geometry helpers
def _polyline_distance(q: np.ndarray, poly: np.ndarray, near: int = 8) -> np.ndarray:
    """Distance (M,) from points q (M, 2) to the closed polygon poly (n, 2): to the segments at the
    `near` vertices nearest each point (all of them for a small polygon), which hold the nearest
    point of a densely sampled curve."""
    n = len(poly)
    ab = np.roll(poly, -1, axis=0) - poly
    ab2 = np.einsum("nk,nk->n", ab, ab)
    k = min(near, n)
    _, idx = cKDTree(poly).query(q, k=k) if k < n else (None, np.broadcast_to(np.arange(n), (len(q), n)))
    idx = np.asarray(idx).reshape(len(q), -1)
    seg = np.concatenate([idx, (idx - 1) % n], axis=1)                   # the segments starting and ending there
    d = q[:, None] - poly[seg]
    t = np.clip(np.einsum("mjk,mjk->mj", d, ab[seg]) / ab2[seg], 0, 1)
    return np.linalg.norm(d - t[..., None] * ab[seg], axis=2).min(axis=1)


def _inside(q: np.ndarray, poly: np.ndarray) -> np.ndarray:

    return MplPath(poly).contains_points(q)


def _label(domain: Domain2D, q: np.ndarray) -> np.ndarray:
    """Layer at points q (0 = outside): the layer inside the innermost curve containing q."""
    depth = sum(_inside(q, c).astype(int) for c in domain.curves)
    lab = np.zeros(len(q), int)
    lab[depth > 0] = np.asarray(domain.layers)[depth[depth > 0] - 1]
    return lab


def _layer_caps(domain: Domain2D) -> list[float]:
    """Thinnest part (mm) of each layer region: min distance between consecutive curves."""
    caps = []
    for i in range(len(domain.curves)):
        if i + 1 < len(domain.curves):
            caps.append(float(_polyline_distance(domain.curves[i + 1], domain.curves[i]).min()))
        else:
            xy = domain.curves[i]
            caps.append(float(np.ptp(xy, axis=0).min()))
    return caps


# ---------------------------------------------------------------------- mesher
def target_size(domain: Domain2D, sizing: Sizing2D, q: np.ndarray) -> np.ndarray:
    """Target edge length (mm) at points q (M, 2), before the per-layer caps."""
    d = domain.depth(q)
    dist = np.clip(d - sizing.fine_depth_mm, 0, None)
    # points not under the contact surface: distance to the fine zone along the boundary is
    # approximated by their distance to the nearest fine-zone sample point
    far = ~np.isfinite(d)
    if far.any():

        outer = _resample(domain.curves[0], sizing.size_mm)
        zone = outer[domain.surface(outer)]
        dist[far] = cKDTree(zone).query(q[far])[0]
    return np.minimum(sizing.size_mm + sizing.growth * dist, sizing.coarse_mm)


def _resample(poly: np.ndarray, step: float) -> np.ndarray:
    """Closed polygon resampled at about `step` mm arc length, its vertices kept (so that the
    polyline through the samples is the polygon)."""
    seg = np.linalg.norm(np.roll(poly, -1, axis=0) - poly, axis=1)
    s = np.concatenate([[0], np.cumsum(seg)])
    n = max(int(np.ceil(s[-1] / step)), 8)
    t = np.union1d(np.linspace(0, s[-1], n, endpoint=False), s[:-1])
    closed = np.vstack([poly, poly[:1]])
    return np.column_stack([np.interp(t, s, closed[:, 0]), np.interp(t, s, closed[:, 1])])


def _sample_curve(poly: np.ndarray, h_at, cap: float, breaks=()) -> np.ndarray:
    """Points along a closed polygon spaced by the local target size (capped): its corners and the
    break points given on it are samples, and each piece between them is divided evenly."""
    dense = _resample(poly, min(cap, 0.02) / 2)
    knots = np.vstack([_corners(poly), np.reshape(np.asarray(breaks, float), (-1, 2))])
    at = np.zeros(0, int)
    if len(knots):
        _, at = cKDTree(dense).query(knots)
        dense[at] = knots                                    # the knots themselves on the dense curve
        at = np.unique(at)
    h = np.minimum(h_at(dense), cap)
    seg = np.linalg.norm(np.roll(dense, -1, axis=0) - dense, axis=1)
    u = np.concatenate([[0], np.cumsum(seg / h)])          # arc length in units of local size
    stretch = max(1.0, 8 / u[-1])                           # at least 8 samples
    starts = u[at] if len(at) else np.zeros(1)
    ends = np.append(starts[1:], starts[0] + u[-1])
    counts = np.maximum(1, np.round(stretch * (ends - starts))).astype(int)
    targets = np.unique(np.concatenate([a + (b - a) * np.arange(n) / n
                                        for a, b, n in zip(starts, ends, counts)]) % u[-1])
    closed = np.vstack([dense, dense[:1]])                  # positions at the targets' arc lengths, in order
    return np.column_stack([np.interp(targets, u, closed[:, 0]), np.interp(targets, u, closed[:, 1])])


def _corners(poly: np.ndarray) -> np.ndarray:
    e1 = poly - np.roll(poly, 1, axis=0)
    e2 = np.roll(poly, -1, axis=0) - poly
    cos = np.einsum("ij,ij->i", e1, e2) / (np.linalg.norm(e1, axis=1) * np.linalg.norm(e2, axis=1))
    return poly[cos < 0.9]


def mesh_domain(domain: Domain2D, sizing: Sizing2D):
    """-> (points (P, 2), triangles (T, 3) CCW, layer (T,) int32). Raises RuntimeError if an
    interface is not recovered as mesh edges."""
    sizing.check()
    h0 = sizing.size_mm
    caps = [cap * min(1.0, h0 / CAP_SIZE_MM) for cap in _layer_caps(domain)]
    if len(domain.curves) > 1:
        caps[-1] /= 4                  # innermost disc (bone): keep interior points, no slivers
    # curves first: samples at the local size, capped by the adjacent layers' thinnest part
    samples, spacing = [], []
    for i, c in enumerate(domain.curves):
        cap = min(caps[max(i - 1, 0)], caps[i], _perimeter(c) / 48)   # 48: area error < 0.3 % on a circle
        s = _sample_curve(c, lambda p: target_size(domain, sizing, p), cap, domain.breaks if i == 0 else ())
        samples.append(s)
        seg = np.linalg.norm(np.roll(s, -1, axis=0) - s, axis=1)
        spacing.append(np.maximum(seg, np.roll(seg, 1)))            # longest segment at each sample
    allc, spacing = np.vstack(samples), np.concatenate(spacing)
    row, row_spacing = _surface_row(samples[0], allc, spacing, domain.surface, h0)
    tree = cKDTree(np.vstack([allc, row]))
    spacing = np.concatenate([spacing, row_spacing])
    # nested triangular lattices: keep a lattice-0 point iff it lies on the lattice of its level
    lo, hi = domain.curves[0].min(0), domain.curves[0].max(0)
    a, b = np.array([h0, 0.0]), np.array([h0 / 2, h0 * np.sqrt(3) / 2])
    jn = int(np.ceil((hi[1] - lo[1]) / b[1])) + 2
    shift = jn // 2 + 2
    i_rng = np.arange(-shift, int(np.ceil((hi[0] - lo[0]) / h0)) + shift)
    I, J = np.meshgrid(i_rng, np.arange(jn + 1), indexing="ij")
    I, J = I.ravel(), J.ravel()
    q = lo + I[:, None] * a + J[:, None] * b
    lab = _label(domain, q)
    q, I, J, lab = q[lab > 0], I[lab > 0], J[lab > 0], lab[lab > 0]
    layer_idx = {L: i for i, L in enumerate(domain.layers)}
    d, j = tree.query(q)
    near_curve = spacing[j] + sizing.growth * d           # grade away from finely sampled curves too
    h = np.minimum.reduce([target_size(domain, sizing, q), np.array([caps[layer_idx[L]] for L in lab]),
                           near_curve])
    level = np.floor(np.log2(h / h0 + 1e-9)).astype(int).clip(0, None)
    keep = (I % (2**level) == 0) & (J % (2**level) == 0)
    keep &= d > 0.75 * np.maximum(h, spacing[j])        # > 1/sqrt(2): outside every segment's diametral circle
    q = q[keep]
    pts = np.vstack([allc, row, q])
    tri = Delaunay(pts).simplices
    x = pts[tri]
    area = 0.5 * ((x[:, 1, 0] - x[:, 0, 0]) * (x[:, 2, 1] - x[:, 0, 1])
                  - (x[:, 1, 1] - x[:, 0, 1]) * (x[:, 2, 0] - x[:, 0, 0]))
    tri[area < 0] = tri[area < 0][:, [0, 2, 1]]
    centroid_lab = _label(domain, x.mean(axis=1))
    ok = (np.abs(area) > 1e-12 * h0**2) & (centroid_lab > 0)
    tri, layer = tri[ok], centroid_lab[ok].astype(np.int32)
    _check_interfaces(samples, tri)
    return pts, tri, layer


def _surface_row(outer: np.ndarray, samples: np.ndarray, spacing: np.ndarray, surface, h0: float):
    """A row of points under the contact surface: one under the middle of each segment of the outer
    curve's samples `outer` (CCW) that lies on the surface and is of the fine size h0, at the height
    of an equilateral triangle on it, so the elements under the contact are regular (the contact
    pressure of the lattice's irregular triangles along the curve varied by 1 % from node to node);
    none too near another curve's samples. -> (points, spacing)."""
    nxt = np.roll(outer, -1, axis=0)
    t = nxt - outer
    length = np.linalg.norm(t, axis=1)
    row = 0.5 * (outer + nxt) + np.sqrt(3) / 2 * np.column_stack([-t[:, 1], t[:, 0]])
    d, j = cKDTree(samples).query(row)
    ok = (d > 0.7 * np.maximum(length, spacing[j])) & surface(outer) & surface(nxt) & (length < 1.25 * h0)
    return row[ok], length[ok]


def _check_interfaces(samples: list, tri: np.ndarray) -> None:
    """Every segment of every sampled curve must be a mesh edge (the mesh conforms)."""
    edges = np.sort(np.vstack([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]]), axis=1)
    have = set(map(tuple, edges))
    start = 0
    for i, s in enumerate(samples):
        n = len(s)
        idx = start + np.arange(n)
        seg = np.sort(np.column_stack([idx, np.roll(idx, -1)]), axis=1)
        missing = sum(tuple(e) not in have for e in seg)
        if missing:
            raise RuntimeError(f"2D mesher: {missing} of {n} segments of curve {i} not recovered")
        start += n


# ---------------------------------------------------------------------- report and output
def report2d(domain: Domain2D, sizing: Sizing2D, pts, tri, layer, flags) -> dict:
    x = pts[tri]
    e = [np.linalg.norm(x[:, (i + 1) % 3] - x[:, i], axis=1) for i in range(3)]
    ang = []
    for i in range(3):
        u, v = x[:, (i + 1) % 3] - x[:, i], x[:, (i + 2) % 3] - x[:, i]
        ang.append(np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", u, v)
                                                / (np.linalg.norm(u, axis=1) * np.linalg.norm(v, axis=1)), -1, 1))))
    min_ang = np.min(ang, axis=0)
    area = 0.5 * np.abs((x[:, 1, 0] - x[:, 0, 0]) * (x[:, 2, 1] - x[:, 0, 1])
                        - (x[:, 1, 1] - x[:, 0, 1]) * (x[:, 2, 0] - x[:, 0, 0]))
    layers = sorted(set(domain.layers))
    curve_area = [_poly_area(c) for c in domain.curves] + [0.0]
    model_area = {L: curve_area[i] - curve_area[i + 1] for i, L in enumerate(domain.layers)}
    top = domain.depth(x.mean(axis=1)) <= sizing.fine_depth_mm          # the fine zone: the top fine_depth_mm
    return {
        "domain": domain.name, "points": len(pts), "triangles": len(tri),
        "triangles_per_layer": {str(L): int((layer == L).sum()) for L in layers},
        "layer_areas_mm2": {str(L): float(area[layer == L].sum()) for L in layers},
        "model_layer_areas_mm2": {str(L): float(model_area[L]) for L in layers},
        "min_angle_deg": float(min_ang.min()), "p1_angle_deg": float(np.percentile(min_ang, 1)),
        "sizing_achieved": sizes_achieved(pts, tri, np.mean(e, axis=0), layer, top),
        "regions": {k: int(v.sum()) for k, v in flags.items()},
    }


def _perimeter(p):
    return float(np.linalg.norm(np.roll(p, -1, axis=0) - p, axis=1).sum())


def _poly_area(p):
    return 0.5 * float(np.dot(p[:, 0], np.roll(p[:, 1], -1)) - np.dot(p[:, 1], np.roll(p[:, 0], -1)))


def boundary_points(tri: np.ndarray, n_points: int) -> np.ndarray:
    """(P,) bool: points on edges that belong to one triangle."""
    edges = np.sort(np.vstack([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]]), axis=1)
    uniq, cnt = np.unique(edges, axis=0, return_counts=True)
    out = np.zeros(n_points, bool)
    out[uniq[cnt == 1].ravel()] = True
    return out


def run_mesh2d(out_dir, domain: Domain2D, sizing: Sizing2D, progress=None):
    """Mesh, check and write mesh.vtu + model.json; returns ((points, triangles, layer, flags), report).
    progress: optional `fingertip.progress` object, or True for one on stderr (None, False: silent)."""
    with as_progress(progress).task(f"meshing 2D {domain.name} (top size {sizing.size_mm} mm)"):
        pts, tri, layer = mesh_domain(domain, sizing)
    on_b = boundary_points(tri, len(pts))
    flags = {"fixed": (on_b & domain.fixed(pts)).astype(np.uint8),
             "surface": (on_b & domain.surface(pts)).astype(np.uint8)}
    rep = report2d(domain, sizing, pts, tri, layer, flags)
    xyz = np.column_stack([pts, np.zeros(len(pts))])
    m = meshio.Mesh(xyz, [("triangle", tri.astype(np.int64))], cell_data={"layer": [layer]},
                    point_data=flags)
    data = {"kind": "2d plane strain", "units": "mm", "points": "(x, y, 0)", "domain": domain.name,
            "params": domain.params, "layers": domain.layers, "sizing": asdict(sizing),
            "material": default_code(domain.layers), "nu": DEFAULT_NU,
            "mesh": rep}
    with staged_output(out_dir) as tmp:
        meshio.write(tmp / "mesh.vtu", m)
        write_json(tmp / "model.json", data)
    return (pts, tri, layer, flags), rep


def summary(rep: dict, out_dir) -> str:
    a = rep["sizing_achieved"]
    lines = [f"mesh.vtu + model.json in {out_dir}",
             f"  2D {rep['domain']}: {rep['triangles']} triangles, {rep['points']} points",
             "  layer  triangles  area mm2   model mm2"]
    for L, n in rep["triangles_per_layer"].items():
        lines.append(f"  {L:>5} {n:>10} {rep['layer_areas_mm2'][L]:>9.3f} {rep['model_layer_areas_mm2'][L]:>11.3f}")
    lines += [f"  {a['dofs']} DOFs (P2); top zone: {a['fine_zone_elements']} triangles, median edge "
              f"{a['fine_zone_median_edge_mm']:.3f} mm (90th pct {a['fine_zone_p90_edge_mm']:.3f}); elsewhere "
              f"{a['elsewhere_median_edge_mm']:.3f}, largest {a['elsewhere_max_edge_mm']:.3f} mm; per layer "
              + " ".join(f"{v['median_edge_mm']:.3f}" for v in a["per_layer"].values()) + " mm",
              f"  min angle {rep['min_angle_deg']:.1f} deg (1st pct {rep['p1_angle_deg']:.1f})",
              "  regions: " + ", ".join(f"{k} {v} points" for k, v in rep["regions"].items())]
    return "\n".join(lines)
