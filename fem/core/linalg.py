"""Linear algebra of the FE stage: BLAS thread limits and sparse symmetric indefinite solves.

    blas_threads(limit)                    context manager limiting BLAS threads (None: no limit)
    Pardiso(upper, schur=None)             MKL PARDISO LDL^T of a symmetric matrix (upper triangle,
                                           CSR), optionally with the dense Schur complement onto rows;
                                           `solve_schur` for loads on those rows only (backward
                                           substitution alone); single=True in single precision
    SaddleFactor(Kdev, B, D, ...)          K = Kdev + B^T D^-1 B solved through the factorised
                                           quasi-definite [[Kdev, B^T], [B, -D]], with refinement on K
    solve_refined(A, b)                    one solve of a sparse symmetric indefinite A, one step of
                                           iterative refinement

The pattern PARDISO is given (free of round-off entries, or an earlier one's grown by real
entries, or gathered onto it) is built by `fem.core.patterns`.

PARDISO comes from MKL through pypardiso; without pypardiso SciPy's SuperLU is used (much slower,
with a warning). Every call into pypardiso's internals is in this module: `Pardiso` calls MKL's
`pardiso` entry point through ctypes itself, on the shared library that pypardiso loads. pypardiso
documents no API for that library handle, so pyproject.toml pins pypardiso to its 0.4 series.
"""
from __future__ import annotations

import contextlib
import ctypes
import functools
import logging
import os
import sys
import threading

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
from scipy.sparse.linalg import splu

from fem.core.longcalls import interruptible
from fem.core.patterns import Gather, drop_round_off, onto_pattern
from fingertip.errors import InputError

logger = logging.getLogger(__name__)


# --------------------------------------------------------------------------- BLAS threads
def _thread_controller():
    """threadpoolctl's view of the loaded BLAS libraries: scanned again once pypardiso has loaded
    MKL (a view taken before would leave PARDISO's threads unlimited), else cached."""
    return _scanned("pypardiso" in sys.modules)


@functools.lru_cache(maxsize=2)
def _scanned(with_mkl: bool):  # noqa: ARG001 - the cache key
    """threadpoolctl's ThreadpoolController (a scan of the loaded libraries, about 10 ms), one
    per `with_mkl` (whether pypardiso is imported).

    Importing threadpoolctl sets KMP_DUPLICATE_LIB_OK in the environment (to tolerate several
    OpenMP runtimes); the library leaves the caller's environment as it found it, so that entry is
    removed again unless the caller had set it."""
    had = "KMP_DUPLICATE_LIB_OK" in os.environ
    from threadpoolctl import ThreadpoolController

    if not had:
        os.environ.pop("KMP_DUPLICATE_LIB_OK", None)
    return ThreadpoolController()


def load_mkl() -> None:
    """Load MKL (through pypardiso, when installed) so that `blas_threads` finds and limits it
    (threadpoolctl sees only libraries already loaded)."""
    with contextlib.suppress(ImportError):
        import pypardiso  # noqa: F401


def blas_threads(limit: int | None):
    """Context manager limiting BLAS threads to `limit` (None: no limit)."""
    return contextlib.nullcontext() if limit is None else _thread_controller().limit(limits=limit, user_api="blas")


def serial_openblas():
    """Context manager running OpenBLAS (NumPy's and SciPy's BLAS in their wheels) on one thread,
    for loops that alternate NumPy work with PARDISO solves: after each call OpenBLAS's threads
    spin for a while and take the cores the next solve needs. Measured on the 1 mm monkey's
    neo-Hookean tangent (65,736 unknowns): a single-right-hand-side solve after a vector norm takes
    50-70 ms instead of 32 ms. MKL (PARDISO's threads) is left as it is."""
    return _thread_controller().select(internal_api="openblas").limit(limits=1)


SERIAL_BLAS_BELOW = 1500
"""Dense symmetric factorisations (and their solves and inverses) smaller than this run on one BLAS
thread: for such small matrices a second thread mostly waits for the other core, which is often
busy, and can slow them several times over (a 201 x 201 Cholesky factorisation: a fraction of a
millisecond on one thread, tenths of a second on two OpenBLAS threads of a loaded 2-core machine)."""

