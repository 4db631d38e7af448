"""det F at element centroids (fem.core.fields.centroid_jacobians): F = I + grad u of a linear
displacement, exact for fields the P2 space holds; <= 0 where the displacement inverts an element."""
import numpy as np
import pytest

from fem import Model
from fem.core.fields import centroid_jacobians
from fem.verify import closed_forms as ref


@pytest.mark.parametrize("dim", [2, 3])
def test_affine_and_quadratic_fields(dim):
    pts, cells, regions = ref.box(*[np.linspace(0, 1, 4)] * dim)
    model = Model(pts, cells, np.ones(len(cells)), regions)
    x = model.nodes
    G = np.diag([0.2, -1.5, 0.1][:dim]) + 0.05 * np.eye(dim, k=1)      # grad u: y squeezed by 150 %
    u = (x @ G.T).ravel()
    np.testing.assert_allclose(centroid_jacobians(model, u), np.linalg.det(np.eye(dim) + G), rtol=1e-12)
    # u_y = -a y^2: F_yy = 1 - 2 a y at the centroid; two fields at once -> (M, 2)
    c = model.mesh.p[:, model.mesh.t].mean(axis=1).T
    q = np.zeros_like(x)
    q[:, 1] = -0.8 * x[:, 1] ** 2
    J = centroid_jacobians(model, np.column_stack([u, q.ravel()]))
    assert J.shape == (len(cells), 2)
    np.testing.assert_allclose(J[:, 1], 1 - 1.6 * c[:, 1], atol=1e-12)
    assert np.all(J[:, 0] < 0) and ((J[:, 1] <= 0) == (c[:, 1] >= 1 / 1.6)).all()
