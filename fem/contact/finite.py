"""Large-deformation frictionless contact of the layered neo-Hookean fingertip
(`fem.core.neohookean.NeoHookean`) with a rigid indentor whose surface is known in closed form
(`fem.contact.surfaces.RigidSurface`: cylinders, spheres, bars, plates, punches, gratings, steps,
two-point stimuli with spherical tips).

The gap of a candidate node is measured in the deformed configuration, to the indentor's true
surface: the signed distance from its current position x = X + u to the surface, along the
surface's normal (normal projection onto the circle, the cylinder's axis or the sphere's centre,
g = |x - c|_perp - R; for a flat indentor the nearest of its face, its side and its edge; for a
step the closest point of its profile; for several parts or bars the nearest of them). A node
in contact carries a force lambda >= 0 along the normal n; the rest of the surface is free. The
method is an active set with Lagrange multipliers (a semi-smooth Newton): each iteration solves
the mixed u-p tangent bordered by the active constraints,

    [ K - sum lambda_i H_i   G^T   -C^T ] [du  ]   [-(f_int - C^T lambda)]
    [ G                      -D     0   ] [dp  ] = [ 0                   ]
    [-C                       0     0   ] [dlam]   [ g_active            ]

(C: the active nodes' normals; H_i = k_i (I - n n^T - t t^T), the Hessian of the gap, with k_i
the curvature of the gap's level set, 1 / |x - c|_perp for a round indentor, 1 / distance from the
edge around a flat one's edge, the profile's curvature at the closest point for a step, and t
its straight direction in 3D: a cylinder's axis, the edge's line, the step's length axis; the
pressure block as in NeoHookean), takes lambda + dlam as the new multipliers, and moves the
active set: nodes whose multiplier turns negative leave, nodes that penetrate by more than
GAP_TOL_MM join. An iteration whose residual fell by CHORD since the last (or, falling at that
rate, reaches the tolerance within FINISH more iterations) is solved on the last factorisation
(a chord step). In 3D, where a factorisation costs about 60 solves (the 1 mm monkey), any other
iteration is first solved with its own tangent by GMRES on the last factorisation (`_krylov`, a
Newton-Krylov step), and factorises only when that does not reach ETA of the residual within
KRYLOV_MAX iterations. In 3D the factorisations are in single precision (`fem.core.linalg.Pardiso`,
PARDISO's iparm[27] = 1: half the factorisation's time and memory, faster solves) and every
iteration, chord steps and those right after a factorisation too, is solved by GMRES on it: a
single-precision solve leaves a relative residual of 6e-4 to 1.2e-3 (the 1 mm monkey's tangent,
random loads; the solution within 9e-5), well inside ETA, so those take 0-1 GMRES iterations. A
factorisation GMRES cannot use is redone in double precision for the rest of the run (in 2D,
where a factorisation costs about a solve, double precision throughout). It stops when the active set
is stable, the free residual is below `tol` of the contact force (1e-8: the solves skip iterative
refinement, so the last iterations converge linearly, and each further digit of the residual costs
about one more tangent while the force is settled to 9-10 digits) and every gap is within GAP_TOL_MM,
so the constraint holds to the linear solver's tolerance (`fem.contact.linear.GAP_TOL_MM`): no
penalty stiffness to tune and no penetration left by one, and sliding of the skin along a curved
indentor comes with the normal projection. (Mortar methods pay off between two deformable bodies
with non-matching meshes; against a rigid analytic surface node-to-surface is exact.)

The indentor travels in depth increments of STEP_MM[dimension] (halved when Newton fails, up to
MAX_CUTS times); the increments on the way to a depth asked for are solved to PASSING_TOL only.

    fc = FiniteContact(model, "surface", held_regions(model))
    results = fc.indent(make_indentor("C5"), [0.5, 1.0, 2.0])
    results[-1].force_N, results[-1].energy_Nmm, results[-1].penetration_mm
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from fem.contact.facets import edge_area_mm2, fe_facets, node_pairs, smoothed_pressure
from fem.contact.linear import GAP_TOL_MM, ContactResult, kkt_record
from fem.contact.surfaces import RigidSurface
from fem.core.linalg import SaddleFactor, serial_openblas
from fem.core.measures import State, evaluate
from fem.core.neohookean import NeoHookean
from fingertip.errors import InputError

STEP_MM = {2: 0.1, 3: 0.25}
"""Depth increment of the load stepping (mm) per dimension. Measured (C5, forces equal to 1e-8):
the 2D cylinder8 with bone 0.25:2:0.25 mm 6.8-7.0 s at 0.1 mm, 16.8 s at 0.25 mm (a 2D
factorisation costs about one solve: Newton's iterations are what costs); the 1 mm monkey,
perpendicular, 0.5:2:0.5 mm in process, with Newton-Krylov steps, 192.7 s at 0.1 mm, 122.4 s at
0.25 mm (fewer steps, each a few more iterations on the same factorisation)."""
MAX_CUTS = 6
MAX_ITER = 40
CHORD = 0.2
"""A Newton iteration whose residual fell below CHORD times the last one's is solved on the last
factorisation (a chord step: the residual alone, no tangent, no factorisation).
Measured (C5, forces unchanged to 9-10 digits): the 1.5 mm monkey, 0.3:0.9:0.3 mm, 181 s with a
factorisation every iteration, 131 s with chord steps at 0.3 (21 factorisations in 69 iterations
instead of 41 in 41); 0.2 mm there 42.6, 32.9, 29.6, 27.6 s at 0 (none), 0.1, 0.2, 0.3; the 2D
cylinder8 with bone 0.25:2:0.25 mm 9.1, 8.6-9.0, 8.9-9.0, 9.2 s (a 2D factorisation costs about
one solve, so chord steps gain little there)."""
FINISH = 3
"""A chord step also follows a residual that fell by less than CHORD but by more than half, when
falling at that rate FINISH more times reaches the tolerance (on the 1 mm monkey an iteration
with a new tangent costs 3.5-4 s, a chord step 0.3-0.9 s)."""
PASSING_TOL = 1e-5
"""Relative residual of the load steps on the way to a depth asked for (they are only starting
points: frictionless hyperelastic contact has no memory of its path); the depths asked for are
solved to `FiniteContact.tol`."""
KRYLOV_MAX = 12
"""GMRES iterations of a Newton-Krylov step (3D) before the tangent is factorised instead."""
KRYLOV_STALE = 8
"""A Newton-Krylov step that took more GMRES iterations than this has the next tangent factorised
(the last factorisation has aged: each GMRES iteration costs a solve, a factorisation with its
columns about 50 on the 1 mm monkey). Measured with ETA (see there): 70.1 s at 6, 68.2 s at 8."""
ETA = 3e-2
"""Forcing term of the Newton-Krylov steps: GMRES stops when the force residual of the linearised
problem is below ETA times the Newton residual. Measured on the 1 mm monkey, C5 perpendicular
0.5:2:0.5 mm in process (forces within 4e-10 of each other): 74.1 s at 1e-2, 68.2 s at 3e-2,
69.8 s at 5e-2; at 3e-2 with KRYLOV_STALE 6 70.1 s; at 1e-2 with KRYLOV_STALE 11 (KRYLOV_MAX
16) 76.2 s."""
COLUMNS_MAX_BYTES = 2**28
"""Memory for the kept columns of `FiniteContact._columns` (float64). While the active candidates'
whole columns fit, they are kept (the 1 mm monkey: up to 470 of its 70k unknowns); beyond it only
their rows at the candidates' DOFs are kept (`_Border`: the human 0.5 mm model, 20,739 rows
instead of 311k; its acceptance run held up to 9.9 GB keeping whole columns within 1 GiB), and
X lambda is one more solve; beyond it in rows too, none is kept and every iteration solves its
active set's columns afresh."""
COLUMN_BLOCK = 256
"""Columns of `FiniteContact._columns` per solve, at most; fewer where their right-hand sides
would take more than COLUMN_BLOCK_BYTES. (1 mm monkey, C5 perpendicular 0.5:2:0.5 mm in process:
70.8 s at 256, 72.2 s at 64, 68.2 s in one solve.)"""
COLUMN_BLOCK_BYTES = 2**28
"""A solve holds its right-hand sides three times over (dense, padded for PARDISO, solution): 256
columns of the human 0.5 mm model are 0.64 GB each time, and its acceptance run held up to 14.8 GB
solving all active columns at once. So a block holds at most this (107 columns there, 256 on the
1 mm monkey)."""
PATIENCE = 6
"""Newton iterations in a row without a new smallest residual after which a step is given up (and
cut): an active set cycling at the edge of the contact, or a diverging iterate, never recovers."""


