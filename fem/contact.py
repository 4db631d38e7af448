"""Frictionless contact of rigid indentors with a linear elastic body, by condensed compliance.

Small strain, linear elasticity, frictionless: the solution depends only on the final indentor
position (no path dependence), so depth increments are outputs and warm starts, not a need.

Candidate surface nodes i = 1..m (points x_i, tributary areas A_i) carry normal contact forces
f_i >= 0 along the approach direction a. The displacement of node j along a is w_j = sum_i C_ji f_i
with the compliance C = B^T K^-1 B (B: unit loads along a at the candidate nodes), symmetric
positive definite. With the indentor tip travelled t along a, the gap after deformation is

    g_j = standoff_j - t + w_j >= -tol,   f_j >= 0,   f_j g_j = 0           (an LCP in f)

solved by block principal pivoting (Judice and Pires 1994; Murty's single-pivot rule as the
finite-termination backup), which only needs the compliance columns of the nodes it tries as
active. When the system was factorised with the candidates condensed along the approach
(`Model.system(condense=(nodes, a))`, as `open_model` does), C is the inverse of their Schur
complement, all of it at once with no solves (`CondensedCompliance`); otherwise its columns are
computed lazily with the factorised stiffness, many right-hand sides at once, and cached
(`FactorCompliance`). Either way sweeps and depth or force iterations reuse them. Candidates held
along the approach (zero compliance) never carry force; an indentor that would push one is an
error. Every solve reports its KKT residuals (penetration, tensile force, complementarity).

Contact pressure is recovered from the nodal forces: nodal force / tributary area, averaged over
each surface facet and back to the nodes (`smoothed_pressure`) when the facets are known, plain
f_i / A_i otherwise. Contact area is the sum of the tributary areas of the nodes carrying force
(node-based; in 2D it is the contact width per unit length).
Quantities at other points (receptor strains, deflections) are an observation matrix O times the
displacement. With lazy columns their response is cached with each column (a small matrix times
the contact forces per indentation); with a condensed compliance they take one solve per
indentation, deferred until a result's `observed` is read and then done for every waiting
indentation together, 64 right-hand sides per solve.

P2 meshes: every trace node (vertices and edge midpoints) is a contact node with the solver's
tributary areas. Node-to-surface constraints on P2 give accurate force, contact size and
deflection (Hertz within 3 %, tests/test_contact_fe.py) but nodal forces alternate between vertex
and midside nodes (about 1 : 2 against a consistent load), so raw f_i / A_i overstates the peak
pressure by about a third: hence the facet-averaged pressure.

    model, system, region, info = open_model("out/cyl8")          # fem.solver Model, factorised
    cm = ContactModel.from_fe(model, system, region, observe=model.strain_operator(points))
    res = cm.indent(indentor, depth_mm=1.0)             # or force_N=0.2, equal_force=True
    res.total_force_N, res.contact_area_mm2, res.max_pressure_MPa, res.kkt, res.observed
    cm.sweep(indentor, offsets_mm, force_N=0.2)         # one small LCP per position
    run_scene("out/cyl8", "out/cyl8/indent_x", load_scene("scenes/bars.toml"))   # files

Any other elastic body works through `ContactModel(points, areas, compliance_for)` with a
`Compliance` (e.g. `MatrixCompliance` for an analytic half-space).
"""
from __future__ import annotations

import contextlib
import functools
import sys
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from common.errors import InputError

GAP_TOL_MM = 1e-8
"""Allowed penetration after deformation (mm) and the pivoting threshold on the gap."""
FORCE_RTOL = 1e-6
"""Relative tolerance on prescribed forces."""
MAX_DEPTH_MM = 5.0
SERIAL_BLAS_BELOW = 1500
"""Active sets smaller than this are factorised on one BLAS thread (measured: an 843-node Cholesky
takes 0.013 s on one thread and 0.1-1.7 s on two when the other core is busy)."""
CONDENSE_MAX_NODES = 8000
"""Largest candidate set whose dense compliance `open_model` stores (8000 nodes: 0.5 GB, k^3 flops)."""


