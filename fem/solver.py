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
quasi-definite matrix [[K_dev, B^T], [B, -D]] is factorised (fem.linalg: MKL PARDISO LDL^T via
pypardiso; SciPy SuperLU fallback, slow, with a warning) and re-solved for new right-hand sides.
Strain, stress and every measure are the element's own fields (fem.fields), evaluated in the
element that holds the point; the pressure never couples across a layer interface.

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

Linear systems, nodes and point operators
-----------------------------------------
    system = model.system(prescribed={...})   # fem.system.LinearSystem; factorisation cached per constrained-DOF set
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
    model.solution(u, f=None) -> Solution      # fem.fields.Solution: fields, measures, sample, save for any u
    model.load_vector(tractions=..., pressures=..., forces=..., point_forces=...) -> (ndof,)
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components
from scipy.sparse.linalg import LinearOperator
from skfem import (Basis, ElementTetP1, ElementTetP2, ElementTriP1, ElementTriP2,
                   ElementVector, FacetBasis, LinearForm, MeshTet, MeshTri, asm)
from skfem.helpers import dot

from common.errors import InputError
from fem.fields import PointEvaluator, Solution
from fem.linalg import SaddleFactor
from fem.materials import FLUID_LAYER, Material
from fem.system import LinearSystem, condense_plan


@LinearForm
def _lumped_compliance(q, w):
    return q / w.kappa


@dataclass(frozen=True)
class SurfaceNodes:
    """Nodes of a boundary region: P2 node ids (n,), DOFs (n, dim), coordinates x (n, dim) [mm],
    outward unit normals (n, dim), tributary areas (n,) [mm^2; mm in 2D]."""

    nodes: np.ndarray
    dofs: np.ndarray
    x: np.ndarray
    normal: np.ndarray
    area: np.ndarray


def _entities(t, indices, sort=True):
    """skfem's `Mesh.build_entities` (the same arrays): the sorted vertex tuples of the edges or
    facets are packed into one int64 key each, so np.unique runs on a 1D array instead of rows
    (several times faster than unique with axis=1; both order lexicographically and return first
    occurrences). Falls back to skfem's when the key would overflow."""
    if indices is None:
        return None, None
    nv = int(t.max(initial=0)) + 1
    if nv ** len(indices[0]) >= 2 ** 62:
        return MeshTet.build_entities(t, indices, sort)
    indexing = np.hstack([t[ix] for ix in indices])
    ordered = np.sort(indexing, axis=0).astype(np.int64)
    key = ordered[0]
    for row in ordered[1:]:
        key = key * nv + row
    _, first, inverse = np.unique(key, return_index=True, return_inverse=True)
    out = (ordered if sort else indexing)[:, first].astype(t.dtype)
    return np.ascontiguousarray(out), inverse.reshape(len(indices), t.shape[1])


class _Tet(MeshTet):
    build_entities = staticmethod(_entities)


