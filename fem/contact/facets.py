"""The contact surface's facets: the area each node carries, the contact pressure recovered from
nodal forces (facet-averaged: P2 node-to-surface contact loads midside nodes about twice as much as
vertices), and which nodes neighbour each other (the ring a node-counted contact area steps by).

    facets, shares = fe_facets(model, "volar", model.surface_nodes("volar"))
    pressure_MPa = smoothed_pressure(force_N, facets, shares)
    peak_MPa = averaged_peak_pressure(force_N, points_mm, PEAK_PRESSURE_RADIUS_MM)   # mesh-converged
    pairs = node_pairs(facets, points_mm)
"""
from __future__ import annotations

import hashlib

import numpy as np
from scipy.spatial import cKDTree


def facet_shares(facets, facet_area, dim) -> np.ndarray:
    """(k, n_per_facet) share of each facet's area given to each of its nodes.

    facets: (k, n) node indices (vertices first, then midside nodes); facet_area: (k,) mm^2 (mm
    in 2D). P2 shares as `fem.core.model.Model.surface_nodes` (the facet cut into its linear
    sub-facets): 3D 1/12 per vertex and 1/4 per edge node, 2D 1/4 and 1/2; P1: equal shares.
    """
    n = facets.shape[1]
    if n == dim:
        w = np.full(n, 1.0 / n)
    else:
        w = np.array([1 / 12] * 3 + [1 / 4] * 3) if dim == 3 else np.array([1 / 4, 1 / 4, 1 / 2])
    return np.outer(facet_area, w)


def smoothed_pressure(force_N, facets, shares) -> np.ndarray:
    """(m,) contact pressure [MPa] recovered from nodal forces (m,) on facets (k, n) with area
    shares (k, n): each node's force is spread over its facets in proportion to their shares,
    giving a mean pressure per facet; a node's pressure is the share-weighted mean of its facets.
    Exact for uniform pressure whatever the split of force between vertex and midside nodes
    (node-to-surface contact on P2 loads midside nodes about twice as much as vertices)."""
    area = np.bincount(facets.ravel(), shares.ravel(), minlength=len(force_N))
    with np.errstate(divide="ignore", invalid="ignore"):
        per_area = np.where(area > 0, force_N / area, 0.0)
    p_facet = (per_area[facets] * shares).sum(axis=1) / shares.sum(axis=1)
    num = np.bincount(facets.ravel(), (shares * p_facet[:, None]).ravel(), minlength=len(force_N))
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(area > 0, num / area, 0.0)


def fe_facets(model, region: str, sn) -> tuple[np.ndarray, np.ndarray]:
    """((k, n) candidate-local node indices, (k, n) area shares) of the facets of `region` of a
    `fem.core.model.Model`, whose candidate nodes are `sn` (`Model.surface_nodes(region)`): the
    `facets` argument of ContactModel."""
    mesh, fids = model.mesh, model.region_facets(region)
    fv = mesh.facets[:, fids]
    mids = mesh.f2e[:, fids] if model.dim == 3 else fids[None]
    facets = np.searchsorted(sn.nodes, np.vstack([fv, mids + mesh.nvertices]).T)
    x = mesh.p[:, fv]
    if model.dim == 3:
        size = 0.5 * np.linalg.norm(np.cross((x[:, 1] - x[:, 0]).T, (x[:, 2] - x[:, 0]).T), axis=1)
    else:
        size = np.linalg.norm(x[:, 1] - x[:, 0], axis=0)
    return facets, facet_shares(facets, size, model.dim)


EDGES = np.array([(0, 1), (1, 2), (0, 2)])
"""The edges of a triangle by its vertices (0, 1, 2)."""


def midside_edges(facets, points_mm) -> np.ndarray:
    """(k, 3) the EDGES row each midside node of the P2 triangles facets (k, 6) (vertices, then
    midside nodes in any order; indices into points_mm (m, 3)) lies on, matched by position."""
    x = np.asarray(points_mm, float)[np.asarray(facets)]
    mid = 0.5 * (x[:, EDGES[:, 0]] + x[:, EDGES[:, 1]])                                  # (k, 3, 3)
    return np.argmin(np.linalg.norm(x[:, 3:, None] - mid[:, None], axis=-1), axis=2)


def node_pairs(facets, points_mm) -> np.ndarray:
    """(p, 2) node pairs (indices into points_mm (m, dim)) that share an edge of a linear sub-facet
    of the facets (k, n): P2, a vertex with the midside nodes of its edges and the midside nodes of
    one facet with each other (a 3D facet's midside nodes matched to their edges by position); P1,
    the facet's vertices. Each pair once, sorted."""
    facets = np.asarray(facets)
    k, n = facets.shape
    dim = np.asarray(points_mm).shape[1]
    if n == dim:                                               # P1: the vertices pairwise
        pairs = np.vstack([facets[:, [i, j]] for i in range(n) for j in range(i + 1, n)])
    elif dim == 2:                                             # (v0, v1, m): v0-m, m-v1
        pairs = np.vstack([facets[:, [0, 2]], facets[:, [2, 1]]])
    else:                                                      # (v0, v1, v2, three midside nodes)
        on = midside_edges(facets, points_mm)                  # (k, 3): the edge of each
        rows = np.arange(k)
        pairs = [facets[:, [3 + j, 3 + (j + 1) % 3]] for j in range(3)]             # the midside ring
        for j in range(3):
            a, b = EDGES[on[:, j]].T
            pairs += [np.column_stack([facets[rows, a], facets[:, 3 + j]]),
                      np.column_stack([facets[rows, b], facets[:, 3 + j]])]
        pairs = np.vstack(pairs)
    return np.unique(np.sort(pairs, axis=1), axis=0)


