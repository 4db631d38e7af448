"""Fields of a solved `fem.core.model.Model` at points: point location, sparse point operators
(displacement, strain, stress) and `Solution` (a displacement field with its measures).

Strain and stress are the element's own fields (no averaging across elements), with the
formulation's assumed volumetric strain theta_bar = p / kappa from the layer-wise P1 pressure
p = D^-1 B u:

    eps_bar = dev_d eps(u) + theta_bar / d * I,      sigma = 2 mu eps_bar + lambda theta_bar I  (3x3)
"""
from __future__ import annotations

from functools import cached_property

import numpy as np
import scipy.sparse as sp

from fem.core.measures import State, evaluate
from fingertip.errors import InputError

#: strain tensor components returned by strain_operator, per space dimension
STRAIN_COMPONENTS = {3: ("xx", "yy", "zz", "yz", "xz", "xy"), 2: ("xx", "yy", "xy")}
#: stress components returned by stress_operator (plane strain has sigma_zz)
STRESS_COMPONENTS = {3: ("xx", "yy", "zz", "yz", "xz", "xy"), 2: ("xx", "yy", "zz", "xy")}
_INDEX = {"x": 0, "y": 1, "z": 2}
JACOBIAN_CHUNK = 100000
"""Elements times displacement fields per block of `centroid_jacobians` (3D: 24 MB of element
displacements a block)."""


