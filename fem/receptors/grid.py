"""Receptor grids: points at given depths below the undeformed skin surface, and their measures.

Receptors sit 0.5-1.0 mm below the skin (Merkel cells 0.75 mm typical), about 1 mm apart
(thesis 2.1.2). A grid is a set of surface sites (nodes of the contact region thinned to a
spacing, or those along a line) each repeated at every depth along the inward surface normal.
Fields are sampled in the element that holds each point (the solver's point operators), so
nothing is averaged across a layer interface. A receptor within INTERFACE_SNAP_MM of a layer
interface of the mesh (the default 0.5 mm depth is the epidermis thickness, and meshes place
interfaces only to about 0.02 mm) is sampled in the deeper layer, moved along its normal by at
most INTERFACE_SNAP_MM (`ReceptorSampler.shift_mm`), so neighbouring receptors agree on a side.

    grid = receptor_grid(sn.x, sn.normal, depths_mm=(0.5, 0.75, 1.0), spacing_mm=1.0)
    sampler = ReceptorSampler(model, grid)            # sampler.operator: sparse (r, ndof)
    values = sampler.measures(sampler.operator @ u, ["sed_MPa", "max_compressive_strain"])
"""
from __future__ import annotations

import copy
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from fem.core.fields import hooke_matrix
from fem.core.measures import State, check_names, evaluate
from fingertip.errors import InputError

DEFAULT_DEPTHS_MM = (0.5, 0.75, 1.0)
INTERFACE_SNAP_MM = 0.03
"""Receptors this close to a mesh layer interface are sampled in the deeper layer (mm); larger
than the 0.013 mm by which pytetwild's interfaces were measured to stray from the model shells."""
DEFAULT_MEASURES = ("sed_MPa", "max_compressive_strain", "max_shear_strain", "strain_yy")


@dataclass(frozen=True)
class ReceptorGrid:
    """points_mm (n, dim); depth_mm (n,); site (n,) index into sites_mm (k, dim) on the surface."""
    points_mm: np.ndarray
    depth_mm: np.ndarray
    site: np.ndarray
    sites_mm: np.ndarray


def receptor_grid(surface_x, surface_normal, depths_mm=DEFAULT_DEPTHS_MM, spacing_mm: float = 1.0,
                  line: tuple[int, float] | None = None) -> ReceptorGrid:
    """Receptor points below surface nodes (m, dim) with outward unit normals (m, dim).

    Sites are the surface nodes thinned to one per spacing_mm cube (the one nearest its centre).
    The cubes are centred on multiples of spacing_mm, so a row of sites lies on x = 0, the pad's
    midline (and on the default indentor position). line=(axis, value): only nodes within
    spacing_mm / 2 of the plane x[axis] = value, moved onto it (a profile across the pad, e.g.
    (2, 0.0) for the section z = 0 of a 3D finger); with a line the spacing is kept along the line
    only. `site` numbers the sites in the order of their cubes (a stable id within one grid).
    """
    x, n = np.asarray(surface_x, float), np.asarray(surface_normal, float)
    depths = np.atleast_1d(np.asarray(depths_mm, float))
    if np.any(depths <= 0) or not spacing_mm > 0:
        raise InputError("receptor depths and spacing must be positive (mm)")
    if line is not None:
        axis, value = int(line[0]), float(line[1])
        keep = np.abs(x[:, axis] - value) <= 0.5 * spacing_mm
        if not keep.any():
            raise InputError(f"no surface nodes near the line x[{axis}] = {value} mm: pick a value "
                             f"inside the model")
        x, n = x[keep].copy(), n[keep]
        x[:, axis] = value
    cell = np.floor(x / spacing_mm + 0.5).astype(np.int64)
    if line is not None:
        cell[:, line[0]] = 0
    centre = cell * spacing_mm
    dist = np.linalg.norm(x - centre, axis=1)
    order = np.lexsort((dist, *cell.T[::-1]))
    _, first = np.unique(cell[order], axis=0, return_index=True)
    pick = order[first]
    sites, normals = x[pick], n[pick]
    k = len(sites)
    pts = (sites[None] - depths[:, None, None] * normals[None]).reshape(-1, x.shape[1])
    return ReceptorGrid(pts, np.repeat(depths, k), np.tile(np.arange(k), len(depths)), sites)


