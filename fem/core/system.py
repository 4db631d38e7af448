"""A model's constrained linear system: K restricted to the free DOFs, factorised once
(`fem.core.linalg.SaddleFactor`), with the prescribed displacements bound to it, and the exact
compliance of chosen nodes along a direction (from the factorisation's Schur complement).

    system = model.system(prescribed={...})   # LinearSystem; factorisation cached per constrained-DOF set
    system.u0                  # (ndof,) response to the prescribed displacements alone
    system.solve(f)            # f (ndof,) or (ndof, k) nodal forces [N] -> u, same shape, u = 0 on
                               # constrained DOFs; loads on constrained DOFs are ignored
    u = system.u0 + system.solve(f)            # superposition; system.residual = last relative residual
    system = model.system(prescribed, condense=(nodes, direction))     # + exact compliance block:
    system.compliance(nodes, direction)        # (k, k) [mm/N] along direction, no solves
    system.solve_condensed(nodes, direction)   # (ndof, k) fields of unit forces there: backward
                                               # substitution only
"""
from __future__ import annotations

import logging

import numpy as np
import scipy.sparse as sp

from fem.core.linalg import SaddleFactor

logger = logging.getLogger(__name__)


class LinearSystem:
    """K restricted to the free DOFs, factorised once; prescribed values bound to it.

    Attributes: `fixed` (m,), `free` (ndof - m,) DOF indices; `values` (m,) prescribed
    displacements [mm]; `u0` (ndof,) response to them with no load; `residual` relative
    residual ||K_ff x - b|| / ||b|| of the last solve; `refined` whether the last
    `solve_condensed` refined with gain; `backend` ("pardiso" or "scipy-splu").
    """

    def __init__(self, model, fixed: np.ndarray, values: np.ndarray, factor: SaddleFactor):
        self.model, self.fixed, self.values, self._factor = model, fixed, values, factor
        self.free = np.setdiff1d(np.arange(model.ndof), fixed)
        self.backend = factor.backend
        self.u0 = np.zeros(model.ndof)
        self.u0[fixed] = values
        self._b0 = -(model.K @ self.u0)[self.free]      # load on the free DOFs from the prescribed values
        self.u0[self.free] = self._solve_free(self._b0) if np.any(values) else 0.0
        self.residual_u0 = self.residual if np.any(values) else 0.0
        self.refined = False

    def _solve_free(self, b):
        x = self._factor(b)
        self.residual = self._factor.last_residual
        if self.residual > 1e-6:
            logger.warning(f"linear solve residual {self.residual:.1e} is large: the model is nearly "
                           "singular or badly conditioned")
        return x

    def solve(self, f: np.ndarray) -> np.ndarray:
        """Displacement [mm] (ndof,) or (ndof, k) caused by nodal forces `f` [N], zero on `fixed`."""
        f = np.asarray(f, dtype=float)
        if f.shape[0] != self.model.ndof:
            raise ValueError(f"load vector has {f.shape[0]} rows, the model has {self.model.ndof} DOFs")
        u = np.zeros(f.shape)
        u[self.free] = self._solve_free(f[self.free])
        return u

    def restart_refinement(self) -> None:
        """Forget what earlier solves learnt about refinement (`fem.core.linalg.SaddleFactor`): the next
        solves refine as on a fresh factorisation, so their bits do not depend on the solves before."""
        self._factor.refine_tol = self._factor.REFINE_TOL

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
        axis = coordinate_axis(along)
        held = np.isin(dofs[:, axis], self.fixed) if axis is not None else np.isin(dofs, self.fixed).all(axis=1)
        return pos, have[pos] == nodes, held

    def _condensed_only(self, nodes, direction):
        """(positions in the condensed set (k,), indices of the condensed nodes among `nodes`);
        ValueError unless every node is condensed or held along the direction."""
        pos, inside, held = self._stored(nodes, direction)
        if not (inside | held).all():
            raise ValueError(f"this system stores no compliance along {np.round(direction, 6).tolist()} for "
                             f"{int((~(inside | held)).sum())} of the nodes (not condensed): factorise with "
                             f"condense=")
        return pos, np.flatnonzero(inside)

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
        pos, i = self._condensed_only(nodes, direction)
        order = self._factor.condensed_order[pos[i]]
        block = self._factor.compliance_block()
        if len(i) == len(nodes) == len(block) and np.array_equal(order, np.arange(len(block))):
            return block                                # read-only, shared: no 0.4 GB copy for k = 7,000
        C = np.zeros((len(nodes), len(nodes)))
        C[np.ix_(i, i)] = block[np.ix_(order, order)]
        return C

    def solve_condensed(self, nodes, direction, check: bool = True) -> np.ndarray:
        """(ndof, k) displacement [mm] for a unit force [N] along the unit `direction` at each of the
        P2 nodes (k,), zero on `fixed`: `solve` of those loads, but with the loads on condensed
        unknowns only the backward substitution runs (`fem.core.linalg.SaddleFactor.solve_condensed`).
        Nodes held along the direction give zero columns. check: residual check and refinement
        as `solve` (sets `residual` and `refined`: refinement steps were taken and gained);
        False skips both (`residual` NaN, e.g. once a checked block showed they are not needed).
        Raises ValueError unless every node is `stored`."""
        pos, i = self._condensed_only(nodes, direction)
        tol = self._factor.refine_tol
        u = np.zeros((self.model.ndof, len(pos)))
        if len(i):
            along = self.condensed[1]                   # a condensed unknown is the DOF along a
            axis = coordinate_axis(along)               # coordinate axis, else along itself
            unit = np.eye(self.model.dim)[axis] if axis is not None else along
            sign = np.sign(np.asarray(direction, float)[:self.model.dim] @ unit)
            u[np.ix_(self.free, i)] = sign * self._factor.solve_condensed(self._factor.condensed_order[pos[i]], check)
        f = self._factor
        self.residual = f.last_residual if len(i) else 0.0
        self.refined = bool(len(i) and f.refinements > 0 and f.refine_tol == tol)
        if self.residual > 1e-6:
            logger.warning(f"linear solve residual {self.residual:.1e} is large: the model is nearly "
                           "singular or badly conditioned")
        return u

    def displacement(self, f: np.ndarray | None = None) -> np.ndarray:
        """u0 + solve(f); sets `residual` to that of the combined system."""
        if f is None:
            self.residual = self.residual_u0
            return self.u0.copy()
        u = self.u0 + self.solve(f)
        self.residual = self._factor.residual(u[self.free], f[self.free] + self._b0)
        return u


