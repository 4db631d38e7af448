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
(`Model.system(condense=(nodes, a))`, as `fem.io.modelfolder.open_model` does), C is the inverse of their Schur
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
deflection (Hertz within 3 %, tests/fem/contact/test_contact_fe.py) but nodal forces alternate between vertex
and midside nodes (about 1 : 2 against a consistent load), so raw f_i / A_i overstates the peak
pressure by about a third: hence the facet-averaged pressure.

    model, system, region, info = open_model("out/cyl8")          # fem.io.modelfolder: factorised
    cm = ContactModel.from_fe(model, system, region, observe=model.strain_operator(points))
    res = cm.indent(indentor, depth_mm=1.0)             # or force_N=0.2, equal_force=True
    res.total_force_N, res.contact_area_mm2, res.max_pressure_MPa, res.kkt, res.observed
    cm.sweep(indentor, offsets_mm, force_N=0.2)         # one small LCP per position

Any other elastic body works through `ContactModel(points, areas, compliance_for)` with a
`fem.contact.compliance.Compliance` (e.g. `MatrixCompliance` for an analytic half-space).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla

from fem.contact.compliance import (
    Compliance,
    CondensedCompliance,
    FactorCompliance,
    RowCache,
)
from fem.contact.facets import edge_area_mm2, fe_facets, node_pairs, smoothed_pressure
from fem.core.linalg import SERIAL_BLAS_BELOW, blas_threads
from fem.core.materials import BONE_LAYER
from fingertip.errors import InputError

GAP_TOL_MM = 1e-8
"""Allowed penetration after deformation (mm) and the pivoting threshold on the gap."""
FORCE_RTOL = 1e-6
"""Relative tolerance on prescribed forces."""
MAX_DEPTH_MM = 5.0
"""Depth limit of force control (mm) where the model's tissue is thicker (`tissue_mm`)."""


def point_text(x, digits: int = 2) -> str:
    """A point (dim,) in words for a message: "(0.5, -1.25, 3)" (rounded to `digits`)."""
    return "(" + ", ".join(f"{v:g}" for v in np.round(np.asarray(x, float), digits) + 0.0) + ")"


class BlockedError(InputError):
    """The indentor would push surface nodes that are held fixed (no finite force can)."""


# --------------------------------------------------------------------------- LCP
@dataclass
class LCPSolution:
    force: np.ndarray        # (n,) f >= 0
    gap: np.ndarray          # (n,) q + C f
    active: np.ndarray       # (n,) bool, f carried
    factor: ActiveFactor | None     # solves with C over the active set
    iterations: int


class ActiveFactor:
    """Solves with C over an active set S from an upper Cholesky factor R (R^T R = C[T, T]) over
    a base set T that contains S: the members of T outside S (D, k of them) are held at zero
    force through their capacitance, x = y - W (W_D)^-1 y_D with y = C_TT^-1 b and
    W = C_TT^-1 E_D (2 k triangular solves, then a k x k factorisation), instead of a new
    factorisation of C[S, S] (|S|^3 / 3 flops)."""

    def __init__(self, R: np.ndarray, base: np.ndarray, active: np.ndarray):
        self.R, self.base = R, base
        self.active = active.copy()
        at = np.flatnonzero(active[base])                       # positions of S in T
        self._pos = at[np.argsort(base[at])]                    # ... of S in increasing index order
        self._held = np.flatnonzero(~active[base])              # positions of D in T
        self._W = self._cap = None
        if self._held.size:
            E = np.zeros((len(base), self._held.size))
            E[self._held, np.arange(self._held.size)] = 1.0
            self._W = sla.cho_solve((R, False), E, check_finite=False)
            self._cap = sla.cho_factor(self._W[self._held], check_finite=False)

    def solve(self, b: np.ndarray) -> np.ndarray:
        """x with C[S, S] x = b; b (|S|,) or (|S|, r) over the active indices in increasing order."""
        y = np.zeros((len(self.base),) + b.shape[1:])
        y[self._pos] = b
        y = sla.cho_solve((self.R, False), y, check_finite=False)
        if self._held.size:
            y -= self._W @ sla.cho_solve(self._cap, y[self._held], check_finite=False)
        return y[self._pos]


