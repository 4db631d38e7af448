"""Compliance of contact candidates along an approach direction: the (m, m) operator C [mm/N]
(a unit force along the approach at candidate j moves candidate i by C_ij along it) and the
observed response O K^-1 B (receptor strains, deflections) per unit force.

- `MatrixCompliance`: a given dense C (analytic bodies, e.g. a half-space);
- `FactorCompliance`: columns of B^T K^-1 B computed lazily from a factorised stiffness, many
  right-hand sides per solve, and cached;
- `CondensedCompliance`: all of C at once as the inverse of the Schur complement of a system
  factorised with the candidates condensed (`Model.system(condense=...)`), no solves.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from fingertip.errors import InputError


class RowCache:
    """Vectors (length,) fetched once each by index and kept as the rows of `data`; the rows grow
    by doubling. fetch: sorted unique indices (k,) -> (k, length); count: how many indices exist.

        cache = RowCache(lambda i: WT[i], len(WT), WT.shape[1])
        rows = cache.data[cache.slots(idx)]          # (len(idx), length)
    """

    def __init__(self, fetch, count: int, length: int):
        self._fetch = fetch
        self._slot = np.full(count, -1)
        self.data = np.empty((0, length))
        self.size = 0

    def slots(self, idx) -> np.ndarray:
        """(len(idx),) rows of `data` holding the vectors idx, fetching the new ones (call it
        before reading `data`: it may replace the array)."""
        idx = np.asarray(idx, int)
        new = np.unique(idx[self._slot[idx] < 0])
        if new.size:
            n = self.size
            if n + new.size > len(self.data):
                grown = np.empty((min(max(2 * len(self.data), n + new.size, 16), len(self._slot)), self.data.shape[1]))
                grown[:n] = self.data[:n]
                self.data = grown
            self.data[n:n + new.size] = self._fetch(new)
            self._slot[new] = np.arange(n, n + new.size)
            self.size += new.size
        return self._slot[idx]


class Compliance:
    """Cached compliance columns: C[:, j] (m,) and observed response O K^-1 B e_j (r,).

    Subclasses implement `_compute(idx) -> (m + r, len(idx))`.
    """

    def __init__(self, m: int, r: int):
        self.m, self.r = m, r
        self.held = np.zeros(m, bool)       # nodes that cannot move along the approach (zero compliance)
        self.reach = np.ones(m, bool)       # nodes whose compliance is available (see CondensedCompliance)
        self._cache = RowCache(lambda i: self._compute(i).T, m, m + r)      # one row per candidate

    @property
    def computed(self) -> int:
        """Candidates whose columns have been computed."""
        return self._cache.size

    def _column_rows(self, idx) -> np.ndarray:
        """(len(idx), m + r) the computed columns of candidates idx, one per row."""
        slots = self._cache.slots(idx)
        return self._cache.data[slots]

    def columns(self, idx) -> np.ndarray:
        """(m, k) compliance columns (mm/N) of candidate nodes idx."""
        return self._column_rows(idx)[:, :self.m].T

    def block(self, rows, cols) -> np.ndarray:
        """(len(rows), len(cols)) compliance (mm/N) between candidate nodes."""
        return self.columns(cols)[np.asarray(rows, int)]

    def observed(self, idx) -> np.ndarray:
        """(r, k) observed response per unit force at candidate nodes idx."""
        return self._column_rows(idx)[:, self.m:].T

    def observe(self, force_N) -> np.ndarray:
        """(r,) or (r, k) observed response to nodal contact forces (m,) or (m, k): cached
        columns times the forces."""
        force_N = np.asarray(force_N, float)
        act = np.flatnonzero(np.any(force_N.reshape(self.m, -1) != 0, axis=1))
        if not act.size:
            return np.zeros((self.r,) + force_N.shape[1:])
        return self.observed(act) @ force_N[act]


class MatrixCompliance(Compliance):
    """A given dense compliance (m, m) and optional observation response (r, m): analytic models."""

    def __init__(self, C, observed=None):
        C = np.asarray(C, float)
        R = np.zeros((0, len(C))) if observed is None else np.asarray(observed, float)
        super().__init__(len(C), len(R))
        self._full = np.vstack([C, R])
        self.held = np.diag(C) == 0

    def _compute(self, idx):
        return self._full[:, idx]


class FactorCompliance(Compliance):
    """Compliance from a factorised stiffness; columns are computed `chunk` right-hand sides at a time.

    solve: callable (n_dofs, k) load -> (n_dofs, k) displacement (the factorised, constrained
    system); n_dofs: its size; dofs: (m, dim) DOF index of each candidate node's components; direction: (dim,)
    unit force direction (3,) (its x, y part in 2D); observe: optional sparse (r, n_dofs) observation operator;
    fixed: optional constrained DOF indices (nodes held along the direction are marked `held`).
    """

    def __init__(self, solve, n_dofs: int, dofs, direction, observe=None, chunk: int = 64, fixed=None):
        dofs = np.asarray(dofs)
        m, dim = dofs.shape
        if dim == 2 and abs(direction[2]) > 1e-12:
            raise InputError("a 2D model can only be indented within its x-y plane: use incline 0")
        rows = dofs.ravel()
        cols = np.repeat(np.arange(m), dim)
        vals = np.tile(np.asarray(direction, float)[:dim], m)
        self.n_dofs = n_dofs
        self.B = sp.csc_matrix((vals, (rows, cols)), shape=(self.n_dofs, m))
        O = sp.csr_matrix((0, self.n_dofs)) if observe is None else sp.csr_matrix(observe)
        self.O = sp.vstack([self.B.T, O]).tocsr()
        super().__init__(m, O.shape[0])
        self.solve, self.chunk = solve, chunk
        if fixed is not None:
            moves = np.abs(np.asarray(direction, float)[:dim]) > 0
            self.held = np.all(np.isin(dofs, fixed) | ~moves, axis=1)

    def _compute(self, idx):
        return self._respond(self.B[:, idx])

    def _respond(self, loads) -> np.ndarray:
        """(m + r, k) O K^-1 loads for sparse loads (n_dofs, k) [N], `chunk` columns per solve
        (only a chunk is ever dense)."""
        loads = sp.csc_matrix(loads)
        out = np.empty((self.m + self.r, loads.shape[1]))
        for s in range(0, loads.shape[1], self.chunk):
            u = self.solve(np.asfortranarray(loads[:, s:s + self.chunk].toarray()))
            out[:, s:s + self.chunk] = self.O @ np.asarray(u).reshape(self.n_dofs, -1)
        return out

    def displacement(self, force_N) -> np.ndarray:
        """(n_dofs,) full displacement field for nodal contact forces (m,), or (n_dofs, k) for k
        force vectors (m, k): one solve with k right-hand sides."""
        F = np.asarray(force_N, float)
        u = np.asarray(self.solve(np.asfortranarray(self.B @ F.reshape(self.m, -1))))
        return u.reshape(-1) if F.ndim == 1 else u.reshape(-1, F.shape[1])


class DenseReach:
    """Columns and blocks of a dense compliance C (k, k) over the candidates in `reach` (m,) bool;
    the other candidates' rows are NaN (they cannot carry force). Mixed into a Compliance; the
    rows of C come from `_rows` (C is symmetric, so a column is a row: contiguous memory, several
    times faster to gather than columns or np.ix_ blocks of a large C)."""

    def _dense(self, reach, diagonal, C=None) -> None:
        """reach (m,) bool, diagonal (k,) of C; C (k, k) unless `_rows` is overridden."""
        self.reach = np.asarray(reach, bool)
        self._C = C
        self._row = np.cumsum(self.reach) - 1                       # candidate -> row of C
        self.held = np.zeros(self.m, bool)
        self.held[self.reach] = np.asarray(diagonal) == 0

    def _rows(self, rows) -> np.ndarray:
        """(len(rows), k) rows of C."""
        return self._C[rows]

    def columns(self, idx) -> np.ndarray:
        cols = self._rows(self._row[np.asarray(idx, int)]).T
        if self.reach.all():
            return cols
        out = np.full((self.m, cols.shape[1]), np.nan)
        out[self.reach] = cols
        return out

    def block(self, rows, cols) -> np.ndarray:
        return self._rows(self._row[np.asarray(cols, int)])[:, self._row[np.asarray(rows, int)]].T


class CondensedCompliance(DenseReach, FactorCompliance):
    """The whole compliance at once from a system factorised with `condense=(nodes, approach)` on
    the candidates (`LinearSystem.compliance`: the inverse of their Schur complement, no solves);
    observations take one solve per indentation (in blocks, `ContactModel.observe_pending`)
    instead of cached columns. Arguments as FactorCompliance, plus the LinearSystem and the
    candidates' P2 node ids (m,).

    When only some candidates were condensed (`reach`, e.g. those a scene's indentors can touch),
    compliance rows of the others are NaN: they cannot carry force, and their deflection comes
    with the observation solve. Raises ValueError when none was condensed along the direction."""

    def __init__(self, system, nodes, dofs, direction, observe=None, chunk: int = 64):
        super().__init__(system.solve, system.model.ndof, dofs, direction, observe, chunk)
        reach = system.stored(nodes, direction)                     # the same for -direction
        if not reach.any():
            raise ValueError("no candidate has a stored compliance along this direction")
        C = system.compliance(np.asarray(nodes)[reach], direction)
        self._dense(reach, np.diag(C), C)

    def observed(self, idx) -> np.ndarray:
        raise NotImplementedError("a condensed compliance observes whole force vectors: use observe()")

    def response(self, force_N) -> tuple[np.ndarray, np.ndarray]:
        """((m, k) deflections of every candidate along the direction, (r, k) observed response) to
        nodal contact forces (m, k): one solve per force vector, `chunk` of them per call."""
        F = np.asarray(force_N, float).reshape(self.m, -1)
        out = self._respond(self.B @ sp.csc_matrix(F))
        return out[:self.m], out[self.m:]

    def observe(self, force_N) -> np.ndarray:
        """(r,) or (r, k) observed response to nodal contact forces (m,) or (m, k)."""
        if not self.r:
            return np.zeros((0,) + np.shape(force_N)[1:])
        return self.response(force_N)[1].reshape((self.r,) + np.shape(force_N)[1:])
