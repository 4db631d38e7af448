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
