"""Contact algorithm on analytic compliances: LCP solver, Hertz on an elastic half-space (Love's
uniform-pressure cells), force control, two-point equal force, sweeps reusing the cache, errors."""
import math

import numpy as np
import pytest
import scipy.optimize as so

from fem.contact import compliance
from fem.contact import linear as contact
from fem.contact.facets import averaged_peak_pressure
from fem.contact.indentors import make_indentor
from fem.verify.closed_forms import hertz_sphere
from fingertip.errors import InputError


# --------------------------------------------------------------------------- half-space compliance
def _love(X, Y):
    """Antiderivative with d2/dXdY = 1/sqrt(X^2+Y^2) (0 on the axes)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        t1 = np.where(X != 0, X * np.arcsinh(Y / np.abs(X)), 0.0)
        t2 = np.where(Y != 0, Y * np.arcsinh(X / np.abs(Y)), 0.0)
    return t1 + t2


class HalfSpace(compliance.Compliance):
    """Surface nodes on a square grid (spacing h) of an elastic half-space y < 0; each node's
    force is a uniform pressure over its h x h cell (Love 1929); displacement at cell centres."""

    def __init__(self, xz, h, E, nu):
        super().__init__(len(xz), 0)
        self.xz, self.h, self.k = xz, h, (1 - nu * nu) / (math.pi * E) / (h * h)

    def _compute(self, idx):
        dx = self.xz[:, :1] - self.xz[idx, 0]
        dz = self.xz[:, 1:] - self.xz[idx, 1]
        c = 0.5 * self.h
        F = _love(dx + c, dz + c) - _love(dx - c, dz + c) - _love(dx + c, dz - c) + _love(dx - c, dz - c)
        return self.k * F


def half_space_model(half_width_mm, h, E=1.0, nu=0.3, tilt=0.0):
    n = int(round(2 * half_width_mm / h))
    c = (np.arange(n) - (n - 1) / 2) * h
    X, Z = np.meshgrid(c, c, indexing="ij")
    xz = np.column_stack([X.ravel(), Z.ravel()])
    pts = np.column_stack([xz[:, 0], tilt * xz[:, 0], xz[:, 1]])
    hs = HalfSpace(xz, h, E, nu)
    return contact.ContactModel(pts, np.full(len(xz), h * h), lambda a: hs), hs


def test_love_cells_match_boussinesq_far_away_and_sum():
    h, E, nu = 0.1, 2.0, 0.3
    xz = np.array([[0.0, 0.0], [3.0, 0.0], [2.0, 2.0]])
    col = HalfSpace(xz, h, E, nu).columns([0])[:, 0]
    r = np.hypot(xz[1:, 0], xz[1:, 1])
    np.testing.assert_allclose(col[1:], (1 - nu * nu) / (math.pi * E * r), rtol=1e-3)
    # centre of a uniformly loaded square of side 2c: int dA/r = 8 c ln(1 + sqrt 2), p = 1/h^2
    centre = (1 - nu * nu) / (math.pi * E) * (1 / h ** 2) * 8 * (h / 2) * math.log(1 + math.sqrt(2))
    assert math.isclose(col[0], centre, rel_tol=1e-12)


# --------------------------------------------------------------------------- LCP
@pytest.mark.parametrize("seed", range(5))
def test_lcp_matches_nnls_and_satisfies_kkt(seed):
    rng = np.random.default_rng(seed)
    n = 60
    G = rng.normal(size=(n, n))
    C = G @ G.T / n + 0.05 * np.eye(n)
    q = rng.normal(size=n)
    sol = contact.solve_lcp(lambda i: C[:, i], q)
    f, g = sol.force, sol.gap
    assert f.min() >= 0 and g.min() >= -contact.GAP_TOL_MM
    assert np.abs(f * g).max() < 1e-9
    L = np.linalg.cholesky(C)                       # min |L^T f + L^-1 q|^2, f >= 0
    ref, _ = so.nnls(L.T, -np.linalg.solve(L, q))
    np.testing.assert_allclose(f, ref, atol=1e-8)


def test_active_factor_solves_over_changing_active_sets():
    """Successive active sets on one LCPBlocks (members added: bordered factor; dropped: held by
    their capacitance; many dropped: factorised afresh) solve C[S, S] x = b as a dense solve
    does, and the same factor is returned for an unchanged set."""
    rng = np.random.default_rng(7)
    n = 80
    G = rng.normal(size=(n, n))
    C = G @ G.T / n + 0.05 * np.eye(n)
    blocks = contact.LCPBlocks(lambda i: C[:, i], n)
    active = rng.random(n) < 0.4
    seen = {"held": False, "bordered": False, "rebased": False}
    for step in range(30):
        last = blocks._last
        factor = blocks.factor(active)
        assert blocks.factor(active.copy()) is factor
        idx = np.flatnonzero(active)
        b = rng.normal(size=(len(idx), 2))
        np.testing.assert_allclose(factor.solve(b), np.linalg.solve(C[np.ix_(idx, idx)], b), rtol=1e-9, atol=1e-9)
        seen["held"] |= len(factor.base) > len(idx)
        if last is not None:
            extends = np.array_equal(factor.base[:len(last.base)], last.base)
            seen["bordered"] |= extends and len(factor.base) > len(last.base)
            seen["rebased"] |= not extends
        flip = rng.choice(n, size=rng.integers(1, 4) if step % 10 else 25, replace=False)
        active = active.copy()
        active[flip] ^= True
        if not active.any():
            active[0] = True
    assert all(seen.values()), seen


# --------------------------------------------------------------------------- Hertz on the half-space
@pytest.mark.parametrize("nu", [0.3, 0.49])
def test_hertz_sphere_on_half_space(nu):
    """Force and contact radius within 3 % of Hertz for depths 0.05-0.3 mm (R = 5 mm)."""
    E, R = 1.0, 5.0
    model, hs = half_space_model(1.4, 0.05, E, nu)
    sph = make_indentor(f"sphere:{R}", position_mm=(0.0, 0.0))
    results = model.indent_depths(sph, [0.05, 0.1, 0.2, 0.3])
    for res in results:
        d = float(res.depth_mm[0])
        F, a, p0 = hertz_sphere(R, d, E, nu)
        assert res.kkt["ok"], res.kkt
        assert abs(res.total_force_N / F - 1) < 0.03
        radius = math.sqrt(res.contact_area_mm2 / math.pi)
        assert abs(radius / a - 1) < 0.03, (d, radius, a)
        assert abs(res.max_pressure_MPa / p0 - 1) < 0.05
    # lazy: columns were built for little more than the final contact zone, not the whole grid
    assert hs.computed < 1.25 * results[-1].active.sum() < 0.75 * len(hs.xz)


def test_force_control_inverts_depth_control():
    E, nu, R = 1.0, 0.49, 5.0
    model, _ = half_space_model(1.2, 0.05, E, nu)
    sph = make_indentor(f"sphere:{R}")
    target = hertz_sphere(R, 0.2, E, nu)[0]
    res = model.indent(sph, force_N=target)
    assert abs(res.total_force_N / target - 1) <= contact.FORCE_RTOL
    assert abs(res.depth_mm[0] - 0.2) < 0.006          # Hertz depth within 3 %
    again = model.indent(sph, depth_mm=float(res.depth_mm[0]))
    np.testing.assert_allclose(again.force_N, res.force_N, atol=1e-9 * target)
    with pytest.raises(InputError, match="not reached"):
        model.indent(sph, force_N=1e3, max_depth_mm=0.5)


def test_two_point_equal_force_vs_equal_depth():
    """On a tilted surface the lower tip touches first: equal depth gives unequal forces, equal
    force gives equal forces at unequal tip travels."""
    model, _ = half_space_model(2.0, 0.08, tilt=0.05)
    tp = make_indentor("two-point:2:1.0")            # two spheres of radius 1 mm, 2 mm apart
    eq_d = model.indent(tp, depth_mm=0.2)
    fd = eq_d.part_force_N
    assert fd[1] > 1.5 * fd[0] > 0                  # the +x tip sits on the higher side
    target = 0.5 * fd.sum()
    eq_f = model.indent(tp, force_N=target, equal_force=True)
    np.testing.assert_allclose(eq_f.part_force_N, target, rtol=2e-6)
    # same tips on a (tilted) half-space: equal own depths, travels differ by the 0.1 mm tilt
    assert abs(eq_f.depth_mm[1] / eq_f.depth_mm[0] - 1) < 0.01
    assert abs(eq_f.travel_mm[0] - eq_f.travel_mm[1] - 0.1) < 0.002
    assert eq_f.kkt["ok"]


def test_sweep_reuses_columns_and_matches_fresh_solves():
    model, hs = half_space_model(1.5, 0.1)
    bar = make_indentor("C3", orientation="parallel")
    offs = np.column_stack([np.linspace(-0.5, 0.5, 11), np.zeros(11), np.zeros(11)])
    out = model.sweep(bar, offs, depth_mm=0.1)
    built = hs.computed
    assert built < sum(int(r.active.sum()) for r in out)     # the cache is shared
    for off, r in zip(offs[::5], out[::5]):
        fresh, _ = half_space_model(1.5, 0.1)
        ref = fresh.indent(bar.shifted(off), depth_mm=0.1)
        np.testing.assert_allclose(r.force_N, ref.force_N, atol=1e-12)
        assert r.kkt["ok"]
    with pytest.raises(InputError, match="sweep position"):
        model.sweep(make_indentor("punch:1"), [[0, 0, 0], [9, 0, 0]], depth_mm=0.1)


def test_bad_requests():
    model, _ = half_space_model(1.0, 0.1)
    with pytest.raises(InputError, match="never touches"):
        model.indent(make_indentor("sphere:1", position_mm=(5.0, 0.0)), depth_mm=0.1)
    with pytest.raises(InputError):
        model.indent(make_indentor("sphere:1"), depth_mm=0.1, force_N=1.0)
    with pytest.raises(InputError):
        model.indent(make_indentor("sphere:1"), depth_mm=-0.1)


def test_matrix_compliance_and_observation():
    """A dense compliance with observation rows = the compliance itself: the observed response is
    the deflection of every node, and results equal those of the lazily built model."""
    lazy, hs = half_space_model(1.0, 0.1)
    C = hs.columns(np.arange(len(hs.xz)))
    dense = contact.ContactModel(lazy.points_mm, lazy.areas_mm2, lambda a: compliance.MatrixCompliance(C, C))
    ind = make_indentor("sphere:2")
    a, b = lazy.indent(ind, depth_mm=0.05), dense.indent(ind, depth_mm=0.05)
    np.testing.assert_allclose(b.force_N, a.force_N, atol=1e-12)
    np.testing.assert_allclose(b.observed, b.deflection_mm, atol=1e-12)
    assert b.active.sum() > 10


def test_held_nodes_block_the_indentor_with_a_clear_error():
    """Nodes the body holds fixed have zero compliance: an indentor that would push one raises a
    one-line InputError (no LCP can give it a finite force); force control bisects below the
    depth where that happens and still reaches a force attainable before it."""
    cm, hs = half_space_model(1.0, 0.1)
    held = np.abs(hs.xz[:, 0] - 0.85) < 0.01                          # a held row at x = 0.85 mm
    C = hs.columns(np.arange(hs.m))
    C[held] = 0.0
    C[:, held] = 0.0
    blocked = contact.ContactModel(cm.points_mm, cm.areas_mm2, lambda a: compliance.MatrixCompliance(C))
    sphere = make_indentor("sphere:2")
    ok = blocked.indent(sphere, depth_mm=0.05)                       # contact radius ~0.3 mm: clear of it
    assert ok.kkt["ok"] and not ok.active[held].any()
    with pytest.raises(InputError, match="held fixed") as info:
        blocked.indent(sphere, depth_mm=0.5)                          # reaches x = 0.85 mm
    assert "\n" not in str(info.value)
    res = blocked.indent(sphere, force_N=1.2 * ok.total_force_N)     # Newton's first trial is too deep
    assert abs(res.total_force_N / (1.2 * ok.total_force_N) - 1) < 1e-6
    with pytest.raises(InputError, match="force .* held fixed"):
        blocked.indent(sphere, force_N=100 * ok.total_force_N)


def test_edge_area_is_the_contact_rings_tributary_area():
    """A row of 2D P2 facets (vertices 0, 2, 4, ..., midside nodes between): with nodes 3-9 in
    contact, the outer ring is nodes 3 and 9 (each next to an inactive node on a sub-facet), and
    their tributary lengths sum; all in contact, no ring. A 3D P2 triangle whose midside nodes are
    listed out of edge order: the neighbours are found from the positions."""
    from types import SimpleNamespace

    ContactModel = contact.ContactModel
    x = np.linspace(0.0, 6.0, 13)                             # 6 P2 facets of 1 mm
    facets = np.array([[2 * k, 2 * k + 2, 2 * k + 1] for k in range(6)])
    areas = np.full(13, 0.5)                                   # P2 shares: 1/4 + 1/4 at a vertex, 1/2 midside
    areas[[0, -1]] = 0.25
    cm = ContactModel(np.column_stack([x, np.zeros(13)]), areas, None, facets=(facets, np.ones((6, 3))))
    active = np.zeros(13, bool)
    active[3:10] = True
    assert cm.edge_area_mm2(SimpleNamespace(active=active, area_mm2=areas)) == pytest.approx(areas[[3, 9]].sum())
    active[:] = True
    assert cm.edge_area_mm2(SimpleNamespace(active=active, area_mm2=areas)) == 0.0
    assert np.isnan(ContactModel(x[:, None], areas, None).edge_area_mm2(SimpleNamespace(active=active,
                                                                                          area_mm2=areas)))
    v = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]])
    p = np.vstack([v, 0.5 * (v[1] + v[2]), 0.5 * (v[0] + v[2]), 0.5 * (v[0] + v[1])])   # m12, m02, m01
    tri = ContactModel(p, np.arange(1.0, 7.0), None, facets=(np.arange(6)[None], np.ones((1, 6))))
    from fem.contact.facets import node_pairs

    assert {tuple(q) for q in node_pairs(np.arange(6)[None], p)} == {(0, 4), (0, 5), (1, 3), (1, 5), (2, 3), (2, 4),
                                                    (3, 4), (3, 5), (4, 5)}
    one = np.array([True, False, False, False, False, False])
    assert tri.edge_area_mm2(SimpleNamespace(active=one, area_mm2=np.arange(1.0, 7.0))) == 1.0
    two = one | (np.arange(6) == 5)                          # v0 and m01: both next to inactive nodes
    assert tri.edge_area_mm2(SimpleNamespace(active=two, area_mm2=np.arange(1.0, 7.0))) == 1.0 + 6.0


def _p2_line_loads(h, a, pressure):
    """Nodes (n, 2) of a row of 2D P2 facets of length h over [-a, a] and the consistent nodal
    loads of the pressure p(x) (5-point Gauss per facet)."""
    x = np.arange(-a, a + 1e-12, h / 2)
    f = np.zeros(len(x))
    g, wg = np.polynomial.legendre.leggauss(5)
    for k in range(0, len(x) - 2, 2):
        s = x[k] + 0.5 * h * (g + 1)
        t = (s - x[k]) / h
        N = np.array([(1 - t) * (1 - 2 * t), 4 * t * (1 - t), t * (2 * t - 1)])
        f[k:k + 3] += N @ (wg * pressure(s)) * 0.5 * h
    return np.column_stack([x, np.zeros_like(x)]), f


def test_averaged_peak_pressure_is_the_pressure_over_its_radius():
    """Uniform pressure on P2 facets: the bump-weighted average returns it (measured 7e-16). A
    Hertz profile p0 sqrt(1 - x^2 / a^2): the exact average over the bump at x = 0 (by
    quadrature), to 1e-6 at h = radius / 10 (measured 1.0e-8) and closer when h halves (6e-10). 3D:
    a uniform pressure lumped on a square grid of radius / 10, to 1e-4 (measured 3.3e-5)."""
    ell = 0.1
    x, f = _p2_line_loads(0.01, 1.0, lambda s: np.full_like(s, 2.5e-4))
    assert averaged_peak_pressure(f, x, ell) == pytest.approx(2.5e-4, rel=1e-9)
    hertz = lambda s: 5e-4 * np.sqrt(np.clip(1 - s ** 2, 0, None))  # noqa: E731
    s = np.linspace(-ell, ell, 200001)
    exact = np.trapezoid(hertz(s) * np.cos(0.5 * np.pi * s / ell) ** 2, s) / ell
    errors = []
    for h in (0.01, 0.005):
        x, f = _p2_line_loads(h, 1.0, hertz)
        errors.append(abs(averaged_peak_pressure(f, x, ell) / exact - 1))
    assert errors[0] < 1e-6 and errors[1] < errors[0] / 4
    g = np.arange(-0.5, 0.5 + 1e-12, 0.01)
    X, Y = np.meshgrid(g, g)
    pts = np.column_stack([X.ravel(), Y.ravel(), np.zeros(X.size)])
    assert averaged_peak_pressure(np.full(len(pts), 2.5e-4 * 0.01 ** 2), pts, ell) == pytest.approx(2.5e-4, rel=1e-4)
    assert averaged_peak_pressure(np.zeros(3), np.zeros((3, 2)), ell) == 0.0