@dataclass
class FiniteResult:
    """One depth: depth_mm, force_N along the approach (N; N/mm in 2D), u (ndof,) [mm], force per
    candidate along its normal lambda (m,) [N], gap (m,) [mm] and normal (m, 3) in the deformed
    configuration, stored energy energy_Nmm, largest penetration penetration_mm, smallest J,
    Newton iterations since the depth before."""
    depth_mm: float
    force_N: float
    u: np.ndarray
    contact_force_N: np.ndarray
    gap_mm: np.ndarray
    normal: np.ndarray
    energy_Nmm: float
    penetration_mm: float
    min_J: float
    iterations: int


def _positions(A: sp.csr_matrix, dofs) -> np.ndarray:
    """(k d d,) positions in A.data (CSR, sorted indices) of the entries A[dofs[a, i], dofs[a, j]],
    dofs (k, d), row by row; KeyError when one is not stored."""
    rows = np.asarray(dofs).reshape(-1)
    cols = np.repeat(np.asarray(dofs), dofs.shape[1], axis=0).reshape(-1)      # each row's d columns
    start, length = A.indptr[rows], np.diff(A.indptr)[rows]
    at = np.repeat(start - np.cumsum(length) + length, length) + np.arange(length.sum())   # the rows' entries
    keys = np.repeat(np.arange(len(rows), dtype=np.int64), length) * A.shape[1] + A.indices[at]
    wanted = np.repeat(np.arange(len(rows), dtype=np.int64), dofs.shape[1]) * A.shape[1] + cols
    found = np.searchsorted(keys, wanted)
    if len(wanted) and (found.max() >= len(keys) or np.any(keys[found] != wanted)):
        raise KeyError("an entry of the DOF blocks is not in the matrix's pattern")
    return at[found]


