"""Entries of the inverse of a sparse symmetric matrix by MUMPS (ICNTL(30)), for the stored
response models (`fem.experiments.response`): a factorisation with no ordering constraint, then
per block of unit right-hand sides a forward substitution pruned to their paths and a backward one
stopped at the rows asked for. On the human 0.5 mm model's whole pad: factorisation and entries
133 s against about 200 s for PARDISO's Schur complement and backward substitutions
(docs/indentation.md, benchmarks/prepare_mumps.py).

Optional: python-mumps over the system's MUMPS library (Debian: libmumps-seq-dev; PyPI has
python-mumps only as a source package that builds against it). Without it `available()` is False
and the response models are built by PARDISO.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

ORDERING = "scotch"
"""The fill-reducing ordering: the best of Debian's build (no METIS) on the human 0.5 mm model
(356 M factor non-zeros; PORD 368 M, AMF 463 M)."""
RHS_BLOCK = 128
"""MUMPS's right-hand-side blocking in the solve (ICNTL(27)), and the columns `fem.experiments.
response` asks for per solve: on the human 0.5 mm model, 3 blocks of 128 candidates, 12.7 ms per
candidate against 12.95 ms at 64 and 15.1 ms at 32 (9.5 s for a block of 512 at 512)."""


def available() -> bool:
    """Whether python-mumps and its library load."""
    try:
        import mumps  # noqa: F401
    except ImportError:
        return False
    return True


class InverseEntries:
    """A^-1 restricted to given rows and columns, for A (n, n) sparse symmetric (indefinite allowed)
    given by its upper triangle, factorised once (LDL^T with pivoting), in core or with the factor
    on disk (`out_of_core`: on the human 0.5 mm model 3.1 GB peak instead of 5.5 GB, 1.7 times the
    time). `stats`: MUMPS's factorisation statistics (memory MB, non-zeros)."""

    def __init__(self, upper: sp.spmatrix, out_of_core: bool = False):
        import mumps

        self.n = upper.shape[0]
        self._ctx = mumps.Context()
        self._ctx.set_matrix(sp.coo_matrix(upper), symmetric=True)
        self._ctx.analyze(ordering=ORDERING)
        self._ctx.factor(reuse_analysis=True, ooc=out_of_core)
        self.stats = self._ctx.factor_stats
        inst = self._ctx.mumps_instance
        inst.icntl[27], inst.icntl[30], inst.icntl[20] = RHS_BLOCK, 1, 1     # blocking; entries of A^-1; sparse

    def block(self, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """(len(rows), len(cols)) A^-1[rows][:, cols]: rows (r,) sorted unique, cols (c,) unique
        indices; one MUMPS solve (keep c to a few hundred: it holds r c values)."""
        from mumps import _mumps

        rows, cols = np.asarray(rows), np.asarray(cols)
        order = np.argsort(cols)
        counts = np.zeros(self.n, int)
        counts[cols] = len(rows)                       # MUMPS takes all n columns, most of them empty
        ptr = (np.r_[0, np.cumsum(counts)] + 1).astype(_mumps.int_dtype)
        ind = (np.tile(rows, len(cols)) + 1).astype(_mumps.int_dtype)
        values = np.zeros(len(ind))
        inst = self._ctx.mumps_instance
        inst.set_sparse_rhs(ptr, ind, values)
        inst.job = 3
        self._ctx.call()
        out = np.empty((len(rows), len(cols)))
        out[:, order] = values.reshape(len(cols), len(rows)).T
        return out

    def release(self) -> None:
        """Free MUMPS's factor (python-mumps ends the instance, JOB = -2, when it is collected)."""
        self._ctx = None