class PointLocator:
    """Locates points (n, dim) [mm] in the elements of a mesh (a `fem.core.discretisation.
    Discretisation`) and evaluates its P2 basis there: the mesh's own, no material."""

    def __init__(self, discretisation):
        self.discretisation = discretisation
        p, t = discretisation.mesh.p.T, discretisation.mesh.t.T
        A = np.stack([p[t[:, k]] - p[t[:, 0]] for k in range(1, discretisation.dim + 1)], axis=2)
        self._p0, self._Ainv = p[t[:, 0]], np.linalg.inv(A)         # affine element maps

    def _min_barycentric(self, x, cand):
        X = np.einsum("...ij,...j->...i", self._Ainv[cand], x[:, None, :] - self._p0[cand])
        return np.minimum(1.0 - X.sum(axis=-1), X.min(axis=-1))

    def locate(self, x, layer=None) -> np.ndarray:
        """(n,) element holding each point of x (n, dim) [mm]; `layer` restricts the search.

        On an interface the element with the point deepest inside wins; give `layer` to choose.
        """
        m = self.discretisation
        pool = np.arange(m.mesh.nelements) if layer is None else np.flatnonzero(m.layer == layer)
        if len(pool) == 0:
            raise InputError(f"no elements in layer {layer}; the mesh has layers {sorted(set(m.layer))}")
        if len(x) == 0:
            return np.zeros(0, dtype=np.int64)
        from scipy.spatial import (
            cKDTree,  # scipy.spatial costs 0.1 s of import: only where points are located
        )

        centroids = m.mesh.p[:, m.mesh.t[:, pool]].mean(axis=1).T
        _, idx = cKDTree(centroids).query(x, k=min(16, len(pool)))
        cand = pool[np.asarray(idx).reshape(len(x), -1)]
        score = self._min_barycentric(x, cand)
        best = np.argmax(score, axis=1)
        cells, inside = cand[np.arange(len(x)), best], score[np.arange(len(x)), best]
        for i in np.flatnonzero(inside < -1e-9):   # rare: search every element of the pool
            s = np.concatenate([self._min_barycentric(x[i:i + 1], chunk[None])[0]
                                for chunk in np.array_split(pool, max(1, len(pool) // 100000))])
            cells[i], inside[i] = pool[np.argmax(s)], s.max()
        if np.any(inside < -1e-6):
            i = np.flatnonzero(inside < -1e-6)
            where = "the mesh" if layer is None else f"layer {layer}"
            raise InputError(f"{len(i)} sample points lie outside {where}, e.g. {x[i[0]].round(4).tolist()} mm")
        return cells

    def reference(self, x, cells) -> np.ndarray:
        """(dim, n) reference coordinates of points x (n, dim) in `cells` (n,)."""
        return np.einsum("nij,nj->in", self._Ainv[cells], x - self._p0[cells])

    def shape(self, x, cells):
        """Values (nb, dim, n) and gradients (nb, dim, dim, n) of the vector element's shape
        functions at x (function a * dim + i is the scalar P2 function a along axis i, the order
        of `Model.element_dofs`)."""
        basis, d = self.discretisation.scalar_basis, self.discretisation.dim
        X = self.reference(x, cells)[:, :, None]
        fields = [basis.elem.gbasis(basis.mapping, X, a, tind=cells)[0] for a in range(basis.Nbfun)]
        N = np.array([np.asarray(f)[..., 0] for f in fields])                   # (nb, n)
        dN = np.array([f.grad[..., 0] for f in fields])                         # (nb, d, n)
        eye = np.eye(d)[None, :, :, None]                                       # (1, i, j, 1)
        value = (eye * N[:, None, None, :]).reshape(-1, d, N.shape[1])
        grad = (eye[..., None, :] * dN[:, None, None, :, :]).reshape(-1, d, d, N.shape[1])
        return value, grad


def point_operator(m, x, cells, quantity) -> sp.csr_matrix:
    """Sparse (n * ncomp, ndof) map from u to `quantity` ("displacement", "strain" or "stress")
    at points x (n, dim) in `cells` of model m (a `fem.core.model.Model`)."""
    n, d = len(x), m.dim
    value, grad = m.locator.shape(x, cells)
    dofs = m.element_dofs[:, cells]                           # (nb, n)
    if quantity == "displacement":
        rows = (np.arange(n)[None, None] * d + np.arange(d)[None, :, None])
        rows = np.broadcast_to(rows, value.shape)
        cols = np.broadcast_to(dofs[:, None, :], value.shape)
        return sp.csr_matrix((value.ravel(), (rows.ravel(), cols.ravel())), shape=(n * d, m.ndof))
    eps = 0.5 * (grad + grad.transpose(0, 2, 1, 3))
    dev = eps - np.einsum("kiin->kn", eps)[:, None, None] / d * np.eye(d)[None, :, :, None]
    X = m.locator.reference(x, cells)
    lam = np.vstack([1.0 - X.sum(axis=0), X])                       # P1 values
    pdofs = m.pressure_basis.element_dofs[:, cells].ravel()
    P1 = sp.csr_matrix((lam.ravel(), (np.tile(np.arange(n), d + 1), pdofs)), shape=(n, m.pressure_basis.N))
    vol = (sp.diags(1.0 / (d * m.kappa[cells])) @ P1 @ m.pressure_operator).tocoo()   # theta_bar / d
    comps = [(_INDEX[c[0]], _INDEX[c[1]]) for c in STRAIN_COMPONENTS[d]]
    ncomp = len(comps)
    rows, cols, vals = [], [], []
    for c, (i, j) in enumerate(comps):
        rows.append(np.broadcast_to(np.arange(n) * ncomp + c, dofs.shape).ravel())
        cols.append(dofs.ravel())
        vals.append(dev[:, i, j].ravel())
        if i == j:
            rows.append(vol.row * ncomp + c)
            cols.append(vol.col)
            vals.append(vol.data)
    strain = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                           shape=(n * ncomp, m.ndof))
    if quantity == "strain":
        return strain
    return (hooke_matrix(m.mu[cells], m.lam[cells], d) @ strain).tocsr()


def hooke_matrix(mu_MPa, lam_MPa, dim: int) -> sp.csr_matrix:
    """Sparse (n * len(STRESS_COMPONENTS[dim]), n * len(STRAIN_COMPONENTS[dim])) map from the
    strain components of `point_operator` at n points, point-major, to their stress components
    [MPa]: stress = 2 mu eps + lam tr(eps) I, with the Lame moduli mu, lam (n,) of each point's
    element (the strain's volumetric part is the mixed formulation's, so this is its stress)."""
    out, names = STRESS_COMPONENTS[dim], STRAIN_COMPONENTS[dim]
    S = np.array([[float(a == b) for b in names] for a in out])
    T = np.outer([a[0] == a[1] for a in out], [b[0] == b[1] for b in names]).astype(float)
    M = 2 * np.asarray(mu_MPa, float)[:, None, None] * S + np.asarray(lam_MPa, float)[:, None, None] * T
    k, a, c = np.indices(M.shape)
    n, ncomp = len(M), len(names)
    return sp.csr_matrix((M.ravel(), ((k * len(out) + a).ravel(), (k * ncomp + c).ravel())),
                         shape=(n * len(out), n * ncomp))


def centroid_jacobians(m, u) -> np.ndarray:
    """det F at each element's centroid of model m (a `fem.core.model.Model`) for displacements u
    (ndof,) -> (M,), or (ndof, k) -> (M, k): F = I + grad u, the deformation gradient of linear
    kinematics (plane strain: its in-plane block). det F <= 0 where the displacement turns an
    element inside out: there a small-strain result has lost its meaning. The P2 shape gradients
    at the reference centroid are mapped by each element's affine map (no point location)."""
    U = np.asarray(u, float).reshape(m.ndof, -1)
    d, M, basis = m.dim, m.mesh.nelements, m.scalar_basis
    centre = np.full((d, 1), 1.0 / (d + 1))
    ref = np.array([np.asarray(basis.elem.lbasis(centre, a)[1])[:, 0] for a in range(basis.Nbfun)])   # (nb, d)
    A_inv = m.locator._Ainv                                                  # (M, d, d): x -> reference
    out = np.empty((M, U.shape[1]))
    for cells in np.array_split(np.arange(M), max(1, M * U.shape[1] // JACOBIAN_CHUNK)):
        ue = U[m.element_dofs[:, cells]].reshape(len(ref), d, len(cells), -1)          # (nb, d, n, k)
        grad = np.einsum("aink,al,nlj->nkij", ue, ref, A_inv[cells], optimize=True)    # grad u (n, k, d, d)
        out[cells] = np.linalg.det(np.eye(d) + grad)
    return out if np.ndim(u) > 1 else out[:, 0]


class Solution:
    """A displacement field and everything derived from it.

    u (ndof,) [mm]; f (ndof,) applied nodal forces [N]; residual: relative solve residual.
    Strain, stress and measures come from the element holding each point (never averaged).
    """

    def __init__(self, model, u: np.ndarray, f: np.ndarray | None = None, residual=float("nan")):
        self.model, self.u, self.residual = model, u, residual
        self.f = np.zeros(model.ndof) if f is None else f

    @cached_property
    def displacement_mm(self) -> np.ndarray:
        """(nnodes, dim) displacement of every P2 node (vertices first)."""
        return self.u.reshape(-1, self.model.dim)

    @cached_property
    def nodal_forces(self) -> np.ndarray:
        """(ndof,) K u [N]: applied loads on free DOFs, reactions on constrained DOFs."""
        return self.model.K @ self.u

    def force(self, region) -> np.ndarray:
        """(dim,) resultant force [N] on the body through a region's nodes (load or reaction)."""
        return self.nodal_forces[self.model.node_dofs(self.model.region_nodes(region))].sum(axis=0)

    @property
    def energy(self) -> float:
        """Strain energy u.K.u / 2 [N mm = mJ] (2D: per mm of thickness)."""
        return 0.5 * float(self.u @ self.nodal_forces)

    def _state(self, x, cells):
        """State at points x (n, dim) in `cells`: the same fields as the operators, evaluated
        directly from the element DOFs (no sparse matrices: fast for all element centroids)."""
        m, d, n = self.model, self.model.dim, len(x)
        at = m.locator
        value, grad = at.shape(x, cells)                                  # (nb, d, n), (nb, d, d, n)
        ue = self.u[m.element_dofs[:, cells]]                       # (nb, n)
        disp = np.zeros((n, 3))
        disp[:, :d] = np.einsum("kin,kn->ni", value, ue)
        g = np.einsum("kijn,kn->nij", grad, ue)
        eps = 0.5 * (g + g.transpose(0, 2, 1))
        X = at.reference(x, cells)
        p1 = np.vstack([1.0 - X.sum(axis=0), X])                          # P1 pressure shape values
        p = (m.pressure_operator @ self.u)[m.pressure_basis.element_dofs[:, cells]]
        theta_bar = (p1 * p).sum(axis=0) / m.kappa[cells]
        eps += ((theta_bar - np.trace(eps, axis1=1, axis2=2)) / d)[:, None, None] * np.eye(d)
        strain = np.zeros((n, 3, 3))
        strain[:, :d, :d] = eps
        stress = 2 * m.mu[cells, None, None] * strain + (m.lam[cells] * theta_bar)[:, None, None] * np.eye(3)
        return State(disp, strain, stress)

    def fields(self, points, names=None, layer=None) -> dict[str, np.ndarray]:
        """{measure name: (n,) values} at points (n, dim or 3) [mm]; all measures if names is None.

        Also 'element' and 'layer' (n,) of the element that holds each point."""
        x = np.atleast_2d(np.asarray(points, dtype=float))[:, :self.model.dim]
        cells = self.model.locate(x, layer)
        return {"element": cells, "layer": self.model.layer[cells], **evaluate(names, self._state(x, cells))}

    def sample(self, name: str, points, layer=None) -> np.ndarray:
        """(n,) values of one measure (see fem.core.measures.MEASURES) at points [mm]."""
        return self.fields(points, [name], layer)[name]

    @cached_property
    def element_fields(self) -> dict[str, np.ndarray]:
        """{measure name: (M,) value at each element's centroid}."""
        m = self.model
        cells = np.arange(m.mesh.nelements)
        x = m.mesh.p[:, m.mesh.t].mean(axis=1).T
        return evaluate(None, self._state(x, cells))