class LCPBlocks:
    """Columns of C over one candidate subset (n,), each fetched once (a `RowCache` of them, one
    per row: C is symmetric), and the factor of the last active sets: successive LCPs on the same
    subset (force control's depth iterations, sweep positions under a wide indentor) fetch only
    newly touching columns, and a new active set extends the last Cholesky factor by its new
    members (a bordered factor, |T|^2 per member) and holds the dropped ones at zero (see
    `ActiveFactor`) until more than REBASE of them are held; then the active block is
    factorised afresh. Products sum in fetch order and factors depend on the active sets before,
    so the bits depend on the LCPs before on the same blocks: `ContactModel.restart` starts new
    ones per experiment."""

    REBASE = (8, 0.1)       # refactorise when more than 8 + 10 % of the active set are held

    def __init__(self, columns, n: int):
        self._cols = RowCache(lambda i: columns(i).T, n, n)
        self._last: ActiveFactor | None = None

    def apply(self, idx, f) -> np.ndarray:
        """(n,) C[:, idx] @ f (f (len(idx),)), summed in fetch order: no gathered copy."""
        slots = self._cols.slots(idx)
        fs = np.zeros(self._cols.size)
        fs[slots] = f
        return fs @ self._cols.data[:self._cols.size]

    def _block(self, rows, cols) -> np.ndarray:
        """C[rows][:, cols] from the fetched columns (C is symmetric)."""
        slots = self._cols.slots(cols)
        return self._cols.data[np.ix_(slots, rows)].T

    def factor(self, active) -> ActiveFactor:
        """An `ActiveFactor` over the active set (n,) bool, reused while it is the last one's."""
        last = self._last
        if last is not None and np.array_equal(last.active, active):
            return last
        idx = np.flatnonzero(active)
        with blas_threads(1 if len(idx) < SERIAL_BLAS_BELOW else None):
            if last is not None:
                new = idx[~np.isin(idx, last.base)]
                held = len(last.base) + len(new) - len(idx)
                if held <= self.REBASE[0] + self.REBASE[1] * len(idx):
                    R, base = last.R, last.base
                    if new.size:                                # bordered: [[R, X], [0, R_s]]
                        X = sla.solve_triangular(R, self._block(base, new), trans="T", check_finite=False)
                        S = self._block(new, new) - X.T @ X
                        R = np.block([[R, X], [np.zeros((len(new), len(base))),
                                                sla.cholesky(S, check_finite=False)]])
                        base = np.concatenate([base, new])
                    self._last = ActiveFactor(R, base, active)
                    return self._last
            self._last = ActiveFactor(sla.cholesky(self._block(idx, idx), check_finite=False), idx, active)
        return self._last


def solve_lcp(columns, q, start=None, tol_mm: float = GAP_TOL_MM, max_iter: int = 500) -> LCPSolution:
    """Solve f >= 0, g = q + C f >= -tol, f g = 0 for symmetric positive definite C.

    columns: callable idx -> (n, k) columns of C, or the `LCPBlocks` of earlier LCPs with the
    same C; q: (n,) gaps without contact forces (mm); start: (n,) bool initial guess of the active
    set (default: q < 0), e.g. the previous solution's. Block principal pivoting with Murty's rule
    as backup: finite for P-matrices.
    """
    n = len(q)
    active = (q < 0) if start is None else start.copy()
    best, backup = n + 1, 3
    blocks = columns if isinstance(columns, LCPBlocks) else LCPBlocks(columns, n)
    for it in range(1, max_iter + 1):
        idx = np.flatnonzero(active)
        f = np.zeros(n)
        factor = None
        if idx.size:
            factor = blocks.factor(active)
            with blas_threads(1 if idx.size < SERIAL_BLAS_BELOW else None):
                f[idx] = factor.solve(-q[idx])
            g = q + blocks.apply(idx, f[idx])
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
    _source: ContactModel | None = field(default=None, repr=False)
    _unseen: np.ndarray | None = field(default=None, repr=False)    # candidates outside the reach
    elastic_force_N: np.ndarray | None = field(default=None, repr=False)   # viscoelastic: (m,) the elastic
                                    # forces, whose displacement field the result has (None: elastic)
    stored_energy_Nmm: float | None = field(default=None, repr=False)  # finite kinematics: the model's
                                    # stored energy (None: linear, f . w / 2)

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


