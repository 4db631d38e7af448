"""Large deformation: geometrically nonlinear, nearly incompressible neo-Hookean solids in 2D plane
strain, Newton's method with load stepping (thesis 6.2.1 used a large-displacement formulation
for the 2 mm line load). Prescribed displacements only (the thesis indented by prescribing the
displacement of the nodes under the wedge); frictionless contact is not part of this solver.

Units mm, N (per mm of thickness), MPa.

Material and formulation
------------------------
Per layer (mu, lambda from the model's material), with the plane-strain deformation gradient F
(2 x 2; F_33 = 1), J = det F, I1 = tr(F^T F):

    W(F, p) = mu / 2 (I1 / J - 2)  +  p (J - 1)  -  p^2 / (2 kappa),     kappa = lambda + mu

the isochoric part in the 2D split (the deviator of the linear solver); at J = 1 it equals the
3D neo-Hookean mu / 2 (I1 + 1 - 3) with F_33 = 1, and it linearises to the solver's
2 mu dev eps : dev eps + kappa (tr eps)^2. Mixed u-p: quadratic (P2) displacement and the linear
solver's pressure space (P1, continuous within a layer, discontinuous across layers) with the
same 1 / kappa-weighted lumped mass D, so that the pressure is explicit, p = D^-1 g(u) with
g_i = int q_i (J - 1), and the small-strain limit is exactly `fem.solver.Model`'s discretisation
(no locking as nu -> 0.5, for the same reason). Newton's tangent is exact:

    K = K_iso + K_p + G^T D^-1 G,   G_ij = int q_i J F^-T : grad phi_j

solved as the sparse symmetric saddle system [[K_iso + K_p, G^T], [G, -D]]. Load steps scale all
prescribed displacements; Newton steps are backtracked (halved up to 6 times) when they do not
lower the residual or invert an element; a load step whose Newton iteration fails (J <= 0 at a
quadrature point, or no convergence) is halved.

    nl = NeoHookean2D(model)                           # fem.solver.Model, 2D
    res = nl.solve({"fixed": 0.0, "load": (None, -2.0)}, steps=8)
    res.u[-1], res.history[-1] (residual norms of the last step's Newton iterations)
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from reconstruct.errors import InputError


def _sparse_solve(A, b):
    """Solve A x = b (A sparse, symmetric indefinite saddle) with one step of iterative refinement:
    the bone is 1e5 times stiffer than the soft layers, and without refinement the solve's error
    floors Newton's residual decrease at ~1e-7 of the reactions."""
    A = A.tocsr()
    try:
        from pypardiso import PyPardisoSolver
    except ImportError:
        from scipy.sparse.linalg import splu

        lu = splu(A.tocsc())
        x = lu.solve(b)
        return x + lu.solve(b - A @ x)
    upper = sp.triu(A, format="csr")                 # PARDISO symmetric indefinite reads the upper part
    solver = PyPardisoSolver(mtype=-2)
    try:
        solver.factorize(upper)
        x = solver.solve(upper, b)
        return x + solver.solve(upper, b - A @ x)
    finally:
        solver.free_memory(everything=True)


@dataclass
class NonlinearResult:
    """Converged load steps: load factors t (k,), displacements u (k, ndof) [mm], reaction
    nodal forces (k, ndof) [N/mm] (internal force on every DOF; on constrained DOFs the reaction),
    Newton residual norm histories per step, step cuts taken."""
    t: np.ndarray
    u: np.ndarray
    reaction: np.ndarray
    history: list = field(default_factory=list)
    cuts: int = 0