def dense_threads(n: int):
    """`blas_threads` for dense work on an (n, n) matrix: one thread below SERIAL_BLAS_BELOW."""
    return blas_threads(1 if n < SERIAL_BLAS_BELOW else None)


SERIAL_PARDISO_BELOW = 25_000
"""PARDISO runs every phase of a matrix with fewer unknowns on one thread when called from the main
thread (MKL's thread count local to it, set around each call; such phases take a second or less
and run there, not in the long-call thread). Measured on 2 cores, whole runs: the 2D finite Newton
on 12,648 unknowns (cylinder with bone, 0.125 mm, C5 to 2 mm, 115 factorisations) 10.1-10.8 s on
one thread against 14.2-15.3 s on two, where MKL's OpenMP threads spin after each short call and
take the core the Python side needs; on 44,918 unknowns (0.0625 mm) 39.7 s against 36.9 s; a 3D
linear run on 70,629 unknowns 7.2-7.6 s against 5.2-5.9 s (forces equal in the 8-10 digits
printed). Off the main thread (the long-call thread, a caller's own threads) MKL keeps its own
count: a count of one set there, with MKL's reproducible mode on, crashed PARDISO's analysis with
a segmentation fault (the 2D cylinder models' Schur factorisations in a loop, 2,100 per run: 15 of
21 runs, in a new thread per call or in the long-call thread; none of 4 with every call on the
main thread, none of 6 with MKL's own count in the long-call thread, none of 4 without the mode)."""


# --------------------------------------------------------------------------- PARDISO
def _pardiso_available() -> bool:
    """Whether pypardiso imports; logs a warning when it does not. (Imported here, not at the top:
    it loads MKL, 0.2 s, which a run answered by stored response models does without.)"""
    try:
        import pypardiso  # noqa: F401
    except ImportError:
        logger.warning("pypardiso is not installed: using SciPy SuperLU, about 50x slower (pip install pypardiso)")
        return False
    return True


_PT = ctypes.c_int64 if ctypes.sizeof(ctypes.c_void_p) == 8 else ctypes.c_int32     # PARDISO's handle words
_I32 = ctypes.POINTER(ctypes.c_int32)
_F64 = ctypes.POINTER(ctypes.c_double)
MKL_CBWR_AUTO = 2           # MKL_CBWR_Set's mode: the same bits on the same instruction set and threads
MKL_CBWR_BRANCH = 1         # MKL_CBWR_Get's query: the code branch (mode) in use


@functools.lru_cache(maxsize=1)
def _libmkl():
    """The MKL library (ctypes) pypardiso loaded, found once per process: pypardiso finds libmkl_rt
    when a PyPardisoSolver is built (without find_library's help by a recursive glob over the
    environment, every time), so the one its import-time solver loaded is used."""
    try:                                            # the solver pypardiso built on import
        from pypardiso.scipy_aliases import pypardiso_solver as solver
    except ImportError:                             # (a new one searches the environment again)
        from pypardiso import PyPardisoSolver

        solver = PyPardisoSolver()
    return solver.libmkl


@functools.lru_cache(maxsize=1)
def _mkl_pardiso():
    """(MKL's `pardiso`, MKL's `MKL_Set_Num_Threads_Local`) as ctypes functions of this module's own
    (indexing the library gives new function objects: no environment variable or pypardiso state
    is changed), located once per process.

    MKL's conditional numerical reproducibility is switched on here, before the first PARDISO call
    (`MKL_CBWR_Set(MKL_CBWR_AUTO)`): without it a factorisation on two threads that reuses an
    analysis gives other last bits from run to run (measured: 1e-16 relative in double precision,
    enough to change the noise-level penetration column; in single precision the finite solver's
    receptor tables differed in the 9th digit between runs of one command). With it, the same
    command on the same thread count writes the same bytes, at about 10 % of the 3D finite
    solver's time (the 1 mm monkey, 46.7 s against 42.6 s in process)."""
    lib = _libmkl()
    fn = lib["pardiso"]
    fn.argtypes = [ctypes.POINTER(_PT), _I32, _I32, _I32, _I32, _I32, ctypes.c_void_p, _I32, _I32, _I32,
                   _I32, _I32, _I32, ctypes.c_void_p, ctypes.c_void_p, _I32]
    fn.restype = None
    threads = lib["MKL_Set_Num_Threads_Local"]
    threads.argtypes, threads.restype = [ctypes.c_int], ctypes.c_int
    reproducible = lib["MKL_CBWR_Set"]
    reproducible.argtypes, reproducible.restype = [ctypes.c_int], ctypes.c_int
    if reproducible(MKL_CBWR_AUTO) != 0:
        logger.warning("MKL refused its reproducible mode: repeated runs may differ in the last bits")
    return fn, threads