class _Tri(MeshTri):
    build_entities = staticmethod(_entities)


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
        self.mesh = (_Tet if self.dim == 3 else _Tri)(p, np.ascontiguousarray(cells.T))
        self.layer = np.asarray(layer, dtype=np.int64).ravel()
        if self.layer.shape != (len(cells),):
            raise InputError(f"'layer' has {self.layer.size} values for {len(cells)} cells; "
                             "give one layer id per cell")
        self._set_material(material, nu, rigid_bone)
        self.regions = {name: self._flags(name, v) for name, v in (regions or {}).items()}

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

    GEOMETRY = ("scalar_basis", "element_nodes", "element_dofs", "element", "nnodes", "nodes", "_edges",
                "pressure_basis", "_fluid_tie", "_B", "_fluid_row", "_node_pairs", "_inner_fluid_dofs")
    """Cached properties that depend on the mesh and its layers only (`with_material` shares them)."""

    def with_material(self, material, nu=0.48, rigid_bone=False) -> "Model":
        """This mesh and its regions with another material (arguments as the constructor's).
        Whatever of `GEOMETRY` this model has computed is shared, not rebuilt: a loop over
        materials (fits, layer studies) pays for the bases, the divergence matrix and K_dev's
        pattern once (about 1.6 s a material on the human 0.5 mm model: B 0.4 s, the scalar basis
        0.2 s, the pattern 1 s)."""
        new = object.__new__(type(self))
        new.dim, new.mesh, new.layer, new.regions = self.dim, self.mesh, self.layer, dict(self.regions)
        new._set_material(material, nu, rigid_bone)
        new.__dict__.update({k: self.__dict__[k] for k in self.GEOMETRY if k in self.__dict__})
        return new

    def _set_material(self, material, nu, rigid_bone) -> None:
        """The material, its Lame parameters per element, and no factorisation yet."""
        self.material = material if isinstance(material, Material) else Material(material, nu, rigid_bone=rigid_bone)
        self.mu, self.lam = self.material.lame(self.layer)
        self._factors: dict = {}

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
    def scalar_basis(self) -> Basis:
        """The scalar P2 basis (quadrature order 2), built when first needed (a run answered by a
        stored response model does without it). The vector unknowns' forms are assembled from its
        shape functions: an skfem vector basis holds 9x the arrays (630 against 80 MB and 1.5
        against 0.2 s on a 65k-tet mesh)."""
        return Basis(self.mesh, self.element.elem, intorder=2)

    def shape_gradients(self) -> np.ndarray:
        """(nb, dim, M, nqp) gradients [1/mm] of the scalar P2 shape functions at the quadrature
        points of `scalar_basis` (a new array, not kept)."""
        b = self.scalar_basis
        return np.array([b.basis[a][0].grad for a in range(b.Nbfun)])

    @cached_property
    def element_nodes(self) -> np.ndarray:
        """(nb, M) P2 nodes of each element: its vertices, then its edges' midside nodes (skfem's
        P2 DOF order, which is also VTK's tetra10 and triangle6 order)."""
        mids = self.mesh.t2e if self.dim == 3 else self.mesh.t2f
        return np.vstack([self.mesh.t, self.mesh.nvertices + mids]).astype(np.int64)

    @cached_property
    def element_dofs(self) -> np.ndarray:
        """(nb * dim, M) DOFs of each element, shape function a's component i in row a * dim + i
        (skfem's ElementVector order)."""
        nodes = self.element_nodes
        return (self.dim * nodes[:, None, :] + np.arange(self.dim)[None, :, None]).reshape(-1, nodes.shape[1])

    @cached_property
    def element(self) -> ElementVector:
        """The vector P2 element of the displacement."""
        return ElementVector(ElementTetP2() if self.dim == 3 else ElementTriP2())

    @cached_property
    def nnodes(self) -> int:
        """Number of P2 nodes: the vertices, then one midside node per edge (3D) or facet (2D)."""
        return self.mesh.nvertices + self._edges.shape[1]

    @property
    def ndof(self) -> int:
        return self.dim * self.nnodes

    @cached_property
    def nodes(self) -> np.ndarray:
        """(nnodes, dim) coordinates [mm] of all P2 nodes (the basis's DOF locations)."""
        p = self.mesh.p
        return np.vstack([p.T, 0.5 * (p[:, self._edges[0]] + p[:, self._edges[1]]).T])

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
    def kappa(self) -> np.ndarray:
        """(M,) bulk modulus lambda + 2 mu / d [MPa] (d = 2: the plane-strain in-plane bulk)."""
        return self.lam + 2.0 * self.mu / self.dim

    @cached_property
    def _fluid_tie(self) -> sp.csr_matrix | None:
        """(n P1 pressures, n unknown pressures): every P1 pressure of the fluid layer
        (fem.materials.FLUID_LAYER) tied to one uniform fluid pressure (hydrostatic, as the
        thesis's fluid elements); None without fluid."""
        fluid = self.layer == FLUID_LAYER
        if not fluid.any():
            return None
        n = self.pressure_basis.N
        tied = np.zeros(n, dtype=bool)
        tied[self.pressure_basis.element_dofs[:, fluid].ravel()] = True
        col = np.cumsum(~tied) - 1
        col[tied] = (~tied).sum()
        return sp.csr_matrix((np.ones(n), (np.arange(n), col)), shape=(n, col.max() + 1))

    def _reduce(self, a):
        return a if self._fluid_tie is None else self._fluid_tie.T @ a

    @cached_property
    def pressure_compliance(self) -> np.ndarray:
        """(npressure,) lumped P1 mass weighted by 1 / kappa [mm^3 / MPa]; with a fluid layer its
        entries are summed into one for the uniform fluid pressure (the last)."""
        nqp = self.scalar_basis.X.shape[1]
        return self._reduce(asm(_lumped_compliance, self.pressure_basis,
                                kappa=np.repeat(self.kappa[:, None], nqp, axis=1)))

    @cached_property
    def _B(self) -> sp.csr_matrix:
        """(npressure, ndof): int q_c div u for the pressure unknowns (see pressure_compliance);
        entry (c, a * dim + i) of an element is sum over points of q_c dN_a/dx_i dx."""
        s, q = self.scalar_basis, self.pressure_basis          # same elements, same quadrature
        G = self.shape_gradients()                                              # (nb, d, M, nqp)
        Q = np.array([np.asarray(q.basis[c][0]) for c in range(q.Nbfun)])       # (nc, M, nqp)
        local = np.einsum("cmq,aimq->mcai", Q * s.dx, G)                        # (M, nc, nb, d)
        rows = np.broadcast_to(q.element_dofs.T[:, :, None], local.shape[:2] + (local.shape[2] * self.dim,))
        cols = np.broadcast_to(self.element_dofs.T[:, None, :], rows.shape)
        B = sp.coo_matrix((local.ravel(), (rows.ravel(), cols.ravel())), shape=(q.N, self.ndof)).tocsr()
        return sp.csr_matrix(self._reduce(B))

    @cached_property
    def pressure_operator(self) -> sp.csr_matrix:
        """(n P1 pressures of pressure_basis, ndof): nodal pressure (mean-stress-like) p = D^-1 B u [MPa]."""
        p = sp.diags(1.0 / self.pressure_compliance) @ self._B
        return (p if self._fluid_tie is None else self._fluid_tie @ p).tocsr()

    @cached_property
    def _fluid_row(self) -> np.ndarray:
        """(ndof,) int div u over the fluid layer: the uniform fluid pressure's row of B."""
        if self._fluid_tie is None:
            raise InputError("this model has no fluid layer (layer 6)")
        return self._B[-1].toarray().ravel()

    @property
    def fluid_pressure_operator(self) -> np.ndarray:
        """(ndof,) row giving the uniform fluid pressure [MPa] from u (positive: tension)."""
        return self._fluid_row / self.pressure_compliance[-1]

    def fluid_volume_change(self, u: np.ndarray) -> float:
        """Linearised volume change of the fluid layer int div u [mm^3; mm^2 in 2D]."""
        return float(self._fluid_row @ u)

    @cached_property
    def _node_pairs(self) -> tuple:
        """The pattern of K_dev, which depends on the mesh only: (pos (M, nb^2) index of each
        element's node pairs (a, b) among the sorted distinct pairs, item (dim, npairs) where the
        dim entries of row i of pair p's block start in K_dev's CSR data, divided by dim, indptr,
        indices). Row a * dim + i of the CSR holds, for every neighbour b of node a in increasing
        order, the columns b * dim + j. Read-only arrays, int32 below 2^31 non-zeros."""
        d, nn, M = self.dim, self.nnodes, self.mesh.nelements
        nodes = self.element_nodes.T                                             # (M, nb)
        pairs, pos = np.unique((nodes[:, :, None] * nn + nodes[:, None, :]).reshape(M, -1), return_inverse=True)
        row, col = pairs // nn, pairs % nn
        start = np.searchsorted(row, np.arange(nn + 1))                         # each node's first pair
        deg = np.diff(start)
        item = d * start[row] + np.arange(d)[:, None] * deg[row] + (np.arange(len(pairs)) - start[row])
        nnz = d * d * len(pairs)
        index = np.int32 if nnz < 2 ** 31 else np.int64
        indptr = np.append((d * d * start[:-1, None] + d * np.arange(d) * deg[:, None]).ravel(), nnz)
        block_col = np.empty(d * len(pairs), index)
        block_col[item] = col
        indices = (d * block_col[:, None] + np.arange(d, dtype=index)).ravel()
        out = pos.reshape(M, -1).astype(index), item.astype(index), indptr.astype(index), indices
        for a in out:
            a.flags.writeable = False       # shared by every K_dev of this mesh (`with_material`)
        return out

    @cached_property
    def K_dev(self) -> sp.csr_matrix:
        """(ndof, ndof) deviatoric stiffness int 2 mu dev eps(u) : dev eps(v) [N/mm].

        Vectorised over elements (skfem's generic assembly is slower for this form): with
        M[a,i,b,j] = int 2 mu dN_a/dx_i dN_b/dx_j (one batched X^T X per element), the block of
        nodes a, b is k[i,j] = d_ij sum_k M[akbk] / 2 + M[ajbi] / 2 - M[aibj] / d. Blocks are
        summed per node pair (bincount) and written straight into CSR order (`_node_pairs`)."""
        d, b = self.dim, self.scalar_basis
        nb, M = b.Nbfun, self.mesh.nelements
        pos, item, indptr, indices = self._node_pairs
        npairs = item.shape[1]
        G = self.shape_gradients()                                               # (nb, d, M, nqp)
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
        D = self.pressure_compliance

        def apply(u):
            Bu = self._B @ u
            return self.K_dev @ u + self._B.T @ (Bu / (D if u.ndim == 1 else D[:, None]))
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
        held = np.unique(self.element_dofs[:, rigid])     # rigid-layer nodes, interfaces too
        held = np.union1d(held, self._inner_fluid_dofs)
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

    @cached_property
    def _inner_fluid_dofs(self) -> np.ndarray:
        """DOFs of fluid nodes off the solid (no stiffness, no load: held, and they hold nothing)."""
        fluid = self.layer == FLUID_LAYER
        return np.setdiff1d(self.element_dofs[:, fluid], self.element_dofs[:, ~fluid])

    def _check_held(self, fixed):
        """Refuse constraints that leave a rigid-body motion free (a singular system)."""
        fixed = np.setdiff1d(fixed, self._inner_fluid_dofs)
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
        Schur complement, then a k^3 inverse); the block is dense, so keep k below ~8,000.
        Along a coordinate axis the node's DOF is used as is; along any other direction the nodes'
        DOFs are rotated so that one of them is the displacement along it, and nodes with some but
        not all DOFs held are left out."""
        fixed, values = self._constraints(prescribed)
        free = np.setdiff1d(np.arange(self.ndof), fixed)
        key = fixed.tobytes()
        have = self._factors.get(key)
        plan = None if condense is None else condense_plan(self, free, *condense)
        if have is None or (plan is not None and not (
                len(have.condensed) and abs(abs(plan[1] @ have.condensed_direction) - 1) < 1e-12
                and np.isin(plan[0], have.condensed_nodes).all())):
            self._check_held(fixed)
            nodes, a, pos, T = plan if plan is not None else (np.zeros(0, int), None, np.zeros(0, int), None)
            order = np.argsort(pos)
            factor = SaddleFactor(self.K_dev, self._B, self.pressure_compliance, pos[order], T, free=free)
            by_node = np.argsort(nodes[order])                  # block index of each sorted node
            factor.condensed_nodes, factor.condensed_direction = nodes[order][by_node], a
            factor.condensed_order = by_node
            self._factors = {key: factor}                       # keep one
        return LinearSystem(self, fixed, values, self._factors[key])

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
    @cached_property
    def point_evaluator(self) -> PointEvaluator:
        """Point location and basis evaluation on this mesh (fem.fields)."""
        return PointEvaluator(self)

    def _points(self, points) -> np.ndarray:
        return np.atleast_2d(np.asarray(points, dtype=float))[:, :self.dim]

    def locate(self, points, layer=None) -> np.ndarray:
        """(n,) element holding each point (n, dim or 3) [mm]; `layer` restricts the search.

        On an interface the element with the point deepest inside wins; give `layer` to choose.
        """
        return self.point_evaluator.locate(self._points(points), layer)

    def _operator(self, points, layer, quantity) -> sp.csr_matrix:
        x = self._points(points)
        return self.point_evaluator.operator(x, self.point_evaluator.locate(x, layer), quantity)

    def displacement_operator(self, points, layer=None) -> sp.csr_matrix:
        """(n * dim, ndof) sparse: displacement [mm] at points, point-major."""
        return self._operator(points, layer, "displacement")

    def strain_operator(self, points, layer=None) -> sp.csr_matrix:
        """(n * ncomp, ndof) sparse: strain tensor components (fem.fields.STRAIN_COMPONENTS) at points."""
        return self._operator(points, layer, "strain")

    def stress_operator(self, points, layer=None) -> sp.csr_matrix:
        """(n * ncomp, ndof) sparse: stress components [MPa] (fem.fields.STRESS_COMPONENTS) at points."""
        return self._operator(points, layer, "stress")

    def __repr__(self):
        kind = "3D tetra10" if self.dim == 3 else "2D plane-strain triangle6"
        return (f"Model({kind}, {self.mesh.nelements} elements, {self.ndof} DOFs, layers "
                f"{sorted(set(self.layer.tolist()))}, material {self.material}, regions {sorted(self.regions)})")