class NeoHookean2D:
    """Nearly incompressible neo-Hookean plane strain on a 2D `fem.solver.Model` (same mesh,
    layers, materials, regions and pressure space)."""

    def __init__(self, model):
        from skfem import Basis, ElementTriP2

        if model.dim != 2:
            raise InputError("the large-deformation solver handles 2D plane-strain models only (3D is not "
                             "implemented): mesh a cross-section with `pipeline.py mesh --section-z`")
        self.model = model
        self.rigid = np.isin(model.layer, list(model.material.rigid))
        scalar = Basis(model.mesh, ElementTriP2(), intorder=2)
        self.grad = np.array([scalar.basis[a][0].grad for a in range(scalar.Nbfun)])   # (nb, 2, M, nq)
        self.dx = scalar.dx                                                              # (M, nq)
        # the linear solver's layer-discontinuous P1 pressure basis and lumped 1/kappa mass (same
        # element order and quadrature): its small-strain limit is then Model's discretisation
        pb = model.pressure_basis
        self.q = np.array([np.asarray(pb.basis[c][0]) for c in range(pb.Nbfun)])              # (3, M, nq)
        self.pdofs = pb.element_dofs                                                      # (3, M)
        self.D = model.pressure_compliance
        self.udofs = model.basis.element_dofs                                             # (nb*2, M)
        self.mu = model.mu[:, None]
        self.ndof, self.np_ = model.ndof, pb.N

    # ------------------------------------------------------------------ kinematics and assembly
    def deformation_gradient(self, u) -> np.ndarray:
        """(2, 2, M, nq) F = I + grad u at the quadrature points."""
        ue = u[self.udofs].reshape(len(self.grad), 2, -1)                                # (nb, 2, M)
        H = np.einsum("aie,ajeq->ijeq", ue, self.grad)
        return H + np.eye(2)[:, :, None, None]

    def _local(self, u, tangent=True):
        F = self.deformation_gradient(u)
        J = F[0, 0] * F[1, 1] - F[0, 1] * F[1, 0]
        if np.any(J <= 0):
            raise FloatingPointError("inverted element (J <= 0)")
        FiT = np.stack([np.stack([F[1, 1], -F[1, 0]]), np.stack([-F[0, 1], F[0, 0]])]) / J   # F^-T
        I1 = np.einsum("ijeq,ijeq->eq", F, F)
        mu = self.mu / J
        g = np.einsum("ceq,eq->ce", self.q, self.dx * (J - 1.0))                           # (3, M)
        p_nodes = np.bincount(self.pdofs.ravel(), g.ravel(), minlength=self.np_) / self.D
        p = np.einsum("ceq,ce->eq", self.q, p_nodes[self.pdofs])                           # at qp
        P = mu * (F - 0.5 * I1 * FiT) + p * J * FiT                                        # (2, 2, M, nq)
        r = np.einsum("iJeq,aJeq,eq->aie", P, self.grad, self.dx)                          # (nb, 2, M)
        if not tangent:
            return r, None, None, p_nodes, J
        d = np.eye(2)
        A = (mu * (np.einsum("ik,JL->iJkL", d, d)[..., None, None]
                   - np.einsum("iJeq,kLeq->iJkLeq", F, FiT) - np.einsum("iJeq,kLeq->iJkLeq", FiT, F)
                   + 0.5 * I1 * (np.einsum("iJeq,kLeq->iJkLeq", FiT, FiT)
                                 + np.einsum("iLeq,kJeq->iJkLeq", FiT, FiT)))
             + p * J * (np.einsum("kLeq,iJeq->iJkLeq", FiT, FiT) - np.einsum("iLeq,kJeq->iJkLeq", FiT, FiT)))
        k = np.einsum("iJkLeq,aJeq,bLeq,eq->eaibk", A, self.grad, self.grad, self.dx)      # (M, nb, 2, nb, 2)
        G = np.einsum("ceq,kLeq,bLeq,eq->ecbk", self.q, J * FiT, self.grad, self.dx)       # (M, 3, nb, 2)
        return r, k, G, p_nodes, J

    def internal_force(self, u) -> np.ndarray:
        """(ndof,) internal nodal forces [N/mm] of displacement u (the residual with no load)."""
        r = self._local(u, tangent=False)[0]
        return np.bincount(self.udofs.ravel(), r.reshape(-1, r.shape[-1]).ravel(), minlength=self.ndof)

    def tangent(self, u):
        """(internal force (ndof,), saddle matrix ((ndof + npressure)^2) of the exact tangent)."""
        r, k, G, _, _ = self._local(u)
        M, nb = k.shape[0], k.shape[1]
        dofs = self.udofs.T                                                                 # (M, nb*2)
        n = nb * 2
        K = sp.csr_matrix((k.reshape(M, -1).ravel(), (np.repeat(dofs, n, axis=1).ravel(),
                                                      np.tile(dofs, (1, n)).ravel())), shape=(self.ndof,) * 2)
        Gm = sp.csr_matrix((G.reshape(M, -1).ravel(), (np.repeat(self.pdofs.T, n, axis=1).ravel(),
                                                        np.tile(dofs, (1, 3)).ravel())), shape=(self.np_, self.ndof))
        f = np.bincount(self.udofs.ravel(), r.reshape(-1, M).ravel(), minlength=self.ndof)
        return f, K, Gm

    # ------------------------------------------------------------------ Newton with load stepping
    def solve(self, prescribed, steps: int = 4, tol: float = 1e-10, max_iter: int = 25,
              max_cuts: int = 8, loads=None) -> NonlinearResult:
        """Prescribed displacements (as `Model.system`: region -> value) applied in `steps` equal
        load steps (halved on failure, at most max_cuts times). tol: Newton stops when the free
        residual norm is below tol times the norm of the first step's initial residual.
        loads: optional (ndof,) fixed nodal forces [N/mm] scaled with the load factor too."""
        system = self.model.system(prescribed)
        fixed, values = system.fixed, system.values
        rigid = np.unique(self.udofs[:, self.rigid]) if self.rigid.any() else np.zeros(0, int)
        free = np.setdiff1d(np.arange(self.ndof), np.union1d(fixed, rigid))
        ext = np.zeros(self.ndof) if loads is None else np.asarray(loads, float)
        u = np.zeros(self.ndof)
        out_t, out_u, out_f, hist = [0.0], [u.copy()], [np.zeros(self.ndof)], [[]]
        t, dt, cuts, scale = 0.0, 1.0 / steps, 0, None
        while t < 1.0 - 1e-12:
            t_new = min(1.0, t + dt)
            try:
                trial, h, scale = self._newton(u, fixed, (t_new - t) * values, free, t_new * ext, tol,
                                               max_iter, scale)
            except (FloatingPointError, RuntimeError) as exc:
                cuts += 1
                if cuts > max_cuts:
                    raise RuntimeError(f"large-deformation solve failed at load factor {t_new:.4g} after "
                                       f"{max_cuts} step cuts ({exc}); use more steps or a finer mesh") from None
                dt /= 2
                continue
            t, u = t_new, trial
            out_t.append(t)
            out_u.append(u.copy())
            out_f.append(self.internal_force(u))
            hist.append(h)
        return NonlinearResult(np.array(out_t), np.array(out_u), np.array(out_f), hist, cuts)

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

    def _newton(self, u, fixed, dfix, free, ext, tol, max_iter, scale):
        """Newton from the last converged u; the first iteration moves the prescribed DOFs by dfix
        with the consistent tangent predictor (the free DOFs follow), so that the loaded nodes
        never run ahead of their neighbours."""
        hist, u = [], u.copy()
        for it in range(max_iter):
            f, K, G = self.tangent(u)
            r = (f - ext)[free]
            norm = float(np.linalg.norm(r))
            if it > 0:
                scale = max(float(np.linalg.norm(f[fixed])), float(np.linalg.norm(ext)), 1e-300)
                hist.append(norm)
                stalled = len(hist) > 1 and norm > 0.5 * hist[-2] and norm <= 1e-6 * scale   # round-off floor
                if norm <= tol * scale or stalled:
                    return u, hist, scale
            Gf = G[:, free]
            A = sp.bmat([[K[free][:, free], Gf.T], [Gf, -sp.diags(self.D)]], format="csr")
            rhs_u, rhs_p = -r, np.zeros(len(self.D))
            if it == 0:
                rhs_u = rhs_u - K[free][:, fixed] @ dfix
                rhs_p = -(G[:, fixed] @ dfix)
            du = _sparse_solve(A, np.concatenate([rhs_u, rhs_p]))[:len(free)]
            if not np.all(np.isfinite(du)):
                raise RuntimeError("singular tangent")
            if it == 0:
                u[fixed] += dfix
                u[free] += du
                continue
            u = self._line_search(u, du, free, ext, norm)
        raise RuntimeError(f"Newton did not converge in {max_iter} iterations (residual {hist[-1]:.2e})")