def kkt_record(f, g, tol_mm) -> dict:
    """The KKT check of contact forces f (m,) [N] and gaps g (m,) [mm]: largest penetration,
    largest tensile force, largest |f g|, and whether all are within tol_mm (and round-off)."""
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
    (k, n) area shares) for the pressure recovery (`fem.contact.facets.facet_shares`).
    """

    def __init__(self, points_mm, areas_mm2, compliance_for, tol_mm: float = GAP_TOL_MM, facets=None):
        self.points_mm = np.asarray(points_mm, float)
        self.areas_mm2 = np.asarray(areas_mm2, float)
        self.facets = facets
        self._compliance_for = compliance_for
        self._compliance = {}
        self.tol_mm = tol_mm
        self._pending = []           # (result, compliance) awaiting observations
        self._pairs = None           # node_pairs, built on first use
        self.preload_mm = None       # (m,) displacement along the approach from other loads (None: 0)
        self.restart()

    def restart(self) -> None:
        """Forget what earlier indentations leave for the next (warm start, force control's first
        trial depth, fetched compliance blocks): what follows is computed as by a new contact model,
        so an experiment's numbers do not depend on the experiments before it."""
        self._warm = None
        self._blocks = None          # (compliance, candidate subset, LCPBlocks) of the last LCP
        self._force_depth = 0.5      # first trial depth (mm) of force control; then the last one

    @classmethod
    def from_fe(cls, model, system, region: str, observe=None, chunk=64, **kw):
        """Contact on the nodes of `region` of a `fem.core.model.Model`, with its factorised
        `LinearSystem` (constraints applied); observe: optional sparse (r, ndof) operator
        (e.g. `model.strain_operator(receptors)`) whose response is cached with the columns."""
        sn = model.surface_nodes(region)
        def compliance_for(a):
            try:
                return CondensedCompliance(system, sn.nodes, sn.dofs, a, observe=observe, chunk=chunk)
            except ValueError:          # not condensed along a (or not these nodes): lazy columns
                return FactorCompliance(system.solve, model.ndof, sn.dofs, a, observe=observe, chunk=chunk,
                                        fixed=system.fixed)
        return cls(sn.x, sn.area, compliance_for, facets=fe_facets(model, region, sn), **kw)

    def compliance(self, direction) -> Compliance:
        key = tuple(np.round(direction, 12))
        if key not in self._compliance:
            self._compliance[key] = self._compliance_for(np.asarray(direction, float))
        return self._compliance[key]

    def edge_area_mm2(self, result: ContactResult) -> float:
        """Tributary area [mm^2; mm in 2D] of the contact's outer ring (`fem.contact.facets.edge_area_mm2`,
        neighbours on the facets' linear sub-facets): what a node-counted area cannot resolve. NaN
        without facets."""
        if self.facets is None:
            return math.nan
        if self._pairs is None:
            self._pairs = node_pairs(self.facets[0], self.points_mm)
        return edge_area_mm2(result.active, result.area_mm2, self._pairs)

    def first_touch_mm(self, indentor) -> np.ndarray:
        """(n_parts,) travel at which each part first touches the undeformed candidate surface."""
        return first_touch(self.points_mm, indentor)[1]

    def solve_travel(self, indentor, travel_mm, warm=None) -> tuple[ContactResult, LCPSolution, np.ndarray]:
        """Contact at given tip travels (n_parts,) mm. Returns (result, lcp, candidate subset).
        With `preload_mm` (m,) set, the candidates start displaced by it along the approach (loads
        other than the contact, e.g. a viscoelastic body's history, `fem.experiments.stepping`):
        it adds to the gaps and to the deflection."""
        travel = np.broadcast_to(np.asarray(travel_mm, float), (indentor.n_parts,))
        comp = self.compliance(indentor.approach)
        s = indentor.part_standoff(self.points_mm) - travel
        part = np.argmin(s, axis=1)
        pre = 0.0 if self.preload_mm is None else self.preload_mm
        gap0 = s[np.arange(len(s)), part] + pre
        sub = np.flatnonzero(np.isfinite(gap0))
        blocked = sub[comp.held[sub] & (gap0[sub] < -self.tol_mm)]
        if blocked.size:
            x = point_text(self.points_mm[blocked[np.argmin(gap0[blocked])]])
            raise BlockedError(f"indentor {indentor.name} would push {blocked.size} surface nodes that are held "
                               f"fixed (the deepest at {x} mm): it reaches the model's fixed boundary (nail or "
                               f"proximal cut); use a smaller depth or indentor, or move it away from there")
        sub = sub[~comp.held[sub]]
        far = sub[~comp.reach[sub]]
        if far.size and gap0[far].min() < -self.tol_mm:
            x = point_text(self.points_mm[far[np.argmin(gap0[far])]])
            raise InputError(f"indentor {indentor.name} reaches surface nodes (the deepest at {x} mm) outside "
                             f"the candidates condensed when the model was factorised: factorise with "
                             f"candidates covering this indentation (fem.contact.linear.reach)")
        sub = sub[comp.reach[sub]]
        q = gap0[sub]
        start = warm[sub] if warm is not None and warm[sub].any() else q < min(0.0, 0.5 * q.min(initial=0))
        if not (self._blocks and self._blocks[0] is comp and np.array_equal(self._blocks[1], sub)):
            self._blocks = (comp, sub, LCPBlocks(lambda i: comp.block(sub, sub[i]), len(sub)))
        lcp = solve_lcp(self._blocks[2], q, start, self.tol_mm)
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
        res = ContactResult(indentor.name, travel - t0, travel.copy(), f, g, w + pre, part, pressure,
                            self.areas_mm2, kkt_record(f[sub], g[sub], self.tol_mm))
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
            res = self.solve_travel(indentor, t0.min() + depth_mm, self._warm)[0]
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
                raise InputError(f"sweep position {point_text(off, 4)} mm: {exc}") from None
        return out

    def _finish(self, res, indentor) -> ContactResult:
        """Warm start for the next indentation; the result's observations are left pending."""
        self._warm = res.force_N > 0
        res._source = self
        self._pending.append((res, self.compliance(indentor.approach)))
        return res

    def discard_pending(self) -> None:
        """Drop the observations finished indentations await (their caller computes its own)."""
        for res, _ in self._pending:
            res._source = None
        self._pending = []

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
                        x = point_text(self.points_mm[rows[np.argmin(r._gap_mm[rows])]])
                        raise InputError(f"indentor {r.indentor_name}: the skin touched it at {x} mm, outside the "
                                         f"candidates condensed when the model was factorised: factorise with "
                                         f"a larger reach margin (fem.contact.linear.reach)")

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
        tried = []
        for it in range(1, 101):
            if n > 1 and any(np.allclose(depth, d, rtol=1e-9, atol=1e-12) for d in tried[-2:]):
                return self._equal_travel(indentor, n * target, max_depth_mm, t0)
            tried.append(depth.copy())
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
                raise self._not_reached(target, max_depth_mm, err + target)
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

    def _equal_travel(self, indentor, total, max_depth_mm, t0):
        """Equal force that the mesh cannot resolve: Newton cycles between two states when a node
        lies as near one part as the other (two tips closer than the elements under them, the node
        passing from part to part as their depths differ). The tips then travel together, carrying
        `total` between them; kkt["equal_force"] says so and gives the parts' forces."""
        res = self._force(indentor, total, False, max_depth_mm, t0)
        res.kkt["equal_force"] = ("not resolved by the mesh (the parts share nodes): equal travel, parts carry "
                                  + ", ".join(f"{f:.4g}" for f in res.part_force_N))
        return res

    def _not_reached(self, target, max_depth_mm, force) -> InputError:
        unit = "N/mm" if self.points_mm.shape[1] == 2 else "N"
        there = ", ".join(f"{f:.4g}" for f in np.atleast_1d(force))
        return InputError(f"force_N {target:g} {unit} is not reached within max_depth_mm {max_depth_mm:g} mm "
                          f"(the force there is {there} {unit}): lower force_N or raise max_depth_mm")

    def force_at(self, indentor, depth_mm: float, equal_force=False) -> np.ndarray | None:
        """(1,) total force, or (n_parts,) part forces (equal_force), at depth_mm beyond first
        touch, e.g. the depth limit of force control, to refuse a force not reached there before a
        loop of indentations; None when the indentor pushes held nodes there. What it leaves for
        the next problem is forgotten (`restart`)."""
        t0 = self.first_touch_mm(indentor)
        travel = t0 + depth_mm if equal_force else np.full(indentor.n_parts, t0.min() + depth_mm)
        try:
            res = self.solve_travel(indentor, travel)[0]
        except BlockedError:
            return None
        finally:
            self.restart()
        return res.part_force_N.copy() if equal_force else np.array([res.total_force_N])

    @staticmethod
    def _force_jacobian(lcp, part, n):
        """(n, n) d(part force)/d(part travel) for the current active set: 1_k^T C_AA^-1 1_l."""
        J = np.zeros((n, n))
        if lcp.factor is None:
            return J
        pa = part[lcp.active] if n > 1 else np.zeros(lcp.active.sum(), int)
        ones = np.stack([(pa == k).astype(float) for k in range(n)], axis=1)
        sol = lcp.factor.solve(ones)
        return ones.T @ sol


