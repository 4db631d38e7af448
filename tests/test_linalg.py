"""fem.linalg: PARDISO's Schur complement and Schur-path solves against dense linear algebra,
the refined saddle solve, BLAS thread limits, and no environment changes."""
import os

import numpy as np
import pytest
import scipy.sparse as sp

from fem import reference as ref
from fem.linalg import Pardiso, SaddleFactor, blas_threads, solve_refined
from fem.solver import Model


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


@pytest.mark.parametrize("direction", [(0.0, -1.0, 0.0), (0.6, -0.8, 0.0)])
def test_model_compliance_is_the_dense_inverse_block(direction):
    """Model.system(condense=) on a small box: the stored compliance along an axis and along a
    rotated direction equals a^T K_ff^-1 a between the nodes, from the dense K."""
    pytest.importorskip("pypardiso")
    g = np.linspace(0, 1, 3)
    p, cells, regions = ref.box(g, g, g)
    model = Model(p, cells, np.ones(len(cells)), regions, material="m43", nu=0.45)
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