# --------------------------------------------------------------------------- line load: nonlinear vs linear
@dataclass
class LineLoadComparison:
    """Linear and large-deformation solutions of a 2D section whose surface nodes within
    half_width_mm of the load line are pushed down (approach -y) by each depth, sideways free.

    Per depth (k,): force_linear_N / force_nonlinear_N [N/mm]; surface nodes' undeformed x
    distance_mm (n,) from the load line and deflection (k, n) [mm, into the body +];
    max_difference (k,) = max |nonlinear - linear| surface deflection / depth; newton: residual
    histories of the last load step per depth; failed: {depth: message} where the nonlinear solve
    could not reach the depth."""
    depths_mm: np.ndarray
    distance_mm: np.ndarray
    deflection_linear_mm: np.ndarray
    deflection_nonlinear_mm: np.ndarray
    force_linear_N: np.ndarray
    force_nonlinear_N: np.ndarray
    max_difference: np.ndarray
    newton: list
    failed: dict


def line_load_model(model_dir, material=None, nu=None, position_x_mm=None, half_width_mm: float = 0.0):
    """(fem.solver.Model with a 'load' region, load x [mm]) for a 2D model folder: the surface
    vertices within half_width_mm of x = position (default the section's centroid x; at least
    the nearest vertex) form the loaded patch."""
    import json
    from pathlib import Path

    from fem.solver import Model

    folder = Path(model_dir)
    info = json.loads((folder / "model.json").read_text()) if (folder / "model.json").is_file() else {}
    if not (folder / "mesh.vtu").is_file():
        raise InputError(f"no mesh.vtu in '{model_dir}': run `pipeline.py mesh` first")
    t = Model.from_mesh(folder / "mesh.vtu", material=material or info.get("material", "m33338"),
                        nu=info.get("nu", 0.48) if nu is None else nu)
    if t.dim != 2:
        raise InputError("the large-deformation solver handles 2D plane-strain models only (3D is not "
                         "implemented): mesh a cross-section with `pipeline.py mesh --section-z`")
    x0 = info.get("params", {}).get("centroid_mm", [0.0])[0] if position_x_mm is None else float(position_x_mm)
    sn = t.surface_nodes("surface")
    verts = sn.nodes[sn.nodes < t.mesh.nvertices]
    dist = np.abs(t.mesh.p[0, verts] - x0)
    load = verts[dist <= max(half_width_mm, dist.min() + 1e-9)]
    model = Model(t.mesh.p.T, t.mesh.t.T, t.layer, {**t.regions, "load": load}, material=t.material)
    return model, x0