class _Border:
    """The active constraints' columns X = K_T^-1 C^T (nf, k) on one factorisation, as a bordered
    solve uses them: CX = C X (k, k), and X lambda (`times`) from the columns X when they are kept
    whole, else as one more solve, K_T^-1 (C^T lambda), on the factorisation `factor`."""

    def __init__(self, CX, X=None, factor=None, C=None):
        self.CX, self._X, self._factor, self._C = CX, X, factor, C

    def times(self, lam) -> np.ndarray:
        """(nf,) X lambda for lambda (k,)."""
        if self._X is not None:
            return self._X @ lam
        return self._factor(self._C.T @ lam, refine=False)


class FiniteContact:
    """Frictionless contact of a model's neo-Hookean body (`fem.core.model.Model`, 2D or 3D) on the
    candidate nodes of `region` with a rigid indentor; held: the regions held fixed (as
    `Model.system`'s prescribed, zero displacement)."""

    def __init__(self, model, region: str, held: dict, tol_mm: float = GAP_TOL_MM, tol: float = 1e-8):
        self.model, self.nh, self.tol_mm, self.tol = model, NeoHookean(model), tol_mm, tol
        self._factor = None             # the last tangent's factorisation: its analysis serves the next
        self._cols = {}                 # candidate -> its column of K_T^-1 C^T on that factorisation (or its rows)
        self._whole = True              # whether _cols holds whole columns (else their rows at `_at`)
        self._stale = False             # the last Newton-Krylov step found it aged: factorise the next tangent
        self.krylov = model.dim == 3    # Newton-Krylov steps (module notes)
        self.single = self.krylov       # factorisations in single precision (module notes)
        self.sn = model.surface_nodes(region)
        self.fixed, values = model.discretisation.constraints(held, model.material.rigid)   # no factorisation
        if np.any(values):
            raise InputError("finite contact holds its fixed regions at zero displacement")
        model.discretisation.check_held(self.fixed)
        self.free = np.setdiff1d(np.arange(model.ndof), self.fixed)
        self.stopped = None                # why the last `indent` ended early (partial=True)
        self.dofs = self.sn.dofs                                   # (m, dim)
        self._at = np.flatnonzero(np.isin(self.free, self.dofs))  # the candidates' DOFs among the free ones
        self.X = np.zeros((len(self.dofs), 3))
        self.X[:, :model.dim] = self.sn.x
        self.facets = fe_facets(model, region, self.sn)
        self._pairs = None                 # node_pairs of the facets, built on first use

    def observe(self, u, sampler) -> np.ndarray:
        """Receptor values of displacement u at a fem.receptors.grid.ReceptorSampler's points, in
        `sampler.with_energy()`'s layout: displacement, Green-Lagrange strain E = (F^T F - I) / 2
        with its volumetric part p / kappa from the pressure field (the mixed formulation's, as the
        linear solver's assumed strain), Cauchy stress sigma = P F^T / J (plane strain: sigma_zz =
        lambda / kappa p, the linear solver's in the small-strain limit) and the stored energy per
        reference volume mu / 2 (J^(-2/d) I1 - d) + p^2 / (2 kappa) (`fem.core.neohookean`'s with
        the pressure eliminated) [MPa]. Each reduces to the linear measure at small strain."""
        x = sampler.points_mm
        disp, E_d, sigma_d, sigma_zz, W = self._state_at(u, x, self.model.locate(x))
        n, d = len(x), self.model.dim
        if d == 3:
            comps = [(0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1)]
            strain = np.stack([E_d[:, i, j] for i, j in comps], axis=1)
            stress = np.stack([sigma_d[:, i, j] for i, j in comps], axis=1)
        else:
            strain = np.stack([E_d[:, 0, 0], E_d[:, 1, 1], E_d[:, 0, 1]], axis=1)
            stress = np.stack([sigma_d[:, 0, 0], sigma_d[:, 1, 1], sigma_zz, sigma_d[:, 0, 1]], axis=1)
        return np.concatenate([disp.reshape(n * d), strain.ravel(), stress.ravel(), W])

    def element_fields(self, u) -> dict[str, np.ndarray]:
        """{measure name: (M,) value at each element's centroid} of displacement u, every measure of
        fem.core.measures from the finite state (`observe`'s strain, stress and energy): the cell
        data of a finite run's VTU files."""
        m, d = self.model, self.model.dim
        x = m.mesh.p[:, m.mesh.t].mean(axis=1).T
        disp, E_d, sigma_d, sigma_zz, W = self._state_at(u, x, np.arange(m.mesh.nelements))
        n = len(x)
        disp3, strain, stress = np.zeros((n, 3)), np.zeros((n, 3, 3)), np.zeros((n, 3, 3))
        disp3[:, :d], strain[:, :d, :d], stress[:, :d, :d] = disp, E_d, sigma_d
        if d == 2:
            stress[:, 2, 2] = sigma_zz
        return evaluate(None, State(disp3, strain, stress, W))

    def _state_at(self, u, x, cells) -> tuple:
        """(displacement (n, d) mm, Green-Lagrange strain with the assumed volumetric part (n, d, d),
        Cauchy stress (n, d, d) MPa, plane strain's sigma_zz (n,) (2D; else None), stored energy per
        reference volume (n,) MPa) of displacement u at points x (n, d) in elements `cells` (n,)."""
        m, d, nh = self.model, self.model.dim, self.nh
        value, grad = m.locator.shape(x, cells)                   # (nb, d, n), (nb, d, d, n)
        ue = u[m.element_dofs[:, cells]]                          # (nb, n)
        disp = np.einsum("kn,kin->ni", ue, value)
        F = np.einsum("kn,kijn->nij", ue, grad) + np.eye(d)
        X = m.locator.reference(x, cells)
        lam1 = np.vstack([1.0 - X.sum(axis=0), X])                 # P1 values (d + 1, n)
        p = np.einsum("cn,cn->n", lam1, nh.pressure(u)[m.pressure_basis.element_dofs[:, cells]])
        mu, kappa, lame = m.mu[cells], m.kappa[cells], m.lam[cells]
        J = np.linalg.det(F)
        I1 = np.einsum("nij,nij->n", F, F)
        FiT = np.linalg.inv(F).transpose(0, 2, 1)
        c = mu * J ** (-2.0 / d)
        P = c[:, None, None] * (F - (I1 / d)[:, None, None] * FiT) + (p * J)[:, None, None] * FiT
        sigma_d = P @ F.transpose(0, 2, 1) / J[:, None, None]
        E_d = 0.5 * (F.transpose(0, 2, 1) @ F - np.eye(d))
        trace = np.trace(E_d, axis1=1, axis2=2)
        E_d = E_d + ((p / kappa - trace) / d)[:, None, None] * np.eye(d)    # the volumetric part assumed
        W = 0.5 * mu * (J ** (-2.0 / d) * I1 - d) + p * p / (2.0 * kappa)
        return disp, E_d, sigma_d, (lame / kappa * p if d == 2 else None), W

    def contact_result(self, indentor, r: FiniteResult, sampler=None) -> ContactResult:
        """The indentation `r` by `indentor` as the linear solver's ContactResult: forces per candidate
        along the approach, deflection along it, the normal gaps, the pressure of the normal forces
        over the reference areas (nominal), the KKT check, the stored energy, and with a
        fem.receptors.grid.ReceptorSampler the receptor values of the finite state (`observe`)."""
        first = float(indentor.standoff(self.X).min())
        f = r.contact_force_N * (r.normal @ indentor.approach)
        res = ContactResult(indentor.name, np.array([r.depth_mm]), np.array([first + r.depth_mm]), f, r.gap_mm,
                            r.u[self.dofs] @ indentor.approach[:self.model.dim], np.zeros(len(f), int),
                            smoothed_pressure(r.contact_force_N, *self.facets), self.sn.area,
                            kkt_record(r.contact_force_N, r.gap_mm, self.tol_mm),
                            _observed=None if sampler is None else self.observe(r.u, sampler),
                            stored_energy_Nmm=r.energy_Nmm)
        res.kkt["iterations"] = r.iterations
        return res

    def contact_loads(self, r: FiniteResult, along=None) -> np.ndarray:
        """(ndof,) nodal forces [N; N/mm in 2D] the indentor applies in result `r`: each candidate's
        force along its normal in the deformed configuration, or along the unit vector `along` (3,)
        instead. The linear solver under the first is the small-depth limit of `r`
        (`benchmarks/finite_small_depth.py`); the linear contact solver's own forces act along the
        approach, the second with along = approach."""
        d = self.model.dim
        direction = (r.normal[:, :d] if along is None
                     else np.broadcast_to(np.asarray(along, float)[:d], (len(self.dofs), d)))
        f = np.zeros(self.model.ndof)
        np.add.at(f, self.dofs, r.contact_force_N[:, None] * direction)
        return f

    def edge_area_mm2(self, result: ContactResult) -> float:
        """Tributary area [mm^2; mm in 2D] of a contact result's outer ring
        (`fem.contact.facets.edge_area_mm2`): what its node-counted area cannot resolve."""
        if self._pairs is None:
            self._pairs = node_pairs(self.facets[0], self.sn.x)
        return edge_area_mm2(result.active, result.area_mm2, self._pairs)

    def _positions(self, u) -> np.ndarray:
        x = self.X.copy()
        x[:, :self.model.dim] += u[self.dofs]
        return x

    def indent(self, indentor, depths_mm, partial: bool = False, progress=None, tol=None) -> list[FiniteResult]:
        """Results at increasing depths (mm beyond first touch of the undeformed surface), each
        solved to the relative residual tol (default `tol`). A depth that cannot be reached (Newton
        fails after MAX_CUTS halvings of the step) raises RuntimeError, or with partial=True ends
        the list there, the reason in `stopped`."""
        self.stopped = None
        surf = RigidSurface(indentor)
        depths = np.asarray(depths_mm, float)
        if np.any(np.diff(depths) <= 0) or depths.min(initial=0) < 0:
            raise InputError("finite contact: give increasing depths >= 0 mm")
        t0 = float(indentor.standoff(self.X).min())
        u, lam, depth, out = np.zeros(self.model.ndof), np.zeros(len(self.dofs)), 0.0, []
        for target in depths:
            try:
                u, lam, its = self._advance(u, lam, surf, t0, depth, target, tol)
            except RuntimeError as exc:
                self.stopped = str(exc)
                if partial:
                    return out
                raise
            depth = target
            out.append(self._result(u, lam, surf, t0 + target, target, its))
            if progress is not None:
                progress.note(f"finite contact: {target:g} mm, force {out[-1].force_N:.4g} N")
        return out

    def indent_force(self, indentor, force_N: float, max_depth_mm: float, rtol: float = 1e-7,
                     progress=None) -> FiniteResult:
        """The state at which the force along the approach is force_N [N; N/mm in 2D]: depth steps
        of STEP_MM[dimension] until the force passes it, then the Illinois variant of regula falsi on the
        bracket (superlinear; each trial solved from the bracket's lower state), to rtol.
        InputError when max_depth_mm [mm] does not reach the force."""
        surf = RigidSurface(indentor)
        t0 = float(indentor.standoff(self.X).min())
        lo = (0.0, np.zeros(self.model.ndof), np.zeros(len(self.dofs)), 0.0)     # depth, u, lambda, force
        while True:
            if lo[0] >= max_depth_mm - 1e-12:
                raise InputError(f"indentor {indentor.name}: {force_N:g} N not reached within {max_depth_mm:g} mm "
                                 f"(finite kinematics: {lo[3]:.4g} N there); raise max_depth_mm or lower the force")
            d = min(lo[0] + STEP_MM[self.model.dim], max_depth_mm)
            u, lam, _ = self._advance(lo[1], lo[2], surf, t0, lo[0], d)
            hi = (d, u, lam, self._result(u, lam, surf, t0 + d, d, 0).force_N)
            if hi[3] >= force_N:
                break
            lo = hi
        side = 0                      # which end the last trials replaced: Illinois halves the other's excess
        over = [lo[3] - force_N, hi[3] - force_N]
        for _ in range(60):
            d = lo[0] + over[0] / (over[0] - over[1]) * (hi[0] - lo[0])
            u, lam, its = self._advance(lo[1], lo[2], surf, t0, lo[0], d)
            res = self._result(u, lam, surf, t0 + d, d, its)
            if abs(res.force_N - force_N) <= rtol * force_N:
                if progress is not None:
                    progress.note(f"finite contact: {force_N:g} N at {d:.4g} mm")
                return res
            if res.force_N < force_N:
                lo, over[0] = (d, u, lam, res.force_N), res.force_N - force_N
                over[1] *= 0.5 if side == -1 else 1.0
                side = -1
            else:
                hi, over[1] = (d, u, lam, res.force_N), res.force_N - force_N
                over[0] *= 0.5 if side == 1 else 1.0
                side = 1
        raise RuntimeError(f"finite contact: {force_N:g} N not bracketed to {rtol:g} in 60 trials")

    def _advance(self, u, lam, surf, t0, depth, target, tol=None):
        """(u, lambda, Newton iterations) at depth `target` from the state (u, lambda) at `depth`,
        in steps of at most STEP_MM[dimension], halved up to MAX_CUTS times when Newton fails. Each
        step's Newton starts from the last two states' linear extrapolation (when it inverts no element)."""
        full = STEP_MM[self.model.dim]
        step, cuts, iterations, before = full, 0, 0, None
        while depth < target - 1e-12:
            trial = min(target, depth + step)
            start = u
            if before is not None:
                guess = u + (u - before[0]) * ((trial - depth) / (depth - before[1]))
                start = guess if self.nh.jacobian(guess).min() > 0 else u
            try:
                with serial_openblas():          # NumPy work between PARDISO solves
                    u_new, lam_new, its = self._newton(start, lam, surf, t0 + trial,
                                                       tol if trial >= target - 1e-12 else PASSING_TOL)
            except (FloatingPointError, RuntimeError) as exc:
                cuts += 1
                step /= 2
                if cuts > MAX_CUTS:
                    raise RuntimeError(f"finite contact stopped at depth {depth:.4g} mm: {exc}") from None
                continue
            before = (u, depth)
            u, lam, depth = u_new, lam_new, trial
            iterations += its
            step = min(full, 2 * step)
        return u, lam, iterations

    def _result(self, u, lam, surf, travel, depth, iterations) -> FiniteResult:
        g, n, _, _ = surf.distance(self._positions(u), travel)
        force = float(np.sum(lam * (n @ surf.approach)))
        J = self.nh.jacobian(u)
        return FiniteResult(float(depth), force, u.copy(), lam.copy(), g, n, self.nh.stored_energy(u),
                            float(max(0.0, -g.min())), float(J.min()), iterations)

    def _solve(self, K, G, C, rhs, gap, act, target):
        """(du (nf,), lambda (k,)) on the free DOFs of [[K_T, -C^T], [-C, 0]] [du, lambda] = [rhs,
        gap], K_T = K + G^T D^-1 G the mixed tangent (`fem.core.linalg.SaddleFactor`, as the linear
        solver's): du = x0 + X lambda with x0 = K_T^-1 rhs, X = K_T^-1 C^T (`_columns` of the active
        candidates act (k,)), and the constraints C du = -gap give (C X) lambda = -gap - C x0 (k x k,
        dense). K None: the last tangent's factorisation (a chord step). A single-precision
        factorisation (`single`) is GMRES's preconditioner (`_krylov`) to the force residual
        `target` [N] or ETA of the step's change of contact forces; where it does not get there,
        the tangent is factorised in double precision, for the rest of the run."""
        if K is not None:
            self._factorise(K, G, self.single)
        if self._factor.single:
            solved = self._krylov(self._factor.apply, C, rhs, gap, act, target, ETA)
            if solved is not None:
                return solved[:2]
            self.single = False
            self._factorise(self._factor.Kdev, self._factor.B, False)
        x0 = self._factor(rhs, refine=False)                                     # Newton corrects it
        X = self._columns(act, C)
        lam = np.linalg.solve(X.CX, -gap - C @ x0) if C.shape[0] else np.zeros(0)
        return x0 + X.times(lam), lam

    def _factorise(self, K, G, single):
        self._factor = SaddleFactor(K, G, self.nh.D, free=self.free, reuse=self._factor, single=single,
                                    keep_zeros=True)        # the tangents' fixed pattern: one analysis
        self._cols, self._whole = {}, True

    def _columns(self, act, C) -> _Border:
        """X = K_T^-1 C^T of the last factorisation for the active candidates act (k,) (C: their rows,
        on the free DOFs), as `_Border`. Each candidate's column is solved once per factorisation,
        with its normal of then: exact right after the factorisation, and for chord and
        Newton-Krylov steps a preconditioner that still meets C du = -gap exactly (lambda comes from
        C X); its error, the normals' turn times lambda, is what the next iteration corrects. (On the
        1 mm monkey a solve of 200 columns takes 1.4 s, of one 0.04 s.) Kept within
        COLUMNS_MAX_BYTES: whole columns while they fit, else their rows at the candidates' DOFs."""
        missing = [j for j, i in enumerate(act) if i not in self._cols]
        if self._whole and (len(self._cols) + len(missing)) * len(self.free) * 8 > COLUMNS_MAX_BYTES:
            self._whole = False                  # rows from here on, for this factorisation
            self._cols = {i: x[self._at] for i, x in self._cols.items()}
        if not self._whole and (len(self._cols) + len(missing)) * len(self._at) * 8 > COLUMNS_MAX_BYTES:
            self._cols, missing = {}, list(range(len(act)))      # none kept: solved afresh
        size = max(1, min(COLUMN_BLOCK, COLUMN_BLOCK_BYTES // (8 * len(self.free))))
        for b in range(0, len(missing), size):
            block = missing[b:b + size]
            x = self._factor(C[block].T.toarray(), refine=False)
            self._cols.update(zip(act[block], (x if self._whole else x[self._at]).T.copy()))
        Y = (np.column_stack([self._cols[i] for i in act]) if len(act)
             else np.zeros((len(self.free) if self._whole else len(self._at), 0)))
        return _Border(C @ Y, Y) if self._whole else _Border(C[:, self._at] @ Y, None, self._factor, C)

    def _tangent(self, K, G):
        """x (nf,) -> K_T x on the free DOFs, K_T = K + G^T D^-1 G (K with `_bent`'s curvature)."""
        free, D = self.free, self.nh.D
        whole = np.zeros(self.model.ndof)

        def apply(x):
            whole[free] = x
            return (K @ whole + G.T @ ((G @ whole) / D))[free]
        return apply

    def _krylov(self, tangent, C, rhs, gap, act, target, eta_force=0.0):
        """(du (nf,), lambda (k,), GMRES iterations) solving `_solve`'s system with the tangent
        `tangent` (`_tangent`) by GMRES on the last factorisation, or None when the
        force rows' residual is not below `target` [N], or eta_force times the contact forces'
        change C^T lambda of the first iterate, within KRYLOV_MAX iterations. Right-
        preconditioned by the bordered solve with that older tangent and started from its chord
        step: that preconditioner meets the constraint rows exactly, so GMRES iterates on the
        force rows alone (r = rhs - K_T du + C^T lambda)."""
        F = self._factor
        X = self._columns(act, C)
        S = sla.lu_factor(X.CX) if C.shape[0] else None

        def bordered(x, g):                      # (du, lambda) of the old tangent's system, x = K_old^-1 b
            if S is None:
                return x, np.zeros(0)
            lam = sla.lu_solve(S, -g - C @ x)
            return x + X.times(lam), lam

        du, lam = bordered(F(rhs, refine=False), gap)
        r = rhs - tangent(du) + C.T @ lam
        beta = float(np.linalg.norm(r))
        target = max(target, eta_force * float(np.linalg.norm(C.T @ lam)))
        if beta <= target:
            return du, lam, 0
        V, Z, H = [r / beta], [], np.zeros((KRYLOV_MAX + 1, KRYLOV_MAX))
        for j in range(KRYLOV_MAX):              # Arnoldi, modified Gram-Schmidt
            Z.append(bordered(F(V[j], refine=False), np.zeros(len(gap))))
            w = tangent(Z[j][0]) - C.T @ Z[j][1]
            for i in range(j + 1):
                H[i, j] = w @ V[i]
                w = w - H[i, j] * V[i]
            H[j + 1, j] = np.linalg.norm(w)
            e = np.zeros(j + 2)
            e[0] = beta
            y = np.linalg.lstsq(H[:j + 2, :j + 1], e, rcond=None)[0]
            if np.linalg.norm(e - H[:j + 2, :j + 1] @ y) <= target:
                return du + sum(c * z[0] for c, z in zip(y, Z)), lam + sum(c * z[1] for c, z in zip(y, Z)), j + 1
            if H[j + 1, j] == 0:
                break
            V.append(w / H[j + 1, j])
        return None

    def _bent(self, K, act, lam, n, curv, straight):
        """K with the contact curvature -lambda k (I - n n^T - t t^T) added on the active nodes' DOF
        blocks, in place (K's pattern, which holds every node's own block, is kept)."""
        dim = self.model.dim
        bent = act[(lam[act] > 0) & (curv[act] != 0)]
        nn, tt = n[bent, :dim], straight[bent, :dim]
        H = -(lam[bent] * curv[bent])[:, None, None] * (np.eye(dim) - nn[:, :, None] * nn[:, None, :]
                                                        - tt[:, :, None] * tt[:, None, :])
        K.data[_positions(K, self.dofs[bent])] += H.ravel()
        return K

    def _newton(self, u, lam, surf, travel, tol=None):
        """(u, lambda (m,), iterations) at one travel, from the last state (module notes); tol: the
        relative residual to reach (default `tol`)."""
        dim, m = self.model.dim, len(self.dofs)
        tol = self.tol if tol is None else tol
        u, lam = u.copy(), lam.copy()
        g = surf.distance(self._positions(u), travel)[0]
        active = (lam > 0) | (g < -self.tol_mm)
        last, best, since, chord, fresh = math.inf, math.inf, 0, False, False
        for it in range(MAX_ITER):
            g, n, curv, straight = surf.distance(self._positions(u), travel)
            act = np.flatnonzero(active)
            f, K, G = self.nh.tangent(u) if it == 0 else (self.nh.internal_force(u), None, None)  # it 0 factorises
            C = sp.csr_matrix((n[act, :dim].ravel(), (np.repeat(np.arange(len(act)), dim), self.dofs[act].ravel())),
                              shape=(len(act), self.model.ndof))
            r = f - C.T @ lam[act]
            fr, Cf = r[self.free], C[:, self.free]
            scale = max(float(np.abs(lam).sum()), 1e-300)
            norm = float(np.linalg.norm(fr))
            # round-off reached (a chord step's slow contraction is its old tangent's, not round-off)
            floor = it > 1 and not chord and norm > 0.5 * last and norm <= 1e-6 * scale
            feasible = (np.all(np.abs(g[act]) <= self.tol_mm) and np.all(lam[act] >= 0)
                        and np.all(g[~active] >= -self.tol_mm))
            if it > 0 and feasible and (norm <= tol * scale or floor):
                return u, np.where(active, lam, 0.0), it
            # keep the last factorisation while it contracts well, or will reach tol within FINISH more
            # steps; only its own tangent's (after a Newton-Krylov step it is an older tangent's)
            rate = norm / last if it > 0 and last > 0 else math.inf
            chord = fresh and (rate <= CHORD or (rate < 0.5 and rate ** FINISH * norm <= tol * scale))
            last = norm
            if it > 0:                  # the first residual is the last converged state's
                best, since = (norm, 0) if norm < best else (best, since + 1)
                if since >= PATIENCE:
                    raise RuntimeError(f"finite contact: no progress in {PATIENCE} Newton iterations "
                                       f"(residual {norm:.2e}, at best {best:.2e})")
            solved = None
            if chord:
                K = G = None
            else:
                if K is None:
                    _, K, G = self.nh.tangent(u)
                K = self._bent(K, act, lam, n, curv, straight)
                if self.krylov and self._factor is not None and not self._stale:
                    solved = self._krylov(self._tangent(K, G), Cf, -fr, g[act], act, ETA * norm)
                    self._stale = solved is not None and solved[2] > KRYLOV_STALE
            if solved is None:
                du, dlam = self._solve(K, G, Cf, -fr, g[act], act, ETA * norm)
                self._stale = self._stale and chord
            else:
                du, dlam = solved[:2]
            new_lam = lam[act] + dlam           # increments: with approximate columns the fixed point stays exact
            fresh = solved is None
            alpha = 1.0
            for _ in range(6):                     # no inverted element
                trial = u.copy()
                trial[self.free] += alpha * du
                if self.nh.jacobian(trial).min() > 0:
                    break
                alpha /= 2
            else:
                raise FloatingPointError("inverted element (J <= 0)")
            u = trial
            lam = np.zeros(m)
            lam[act] = new_lam
            g_new = surf.distance(self._positions(u), travel)[0]
            leaving = active & (lam < 0)
            joining = ~active & (g_new < -self.tol_mm)
            active = (active & ~leaving) | joining
            lam[~active] = 0.0
        raise RuntimeError(f"finite contact: Newton did not converge in {MAX_ITER} iterations")