def mkl_reproducible() -> bool:
    """Whether MKL runs in its conditional numerical reproducibility mode (`_mkl_pardiso` sets it
    before the first PARDISO call)."""
    get = _libmkl()["MKL_CBWR_Get"]
    get.argtypes, get.restype = [ctypes.c_int], ctypes.c_int
    return get(MKL_CBWR_BRANCH) == MKL_CBWR_AUTO


class Pardiso:
    """MKL PARDISO LDL^T (mtype -2) of a symmetric matrix given by its upper triangle (CSR),
    factorised once; `solve` runs the solve phase (33) directly on Fortran-ordered blocks.

    Every phase runs on one thread below SERIAL_PARDISO_BELOW unknowns, on MKL's own count above.
    iparm is set explicitly (the defaults for mtype -2: METIS nested dissection, 1e-8 pivot
    perturbation, Bunch-Kaufman within supernodes) except that PARDISO's own iterative refinement
    is off (the caller refines where a residual asks for it, see `SaddleFactor`).
    mkl_defaults: use PARDISO's default settings instead (iparm[0] = 0, as pypardiso's public
    solver does; they refine inside every solve); no Schur complement then.

    schur: optional sorted (k,) row indices. PARDISO then orders them last and returns the dense
    Schur complement S = A_SS - A_SI A_II^-1 A_IS (k, k) with a partial factorisation of the rest
    (iparm[35] = 2); a solve is forward substitution (phase 331, which leaves the reduced
    right-hand side in the Schur rows), a dense Cholesky solve with S there, and backward
    substitution (phase 333). S must be positive definite (true for the displacement rows of a
    quasi-definite matrix). Raises pypardiso's PyPardisoError when PARDISO fails and
    np.linalg.LinAlgError for an empty row or an S that is not positive definite.
    single: factorise and solve in single precision (iparm[27] = 1; the matrix, right-hand sides
    and solutions in float32, solutions returned as float64): half the factorisation's time and
    memory and faster solves, leaving a relative residual of about 1e-3 on the fingertip's
    neo-Hookean tangent (a preconditioner, not a solver there; no Schur complement then).
    reuse: an earlier factorisation of a matrix with the same pattern (`takes`): its analysis (the
    ordering and symbolic factor, a quarter of a factorisation's time on the 1 mm monkey's
    neo-Hookean tangent) serves this one, which takes over its handle; for another pattern, `reuse`
    is released before this one is factorised (both factors held at once took 8.7 GB instead of
    5.2 GB on the human 0.5 mm model). Either way `reuse` cannot solve after.
    """
    def __init__(self, upper: sp.csr_matrix, schur: np.ndarray | None = None, mkl_defaults: bool = False,
                 reuse: "Pardiso | None" = None, single: bool = False):
        from pypardiso.pardiso_wrapper import (
            PyPardisoError,  # pypardiso (MKL) only where PARDISO runs
        )

        self._error = PyPardisoError
        self._call, self._threads = _mkl_pardiso()
        upper = sp.csr_matrix(upper)
        upper.sort_indices()
        self.n = upper.shape[0]
        if not np.diff(upper.indptr).all():                 # PARDISO crashes on empty rows
            raise np.linalg.LinAlgError("the matrix has empty rows")
        self._dtype = np.float32 if single else np.float64
        self._data = np.ascontiguousarray(upper.data, dtype=self._dtype)
        self._ia = (upper.indptr + 1).astype(np.int32)      # PARDISO's default one-based indexing
        self._ja = (upper.indices + 1).astype(np.int32)
        self._pt = np.zeros(64, dtype=_PT)                  # PARDISO's internal handle
        self._perm = np.zeros(0, dtype=np.int32)
        self.iparm = ip = np.zeros(64, dtype=np.int32)
        self._schur_factor = None       # (Cholesky factor of S, lower) when schur rows are given
        self._schur_inverse = None
        has_schur = schur is not None and len(schur) > 0
        if (mkl_defaults or single) and has_schur:
            raise ValueError("a Schur complement needs the explicit settings in double precision")
        if mkl_defaults and single:
            raise ValueError("single precision needs the explicit settings (mkl_defaults=False)")
        if not mkl_defaults:
            ip[0] = 1       # iparm given explicitly
            ip[1] = 2       # METIS nested dissection (parallel METIS, 3, is no faster on 2 cores)
            ip[7] = 0       # no PARDISO refinement unless pivots were perturbed
            ip[9] = 8       # pivot perturbation 1e-8 (mtype -2 default)
            ip[17] = -1     # report nnz(L) in iparm[17]
            ip[20] = 1      # Bunch-Kaufman pivoting (mtype -2 default)
            ip[27] = int(single)
            # (two-level factorisation, iparm[23] = 1, is about 9 % faster on 2 cores, but its
            # last digits depend on the thread count: a Dask task's run would differ from serial)
        self._live = True
        taken = not has_schur and reuse is not None and reuse.takes(self)
        if reuse is not None and not taken:
            reuse.release()             # another pattern: its factor goes before this one is made
        if taken:
            self._pt, self.iparm = reuse._pt, reuse.iparm       # its analysis (ordering, symbolic factor)
            reuse._live = False                                 # the handle is this factorisation's now
            self._long_phase(22, *self._empty())
        elif not has_schur:
            self._long_phase(12, *self._empty())
        else:
            ip[35] = 2                                      # Schur complement + partial factorisation
            self._perm = np.zeros(self.n, dtype=np.int32)
            self._perm[schur] = 1
            self._rows = np.asarray(schur)
            S = np.zeros((len(schur), len(schur)), order="F")     # symmetric: either order
            b, x, _ = self._empty()
            self._long_phase(11, b, x, 1)
            self._long_phase(22, b, S, 1)
            with dense_threads(len(S)):
                self._schur_factor = interruptible(functools.partial(sla.cho_factor, S, lower=True, overwrite_a=True))
        self.nnz_factor = int(ip[17])

    def _empty(self):
        z = np.zeros((self.n, 1), dtype=self._dtype, order="F")
        return z, z.copy(), 1

    @property
    def single(self) -> bool:
        """Whether this factorisation is in single precision."""
        return self._dtype == np.float32

    @property
    def reusable(self) -> bool:
        """Whether a new matrix of the same pattern can be factorised on this one's analysis."""
        return self._live and self._schur_factor is None

    @property
    def pattern(self) -> tuple[np.ndarray, np.ndarray]:
        """(indptr (n + 1,), indices) zero-based: the sorted CSR pattern factorised."""
        return self._ia - 1, self._ja - 1

    def takes(self, other: "Pardiso") -> bool:
        """Whether `other` (a new matrix) can be factorised on this factorisation's analysis: this
        one live, without a Schur complement, with the same settings and the same pattern."""
        return (self.reusable and other._perm.size == 0 and self.n == other.n
                and np.array_equal(self.iparm[[0, 1, 7, 9, 20, 27]], other.iparm[[0, 1, 7, 9, 20, 27]])
                and np.array_equal(self._ia, other._ia) and np.array_equal(self._ja, other._ja))

    def _long_phase(self, phase, b, x, nrhs):
        """A phase that takes long (analysis, factorisation) run `interruptible`: Ctrl-C acts at
        once. An interrupted factorisation is abandoned: its memory is not released (the call still
        runs in its thread; releasing under it would crash), the process ends soon after. Below
        SERIAL_PARDISO_BELOW unknowns (a second or less) the phase runs here (`_phase`)."""
        if self.n < SERIAL_PARDISO_BELOW:
            return self._phase(phase, b, x, nrhs)
        try:
            interruptible(self._phase, phase, b, x, nrhs)
        except KeyboardInterrupt:
            self._live = False
            raise

    def _phase(self, phase, b, x, nrhs):
        err = ctypes.c_int32(0)
        serial = self.n < SERIAL_PARDISO_BELOW and threading.current_thread() is threading.main_thread()
        before = self._threads(1) if serial else None
        try:
            self._call(self._pt.ctypes.data_as(ctypes.POINTER(_PT)), ctypes.byref(ctypes.c_int32(1)),
                       ctypes.byref(ctypes.c_int32(1)), ctypes.byref(ctypes.c_int32(-2)),
                       ctypes.byref(ctypes.c_int32(phase)), ctypes.byref(ctypes.c_int32(self.n)),
                       self._data.ctypes.data_as(_F64), self._ia.ctypes.data_as(_I32), self._ja.ctypes.data_as(_I32),
                       self._perm.ctypes.data_as(_I32), ctypes.byref(ctypes.c_int32(nrhs)),
                       self.iparm.ctypes.data_as(_I32), ctypes.byref(ctypes.c_int32(0)),
                       b.ctypes.data_as(_F64), x.ctypes.data_as(_F64), ctypes.byref(err))
        finally:
            if serial:
                self._threads(before)
        if err.value != 0:
            raise self._error(err.value)

    def solve(self, b: np.ndarray) -> np.ndarray:
        """x (n,) or (n, k) float64 with A x = b; b (n,) or (n, k) (not modified)."""
        b = np.asfortranarray(b, dtype=self._dtype)
        x = np.zeros_like(b, order="F")
        if not x.size:                                  # PARDISO rejects nrhs = 0
            return x.astype(np.float64)
        nrhs = 1 if b.ndim == 1 else b.shape[1]
        if self._schur_factor is None:
            self._phase(33, b, x, nrhs)
            return x if not self.single else x.astype(np.float64, order="F")
        y = np.zeros_like(b, order="F")
        self._phase(331, b, y, nrhs)
        with dense_threads(len(self._rows)):
            y[self._rows] = sla.cho_solve(self._schur_factor, y[self._rows])
        self._phase(333, y, x, nrhs)
        return x

    def solve_schur(self, b_schur: np.ndarray) -> np.ndarray:
        """x (n, q) with A x = b for a b (n, q) that is zero outside the Schur rows, given by its
        values there b_schur (k, q). No forward substitution: with the interior of b zero, phase
        331 leaves zeros in the interior and b unchanged in the Schur rows, so the Schur part of x
        is S^-1 b_schur (from S^-1 when `schur_inverse` has been computed, else the Cholesky
        factor of S) and the interior one backward substitution (phase 333)."""
        if self._schur_factor is None:
            raise ValueError("this factorisation has no Schur complement")
        b_schur = np.asarray(b_schur, dtype=np.float64).reshape(len(self._rows), -1)
        y = np.zeros((self.n, b_schur.shape[1]), order="F")
        if not y.size:
            return y
        with dense_threads(len(self._rows)):
            y[self._rows] = (self._schur_inverse @ b_schur if self._schur_inverse is not None
                             else sla.cho_solve(self._schur_factor, b_schur))
        x = np.zeros_like(y, order="F")
        self._phase(333, y, x, y.shape[1])
        return x

    @property
    def schur(self) -> np.ndarray:
        """(k,) the Schur rows (empty without them)."""
        return self._rows if self._schur_factor is not None else np.zeros(0, dtype=int)

    def schur_inverse(self) -> np.ndarray:
        """(k, k) read-only S^-1, the Schur rows' block of A^-1 (LAPACK potri on the Cholesky
        factor of S, k^3 flops; computed once)."""
        if self._schur_factor is None:
            raise ValueError("this factorisation has no Schur complement")
        if self._schur_inverse is None:
            with dense_threads(len(self._rows)):
                c, info = interruptible(functools.partial(sla.lapack.dpotri, self._schur_factor[0], lower=1))
            if info:
                raise np.linalg.LinAlgError(f"potri failed ({info})")
            for a in range(0, len(c), 1024):            # mirror the lower triangle, in blocks
                b = min(a + 1024, len(c))
                c[a:b, b:] = c[b:, a:b].T
                d = c[a:b, a:b]
                d[:] = np.tril(d) + np.tril(d, -1).T
            c.flags.writeable = False
            self._schur_inverse = c
        return self._schur_inverse

    def release(self) -> None:
        """Free PARDISO's memory for this factorisation (later solves fail)."""
        if self._live:
            self._live = False
            self._phase(-1, np.zeros(1), np.zeros(1), 1)

    def __del__(self):
        try:
            self.release()
        except Exception:  # noqa: BLE001  (interpreter shutdown, failed factorisation)
            pass


