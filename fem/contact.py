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
active: they are computed lazily with the factorised stiffness, many right-hand sides at once,
and cached, so sweeps and depth or force iterations reuse them. Every solve reports its KKT
residuals (penetration, tensile force, complementarity).

Contact pressure is recovered from the nodal forces: nodal force / tributary area, averaged over
each surface facet and back to the nodes (`smoothed_pressure`) when the facets are known, plain
f_i / A_i otherwise. Contact area is the sum of the tributary areas of the nodes carrying force
(node-based; in 2D it is the contact width per unit length).
Quantities at other points (receptor strains, deflections) are an observation matrix O times the
displacement: their response to the contact forces is cached column by column too, so receptor
strains cost a small matrix times the contact forces per indentation.

P2 meshes: every trace node (vertices and edge midpoints) is a contact node with the solver's
tributary areas. Node-to-surface constraints on P2 give accurate force, contact size and
deflection (Hertz within 3 %, tests/test_contact_fe.py) but nodal forces alternate between vertex
and midside nodes (about 1 : 2 against a consistent load), so raw f_i / A_i overstates the peak
pressure by about a third: hence the facet-averaged pressure.

    model = ContactModel.from_solver(solve, n_dofs, points_mm, dofs, areas_mm2, observe=O)
    res = model.indent(indentor, depth_mm=1.0)          # or force_N=0.2, equal_force=True
    res.total_force_N, res.contact_area_mm2, res.kkt, res.observed
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from reconstruct.errors import InputError

GAP_TOL_MM = 1e-8
"""Allowed penetration after deformation (mm) and the pivoting threshold on the gap."""
FORCE_RTOL = 1e-6
"""Relative tolerance on prescribed forces."""
MAX_DEPTH_MM = 5.0


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

    def observed(self, idx) -> np.ndarray:
        """(r, k) observed response per unit force at candidate nodes idx."""
        idx = np.asarray(idx, int)
        self._ensure(idx)
        return self._store[self.m:, self._slot[idx]]


class MatrixCompliance(Compliance):
    """A given dense compliance (m, m) and optional observation response (r, m): analytic models."""

    def __init__(self, C, observed=None):
        C = np.asarray(C, float)
        R = np.zeros((0, len(C))) if observed is None else np.asarray(observed, float)
        super().__init__(len(C), len(R))
        self._full = np.vstack([C, R])

    def _compute(self, idx):
        return self._full[:, idx]


class FactorCompliance(Compliance):
    """Compliance from a factorised stiffness; columns are computed `chunk` right-hand sides at a time.

    solve: callable (n_dofs, k) load -> (n_dofs, k) displacement (the factorised, constrained
    system); n_dofs: its size; dofs: (m, dim) DOF index of each candidate node's components; direction: (dim,)
    unit force direction (3,) (its x, y part in 2D); observe: optional sparse (r, n_dofs) observation operator.
    """

    def __init__(self, solve, n_dofs: int, dofs, direction, observe=None, chunk: int = 64):
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

    def _compute(self, idx):
        out = np.empty((self.m + self.r, len(idx)))
        for s in range(0, len(idx), self.chunk):
            sel = idx[s:s + self.chunk]
            u = np.asarray(self.solve(self.B[:, sel].toarray())).reshape(self.n_dofs, -1)
            out[:, s:s + len(sel)] = self.O @ u
        return out

    def displacement(self, force_N) -> np.ndarray:
        """(n_dofs,) full displacement field for nodal contact forces (m,): one solve."""
        return np.asarray(self.solve((self.B @ force_N)[:, None])).reshape(-1)


