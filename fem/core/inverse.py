"""Entries of the inverse of a sparse symmetric matrix by MUMPS (ICNTL(30)), for the stored
response models (`fem.experiments.response`): a factorisation with no ordering constraint, then
per block of unit right-hand sides a forward substitution pruned to their paths and a backward one
stopped at the rows asked for. The whole `prepare` command on the human 0.5 mm model: 141 s against
191-214 s with PARDISO's Schur complement and backward substitutions on one machine, 203-228 s
against 339 s on a slower one (docs/indentation.md, benchmarks/prepare_mumps.py).

Optional: python-mumps over the system's MUMPS library (Debian: libmumps-seq-dev; PyPI has
python-mumps only as a source package that builds against it). Without it `available()` is False
and the response models are built by PARDISO.

MUMPS does its dense work in the system's BLAS. Debian 12's OpenBLAS (0.3.21) does not recognise
newer processors and falls back to its slowest kernel: on a Xeon with AVX-512 that it reported as
"Prescott", dgemm ran at 16 GFlop/s against 149 with the SkylakeX kernel, and the human 0.5 mm
model's factorisation took 80 s against 41 s. So the first import of MUMPS names the kernel the
processor's flags allow (`openblas_kernel`) unless OPENBLAS_CORETYPE is set; only the library
loaded then sees the setting (NumPy's own OpenBLAS and PARDISO's MKL are loaded before and choose
for themselves).
"""
from __future__ import annotations

import functools
import os
import sys

import numpy as np
import scipy.sparse as sp

from fem.core.longcalls import interruptible

ORDERING = "scotch"
"""The fill-reducing ordering: the best of Debian's build (no METIS) on the human 0.5 mm model
(356 M factor non-zeros; PORD 368 M, AMF 463 M)."""
RHS_BLOCK = 128
"""MUMPS's right-hand-side blocking in the solve (ICNTL(27)), and the columns `fem.experiments.
response` asks for per solve: on the human 0.5 mm model, 3 blocks of 128 candidates, 12.7 ms per
candidate against 12.95 ms at 64 and 15.1 ms at 32 (9.5 s for a block of 512 at 512)."""


OPENBLAS_KERNELS = (("SkylakeX", {"avx512f", "avx512dq", "avx512cd", "avx512bw", "avx512vl"}),
                    ("Haswell", {"avx2", "fma"}))
"""OpenBLAS kernels by the processor flags they need, fastest first."""


def openblas_kernel(flags) -> str | None:
    """The fastest of OPENBLAS_KERNELS that a processor with these flags (/proc/cpuinfo) runs, or
    None (then OpenBLAS chooses)."""
    return next((name for name, need in OPENBLAS_KERNELS if need <= set(flags)), None)


def _cpu_flags() -> set:
    """The first processor's flags in /proc/cpuinfo (empty where there is none)."""
    try:
        with open("/proc/cpuinfo") as f:
            return next((set(line.split(":", 1)[1].split()) for line in f if line.startswith("flags")), set())
    except OSError:
        return set()


def _mumps():
    """The python-mumps module, imported with OPENBLAS_CORETYPE set for the load of the system's
    OpenBLAS (module docstring) and the environment restored after."""
    if "mumps" in sys.modules or "OPENBLAS_CORETYPE" in os.environ:
        import mumps
        return mumps
    kernel = openblas_kernel(_cpu_flags())
    if kernel is not None:
        os.environ["OPENBLAS_CORETYPE"] = kernel
    try:
        import mumps
    finally:
        os.environ.pop("OPENBLAS_CORETYPE", None)
    return mumps


def loaded_openblas_kernel() -> str | None:
    """The kernel the system's OpenBLAS (the one MUMPS loaded) runs, e.g. "SkylakeX", or None
    when no system OpenBLAS is loaded."""
    import ctypes

    try:
        lib = ctypes.CDLL("libopenblas.so.0", mode=getattr(os, "RTLD_NOLOAD", 4) | ctypes.RTLD_GLOBAL)
        lib.openblas_get_corename.restype = ctypes.c_char_p
        return lib.openblas_get_corename().decode()
    except (OSError, AttributeError):
        return None


