"""Large-deformation neo-Hookean solver (3D tetrahedra and 2D plane strain): exact tangent, the
small-strain limit is the linear solver, a closed-form large stretch, quadratic Newton
convergence, the 2 mm line load, bad input."""
import numpy as np
import pytest
import scipy.sparse as sp
from scipy.optimize import brentq

from fem.biomech.line_load import compare_line_load, line_load_model
from fem.core.model import Model
from fem.core.neohookean import NeoHookean
from fem.verify.closed_forms import box


def _block(dim, n=2, layered=False, nu=0.45):
    """Unit block [0, 1]^dim (n elements a side); layered: the top half (y > 0.5) 10x stiffer."""
    g = np.linspace(0, 1, n + 1)
    p, cells, regions = box(g, g, g if dim == 3 else None)
    layer = np.where(p[cells].mean(axis=1)[:, 1] > 0.5, 1, 2) if layered else np.ones(len(cells), int)
    return Model(p, cells, layer, regions, material=[1.0, 0.1] if layered else [1.0], nu=nu)


def _strip(dim, nu):
    """Layered slab 4 x 3 (x 4) mm, stiff 0.5 mm top layer (m43 ratio 10), bottom held; 'load':
    the top vertices within 0.35 mm of x = 2 (3D: the strip across z, |z - 2| <= 1)."""
    xs, ys = np.linspace(0, 4, 13), np.array([0.0, 1.0, 2.0, 2.5, 3.0])
    p, cells, r = box(xs, ys, np.linspace(0, 4, 5) if dim == 3 else None)
    layer = np.where(p[cells].mean(axis=1)[:, 1] > 2.5, 1, 2)
    load = r["ymax"] & (np.abs(p[:, 0] - 2) <= 0.35) & ((np.abs(p[:, 2] - 2) <= 1) if dim == 3 else True)
    return Model(p, cells, layer, {"bottom": r["ymin"], "load": load}, material=[0.01, 0.001], nu=nu)


@pytest.mark.parametrize("dim", [2, 3])
def test_tangent_is_the_derivative_and_linearises_to_the_linear_solver(dim):
    """Central differences of the internal force match the exact tangent K + G^T D^-1 G (to the
    1e-10 the differences allow), it is symmetric, and at u = 0 it is the linear solver's K
    (two layers; elements assembled in chunks of 7)."""
    model = _block(dim, layered=True)
    nl = NeoHookean(model, chunk=7)
    x = model.nodes
    u = 0.1 * np.column_stack([np.sin(x[:, 1] + 0.3 * x[:, 0])]
                              + [np.cos(x[:, k]) * x[:, 1] for k in range(1, dim)]).ravel()
    f, K, G = nl.tangent(u)
    Kc = K + G.T @ sp.diags(1 / nl.D) @ G
    v = np.random.default_rng(0).standard_normal(model.ndof)
    h = 1e-6
    fd = (nl.internal_force(u + h * v) - nl.internal_force(u - h * v)) / (2 * h)
    assert np.linalg.norm(fd - Kc @ v) < 1e-8 * np.linalg.norm(fd)
    assert abs(Kc - Kc.T).max() < 1e-12 * abs(Kc).max()
    np.testing.assert_allclose(f, nl.internal_force(u), rtol=0, atol=1e-13 * np.abs(f).max())
    f0, K0, G0 = nl.tangent(np.zeros(model.ndof))
    assert np.abs(f0).max() == 0
    lin = (K0 + G0.T @ sp.diags(1 / nl.D) @ G0) @ v
    assert np.linalg.norm(lin - model.K @ v) < 1e-12 * np.linalg.norm(lin)