def coordinate_axis(a) -> int | None:
    """Index of the coordinate axis the unit vector `a` lies along (either sign), else None."""
    axis = np.flatnonzero(np.abs(np.asarray(a, float)) > 1 - 1e-12)
    return int(axis[0]) if axis.size else None


def condense_plan(model, free, nodes, direction):
    """(nodes (k,), unit direction (dim,), free-DOF position of each node's displacement along
    it (k,), rotation T (n_free, n_free) or None) for `Model.system(condense=...)`;
    free: (n_free,) sorted free DOFs, nodes (k,) P2 nodes, direction (dim or 3,)."""
    a = np.asarray(direction, float)[:model.dim]
    a = a / np.linalg.norm(a)
    nodes = np.unique(np.asarray(nodes, int))
    dofs = model.node_dofs(nodes)
    is_free = np.zeros(model.ndof, bool)
    is_free[free] = True
    axis = coordinate_axis(a)
    if axis is not None:                                # a coordinate axis: its DOF as is
        keep = is_free[dofs[:, axis]]
        return nodes[keep], a, np.searchsorted(free, dofs[keep, axis]), None
    keep = is_free[dofs].all(axis=1)
    nodes, pos = nodes[keep], np.searchsorted(free, dofs[keep])        # (k, dim)
    e0 = np.eye(model.dim)[np.argmin(np.abs(a))]        # local axes (rows); local 1 = along a
    e0 = e0 - (e0 @ a) * a
    e0 /= np.linalg.norm(e0)
    Q = np.array([e0, a] + ([np.cross(e0, a)] if model.dim == 3 else []))
    rows = np.repeat(pos, model.dim, axis=1).ravel()    # x_global[r] = sum_c Q[c, r] x_local[c]
    cols = np.tile(pos, (1, model.dim)).ravel()
    vals = np.tile(Q.T.ravel(), len(nodes))
    rest = np.setdiff1d(np.arange(len(free)), pos.ravel())
    T = sp.csr_matrix((np.r_[vals, np.ones(len(rest))], (np.r_[rows, rest], np.r_[cols, rest])),
                      shape=(len(free), len(free)))
    return nodes, a, pos[:, 1], T