def available() -> bool:
    """Whether python-mumps and its library load."""
    try:
        _mumps()
    except ImportError:
        return False
    return True


def local_blocks(points: np.ndarray, size: int) -> list[np.ndarray]:
    """Indices of points (k, d) cut into blocks of at most `size` neighbours, by recursive
    bisection across the longest extent (whole blocks on the first side). The unit loads of one
    block share most of their paths up the elimination tree, so a block's pruned forward
    substitution does less work: on the human 0.5 mm model 19.3 ms per candidate against 21.5
    for blocks of consecutive unknowns (benchmarks/prepare_mumps.py). Deterministic."""
    def cut(idx):
        if len(idx) <= size:
            return [idx]
        axis = int(np.argmax(np.ptp(points[idx], axis=0)))
        idx = idx[np.argsort(points[idx, axis], kind="stable")]
        half = (-(-len(idx) // size) // 2) * size
        return cut(idx[:half]) + cut(idx[half:])
    return cut(np.arange(len(points)))


def _solve_sparse(ctx, ptr, ind, values) -> None:
    """MUMPS's solve for the sparse right-hand sides (ptr, ind), the answers written into values.
    Run `interruptible`, whose thread holds the arguments until the call ends: python-mumps keeps
    no reference to the arrays MUMPS writes into."""
    inst = ctx.mumps_instance
    inst.set_sparse_rhs(ptr, ind, values)
    inst.job = 3
    ctx.call()


class InverseEntries:
    """A^-1 restricted to given rows and columns, for A (n, n) sparse symmetric (indefinite allowed)
    given by its upper triangle, factorised once (LDL^T with pivoting), in core or with the factor
    on disk (`out_of_core`: on the human 0.5 mm model 3.1 GB peak instead of 5.5 GB, 1.7 times the
    time). `stats`: MUMPS's factorisation statistics (memory MB, non-zeros). MUMPS releases
    Python's lock, so its calls run `interruptible`: Ctrl-C acts within a fraction of a second,
    inside the factorisation too."""

    def __init__(self, upper: sp.spmatrix, out_of_core: bool = False):
        mumps = _mumps()
        self.n = upper.shape[0]
        self._ctx = mumps.Context()
        self._ctx.set_matrix(sp.coo_matrix(upper), symmetric=True)
        interruptible(functools.partial(self._ctx.analyze, ordering=ORDERING))
        interruptible(functools.partial(self._ctx.factor, reuse_analysis=True, ooc=out_of_core))
        self.stats = self._ctx.factor_stats
        inst = self._ctx.mumps_instance
        inst.icntl[27], inst.icntl[30], inst.icntl[20] = RHS_BLOCK, 1, 1     # blocking; entries of A^-1; sparse
        self._rows = self._ind = None

    def block(self, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """(len(rows), len(cols)) A^-1[rows][:, cols]: rows (r,) sorted unique, cols (c,) unique
        indices; one MUMPS solve (keep c to a few hundred: it holds r c values)."""
        return self.block_t(rows, cols).T

    def block_t(self, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """`block` transposed, (len(cols), len(rows)) C-ordered: MUMPS's own layout, no transposing
        copy. The row indices are kept for the next call with the same rows."""
        from mumps import _mumps

        rows, cols = np.asarray(rows), np.asarray(cols)
        if self._rows is None or not np.array_equal(self._rows, rows):
            self._rows, self._ind = rows.copy(), (rows + 1).astype(_mumps.int_dtype)
        order = np.argsort(cols)
        counts = np.zeros(self.n, int)
        counts[cols] = len(rows)                       # MUMPS takes all n columns, most of them empty
        ptr = (np.r_[0, np.cumsum(counts)] + 1).astype(_mumps.int_dtype)
        ind = np.tile(self._ind, len(cols))
        values = np.zeros(len(ind))
        interruptible(_solve_sparse, self._ctx, ptr, ind, values)
        out = values.reshape(len(cols), len(rows))          # by increasing column
        return out if np.all(np.diff(cols) > 0) else out[np.argsort(order)]

    def release(self) -> None:
        """Free MUMPS's factor (python-mumps ends the instance, JOB = -2, when it is collected)."""
        self._ctx = None