def _uniaxial(stretch, mu, lam, dim):
    """Closed form: homogeneous stretch `stretch` along x, free sideways, of the nearly
    incompressible neo-Hookean W = mu/2 (J^(-2/d) I1 - d) + kappa/2 (J - 1)^2 (the u-p
    formulation with p eliminated, kappa = lam + 2 mu / d). Returns (lateral stretch, P_xx [MPa])."""
    kappa = lam + 2 * mu / dim

    def P(s, i):                      # first Piola stress component i (0: along x, 1: lateral)
        J = stretch * s ** (dim - 1)
        I1 = stretch**2 + (dim - 1) * s**2
        Fi = stretch if i == 0 else s
        return mu * J ** (-2 / dim) * (Fi - I1 / (dim * Fi)) + kappa * (J - 1) * J / Fi

    s = brentq(lambda s: P(s, 1), 0.1, 5.0, xtol=1e-15)
    return s, P(s, 0)


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("stretch", [1.6, 0.6])
def test_uniaxial_stretch_matches_closed_form(dim, stretch):
    """Unit block on rollers (x, y, z = 0 planes), the x = 1 face moved to x = stretch in 8
    steps: lateral contraction and the force on the face are the closed form's to 1e-9 (the
    homogeneous field is in the P2 / P1 spaces); the linear answer is 10-60 % off there."""
    model = _block(dim, nu=0.45)
    rollers = {f"{c}min": tuple(0.0 if k == i else None for k in range(dim)) for i, c in enumerate("xyz"[:dim])}
    pres = {**rollers, "xmax": tuple(stretch - 1.0 if k == 0 else None for k in range(dim))}
    res = NeoHookean(model).solve(pres, steps=8)
    s, Pxx = _uniaxial(stretch, model.mu[0], model.lam[0], dim)
    top = model.node_dofs(model.region_nodes("ymax"))[:, 1]
    np.testing.assert_allclose(res.u[-1][top], s - 1.0, rtol=1e-9)
    force = res.reaction[-1][model.node_dofs(model.region_nodes("xmax"))[:, 0]].sum()
    assert force == pytest.approx(Pxx, rel=1e-9)
    linear = (model.K @ model.system(pres).u0)[model.node_dofs(model.region_nodes("xmax"))[:, 0]].sum()
    assert abs(linear / force - 1) > 0.1
    assert res.min_J[-1] == pytest.approx(stretch * s ** (dim - 1), rel=1e-9)


@pytest.mark.parametrize("nu", [0.48, 0.4999])
def test_3d_small_depth_reduces_to_the_linear_solver(nu):
    """3D layered slab, strip pressed 0.05 mm (held sideways): force and top-surface deflection
    within 1 % of the linear (locking-free) solver, also nearly incompressible (measured 0.3 % and
    0.7-0.8 % of the depth); at half the depth the difference halves (first order in the depth)."""
    model = _strip(3, nu)
    load = model.node_dofs(model.region_nodes("load"))[:, 1]
    top = model.node_dofs(np.flatnonzero(np.isclose(model.nodes[:, 1], 3.0)))[:, 1]
    force, deflection = [], []
    for depth in (0.05, 0.025):
        pres = {"bottom": 0.0, "load": (0.0, -depth, 0.0)}
        ul = model.system(pres).u0
        res = NeoHookean(model).solve(pres, steps=1)
        force.append(res.reaction[-1][load].sum() / (model.K @ ul)[load].sum() - 1)
        deflection.append(np.abs(res.u[-1][top] - ul[top]).max() / depth)
    assert 0 < force[0] < 0.01 and deflection[0] < 0.01
    assert force[1] / force[0] == pytest.approx(0.5, abs=0.05)
    assert deflection[1] / deflection[0] == pytest.approx(0.5, abs=0.05)


def _ratios(res, model):
    load = model.node_dofs(model.region_nodes("load"))[:, 1]
    return np.array(res.history[-1]) / abs(res.reaction[-1][load].sum())


def _assert_quadratic(r):
    """Residuals relative to the reaction: converged below 1e-11; above the round-off floor
    (1e-13) each residual below 1e-2 is squared by the next, r_k+1 <= 100 r_k^2 (a linear rate
    of 0.1 fails this by 10^3 at 1e-6), and the last three give an order of convergence > 1.5."""
    assert r[-1] < 1e-11, r
    r = r[r > 1e-13]
    tail = [(a, b) for a, b in zip(r[:-1], r[1:]) if a < 1e-2]
    assert len(tail) >= 2 and all(b <= 100 * a * a for a, b in tail), r
    assert np.log(r[-1] / r[-2]) / np.log(r[-2] / r[-3]) > 1.5, r


