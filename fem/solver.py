"""Static, locking-free linear elasticity on layered P2 meshes: 3D tetrahedra and 2D plane strain.

Units: mm, N, MPa. In 2D (plane strain, x-y plane) forces and tractions are per mm of thickness.

Formulation
-----------
Quadratic (P2) displacements with a linear (P1) pressure that is continuous inside a layer and
discontinuous across layers (Taylor-Hood per layer), the pressure condensed with a lumped
(1 / kappa)-weighted mass D. With d the space dimension, kappa = lambda + 2 mu / d,
p = D^-1 B u (B_i u = int q_i div u) and theta_bar = p / kappa the assumed volumetric strain:

    a(u, v) = int 2 mu dev_d eps(u) : dev_d eps(v)  +  (B u)^T D^-1 (B v),   dev_d e = e - tr(e) / d I
    eps_bar = dev_d eps(u) + theta_bar / d * I,      sigma = 2 mu eps_bar + lambda theta_bar I  (3x3)

In plane strain eps_zz = 0 and sigma_zz = lambda theta_bar. As nu -> 0.5 this tends to the
inf-sup stable Taylor-Hood constraint B u = 0, so it does not lock; it is symmetric positive
definite. Measured on the Lame sphere at nu = 0.4999 (9k DOFs): displacement 0.3 %, mean stress
1.6 % max error. Rejected: plain P2 (locks: 50 % stress error at nu = 0.4999, DESIGN.md) and P2
with an element-constant condensed pressure (P2-P0), which gave accurate displacements but a mean
stress that did not converge in 3D (24 % rms on the same sphere at nu = 0.4999, measured).
The condensed K has ~7x the non-zeros of K_dev, so K is kept as an operator and the sparse
quasi-definite matrix [[K_dev, B^T], [B, -D]] is factorised (MKL PARDISO LDL^T via pypardiso;
SciPy SuperLU fallback, slow, with a warning) and re-solved for new right-hand sides. Strain,
stress and every measure are the element's own fields, evaluated in the element that holds
the point; the pressure never couples across a layer interface.

User API
--------
    model = Model.from_mesh("mesh.vtu", material="m43338", nu=0.48)      # or Model(points, cells, layer, regions)
    sol = model.solve(prescribed={"nail": 0.0, "support": (None, 0.0, None), "pad": (0, -1.0, 0)},
                      pressures={"inner": 0.01}, tractions=..., forces=..., point_forces=...)
    sol.sample("sed_MPa", points)   # fem.measures.MEASURES lists every name
    sol.save("static.vtu", points=receptors)   # tetra10/triangle6 VTU + CSV of samples

Prescribed values per region: a scalar (all components), a tuple with None for free components,
an (n_region_vertices, dim) array (midside nodes take the mean of their edge's two vertices), or a
callable x (n, dim) -> (n, dim) over all region nodes (NaN = free).

Stable API for the contact solver (issue 5)
-------------------------------------------
    system = model.system(prescribed={...})   # LinearSystem; factorisation cached per constrained-DOF set
    system.u0                  # (ndof,) response to the prescribed displacements alone
    system.solve(f)            # f (ndof,) or (ndof, k) nodal forces [N] -> u, same shape, u = 0 on
                               # constrained DOFs; loads on constrained DOFs are ignored
    system = model.system(prescribed, condense=(nodes, direction))     # + exact compliance block:
    system.compliance(nodes, direction)        # (k, k) [mm/N] along direction, no solves (Schur
                               # complement from PARDISO, inverted once; rotated DOFs off the axes)
    u = system.u0 + system.solve(f)            # superposition; system.residual = last relative residual
    model.vertex_dofs(ids) -> (n, dim) int     # DOF indices of mesh vertices (node k has DOFs dim*k + c)
    model.node_dofs(nodes) -> (n, dim) int     # same for any P2 node (vertices first, then midside nodes)
    model.surface_nodes(region, midside=True) -> SurfaceNodes(nodes, dofs, x, normal, area)
                               # outward unit normals and tributary areas [mm^2] (2D: lengths [mm])
    model.strain_operator(points, layer=None)  # sparse (n_points * ncomp, ndof); ncomp 6 (3D:
                               # xx, yy, zz, yz, xz, xy tensor components) or 3 (2D: xx, yy, xy)
    model.stress_operator(points, layer=None)  # sparse (n_points * 6, ndof) [MPa]; 2D: xx, yy, zz, xy (4)
    model.displacement_operator(points)        # sparse (n_points * dim, ndof)
    model.solution(u, f=None) -> Solution      # fields, measures, sample, save for any u
    model.load_vector(tractions=..., pressures=..., forces=..., point_forces=...) -> (ndof,)
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components
from scipy.sparse.linalg import LinearOperator
from scipy.spatial import cKDTree
from skfem import (Basis, BilinearForm, ElementTetP1, ElementTetP2, ElementTriP1, ElementTriP2,
                   ElementVector, FacetBasis, LinearForm, MeshTet, MeshTri, asm)
from skfem.helpers import div, dot

from fem.materials import Material
from common.errors import InputError

#: strain tensor components returned by strain_operator, per space dimension
STRAIN_COMPONENTS = {3: ("xx", "yy", "zz", "yz", "xz", "xy"), 2: ("xx", "yy", "xy")}
#: stress components returned by stress_operator (plane strain has sigma_zz)
STRESS_COMPONENTS = {3: ("xx", "yy", "zz", "yz", "xz", "xy"), 2: ("xx", "yy", "zz", "xy")}
_INDEX = {"x": 0, "y": 1, "z": 2}


@BilinearForm
def _divergence(u, q, w):
    return div(u) * q


@LinearForm
def _lumped_compliance(q, w):
    return q / w.kappa


class _Pardiso:
    """MKL PARDISO LDL^T (mtype -2) of a symmetric matrix given by its upper triangle (CSR),
    factorised once; `solve` runs the solve phase (33) directly on Fortran-ordered blocks.

    pypardiso's own `solve(A, b)` re-checks on every call that A is the factorised matrix (array
    compare or SHA-1 of A), re-converts the index arrays and copies b; and PARDISO's default
    settings add two iterative-refinement sweeps to every solve (3x the triangular solves; measured
    2.5x slower re-solves). Here iparm is set explicitly (the defaults for mtype -2, METIS nested
    dissection, 1e-8 pivot perturbation, Bunch-Kaufman within supernodes) except that PARDISO's
    refinement is off: _Factor refines on K_ff itself, only when a residual asks for it.

    schur: optional sorted (k,) row indices. PARDISO then orders them last and returns the dense
    Schur complement S = A_SS - A_SI A_II^-1 A_IS (k, k) with a partial factorisation of the rest
    (iparm[35] = 2); a solve is forward substitution (phase 331, which leaves the reduced
    right-hand side in the Schur rows), a dense Cholesky solve with S there, and backward
    substitution (phase 333). Measured on the 97k-DOF monkey model with k = 1945: factorisation
    8.4 s against 9.6 s without, factor non-zeros 94M against 84M.
    """

    def __init__(self, A: sp.csr_matrix, schur: np.ndarray | None = None):
        from pypardiso import PyPardisoSolver

        A.sort_indices()
        self.n = A.shape[0]
        self._data = np.ascontiguousarray(A.data, dtype=np.float64)
        self._ia = (A.indptr + 1).astype(np.int32)      # PARDISO's default one-based indexing
        self._ja = (A.indices + 1).astype(np.int32)
        self._ps = ps = PyPardisoSolver(mtype=-2)
        ip = ps.iparm
        ip[:] = 0
        ip[0] = 1       # iparm given explicitly
        ip[1] = 2       # METIS nested dissection (measured: parallel METIS, 3, no better on 2 cores)
        ip[7] = 0       # no PARDISO refinement unless pivots were perturbed (there were none here)
        ip[9] = 8       # pivot perturbation 1e-8 (mtype -2 default)
        ip[17] = -1     # report nnz(L) in iparm[17]
        ip[20] = 1      # Bunch-Kaufman pivoting (mtype -2 default)
        self._schur_factor = None      # (Cholesky factor of S, lower) when schur rows are given
        if schur is None or len(schur) == 0:
            self._phase(12, np.zeros(1), np.zeros(1), 1)    # analysis + numerical factorisation
        else:
            ip[35] = 2                                      # Schur complement + partial factorisation
            ps.perm = np.zeros(self.n, dtype=np.int32)
            ps.perm[schur] = 1
            self._rows = np.asarray(schur)
            S = np.zeros((len(schur), len(schur)), order="F")     # symmetric: either order
            self._phase(11, np.zeros(1), np.zeros(1), 1)
            self._phase(22, np.zeros(1), S, 1)
            self._schur_factor = sla.cho_factor(S, lower=True, overwrite_a=True)
        self.nnz_factor = int(ip[17])

    def _phase(self, phase, b, x, nrhs):
        import ctypes
        from pypardiso.pardiso_wrapper import PyPardisoError

        ps, i32 = self._ps, ctypes.POINTER(ctypes.c_int32)
        err = ctypes.c_int32(0)
        ps._mkl_pardiso(ps.pt.ctypes.data_as(ctypes.POINTER(ps._pt_type[0])),
                        ctypes.byref(ctypes.c_int32(1)), ctypes.byref(ctypes.c_int32(1)),
                        ctypes.byref(ctypes.c_int32(ps.mtype)), ctypes.byref(ctypes.c_int32(phase)),
                        ctypes.byref(ctypes.c_int32(self.n)), self._data.ctypes.data_as(ctypes.POINTER(ctypes.c_double)),
                        self._ia.ctypes.data_as(i32), self._ja.ctypes.data_as(i32), ps.perm.ctypes.data_as(i32),
                        ctypes.byref(ctypes.c_int32(nrhs)), ps.iparm.ctypes.data_as(i32),
                        ctypes.byref(ctypes.c_int32(0)), b.ctypes.data_as(ctypes.POINTER(ctypes.c_double)),
                        x.ctypes.data_as(ctypes.POINTER(ctypes.c_double)), ctypes.byref(err))
        if err.value != 0:
            raise PyPardisoError(err.value)

    def solve(self, b: np.ndarray) -> np.ndarray:
        """x with A x = b; b (n,) or (n, k) float64, Fortran-ordered (not modified)."""
        x = np.zeros_like(b, order="F")
        if not x.size:                                  # PARDISO rejects nrhs = 0
            return x
        nrhs = 1 if b.ndim == 1 else b.shape[1]
        if self._schur_factor is None:
            self._phase(33, b, x, nrhs)
            return x
        y = np.zeros_like(b, order="F")
        self._phase(331, b, y, nrhs)
        y[self._rows] = sla.cho_solve(self._schur_factor, y[self._rows])
        self._phase(333, y, x, nrhs)
        return x

    def __del__(self):
        try:
            self._phase(-1, np.zeros(1), np.zeros(1), 1)    # release PARDISO's memory
        except Exception:  # noqa: BLE001  (interpreter shutdown, failed factorisation)
            pass


class _Factor:
    """Factorised constrained system, reused for many right-hand sides.

    The condensed stiffness K_ff = Kdev_ff + B_f^T D^-1 B_f is much denser than its parts (the
    pressure couples a vertex's whole patch), so the sparse symmetric quasi-definite matrix
    [[Kdev_ff, B_f^T], [B_f, -D]] is factorised instead (LDL^T, PARDISO mtype -2); its solution's
    displacement part solves K_ff x = b exactly. (Measured on a 71k-DOF sphere: factorising K_ff
    itself with Cholesky, mtype 2, has 4.5x the factor non-zeros and 13x the flops.)

    Each solve checks ||K_ff x - b|| / ||b|| per column and, only for columns above the
    refinement tolerance (REFINE_TOL at first), runs up to MAX_REFINE steps of iterative refinement
    on K_ff. A step that gains less than 10x ends the refinement and raises this factor's tolerance
    to 10x the residual reached, so later solves skip refinement that does not help (round-off
    limited systems, e.g. the fingertip with moduli 1e4 apart).

    condensed: optional sorted (k,) indices into the free DOFs whose compliance block
    (K_ff^-1 restricted to them, `compliance_block`) is wanted: PARDISO then returns the Schur
    complement onto them with the factorisation (see `_Pardiso`); the SciPy fallback ignores it.
    rotation: optional sparse orthogonal T (n_free, n_free), x = T x_local: the system is
    factorised in the local DOFs (T^T K_ff T) and `condensed` indexes those; solves and
    residuals stay in the global DOFs.
    """

    REFINE_TOL = 1e-10
    MAX_REFINE = 2

    def __init__(self, Kdev: sp.csr_matrix, B: sp.csr_matrix, D: np.ndarray, condensed=None, rotation=None):
        self.Kdev, self.B, self.D = Kdev, B, D
        self.refinements = 0        # refinement steps taken by the last call
        self.refine_tol = self.REFINE_TOL
        self.condensed = np.zeros(0, dtype=int)
        self._block = None
        self._T = None if rotation is None else sp.csr_matrix(rotation)
        if self._T is not None:
            Kdev, B = (self._T.T @ Kdev @ self._T).tocsr(), (B @ self._T).tocsr()
        A = sp.bmat([[Kdev, B.T], [B, -sp.diags(D)]], format="csr")
        try:
            from pypardiso import PyPardisoSolver  # noqa: F401  (availability check)
            from pypardiso.pardiso_wrapper import PyPardisoError
        except ImportError:
            warnings.warn("pypardiso is not installed: using SciPy SuperLU, about 50x slower "
                          "(pip install pypardiso)", stacklevel=3)
            from scipy.sparse.linalg import splu
            self.backend, self._solve = "scipy-splu", splu(A.tocsc()).solve
            return
        try:                                # symmetric types read the upper triangle
            self._pardiso = _Pardiso(sp.triu(A, format="csr"), condensed)
        except (PyPardisoError, np.linalg.LinAlgError) as exc:
            raise InputError(f"the stiffness matrix is singular ({exc}); check that every part of the "
                             "mesh is held") from None
        self.backend, self._solve = "pardiso", self._pardiso.solve
        if self._pardiso._schur_factor is not None:
            self.condensed = np.asarray(condensed)

    def compliance_block(self) -> np.ndarray:
        """(k, k) K_ff^-1 restricted to the `condensed` DOFs: the inverse of their Schur complement
        (LAPACK potri on its Cholesky factor, k^3 flops; computed once)."""
        if self._block is None:
            c, info = sla.lapack.dpotri(self._pardiso._schur_factor[0], lower=1)
            if info:
                raise np.linalg.LinAlgError(f"potri failed ({info})")
            for a in range(0, len(c), 1024):            # mirror the lower triangle, in blocks
                b = min(a + 1024, len(c))
                c[a:b, b:] = c[b:, a:b].T
                d = c[a:b, a:b]
                d[:] = np.tril(d) + np.tril(d, -1).T
            c.flags.writeable = False
            self._block = c
        return self._block

    def apply(self, x: np.ndarray) -> np.ndarray:
        """K_ff x."""
        Bx = self.B @ x
        return self.Kdev @ x + self.B.T @ (Bx / (self.D if x.ndim == 1 else self.D[:, None]))

    def _raw(self, b: np.ndarray) -> np.ndarray:
        rhs = np.zeros((len(b) + len(self.D),) + b.shape[1:], order="F")
        rhs[:len(b)] = b if self._T is None else self._T.T @ b
        x = self._solve(rhs)[:len(b)]
        return x if self._T is None else self._T @ x

    def _relres(self, x, b):
        r = b - self.apply(x)
        nr, nb = np.linalg.norm(r, axis=0), np.linalg.norm(b, axis=0)
        return r, np.where(nb > 0, nr / np.where(nb > 0, nb, 1.0), nr)

    def __call__(self, b: np.ndarray) -> np.ndarray:
        """x with K_ff x = b (b (n,) or (n, k)); sets `last_residual` (max relative residual)."""
        b = np.asarray(b, dtype=float)
        x = self._raw(b)
        r, rel = self._relres(x, b)
        self.refinements = 0
        while self.refinements < self.MAX_REFINE and rel.max(initial=0.0) > self.refine_tol:
            if x.ndim == 1:
                x = x + self._raw(r)
                r, new = self._relres(x, b)
            else:
                cols = np.flatnonzero(rel > self.refine_tol)
                x[:, cols] += self._raw(r[:, cols])
                rc, nc = self._relres(x[:, cols], b[:, cols])
                r[:, cols] = rc
                new = rel.copy()
                new[cols] = nc
            self.refinements += 1
            gained = rel.max() / max(new.max(), 1e-300)
            rel = new
            if gained < 10:
                self.refine_tol = max(self.refine_tol, 10 * float(rel.max()))
                break
        self.last_residual = float(rel.max(initial=0.0))
        return x

    def residual(self, x, b) -> float:
        """max over columns of ||K_ff x - b|| / ||b||."""
        return float(self._relres(x, b)[1].max(initial=0.0))


class LinearSystem:
    """K restricted to the free DOFs, factorised once; prescribed values bound to it.

    Attributes: `fixed` (m,), `free` (ndof - m,) DOF indices; `values` (m,) prescribed
    displacements [mm]; `u0` (ndof,) response to them with no load; `residual` relative
    residual ||K_ff x - b|| / ||b|| of the last solve; `backend` ("pardiso" or "scipy-splu").
    """

    def __init__(self, model: "Model", fixed: np.ndarray, values: np.ndarray, factor: _Factor):
        self.model, self.fixed, self.values, self._factor = model, fixed, values, factor
        self.free = np.setdiff1d(np.arange(model.ndof), fixed)
        self.backend = factor.backend
        self.u0 = np.zeros(model.ndof)
        self.u0[fixed] = values
        self._b0 = -(model.K @ self.u0)[self.free]      # load on the free DOFs from the prescribed values
        self.u0[self.free] = self._solve_free(self._b0) if np.any(values) else 0.0
        self.residual_u0 = self.residual if np.any(values) else 0.0

    def _solve_free(self, b):
        x = self._factor(b)
        self.residual = self._factor.last_residual
        if self.residual > 1e-6:
            warnings.warn(f"linear solve residual {self.residual:.1e} is large: the model is nearly "
                          "singular or badly conditioned", stacklevel=3)
        return x

    def solve(self, f: np.ndarray) -> np.ndarray:
        """Displacement [mm] (ndof,) or (ndof, k) caused by nodal forces `f` [N], zero on `fixed`."""
        f = np.asarray(f, dtype=float)
        if f.shape[0] != self.model.ndof:
            raise ValueError(f"load vector has {f.shape[0]} rows, the model has {self.model.ndof} DOFs")
        u = np.zeros(f.shape)
        u[self.free] = self._solve_free(f[self.free])
        return u

    @property
    def condensed(self) -> tuple[np.ndarray, np.ndarray | None]:
        """(nodes (k,), unit direction (dim,) or None): P2 nodes whose compliance along the
        direction this system stores (`Model.system(..., condense=)`); empty when none."""
        f = self._factor
        return (f.condensed_nodes, f.condensed_direction) if len(f.condensed) else (np.zeros(0, int), None)

    def _stored(self, nodes, direction):
        """(positions of nodes in the condensed set (k,), condensed (k,) bool, held (k,) bool)."""
        nodes = np.asarray(nodes)
        have, along = self.condensed
        a = np.asarray(direction, float)[:self.model.dim]
        if along is None or abs(abs(a @ along) - 1) > 1e-12:
            return np.zeros(len(nodes), int), np.zeros(len(nodes), bool), np.zeros(len(nodes), bool)
        pos = np.minimum(np.searchsorted(have, nodes), max(len(have) - 1, 0))
        dofs = self.model.node_dofs(nodes)
        axis = np.flatnonzero(np.abs(along) > 1 - 1e-12)
        held = (np.isin(dofs[:, axis[0]], self.fixed) if axis.size else np.isin(dofs, self.fixed).all(axis=1))
        return pos, have[pos] == nodes, held

    def stored(self, nodes, direction) -> np.ndarray:
        """(k,) bool: which P2 nodes have a stored compliance along the unit `direction` (condensed
        along +-direction, or held along it); all False when nothing is condensed along it."""
        _, inside, held = self._stored(nodes, direction)
        return inside | held

    def compliance(self, nodes, direction) -> np.ndarray:
        """(k, k) exact compliance [mm/N] along the unit `direction` (dim,) between P2 nodes (k,):
        a force f_j along it at node j moves node i by C_ij f_j along it. No solves: the inverse of
        the stored Schur complement. Zero rows and columns for nodes held along the direction.
        Raises ValueError unless every node is `stored`."""
        pos, inside, held = self._stored(nodes, direction)
        if not (inside | held).all():
            raise ValueError(f"this system stores no compliance along {np.round(direction, 6).tolist()} for "
                             f"{int((~(inside | held)).sum())} of the nodes: factorise with condense=")
        i = np.flatnonzero(inside)
        order = self._factor.condensed_order[pos[i]]
        block = self._factor.compliance_block()
        if len(i) == len(nodes) == len(block) and np.array_equal(order, np.arange(len(block))):
            return block                                # read-only, shared: no 0.4 GB copy for k = 7,000
        C = np.zeros((len(nodes), len(nodes)))
        C[np.ix_(i, i)] = block[np.ix_(order, order)]
        return C

    def displacement(self, f: np.ndarray | None = None) -> np.ndarray:
        """u0 + solve(f); sets `residual` to that of the combined system."""
        if f is None:
            self.residual = self.residual_u0
            return self.u0.copy()
        u = self.u0 + self.solve(f)
        self.residual = self._factor.residual(u[self.free], f[self.free] + self._b0)
        return u


@dataclass(frozen=True)
class SurfaceNodes:
    """Nodes of a boundary region: P2 node ids (n,), DOFs (n, dim), coordinates x (n, dim) [mm],
    outward unit normals (n, dim), tributary areas (n,) [mm^2; mm in 2D]."""

    nodes: np.ndarray
    dofs: np.ndarray
    x: np.ndarray
    normal: np.ndarray
    area: np.ndarray


class Model:
    """A layered mesh, its materials and the assembled P2 stiffness.

    Parameters
    ----------
    points : (N, 2 or 3) vertex coordinates [mm]; a 2D model uses x, y.
    cells : (M, 4) linear tetrahedra (3D) or (M, 3) triangles (2D plane strain).
    layer : (M,) positive int layer id per cell.
    regions : name -> bool/uint8 (N,) vertex flags, or an int array of vertex ids. A region is the
        boundary facets whose vertices are all flagged; its nodes are the flagged vertices plus
        the midside nodes of those facets.
    material : `mABCDE` code, moduli [MPa] per layer (mapping or sequence), or a `Material`.
    nu : Poisson ratio in [0, 0.4999] (ignored when `material` is a `Material`).
    rigid_bone : treat layer 5 as rigid (its nodes fixed) instead of elastic.
    """

    def __init__(self, points, cells, layer, regions=None, material="m33338", nu=0.48,
                 rigid_bone=False):
        cells = np.asarray(cells, dtype=np.int64)
        if cells.ndim != 2 or cells.shape[1] not in (3, 4):
            raise InputError(f"cells must be (M, 4) tetrahedra or (M, 3) triangles, got shape {cells.shape}")
        self.dim = cells.shape[1] - 1
        points = np.asarray(points, dtype=float)
        if points.ndim != 2 or points.shape[1] < self.dim:
            raise InputError(f"points must be (N, {self.dim}) or (N, 3), got shape {points.shape}")
        p = np.ascontiguousarray(points[:, :self.dim].T)
        if cells.size and (cells.min() < 0 or cells.max() >= len(points)):
            raise InputError(f"cells refer to point ids outside 0..{len(points) - 1}")
        orphans = len(points) - len(np.unique(cells))
        if orphans:
            raise InputError(f"{orphans} mesh points belong to no cell; remove them "
                             "(meshio: mesh.remove_orphaned_nodes())")
        cells = self._oriented(p, cells)
        self.mesh = (MeshTet if self.dim == 3 else MeshTri)(p, np.ascontiguousarray(cells.T))
        self.layer = np.asarray(layer, dtype=np.int64).ravel()
        if self.layer.shape != (len(cells),):
            raise InputError(f"'layer' has {self.layer.size} values for {len(cells)} cells; "
                             "give one layer id per cell")
        self.material = material if isinstance(material, Material) else Material(material, nu, rigid_bone=rigid_bone)
        self.mu, self.lam = self.material.lame(self.layer)
        self.regions = {name: self._flags(name, v) for name, v in (regions or {}).items()}
        self.basis = Basis(self.mesh, ElementVector(ElementTetP2() if self.dim == 3 else ElementTriP2()),
                           intorder=2)
        self.ndof = self.basis.N
        self.nnodes = self.ndof // self.dim
        self._factors: dict = {}

    # ------------------------------------------------------------------ construction
    @classmethod
    def from_mesh(cls, path, material="m33338", nu=0.48, rigid_bone=False) -> "Model":
        """Read `mesh.vtu` (meshio): `tetra` (3D) or `triangle` (2D) cells, cell data `layer`,
        point data region flags (0/1 integer arrays)."""
        import meshio

        try:
            m = meshio.read(path)
        except Exception as exc:  # meshio raises many types for unreadable files
            raise InputError(f"cannot read mesh '{path}': {exc}") from None
        kind = "tetra" if any(b.type == "tetra" for b in m.cells) else "triangle"
        blocks = [i for i, b in enumerate(m.cells) if b.type == kind]
        if not blocks:
            raise InputError(f"mesh '{path}' has no 'tetra' or 'triangle' cells (linear cells are required)")
        if "layer" not in m.cell_data:
            raise InputError(f"mesh '{path}' has no cell data 'layer'; every cell needs its layer id "
                             "(1 = epidermis ... 5 = bone)")
        cells = np.vstack([m.cells[i].data for i in blocks])
        layer = np.concatenate([np.asarray(m.cell_data["layer"][i]).ravel() for i in blocks])
        regions = {k: v for k, v in m.point_data.items()
                   if np.asarray(v).ndim == 1 and np.asarray(v).dtype.kind in "biu"
                   and np.isin(v, (0, 1)).all()}
        return cls(m.points, cells, layer, regions, material=material, nu=nu, rigid_bone=rigid_bone)

    @staticmethod
    def _oriented(p, cells):
        x = p.T[cells]
        e = x[:, 1:] - x[:, :1]
        det = np.linalg.det(e) if len(cells) else np.zeros(0)
        flat = np.abs(det) <= 1e-14 * np.max(np.abs(e), initial=0.0) ** len(p)
        if flat.any():
            raise InputError(f"{int(flat.sum())} degenerate (zero-volume) cells in the mesh; remove them")
        cells = cells.copy()
        neg = det < 0
        cells[neg, 0], cells[neg, 1] = cells[neg, 1], cells[neg, 0].copy()
        return cells

    def _flags(self, name, v):
        v = np.asarray(v)
        n = self.mesh.nvertices
        if v.dtype.kind == "b" or (v.dtype == np.uint8 and v.size == n):
            if v.size != n:
                raise InputError(f"region '{name}' has {v.size} flags for {n} vertices")
            return v.astype(bool)
        flags = np.zeros(n, dtype=bool)
        if v.size and (v.min() < 0 or v.max() >= n):
            raise InputError(f"region '{name}' refers to vertex ids outside 0..{n - 1}")
        flags[v.astype(np.int64)] = True
        return flags

    # ------------------------------------------------------------------ DOFs and regions
    def node_dofs(self, nodes) -> np.ndarray:
        """(n, dim) DOF indices of P2 nodes (vertex ids first, then midside nodes)."""
        return self.dim * np.asarray(nodes, dtype=np.int64)[:, None] + np.arange(self.dim)

    vertex_dofs = node_dofs

    @cached_property
    def nodes(self) -> np.ndarray:
        """(nnodes, dim) coordinates [mm] of all P2 nodes."""
        return self.basis.doflocs[:, ::self.dim].T.copy()

    @cached_property
    def _edges(self) -> np.ndarray:
        """(2, n) vertex pairs of the midside nodes, in node order after the vertices."""
        return self.mesh.edges if self.dim == 3 else self.mesh.facets

    def _region(self, name) -> np.ndarray:
        if name not in self.regions:
            raise InputError(f"unknown region '{name}'; the mesh has regions {sorted(self.regions)}")
        return self.regions[name]

    def region_facets(self, name) -> np.ndarray:
        """Boundary facet ids whose vertices all carry region `name`'s flag."""
        flags = self._region(name)
        bf = self.mesh.boundary_facets()
        return bf[flags[self.mesh.facets[:, bf]].all(axis=0)]

    def _facet_midsides(self, facets):
        if self.dim == 2:
            return self.mesh.nvertices + facets
        return self.mesh.nvertices + np.unique(self.mesh.f2e[:, facets])

    def region_nodes(self, name) -> np.ndarray:
        """Sorted P2 node ids of a region: flagged vertices + midside nodes of its facets."""
        return np.union1d(np.flatnonzero(self._region(name)), self._facet_midsides(self.region_facets(name)))

    def surface_nodes(self, name, midside=True) -> SurfaceNodes:
        """Nodes of region `name`'s facets with outward unit normals and tributary areas.

        Areas split each quadratic facet into its linear sub-facets, each shared equally by its
        corners (as fem.contact.trace_areas): 3D A/12 per vertex and A/4 per edge node, 2D L/4 and
        L/2; without midside nodes A/3 (3D) or L/2 (2D) per vertex.
        """
        facets = self.region_facets(name)
        fv = self.mesh.facets[:, facets]                                    # (dim, nf)
        x = self.mesh.p[:, fv]                                              # (dim, dim, nf)
        if self.dim == 3:
            nvec = np.cross((x[:, 1] - x[:, 0]).T, (x[:, 2] - x[:, 0]).T)
        else:
            t = (x[:, 1] - x[:, 0]).T
            nvec = np.column_stack([t[:, 1], -t[:, 0]])
        size = np.linalg.norm(nvec, axis=1) / (2.0 if self.dim == 3 else 1.0)
        inner = self.mesh.p[:, self.mesh.t[:, self.mesh.f2t[0, facets]]].mean(axis=1).T
        flip = np.einsum("ij,ij->i", nvec, x.mean(axis=1).T - inner) < 0
        nvec[flip] *= -1
        unit = nvec / np.linalg.norm(nvec, axis=1, keepdims=True)
        vshare = (1 / 12 if self.dim == 3 else 1 / 4) if midside else 1 / self.dim
        ids = [fv.ravel()]
        weights = [np.tile(size * vshare, self.dim)]
        if midside:
            mids = (self.mesh.f2e[:, facets] if self.dim == 3 else facets[None]) + self.mesh.nvertices
            ids.append(mids.ravel())
            weights.append(np.tile(size * (0.25 if self.dim == 3 else 0.5), mids.shape[0]))
        ids, weights = np.concatenate(ids), np.concatenate(weights)
        nodes, inv = np.unique(ids, return_inverse=True)
        area = np.bincount(inv, weights=weights, minlength=len(nodes))
        nsum = np.zeros((len(nodes), self.dim))
        reps = len(ids) // len(facets) if len(facets) else 0
        np.add.at(nsum, inv, np.tile(unit * size[:, None], (reps, 1)))
        normal = nsum / np.maximum(np.linalg.norm(nsum, axis=1, keepdims=True), 1e-300)
        return SurfaceNodes(nodes, self.node_dofs(nodes), self.nodes[nodes], normal, area)

    # ------------------------------------------------------------------ assembly
    @cached_property
    def pressure_basis(self) -> Basis:
        """P1 pressure basis, continuous within a layer, discontinuous across layers: built on a
        copy of the mesh whose interface vertices are duplicated per layer (same element order)."""
        key = self.mesh.t * (self.layer.max() + 1) + self.layer       # (vertex, layer) pairs
        uniq, t_split = np.unique(key, return_inverse=True)
        vertex = uniq // (self.layer.max() + 1)
        split = type(self.mesh)(np.ascontiguousarray(self.mesh.p[:, vertex]),
                                np.ascontiguousarray(t_split.reshape(self.mesh.t.shape), dtype=np.int32))
        return Basis(split, ElementTetP1() if self.dim == 3 else ElementTriP1(), intorder=2)

    @cached_property
    def _kappa(self) -> np.ndarray:
        """(M,) bulk modulus lambda + 2 mu / d [MPa] (d = 2: the plane-strain in-plane bulk)."""
        return self.lam + 2.0 * self.mu / self.dim

    @cached_property
    def pressure_compliance(self) -> np.ndarray:
        """(npressure,) lumped P1 mass weighted by 1 / kappa [mm^3 / MPa]."""
        nqp = self.basis.X.shape[1]
        return asm(_lumped_compliance, self.pressure_basis, kappa=np.repeat(self._kappa[:, None], nqp, axis=1))

    @cached_property
    def _B(self) -> sp.csr_matrix:
        """(npressure, ndof): int q_i div u."""
        return asm(_divergence, self.basis, self.pressure_basis).tocsr()

    @cached_property
    def _pressure(self) -> sp.csr_matrix:
        """(npressure, ndof): nodal pressure (mean-stress-like) p = D^-1 B u [MPa]."""
        return (sp.diags(1.0 / self.pressure_compliance) @ self._B).tocsr()

    @cached_property
    def K_dev(self) -> sp.csr_matrix:
        """(ndof, ndof) deviatoric stiffness int 2 mu dev eps(u) : dev eps(v) [N/mm].

        Vectorised over elements (skfem's generic assembly is ~5x slower for this form): with
        M[a,i,b,j] = int 2 mu dN_a/dx_i dN_b/dx_j (one batched X^T X per element), the block of
        nodes a, b is k[i,j] = d_ij sum_k M[akbk] / 2 + M[ajbi] / 2 - M[aibj] / d. Blocks are
        summed per node pair (bincount) into a 3x3-block matrix: 4 s instead of 8 s for 284k DOFs."""
        d, b = self.dim, self.basis
        nb, M, nn = b.Nbfun // d, self.mesh.nelements, self.ndof // d
        G = np.array([b.basis[a * d][0].grad[0] for a in range(nb)])             # (nb, d, M, nqp)
        X = np.ascontiguousarray((G * np.sqrt(2 * self.mu[:, None] * b.dx)).transpose(2, 0, 1, 3))
        X = X.reshape(M, nb * d, -1)                                             # (M, nb d, nqp)
        nodes = (b.element_dofs[::d].T // d).astype(np.int64)                   # (M, nb) P2 nodes
        pairs, pos = np.unique((nodes[:, :, None] * nn + nodes[:, None, :]).reshape(M, -1), return_inverse=True)
        pos = pos.reshape(M, -1)
        data = np.zeros((d * d, len(pairs)))
        for chunk in np.array_split(np.arange(M), max(1, M // 10000)):
            m = np.matmul(X[chunk], X[chunk].transpose(0, 2, 1))
            m = m.reshape(len(chunk), nb, d, nb, d).transpose(0, 2, 4, 1, 3)     # (e, i, j, a, b)
            k = m * (-1.0 / d) + 0.5 * m.transpose(0, 2, 1, 3, 4)
            half_trace = 0.5 * np.einsum("ekkab->eab", m)
            for i in range(d):
                k[:, i, i] += half_trace
            k = np.ascontiguousarray(k.transpose(1, 2, 0, 3, 4)).reshape(d * d, -1)
            p = pos[chunk].ravel()
            for c in range(d * d):
                data[c] += np.bincount(p, weights=k[c], minlength=len(pairs))
        indptr = np.searchsorted(pairs // nn, np.arange(nn + 1))
        return sp.bsr_matrix((data.T.reshape(-1, d, d), pairs % nn, indptr), shape=(self.ndof, self.ndof)).tocsr()

    @cached_property
    def K(self) -> LinearOperator:
        """(ndof, ndof) stiffness K = K_dev + B^T D^-1 B [N/mm] as an operator (`K @ u`); it is
        never formed (it would be ~7x denser than its factors)."""
        def apply(u):
            return self.K_dev @ u + self._B.T @ (self._pressure @ u)
        return LinearOperator((self.ndof, self.ndof), matvec=apply, matmat=apply, dtype=float)

    # ------------------------------------------------------------------ loads
    def _facet_basis(self, name):
        facets = self.region_facets(name)
        if len(facets) == 0:
            raise InputError(f"region '{name}' has no boundary facets to load")
        return FacetBasis(self.mesh, self.basis.elem, facets=facets, intorder=4)

    def load_vector(self, tractions=None, pressures=None, forces=None, point_forces=None) -> np.ndarray:
        """Consistent nodal forces (ndof,) [N].

        tractions : region -> traction vector (dim,) [MPa] or callable (x, n) -> (dim, ...) of the
            position x and outward unit normal n, both (dim, ...) arrays
        pressures : region -> normal pressure [MPa] (positive pushes into the body) or callable
        forces : region -> total force (dim,) [N], spread as a uniform traction over the region
        point_forces : (vertex_ids (n,), forces (n, dim) [N]) applied at single vertices
        """
        f = np.zeros(self.ndof)
        for name, t in (tractions or {}).items():
            fb = self._facet_basis(name)
            f += asm(LinearForm(lambda v, w: dot(self._field(t, w.x, (self.dim,), w.n), v)), fb)
        for name, pr in (pressures or {}).items():
            fb = self._facet_basis(name)
            f += asm(LinearForm(lambda v, w: -self._field(pr, w.x, ()) * dot(w.n, v)), fb)
        for name, F in (forces or {}).items():
            fb = self._facet_basis(name)
            F = np.asarray(F, dtype=float).reshape(self.dim)
            t = F / fb.dx.sum()
            f += asm(LinearForm(lambda v, w: dot(self._field(t, w.x, (self.dim,)), v)), fb)
        if point_forces is not None:
            ids, F = point_forces
            np.add.at(f, self.vertex_dofs(np.atleast_1d(ids)).ravel(),
                      np.asarray(F, dtype=float).reshape(-1, self.dim).ravel())
        return f

    @staticmethod
    def _field(value, x, shape, n=None):
        if callable(value):
            x = np.asarray(x)                 # plain arrays: skfem's DiscreteField ignores item assignment
            return np.asarray(value(x) if n is None else value(x, np.asarray(n)), dtype=float)
        value = np.asarray(value, dtype=float)
        if value.shape != shape:
            raise InputError(f"load value has shape {value.shape}, expected {shape}")
        return value.reshape(shape + (1,) * (x.ndim - 1))

    # ------------------------------------------------------------------ constraints and solve
    def _prescribed_values(self, name, spec) -> tuple[np.ndarray, np.ndarray]:
        nodes = self.region_nodes(name)
        if callable(spec):
            vals = np.asarray(spec(self.nodes[nodes]), dtype=float).reshape(len(nodes), self.dim)
        elif np.ndim(spec) == 2:
            verts = np.flatnonzero(self._region(name))
            arr = np.asarray(spec, dtype=float)
            if arr.shape != (len(verts), self.dim):
                raise InputError(f"prescribed displacement for '{name}' has shape {arr.shape}; expected "
                                 f"({len(verts)}, {self.dim}), one row per region vertex in id order")
            per_vertex = np.full((self.mesh.nvertices, self.dim), np.nan)
            per_vertex[verts] = arr
            full = np.vstack([per_vertex, per_vertex[self._edges].mean(axis=0)])
            vals = full[nodes]
        else:
            comp = np.array([np.nan if c is None else c for c in np.broadcast_to(
                np.asarray(spec, dtype=object), (self.dim,))], dtype=float)
            vals = np.broadcast_to(comp, (len(nodes), self.dim))
        dofs = self.node_dofs(nodes)
        keep = ~np.isnan(vals)
        return dofs[keep], vals[keep]

    def _constraints(self, prescribed) -> tuple[np.ndarray, np.ndarray]:
        dofs, vals = [], []
        for name, spec in (prescribed or {}).items():
            d, v = self._prescribed_values(name, spec)
            dofs.append(d)
            vals.append(v)
        rigid = np.isin(self.layer, list(self.material.rigid))
        held = np.unique(self.basis.element_dofs[:, rigid])     # rigid-layer nodes, interfaces too
        dofs.append(held)
        vals.append(np.zeros(len(held)))
        dofs, vals = np.concatenate(dofs), np.concatenate(vals)
        order = np.lexsort((vals, dofs))
        dofs, vals = dofs[order], vals[order]
        first = np.r_[True, dofs[1:] != dofs[:-1]][:len(dofs)]
        clash = ~first & (np.abs(np.diff(vals, prepend=0.0)) > 1e-12 * (1 + np.abs(vals)))
        if clash.any():
            raise InputError(f"{int(clash.sum())} DOFs get two different prescribed displacements "
                             "(overlapping regions); make the regions agree where they meet")
        return dofs[first], vals[first]

    def _check_held(self, fixed):
        """Refuse constraints that leave a rigid-body motion free (a singular system)."""
        n, d = self.mesh.nvertices, self.dim
        t = self.mesh.t
        adj = sp.coo_matrix((np.ones(t.size), (np.repeat(t[0], t.shape[0]), t.T.ravel())), shape=(n, n))
        _, label = connected_components(adj, directed=False)
        node_label = np.concatenate([label, label[self._edges[0]]])
        names = ["translation x", "translation y", "translation z"][:d] + (
            ["rotation about x", "rotation about y", "rotation about z"] if d == 3 else ["rotation about z"])
        is_fixed = np.zeros(self.ndof, dtype=bool)
        is_fixed[fixed] = True
        for c in np.unique(label[t]):               # vertices outside every cell are simply held
            nodes = np.flatnonzero(node_label == c)
            x = self.nodes[nodes] - self.nodes[nodes].mean(axis=0)
            x /= max(np.abs(x).max(), 1e-300)
            modes = [np.eye(d)[i][None].repeat(len(nodes), 0) for i in range(d)]
            if d == 3:
                modes += [np.cross(np.eye(3)[i], x) for i in range(3)]
            else:
                modes += [np.column_stack([-x[:, 1], x[:, 0]])]
            R = np.stack([m.ravel() for m in modes], axis=1)[is_fixed[self.node_dofs(nodes).ravel()]]
            # full_matrices only when R has fewer rows than modes (V must stay square); a full
            # U would be (fixed DOFs)^2: 400 MB and seconds for a 7k-DOF symmetry plane
            s, V = (np.linalg.svd(R, full_matrices=len(R) < len(modes))[1:] if len(R)
                    else (np.zeros(0), np.eye(len(modes))))
            free = [names[np.argmax(np.abs(v))] for v in V[len(s[s > 1e-8 * max(s.max(initial=0), 1)]):]]
            if free:
                raise InputError(f"the system is singular: nothing holds {', '.join(free)}"
                                 + (f" of mesh part {c + 1}" if len(np.unique(label[t])) > 1 else "")
                                 + "; prescribe displacements on a region, e.g. prescribed={'nail': 0.0}")

    def system(self, prescribed=None, condense=None) -> LinearSystem:
        """Factorised system for these constraints (cached per set of constrained DOFs; one kept).

        condense: optional (nodes (k,), direction (3,)): P2 nodes whose displacement along the unit
        direction (its x, y part in 2D) gets an exact stored compliance (`LinearSystem.compliance`),
        e.g. contact candidates along the approach. It comes with the factorisation (a PARDISO
        Schur complement, then a k^3 inverse; measured on the 284k-DOF human model with k = 6848:
        88 CPU-s instead of 52, plus 5 for the inverse); the block is dense, so keep k below ~8,000.
        Along a coordinate axis the node's DOF is used as is; along any other direction the nodes'
        DOFs are rotated so that one of them is the displacement along it, and nodes with some but
        not all DOFs held are left out."""
        fixed, values = self._constraints(prescribed)
        free = np.setdiff1d(np.arange(self.ndof), fixed)
        key = fixed.tobytes()
        have = self._factors.get(key)
        plan = None if condense is None else self._condense_plan(free, *condense)
        if have is None or (plan is not None and not (
                len(have.condensed) and abs(abs(plan[1] @ have.condensed_direction) - 1) < 1e-12
                and np.isin(plan[0], have.condensed_nodes).all())):
            self._check_held(fixed)
            nodes, a, pos, T = plan if plan is not None else (np.zeros(0, int), None, np.zeros(0, int), None)
            order = np.argsort(pos)
            factor = _Factor(self.K_dev[free][:, free], self._B[:, free], self.pressure_compliance,
                             pos[order], T)
            by_node = np.argsort(nodes[order])                  # block index of each sorted node
            factor.condensed_nodes, factor.condensed_direction = nodes[order][by_node], a
            factor.condensed_order = by_node
            self._factors = {key: factor}                       # keep one
        return LinearSystem(self, fixed, values, self._factors[key])

    def _condense_plan(self, free, nodes, direction):
        """(nodes (k,), unit direction (dim,), free-DOF position of each node's displacement along
        it (k,), rotation T (n_free, n_free) or None) for `system(condense=...)`."""
        a = np.asarray(direction, float)[:self.dim]
        a = a / np.linalg.norm(a)
        nodes = np.unique(np.asarray(nodes, int))
        dofs = self.node_dofs(nodes)
        is_free = np.zeros(self.ndof, bool)
        is_free[free] = True
        axis = np.flatnonzero(np.abs(a) > 1 - 1e-12)
        if axis.size:                                           # a coordinate axis: its DOF as is
            keep = is_free[dofs[:, axis[0]]]
            return nodes[keep], a, np.searchsorted(free, dofs[keep, axis[0]]), None
        keep = is_free[dofs].all(axis=1)
        nodes, pos = nodes[keep], np.searchsorted(free, dofs[keep])            # (k, dim)
        e0 = np.eye(self.dim)[np.argmin(np.abs(a))]              # local axes (rows); local 1 = along a
        e0 = e0 - (e0 @ a) * a
        e0 /= np.linalg.norm(e0)
        Q = np.array([e0, a] + ([np.cross(e0, a)] if self.dim == 3 else []))
        rows = np.repeat(pos, self.dim, axis=1).ravel()         # x_global[r] = sum_c Q[c, r] x_local[c]
        cols = np.tile(pos, (1, self.dim)).ravel()
        vals = np.tile(Q.T.ravel(), len(nodes))
        rest = np.setdiff1d(np.arange(len(free)), pos.ravel())
        T = sp.csr_matrix((np.r_[vals, np.ones(len(rest))], (np.r_[rows, rest], np.r_[cols, rest])),
                          shape=(len(free), len(free)))
        return nodes, a, pos[:, 1], T

    def solve(self, prescribed=None, tractions=None, pressures=None, forces=None, point_forces=None,
              f=None) -> "Solution":
        """Static solution for prescribed displacements [mm] and loads (see `load_vector`; `f` adds
        raw nodal forces (ndof,) [N])."""
        system = self.system(prescribed)
        load = self.load_vector(tractions, pressures, forces, point_forces)
        if f is not None:
            load = load + f
        u = system.displacement(load if load.any() else None)
        return Solution(self, u, load, system.residual)

    def solution(self, u: np.ndarray, f: np.ndarray | None = None, residual: float = float("nan")) -> "Solution":
        """Wrap a displacement vector u (ndof,) [mm] (e.g. from a contact solve) as a Solution."""
        return Solution(self, np.asarray(u, dtype=float), f, residual)

    # ------------------------------------------------------------------ point evaluation
    @cached_property
    def _affine(self):
        p, t = self.mesh.p.T, self.mesh.t.T
        A = np.stack([p[t[:, k]] - p[t[:, 0]] for k in range(1, self.dim + 1)], axis=2)
        return p[t[:, 0]], np.linalg.inv(A)

    def _min_barycentric(self, x, cand):
        p0, Ainv = self._affine
        X = np.einsum("...ij,...j->...i", Ainv[cand], x[:, None, :] - p0[cand])
        return np.minimum(1.0 - X.sum(axis=-1), X.min(axis=-1))

    def locate(self, points, layer=None) -> np.ndarray:
        """(n,) element holding each point (n, dim or 3) [mm]; `layer` restricts the search.

        On an interface the element with the point deepest inside wins; give `layer` to choose.
        """
        x = np.atleast_2d(np.asarray(points, dtype=float))[:, :self.dim]
        pool = np.arange(self.mesh.nelements) if layer is None else np.flatnonzero(self.layer == layer)
        if len(pool) == 0:
            raise InputError(f"no elements in layer {layer}; the mesh has layers {sorted(set(self.layer))}")
        centroids = self.mesh.p[:, self.mesh.t[:, pool]].mean(axis=1).T
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

    def _reference(self, x, cells):
        p0, Ainv = self._affine
        return np.einsum("nij,nj->in", Ainv[cells], x - p0[cells])

    def _shape(self, x, cells):
        """Values (nb, dim, n) and gradients (nb, dim, dim, n) of the element basis at x."""
        X = self._reference(x, cells)[:, :, None]
        fields = [self.basis.elem.gbasis(self.basis.mapping, X, k, tind=cells)[0]
                  for k in range(self.basis.Nbfun)]
        return (np.array([np.asarray(f)[..., 0] for f in fields]), np.array([f.grad[..., 0] for f in fields]))

    def _operator(self, x, cells, quantity):
        """Sparse (n * ncomp, ndof) map from u to `quantity` at points x (n, dim) in `cells`."""
        n, d = len(x), self.dim
        value, grad = self._shape(x, cells)
        dofs = self.basis.element_dofs[:, cells]                        # (nb, n)
        if quantity == "displacement":
            rows = (np.arange(n)[None, None] * d + np.arange(d)[None, :, None])
            rows = np.broadcast_to(rows, value.shape)
            cols = np.broadcast_to(dofs[:, None, :], value.shape)
            return sp.csr_matrix((value.ravel(), (rows.ravel(), cols.ravel())), shape=(n * d, self.ndof))
        eps = 0.5 * (grad + grad.transpose(0, 2, 1, 3))
        dev = eps - np.einsum("kiin->kn", eps)[:, None, None] / d * np.eye(d)[None, :, :, None]
        lam = np.vstack([1.0 - self._reference(x, cells).sum(axis=0), self._reference(x, cells)])   # P1 values
        pdofs = self.pressure_basis.element_dofs[:, cells].ravel()
        P1 = sp.csr_matrix((lam.ravel(), (np.tile(np.arange(n), d + 1), pdofs)), shape=(n, self.pressure_basis.N))
        vol = (sp.diags(1.0 / (d * self._kappa[cells])) @ P1 @ self._pressure).tocoo()   # theta_bar / d
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
                               shape=(n * ncomp, self.ndof))
        if quantity == "strain":
            return strain
        # stress = 2 mu eps_bar + lambda tr(eps_bar) I, laid out as STRESS_COMPONENTS
        out, names = STRESS_COMPONENTS[d], STRAIN_COMPONENTS[d]
        S = np.array([[float(a == b) for b in names] for a in out])
        T = np.outer([a[0] == a[1] for a in out], [b[0] == b[1] for b in names]).astype(float)
        M = 2 * self.mu[cells, None, None] * S + self.lam[cells, None, None] * T   # (n, nout, ncomp)
        k, a, c = np.indices(M.shape)
        hooke = sp.csr_matrix((M.ravel(), ((k * len(out) + a).ravel(), (k * ncomp + c).ravel())),
                              shape=(n * len(out), n * ncomp))
        return (hooke @ strain).tocsr()

    def displacement_operator(self, points, layer=None) -> sp.csr_matrix:
        """(n * dim, ndof) sparse: displacement [mm] at points, point-major."""
        x = np.atleast_2d(np.asarray(points, dtype=float))[:, :self.dim]
        return self._operator(x, self.locate(x, layer), "displacement")

    def strain_operator(self, points, layer=None) -> sp.csr_matrix:
        """(n * ncomp, ndof) sparse: strain tensor components (STRAIN_COMPONENTS) at points."""
        x = np.atleast_2d(np.asarray(points, dtype=float))[:, :self.dim]
        return self._operator(x, self.locate(x, layer), "strain")

    def stress_operator(self, points, layer=None) -> sp.csr_matrix:
        """(n * ncomp, ndof) sparse: stress components [MPa] (STRESS_COMPONENTS) at points."""
        x = np.atleast_2d(np.asarray(points, dtype=float))[:, :self.dim]
        return self._operator(x, self.locate(x, layer), "stress")

    def __repr__(self):
        kind = "3D tetra10" if self.dim == 3 else "2D plane-strain triangle6"
        return (f"Model({kind}, {self.mesh.nelements} elements, {self.ndof} DOFs, layers "
                f"{sorted(set(self.layer.tolist()))}, material {self.material}, regions {sorted(self.regions)})")

class Solution:
    """A displacement field and everything derived from it.

    u (ndof,) [mm]; f (ndof,) applied nodal forces [N]; residual: relative solve residual.
    Strain, stress and measures come from the element holding each point (never averaged).
    """

    def __init__(self, model: Model, u: np.ndarray, f: np.ndarray | None = None, residual=float("nan")):
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
        from fem.measures import State

        m, d, n = self.model, self.model.dim, len(x)
        value, grad = m._shape(x, cells)                                  # (nb, d, n), (nb, d, d, n)
        ue = self.u[m.basis.element_dofs[:, cells]]                       # (nb, n)
        disp = np.zeros((n, 3))
        disp[:, :d] = np.einsum("kin,kn->ni", value, ue)
        g = np.einsum("kijn,kn->nij", grad, ue)
        eps = 0.5 * (g + g.transpose(0, 2, 1))
        X = m._reference(x, cells)
        p1 = np.vstack([1.0 - X.sum(axis=0), X])                          # P1 pressure shape values
        theta_bar = (p1 * (m._pressure @ self.u)[m.pressure_basis.element_dofs[:, cells]]).sum(axis=0) / m._kappa[cells]
        eps += ((theta_bar - np.trace(eps, axis1=1, axis2=2)) / d)[:, None, None] * np.eye(d)
        strain = np.zeros((n, 3, 3))
        strain[:, :d, :d] = eps
        stress = 2 * m.mu[cells, None, None] * strain + (m.lam[cells] * theta_bar)[:, None, None] * np.eye(3)
        return State(disp, strain, stress)

    def fields(self, points, names=None, layer=None) -> dict[str, np.ndarray]:
        """{measure name: (n,) values} at points (n, dim or 3) [mm]; all measures if names is None.

        Also 'element' and 'layer' (n,) of the element that holds each point."""
        from fem.measures import evaluate

        x = np.atleast_2d(np.asarray(points, dtype=float))[:, :self.model.dim]
        cells = self.model.locate(x, layer)
        return {"element": cells, "layer": self.model.layer[cells], **evaluate(names, self._state(x, cells))}

    def sample(self, name: str, points, layer=None) -> np.ndarray:
        """(n,) values of one measure (see fem.measures.MEASURES) at points [mm]."""
        return self.fields(points, [name], layer)[name]

    @cached_property
    def element_fields(self) -> dict[str, np.ndarray]:
        """{measure name: (M,) value at each element's centroid}."""
        from fem.measures import evaluate

        m = self.model
        cells = np.arange(m.mesh.nelements)
        x = m.mesh.p[:, m.mesh.t].mean(axis=1).T
        return evaluate(None, self._state(x, cells))

    def save(self, path, points=None, names=None, layer=None) -> None:
        """Write a quadratic-cell VTU (`path`) and, with `points`, a CSV of samples next to it."""
        from fem.export import write_csv, write_vtu

        write_vtu(path, self)
        if points is not None:
            write_csv(Path(path).with_suffix(".csv"), points, self.fields(points, names, layer))
