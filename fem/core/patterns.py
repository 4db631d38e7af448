"""Sparse patterns of the factorised saddle matrix (`fem.core.linalg.SaddleFactor`): free of
round-off entries, carried from one matrix to the next, and filled by a gather.

    drop_round_off(upper)                  the upper triangle without entries at round-off, so the
                                           pattern (and PARDISO's ordering) does not depend on the
                                           order of summation
    onto_pattern(upper, indptr, indices)   a new matrix on an earlier one's pattern, grown by real
                                           entries only: its factorisation reuses the analysis
    Gather(Kdev, B, D, free, ia, ja)       where each entry of that matrix comes from, for inputs of
                                           one pattern: the same matrix by a gather
"""
from __future__ import annotations

import hashlib

import numpy as np
import scipy.sparse as sp

ROUND_OFF = 1e-12


def _round_off(data, indptr, indices, d, rtol: float) -> np.ndarray:
    """(nnz,) bool: the off-diagonal entries of the CSR upper triangle (data, indptr, indices) at or
    below rtol * d_i d_j, d (n,) the square roots of |diagonal|."""
    rows = np.repeat(np.arange(len(indptr) - 1, dtype=indices.dtype), np.diff(indptr))
    scale = d[rows]                     # in place from here: fresh temporaries of the matrix's size
    scale *= d[indices]                 # cost page faults (5x the time on the human 0.5 mm matrix)
    scale *= rtol
    small = np.abs(data) <= scale
    small &= rows != indices
    return small


def _keys(indptr, indices) -> np.ndarray:
    """(nnz,) int64 row n + column of each entry of a CSR pattern with n rows: sorted for sorted
    indices."""
    n = len(indptr) - 1
    return np.repeat(np.arange(n, dtype=np.int64), np.diff(indptr)) * n + indices


def drop_round_off(upper: sp.csr_matrix, rtol: float = ROUND_OFF) -> sp.csr_matrix:
    """The upper triangle (CSR) of a symmetric matrix without its off-diagonal entries below
    rtol * sqrt(|a_ii a_jj|): explicit zeros, and sums that cancel to round-off, whose presence
    depends on the order of summation (a rotation's sparse product keeps 1e-17 and drops 0.0).

    The ordering PARDISO's METIS finds depends on the pattern, and its fill is sensitive to it:
    on the human 0.5 mm first run (13.8 M entries, 22,500 of them below 1e-14 of the diagonal
    scale and none between 1e-14 and 1e-12), patterns differing only in such entries gave
    factorisations of 1,077 to 1,374 GFlop; without them, 1,059. The pattern, and so the ordering
    and the factorisation's cost, then no longer depend on the order of summation (they still
    depend on which layers share a modulus: a sum over two layers' elements cancels only when
    their moduli are equal). The matrix changes by at most rtol of its diagonal scale; residuals
    are still checked against the exact matrix."""
    upper = upper.tocsr(copy=True)
    upper.data[_round_off(upper.data, upper.indptr, upper.indices, np.sqrt(np.abs(upper.diagonal())), rtol)] = 0.0
    upper.eliminate_zeros()
    return upper


def onto_pattern(upper: sp.csr_matrix, indptr, indices, rtol: float = ROUND_OFF) -> sp.csr_matrix:
    """The upper triangle (CSR) `upper` (n, n) on the union of the sorted CSR pattern (indptr
    (n + 1,), indices) and its own entries above `drop_round_off`'s threshold (positions it lacks
    as explicit zeros). A Newton's tangents differ from one another in which entries cancel to
    round-off and in a few that grow from zero as the body deforms: on a pattern carried from one
    tangent to the next, each factorisation but a few reuses the first one's analysis (the 2D
    cylinder with bone, 12,648 unknowns, C5 to 2 mm: 16 ms a factorisation instead of 55 ms)."""
    n = upper.shape[0]
    upper = drop_round_off(upper, rtol)
    upper.sort_indices()
    keys, old = _keys(upper.indptr, upper.indices), _keys(indptr, indices)
    at = np.searchsorted(old, keys)
    extra = keys[old[np.minimum(at, len(old) - 1)] != keys]
    if not extra.size:
        data = np.zeros(len(old))
        data[at] = upper.data
        return sp.csr_matrix((data, indices, indptr), shape=upper.shape)
    union = np.insert(old, np.searchsorted(old, extra), extra)          # both sorted
    data = np.zeros(len(union))
    data[np.searchsorted(union, keys)] = upper.data
    rows = union // n
    return sp.csr_matrix((data, (union - rows * n).astype(np.int32),
                          np.searchsorted(rows, np.arange(n + 1)).astype(np.int32)), shape=upper.shape)


