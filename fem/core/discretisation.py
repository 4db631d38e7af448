"""The discretisation of a layered mesh: its P2 displacement and layer-wise P1 pressure spaces and
everything built from the mesh and its layers alone (nodes, regions, bases, the divergence matrix
B, the stiffness pattern, point location). A `fem.core.model.Model` puts a material on it; every
model of one mesh shares one Discretisation, so a cache here can never hold a material's numbers.

    disc = Discretisation.from_mesh("mesh.vtu")      # or Discretisation(points, cells, layer, regions)
    disc.nodes (nnodes, dim) mm; disc.node_dofs(nodes) (n, dim); disc.surface_nodes("volar")
    disc.B (npressure, ndof); disc.stiffness_pattern; disc.locator.locate(points)

Node k has DOFs dim * k + c; the P2 nodes are the mesh vertices, then one midside node per edge
(3D) or facet (2D), in skfem's order (also VTK's tetra10 and triangle6 order).
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import meshio
import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components
from skfem import (
    Basis,
    ElementTetP1,
    ElementTetP2,
    ElementTriP1,
    ElementTriP2,
    ElementVector,
    MeshTet,
    MeshTri,
)

from fem.core.fields import PointLocator
from fem.core.materials import FLUID_LAYER
from fingertip.errors import InputError


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


class Discretisation:
    """A layered mesh and its spaces (no material).

    Parameters
    ----------
    points : (N, 2 or 3) vertex coordinates [mm]; a 2D mesh uses x, y.
    cells : (M, 4) linear tetrahedra (3D) or (M, 3) triangles (2D plane strain).
    layer : (M,) positive int layer id per cell.
    regions : name -> bool/uint8 (N,) vertex flags, or an int array of vertex ids. A region is the
        boundary facets whose vertices are all flagged; its nodes are the flagged vertices plus
        the midside nodes of those facets.
    """

    def __init__(self, points, cells, layer, regions=None):
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
        self.regions = {name: self._flags(name, v) for name, v in (regions or {}).items()}

    @classmethod
    def from_mesh(cls, path) -> "Discretisation":
        """Read `mesh.vtu` (meshio): `tetra` (3D) or `triangle` (2D) cells, cell data `layer`,
        point data region flags (0/1 integer arrays)."""
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
        return cls(m.points, cells, layer, regions)

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

    # ------------------------------------------------------------------ nodes and DOFs
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
        return self.mesh.nvertices + self.edges.shape[1]

    @property
    def ndof(self) -> int:
        return self.dim * self.nnodes

    @cached_property
    def nodes(self) -> np.ndarray:
        """(nnodes, dim) coordinates [mm] of all P2 nodes (the basis's DOF locations)."""
        p = self.mesh.p
        return np.vstack([p.T, 0.5 * (p[:, self.edges[0]] + p[:, self.edges[1]]).T])

    @cached_property
    def edges(self) -> np.ndarray:
        """(2, n) vertex pairs of the midside nodes, in node order after the vertices."""
        return self.mesh.edges if self.dim == 3 else self.mesh.facets

    @cached_property
    def locator(self) -> PointLocator:
        """Point location and shape functions at points of this mesh (fem.core.fields)."""
        return PointLocator(self)

    # ------------------------------------------------------------------ regions
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
        corners (as fem.contact.linear.trace_areas): 3D A/12 per vertex and A/4 per edge node, 2D
        L/4 and L/2; without midside nodes A/3 (3D) or L/2 (2D) per vertex.
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

    # ------------------------------------------------------------------ pressure space and B
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
    def fluid_tie(self) -> sp.csr_matrix | None:
        """(n P1 pressures, n unknown pressures): every P1 pressure of the fluid layer
        (fem.core.materials.FLUID_LAYER) tied to one uniform fluid pressure (hydrostatic, as the
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

    def reduce(self, a):
        """P1 pressure rows (n, ...) summed into the unknown pressures (`fluid_tie`)."""
        return a if self.fluid_tie is None else self.fluid_tie.T @ a

    @cached_property
    def B(self) -> sp.csr_matrix:
        """(npressure, ndof) divergence matrix: int q_c div u for the pressure unknowns (the P1
        pressures, with a fluid layer's tied into one); entry (c, a * dim + i) of an element is
        sum over points of q_c dN_a/dx_i dx."""
        s, q = self.scalar_basis, self.pressure_basis          # same elements, same quadrature
        G = self.shape_gradients()                                              # (nb, d, M, nqp)
        Q = np.array([np.asarray(q.basis[c][0]) for c in range(q.Nbfun)])       # (nc, M, nqp)
        local = np.einsum("cmq,aimq->mcai", Q * s.dx, G)                        # (M, nc, nb, d)
        rows = np.broadcast_to(q.element_dofs.T[:, :, None], local.shape[:2] + (local.shape[2] * self.dim,))
        cols = np.broadcast_to(self.element_dofs.T[:, None, :], rows.shape)
        B = sp.coo_matrix((local.ravel(), (rows.ravel(), cols.ravel())), shape=(q.N, self.ndof)).tocsr()
        return sp.csr_matrix(self.reduce(B))

    @cached_property
    def fluid_row(self) -> np.ndarray:
        """(ndof,) int div u over the fluid layer: the uniform fluid pressure's row of B."""
        if self.fluid_tie is None:
            raise InputError("this model has no fluid layer (layer 6)")
        return self.B[-1].toarray().ravel()

    @cached_property
    def inner_fluid_dofs(self) -> np.ndarray:
        """DOFs of fluid nodes off the solid (no stiffness, no load: held, and they hold nothing)."""
        fluid = self.layer == FLUID_LAYER
        return np.setdiff1d(self.element_dofs[:, fluid], self.element_dofs[:, ~fluid])

    @cached_property
    def stiffness_pattern(self) -> tuple:
        """The CSR pattern of a stiffness matrix on this mesh: (pos (M, nb^2) index of each
        element's node pairs (a, b) among the sorted distinct pairs, item (dim, npairs) where the
        dim entries of row i of pair p's block start in the CSR data, divided by dim, indptr,
        indices). Row a * dim + i holds, for every neighbour b of node a in increasing order, the
        columns b * dim + j. Read-only arrays, int32 below 2^31 non-zeros."""
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
            a.flags.writeable = False       # shared by every stiffness matrix of this mesh
        return out

    # ------------------------------------------------------------------ constraints
    def prescribed_values(self, name, spec) -> tuple[np.ndarray, np.ndarray]:
        """(DOFs (k,), values (k,) mm) a region's prescribed displacement `spec` fixes (see
        `fem.core.model` for the forms of spec; NaN components stay free)."""
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
            full = np.vstack([per_vertex, per_vertex[self.edges].mean(axis=0)])
            vals = full[nodes]
        else:
            comp = np.array([np.nan if c is None else c for c in np.broadcast_to(
                np.asarray(spec, dtype=object), (self.dim,))], dtype=float)
            vals = np.broadcast_to(comp, (len(nodes), self.dim))
        dofs = self.node_dofs(nodes)
        keep = ~np.isnan(vals)
        return dofs[keep], vals[keep]

    def constraints(self, prescribed, rigid_layers=()) -> tuple[np.ndarray, np.ndarray]:
        """(sorted constrained DOFs (m,), values (m,) mm) of prescribed displacements per region,
        with every node of the rigid layers and the fluid's inner nodes held at zero. InputError
        where two regions prescribe different values to one DOF."""
        dofs, vals = [], []
        for name, spec in (prescribed or {}).items():
            d, v = self.prescribed_values(name, spec)
            dofs.append(d)
            vals.append(v)
        rigid = np.isin(self.layer, list(rigid_layers))
        held = np.unique(self.element_dofs[:, rigid])     # rigid-layer nodes, interfaces too
        held = np.union1d(held, self.inner_fluid_dofs)
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

    def check_held(self, fixed) -> None:
        """Refuse constraints that leave a rigid-body motion free (a singular system)."""
        fixed = np.setdiff1d(fixed, self.inner_fluid_dofs)
        n, d = self.mesh.nvertices, self.dim
        t = self.mesh.t
        adj = sp.coo_matrix((np.ones(t.size), (np.repeat(t[0], t.shape[0]), t.T.ravel())), shape=(n, n))
        _, label = connected_components(adj, directed=False)
        node_label = np.concatenate([label, label[self.edges[0]]])
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

    def __repr__(self):
        kind = "3D tetra10" if self.dim == 3 else "2D plane-strain triangle6"
        return (f"Discretisation({kind}, {self.mesh.nelements} elements, {self.ndof} DOFs, layers "
                f"{sorted(set(self.layer.tolist()))}, regions {sorted(self.regions)})")
