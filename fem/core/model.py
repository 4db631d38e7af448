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
1.6 % max error. Plain P2 locks (50 % stress error at nu = 0.4999); P2 with an element-constant
condensed pressure (P2-P0) gives accurate displacements but a mean stress that does not converge
in 3D (24 % rms on the same sphere at nu = 0.4999).

The condensed K has ~7x the non-zeros of K_dev, so K is kept as an operator and the sparse
quasi-definite matrix [[K_dev, B^T], [B, -D]] is factorised (fem.core.linalg: MKL PARDISO LDL^T via
pypardiso; SciPy SuperLU fallback, slow, with a warning) and re-solved for new right-hand sides.
Strain, stress and every measure are the element's own fields (fem.core.fields), evaluated in the
element that holds the point; the pressure never couples across a layer interface.

User API
--------
    model = Model.from_mesh("mesh.vtu", material="m43338", nu=0.48)      # or Model(points, cells, layer, regions)
    sol = model.solve(prescribed={"nail": 0.0, "support": (None, 0.0, None), "pad": (0, -1.0, 0)},
                      pressures={"inner": 0.01}, tractions=..., forces=..., point_forces=...)
    sol.sample("sed_MPa", points)   # fem.core.measures.MEASURES lists every name
    sol.save("static.vtu", points=receptors)   # tetra10/triangle6 VTU + CSV of samples