# --------------------------------------------------------------------------- facets and pressure
def facet_shares(facets, facet_area, dim) -> np.ndarray:
    """(k, n_per_facet) share of each facet's area given to each of its nodes.

    facets: (k, n) node indices (vertices first, then midside nodes); facet_area: (k,) mm^2 (mm
    in 2D). P2 shares as `fem.solver.Model.surface_nodes` (the facet cut into its linear
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


# --------------------------------------------------------------------------- compliance
class Compliance:
    """Cached compliance columns: C[:, j] (m,) and observed response O K^-1 B e_j (r,).

    Subclasses implement `_compute(idx) -> (m + r, len(idx))`.
    """

    def __init__(self, m: int, r: int):
        self.m, self.r = m, r
        self.held = np.zeros(m, bool)       # nodes that cannot move along the approach (zero compliance)
        self.reach = np.ones(m, bool)       # nodes whose compliance is available (see CondensedCompliance)
        self._slot = np.full(m, -1)
        self._store = np.empty((m + r, 0))
        self.computed = 0

    def _ensure(self, idx):
        missing = np.unique(idx[self._slot[idx] < 0])
        if missing.size:
            new = self._compute(missing)
            start = self.computed
            if start + missing.size > self._store.shape[1]:
                cap = max(2 * self._store.shape[1], start + missing.size, 16)
                grown = np.empty((self.m + self.r, cap))
                grown[:, :start] = self._store[:, :start]
                self._store = grown
            self._store[:, start:start + missing.size] = new
            self._slot[missing] = np.arange(start, start + missing.size)
            self.computed += missing.size

    def columns(self, idx) -> np.ndarray:
        """(m, k) compliance columns (mm/N) of candidate nodes idx."""
        idx = np.asarray(idx, int)
        self._ensure(idx)
        return self._store[:self.m, self._slot[idx]]

    def block(self, rows, cols) -> np.ndarray:
        """(len(rows), len(cols)) compliance (mm/N) between candidate nodes."""
        return self.columns(cols)[np.asarray(rows, int)]

    def observed(self, idx) -> np.ndarray:
        """(r, k) observed response per unit force at candidate nodes idx."""
        idx = np.asarray(idx, int)
        self._ensure(idx)
        return self._store[self.m:, self._slot[idx]]

    def observe(self, force_N) -> np.ndarray:
        """(r,) or (r, k) observed response to nodal contact forces (m,) or (m, k): cached
        columns times the forces."""
        force_N = np.asarray(force_N, float)
        act = np.flatnonzero(np.any(force_N.reshape(self.m, -1) != 0, axis=1))
        if not act.size:
            return np.zeros((self.r,) + force_N.shape[1:])
        return self.observed(act) @ force_N[act]


class MatrixCompliance(Compliance):
    """A given dense compliance (m, m) and optional observation response (r, m): analytic models."""

    def __init__(self, C, observed=None):
        C = np.asarray(C, float)
        R = np.zeros((0, len(C))) if observed is None else np.asarray(observed, float)
        super().__init__(len(C), len(R))
        self._full = np.vstack([C, R])
        self.held = np.diag(C) == 0

    def _compute(self, idx):
        return self._full[:, idx]


class FactorCompliance(Compliance):
    """Compliance from a factorised stiffness; columns are computed `chunk` right-hand sides at a time.

    solve: callable (n_dofs, k) load -> (n_dofs, k) displacement (the factorised, constrained
    system); n_dofs: its size; dofs: (m, dim) DOF index of each candidate node's components; direction: (dim,)
    unit force direction (3,) (its x, y part in 2D); observe: optional sparse (r, n_dofs) observation operator;
    fixed: optional constrained DOF indices (nodes held along the direction are marked `held`).
    """

    def __init__(self, solve, n_dofs: int, dofs, direction, observe=None, chunk: int = 64, fixed=None):
        dofs = np.asarray(dofs)
        m, dim = dofs.shape
        if dim == 2 and abs(direction[2]) > 1e-12:
            raise InputError("a 2D model can only be indented within its x-y plane: use incline 0")
        rows = dofs.ravel()
        cols = np.repeat(np.arange(m), dim)
        vals = np.tile(np.asarray(direction, float)[:dim], m)
        self.n_dofs = n_dofs
        self.B = sp.csc_matrix((vals, (rows, cols)), shape=(self.n_dofs, m))
        O = sp.csr_matrix((0, self.n_dofs)) if observe is None else sp.csr_matrix(observe)
        self.O = sp.vstack([self.B.T, O]).tocsr()
        super().__init__(m, O.shape[0])
        self.solve, self.chunk = solve, chunk
        if fixed is not None:
            moves = np.abs(np.asarray(direction, float)[:dim]) > 0
            self.held = np.all(np.isin(dofs, fixed) | ~moves, axis=1)

    def _compute(self, idx):
        return self._respond(self.B[:, idx])

    def _respond(self, loads) -> np.ndarray:
        """(m + r, k) O K^-1 loads for sparse loads (n_dofs, k) [N], `chunk` columns per solve
        (only a chunk is ever dense)."""
        loads = sp.csc_matrix(loads)
        out = np.empty((self.m + self.r, loads.shape[1]))
        for s in range(0, loads.shape[1], self.chunk):
            u = self.solve(np.asfortranarray(loads[:, s:s + self.chunk].toarray()))
            out[:, s:s + self.chunk] = self.O @ np.asarray(u).reshape(self.n_dofs, -1)
        return out

    def displacement(self, force_N) -> np.ndarray:
        """(n_dofs,) full displacement field for nodal contact forces (m,): one solve."""
        return np.asarray(self.solve((self.B @ force_N)[:, None])).reshape(-1)


class CondensedCompliance(FactorCompliance):
    """The whole compliance at once from a system factorised with `condense=(nodes, approach)` on
    the candidates (`LinearSystem.compliance`: the inverse of their Schur complement, no solves);
    observations take one solve per indentation (in blocks, `ContactModel.observe_pending`)
    instead of cached columns. Arguments as FactorCompliance, plus the LinearSystem and the
    candidates' P2 node ids (m,).

    When only some candidates were condensed (`reach`, e.g. those a scene's indentors can touch),
    compliance rows of the others are NaN: they cannot carry force, and their deflection comes
    with the observation solve. Raises ValueError when none was condensed along the direction."""

    def __init__(self, system, nodes, dofs, direction, observe=None, chunk: int = 64):
        super().__init__(system.solve, system.model.ndof, dofs, direction, observe, chunk)
        self.reach = system.stored(nodes, direction)                # the same for -direction
        if not self.reach.any():
            raise ValueError("no candidate has a stored compliance along this direction")
        self._C = system.compliance(np.asarray(nodes)[self.reach], direction)
        self._row = np.cumsum(self.reach) - 1                       # candidate -> row of _C
        self.held = np.zeros(self.m, bool)
        self.held[self.reach] = np.diag(self._C) == 0

    def columns(self, idx) -> np.ndarray:
        idx = np.asarray(idx, int)
        if self.reach.all():
            return self._C[:, idx]
        out = np.full((self.m, len(idx)), np.nan)
        out[self.reach] = self._C[:, self._row[idx]]
        return out

    def block(self, rows, cols) -> np.ndarray:
        """As Compliance.block; C is symmetric, so whole rows are gathered (contiguous; 1.6 ms
        against 11 ms for np.ix_ on 1500 x 300 of a 2000 x 2000 block) and transposed (a view)."""
        return self._C[self._row[np.asarray(cols, int)]][:, self._row[np.asarray(rows, int)]].T

    def observed(self, idx) -> np.ndarray:
        raise NotImplementedError("a condensed compliance observes whole force vectors: use observe()")

    def response(self, force_N) -> tuple[np.ndarray, np.ndarray]:
        """((m, k) deflections of every candidate along the direction, (r, k) observed response) to
        nodal contact forces (m, k): one solve per force vector, `chunk` of them per call."""
        F = np.asarray(force_N, float).reshape(self.m, -1)
        out = self._respond(self.B @ sp.csc_matrix(F))
        return out[:self.m], out[self.m:]

    def observe(self, force_N) -> np.ndarray:
        """(r,) or (r, k) observed response to nodal contact forces (m,) or (m, k)."""
        if not self.r:
            return np.zeros((0,) + np.shape(force_N)[1:])
        return self.response(force_N)[1].reshape((self.r,) + np.shape(force_N)[1:])


class BlockedError(InputError):
    """The indentor would push surface nodes that are held fixed (no finite force can)."""


# --------------------------------------------------------------------------- LCP
@functools.cache
def _thread_controller():
    """threadpoolctl's view of the loaded BLAS libraries (scanning them costs ~6 ms: done once)."""
    from threadpoolctl import ThreadpoolController

    return ThreadpoolController()


def _blas_threads(limit):
    """Context limiting BLAS threads (None: no limit)."""
    return contextlib.nullcontext() if limit is None else _thread_controller().limit(limits=limit, user_api="blas")


@dataclass
class LCPSolution:
    force: np.ndarray        # (n,) f >= 0
    gap: np.ndarray          # (n,) q + C f
    active: np.ndarray       # (n,) bool, f carried
    factor: tuple | None     # Cholesky factor of C over the active set (cho_factor)
    iterations: int


def solve_lcp(columns, q, start=None, tol_mm: float = GAP_TOL_MM, max_iter: int = 500) -> LCPSolution:
    """Solve f >= 0, g = q + C f >= -tol, f g = 0 for symmetric positive definite C.

    columns: callable idx -> (n, k) columns of C; q: (n,) gaps without contact forces (mm);
    start: (n,) bool initial guess of the active set (default: q < 0), e.g. the previous
    solution's. Block principal pivoting
    with Murty's rule as backup: finite for P-matrices.
    """
    n = len(q)
    active = (q < 0) if start is None else start.copy()
    best, backup = n + 1, 3
    for it in range(1, max_iter + 1):
        idx = np.flatnonzero(active)
        f = np.zeros(n)
        factor = None
        if idx.size:
            cols = columns(idx)
            with _blas_threads(1 if idx.size < SERIAL_BLAS_BELOW else None):
                factor = sla.cho_factor(cols[idx], lower=True)
                f[idx] = sla.cho_solve(factor, -q[idx])
            g = q + cols @ f[idx]
        else:
            g = q.copy()
        ftol = 1e-12 * max(np.abs(f).max(), 1e-300)
        bad = (active & (f < -ftol)) | (~active & (g < -tol_mm))
        nbad = int(bad.sum())
        if nbad == 0:
            return LCPSolution(f, g, active, factor, it)
        if nbad < best:
            best, backup = nbad, 3
            active ^= bad
        elif backup > 0:
            backup -= 1
            active ^= bad
        else:
            j = np.flatnonzero(bad)[-1]
            active[j] = ~active[j]
    raise RuntimeError(f"contact LCP did not converge in {max_iter} pivots")


# --------------------------------------------------------------------------- results
@dataclass
class ContactResult:
    """One indentation. Arrays over the m candidate nodes unless said otherwise."""
    indentor_name: str
    depth_mm: np.ndarray            # (n_parts,) travel beyond first touch of each part
    travel_mm: np.ndarray           # (n_parts,) tip travel from the indentor origin
    force_N: np.ndarray             # (m,) nodal contact force (N; N/mm in 2D)
    _gap_mm: np.ndarray             # (m,) gap after deformation (inf outside the footprint): gap_mm
    _deflection_mm: np.ndarray      # (m,) displacement along the approach direction: deflection_mm
    part: np.ndarray                # (m,) index of the indentor part facing each node
    pressure_MPa: np.ndarray        # (m,) contact pressure (facet-averaged nodal force / area)
    area_mm2: np.ndarray            # (m,) tributary areas
    kkt: dict = field(default_factory=dict)
    _observed: np.ndarray | None = field(default=None, repr=False)
    _source: "ContactModel | None" = field(default=None, repr=False)
    _unseen: np.ndarray | None = field(default=None, repr=False)    # candidates outside the reach

    @property
    def gap_mm(self) -> np.ndarray:
        """(m,) gap after deformation [mm] (inf outside the indentor's footprint)."""
        if self._unseen is not None and self._source is not None:
            self._source.observe_pending()
        return self._gap_mm

    @property
    def deflection_mm(self) -> np.ndarray:
        """(m,) displacement along the approach direction [mm]."""
        if self._unseen is not None and self._source is not None:
            self._source.observe_pending()
        return self._deflection_mm

    @property
    def observed(self) -> np.ndarray:
        """(r,) observation operator applied to the displacement (e.g. receptor strains). Computed
        on first use, together with every other finished indentation of the same ContactModel
        still waiting for it (one block solve per 64 on a condensed compliance)."""
        if self._observed is None and self._source is not None:
            self._source.observe_pending()
        return self._observed

    @property
    def active(self) -> np.ndarray:
        return self.force_N > 0

    @property
    def total_force_N(self) -> float:
        return float(self.force_N.sum())

    @property
    def part_force_N(self) -> np.ndarray:
        return np.bincount(self.part, self.force_N, minlength=len(self.depth_mm))

    @property
    def contact_area_mm2(self) -> float:
        """Sum of tributary areas of the nodes carrying force (mm^2; contact width in mm in 2D)."""
        return float(self.area_mm2[self.active].sum())

    @property
    def max_pressure_MPa(self) -> float:
        return float(self.pressure_MPa.max(initial=0.0))


def _kkt(f, g, tol_mm):
    finite = np.isfinite(g)
    pen = float(max(0.0, -g[finite].min(initial=0.0)))
    tens = float(max(0.0, -f.min(initial=0.0)))
    comp = float(np.abs(f[finite] * g[finite]).max(initial=0.0))
    return {"penetration_mm": pen, "tensile_N": tens, "complementarity_Nmm": comp,
            "tolerance_mm": tol_mm, "ok": pen <= tol_mm and tens <= 1e-12 * max(f.max(initial=0), 1e-300)
            and comp <= tol_mm * max(f.max(initial=0), 1e-300)}


# --------------------------------------------------------------------------- model
class ContactModel:
    """Candidate contact nodes of one body and their cached compliance per approach direction.

    points_mm: (m, dim) undeformed candidate node positions (dim 2: plane strain in x-y);
    areas_mm2: (m,) tributary areas; compliance_for: callable direction (3,) -> Compliance (one
    per approach direction, cached here); facets: optional ((k, n) candidate-local node indices,
    (k, n) area shares) for the pressure recovery (`facet_shares`).
    """

    def __init__(self, points_mm, areas_mm2, compliance_for, tol_mm: float = GAP_TOL_MM, facets=None):
        self.points_mm = np.asarray(points_mm, float)
        self.areas_mm2 = np.asarray(areas_mm2, float)
        self.facets = facets
        self._compliance_for = compliance_for
        self._compliance = {}
        self.tol_mm = tol_mm
        self._warm = None
        self._pending = []           # (result, compliance) awaiting observations
        self._force_depth = 0.5      # first trial depth (mm) of force control; then the last one

    @classmethod
    def from_fe(cls, model, system, region: str, observe=None, chunk=64, **kw):
        """Contact on the nodes of `region` of a `fem.solver.Model`, with its factorised
        `LinearSystem` (constraints applied); observe: optional sparse (r, ndof) operator
        (e.g. `model.strain_operator(receptors)`) whose response is cached with the columns."""
        sn = model.surface_nodes(region)
        mesh, fids = model.mesh, model.region_facets(region)
        fv = mesh.facets[:, fids]
        mids = mesh.f2e[:, fids] if model.dim == 3 else fids[None]
        facets = np.searchsorted(sn.nodes, np.vstack([fv, mids + mesh.nvertices]).T)
        x = mesh.p[:, fv]
        if model.dim == 3:
            size = 0.5 * np.linalg.norm(np.cross((x[:, 1] - x[:, 0]).T, (x[:, 2] - x[:, 0]).T), axis=1)
        else:
            size = np.linalg.norm(x[:, 1] - x[:, 0], axis=0)
        def compliance_for(a):
            try:
                return CondensedCompliance(system, sn.nodes, sn.dofs, a, observe=observe, chunk=chunk)
            except ValueError:          # not condensed along a (or not these nodes): lazy columns
                return FactorCompliance(system.solve, model.ndof, sn.dofs, a, observe=observe, chunk=chunk,
                                        fixed=system.fixed)
        return cls(sn.x, sn.area, compliance_for, facets=(facets, facet_shares(facets, size, model.dim)), **kw)

    @classmethod
    def from_solver(cls, solve, n_dofs, points_mm, dofs, areas_mm2, observe=None, chunk=64, **kw):
        """Model on a factorised FE system (see FactorCompliance for the arguments)."""
        return cls(points_mm, areas_mm2,
                   lambda a: FactorCompliance(solve, n_dofs, dofs, a, observe=observe, chunk=chunk), **kw)

    def compliance(self, direction) -> Compliance:
        key = tuple(np.round(direction, 12))
        if key not in self._compliance:
            self._compliance[key] = self._compliance_for(np.asarray(direction, float))
        return self._compliance[key]

    def first_touch_mm(self, indentor) -> np.ndarray:
        """(n_parts,) travel at which each part first touches the undeformed candidate surface."""
        return first_touch(self.points_mm, indentor)[1]

    def solve_travel(self, indentor, travel_mm, warm=None) -> tuple[ContactResult, LCPSolution, np.ndarray]:
        """Contact at given tip travels (n_parts,) mm. Returns (result, lcp, candidate subset)."""
        travel = np.broadcast_to(np.asarray(travel_mm, float), (indentor.n_parts,))
        comp = self.compliance(indentor.approach)
        s = indentor.part_standoff(self.points_mm) - travel
        part = np.argmin(s, axis=1)
        gap0 = s[np.arange(len(s)), part]
        sub = np.flatnonzero(np.isfinite(gap0))
        blocked = sub[comp.held[sub] & (gap0[sub] < -self.tol_mm)]
        if blocked.size:
            x = np.round(self.points_mm[blocked[np.argmin(gap0[blocked])]], 2).tolist()
            raise BlockedError(f"indentor {indentor.name} would push {blocked.size} surface nodes that are held "
                               f"fixed (the deepest at {x} mm): it reaches the model's fixed boundary (nail or "
                               f"proximal cut); use a smaller depth or indentor, or move it away from there")
        sub = sub[~comp.held[sub]]
        far = sub[~comp.reach[sub]]
        if far.size and gap0[far].min() < -self.tol_mm:
            x = np.round(self.points_mm[far[np.argmin(gap0[far])]], 2).tolist()
            raise InputError(f"indentor {indentor.name} reaches surface nodes (the deepest at {x} mm) outside "
                             f"the candidates condensed when the model was factorised: factorise with "
                             f"candidates covering this indentation (fem.contact.reach)")
        sub = sub[comp.reach[sub]]
        q = gap0[sub]
        start = warm[sub] if warm is not None and warm[sub].any() else q < min(0.0, 0.5 * q.min(initial=0))
        lcp = solve_lcp(lambda i: comp.block(sub, sub[i]), q, start, self.tol_mm)
        m = len(self.points_mm)
        f = np.zeros(m)
        f[sub] = lcp.force
        act = sub[lcp.active]
        w = comp.columns(act) @ f[act] if act.size else np.zeros(m)
        unseen = np.flatnonzero(np.isnan(w))            # outside the reach: with the observation solve
        g = gap0 + np.where(np.isnan(w), 0.0, w)
        if self.facets is not None:
            pressure = smoothed_pressure(f, *self.facets)
        else:
            with np.errstate(divide="ignore", invalid="ignore"):
                pressure = np.where(f > 0, f / self.areas_mm2, 0.0)
        t0 = self.first_touch_mm(indentor)
        res = ContactResult(indentor.name, travel - t0, travel.copy(), f, g, w, part, pressure,
                            self.areas_mm2, _kkt(f[sub], g[sub], self.tol_mm))
        res.kkt["iterations"] = lcp.iterations
        res._unseen = unseen if unseen.size else None
        return res, lcp, sub

    def indent(self, indentor, depth_mm=None, force_N=None, equal_force=False,
               max_depth_mm: float = MAX_DEPTH_MM) -> ContactResult:
        """One indentation at a prescribed depth (mm beyond first touch; all parts move together)
        or a prescribed total force (N; N/mm in 2D). equal_force: every part (two-point loads)
        carries force_N on its own, each at its own depth."""
        if (depth_mm is None) == (force_N is None):
            raise InputError("give either a depth (mm) or a force (N), not both")
        t0 = self.first_touch_mm(indentor)
        if depth_mm is not None:
            if depth_mm < 0:
                raise InputError(f"depth must be >= 0 mm, got {depth_mm}")
            res, lcp, sub = self.solve_travel(indentor, t0.min() + depth_mm, self._warm)
            return self._finish(res, indentor)
        return self._force(indentor, float(force_N), equal_force, max_depth_mm, t0)

    def indent_depths(self, indentor, depths_mm) -> list[ContactResult]:
        """Increasing depths (the thesis increments, e.g. 0.5, 1.0, ... mm), warm-started."""
        return [self.indent(indentor, depth_mm=d) for d in depths_mm]

    def sweep(self, indentor, offsets_mm, **load) -> list[ContactResult]:
        """The same indentor moved by each offset (k, 3) mm and indented with `load`
        (depth_mm=... or force_N=..., equal_force=...): one condensed problem per position."""
        out = []
        for off in np.atleast_2d(offsets_mm):
            moved = indentor.shifted(off)
            try:
                out.append(self.indent(moved, **load))
            except InputError as exc:
                raise InputError(f"sweep position {np.round(off, 4).tolist()} mm: {exc}") from None
        return out

    def _finish(self, res, indentor) -> ContactResult:
        """Warm start for the next indentation; the result's observations are left pending."""
        self._warm = res.force_N > 0
        res._source = self
        self._pending.append((res, self.compliance(indentor.approach)))
        return res

    def observe_pending(self) -> None:
        """Observations of every finished indentation not observed yet, in blocks per compliance."""
        pending, self._pending = self._pending, []
        for comp in {id(c): c for _, c in pending}.values():
            group = [r for r, c in pending if c is comp]
            F = np.stack([r.force_N for r in group], axis=1)
            if comp.reach.all():
                obs = comp.observe(F)
            else:
                defl, obs = comp.response(F)
            for j, r in enumerate(group):
                r._observed, r._source = obs[:, j], None
                if r._unseen is not None:
                    rows, r._unseen = r._unseen, None
                    r._deflection_mm[rows] = defl[rows, j]
                    r._gap_mm[rows] += defl[rows, j]
                    if r._gap_mm[rows].min() < -self.tol_mm:
                        x = np.round(self.points_mm[rows[np.argmin(r._gap_mm[rows])]], 2).tolist()
                        raise InputError(f"indentor {r.indentor_name}: the skin touched it at {x} mm, outside the "
                                         f"candidates condensed when the model was factorised: factorise with "
                                         f"a larger reach margin (fem.contact.reach)")

    def _force(self, indentor, target, equal_force, max_depth_mm, t0):
        """Newton on the depth(s) with the exact Jacobian of the current active set, safeguarded:
        each step at most doubles or halves the depth, and (one unknown) stays inside the
        bracket of depths known to give too little / too much force. Deep trial depths are
        avoided because with lazy columns every newly touching node costs one compliance column;
        a trial depth that would push held nodes counts as too deep."""
        if not target > 0:
            raise InputError(f"force must be positive, got {target} N")
        n = indentor.n_parts if equal_force else 1
        base = t0[:n] if equal_force else np.array([t0.min()])
        travels = (lambda d: base + d) if equal_force else (lambda d: np.full(indentor.n_parts, base[0] + d[0]))
        depth = np.full(n, min(self._force_depth, max_depth_mm))
        lo, hi = np.zeros(n), np.full(n, np.inf)
        warm = self._warm
        for it in range(1, 101):
            try:
                res, lcp, sub = self.solve_travel(indentor, travels(depth), warm)
            except BlockedError as exc:         # too deep: held nodes reached; bisect below
                if n > 1 or depth[0] - lo[0] < 1e-9:
                    raise BlockedError(f"force {target} N: {exc}") from None
                hi = np.minimum(hi, depth)
                depth = 0.5 * (lo + hi)
                continue
            warm = res.force_N > 0
            err = (res.part_force_N if equal_force else np.array([res.total_force_N])) - target
            if np.all(np.abs(err) <= FORCE_RTOL * target):
                self._force_depth = float(depth.mean())
                res.kkt["force_iterations"] = it
                return self._finish(res, indentor)
            if np.any((depth >= max_depth_mm) & (err < 0)):
                raise InputError(f"force {target} N is not reached within {max_depth_mm} mm depth "
                                 f"(force there {np.round(err + target, 6).tolist()} N): lower the force "
                                 f"or raise the depth limit")
            lo = np.where(err < 0, np.maximum(lo, depth), lo)
            hi = np.where(err > 0, np.minimum(hi, depth), hi)
            J = self._force_jacobian(lcp, res.part[sub], n)
            try:
                new = depth - np.linalg.solve(J, err)
            except np.linalg.LinAlgError:
                new = np.full(n, np.nan)
            new = np.where(np.isfinite(new), new, 2 * depth)
            if n == 1 and not lo[0] < new[0] < hi[0]:
                new = 0.5 * (lo + np.minimum(hi, 2 * depth))
            depth = np.minimum(np.clip(new, 0.5 * depth, 2 * depth), max_depth_mm)
        raise RuntimeError(f"force control did not converge for {indentor.name}")

    @staticmethod
    def _force_jacobian(lcp, part, n):
        """(n, n) d(part force)/d(part travel) for the current active set: 1_k^T C_AA^-1 1_l."""
        J = np.zeros((n, n))
        if lcp.factor is None:
            return J
        pa = part[lcp.active] if n > 1 else np.zeros(lcp.active.sum(), int)
        ones = np.stack([(pa == k).astype(float) for k in range(n)], axis=1)
        sol = sla.cho_solve(lcp.factor, ones)
        return ones.T @ sol


# --------------------------------------------------------------------------- experiments on a model folder
EXPERIMENT_KEYS = {"name", "indentor", "orientation", "position_mm", "incline_deg", "approach",
                   "depth_mm", "force_N", "equal_force", "max_depth_mm", "sweep"}
SCENE_KEYS = {"material", "nu", "receptors", "output", "experiment"}
RECEPTOR_KEYS = {"depths_mm", "spacing_mm", "line", "measures"}
OUTPUT_KEYS = {"pvd", "plots"}


def parse_values(text) -> np.ndarray:
    """'a:b:step' (inclusive), 'v1,v2,...', a number or a list -> (n,) floats."""
    if isinstance(text, (int, float)):
        return np.array([float(text)])
    if isinstance(text, (list, tuple)):
        return np.asarray(text, float)
    try:
        if ":" in text:
            a, b, step = (float(t) for t in text.split(":"))
            if not step > 0 or b < a:
                raise ValueError
            return a + step * np.arange(int(np.floor((b - a) / step + 1e-9)) + 1)
        return np.array([float(t) for t in text.split(",")])
    except ValueError:
        raise InputError(f"bad value list '{text}': use start:stop:step (e.g. 0.5:3:0.5) or v1,v2,...") from None


def parse_sweep(text) -> tuple[int, np.ndarray]:
    """'x=-3:3:0.1' or 'z=...' -> (axis index, (k,) offsets in mm)."""
    axis, eq, values = str(text).partition("=")
    if not eq or axis.strip() not in ("x", "z"):
        raise InputError(f"bad sweep '{text}': use x=start:stop:step or z=start:stop:step (mm)")
    return {"x": 0, "z": 2}[axis.strip()], parse_values(values)


def load_scene(path) -> dict:
    """Read a TOML scene file; unknown keys are errors (a typo must not be silently ignored)."""
    import tomllib

    try:
        with open(path, "rb") as fh:
            scene = tomllib.load(fh)
    except (OSError, tomllib.TOMLDecodeError) as exc:
        raise InputError(f"cannot read scene '{path}': {exc}") from None
    _check_keys(scene, SCENE_KEYS, "scene")
    _check_keys(scene.get("receptors", {}), RECEPTOR_KEYS, "[receptors]")
    _check_keys(scene.get("output", {}), OUTPUT_KEYS, "[output]")
    if not scene.get("experiment"):
        raise InputError(f"scene '{path}' has no [[experiment]] table")
    for exp in scene["experiment"]:
        _check_keys(exp, EXPERIMENT_KEYS, "[[experiment]]")
    return scene


def _check_keys(table, allowed, where):
    unknown = set(table) - allowed
    if unknown:
        raise InputError(f"unknown key(s) {sorted(unknown)} in {where}; allowed: {sorted(allowed)}")


# The proximal cut is where the distal phalanx joins the rest of the finger, which the experiments
# hold still (thesis 2.2.2: hand restrained, no joint moves; 6.2.1: the ends' boundary conditions
# differ markedly and deformation fades faster proximally). Left free, the cut swung by 12.5 % of a
# 2 mm line load on the human preset (README "Indentation"). Only its core is held (layers 3-5,
# `proximal_core`): the skin goes on proximally, so indentors as long as the finger (bars and
# wedges along the axis, steps, large cylinders) press the cut's skin instead of a fixed rim.
HELD = {3: {"nail": 0.0, "support": (None, 0.0, None), "proximal_core": 0.0}, 2: {"fixed": 0.0}}
"""Constraints of a model folder per dimension: 3D nail and the proximal cut's core fixed, support
held along its normal; 2D `fixed` held (`held_regions` skips regions a mesh lacks)."""
SKIN_LAYERS = (1, 2)
"""Epidermis and dermis: their vertices on the proximal cut are not held (`held_regions`)."""
CONTACT_REGION = {3: "volar", 2: "surface"}
"""Contact candidate region of a model folder per dimension."""


def read_model(model_dir, material=None, nu=None):
    """(fem.solver.Model, model.json dict) of a model folder; material and nu default to model.json's."""
    import json
    from pathlib import Path

    from fem.solver import Model

    folder = Path(model_dir)
    if not (folder / "mesh.vtu").is_file():
        raise InputError(f"no mesh.vtu in '{model_dir}': run `pipeline.py mesh` first or give a model folder")
    info = json.loads((folder / "model.json").read_text()) if (folder / "model.json").is_file() else {}
    model = Model.from_mesh(folder / "mesh.vtu", material=material or info.get("material", "m33338"),
                            nu=info.get("nu", 0.48) if nu is None else nu)
    return model, info


def held_regions(model) -> dict:
    """`HELD` for the model's dimension, restricted to the regions its mesh has. Adds the region
    `proximal_core` to a 3D model with a `proximal` cut: the cut's vertices outside the skin."""
    if "proximal" in model.regions and "proximal_core" not in model.regions:
        skin = np.zeros(model.mesh.nvertices, bool)
        skin[model.mesh.t[:, np.isin(model.layer, SKIN_LAYERS)].ravel()] = True
        model.regions["proximal_core"] = model.regions["proximal"] & ~skin
    return {k: v for k, v in HELD[model.dim].items() if k in model.regions}


def approach_down(info) -> np.ndarray:
    """(3,) default approach of a model folder: minus its support's vertical_up (-y if none)."""
    return -np.asarray(info.get("regions", {}).get("support", {}).get("vertical_up", [0.0, 1.0, 0.0]), float)


def factorise(model, info, candidates=None, progress: bool = False):
    """LinearSystem of a model folder's model, held as `HELD` says, factorised with contact
    candidates condensed along `approach_down` when there are at most CONDENSE_MAX_NODES of them.
    candidates: P2 node ids (default: every node of the contact region), e.g. `reach` of the
    indentations to come: fewer condensed nodes factorise faster (PARDISO on the 284k-DOF human
    model, 2 cores: 52 s with all 6,913 volar nodes, 33 s with the 2,441 that C5 reaches at 3 mm,
    26 s with none). progress: say on stderr what is being factorised."""
    nodes = model.surface_nodes(CONTACT_REGION[model.dim]).nodes if candidates is None else candidates
    condense = (nodes, approach_down(info)) if 0 < len(nodes) <= CONDENSE_MAX_NODES else None
    if progress:
        print(f"factorising {model.ndof} DOFs" + (f" with {len(nodes)} contact candidates condensed"
              if condense else "") + " ...", file=sys.stderr, flush=True)
    return model.system(held_regions(model), condense=condense)


def open_model(model_dir, material=None, nu=None, progress: bool = False):
    """(fem.solver.Model, LinearSystem, contact region name, model.json dict) of a model folder,
    factorised with every contact candidate condensed (`factorise`)."""
    model, info = read_model(model_dir, material, nu)
    return model, factorise(model, info, progress=progress), CONTACT_REGION[model.dim], info


REACH_MARGIN_MM = 0.25
"""Allowance (mm) beyond an indentation's depth within which `reach` includes candidate nodes."""


def reach(points_mm, indentor, offsets_mm, depth_mm: float, margin_mm: float = REACH_MARGIN_MM) -> np.ndarray:
    """(m,) bool: candidate nodes (m, dim) mm that `indentor`, moved by any of the offsets (k, 3) mm
    and pushed up to depth_mm beyond each part's first touch, overlaps in the undeformed state
    (within margin_mm). Only these can carry force: on the fingertip models (monkey, cylinders
    C1-C8, bar, sphere, wedge, step, punch to 3 mm) no node outside the undeformed overlap touched
    (the skin around an indentor moves away from it), and ContactModel checks it on every result.
    Raises InputError when the indentor at some offset never touches the candidates."""
    mask = np.zeros(len(points_mm), bool)
    offsets_mm = np.atleast_2d(offsets_mm)
    for off in offsets_mm:
        try:
            s, t0 = first_touch(points_mm, indentor.shifted(off))
        except InputError as exc:
            raise InputError(f"sweep position {np.round(off, 4).tolist()} mm: {exc}" if len(offsets_mm) > 1
                             else str(exc)) from None
        mask |= np.any(s - t0 <= depth_mm + margin_mm, axis=1)
    return mask


def receptor_surface(model, sn) -> tuple[np.ndarray, np.ndarray]:
    """(positions (k, dim) mm, outward normals (k, dim)) of the contact-region nodes `sn` that may
    carry receptor sites: all but those on a 3D end cut. Below a node on the rim of a cut the
    receptors lie on the cut plane, which the mesh reproduces only within pytetwild's envelope
    (0.02 mm): with a 0.05 mm envelope one fell outside the mesh."""
    ends = [model.region_nodes(r) for r in ("proximal", "distal") if r in model.regions]
    keep = ~np.isin(sn.nodes, np.concatenate(ends)) if ends else np.ones(len(sn.nodes), bool)
    return sn.x[keep], sn.normal[keep]


def first_touch(points_mm, indentor) -> tuple[np.ndarray, np.ndarray]:
    """(standoff (m, n_parts) mm of each candidate point (m, dim) from each part along the approach,
    inf where it misses; (n_parts,) travel at which each part first touches). Raises InputError
    when a part touches none of them."""
    s = indentor.part_standoff(points_mm)
    t0 = s.min(axis=0)
    if not np.all(np.isfinite(t0)):
        raise InputError(f"indentor {indentor.name} at {np.round(indentor.origin_mm, 3).tolist()} mm "
                         f"never touches the finger surface: move it over the pad or change the approach")
    return s, t0


def top_point(points, place) -> int:
    """Index of the contact-region point (P, dim) highest against the approach of `place` (its
    "approach", else its "incline_deg"): where a plate would touch first."""
    from fem.indentors import approach_direction

    a = place.get("approach")
    a = approach_direction(place.get("incline_deg", 0.0)) if a is None else np.asarray(a, float)
    return int(np.argmax(points @ -a[:points.shape[1]]))


def scene_position(position, points, place) -> tuple:
    """A scene's position_mm: (x, z) or (x, y, z) mm as given, or "top": the `top_point` of the
    contact region (P, dim), e.g. the pad of a finger on an inclined support."""
    if isinstance(position, str) and position != "top":
        raise InputError(f'position_mm "{position}": give [x, z] in mm or "top"')
    if position != "top":
        return tuple(position)
    p = points[top_point(points, place)]
    return tuple(float(v) for v in p) if len(p) == 3 else (float(p[0]), 0.0)


def run_scene(model_dir, out_dir, scene: dict, progress: bool = True) -> str:
    """Run every [[experiment]] of a scene on a model folder; write CSV, PNG (and PVD) atomically
    into out_dir. Returns a text summary."""
    import time

    from fem.indentors import make_indentor
    from fem.receptors import DEFAULT_DEPTHS_MM, DEFAULT_MEASURES, ReceptorSampler, receptor_grid
    from common.staging import staged_output, write_json

    t_start = time.perf_counter()
    model, info = read_model(model_dir, scene.get("material"), scene.get("nu"))
    region = CONTACT_REGION[model.dim]
    sn = model.surface_nodes(region)
    middle_z = 0.5 * (sn.x[:, 2].min() + sn.x[:, 2].max()) if model.dim == 3 else 0.0
    plans, touched = [], np.zeros(len(sn.nodes), bool)
    for k, exp in enumerate(scene["experiment"]):
        name = str(exp.get("name", f"experiment{k + 1}"))
        place = {"orientation": exp.get("orientation", "parallel")}
        if "approach" in exp:
            place["approach"] = exp["approach"]
        elif "incline_deg" in exp:
            place["incline_deg"] = float(exp["incline_deg"])
        elif model.dim == 3:
            place["approach"] = approach_down(info)
        place["position_mm"] = scene_position(exp.get("position_mm", (0.0, middle_z)), sn.x, place)
        if exp.get("position_mm") == "top" and model.dim == 3:        # 2D models have no end cuts
            top = sn.nodes[top_point(sn.x, place)]
            cuts = [r for r in ("distal", "proximal") if r in model.regions and top in model.region_nodes(r)]
            if cuts:
                print(f"warning: experiment '{name}': the top point is on the rim of the {cuts[0]} cut, not "
                      "the pad; for an inclined finger mesh with --tip rounded", file=sys.stderr)
        ind = make_indentor(str(exp["indentor"]), **place)
        offsets = np.zeros((1, 3))
        if "sweep" in exp:
            axis, vals = parse_sweep(exp["sweep"])
            offsets = np.zeros((len(vals), 3))
            offsets[:, axis] = vals
        if ("depth_mm" in exp) == ("force_N" in exp):
            raise InputError(f"experiment '{name}': give depth_mm or force_N (one of them)")
        if "depth_mm" in exp:
            loads = [{"depth_mm": float(d)} for d in parse_values(exp["depth_mm"])]
            deepest = max(d["depth_mm"] for d in loads)
        else:
            loads = [{"force_N": float(exp["force_N"]), "equal_force": bool(exp.get("equal_force", False)),
                      "max_depth_mm": float(exp.get("max_depth_mm", MAX_DEPTH_MM))}]
            deepest = loads[0]["max_depth_mm"]
        touched |= reach(sn.x, ind, offsets, deepest)
        plans.append((name, exp, place, ind, offsets, loads))
    rc = scene.get("receptors", {})
    line = rc.get("line")
    if line is not None:
        axis = {"x": 0, "y": 1, "z": 2}.get(str(line[0]))
        try:
            value = 0.5 * (sn.x[:, axis].min() + sn.x[:, axis].max()) if line[1] == "middle" else float(line[1])
        except (ValueError, TypeError, IndexError):
            axis = None
        if axis is None or axis >= model.dim:
            raise InputError(f"bad receptor line {line}: use z=<mm> or z=middle (3D), x=<mm>")
        line = (axis, value)
    x, normal = receptor_surface(model, sn)
    grid = receptor_grid(x, normal, parse_values(rc.get("depths_mm", list(DEFAULT_DEPTHS_MM))),
                         float(rc.get("spacing_mm", 1.0)), line)
    sampler = ReceptorSampler(model, grid)
    measures = list(rc.get("measures", DEFAULT_MEASURES))
    system = factorise(model, info, sn.nodes[touched], progress)     # only what the scene can touch
    cm = ContactModel.from_fe(model, system, region, observe=sampler.operator)
    runs, records = [], []
    for name, exp, place, ind, offsets, loads in plans:
        t0 = time.perf_counter()
        steps = []
        for off in offsets:
            for load in loads:
                res = cm.sweep(ind, off[None], **load)[0] if "sweep" in exp else cm.indent(ind, **load)
                steps.append((off, res))
        runs.append((name, ind, steps, time.perf_counter() - t0))
        records.append(_experiment_record(name, exp, place, ind, offsets, loads, "sweep" in exp))
        if progress:
            print(f"{name}: {len(steps)} indentations in {runs[-1][3]:.2f} s", flush=True)
    out = scene.get("output", {})
    with staged_output(out_dir) as tmp:
        for name, ind, steps, _ in runs:
            _write_run(tmp, name, ind, steps, cm, sn, sampler, measures, model,
                       pvd=bool(out.get("pvd", len(steps) <= 20)), plots=bool(out.get("plots", True)))
        write_json(tmp / "run.json", _run_record(model_dir, model, info, rc, line, grid, measures, records))
    total = time.perf_counter() - t_start
    lines = [f"indentation results in {out_dir} ({total:.1f} s; model {model.ndof} DOFs, "
             f"{len(sn.nodes)} contact candidates, {len(grid.points_mm)} receptor points)"]
    for name, ind, steps, secs in runs:
        worst = max(r.kkt["penetration_mm"] for _, r in steps)
        lines.append(f"  {name}: {len(steps)} indentations, {secs:.2f} s, force "
                     f"{min(r.total_force_N for _, r in steps):.4g}-{max(r.total_force_N for _, r in steps):.4g} N, "
                     f"max penetration {worst:.1e} mm")
    return "\n".join(lines)


RUN_FORMAT = 1
"""Version of the run.json layout (raise it when a key changes meaning)."""


def _experiment_record(name, exp, place, ind, offsets, loads, sweep) -> dict:
    """run.json entry of one experiment: indentor (code, shapes, diameter where it has one),
    placement, sweep axis and offsets (mm), loading."""
    from dataclasses import asdict

    shapes = [{"shape": type(p).__name__, **{k: (None if v == np.inf else v) for k, v in asdict(p).items()}}
              for p in ind.parts]
    diameters = {p.get("diameter_mm") for p in shapes}
    if len(loads) and "force_N" in loads[0]:
        loading = {"force_N": loads[0]["force_N"], "equal_force": loads[0]["equal_force"],
                   "max_depth_mm": loads[0]["max_depth_mm"]}
    else:
        loading = {"depth_mm": [d["depth_mm"] for d in loads]}
    axis = parse_sweep(exp["sweep"])[0] if sweep else None
    return {"name": name, "indentor": str(exp["indentor"]), "shapes": shapes,
            "diameter_mm": diameters.pop() if len(diameters) == 1 else None,
            "orientation": place["orientation"], "position_mm": list(place["position_mm"]),
            "incline_deg": place.get("incline_deg"), "approach": ind.approach.tolist(),
            "length_axis": ind.e1.tolist(), "origin_mm": ind.origin_mm.tolist(),
            "sweep": None if axis is None else {"axis": "xyz"[axis], "offsets_mm": offsets[:, axis].tolist()},
            "loading": loading, "indentations": len(offsets) * len(loads),
            "files": [f"{name}.csv", f"{name}_surface.csv", f"{name}_receptors.csv"]}


def _run_record(model_dir, model, info, rc, line, grid, measures, experiments) -> dict:
    """run.json: what produced an indentation results folder (model, material, receptors, experiments)."""
    import hashlib
    from importlib import metadata
    from pathlib import Path

    folder = Path(model_dir).resolve()
    info_file = folder / "model.json"
    try:
        version = metadata.version("fingertip-fem")
    except metadata.PackageNotFoundError:
        version = None
    mat = model.material
    nus = set(mat.nu.values())
    return {"format": RUN_FORMAT, "package": "fingertip-fem", "version": version,
            "model": {"folder": str(folder), "dim": model.dim, "preset": info.get("preset"),
                      "model_json_sha256": hashlib.sha256(info_file.read_bytes()).hexdigest()
                      if info_file.is_file() else None,
                      "diameter_mm": info.get("params", {}).get("diameter_mm"), "dofs": int(model.ndof)},
            "material": mat.code, "E_MPa": {str(k): v for k, v in sorted(mat.E_MPa.items())},
            "nu": nus.pop() if len(nus) == 1 else {str(k): v for k, v in sorted(mat.nu.items())},
            "receptors": {"depths_mm": np.unique(grid.depth_mm).tolist(),
                          "spacing_mm": float(rc.get("spacing_mm", 1.0)),
                          "line": None if line is None else ["xyz"[line[0]], line[1]], "measures": list(measures),
                          "sites": len(grid.sites_mm), "points": len(grid.points_mm),
                          "site_column": "site: id of the surface site (row of sites_mm), the same in every "
                                         "step, position and experiment of this folder"},
            "experiments": experiments}


def _width_mm(res, ind, x, dim):
    if dim == 2:
        return res.contact_area_mm2
    v = (x[res.active] @ ind.e2) if res.active.any() else np.zeros(1)
    return float(v.max() - v.min())


def _write_run(folder, name, ind, steps, cm, sn, sampler, measures, model, pvd, plots):
    import csv

    x3 = np.zeros((len(sn.x), 3))
    x3[:, :model.dim] = sn.x
    rows, surf, rec = [], [], []
    for i, (off, r) in enumerate(steps):
        vals = sampler.measures(r.observed, measures)
        rows.append({"step": i, "offset_x_mm": off[0], "offset_z_mm": off[2],
                     "depth_mm": float(r.depth_mm.max()), "force_N": r.total_force_N,
                     **{f"force_part{k}_N": f for k, f in enumerate(r.part_force_N) if len(r.depth_mm) > 1},
                     "contact_area_mm2": r.contact_area_mm2, "contact_width_mm": _width_mm(r, ind, x3, model.dim),
                     "max_pressure_MPa": r.max_pressure_MPa, "penetration_mm": r.kkt["penetration_mm"],
                     "tensile_N": r.kkt["tensile_N"], "complementarity_Nmm": r.kkt["complementarity_Nmm"],
                     "kkt_ok": r.kkt["ok"]})
        for j in range(len(sn.x)):
            surf.append([i, *x3[j], r.deflection_mm[j], r.pressure_MPa[j], r.force_N[j]])
        pts = np.zeros((len(sampler.grid.points_mm), 3))
        pts[:, :model.dim] = sampler.grid.points_mm
        for j in range(len(pts)):
            rec.append([i, sampler.grid.site[j], *pts[j], sampler.grid.depth_mm[j], *(vals[m][j] for m in measures)])
    _csv(folder / f"{name}.csv", list(rows[0]), [list(r.values()) for r in rows], csv)
    _csv(folder / f"{name}_surface.csv", ["step", "x_mm", "y_mm", "z_mm", "deflection_mm", "pressure_MPa",
                                          "force_N"], surf, csv)
    _csv(folder / f"{name}_receptors.csv", ["step", "site", "x_mm", "y_mm", "z_mm", "depth_mm", *measures], rec, csv)
    if pvd:
        from fem.export import write_vtu

        comp = cm.compliance(ind.approach)
        names = []
        for i, (_, r) in enumerate(steps):
            names.append(f"{name}_{i:03d}.vtu")
            write_vtu(folder / names[-1], model.solution(comp.displacement(r.force_N)))
        entries = "\n".join(f'    <DataSet timestep="{i}" file="{n}"/>' for i, n in enumerate(names))
        (folder / f"{name}.pvd").write_text('<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1">\n'
                                            f"  <Collection>\n{entries}\n  </Collection>\n</VTKFile>\n")
    if plots:
        _plots(folder, name, ind, steps, sn, x3, sampler, measures, rows)


def _csv(path, header, rows, csv):
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(header)
        w.writerows([[f"{v:.9g}" if isinstance(v, float) else v for v in row] for row in rows])


def _plots(folder, name, ind, steps, sn, x3, sampler, measures, rows):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    sweep = len({tuple(o) for o, _ in steps}) > 1
    key = "offset_x_mm" if sweep and any(r["offset_x_mm"] for r in rows) else ("offset_z_mm" if sweep else "depth_mm")
    fig, ax = plt.subplots(1, 2, figsize=(10, 4))
    ax[0].plot([r[key] for r in rows], [r["force_N"] for r in rows], "o-")
    ax[0].set(xlabel=key, ylabel="force_N", title=f"{name}: force")
    ax[1].plot([r[key] for r in rows], [r["max_pressure_MPa"] for r in rows], "o-")
    ax[1].set(xlabel=key, ylabel="max_pressure_MPa", title="max contact pressure")
    fig.tight_layout()
    fig.savefig(folder / f"{name}_force.png", dpi=110)
    plt.close(fig)
    # deflection and pressure across the indentor (nodes near its centre line), last step(s)
    u = (x3 - ind.origin_mm) @ ind.e1
    v = (x3 - ind.origin_mm) @ ind.e2
    near = np.abs(u) <= max(0.5, np.sort(np.abs(u))[min(len(u) - 1, 50)])
    order = np.argsort(v[near])
    fig, ax = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    for i, (off, r) in enumerate(steps[-8:] if not sweep else steps[-1:]):
        ax[0].plot(v[near][order], -r.deflection_mm[near][order], label=f"{r.depth_mm.max():.2f} mm")
        ax[1].plot(v[near][order], r.pressure_MPa[near][order])
    ax[0].set(ylabel="surface displacement along approach, mm (down -)", title=f"{name}: surface profile")
    ax[0].legend(fontsize=7)
    ax[1].set(xlabel="position across the indentor, mm", ylabel="pressure_MPa")
    fig.tight_layout()
    fig.savefig(folder / f"{name}_profile.png", dpi=110)
    plt.close(fig)
    # receptor measures: profile across the pad (last step) or against the sweep position
    g = sampler.grid
    fig, axes = plt.subplots(len(measures), 1, figsize=(8, 2.2 * len(measures)), sharex=True, squeeze=False)
    site_x = np.pad(g.sites_mm, ((0, 0), (0, 3 - g.sites_mm.shape[1]))) - ind.origin_mm
    site_u, site_v = site_x @ ind.e1, site_x @ ind.e2
    # a pad grid in 3D: only the sites on the indentor's centre line (within 0.5 mm, or the nearest)
    on_line = np.abs(site_u) <= max(0.5, np.abs(site_u).min() + 1e-9)
    for m, a in zip(measures, axes[:, 0]):
        for d in np.unique(g.depth_mm):
            sel = (g.depth_mm == d) & on_line[g.site]
            if sweep:
                j = np.flatnonzero(sel)[np.argmin(np.abs(site_v[g.site[sel]]))]
                vals = [sampler.measures(r.observed, [m])[m][j] for _, r in steps]
                a.plot([r[key] for r in rows], vals, label=f"{d:g} mm")
            else:
                vals = sampler.measures(steps[-1][1].observed, [m])[m][sel]
                o = np.argsort(site_v[g.site[sel]])
                a.plot(site_v[g.site[sel]][o], vals[o], ".-", label=f"{d:g} mm")
        a.set_ylabel(m, fontsize=8)
        a.legend(fontsize=7)
    axes[-1, 0].set_xlabel(key if sweep else "receptor site across the indentor (on its centre line), mm")
    fig.tight_layout()
    fig.savefig(folder / f"{name}_receptors.png", dpi=110)
    plt.close(fig)
    if sn.x.shape[1] == 3:          # contact pressure map of the last indentation, seen along the approach
        r = steps[-1][1]
        fig, ax = plt.subplots(figsize=(6, 5))
        sc = ax.scatter(u, v, c=r.pressure_MPa, s=6, cmap="viridis")
        ax.set(xlabel="along the indentor, mm", ylabel="across the indentor, mm", aspect="equal",
               title=f"{name}: contact pressure, depth {r.depth_mm.max():.2f} mm")
        fig.colorbar(sc, label="pressure_MPa")
        fig.tight_layout()
        fig.savefig(folder / f"{name}_pressure.png", dpi=110)
        plt.close(fig)
