"""An elastic block standing in for a half-space under a rigid flat circular punch (Sneddon 1946).

Units mm, N, MPa; the project's axes: the top face y = 0 is the contact surface, the body is
y < 0, the punch (radius a, on the y axis) approaches along -y. The block checks the 3D contact
solver against `fem.verify.closed_forms.sneddon_punch_force_N` and `sneddon_punch_stress_zz_MPa` at the
depths where TouchSim places its afferents (tests/fem/verify/test_sneddon.py, benchmarks/sneddon_check.py).

    block = flat_block_model()                                        # quarter block, factorised
    points = [[0.0, -0.3, 0.0], [0.5, -1.6, 0.0]]                     # (x, y, z) mm, z = 0 plane
    cm = block.contact(observe=block.model.stress_operator(points))   # fem.contact.linear.ContactModel
    res = cm.indent(block.punch(), depth_mm=0.5)
    force_N = block.symmetry * res.total_force_N                      # the whole punch
    sigma_yy = res.observed.reshape(-1, 6)[:, 1]                      # MPa, tension positive

Mesh. The plan (x, z) is an O-grid: a core of n x n squares (n = a / fine_mm) whose square rings
are mapped onto circles, so that the punch edge r = a is a ring of mesh vertices (the contact set
is the disc itself, not a staircase of nodes), then rings of the same spacing out to
`fine_radius_mm`, then rings growing geometrically out to the block's sides, where the mapping
blends back to the square. The plan triangles are extruded through layers of the same spacing
down to `fine_depth_mm`, growing below, and every prism is cut into three conforming tets
(`fem.verify.closed_forms._prisms_to_tets`); P2 elements (fem.core.model.Model). The defaults (0.25 mm, a = 1 mm,
80 mm quarter block) give 115,593 DOFs, set up and factorised in 10-12 s on 2 cores (1.9 GB).
`round_punch=False` builds a plain tensor grid instead (`fem.verify.closed_forms.box`): at the same fine
spacing it has 3x the DOFs (351,231; 89 s, 18 GB) and is worse, the punch edge a staircase of
nodes: force -3.2 % (too soft), stress distribution up to 9.6 % off, against +1.6 % and 1.6 %
(benchmarks/sneddon_check.py).

Boundary. The bottom is fixed. Free sides approximate the half-space best: on a 20 mm block the
punch force is +5.1 % above Sneddon's with free sides, +6.2 % with rollers (normal displacement
held), +6.3 % with fixed sides: the fixed bottom stiffens the block and free sides partly make up
for it. The excess falls as about 0.9 a / L with the block size L (free sides, W = D = L: +10.0 %
at 10 mm, +5.1 % at 20, +2.8 % at 40, +1.6 % at 80, +1.1 % at 160) over a mesh error of about
+0.5 % at fine_mm = 0.25 (+0.4 % at 0.167); the stresses at the FE's own force do not depend on L
(within 0.1 % from 20 to 160 mm). The grading makes a large block cheap (80 mm: 1.2x the DOFs of
40 mm), hence the 80 mm default.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fem.contact.indentors import make_indentor
from fem.contact.linear import ContactModel, reach
from fem.core.model import Model
from fem.verify.closed_forms import _prisms_to_tets, box, fine_then_growing

APPROACH = np.array([0.0, -1.0, 0.0])
"""The punch approaches along -y."""
FINE_RADII = 2.5
"""Default extent of the uniform fine zone, in punch radii, in plan and in depth: it holds the
stress points of the check (r <= 2 a, and TouchSim's afferent depths 0.3-2 mm for a = 1 mm)."""
RING_SHRINK = 1e-12
"""Relative inward shift of the punch-edge ring: its vertices must count as under the punch
(fem.contact.indentors.Punch takes r <= a), which rounding in the mapping would otherwise decide."""

@dataclass
class HalfSpaceBlock:
    """A factorised elastic block: what `fem.contact.linear.ContactModel.from_fe` consumes (`model`,
    `system`, `region`), the punch radius, the constraints, and the symmetry factor (4 for a
    quarter block: the whole punch carries `symmetry` times the model's force)."""
    model: object               # fem.core.model.Model
    system: object              # fem.core.system.LinearSystem, punch footprint condensed along -y
    region: str                 # contact region: "top"
    radius_mm: float
    symmetry: int               # 4: quarter block x, z >= 0 with symmetry planes; 1: whole block
    prescribed: dict            # the constraints `system` holds

    def punch(self):
        """The flat punch of this radius on the block's axis (fem.contact.indentors; approach -y)."""
        return make_indentor(f"punch:{2 * self.radius_mm!r}")

    def contact(self, observe=None):
        """fem.contact.linear.ContactModel on the top face; observe: optional sparse (r, ndof) operator
        (e.g. `model.stress_operator(points)`) whose response comes with each indentation."""
        return ContactModel.from_fe(self.model, self.system, self.region, observe=observe)


def _rounded(p, a, b, W):
    """Map plan points p (n, 2), laid out on concentric squares (Chebyshev radius m), so that the
    squares become circles of radius m for a <= m <= b, with a blend weight w (p -> p (m/|p|)^w)
    growing as m / a inside a and falling linearly to 0 (the square) at m = W."""
    m = np.abs(p).max(axis=1)
    r = np.hypot(p[:, 0], p[:, 1])
    w = np.where(m <= a, m / a, np.where(m <= b, 1.0, np.clip((W - m) / (W - b), 0.0, 1.0)))
    with np.errstate(invalid="ignore", divide="ignore"):
        scale = np.where(r > 0, (m / r) ** w, 1.0)
    return p * scale[:, None]


def plan_mesh(radius_mm, half_width_mm, fine_mm, growth, quarter=True, fine_radius_mm=None):
    """Triangles of the plan (x, z): (points (N, 2), triangles (M, 3)), the O-grid of the module
    docstring. Quarter: x, z in [0, W]; else [-W, W] (the quarter reflected). Spacing fine_mm
    (rounded to divide the radius) out to fine_radius_mm (default FINE_RADII radii), then growing
    by `growth` per ring."""
    a, W = float(radius_mm), float(half_width_mm)
    b = FINE_RADII * a if fine_radius_mm is None else max(float(fine_radius_mm), a)
    if not W > b:
        raise ValueError(f"the block's half width {W} mm must exceed the fine zone's radius {b} mm")
    n = max(1, round(a / fine_mm))
    m = fine_then_growing(a / n, b, growth, W, exact=True)      # Chebyshev radii of the square rings
    m[n] = a
    K = len(m) - 1
    # core: the (n + 1)^2 grid of [0, a]^2; ring k > n: 2n + 1 points (m, m j / n), (m j / n, m)
    core = np.stack(np.meshgrid(m[:n + 1], m[:n + 1], indexing="ij"), axis=-1).reshape(-1, 2)
    ring = np.stack([np.outer(m[n + 1:], np.r_[np.ones(n + 1), np.arange(n - 1, -1, -1) / n]),
                     np.outer(m[n + 1:], np.r_[np.arange(n + 1) / n, np.ones(n)])], axis=-1).reshape(-1, 2)
    cid = np.arange((n + 1) ** 2).reshape(n + 1, n + 1)
    idx = np.empty((K + 1, 2 * n + 1), np.int64)            # point j of ring k >= n (j = n: diagonal)
    idx[n] = np.r_[cid[n, :], cid[n - 1::-1, n]]
    idx[n + 1:] = (n + 1) ** 2 + np.arange((K - n) * (2 * n + 1)).reshape(K - n, 2 * n + 1)
    quads = np.vstack([np.column_stack([cid[:-1, :-1].ravel(), cid[1:, :-1].ravel(), cid[1:, 1:].ravel(),
                                        cid[:-1, 1:].ravel()]),
                       np.column_stack([idx[n:-1, :-1].ravel(), idx[n + 1:, :-1].ravel(),
                                        idx[n + 1:, 1:].ravel(), idx[n:-1, 1:].ravel()])])
    b = m[min(int(np.searchsorted(m, b - 1e-9)), K - 1)]    # circles out to here
    pts = _rounded(np.vstack([core, ring]), a, b, W)
    pts[idx[n]] *= 1.0 - RING_SHRINK                       # the punch edge
    d02 = np.linalg.norm(pts[quads[:, 0]] - pts[quads[:, 2]], axis=1)
    d13 = np.linalg.norm(pts[quads[:, 1]] - pts[quads[:, 3]], axis=1)
    on02 = d02 <= d13                                       # cut each quad on its shorter diagonal
    tri = np.vstack([quads[on02][:, [0, 1, 2]], quads[on02][:, [0, 2, 3]],
                     quads[~on02][:, [0, 1, 3]], quads[~on02][:, [1, 2, 3]]])
    if quarter:
        return pts, tri
    signs = [(1, 1), (-1, 1), (-1, -1), (1, -1)]
    allp = np.vstack([pts * s for s in signs])
    key = np.round(allp / (1e-9 * W)).astype(np.int64)      # merge the copies on the axes
    _, first, inv = np.unique(key, axis=0, return_index=True, return_inverse=True)
    inv = inv.ravel()
    return allp[first], inv[np.vstack([tri + k * len(pts) for k in range(4)])]


def flat_block_model(half_width_mm=80.0, depth_mm=80.0, fine_mm=0.25, radius_mm=1.0, E_MPa=0.05, nu=0.4,
                     sides="free", quarter=True, growth=1.4, depth_growth=1.3, fine_depth_mm=None,
                     fine_radius_mm=None, round_punch=True) -> HalfSpaceBlock:
    """A homogeneous elastic block, x and z in [-W, W] (quarter: [0, W] with the symmetry planes
    x = 0 and z = 0 on rollers), y in [-D, 0], bottom fixed, factorised with the punch footprint
    (r <= radius on the top face) condensed along -y (module docstring: mesh and boundary).

    sides: "free", "held" (fixed) or "roller" (normal displacement held) on the outer sides.
    fine_mm: element size under the punch, out to fine_radius_mm and down to fine_depth_mm
    (both FINE_RADII radii by default); beyond, the plan rings grow by `growth` and the layers
    by `depth_growth` per element. E_MPa, nu: the material (defaults TouchSim's, 0.05 MPa, 0.4).
    round_punch: O-grid plan with the punch edge a ring of vertices; False: a tensor grid."""
    if sides not in ("free", "held", "roller"):
        raise ValueError(f"sides must be 'free', 'held' or 'roller', got {sides!r}")
    a, W, D = float(radius_mm), float(half_width_mm), float(depth_mm)
    h = a / max(1, round(a / fine_mm))
    fine_depth = FINE_RADII * a if fine_depth_mm is None else fine_depth_mm
    ys = -fine_then_growing(h, fine_depth, depth_growth, D, exact=True)[::-1]
    if round_punch:
        plan, tri = plan_mesh(a, W, fine_mm, growth, quarter, fine_radius_mm)
        pts = np.vstack([np.column_stack([plan[:, 0], np.full(len(plan), y), plan[:, 1]]) for y in ys])
        cells = _prisms_to_tets(tri, len(ys) - 1, len(plan))
        lo = 0.0 if quarter else -W
        regions = {f"{c}{e}": np.isclose(pts[:, i], v, atol=1e-9 * W)
                   for i, c in ((0, "x"), (2, "z")) for e, v in (("min", lo), ("max", W))}
        regions["ymin"], regions["ymax"] = np.isclose(pts[:, 1], -D), np.isclose(pts[:, 1], 0.0)
    else:
        fine_radius = FINE_RADII * a if fine_radius_mm is None else fine_radius_mm
        xs = fine_then_growing(h, fine_radius, growth, W, exact=True)
        if not quarter:
            xs = np.r_[-xs[:0:-1], xs]
        pts, cells, regions = box(xs, ys, xs)
    named = {"top": regions["ymax"], "bottom": regions["ymin"]}
    prescribed = {"bottom": 0.0}
    if quarter:
        named |= {"symx": regions["xmin"], "symz": regions["zmin"]}
        prescribed |= {"symx": (0.0, None, None), "symz": (None, None, 0.0)}
        outer = {"sidex": ("xmax", (0.0, None, None)), "sidez": ("zmax", (None, None, 0.0))}
    else:
        outer = {"sidex0": ("xmin", (0.0, None, None)), "sidex": ("xmax", (0.0, None, None)),
                 "sidez0": ("zmin", (None, None, 0.0)), "sidez": ("zmax", (None, None, 0.0))}
    for name, (face, roller) in outer.items():
        named[name] = regions[face]
        if sides != "free":
            prescribed[name] = 0.0 if sides == "held" else roller
    model = Model(pts, cells, np.ones(len(cells), int), named, material=[float(E_MPa)], nu=nu)
    block = HalfSpaceBlock(model, None, "top", a, 4 if quarter else 1, prescribed)
    sn = model.surface_nodes("top")
    under = sn.nodes[reach(sn.x, block.punch(), np.zeros((1, 3)), 0.0, margin_mm=1e-9)]
    block.system = model.system(prescribed, condense=(under, APPROACH))
    return block
