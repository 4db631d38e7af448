"""fem.core.linalg: PARDISO's Schur complement and Schur-path solves against dense linear algebra,
the refined saddle solve, BLAS thread limits, and no environment changes."""
import os
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

from fem.core.linalg import Pardiso, SaddleFactor, blas_threads, solve_refined
from fem.core.model import Model
from fem.verify import closed_forms as ref
from tests.helpers import ROOT, laplacian_3d


def _saddle(n=40, m=12, seed=0):
    """(Kdev (n, n) sparse SPD, B (m, n) sparse, D (m,) > 0, A the quasi-definite
    [[Kdev, B^T], [B, -D]] as CSR)."""
    rng = np.random.default_rng(seed)
    R = sp.random(n, n, density=0.1, random_state=rng)
    K = (R @ R.T + sp.diags(rng.uniform(1.0, 2.0, n))).tocsr()
    B = sp.random(m, n, density=0.2, random_state=rng, format="csr")
    D = rng.uniform(0.5, 1.5, m)
    return K, B, D, sp.bmat([[K, B.T], [B, -sp.diags(D)]], format="csr")


def test_schur_complement_matches_dense():
    """PARDISO's Schur complement onto some displacement rows, inverted, is the dense inverse's
    block; the complement itself is A_SS - A_SI A_II^-1 A_IS."""
    pytest.importorskip("pypardiso")
    *_, A = _saddle()
    rows = np.array([1, 4, 5, 11, 20, 33, 39])
    pf = Pardiso(sp.triu(A, format="csr"), schur=rows)
    dense = A.toarray()
    inner = np.setdiff1d(np.arange(len(dense)), rows)
    S = dense[np.ix_(rows, rows)] - dense[np.ix_(rows, inner)] @ np.linalg.solve(
        dense[np.ix_(inner, inner)], dense[np.ix_(inner, rows)])
    block = pf.schur_inverse()
    np.testing.assert_allclose(np.linalg.inv(block), S, rtol=0, atol=1e-9 * np.abs(S).max())
    expected = np.linalg.inv(dense)[np.ix_(rows, rows)]
    np.testing.assert_allclose(block, expected, rtol=0, atol=1e-9 * np.abs(expected).max())
    assert not block.flags.writeable and pf.schur_inverse() is block
    np.testing.assert_array_equal(pf.schur, rows)


def test_schur_path_solve_matches_dense():
    """Phases 331 / dense Cholesky / 333 solve A x = b like numpy, for one and several right-hand sides."""
    pytest.importorskip("pypardiso")
    *_, A = _saddle(seed=1)
    rows = np.arange(0, 40, 3)
    pf = Pardiso(sp.triu(A, format="csr"), schur=rows)
    plain = Pardiso(sp.triu(A, format="csr"))
    rng = np.random.default_rng(2)
    b = rng.standard_normal((A.shape[0], 3))
    x = np.linalg.solve(A.toarray(), b)
    for solver in (pf, plain):
        np.testing.assert_allclose(solver.solve(b), x, rtol=0, atol=1e-10 * np.abs(x).max())
        np.testing.assert_allclose(solver.solve(b[:, 1]), x[:, 1], rtol=0, atol=1e-10 * np.abs(x).max())
        assert solver.solve(b[:, :0]).shape == (A.shape[0], 0)


def test_saddle_factor_and_refined_solve_match_dense():
    """SaddleFactor solves K = Kdev + B^T D^-1 B; its compliance block is K^-1's block;
    solve_refined solves the saddle matrix itself."""
    pytest.importorskip("pypardiso")
    K, B, D, A = _saddle(seed=3)
    Kc = (K + B.T @ sp.diags(1 / D) @ B).toarray()
    rows = np.array([0, 7, 8, 30])
    factor = SaddleFactor(K, B, D, condensed=rows)
    b = np.random.default_rng(4).standard_normal(K.shape[0])
    np.testing.assert_allclose(factor(b), np.linalg.solve(Kc, b), rtol=1e-10)
    inv = np.linalg.inv(Kc)[np.ix_(rows, rows)]
    np.testing.assert_allclose(factor.compliance_block(), inv, rtol=0, atol=1e-10 * np.abs(inv).max())
    rhs = np.random.default_rng(5).standard_normal(A.shape[0])
    np.testing.assert_allclose(solve_refined(A, rhs), np.linalg.solve(A.toarray(), rhs), rtol=1e-10)


