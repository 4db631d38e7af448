"""Large deformation: geometrically nonlinear, nearly incompressible neo-Hookean solids in 3D
(tetrahedra) and 2D plane strain, Newton's method with adaptive load stepping (thesis 6.2.1 used a
large-displacement formulation for the 2 mm line load). Prescribed displacements only (the thesis
indented by prescribing the displacement of the nodes under the wedge); frictionless contact is
not part of this solver.

Units mm, N (2D: per mm of thickness), MPa.

Material and formulation
------------------------
Per layer (mu, lambda from the model's material), in d = 2 or 3 dimensions with the deformation
gradient F (d x d; plane strain F_33 = 1), J = det F, I1 = tr(F^T F):

    W(F, p) = mu / 2 (J^(-2/d) I1 - d)  +  p (J - 1)  -  p^2 / (2 kappa),     kappa = lambda + 2 mu / d

the isochoric part in the d-dimensional split of the linear solver (2D: mu / 2 (I1 / J - 2), at
J = 1 the 3D neo-Hookean with F_33 = 1); it linearises to the solver's 2 mu dev_d eps : dev_d eps
+ kappa (tr eps)^2. Mixed u-p: quadratic (P2) displacement and the linear solver's pressure space
(P1, continuous within a layer, discontinuous across layers) with the same 1 / kappa-weighted
lumped mass D, so that the pressure is explicit, p = D^-1 g(u) with g_i = int q_i (J - 1), and the
small-strain limit is exactly `fem.core.model.Model`'s discretisation (no locking as nu -> 0.5, for the
same reason). First Piola stress and exact tangent (c = mu J^(-2/d)):

    P = c (F - I1 / d F^-T) + p J F^-T
    dP/dF = c [I - 2/d (F (x) F^-T + F^-T (x) F) + 2 I1 / d^2 F^-T (x) F^-T + I1 / d F^-T (x)' F^-T]
            + p J [F^-T (x) F^-T - F^-T (x)' F^-T]                  ((A (x)' B)_iJkL = A_iL B_kJ)
    K = K_F + G^T D^-1 G,   G_ij = int q_i J F^-T : grad phi_j

solved as the sparse symmetric saddle system [[K_F, G^T], [G, -D]] (MKL PARDISO LDL^T through
pypardiso, one step of iterative refinement; SciPy SuperLU without pypardiso). Load steps scale
all prescribed displacements; the first Newton iteration of a step moves the prescribed DOFs with
the tangent predictor; later iterations are backtracked (halved up to 6 times) when they do not lower
the residual or would invert an element. A load step whose Newton iteration fails (J <= 0 at a
quadrature point, no convergence in max_iter, or a residual that has not halved in STAGNATION
iterations) is halved, up to max_cuts times below the first step size; after two steps that
converge in at most 6 iterations the step grows back (x 2, at most the first size).

    nl = NeoHookean(model)                            # fem.core.model.Model, 2D or 3D
    res = nl.solve({"fixed": 0.0, "load": (0.0, -2.0)}, steps=20)
    res.u[-1], res.reaction[-1], res.history[-1], res.min_J
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from fem.core.linalg import solve_refined
from fem.core.materials import FLUID_LAYER
from fingertip.errors import InputError
from fingertip.progress import as_progress

STAGNATION = 8
"""Newton iterations without the residual halving its best value after which a load step is cut:
converging steps on the monkey section reach the tolerance in at most 9 iterations with at most 4
between halvings, while steps that fail plateau from their second or third iteration on."""


@dataclass
class NonlinearResult:
    """Converged load steps: load factors t (k,), displacements u (k, ndof) [mm], reaction
    nodal forces (k, ndof) [N; N/mm in 2D] (internal force on every DOF; on constrained DOFs the
    reaction), smallest J at any quadrature point per step min_J (k,), Newton residual norm
    histories per step, step cuts taken; stopped: why the solve ended before load factor 1
    (None when it got there)."""
    t: np.ndarray
    u: np.ndarray
    reaction: np.ndarray
    min_J: np.ndarray
    seconds: np.ndarray
    history: list = field(default_factory=list)
    cuts: int = 0
    stopped: str | None = None


NO_FLUID_CORE = ("the large-deformation solver has no fluid core (layer 6); "
                 "use the linear solver for the solid-fluid models")


class NeoHookean:
    """Nearly incompressible neo-Hookean solid on a `fem.core.model.Model` (3D tetrahedra or 2D plane
    strain; same mesh, layers, materials, regions and pressure space). Element work is done in
    chunks of `chunk` elements (the 3D tangent holds 900 numbers per element: 0.12 GB a chunk, a few
    times over while it is formed). Each chunk's sum into the tangent passes over all of its
    entries, so larger chunks pay on large models: the human 0.5 mm model's tangent (72,577
    tetrahedra) in 1.17 s with 16,000 against 1.44 s with 4,000; the 1 mm monkey's 0.23 s either way."""
    def __init__(self, model, chunk: int = 16000):
        if (model.layer == FLUID_LAYER).any():
            raise InputError(NO_FLUID_CORE)
        self.model, self.dim, self.chunk = model, model.dim, int(chunk)
        self.grad = model.shape_gradients().transpose(2, 3, 0, 1)                             # (M, nq, nb, d)
        self.dx = model.scalar_basis.dx                                                       # (M, nq)
        # the linear solver's layer-discontinuous P1 pressure basis and lumped 1/kappa mass (same
        # element order and quadrature): its small-strain limit is then Model's discretisation
        pb = model.pressure_basis
        self.q = np.array([np.asarray(pb.basis[c][0]) for c in range(pb.Nbfun)]).transpose(1, 2, 0)  # (M, nq, nc)
        self.pdofs = pb.element_dofs.T                                                        # (M, nc)
        self.D = model.pressure_compliance
        self.udofs = model.element_dofs.T                                               # (M, nb*d)
        self.mu = model.mu
        self.ndof, self.npres = model.ndof, pb.N
        self._patterns = None                # `_scatter`

    # ------------------------------------------------------------------ kinematics and assembly
    def deformation_gradient(self, u, cells=slice(None)) -> np.ndarray:
        """(M, nq, d, d) F = I + grad u at the quadrature points of `cells`."""
        grad = self.grad[cells]
        ue = u[self.udofs[cells]].reshape(len(grad), -1, self.dim)                            # (M, nb, d)
        return np.matmul(ue.transpose(0, 2, 1)[:, None], grad) + np.eye(self.dim)

    def jacobian(self, u) -> np.ndarray:
        """(M, nq) J = det F at the quadrature points."""
        return np.concatenate([np.linalg.det(self.deformation_gradient(u, c)) for c in self._chunks()])

    def _chunks(self):
        M = len(self.dx)
        return [slice(s, min(M, s + self.chunk)) for s in range(0, M, self.chunk)]

    def pressure(self, u) -> np.ndarray:
        """(npressure,) nodal pressure [MPa], p = D^-1 g, g_c = int q_c (J - 1)."""
        g = np.zeros(self.npres)
        for c in self._chunks():
            J = np.linalg.det(self.deformation_gradient(u, c))
            g += np.bincount(self.pdofs[c].ravel(), np.einsum("eqc,eq->ec", self.q[c], self.dx[c] * (J - 1.0)).ravel(),
                             minlength=self.npres)
        return g / self.D

    def _local(self, u, p_nodes, cells, tangent):
        """Element residual (m, nb*d) and, with tangent, stiffness (m, nb*d, nb*d) and pressure
        coupling G (m, nc, nb*d) of the elements `cells`."""
        d, grad, w = self.dim, self.grad[cells], self.dx[cells]
        F = self.deformation_gradient(u, cells)
        J = np.linalg.det(F)
        if np.any(J <= 0):
            raise FloatingPointError("inverted element (J <= 0)")
        FiT = np.linalg.inv(F).transpose(0, 1, 3, 2)
        I1 = np.einsum("eqij,eqij->eq", F, F)
        c = self.mu[cells, None] * J ** (-2.0 / d)                                            # mu J^(-2/d)
        p = np.einsum("eqc,ec->eq", self.q[cells], p_nodes[self.pdofs[cells]])
        P = c[..., None, None] * (F - (I1 / d)[..., None, None] * FiT) + (p * J)[..., None, None] * FiT
        M, nb = grad.shape[0], grad.shape[2]
        r = np.einsum("eqai,eq->eai", np.matmul(grad, P.transpose(0, 1, 3, 2)), w).reshape(M, nb * d)
        if not tangent:
            return r, None, None
        X = np.matmul(grad, F.transpose(0, 1, 3, 2)).reshape(M, -1, nb * d)                   # F grad phi_a
        Y = np.matmul(grad, FiT.transpose(0, 1, 3, 2)).reshape(M, -1, nb * d)                 # F^-T grad phi_a

        def quad(weight, A, B):       # (M, m, n) sum over the quadrature points of weight A_m B_n
            return np.matmul((A * weight[..., None]).transpose(0, 2, 1), B)

        cw, pw = c * w, p * J * w
        # the rank-one terms in one product, -(2/d) cw (X Y^T + Y X^T) + (2 cw I1 / d^2 + pw) Y Y^T, then
        # two passes in place: mu J^(-2/d) grad phi_a . grad phi_b on each component, and the
        # component-swapped term ((a, i), (b, j)) <- ((a, j), (b, i))
        k = quad(np.concatenate([(-2.0 / d) * cw, (-2.0 / d) * cw, cw * 2.0 * I1 / d**2 + pw], axis=1),
                 np.concatenate([X, Y, Y], axis=1), np.concatenate([Y, X, Y], axis=1))
        k5 = k.reshape(M, nb, d, nb, d)
        gq = grad.transpose(0, 1, 3, 2).reshape(M, -1, nb)                                     # (M, nq d, nb)
        S = quad(cw.repeat(d, axis=1), gq, gq)                                                 # (M, nb, nb)
        for i in range(d):
            k5[:, :, i, :, i] += S
        k5 += quad(cw * I1 / d - pw, Y, Y).reshape(M, nb, d, nb, d).transpose(0, 1, 4, 3, 2)
        G = quad(J * w, self.q[cells], Y)                                                     # (M, nc, nb*d)
        return r, k, G

    def stored_energy(self, u) -> float:
        """Stored energy [N mm; N mm per mm in 2D] of displacement u: int mu / 2 (J^(-2/d) I1 - d)
        + p^T D p / 2 with p = D^-1 g (`pressure`): the mixed energy with the pressure eliminated,
        whose derivative is `internal_force`."""
        d, w = self.dim, 0.0
        for c in self._chunks():
            F = self.deformation_gradient(u, c)
            I1 = np.einsum("eqij,eqij->eq", F, F)
            w += float(np.sum(0.5 * self.mu[c, None] * (np.linalg.det(F) ** (-2.0 / d) * I1 - d) * self.dx[c]))
        p = self.pressure(u)
        return w + 0.5 * float(p @ (p * self.D))

    def internal_force(self, u) -> np.ndarray:
        """(ndof,) internal nodal forces [N; N/mm in 2D] of displacement u (the residual with no load)."""
        p_nodes = self.pressure(u)
        f = np.zeros(self.ndof)
        for c in self._chunks():
            f += np.bincount(self.udofs[c].ravel(), self._local(u, p_nodes, c, False)[0].ravel(), minlength=self.ndof)
        return f

    def tangent(self, u):
        """(internal force (ndof,), K (ndof^2) and G (npressure x ndof) sparse): the exact tangent
        is K + G^T D^-1 G. The element matrices are summed into the fixed CSR patterns of K and G
        (`_scatter`, built on the first call)."""
        p_nodes = self.pressure(u)
        (kp, kpos), (gp, gpos) = self._scatter()
        f, kd, gd = np.zeros(self.ndof), np.zeros(len(kp.indices)), np.zeros(len(gp.indices))
        for c, ki, gi in zip(self._chunks(), kpos, gpos):
            r, k, g = self._local(u, p_nodes, c, True)
            f += np.bincount(self.udofs[c].ravel(), r.ravel(), minlength=self.ndof)
            kd += np.bincount(ki, k.ravel(), minlength=len(kd))
            gd += np.bincount(gi, g.ravel(), minlength=len(gd))
        return (f, sp.csr_matrix((kd, kp.indices, kp.indptr), shape=kp.shape),
                sp.csr_matrix((gd, gp.indices, gp.indptr), shape=gp.shape))

    def _scatter(self):
        """((K's CSR pattern, per chunk the position in its data of each element entry, (m nb d nb d,)),
        the same for G (m nc nb d,)), built once. The DOFs are node-major (dof = d node + component,
        as the element DOFs), so the patterns follow from the node pairs (nb^2 per element instead
        of (nb d)^2): the row of a node a (K: d rows a, i; G: one, a pressure node) holds, for each
        node b coupled to it in increasing order, the columns d b ... d b + d - 1. (Measured on the
        1 mm monkey: a tangent in 0.30 s instead of 0.54 s summing per-chunk sparse matrices; the
        patterns 1.2 s once.)"""
        if self._patterns is None:
            d, nb, n_nodes = self.dim, self.udofs.shape[1] // self.dim, self.ndof // self.dim
            nodes = self.udofs[:, ::d] // d                                                    # (M, nb)
            if not np.array_equal(self.udofs.reshape(len(nodes), nb, d), d * nodes[..., None] + np.arange(d)):
                raise AssertionError("element DOFs are not node-major")
            out = []
            for rows, size, r in ((nodes, n_nodes, d), (self.pdofs, self.npres, 1)):
                keys = np.repeat(rows, nb, axis=1) * np.int64(n_nodes) + np.tile(nodes, (1, rows.shape[1]))
                pairs = np.unique(keys)
                a = pairs // n_nodes
                ptr = np.searchsorted(a, np.arange(size + 1))                      # node-pair CSR
                start = d * (r * ptr[:-1, None] + np.diff(ptr)[:, None] * np.arange(r))   # (size, r): row (a, i)
                cols = np.empty(d * r * len(pairs), dtype=np.int32)
                cols[start[a][:, :, None] + d * (np.arange(len(pairs)) - ptr[a])[:, None, None] + np.arange(d)] = \
                    (d * (pairs % n_nodes))[:, None, None] + np.arange(d)
                q = np.searchsorted(pairs, keys).reshape(len(nodes), rows.shape[1], nb)
                pos = (start[rows][:, :, :, None, None] + d * (q - ptr[rows][..., None])[:, :, None, :, None]
                       + np.arange(d)).reshape(len(nodes), -1).astype(np.int32)       # (M, rows r nb d)
                csr = sp.csr_matrix((np.zeros(len(cols)), cols, np.append(start.ravel(), d * r * ptr[-1])),
                                    shape=(size * r, self.ndof))
                out.append((csr, [pos[c].ravel() for c in self._chunks()]))
            self._patterns = tuple(out)
        return self._patterns

    # ------------------------------------------------------------------ Newton with load stepping
    def solve(self, prescribed, steps: int = 4, tol: float = 1e-10, max_iter: int = 25,
              max_cuts: int = 8, loads=None, stops=(), partial: bool = False,
              progress=None) -> NonlinearResult:
        """Prescribed displacements (as `Model.system`: region -> value) applied in `steps` equal
        load steps, adapted (see the module notes; at most max_cuts halvings below 1 / steps).
        tol: Newton stops when the free residual norm is below tol times the reaction norm.
        loads: optional (ndof,) fixed nodal forces [N] scaled with the load factor too.
        stops: load factors in (0, 1) that are landed on exactly (extra converged states).
        A solve that cannot go on raises RuntimeError, or with partial=True returns the states
        reached with the reason in `stopped`. progress: optional `fingertip.progress` object (None:
        silent) told each converged step."""
        progress = as_progress(progress)
        start = time.perf_counter()
        system = self.model.system(prescribed)
        fixed, values = system.fixed, system.values
        free = np.setdiff1d(np.arange(self.ndof), fixed)          # fixed holds rigid layers' nodes too
        ext = np.zeros(self.ndof) if loads is None else np.asarray(loads, float)
        targets = np.union1d([t for t in np.asarray(stops, float).ravel() if 1e-12 < t < 1 - 1e-12], [1.0])
        u = np.zeros(self.ndof)
        out_t, out_u, out_f, out_J, out_s, hist = [0.0], [u.copy()], [np.zeros(self.ndof)], [1.0], [0.0], [[]]
        t, dt0, cuts, easy, stopped = 0.0, 1.0 / steps, 0, 0, None
        dt = dt0
        while t < 1.0 - 1e-12:
            target = targets[np.searchsorted(targets, t + 1e-12)]
            t_new = target if t + dt >= target - 1e-12 else t + dt
            try:
                trial, h = self._newton(u, fixed, (t_new - t) * values, free, t_new * ext, tol, max_iter)
            except (FloatingPointError, RuntimeError) as exc:
                cuts += 1
                dt /= 2
                if dt < dt0 / 2 ** max_cuts:
                    J = self.jacobian(u)
                    e = int(np.argmin(J.min(axis=1)))
                    where = self.model.mesh.p[:, self.model.mesh.t[:, e]].mean(axis=1)
                    stopped = (f"large-deformation solve stopped at load factor {t:.4g} (next step {t_new:.4g}: "
                               f"{exc}); smallest J there {J.min():.3g} in layer {self.model.layer[e]} at "
                               f"{np.round(where, 3).tolist()} mm")
                    if not partial:
                        raise RuntimeError(stopped) from None
                    break
                easy = 0
                continue
            t, u = t_new, trial
            easy = easy + 1 if len(h) <= 6 else 0
            if easy >= 2 and dt < dt0:
                dt, easy = min(2 * dt, dt0), 0
            out_t.append(t)
            out_u.append(u.copy())
            out_f.append(self.internal_force(u))
            out_J.append(float(self.jacobian(u).min()))
            out_s.append(time.perf_counter() - start)
            hist.append(h)
            progress.note(f"large deformation: load factor {t:.4g}, {len(h)} Newton iterations, smallest J "
                          f"{out_J[-1]:.3g}, {out_s[-1]:.1f} s")
        return NonlinearResult(np.array(out_t), np.array(out_u), np.array(out_f), np.array(out_J), np.array(out_s),
                               hist, cuts, stopped)

    def _line_search(self, u, du, free, ext, norm, tries: int = 6):
        """The full Newton step if it lowers the residual (always, near the solution: quadratic
        convergence is kept), else the first of 1/2, 1/4, ... that does and inverts no element."""
        alpha = 1.0
        for _ in range(tries):
            trial = u.copy()
            trial[free] += alpha * du
            try:
                if np.linalg.norm((self.internal_force(trial) - ext)[free]) < norm:
                    return trial
            except FloatingPointError:
                pass
            alpha /= 2
        trial = u.copy()
        trial[free] += 2 * alpha * du          # no decrease found: take the smallest step tried
        return trial

    def _newton(self, u, fixed, dfix, free, ext, tol, max_iter):
        """Newton from the last converged u; the first iteration moves the prescribed DOFs by dfix
        with the consistent tangent predictor (the free DOFs follow), so that the loaded nodes
        never run ahead of their neighbours. Returns (u, residual norms after each iteration).
        Raises RuntimeError when the residual has not halved its best value in STAGNATION
        iterations (the step is then cut at once rather than after max_iter)."""
        hist, u = [], u.copy()
        best, since = math.inf, 0
        for it in range(max_iter):
            f, K, G = self.tangent(u)
            r = (f - ext)[free]
            norm = float(np.linalg.norm(r))
            if it > 0:
                scale = max(float(np.linalg.norm(f[fixed])), float(np.linalg.norm(ext)), 1e-300)
                hist.append(norm)
                stalled = len(hist) > 1 and norm > 0.5 * hist[-2] and norm <= 1e-6 * scale   # round-off floor
                if norm <= tol * scale or stalled:
                    return u, hist
                best, since = (norm, 0) if norm < 0.5 * best else (best, since + 1)
                if since >= STAGNATION:
                    raise RuntimeError(f"Newton stagnated: the residual did not halve in {STAGNATION} iterations "
                                       f"(residual {norm:.2e}, best {best:.2e})")
            Gf = G[:, free]
            A = sp.bmat([[K[free][:, free], Gf.T], [Gf, -sp.diags(self.D)]], format="csr")
            rhs_u, rhs_p = -r, np.zeros(len(self.D))
            if it == 0:
                rhs_u = rhs_u - K[free][:, fixed] @ dfix
                rhs_p = -(G[:, fixed] @ dfix)
            du = solve_refined(A, np.concatenate([rhs_u, rhs_p]))[:len(free)]
            if not np.all(np.isfinite(du)):
                raise RuntimeError("singular tangent")
            if it == 0:
                u[fixed] += dfix
                u[free] += du
                continue
            u = self._line_search(u, du, free, ext, norm)
        raise RuntimeError(f"Newton did not converge in {max_iter} iterations (residual {hist[-1]:.2e})")


# --------------------------------------------------------------------------- line load: nonlinear vs linear