def compare_line_load(model_dir, depths_mm=(0.05, 0.5, 1.0), material=None, nu=None, half_width_mm=0.0,
                      step_mm: float = 0.1, position_x_mm=None) -> LineLoadComparison:
    """Linear vs large-deformation surface deflection and force under a prescribed line load."""
    model, x0 = line_load_model(model_dir, material, nu, position_x_mm, half_width_mm)
    nl = NeoHookean2D(model)
    sn = model.surface_nodes("surface")
    order = np.argsort(sn.x[:, 0])
    ydofs, xs = sn.dofs[order, 1], sn.x[order, 0]
    load = model.node_dofs(model.region_nodes("load"))[:, 1]
    lin, non, fl, fn, diff, newton, failed = [], [], [], [], [], [], {}
    for depth in depths_mm:
        pres = {"fixed": 0.0, "load": (None, -float(depth))}
        ul = model.system(pres).u0
        lin.append(-ul[ydofs])
        fl.append(-float((model.K @ ul)[load].sum()))
        try:
            res = nl.solve(pres, steps=max(1, int(np.ceil(depth / step_mm - 1e-9))))
        except RuntimeError as exc:
            failed[float(depth)] = str(exc)
            non.append(np.full(len(xs), np.nan))
            fn.append(np.nan)
            diff.append(np.nan)
            newton.append([])
            continue
        non.append(-res.u[-1][ydofs])
        fn.append(-float(res.reaction[-1][load].sum()))
        diff.append(float(np.abs(non[-1] - lin[-1]).max() / depth))
        newton.append(res.history[-1])
    return LineLoadComparison(np.asarray(depths_mm, float), xs - x0, np.array(lin), np.array(non), np.array(fl),
                              np.array(fn), np.array(diff), newton, failed)