def test_saddle_factor_on_free_rows_solves_the_restricted_system():
    """SaddleFactor(free=) solves K restricted to the free rows and columns, with the compliance
    block of those, and its residual check multiplies by the whole matrices correctly."""
    pytest.importorskip("pypardiso")
    K, B, D, _ = _saddle(seed=6)
    free = np.setdiff1d(np.arange(K.shape[0]), [0, 5, 17])
    Kc = (K + B.T @ sp.diags(1 / D) @ B).toarray()[np.ix_(free, free)]
    rows = np.array([2, 9, 30])
    factor = SaddleFactor(K, B, D, condensed=rows, free=free)
    b = np.random.default_rng(7).standard_normal((len(free), 2))
    np.testing.assert_allclose(factor(b), np.linalg.solve(Kc, b), rtol=1e-10)
    assert factor.last_residual < 1e-12 and factor.residual(np.linalg.solve(Kc, b), b) < 1e-12
    inv = np.linalg.inv(Kc)[np.ix_(rows, rows)]
    np.testing.assert_allclose(factor.compliance_block(), inv, rtol=0, atol=1e-10 * np.abs(inv).max())


@pytest.mark.parametrize("direction", [(0.0, -1.0, 0.0), (0.6, -0.8, 0.0)])
def test_model_compliance_is_the_dense_inverse_block(direction):
    """Model.system(condense=) on a small box: the stored compliance along an axis and along a
    rotated direction equals a^T K_ff^-1 a between the nodes, from the dense K."""
    pytest.importorskip("pypardiso")
    g = np.linspace(0, 1, 3)
    p, cells, regions = ref.box(g, g, g)
    model = Model(p, cells, np.ones(len(cells)), regions, material="m4", nu=0.45)
    top = model.region_nodes("ymax")
    system = model.system({"ymin": 0.0}, condense=(top, direction))
    C = system.compliance(top, direction)
    K = model.K @ np.eye(model.ndof)
    free = system.free
    inv = np.zeros((model.ndof, model.ndof))
    inv[np.ix_(free, free)] = np.linalg.inv(K[np.ix_(free, free)])
    a = np.asarray(direction)
    dofs = model.node_dofs(top)                                         # (k, 3)
    expected = np.einsum("i,kilj,j->kl", a, inv[dofs[:, :, None, None], dofs[None, None]], a)
    np.testing.assert_allclose(C, expected, rtol=0, atol=1e-9 * np.abs(expected).max())


def test_schur_row_loads_need_only_the_backward_substitution():
    """Pardiso.solve_schur (S^-1 on the Schur rows, then phase 333) equals the dense solve of
    loads on those rows, with S^-1 from the Cholesky factor and from schur_inverse."""
    pytest.importorskip("pypardiso")
    *_, A = _saddle(seed=7)
    rows = np.array([2, 3, 9, 17, 25, 38])
    pf = Pardiso(sp.triu(A, format="csr"), schur=rows)
    bs = np.random.default_rng(8).standard_normal((len(rows), 4))
    b = np.zeros((A.shape[0], 4))
    b[rows] = bs
    x = np.linalg.solve(A.toarray(), b)
    np.testing.assert_allclose(pf.solve_schur(bs), x, rtol=0, atol=1e-10 * np.abs(x).max())
    pf.schur_inverse()
    np.testing.assert_allclose(pf.solve_schur(bs), x, rtol=0, atol=1e-10 * np.abs(x).max())
    with pytest.raises(ValueError, match="no Schur"):
        Pardiso(sp.triu(A, format="csr")).solve_schur(bs)