Prescribed values per region: a scalar (all components), a tuple with None for free components,
an (n_region_vertices, dim) array (midside nodes take the mean of their edge's two vertices), or a
callable x (n, dim) -> (n, dim) over all region nodes (NaN = free).

Linear systems, nodes and point operators
-----------------------------------------
    system = model.system(prescribed={...})   # fem.core.system.LinearSystem; factorisation cached per constrained-DOF set
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
    model.solution(u, f=None) -> Solution      # fem.core.fields.Solution: fields, measures, sample, save for any u
    model.load_vector(tractions=..., pressures=..., forces=..., point_forces=...) -> (ndof,)
"""
from __future__ import annotations

from functools import cached_property

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import LinearOperator
from skfem import FacetBasis, LinearForm, asm
from skfem.helpers import dot

from fem.core.discretisation import Discretisation, SurfaceNodes
from fem.core.fields import Solution, point_operator
from fem.core.linalg import SaddleFactor, saddle_upper
from fem.core.materials import DEFAULT_NU, Material, default_code
from fem.core.patterns import drop_round_off
from fem.core.system import LinearSystem, condense_plan
from fingertip.errors import InputError

__all__ = ["Model", "SurfaceNodes"]


@LinearForm
def _lumped_compliance(q, w):
    return q / w.kappa


def _mesh(name: str, doc: str) -> property:
    """A read-only attribute of the model that is its discretisation's (the mesh's own)."""
    return property(lambda self: getattr(self.discretisation, name), doc=doc)


class Model:
    """A material on a layered mesh's discretisation, and the assembled P2 stiffness.

    Parameters
    ----------
    points, cells, layer, regions : the mesh (`fem.core.discretisation.Discretisation`).
    material : `mABCDE` code, moduli [MPa] per layer (mapping or sequence), or a `Material`; a
        code or sequence has one value per layer 1 to the mesh's highest solid layer (InputError
        otherwise). None: `fem.core.materials.default_code` of the mesh's layers ("m3" for one layer).
    nu : Poisson ratio in [0, 0.4999] (ignored when `material` is a `Material`).
    rigid_bone : treat layer 5 as rigid (its nodes fixed) instead of elastic.

    `Model.on(discretisation, material)` puts a material on an existing discretisation: every
    model of one mesh shares its bases, divergence matrix and stiffness pattern, and what depends
    on the material (moduli, K_dev, the factorisations) is the model's own.
    """

    def __init__(self, points, cells, layer, regions=None, material=None, nu=DEFAULT_NU,
                 rigid_bone=False):
        self._setup(Discretisation(points, cells, layer, regions), material, nu, rigid_bone)

    @classmethod
    def on(cls, discretisation: Discretisation, material=None, nu=DEFAULT_NU, rigid_bone=False) -> Model:
        """A model of `discretisation` with this material (arguments as the constructor's)."""
        model = object.__new__(cls)
        model._setup(discretisation, material, nu, rigid_bone)
        return model

    @classmethod
    def from_mesh(cls, path, material=None, nu=DEFAULT_NU, rigid_bone=False) -> Model:
        """A model of the mesh in `mesh.vtu` (`Discretisation.from_mesh`)."""
        return cls.on(Discretisation.from_mesh(path), material, nu, rigid_bone)

    def with_material(self, material, nu=DEFAULT_NU, rigid_bone=False) -> Model:
        """This mesh with another material: a loop over materials (fits, layer studies) pays for
        the bases, the divergence matrix and the stiffness pattern once (about 1.6 s a material on
        the human 0.5 mm model: B 0.4 s, the scalar basis 0.2 s, the pattern 1 s)."""
        return type(self).on(self.discretisation, material, nu, rigid_bone)

    def _setup(self, discretisation, material, nu, rigid_bone) -> None:
        self.discretisation = discretisation
        if material is None:
            material = default_code(discretisation.layer)
        self.material = material if isinstance(material, Material) else Material(material, nu, rigid_bone=rigid_bone)
        self.mu, self.lam = self.material.lame(discretisation.layer)
        self._factors: dict = {}

    dim = _mesh("dim", "Space dimension: 3 (tetrahedra) or 2 (plane strain).")
    mesh = _mesh("mesh", "The skfem mesh (vertices and linear cells).")
    layer = _mesh("layer", "(M,) layer id per element.")
    regions = _mesh("regions", "Region name -> (N,) bool vertex flags.")
    nodes = _mesh("nodes", "(nnodes, dim) coordinates [mm] of all P2 nodes.")
    nnodes = _mesh("nnodes", "Number of P2 nodes.")
    ndof = _mesh("ndof", "Number of displacement DOFs (dim * nnodes).")
    element = _mesh("element", "The vector P2 element of the displacement.")
    element_nodes = _mesh("element_nodes", "(nb, M) P2 nodes of each element.")
    element_dofs = _mesh("element_dofs", "(nb * dim, M) DOFs of each element.")
    scalar_basis = _mesh("scalar_basis", "The scalar P2 basis.")
    pressure_basis = _mesh("pressure_basis", "The layer-wise P1 pressure basis.")
    locator = _mesh("locator", "Point location and shape functions (fem.core.fields.PointLocator).")

    def node_dofs(self, nodes) -> np.ndarray:
        """(n, dim) DOF indices of P2 nodes (vertex ids first, then midside nodes)."""
        return self.discretisation.node_dofs(nodes)

    vertex_dofs = node_dofs

    def shape_gradients(self) -> np.ndarray:
        """(nb, dim, M, nqp) gradients [1/mm] of the scalar P2 shape functions (a new array)."""
        return self.discretisation.shape_gradients()

    def region_facets(self, name) -> np.ndarray:
        """Boundary facet ids of region `name`."""
        return self.discretisation.region_facets(name)

    def region_nodes(self, name) -> np.ndarray:
        """Sorted P2 node ids of region `name`."""
        return self.discretisation.region_nodes(name)

    def surface_nodes(self, name, midside=True) -> SurfaceNodes:
        """Nodes of region `name`'s facets with outward normals and tributary areas."""
        return self.discretisation.surface_nodes(name, midside)

    # ------------------------------------------------------------------ material-bearing operators
    @cached_property
    def kappa(self) -> np.ndarray:
        """(M,) bulk modulus lambda + 2 mu / d [MPa] (d = 2: the plane-strain in-plane bulk)."""
        return self.lam + 2.0 * self.mu / self.dim

    @cached_property
    def pressure_compliance(self) -> np.ndarray:
        """(npressure,) lumped P1 mass weighted by 1 / kappa [mm^3 / MPa]; with a fluid layer its
        entries are summed into one for the uniform fluid pressure (the last)."""
        nqp = self.scalar_basis.X.shape[1]
        return self.discretisation.reduce(asm(_lumped_compliance, self.pressure_basis,
                                              kappa=np.repeat(self.kappa[:, None], nqp, axis=1)))

    @cached_property
    def pressure_operator(self) -> sp.csr_matrix:
        """(n P1 pressures of pressure_basis, ndof): nodal pressure (mean-stress-like) p = D^-1 B u [MPa]."""
        p = sp.diags(1.0 / self.pressure_compliance) @ self.discretisation.B
        tie = self.discretisation.fluid_tie
        return (p if tie is None else tie @ p).tocsr()

    @property
    def fluid_pressure_operator(self) -> np.ndarray:
        """(ndof,) row giving the uniform fluid pressure [MPa] from u (positive: tension)."""
        return self.discretisation.fluid_row / self.pressure_compliance[-1]

    def fluid_volume_change(self, u: np.ndarray) -> float:
        """Linearised volume change of the fluid layer int div u [mm^3; mm^2 in 2D]."""
        return float(self.discretisation.fluid_row @ u)

    @cached_property
    def K_dev(self) -> sp.csr_matrix:
        """(ndof, ndof) deviatoric stiffness int 2 mu dev eps(u) : dev eps(v) [N/mm].

        Vectorised over elements (skfem's generic assembly is slower for this form): with
        M[a,i,b,j] = int 2 mu dN_a/dx_i dN_b/dx_j (one batched X^T X per element), the block of
        nodes a, b is k[i,j] = d_ij sum_k M[akbk] / 2 + M[ajbi] / 2 - M[aibj] / d. Blocks are
        summed per node pair (bincount) and written straight into CSR order
        (`Discretisation.stiffness_pattern`)."""
        d, b = self.dim, self.scalar_basis
        nb, M = b.Nbfun, self.mesh.nelements
        pos, item, indptr, indices = self.discretisation.stiffness_pattern
        npairs = item.shape[1]
        G = self.discretisation.shape_gradients()                                # (nb, d, M, nqp)
        X = np.ascontiguousarray((G * np.sqrt(2 * self.mu[:, None] * b.dx)).transpose(2, 0, 1, 3))
        X = X.reshape(M, nb * d, -1)                                             # (M, nb d, nqp)
        data = np.zeros((d * d, npairs))
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
                data[c] += np.bincount(p, weights=k[c], minlength=npairs)
        csr = np.empty((d * npairs, d))
        for i in range(d):
            csr[item[i]] = data[i * d:(i + 1) * d].T
        K = sp.csr_matrix((csr.ravel(), indices, indptr), shape=(self.ndof, self.ndof), copy=False)
        K.has_sorted_indices = True
        return K

    @cached_property
    def K(self) -> LinearOperator:
        """(ndof, ndof) stiffness K = K_dev + B^T D^-1 B [N/mm] as an operator (`K @ u`); it is
        never formed (it would be ~7x denser than its factors)."""
        D, B = self.pressure_compliance, self.discretisation.B

        def apply(u):
            Bu = B @ u
            return self.K_dev @ u + B.T @ (Bu / (D if u.ndim == 1 else D[:, None]))
        return LinearOperator((self.ndof, self.ndof), matvec=apply, matmat=apply, dtype=float)

    # ------------------------------------------------------------------ loads
    def _facet_basis(self, name):
        facets = self.region_facets(name)
        if len(facets) == 0:
            raise InputError(f"region '{name}' has no boundary facets to load")
        return FacetBasis(self.mesh, self.element, facets=facets, intorder=4)

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
    def system(self, prescribed=None, condense=None) -> LinearSystem:
        """Factorised system for these constraints (cached per set of constrained DOFs; one kept).

        condense: optional (nodes (k,), direction (3,)): P2 nodes whose displacement along the unit
        direction (its x, y part in 2D) gets an exact stored compliance (`LinearSystem.compliance`),
        e.g. contact candidates along the approach. It comes with the factorisation (a PARDISO
        Schur complement, then a k^3 inverse); the block is dense, so keep k below ~8,000.
        Along a coordinate axis the node's DOF is used as is; along any other direction the nodes'
        DOFs are rotated so that one of them is the displacement along it, and nodes with some but
        not all DOFs held are left out."""
        fixed, values = self.discretisation.constraints(prescribed, self.material.rigid)
        free = np.setdiff1d(np.arange(self.ndof), fixed)
        key = fixed.tobytes()
        have = self._factors.get(key)
        plan = None if condense is None else condense_plan(self, free, *condense)
        if have is None or (plan is not None and not (
                len(have.condensed) and abs(abs(plan[1] @ have.condensed_direction) - 1) < 1e-12
                and np.isin(plan[0], have.condensed_nodes).all())):
            self.discretisation.check_held(fixed)
            nodes, a, pos, T = plan if plan is not None else (np.zeros(0, int), None, np.zeros(0, int), None)
            order = np.argsort(pos)
            factor = SaddleFactor(self.K_dev, self.discretisation.B, self.pressure_compliance, pos[order], T,
                                  free=free)
            by_node = np.argsort(nodes[order])                  # block index of each sorted node
            factor.condensed_nodes, factor.condensed_direction = nodes[order][by_node], a
            factor.condensed_order = by_node
            self._factors = {key: factor}                       # keep one
        return LinearSystem(self, fixed, values, self._factors[key])

    def free_saddle(self, prescribed=None) -> tuple[np.ndarray, sp.csr_matrix]:
        """(free DOFs (n_free,) sorted, the upper triangle of the saddle matrix [[Kdev, B^T], [B, -D]]
        on them with round-off dropped): what `system` factorises, for another solver
        (`fem.core.inverse`); prescribed as in `system`."""
        fixed, _ = self.discretisation.constraints(prescribed, self.material.rigid)
        free = np.setdiff1d(np.arange(self.ndof), fixed)
        return free, drop_round_off(saddle_upper(self.K_dev[free][:, free], self.discretisation.B[:, free],
                                                 self.pressure_compliance))

    def release_factors(self) -> None:
        """Drop the cached factorisation of `system` (its memory, with the systems that hold it
        gone too); the next `system` factorises again."""
        self._factors = {}

    def solve(self, prescribed=None, tractions=None, pressures=None, forces=None, point_forces=None,
              f=None) -> Solution:
        """Static solution for prescribed displacements [mm] and loads (see `load_vector`; `f` adds
        raw nodal forces (ndof,) [N])."""
        system = self.system(prescribed)
        load = self.load_vector(tractions, pressures, forces, point_forces)
        if f is not None:
            load = load + f
        u = system.displacement(load if load.any() else None)
        return Solution(self, u, load, system.residual)

    def solution(self, u: np.ndarray, f: np.ndarray | None = None, residual: float = float("nan")) -> Solution:
        """Wrap a displacement vector u (ndof,) [mm] (e.g. from a contact solve) as a Solution."""
        return Solution(self, np.asarray(u, dtype=float), f, residual)

    # ------------------------------------------------------------------ point evaluation
    def _points(self, points) -> np.ndarray:
        return np.atleast_2d(np.asarray(points, dtype=float))[:, :self.dim]

    def locate(self, points, layer=None) -> np.ndarray:
        """(n,) element holding each point (n, dim or 3) [mm]; `layer` restricts the search.

        On an interface the element with the point deepest inside wins; give `layer` to choose.
        """
        return self.locator.locate(self._points(points), layer)

    def _operator(self, points, layer, quantity) -> sp.csr_matrix:
        x = self._points(points)
        return point_operator(self, x, self.locator.locate(x, layer), quantity)

    def displacement_operator(self, points, layer=None) -> sp.csr_matrix:
        """(n * dim, ndof) sparse: displacement [mm] at points, point-major."""
        return self._operator(points, layer, "displacement")

    def strain_operator(self, points, layer=None) -> sp.csr_matrix:
        """(n * ncomp, ndof) sparse: strain tensor components (fem.core.fields.STRAIN_COMPONENTS) at points."""
        return self._operator(points, layer, "strain")

    def stress_operator(self, points, layer=None) -> sp.csr_matrix:
        """(n * ncomp, ndof) sparse: stress components [MPa] (fem.core.fields.STRESS_COMPONENTS) at points."""
        return self._operator(points, layer, "stress")

    def __repr__(self):
        kind = "3D tetra10" if self.dim == 3 else "2D plane-strain triangle6"
        return (f"Model({kind}, {self.mesh.nelements} elements, {self.ndof} DOFs, layers "
                f"{sorted(set(self.layer.tolist()))}, material {self.material}, regions {sorted(self.regions)})")
