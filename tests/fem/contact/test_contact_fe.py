"""Contact on the P2 finite-element solver: Hertz cylinder on a plane-strain half-plane, Hertz
sphere on a quarter block, condensed answers against a full re-solve, receptor strains."""
import math

import numpy as np
import pytest

from fem.contact.indentors import make_indentor
from fem.contact.linear import ContactModel
from fem.core.model import Model
from fem.verify.closed_forms import box, fine_then_growing, hertz_cylinder, hertz_sphere
from tests.helpers import quarter_block


def half_plane(nu, fine_mm=0.02, size_mm=40.0):
    """Half of a plane-strain block (x >= 0 symmetric, y <= 0, bottom fixed), E = 1 MPa."""
    xs = fine_then_growing(fine_mm, 1.3, 1.25, size_mm / 2)
    ys = -fine_then_growing(fine_mm, 0.6, 1.2, size_mm / 2)[::-1]
    p, cells, r = box(xs, ys)
    model = Model(p, cells, np.ones(len(cells), int), {"top": r["ymax"], "bottom": r["ymin"], "sym": r["xmin"]},
                  material=[1.0], nu=nu)
    return model, model.system({"bottom": 0.0, "sym": (0.0, None)})


@pytest.mark.parametrize("nu", [0.3, 0.49])
def test_hertz_cylinder_on_half_plane(nu):
    """Force control: contact half-width and peak pressure within 3 % of Hertz (b = 0.3-1 mm)."""
    model, system = half_plane(nu)
    cm = ContactModel.from_fe(model, system, "top")
    sn = model.surface_nodes("top")
    np.testing.assert_allclose(np.bincount(cm.facets[0].ravel(), cm.facets[1].ravel()), sn.area)
    cyl = make_indentor("cylinder:10", orientation="parallel")          # R = 5 mm, axis along z
    Es = 1.0 / (1 - nu * nu)
    for b in [0.3, 0.5, 0.75, 1.0]:
        P = b * b * math.pi * Es / 20.0                                    # N/mm for half-width b
        res = cm.indent(cyl, force_N=P / 2)                                 # half model
        b_ref, p0 = hertz_cylinder(5.0, P, 1.0, nu)
        assert res.kkt["ok"], res.kkt
        assert abs(res.total_force_N / (P / 2) - 1) < 1e-5
        assert abs(res.contact_area_mm2 / b_ref - 1) < 0.03, (b, res.contact_area_mm2, b_ref)
        assert abs(res.max_pressure_MPa / p0 - 1) < 0.03, (b, res.max_pressure_MPa, p0)


def test_condensed_matches_full_resolve_and_receptor_strains():
    """The cached compliance predicts the deflection and strains that one full solve with the
    contact forces gives; active nodes touch, inactive ones do not penetrate."""
    model, system = half_plane(0.48, fine_mm=0.05, size_mm=20.0)
    receptors = np.column_stack([np.linspace(0.0, 2.0, 9), np.full(9, -0.75)])
    S = model.strain_operator(receptors)
    cm = ContactModel.from_fe(model, system, "top", observe=S)
    sn = model.surface_nodes("top")
    bar = make_indentor("grating:0.5:0.5,1.0", orientation="parallel", position_mm=(-0.3, 0.0))
    offsets = [[0.0, 0, 0], [0.2, 0, 0], [0.4, 0, 0]]
    for off, res in zip(offsets, cm.sweep(bar, offsets, depth_mm=0.5)):
        u = cm.compliance(bar.approach).displacement(res.force_N)
        w = -u[sn.dofs[:, 1]]                                              # along the approach -y
        scale = np.abs(w).max()
        assert np.abs(w - res.deflection_mm).max() < 1e-9 * scale
        gap = bar.shifted(off).gap(sn.x, res.travel_mm[0]) + w
        finite = np.isfinite(gap)
        assert gap[finite].min() > -1e-8 and np.abs(gap[res.active]).max() < 1e-8
        strain = S @ u
        assert np.abs(strain - res.observed).max() < 1e-9 * np.abs(strain).max()
        assert res.active.sum() > 5 and res.kkt["ok"]