def test_3d_newton_converges_quadratically():
    """One 0.6 mm load step on the 3D slab (20 % of its thickness, 1.7 times the strip's half
    width): once the iterations reach the full Newton step the residual squares."""
    model = _strip(3, 0.48)
    res = NeoHookean(model).solve({"bottom": 0.0, "load": (0.0, -0.6, 0.0)}, steps=1, tol=1e-14)
    _assert_quadratic(_ratios(res, model))


def test_2d_newton_converges_quadratically(section):
    """One 0.6 mm load step on the homogeneous section, as in 3D."""
    model, _ = line_load_model(section, "m33333", half_width_mm=0.25)
    res = NeoHookean(model).solve({"fixed": 0.0, "load": (0.0, -0.6)}, steps=1, tol=1e-14)
    _assert_quadratic(_ratios(res, model))


@pytest.mark.parametrize("nu", [0.48, 0.4999])
def test_2d_small_depth_reduces_to_the_linear_solver(section, nu):
    """Line load 0.05 mm on the five-layer section (m43338), frictionless patch: force and surface
    deflection within 1 % of the linear (locking-free) solver, also nearly incompressible
    (measured 0.7 %; with the patch held sideways 0.8 and 1.02 %, first order in the depth)."""
    c = compare_line_load(section, [0.05], material="m43338", nu=nu, half_width_mm=0.25, slip=True)
    assert not c.failed
    assert c.force_nonlinear_N[0] == pytest.approx(c.force_linear_N[0], rel=0.01)
    assert c.max_difference[0] < 0.01
    assert c.deflection_linear_mm[0].max() == pytest.approx(0.05, rel=1e-6)


def test_2d_line_load_reaches_2_mm_and_parts_from_linear(section):
    """The thesis's 2 mm line load on the five-layer section (m43338, 0.5 mm patch held sideways,
    0.25 mm load steps, one solve landing on each depth): reached without step cuts; the force
    ratio nonlinear / linear grows monotonically from 1 (0.8 % at 0.05 mm, measured 1.10, 1.23,
    1.64 at 0.5, 1, 2 mm) and so does the profile difference; no element near inversion."""
    c = compare_line_load(section, [0.05, 0.5, 1.0, 2.0], material="m43338", half_width_mm=0.25, step_mm=0.25)
    assert not c.failed
    ratio = c.force_nonlinear_N / c.force_linear_N
    assert abs(ratio[0] - 1) < 0.01 and np.all(np.diff(ratio) > 0) and 1.3 < ratio[-1] < 2.0
    assert np.all(np.diff(c.max_difference) > 0) and c.max_difference[-1] > 0.05
    assert c.min_J[-1] > 0.3
    np.testing.assert_allclose(c.deflection_linear_mm[:, np.argmin(np.abs(c.distance_mm))], c.depths_mm, rtol=1e-9)


def test_a_stagnating_newton_is_cut_after_the_stagnation_count(monkeypatch):
    """A tangent 1000x too stiff makes each Newton step remove under 1 % of the residual: the step is
    given up after STAGNATION iterations without the residual halving (not max_iter), and with no
    cuts left the solve stops with that reason."""
    import fem.core.neohookean as nh

    model = _block(2)
    nl = NeoHookean(model)
    exact = nl.tangent
    calls = []

    def stiff(u):
        calls.append(1)
        f, K, G = exact(u)
        return f, 1000 * K, G

    monkeypatch.setattr(nl, "tangent", stiff)
    res = nl.solve({"ymin": 0.0, "ymax": (0.0, -0.05)}, steps=1, max_cuts=0, partial=True)
    assert "Newton stagnated" in res.stopped and len(res.t) == 1
    assert len(calls) == nh.STAGNATION + 2            # predictor, the first norm, then STAGNATION more