# --------------------------------------------------------------------------- LCP
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
    gap_mm: np.ndarray              # (m,) gap after deformation (inf outside the footprint)
    deflection_mm: np.ndarray       # (m,) displacement along the approach direction
    part: np.ndarray                # (m,) index of the indentor part facing each node
    pressure_MPa: np.ndarray        # (m,) contact pressure (facet-averaged nodal force / area)
    area_mm2: np.ndarray            # (m,) tributary areas
    observed: np.ndarray            # (r,) observation operator applied to the displacement
    kkt: dict = field(default_factory=dict)

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
        return cls.from_solver(system.solve, model.ndof, sn.x, sn.dofs, sn.area, observe=observe,
                               chunk=chunk, facets=(facets, facet_shares(facets, size, model.dim)), **kw)

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
        s = indentor.part_standoff(self.points_mm)
        t0 = s.min(axis=0)
        if not np.all(np.isfinite(t0)):
            raise InputError(f"indentor {indentor.name} at {np.round(indentor.origin_mm, 3).tolist()} mm "
                             f"never touches the finger surface: move it over the pad or change the approach")
        return t0

    def solve_travel(self, indentor, travel_mm, warm=None) -> tuple[ContactResult, LCPSolution, np.ndarray]:
        """Contact at given tip travels (n_parts,) mm. Returns (result, lcp, candidate subset)."""
        travel = np.broadcast_to(np.asarray(travel_mm, float), (indentor.n_parts,))
        comp = self.compliance(indentor.approach)
        s = indentor.part_standoff(self.points_mm) - travel
        part = np.argmin(s, axis=1)
        gap0 = s[np.arange(len(s)), part]
        sub = np.flatnonzero(np.isfinite(gap0))
        q = gap0[sub]
        start = warm[sub] if warm is not None and warm[sub].any() else q < min(0.0, 0.5 * q.min(initial=0))
        lcp = solve_lcp(lambda i: comp.columns(sub[i])[sub], q, start, self.tol_mm)
        m = len(self.points_mm)
        f = np.zeros(m)
        f[sub] = lcp.force
        act = sub[lcp.active]
        w = comp.columns(act) @ f[act] if act.size else np.zeros(m)
        obs = comp.observed(act) @ f[act] if act.size else np.zeros(comp.r)
        g = gap0 + w
        if self.facets is not None:
            pressure = smoothed_pressure(f, *self.facets)
        else:
            with np.errstate(divide="ignore", invalid="ignore"):
                pressure = np.where(f > 0, f / self.areas_mm2, 0.0)
        t0 = self.first_touch_mm(indentor)
        res = ContactResult(indentor.name, travel - t0, travel.copy(), f, g, w, part, pressure,
                            self.areas_mm2, obs, _kkt(f[sub], g[sub], self.tol_mm))
        res.kkt["iterations"] = lcp.iterations
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
            self._remember(res)
            return res
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

    def _remember(self, res):
        self._warm = res.force_N > 0

    def _force(self, indentor, target, equal_force, max_depth_mm, t0):
        if not target > 0:
            raise InputError(f"force must be positive, got {target} N")
        n = indentor.n_parts if equal_force else 1
        tmax = t0[:n] + max_depth_mm if equal_force else np.array([t0.min() + max_depth_mm])
        travels = lambda t: t if equal_force else np.full(indentor.n_parts, t[0])
        res, lcp, sub = self.solve_travel(indentor, travels(tmax), self._warm)
        reach = res.part_force_N if equal_force else np.array([res.total_force_N])
        if np.any(reach < target):
            raise InputError(f"force {target} N is not reached within {max_depth_mm} mm depth "
                             f"(force there {np.round(reach, 6).tolist()} N): lower the force or raise "
                             f"the depth limit")
        lo = t0[:n] if equal_force else np.array([t0.min()])
        hi = tmax.copy()
        t = lo + 0.5 * (hi - lo) * 0.1
        for it in range(1, 101):
            res, lcp, sub = self.solve_travel(indentor, travels(t), res.force_N > 0)
            phi = res.part_force_N if equal_force else np.array([res.total_force_N])
            err = phi - target
            if np.all(np.abs(err) <= FORCE_RTOL * target):
                self._remember(res)
                res.kkt["force_iterations"] = it
                return res
            if n == 1:
                (lo if err[0] < 0 else hi)[0] = t[0]
            J = self._force_jacobian(lcp, res.part[sub], n if equal_force else 1)
            try:
                step = np.linalg.solve(J, -err)
            except np.linalg.LinAlgError:
                step = np.full(n, np.nan)
            new = t + step
            if n == 1 and not (lo[0] < new[0] < hi[0]):
                new = 0.5 * (lo + hi)
            t = np.clip(new, t0[:n] if equal_force else t0.min(), tmax)
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
