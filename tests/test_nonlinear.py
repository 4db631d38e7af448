"""Large-deformation neo-Hookean solver (2D plane strain): exact tangent, the small-strain limit is
the linear solver, Newton converges quadratically, load stepping, bad input."""
import numpy as np
import pytest
import scipy.sparse as sp

from fem.nonlinear import NeoHookean2D, compare_line_load, line_load_model
from reconstruct.errors import InputError
from test_biomech import section  # noqa: F401  (the coarse monkey section fixture)




def test_tangent_is_the_derivative_and_linearises_to_the_linear_solver(section):
    model, _ = line_load_model(section, "m43338")
    nl = NeoHookean2D(model)
    x = model.nodes
    u = np.column_stack([0.1 * np.sin(x[:, 1]), 0.08 * np.cos(x[:, 0]) * x[:, 1]]).ravel()
    f, K, G = nl.tangent(u)
    Kc = K + G.T @ sp.diags(1 / nl.D) @ G
    v = np.random.default_rng(0).standard_normal(model.ndof)
    h = 1e-5
    fd = (nl.internal_force(u + h * v) - nl.internal_force(u - h * v)) / (2 * h)
    assert np.linalg.norm(fd - Kc @ v) < 1e-5 * np.linalg.norm(fd)
    assert abs(Kc - Kc.T).max() < 1e-12 * abs(Kc).max()
    f0, K0, G0 = nl.tangent(np.zeros(model.ndof))
    assert np.abs(f0).max() == 0
    lin = (K0 + G0.T @ sp.diags(1 / nl.D) @ G0) @ v
    assert np.linalg.norm(lin - model.K @ v) < 1e-10 * np.linalg.norm(lin)


@pytest.mark.parametrize("nu", [0.48, 0.4999])
def test_small_depth_reduces_to_the_linear_solver(section, nu):
    """Line load 0.05 mm on the five-layer section (m43338): force and surface deflection within
    1 % of the linear (locking-free) solver, also nearly incompressible."""
    c = compare_line_load(section, [0.05], material="m43338", nu=nu, half_width_mm=0.25)
    assert not c.failed
    assert c.force_nonlinear_N[0] == pytest.approx(c.force_linear_N[0], rel=0.01)
    assert c.max_difference[0] < 0.01
    assert c.deflection_linear_mm[0].max() == pytest.approx(0.05, rel=1e-6)


def test_newton_converges_quadratically(section):
    """One 0.6 mm load step on the homogeneous section: once the (line-searched) iterations reach
    the full Newton step, the residual (relative to the reaction) squares, r_k+1 <= C r_k^2 with C
    of order 1 (measured 1.7e-2, 2.4e-4, 1.2e-7, 5.3e-14), observed order >= 1.7."""
    model, _ = line_load_model(section, "m33333", half_width_mm=0.25)
    res = NeoHookean2D(model).solve({"fixed": 0.0, "load": (None, -0.6)}, steps=1, tol=1e-14)
    load = model.node_dofs(model.region_nodes("load"))[:, 1]
    r = np.array(res.history[-1]) / abs(res.reaction[-1][load].sum())
    r = r[r > 2e-14]                                         # above the round-off floor (~1.5e-14)
    assert len(r) >= 4 and r[-1] < 1e-10
    tail = [(a, b) for a, b in zip(r[:-1], r[1:]) if a < 3e-2]
    assert len(tail) >= 2 and all(b <= 10 * a * a for a, b in tail), r
    order = np.log(r[-1] / r[-2]) / np.log(r[-2] / r[-3])
    assert order > 1.7, (order, r)


def test_deeper_load_parts_from_linear_and_stiffens(section):
    """At 0.5 mm (2 load steps) the nonlinear line load needs more force than the linear one and
    the profiles differ by a few % of the depth: the report's 'where they part'."""
    c = compare_line_load(section, [0.5], material="m43338", half_width_mm=0.25, step_mm=0.25)
    assert not c.failed
    ratio = c.force_nonlinear_N[0] / c.force_linear_N[0]
    assert 1.02 < ratio < 1.2 and 0.01 < c.max_difference[0] < 0.1


def test_only_2d(tmp_path):
    from fem.reference import box

    p, cells, r = box(np.linspace(0, 1, 3), np.linspace(0, 1, 3), np.linspace(0, 1, 3))
    from fem.solver import Model

    with pytest.raises(InputError, match="2D plane-strain"):
        NeoHookean2D(Model(p, cells, np.ones(len(cells), int), r, material=[1.0]))