class Gather:
    """Where each entry of a saddle system's factorised upper triangle comes from, for systems of
    one input pattern (Kdev, B, free, D's length) factorised on one pattern (`Pardiso.pattern`):
    `upper` then builds the matrix `onto_pattern` would by a gather, without restricting Kdev to the
    free unknowns and stacking the blocks again (3.4 s of each factorisation's preparation on the
    human 0.5 mm model's neo-Hookean tangent, 25.7 M entries; 0.3 GB per copy)."""

    def __init__(self, Kdev, B, D, free, ia, ja):
        n_k, n_b = Kdev.nnz, B.nnz
        self.key, self.ia, self.ja = self.fingerprint(Kdev, B, D, free), ia, ja
        code = np.arange(1, n_k + n_b + len(D) + 1, dtype=np.float64)      # exact in float64
        Kc = sp.csr_matrix((code[:n_k], Kdev.indices, Kdev.indptr), shape=Kdev.shape)
        Bc = sp.csr_matrix((code[n_k:n_k + n_b], B.indices, B.indptr), shape=B.shape)
        if free is not None:
            Kc, Bc = Kc[free][:, free], Bc[:, free]
        upper = sp.bmat([[sp.triu(Kc), Bc.T], [None, sp.diags(code[n_k + n_b:])]], format="csr")
        n = upper.shape[0]
        keys, old = _keys(upper.indptr, upper.indices), _keys(ia - 1, ja - 1)
        at = np.minimum(np.searchsorted(old, keys), len(old) - 1)
        inside = old[at] == keys
        src = upper.data.astype(np.int64) - 1                              # into concat(Kdev, B, -D)
        self.src = np.full(len(old), n_k + n_b + len(D), dtype=np.int32)    # none: the appended 0
        self.src[at[inside]] = src[inside]
        self.out_src, out = src[~inside], keys[~inside]
        self.out_row, self.out_col = out // n, out % n
        self.diag = np.searchsorted(old, np.arange(n, dtype=np.int64) * (n + 1)).astype(np.int32)
        if not np.array_equal(old[np.minimum(self.diag, len(old) - 1)], np.arange(n, dtype=np.int64) * (n + 1)):
            raise ValueError("the factorised pattern lacks a diagonal entry")

    @staticmethod
    def fingerprint(Kdev, B, D, free) -> bytes:
        h = hashlib.blake2b(digest_size=16)
        for a in (Kdev.indptr, Kdev.indices, B.indptr, B.indices, np.zeros(0) if free is None else free):
            h.update(np.ascontiguousarray(a).view(np.uint8))
        h.update(np.int64(len(D)).tobytes())
        return h.digest()

    def serves(self, key: bytes, ia, ja) -> bool:
        return key == self.key and np.array_equal(ia, self.ia) and np.array_equal(ja, self.ja)

    def upper(self, Kdev, B, D, rtol: float = ROUND_OFF) -> sp.csr_matrix | None:
        """`onto_pattern(upper triangle of [[Kdev, B^T], [B, -D]] on the free unknowns, pattern)`, or
        None when an entry outside the pattern is above round-off (the pattern grows: the caller
        builds it the long way)."""
        s = np.concatenate([Kdev.data, B.data, -np.asarray(D, float), [0.0]])
        data = s[self.src]
        d = np.sqrt(np.abs(data[self.diag]))
        if len(self.out_src):
            v = s[self.out_src]
            diagonal = self.out_row == self.out_col
            kept = np.where(diagonal, v != 0, np.abs(v) > rtol * d[self.out_row] * d[self.out_col])
            if kept.any():
                return None
        indptr, indices = self.ia - 1, self.ja - 1
        data[_round_off(data, indptr, indices, d, rtol)] = 0.0    # drop_round_off's, as explicit zeros
        return sp.csr_matrix((data, indices, indptr), shape=(len(indptr) - 1,) * 2)