# --------------------------------------------------------------------------- reach
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
            raise InputError(f"sweep position {point_text(off, 4)} mm: {exc}" if len(offsets_mm) > 1
                             else str(exc)) from None
        mask |= np.any(s - t0 <= depth_mm + margin_mm, axis=1)
    return mask


def tissue_mm(model, surface_mm, approach) -> float:
    """The tissue an indentor can push into along `approach` (3,) on a `fem.core.model.Model`
    (mm): from the highest of the contact-region points surface_mm (m, dim) against the approach
    to the highest point of the bone (layer BONE_LAYER) along it, or, without bone, to the lowest
    point of the model; rounded down to 0.01 mm, so that the limit a message shows may be given.
    Depths beyond it would push the indentor through the bone or the body."""
    up = -np.asarray(approach, float)[:model.dim]
    up = up / np.linalg.norm(up)
    top = float((np.asarray(surface_mm, float) @ up).max())
    p, bone = model.mesh.p, model.layer == BONE_LAYER
    below = (float((p[:, np.unique(model.mesh.t[:, bone])].T @ up).max()) if bone.any()
             else float((p.T @ up).min()))
    return float(np.floor((top - below) * 100 + 1e-6) / 100)


def first_touch(points_mm, indentor) -> tuple[np.ndarray, np.ndarray]:
    """(standoff (m, n_parts) mm of each candidate point (m, dim) from each part along the approach,
    inf where it misses; (n_parts,) travel at which each part first touches). Raises InputError
    when a part touches none of them."""
    s = indentor.part_standoff(points_mm)
    t0 = s.min(axis=0)
    if not np.all(np.isfinite(t0)):
        raise InputError(f"indentor {indentor.name} at {point_text(indentor.origin_mm, 3)} mm "
                         f"never touches the finger surface: move it over the pad or change the approach")
    return s, t0