@pytest.mark.parametrize("direction", [(0.0, -1.0, 0.0), (0.0, 1.0, 0.0), (0.6, -0.8, 0.0)])
@pytest.mark.parametrize("check", [True, False])
def test_solve_condensed_equals_the_plain_solve(direction, check):
    """LinearSystem.solve_condensed: the fields of unit forces along the direction (either sign,
    on an axis or rotated) at condensed nodes equal `solve` of those loads to 1e-10; a node held
    along the direction gives a zero column; nodes not condensed are refused."""
    pytest.importorskip("pypardiso")
    g = np.linspace(0, 1, 3)
    p, cells, regions = ref.box(g, g, g)
    model = Model(p, cells, np.ones(len(cells)), regions, material="m4", nu=0.45)
    top = model.region_nodes("ymax")
    held = np.intersect1d(top, model.region_nodes("xmin"))[:1]
    system = model.system({"ymin": 0.0, "xmin": 0.0}, condense=(top, direction))
    nodes = np.r_[top[top != held[0]][::-1], held]          # any order, the held node last
    a = np.asarray(direction)
    loads = np.zeros((model.ndof, len(nodes)))
    loads[model.node_dofs(nodes), np.arange(len(nodes))[:, None]] = a
    u_ref = system.solve(loads)
    u = system.solve_condensed(nodes, direction, check=check)
    assert u.shape == u_ref.shape and not u[:, -1].any()
    np.testing.assert_allclose(u, u_ref, rtol=0, atol=1e-10 * np.abs(u_ref).max())
    assert (system.residual < 1e-10) if check else np.isnan(system.residual)
    inner = np.setdiff1d(np.arange(len(model.nodes)), np.concatenate(
        [top] + [model.region_nodes(r) for r in ("ymin", "xmin")]))[:2]
    assert inner.size
    with pytest.raises(ValueError, match="not condensed"):
        system.solve_condensed(np.r_[top[:1], inner], direction)


def test_factorisations_leave_the_environment_unchanged():
    pytest.importorskip("pypardiso")
    before = dict(os.environ)
    K, B, D, A = _saddle(seed=6)
    b = np.ones(A.shape[0])
    for _ in range(3):
        Pardiso(sp.triu(A, format="csr"), schur=np.array([2, 3])).solve(b)
        SaddleFactor(K, B, D)(np.ones(K.shape[0]))
        solve_refined(A, b)
    assert dict(os.environ) == before


def test_pardiso_runs_in_mkls_reproducible_mode():
    """Once PARDISO has run, MKL is in its reproducible mode (`fem.core.linalg._mkl_pardiso`):
    without it a factorisation on two threads that reuses an analysis gave other last bits from
    run to run. A 3D Laplacian above SERIAL_PARDISO_BELOW (two threads), refactorised on its
    analysis in single and double precision, solves to the same bits twice."""
    pytest.importorskip("pypardiso")
    from fem.core.linalg import SERIAL_PARDISO_BELOW, mkl_reproducible
    A = laplacian_3d(30)
    assert A.shape[0] > SERIAL_PARDISO_BELOW
    b = np.random.default_rng(13).standard_normal(A.shape[0])
    for single in (False, True):
        solutions = []
        for _ in range(2):
            first = Pardiso(sp.triu(A, format="csr"), single=single)
            again = Pardiso(sp.triu(A + sp.diags(np.linspace(0.1, 0.2, A.shape[0])), format="csr"), single=single,
                            reuse=first)
            solutions.append(again.solve(b))
            again.release()
        assert np.array_equal(*solutions)
    assert mkl_reproducible()