class ReceptorSampler:
    """Point operators of a `fem.core.model.Model` at the receptor points, stacked in one sparse
    (r, ndof) matrix `operator` (displacement, strain, stress), and measures from its output.
    The stress block is the strain block mapped point by point (`fem.core.fields.hooke_matrix`
    with the Lame moduli `lame_MPa` (n, 2) of each point's element), so the first `independent`
    rows of an output give the rest (`complete_outputs`)."""

    def __init__(self, model, grid: ReceptorGrid):
        pts, self.shift_mm = _off_interfaces(model, grid)
        self.points_mm = pts                    # (n, dim) where the operators sample (off interfaces)
        self.dim, self.n = model.dim, len(pts)
        cells = model.locate(pts)
        self.lame_MPa = np.column_stack([model.mu[cells], model.lam[cells]])
        strain = model.strain_operator(pts)
        hooke = hooke_matrix(self.lame_MPa[:, 0], self.lame_MPa[:, 1], self.dim)
        blocks = [model.displacement_operator(pts), strain, (hooke @ strain).tocsr()]
        self.sizes = [b.shape[0] for b in blocks]
        self.operator = sp.vstack(blocks).tocsr()
        self.grid = grid

    @classmethod
    def without_operator(cls, dim: int, grid: ReceptorGrid, shift_mm) -> "ReceptorSampler":
        """A sampler that only turns operator outputs computed elsewhere (a stored response model,
        `fem.experiments.response`) into measures: no model, `operator` and `lame_MPa` None;
        shift_mm (n,) as `shift_mm`."""
        self = cls.__new__(cls)
        self.dim, self.n, self.grid = dim, len(grid.points_mm), grid
        self.shift_mm = np.asarray(shift_mm, float)
        self.lame_MPa = None
        self.sizes = [self.n * c for c in ((3, 6, 6) if dim == 3 else (2, 3, 4))]
        self.operator = None
        return self

    @property
    def independent(self) -> int:
        """The leading rows of `operator` (displacement and strain) that determine the rest
        (`complete_outputs`)."""
        return self.sizes[0] + self.sizes[1]

    @property
    def stress_rows(self) -> slice:
        """The rows of `operator` (and of its output) that hold the stress block."""
        return slice(self.independent, self.independent + self.sizes[2])

    def with_energy(self) -> "ReceptorSampler":
        """This sampler reading a fourth block of values, the stored energy per reference volume
        (n,) of finite kinematics (`fem.contact.finite.FiniteContact.observe`)."""
        other = copy.copy(self)
        other.sizes = list(self.sizes[:3]) + [self.n]
        return other

    def state(self, values) -> State:
        """Measures state from `operator @ u` (r,) (with_energy: the finite state's four blocks)."""
        blocks = np.split(np.asarray(values, float), np.cumsum(self.sizes)[:-1])
        u, e, s = blocks[:3]
        n, d = self.n, self.dim
        disp = np.zeros((n, 3))
        disp[:, :d] = u.reshape(n, d)
        if d == 3:
            strain = _sym(e.reshape(n, 6), (0, 1, 2, 1, 0, 0), (0, 1, 2, 2, 2, 1))
            stress = _sym(s.reshape(n, 6), (0, 1, 2, 1, 0, 0), (0, 1, 2, 2, 2, 1))
        else:
            strain = _sym(e.reshape(n, 3), (0, 1, 0), (0, 1, 1))
            stress = _sym(s.reshape(n, 4), (0, 1, 2, 0), (0, 1, 2, 1))
        return State(disp, strain, stress, blocks[3] if len(blocks) > 3 else None)

    def measures(self, values, names=DEFAULT_MEASURES) -> dict[str, np.ndarray]:
        """{name: (n,) values at the receptor points}."""
        return evaluate(check_names(names), self.state(values))


def complete_outputs(values, hooke) -> np.ndarray:
    """(r, ...) receptor operator outputs (displacement, strain, stress blocks) from their first
    two blocks (independent, ...): the stress block appended, computed from the strain block (the
    last hooke.shape[1] rows) with the points' `fem.core.fields.hooke_matrix` hooke."""
    values = np.asarray(values, float)
    strain = values[len(values) - hooke.shape[1]:]
    stress = hooke @ strain.reshape(len(strain), -1)
    return np.concatenate([values, stress.reshape((-1,) + values.shape[1:])])


def _off_interfaces(model, grid: ReceptorGrid, snap_mm: float = INTERFACE_SNAP_MM):
    """Receptor points (n, dim) with those near a layer interface moved into the deeper layer,
    and the shift of each (n,) in mm (0 for most)."""
    pts = np.array(grid.points_mm, dtype=float)     # a copy: the grid keeps the placed points
    shift = np.zeros(len(pts))
    ok = grid.depth_mm > snap_mm
    normal = np.zeros_like(pts)                     # outward unit normal of each receptor's site
    normal[ok] = (grid.sites_mm[grid.site[ok]] - pts[ok]) / grid.depth_mm[ok, None]

    def layer_at(x):
        return model.layer[model.locate(x)]

    idx = np.flatnonzero(ok)
    deep = layer_at(pts[idx] - snap_mm * normal[idx])
    near = np.flatnonzero(deep != layer_at(pts[idx] + snap_mm * normal[idx]))
    idx, deep = idx[near], deep[near]
    for step in np.linspace(0.0, snap_mm, 7):       # the smallest move that lands in the deeper layer
        if not len(idx):
            break
        moved = pts[idx] - step * normal[idx]
        done = layer_at(moved) == deep
        pts[idx[done]], shift[idx[done]] = moved[done], step
        idx, deep = idx[~done], deep[~done]
    return pts, shift


def _sym(comp, rows, cols):
    t = np.zeros((len(comp), 3, 3))
    for k, (i, j) in enumerate(zip(rows, cols)):
        t[:, i, j] = t[:, j, i] = comp[:, k]
    return t