def edge_area_mm2(active, area_mm2, pairs) -> float:
    """Tributary area [mm^2; mm in 2D] of a contact's outer ring: the nodes carrying force (active
    (m,) bool) next to one that does not, neighbours by `node_pairs` (p, 2); area_mm2 (m,) the
    tributary areas. A node-counted contact area (and a 2D contact width) moves in steps of about
    this as the edge crosses the next ring of nodes, so it cannot resolve a change smaller than it."""
    active = np.asarray(active, bool)
    mixed = pairs[active[pairs[:, 0]] != active[pairs[:, 1]]]
    edge = np.zeros(len(active), bool)
    edge[mixed.ravel()] = True
    return float(np.asarray(area_mm2)[edge & active].sum())


PEAK_PRESSURE_RADIUS_MM = 1.0
"""Radius of the bump over which the step tables' `peak_pressure_MPa` averages the contact pressure
(`averaged_peak_pressure`; its half-maximum width is this radius, the spacing of the receptor
grid). Measured (docs/benchmarks.md, "Fingertip convergence"): over this radius the peak's changes
shrink with every refinement from the default sizes on, in 2D and 3D, while the nodal peak
(`max_pressure_MPa`) keeps moving by up to 0.5 % (2D) and 2-3 % (3D); a smaller radius is
meaningful only where elements are at most half of it (0.1 mm: 2D sizes of 0.0625 mm and finer)."""


class AveragedPeakPressure:
    """The largest contact pressure [MPa] averaged over a stated radius, for nodal forces on fixed
    points_mm (m, dim) [mm]: the forces (m,) [N; N/mm in 2D] weighted by the bump
    w(r) = cos^2(pi r / (2 radius_mm)) for r < radius_mm around each node that carries force,
    divided by the bump's integral (2D: radius_mm; 3D: radius_mm^2 (pi / 2 - 2 / pi)), the maximum
    over those nodes. Exact for a uniform pressure up to the nodal quadrature of the bump,
    O((h / radius_mm)^2) for elements of size h; unlike the nodal peak of `smoothed_pressure`, it
    converges under mesh refinement once h is well below radius_mm (the split of P2
    node-to-surface forces between vertex and midside nodes carries a first-order error that a
    node's own pressure keeps; docs/benchmarks.md). The weights are built once (a sparse (m, m)
    matrix), so each call is one sparse product: a run's steps share them.

        peak = AveragedPeakPressure(points_mm, PEAK_PRESSURE_RADIUS_MM)
        peak(force_N)                       # MPa; 0 without force
    """

    def __init__(self, points_mm, radius_mm: float):
        x = np.asarray(points_mm, float)
        tree = cKDTree(x)
        w = tree.sparse_distance_matrix(tree, radius_mm, output_type="coo_matrix").tocsr()
        w.data = np.cos(0.5 * np.pi * w.data / radius_mm) ** 2
        w.setdiag(1.0)                       # each node's own force, at distance 0
        self.weights = w
        self.area = radius_mm if x.shape[1] == 2 else radius_mm ** 2 * (0.5 * np.pi - 2.0 / np.pi)

    def __call__(self, force_N) -> float:
        f = np.asarray(force_N, float)
        centres = np.flatnonzero(f > 0)
        if not centres.size:
            return 0.0
        return float((self.weights[centres] @ f).max() / self.area)


_AVERAGERS: dict = {}
"""AveragedPeakPressure per (digest of the points, their shape, radius): the last few surfaces."""


def averaged_peak_pressure(force_N, points_mm, radius_mm: float) -> float:
    """`AveragedPeakPressure(points_mm, radius_mm)(force_N)` [MPa], its weights kept for the next
    call on the same points (every step of a run, every answer of the explorer: building them costs
    about 30 ms on 7,000 candidates, a call 0.1 ms)."""
    x = np.ascontiguousarray(points_mm, float)
    key = (hashlib.blake2b(x.tobytes(), digest_size=16).digest(), x.shape, float(radius_mm))
    averager = _AVERAGERS.get(key)
    if averager is None:
        if len(_AVERAGERS) >= 4:
            _AVERAGERS.pop(next(iter(_AVERAGERS)))
        averager = _AVERAGERS[key] = AveragedPeakPressure(x, radius_mm)
    return averager(force_N)