def solve_refined(A: sp.spmatrix, b: np.ndarray) -> np.ndarray:
    """x (n,) with A x = b for a sparse symmetric (indefinite) A (n, n) and b (n,): one solve
    plus one step of iterative refinement, x + A^-1 (b - A x). PARDISO with its default settings
    (LDL^T of the upper triangle), factorised and released here; SciPy SuperLU without pypardiso.
    The refinement step matters for layers 1e5 apart in stiffness: without it the solve's error
    floors a Newton iteration's residual at ~1e-7 of the reactions."""
    A = A.tocsr()
    if not _pardiso_available():

        lu = splu(A.tocsc())
        x = lu.solve(b)
        return x + lu.solve(b - A @ x)
    factor = Pardiso(sp.triu(A, format="csr"), mkl_defaults=True)
    try:
        x = factor.solve(b)
        return x + factor.solve(b - A @ x)
    finally:
        factor.release()


# --------------------------------------------------------------------------- saddle system
def saddle_upper(Kdev: sp.spmatrix, B: sp.spmatrix, D: np.ndarray) -> sp.csr_matrix:
    """(n + m, n + m) upper triangle of the saddle matrix [[Kdev, B^T], [B, -diag(D)]], which
    symmetric solvers read, built without the full matrix (half the memory and time of
    triu(bmat(...))); Kdev (n, n), B (m, n), D (m,)."""
    return sp.bmat([[sp.triu(Kdev), B.T], [None, -sp.diags(D)]], format="csr")


