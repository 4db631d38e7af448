import numpy as np
import pytest
import scipy.sparse as sp

from fem.core import inverse
from fem.core.linalg import saddle_upper

pytestmark = pytest.mark.skipif(not inverse.available(), reason="python-mumps is not installed (optional)")


def test_entries_of_the_inverse_of_a_saddle_matrix():
    rng = np.random.default_rng(0)
    n, m = 40, 12
    Kdev = sp.random(n, n, density=0.15, random_state=1)
    Kdev = (Kdev @ Kdev.T + sp.eye(n)).tocsr()
    B = sp.random(m, n, density=0.2, random_state=2).tocsr()
    D = rng.uniform(0.5, 1.0, m)
    A = sp.bmat([[Kdev, B.T], [B, -sp.diags(D)]]).toarray()        # symmetric indefinite
    rows, cols = np.array([0, 3, 7, 20, 41, 50]), np.array([33, 2, 45, 7])
    got = inverse.InverseEntries(saddle_upper(Kdev, B, D)).block(rows, cols)
    np.testing.assert_allclose(got, np.linalg.inv(A)[np.ix_(rows, cols)], rtol=0, atol=1e-12 * np.abs(got).max())


def test_columns_in_any_order_and_the_transposed_layout():
    rng = np.random.default_rng(3)
    n = 30
    M = sp.random(n, n, density=0.2, random_state=4)
    A = (M @ M.T + 3 * sp.eye(n)).tocsr()
    entries = inverse.InverseEntries(sp.triu(A).tocsr())
    rows = np.sort(rng.choice(n, 9, replace=False))
    dense = np.linalg.inv(A.toarray())
    for cols in (np.array([4, 1, 29, 17]), np.array([1, 4, 17, 29]), np.array([8])):
        got = entries.block_t(rows, cols)
        assert got.shape == (len(cols), len(rows)) and got.flags.c_contiguous
        np.testing.assert_allclose(got, dense[np.ix_(rows, cols)].T, rtol=0, atol=1e-12 * np.abs(dense).max())
    np.testing.assert_array_equal(entries.block(rows, cols), entries.block_t(rows, cols).T)


def test_local_blocks_partition_the_points_into_compact_blocks():
    x, y = np.meshgrid(np.arange(40.0), np.arange(25.0))
    pts = np.c_[x.ravel(), y.ravel()][np.random.default_rng(5).permutation(1000)]
    blocks = inverse.local_blocks(pts, 128)
    assert [len(b) for b in blocks] == [128] * 7 + [104]                  # whole blocks first
    np.testing.assert_array_equal(np.sort(np.concatenate(blocks)), np.arange(1000))
    # each block is a patch: its extent is a fraction of the whole (40 x 25), not a random sample
    assert max(np.ptp(pts[b], axis=0).max() for b in blocks) <= 13
    assert [b.tolist() for b in inverse.local_blocks(pts, 128)] == [b.tolist() for b in blocks]


def test_openblas_kernel_from_the_processor_flags():
    avx512 = {"avx512f", "avx512dq", "avx512cd", "avx512bw", "avx512vl", "avx2", "fma", "sse4_2"}
    assert inverse.openblas_kernel(avx512) == "SkylakeX"
    assert inverse.openblas_kernel({"avx", "avx2", "fma", "avx512f"}) == "Haswell"
    assert inverse.openblas_kernel({"sse2", "sse4_2", "avx"}) is None


def test_the_system_openblas_runs_the_kernel_the_processor_allows():
    """On a processor with AVX2 the OpenBLAS that MUMPS loaded must not have fallen back to its
    Prescott (SSE3) kernel (the module docstring: 9 times slower dense products)."""
    name = inverse.loaded_openblas_kernel()
    if name is None:
        pytest.skip("MUMPS loaded no system OpenBLAS")
    if inverse.openblas_kernel(inverse._cpu_flags()) is None:
        pytest.skip("the processor has neither AVX2 nor AVX-512")
    assert name.lower() != "prescott", name


INTERRUPTED = """
import sys, time
import scipy.sparse as sp
from fem.core import inverse, longcalls
from tests.helpers import laplacian_3d
upper = sp.triu(laplacian_3d(48), format="csr")
print("factorising", flush=True)
t0 = time.perf_counter()
try:
    inverse.InverseEntries(upper)
except KeyboardInterrupt:
    print("interrupted after", time.perf_counter() - t0, flush=True)
    sys.exit(longcalls.end_interrupted(130))
print("finished after", time.perf_counter() - t0, flush=True)
"""


def test_ctrl_c_acts_inside_the_factorisation():
    """Ctrl-C 2 s into the analysis and factorisation of a 3D Laplacian of 110,592 unknowns (about
    4 s for both, the factorisation from about 1.7 s) ends them within a fraction of a second
    (0.13-0.17 s measured; 1.7-2.2 s when MUMPS held the main thread): MUMPS runs `interruptible`."""
    import signal
    import subprocess
    import sys
    import time

    from tests.helpers import ROOT, default_sigint

    proc = subprocess.Popen([sys.executable, "-c", INTERRUPTED], cwd=ROOT, stdout=subprocess.PIPE, text=True,
                            preexec_fn=default_sigint)
    assert proc.stdout.readline().strip() == "factorising"
    time.sleep(2.0)
    t0 = time.perf_counter()
    proc.send_signal(signal.SIGINT)
    out, _ = proc.communicate(timeout=120)
    assert proc.returncode == 130 and out.startswith("interrupted after"), out
    assert time.perf_counter() - t0 < 1.0