def test_blas_threads_limits_and_restores():
    from threadpoolctl import threadpool_info

    def blas():
        return [i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"]

    outside = blas()
    with blas_threads(1):
        assert all(n == 1 for n in blas())
    with blas_threads(None):
        assert blas() == outside
    assert blas() == outside


def test_blas_limit_reaches_pardiso_loaded_after_a_first_limit():
    """A limit set before pypardiso loaded MKL must still reach MKL afterwards (a cached scan of
    the libraries once left PARDISO on all threads, and a serial run's bits differed from its
    one-thread tasks')."""
    import subprocess
    import sys

    code = ("from fem.core.linalg import blas_threads, _thread_controller\n"
            "with blas_threads(1): pass\n"
            "import pypardiso\n"
            "with blas_threads(1):\n"
            "    mkl = [i for i in _thread_controller().info() if i['internal_api'] == 'mkl']\n"
            "    print(len(mkl), [i['num_threads'] for i in mkl])\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                         cwd=str(ROOT)).stdout.split("\n")[0]
    assert out == "1 [1]"


def test_serial_openblas_limits_openblas_and_leaves_mkl():
    """Inside `serial_openblas` every OpenBLAS runs on one thread (its spinning threads doubled the
    finite solver's PARDISO solves) while MKL, PARDISO's, keeps its thread count; both are as before
    afterwards."""
    from fem.core.linalg import _thread_controller, load_mkl, serial_openblas

    load_mkl()

    def threads():
        return sorted((i["internal_api"], i["filepath"], i["num_threads"]) for i in _thread_controller().info())

    before = threads()
    if not any(api == "openblas" for api, _, _ in before):
        pytest.skip("NumPy and SciPy use no OpenBLAS here")
    with serial_openblas():
        inside = threads()
    assert [n for api, _, n in inside if api == "openblas"] == [1] * sum(api == "openblas" for api, _, _ in before)
    assert [t for t in inside if t[0] != "openblas"] == [t for t in before if t[0] != "openblas"]
    assert threads() == before


def test_a_reused_factorisation_gathers_the_matrix_the_long_way_would_build():
    """A factorisation on an earlier one's pattern builds its matrix by a gather (`Gather`) equal,
    bit for bit, to restricting, stacking and `onto_pattern`: with new values, with entries at
    round-off (zeros there), and when an entry above round-off falls outside the pattern (then it
    is built the long way, on the grown pattern, and the earlier factorisation is released before
    the new one is made)."""
    from fem.core.patterns import onto_pattern

    rng = np.random.default_rng(3)
    n, m = 80, 12
    A = sp.random(n, n, density=0.06, random_state=4, format="csr")
    pattern = (A + A.T + sp.eye(n)).tocsr()
    B = sp.random(m, n, density=0.1, random_state=5, format="csr")
    D, free = rng.uniform(0.5, 1.0, m), np.sort(rng.choice(n, n - 7, replace=False))

    def stiffness(values):
        K = pattern.copy()
        K.data = values
        return ((K + K.T) * 0.5 + sp.diags(np.full(n, float(n)))).tocsr()

    def long_way(K, earlier):
        Kf, Bf = K[free][:, free], B[:, free]
        return onto_pattern(sp.bmat([[sp.triu(Kf), Bf.T], [None, -sp.diags(D)]], format="csr"), *earlier.pattern)

    first = SaddleFactor(stiffness(rng.uniform(-1, 1, pattern.nnz)), B, D, free=free)
    K = stiffness(rng.uniform(-1, 1, pattern.nnz)).tolil()
    upper = sp.triu(first.Kdev[free][:, free], 1).tocoo()
    for r, c in zip(free[upper.row[:5]], free[upper.col[:5]]):
        K[r, c] = K[c, r] = 1e-15                       # round-off: explicit zeros on the pattern
    K = K.tocsr()
    again = SaddleFactor(K, B, D, free=free, reuse=first)
    expected = long_way(K, first._pardiso)
    assert again._gather is not None and np.count_nonzero(expected.data == 0) >= 5
    assert again._pardiso._pt is first._pardiso._pt                                    # its analysis taken over
    np.testing.assert_array_equal(again._pardiso._data, expected.data)
    np.testing.assert_array_equal(again._pardiso._ja - 1, expected.indices)
    again(rng.standard_normal(len(free)))
    assert again.last_residual < 1e-10

    grown = K.tolil()
    i, j = free[0], free[-1]                            # a coupling the pattern lacks
    assert K[i, j] == 0
    grown[i, j] = grown[j, i] = 0.3
    grown = grown.tocsr()
    third = SaddleFactor(grown, B, D, free=free, reuse=again)
    assert third._gather.upper(grown, B, D) is None
    assert third._pardiso._pt is not again._pardiso._pt and not again._pardiso._live   # released first
    expected = long_way(grown, again._pardiso)
    assert len(expected.data) > len(again._pardiso._data)
    np.testing.assert_array_equal(third._pardiso._data, expected.data)
    third(rng.standard_normal(len(free)))
    assert third.last_residual < 1e-10


def test_drop_round_off_leaves_a_pattern_free_of_summation_order():
    """Entries at round-off of the diagonal scale (and explicit zeros) go, the diagonal and every
    entry above the threshold stay: two matrices that differ only by round-off-sized entries get
    the same pattern, hence the same PARDISO ordering."""
    from fem.core.patterns import drop_round_off

    rng = np.random.default_rng(3)
    n = 60
    A = sp.random(n, n, density=0.1, random_state=rng) + sp.diags(rng.uniform(1, 1e5, n))
    A = sp.triu(A + A.T, format="csr")
    A.data[np.abs(A.data) < 1e-3] = 1e-3                      # no genuine entry near round-off
    rows, cols = rng.integers(0, n, 40), rng.integers(0, n, 40)
    new = (rows < cols) & (A[rows, cols].A1 == 0)               # absent upper entries
    rows, cols = rows[new], cols[new]
    noise = rng.uniform(-1e-15, 1e-15, len(rows)) * np.sqrt(A.diagonal()[rows] * A.diagonal()[cols])
    noise[0] = 0.0                                              # an explicit zero
    coo = A.tocoo()
    noisy = sp.csr_matrix((np.r_[coo.data, noise], (np.r_[coo.row, rows], np.r_[coo.col, cols])), shape=A.shape)
    assert noisy.nnz > A.nnz
    a, b = drop_round_off(A), drop_round_off(noisy)
    np.testing.assert_array_equal(a.indptr, b.indptr)
    np.testing.assert_array_equal(a.indices, b.indices)
    assert abs(a - A).max() == 0 and a.nnz == A.nnz
    np.testing.assert_allclose(a.diagonal(), A.diagonal(), rtol=0)


def test_onto_pattern_keeps_the_earlier_pattern_and_grows_it_by_real_entries():
    """A matrix that lacks some of an earlier pattern's entries and has round-off ones outside it
    lands on that pattern (explicit zeros, the round-off dropped); an entry above round-off
    outside it joins it. The values are the matrix's own."""
    from fem.core.patterns import drop_round_off, onto_pattern

    rng = np.random.default_rng(8)
    n = 50
    A = sp.random(n, n, density=0.1, random_state=rng) + sp.diags(rng.uniform(1, 10, n))
    A = sp.triu(A + A.T, format="csr")
    A.data[np.abs(A.data) < 1e-3] = 1e-3
    B = A.tolil()
    r, c = sp.triu(A, 1).nonzero()
    B[r[0], c[0]] = 0.0                                      # an entry of the pattern gone
    free = [(i, j) for i in range(n) for j in range(i + 1, n) if A[i, j] == 0]
    B[free[0]] = 1e-16                                       # round-off outside it
    B[free[1]] = 0.5                                         # a real new entry
    B = B.tocsr()
    out = onto_pattern(B, A.indptr, A.indices)
    np.testing.assert_array_equal(out.toarray(), drop_round_off(B).toarray())
    pattern = set(zip(*A.nonzero())) | {free[1]}
    assert set(zip(*np.repeat(np.arange(n), np.diff(out.indptr)).reshape(1, -1), out.indices)) == pattern
    same = onto_pattern(A, A.indptr, A.indices)
    np.testing.assert_array_equal(same.indices, A.indices)
    np.testing.assert_array_equal(same.data, A.data)


def test_saddle_factor_reuses_the_analysis_when_entries_cancel():
    """A tangent that lacks one of the first's entries (a sum that cancelled) and has a round-off
    one outside its pattern is factorised on the first's analysis (its handle taken over) and
    solves exactly."""
    pytest.importorskip("pypardiso")
    K, B, D, _ = _saddle(seed=9)
    first = SaddleFactor(K, B, D)
    upper = sp.triu(K, 1).tocoo()
    i, j = upper.row[np.argmin(np.abs(upper.data))], upper.col[np.argmin(np.abs(upper.data))]
    rows, cols = np.nonzero(K.toarray() == 0)
    K2 = K.tolil()
    K2[i, j] = K2[j, i] = 0.0
    K2[rows[0], cols[0]] = K2[cols[0], rows[0]] = 1e-17
    K2 = K2.tocsr()
    second = SaddleFactor(K2, B, D, reuse=first)
    assert not first._pardiso._live
    b = np.random.default_rng(10).standard_normal(K.shape[0])
    Kc = (K2 + B.T @ sp.diags(1 / D) @ B).toarray()
    np.testing.assert_allclose(second(b), np.linalg.solve(Kc, b), rtol=1e-10)


def test_single_precision_solves_to_its_precision_and_keeps_its_own_analysis():
    """A single-precision factorisation (iparm[27] = 1) solves the saddle system to float32's
    accuracy (the condition number here is about 100: within 1e-4, and not to 1e-9, so it did run
    in float32), returns float64, is reused by single-precision factorisations only, and refuses a
    Schur complement."""
    pytest.importorskip("pypardiso")
    K, B, D, A = _saddle(seed=11)
    upper = sp.triu(A, format="csr")
    single = Pardiso(upper, single=True)
    b = np.random.default_rng(12).standard_normal((A.shape[0], 2))
    x = np.linalg.solve(A.toarray(), b)
    y = single.solve(b)
    assert single.single and y.dtype == np.float64 and y.shape == b.shape
    error = np.abs(y - x).max() / np.abs(x).max()
    assert 1e-9 < error < 1e-4
    assert not Pardiso(upper).takes(single) and not single.takes(Pardiso(upper))
    again = Pardiso(upper, single=True, reuse=single)           # the same pattern and precision
    assert not single._live and np.abs(again.solve(b) - x).max() < 1e-4 * np.abs(x).max()
    with pytest.raises(ValueError):
        Pardiso(upper, schur=np.array([1, 2]), single=True)
    factor = SaddleFactor(K, B, D, single=True)
    Kc = (K + B.T @ sp.diags(1 / D) @ B).toarray()
    assert factor.single and not SaddleFactor(K, B, D).single
    np.testing.assert_allclose(factor(b[:K.shape[0], 0], refine=False), np.linalg.solve(Kc, b[:K.shape[0], 0]),
                               rtol=1e-4, atol=1e-4 * np.abs(np.linalg.solve(Kc, b[:K.shape[0], 0])).max())


def test_interruptible_call_hands_ctrl_c_to_the_caller_at_once():
    """A long call that releases Python's lock runs in the long-call thread: Ctrl-C (here
    simulated with _thread.interrupt_main) reaches the waiting caller within a few WAIT_S, not when
    the call returns; a result or an error of a call that ends comes back as from a direct call."""
    import _thread
    import signal
    import threading
    import time

    from fem.core.longcalls import WAIT_S, interruptible

    assert interruptible(sum, [1, 2, 3]) == 6
    with pytest.raises(ZeroDivisionError):
        interruptible(lambda: 1 / 0)
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)   # a run in the background ignores it
    try:
        timer = threading.Timer(0.2, _thread.interrupt_main)
        timer.start()
        t0 = time.perf_counter()
        with pytest.raises(KeyboardInterrupt):
            interruptible(time.sleep, 1.0)                   # stands in for a PARDISO factorisation
        assert time.perf_counter() - t0 < 0.2 + 3 * WAIT_S
        assert interruptible(sum, [4, 5]) == 9              # after the abandoned call ends
    finally:
        signal.signal(signal.SIGINT, previous)


@pytest.mark.skipif(not Path("/proc/self/status").exists(), reason="reads the thread count from /proc")
def test_factorisations_leave_no_threads_behind():
    """Long PARDISO phases run on one thread for the life of the process (`interruptible`): MKL's
    OpenMP runtime keeps a team of threads for every thread that calls it in parallel, so a thread
    per call left one more OS thread behind per factorisation (103 after 100)."""
    from fem.core.linalg import SERIAL_PARDISO_BELOW

    def os_threads() -> int:
        status = Path("/proc/self/status").read_text()
        return int(next(line.split()[1] for line in status.splitlines() if line.startswith("Threads:")))

    upper = sp.triu(laplacian_3d(30), format="csr")     # 27,000 unknowns: factorised on MKL's threads
    assert upper.shape[0] >= SERIAL_PARDISO_BELOW
    Pardiso(upper).release()
    before = os_threads()
    for _ in range(20):
        Pardiso(upper).release()
    assert os_threads() <= before


def test_one_thread_for_small_matrices_is_set_on_the_main_thread_only():
    """A small matrix's phases run on the calling thread; MKL's thread count is set to one there
    only on the main thread. (Set in another thread, with MKL's reproducible mode on, it crashed
    PARDISO's Schur analysis now and then: `SERIAL_PARDISO_BELOW`.)"""
    import threading

    A = sp.diags([-np.ones(99), 2.5 * np.ones(100), -np.ones(99)], [-1, 0, 1])
    factor = Pardiso(sp.triu(A, format="csr"))
    counts, threads = [], factor._threads

    def spy(k):
        counts.append((threading.current_thread().name, k))
        return threads(k)

    factor._threads = spy
    b = np.ones(100)
    x = factor.solve(b)
    assert counts[0] == (threading.main_thread().name, 1) and len(counts) == 2      # set, then restored
    counts.clear()
    got = []
    elsewhere = threading.Thread(target=lambda: got.append(factor.solve(b)), name="caller")
    elsewhere.start()
    elsewhere.join()
    assert counts == [] and np.array_equal(got[0], x)
    np.testing.assert_allclose(A @ x, b, rtol=1e-12)