class SaddleFactor:
    """K = Kdev + B^T D^-1 B (n, n) factorised once and reused for many right-hand sides.

    Kdev (n, n) sparse symmetric positive semi-definite, B (m, n) sparse, D (m,) positive. K is
    much denser than its parts (each row of B couples a patch of unknowns), so the sparse
    symmetric quasi-definite matrix [[Kdev, B^T], [B, -D]] is factorised instead (LDL^T, PARDISO
    mtype -2); its solution's first n rows solve K x = b exactly. (Measured on a 71k-DOF sphere:
    a Cholesky factorisation of K itself has 4.5x the factor non-zeros and 13x the flops.)

    Each solve checks ||K x - b|| / ||b|| per column and, only for columns above the refinement
    tolerance (REFINE_TOL at first), runs up to MAX_REFINE steps of iterative refinement on K. A
    step that gains less than 10x ends the refinement and raises this factor's tolerance to 10x
    the residual reached, so later solves skip refinement that does not help (round-off limited
    systems, e.g. layers with moduli 1e4 apart).

    condensed: optional sorted (k,) indices into the n unknowns whose compliance block (K^-1
    restricted to them, `compliance_block`) is wanted: PARDISO then returns the Schur complement
    onto them with the factorisation (see `Pardiso`); the SciPy fallback ignores it.
    rotation: optional sparse orthogonal T (n, n), x = T x_local: the system is factorised in the
    local unknowns (T^T K T) and `condensed` indexes those; solves and residuals stay global.
    free: optional sorted (n,) indices: K is the restriction of Kdev (N, N) and B (m, N) to these
    rows and columns (a model's unconstrained DOFs). Kdev and B are then referenced, not copied:
    the restricted copies exist only while the factorised matrix is built (on the human 0.5 mm
    model they would hold 0.3 GB through the factorisation and every later solve), and residuals
    multiply by the whole matrices.
    reuse: an earlier SaddleFactor of a matrix of the same size: this one is stored on its
    pattern (`onto_pattern`) and, when no entry above round-off falls outside it, factorised on
    its PARDISO analysis (`Pardiso`; the earlier one cannot solve after).
    keep_zeros: factorise on every stored entry of Kdev and B, explicit zeros and round-off
    included, instead of dropping those first (`drop_round_off`): for matrices assembled on one
    fixed pattern (`fem.core.neohookean.NeoHookean`'s tangents), whose first factorisation's
    analysis then serves every later one (`reuse`; the human 0.5 mm tangent: analysis and
    factorisation 13.9 s, factorisation alone 9.8 s, in single precision).
    single: factorise in single precision (`Pardiso`; the SciPy fallback ignores it), for use as
    a preconditioner: its solves are as accurate as single precision and the matrix's conditioning
    allow.
    A singular matrix raises InputError.
    """
    REFINE_TOL = 1e-10
    MAX_REFINE = 2

    def __init__(self, Kdev: sp.csr_matrix, B: sp.csr_matrix, D: np.ndarray, condensed=None, rotation=None,
                 free=None, reuse: "SaddleFactor | None" = None, single: bool = False, keep_zeros: bool = False):
        self.Kdev, self.B, self.D = Kdev, B, D
        self._free = None if free is None else np.asarray(free)
        self.n = Kdev.shape[0] if free is None else len(self._free)
        self.refinements = 0        # refinement steps taken by the last call
        self.refine_tol = self.REFINE_TOL
        self.condensed = np.zeros(0, dtype=int)
        self._pardiso = None
        self._gather = None         # `Gather` of this input pattern onto the factorised one, handed on
        self._T = None if rotation is None else sp.csr_matrix(rotation)
        earlier = None if reuse is None else reuse._pardiso
        upper = None
        if earlier is not None and self._T is None and (condensed is None or not len(condensed)):
            upper = self._gathered(reuse)
        if upper is None:
            if free is not None:
                Kdev, B = Kdev[self._free][:, self._free], B[:, self._free]
            if self._T is not None:
                Kdev, B = (self._T.T @ Kdev @ self._T).tocsr(), (B @ self._T).tocsr()
            if not _pardiso_available():
                A = sp.bmat([[Kdev, B.T], [B, -sp.diags(D)]], format="csc")
                self.backend, self._solve = "scipy-splu", splu(A).solve
                return
            upper = saddle_upper(Kdev, B, D)        # the local blocks are freed before the factorisation
            del Kdev, B
            if earlier is not None and earlier.reusable and earlier.n == upper.shape[0]:
                upper = onto_pattern(upper, *earlier.pattern)
            elif not keep_zeros:
                upper = drop_round_off(upper)
        from pypardiso.pardiso_wrapper import PyPardisoError

        try:
            self._pardiso = Pardiso(upper, condensed, reuse=earlier, single=single)
        except (PyPardisoError, np.linalg.LinAlgError) as exc:
            raise InputError(f"the stiffness matrix is singular ({exc}); check that every part of the "
                             "mesh is held") from None
        self.backend, self._solve = "pardiso", self._pardiso.solve
        self.condensed = self._pardiso.schur

    def _gathered(self, reuse: "SaddleFactor"):
        """The matrix to factorise on `reuse`'s pattern by `Gather` (built on the first reuse,
        handed on while the input and factorised patterns stay), or None: not reusable, or the
        pattern grows."""
        earlier = reuse._pardiso
        if (not earlier.reusable or earlier.n != self.n + len(self.D) or not self.Kdev.has_canonical_format
                or not self.B.has_canonical_format):
            return None
        key = Gather.fingerprint(self.Kdev, self.B, self.D, self._free)
        gather = reuse._gather
        if gather is None or not gather.serves(key, earlier._ia, earlier._ja):
            gather = Gather(self.Kdev, self.B, self.D, self._free, earlier._ia, earlier._ja)
        self._gather = gather
        return gather.upper(self.Kdev, self.B, self.D)

    @property
    def single(self) -> bool:
        """Whether the factorisation is in single precision."""
        return self._pardiso is not None and self._pardiso.single

    @property
    def nnz_factor(self) -> float:
        """Non-zeros of PARDISO's factor (NaN with the SciPy fallback)."""
        return float("nan") if self._pardiso is None else float(self._pardiso.nnz_factor)

    def compliance_block(self) -> np.ndarray:
        """(k, k) read-only K^-1 restricted to the `condensed` unknowns: the inverse of their
        Schur complement (computed once)."""
        return self._pardiso.schur_inverse()

    def apply(self, x: np.ndarray) -> np.ndarray:
        """K x (x (n,) or (n, k))."""
        if self._free is not None:
            whole = np.zeros((self.Kdev.shape[0],) + x.shape[1:])
            whole[self._free] = x
            x = whole
        Bx = self.B @ x
        Kx = self.Kdev @ x + self.B.T @ (Bx / (self.D if x.ndim == 1 else self.D[:, None]))
        return Kx if self._free is None else Kx[self._free]

    def _raw(self, b: np.ndarray) -> np.ndarray:
        rhs = np.zeros((len(b) + len(self.D),) + b.shape[1:], order="F")
        rhs[:len(b)] = b if self._T is None else self._T.T @ b
        x = self._solve(rhs)[:len(b)]
        return x if self._T is None else self._T @ x

    def _relres(self, x, b):
        r = b - self.apply(x)
        nr, nb = np.linalg.norm(r, axis=0), np.linalg.norm(b, axis=0)
        return r, np.where(nb > 0, nr / np.where(nb > 0, nb, 1.0), nr)

    def __call__(self, b: np.ndarray, refine: bool = True) -> np.ndarray:
        """x with K x = b (b (n,) or (n, k)); sets `last_residual` (max relative residual).
        refine=False: the factorisation's solution as it is, no residual computed (an inexact
        Newton step, whose outer iteration corrects it); `last_residual` NaN."""
        b = np.asarray(b, dtype=float)
        if not refine:
            self.last_residual, self.refinements = float("nan"), 0
            return self._raw(b)
        return self._refine(self._raw(b), b)

    def solve_condensed(self, cols, check: bool = True) -> np.ndarray:
        """x (n, q) with K x = e for unit loads on the `condensed` unknowns `condensed[cols]`
        (cols (q,) positions in `condensed`; with a rotation, unit loads along the local axis of
        those unknowns): no forward substitution (`Pardiso.solve_schur`).
        check: compute the residual and refine as `__call__` does (sets `last_residual`);
        False: neither (`last_residual` NaN). Raises ValueError when nothing is condensed."""
        cols = np.asarray(cols, int)
        if self._pardiso is None or not len(self.condensed):
            raise ValueError("nothing is condensed in this factorisation")
        e = np.zeros((len(self.condensed), len(cols)))
        e[cols, np.arange(len(cols))] = 1.0
        x = self._pardiso.solve_schur(e)[:self.n]
        if self._T is not None:
            x = self._T @ x
        if not check:
            self.refinements, self.last_residual = 0, float("nan")
            return x
        b = sp.csc_matrix((np.ones(len(cols)), (self.condensed[cols], np.arange(len(cols)))),
                          shape=(self.n, len(cols)))
        b = (b if self._T is None else self._T @ b).toarray()
        return self._refine(x, b)

    def _refine(self, x: np.ndarray, b: np.ndarray) -> np.ndarray:
        """x after the residual check and refinement of the class docstring; sets `refinements`
        and `last_residual`."""
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
        """max over columns of ||K x - b|| / ||b||."""
        return float(self._relres(x, b)[1].max(initial=0.0))