@pytest.mark.parametrize("dim, incline", [(2, 0.0), (3, 0.0), (3, 30.0)])
def test_condensed_compliance_equals_lazy_columns(dim, incline):
    """A system factorised with the candidates condensed along the approach (rotated DOFs for the
    30 deg inclined approach) gives the same indentation (forces, deflections, receptor strains)
    as lazily solved columns, with no column solves; another approach falls back to lazy columns."""
    if dim == 2:
        model, _ = half_plane(0.48, fine_mm=0.05, size_mm=20.0)
        prescribed, ind = {"bottom": 0.0, "sym": (0.0, None)}, make_indentor("C2", orientation="parallel")
    elif incline == 0:
        model, prescribed = quarter_block(0.48, 0.25, 4.0)
        ind = make_indentor("sphere:5")
    else:            # no symmetry planes: rotated DOFs need nodes held in all or no directions
        xs = fine_then_growing(0.3, 0.6, 1.6, 3.0)
        xs = np.r_[-xs[:0:-1], xs]
        p, cells, r = box(xs, -fine_then_growing(0.3, 0.6, 1.5, 3.0)[::-1], xs)
        model = Model(p, cells, np.ones(len(cells), int), {"top": r["ymax"], "bottom": r["ymin"]},
                      material=[1.0], nu=0.48)
        prescribed, ind = {"bottom": 0.0}, make_indentor("sphere:5", incline_deg=incline)
    sn = model.surface_nodes("top")
    receptors = model.strain_operator(sn.x[:7] - [0.0, 0.75, 0.0][:dim])
    lazy = ContactModel.from_fe(model, model.system(prescribed), "top", observe=receptors)
    a = lazy.indent(ind, depth_mm=0.2)
    system = model.system(prescribed, condense=(sn.nodes, ind.approach))
    condensed = ContactModel.from_fe(model, system, "top", observe=receptors)
    b = condensed.indent(ind, depth_mm=0.2)
    assert type(condensed.compliance(ind.approach)).__name__ == "CondensedCompliance"
    assert a.active.sum() > 3 and np.array_equal(a.active, b.active)
    for x, y in [(a.force_N, b.force_N), (a.deflection_mm, b.deflection_mm), (a.observed, b.observed)]:
        assert np.abs(x - y).max() < 1e-9 * np.abs(x).max()
    if dim == 3:
        other = make_indentor("sphere:5", incline_deg=incline + 10.0)
        assert type(condensed.compliance(other.approach)).__name__ == "FactorCompliance"


def test_receptor_grid_measures_match_solver_sampling():
    """Receptor measures from the cached operator equal the solver's own sampling of the full field."""
    from fem.receptors.grid import ReceptorSampler, receptor_grid

    model, system = half_plane(0.48, fine_mm=0.05, size_mm=20.0)
    sn = model.surface_nodes("top")
    grid = receptor_grid(sn.x, sn.normal, depths_mm=(0.5, 1.0), spacing_mm=0.5)
    fine = grid.sites_mm[:, 0] < 1.3                      # uniform 0.05 mm nodes there
    np.testing.assert_allclose(np.sort(grid.sites_mm[fine, 0]), [0.0, 0.5, 1.0])     # cells centred on x = 0
    np.testing.assert_allclose(grid.points_mm[:, 1], -grid.depth_mm, atol=1e-12)
    sampler = ReceptorSampler(model, grid)
    cm = ContactModel.from_fe(model, system, "top", observe=sampler.operator)
    res = cm.indent(make_indentor("C2", orientation="parallel"), depth_mm=0.4)
    sol = model.solution(cm.compliance(np.array([0.0, -1, 0])).displacement(res.force_N))
    got = sampler.measures(res.observed, ["sed_MPa", "max_compressive_strain", "stress_xy_MPa"])
    for name, values in got.items():
        ref = sol.sample(name, grid.points_mm)
        assert np.abs(values - ref).max() <= 1e-9 * np.abs(ref).max(), name
    assert got["sed_MPa"].max() > 0


def test_hertz_sphere_on_quarter_block():
    """Rigid sphere R = 5 mm, 0.1 mm deep, nu = 0.49, on an 8 mm quarter block (P2, 0.125 mm under
    the contact): 3D P2 facets, symmetry planes. Contact radius and peak pressure against Hertz at
    the computed force (local quantities) within 3 %. The force at the given depth is above Hertz
    (+6.7 % here) because the fixed bottom at 8 mm makes the nearly incompressible block stiffer
    than a half-space; on a 40 mm block the force is within 0.6 % of Hertz
    (`benchmarks/contact_bench.py hertz`, docs/verification.md)."""
    nu = 0.49
    model, held = quarter_block(nu, 0.125, 8.0)
    system = model.system(held)
    cm = ContactModel.from_fe(model, system, "top")
    res = cm.indent(make_indentor("sphere:5"), depth_mm=0.1)
    F = 4 * res.total_force_N                                       # quarter model
    a_of_F = (3 * F * 5.0 / (4 / (1 - nu * nu))) ** (1 / 3)
    assert res.kkt["ok"], res.kkt
    assert abs(math.sqrt(4 * res.contact_area_mm2 / math.pi) / a_of_F - 1) < 0.03
    assert abs(res.max_pressure_MPa / (3 * F / (2 * math.pi * a_of_F ** 2)) - 1) < 0.03
    assert 0 < F / hertz_sphere(5.0, 0.1, 1.0, nu)[0] - 1 < 0.1     # stiffer than the half-space


@pytest.mark.parametrize("dim", [2, 3])
def test_condensing_only_the_reach_gives_the_full_answer(dim):
    """A system condensed on the candidates an indentation can reach (fem.contact.linear.reach) gives the
    same forces, deflections and gaps on every candidate (those outside the reach come with the
    observation solve) and receptor strains as one condensed on all candidates; an indentor beyond
    the reach is refused with a one-line error."""
    from fem.contact.linear import reach
    from fingertip.errors import InputError

    if dim == 2:
        model, _ = half_plane(0.48, fine_mm=0.05, size_mm=20.0)
        prescribed, ind = {"bottom": 0.0, "sym": (0.0, None)}, make_indentor("C2", orientation="parallel")
    else:
        model, prescribed = quarter_block(0.48, 0.25, 4.0)
        ind = make_indentor("sphere:5")
    sn = model.surface_nodes("top")
    depths = [0.1, 0.2, 0.3]
    near = reach(sn.x, ind, np.zeros((1, 3)), max(depths))
    assert 3 < near.sum() < 0.8 * len(near)
    receptors = model.strain_operator(sn.x[:7] - [0.0, 0.75, 0.0][:dim])
    part = ContactModel.from_fe(model, model.system(prescribed, condense=(sn.nodes[near], ind.approach)), "top",
                                observe=receptors)           # first: a cached superset would be reused
    full = ContactModel.from_fe(model, model.system(prescribed, condense=(sn.nodes, ind.approach)), "top",
                                observe=receptors)
    assert not part.compliance(ind.approach).reach.all()
    parts = part.indent_depths(ind, depths)
    assert all(b._unseen is not None for b in parts)         # outside the reach: not known yet
    for a, b in zip(full.indent_depths(ind, depths), parts):
        assert np.array_equal(a.active, b.active) and not b.active[~near].any()
        for x, y in [(a.force_N, b.force_N), (a.deflection_mm, b.deflection_mm), (a.observed, b.observed)]:
            assert np.abs(x - y).max() < 1e-9 * np.abs(x).max()
        finite = np.isfinite(a.gap_mm)
        assert np.array_equal(finite, np.isfinite(b.gap_mm))
        assert np.abs(a.gap_mm[finite] - b.gap_mm[finite]).max() < 1e-9
    wide = make_indentor("C8" if dim == 2 else "sphere:20")
    with pytest.raises(InputError, match="outside the candidates condensed"):
        part.indent(wide, depth_mm=0.6)
