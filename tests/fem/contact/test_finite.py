"""Large-deformation frictionless contact (fem.contact.finite) on the coarse five-layer monkey
section: the linear solver's force at a small depth, work equal to stored energy, the constraint
to the linear solver's tolerance, and what it refuses."""
import json
import re

import numpy as np
import pytest
from scipy.integrate import simpson

import pipeline
from fem.contact.finite import FiniteContact
from fem.contact.indentors import make_indentor
from fem.contact.linear import GAP_TOL_MM, ContactModel
from fem.experiments.runner import placement
from fem.experiments.scene import Experiment, Receptors
from fem.io.modelfolder import (
    CONTACT_REGION,
    factorise,
    held_regions,
    read_model,
    receptor_surface,
)
from fem.io.runfolder import stored_energy_Nmm
from fem.receptors.grid import ReceptorSampler, receptor_grid
from fem.verify.energy import indentation_work_Nmm
from fingertip.errors import InputError
from tests.helpers import csv_rows, quarter_block

DEPTHS_MM = np.linspace(0.0, 0.4, 9)[1:]


@pytest.fixture(scope="module")
def c5_course(section):
    """The C5 cylinder pressed 0.05 ... 0.4 mm into the section (m43338), finite and linear."""
    model, info = read_model(section, "m43338")
    ind = make_indentor("C5")
    fc = FiniteContact(model, CONTACT_REGION[2], held_regions(model))
    finite = fc.indent(ind, DEPTHS_MM)
    cm = ContactModel.from_fe(model, factorise(model, info), CONTACT_REGION[2])
    linear = [cm.indent(ind, depth_mm=d) for d in DEPTHS_MM]
    return fc, finite, linear


def test_small_depth_is_the_linear_solution_and_deep_is_stiffer(c5_course):
    """At 0.05 mm (1 % of the cylinder's radius) the finite force is the linear one within 1 %
    (measured +0.39 %; +0.02 % at 0.02 mm); at 0.4 mm it is 5-15 % stiffer (measured +9.8 %), and
    the ratio grows with depth."""
    _, finite, linear = c5_course
    ratio = np.array([r.force_N for r in finite]) / np.array([r.total_force_N for r in linear])
    assert abs(ratio[0] - 1) < 1e-2
    assert 1.05 < ratio[-1] < 1.15 and np.all(np.diff(ratio) > 0)


def test_the_small_depth_limit_is_linear_elasticity_under_its_own_contact_forces(shop):
    """3D, the 1 mm monkey, C5 to 0.0015 mm (0.1 % of the skin): one candidate touches, 0.3 mm beside
    the cylinder's lowest line, where the indentor's normal leans 3.6 degrees from the approach.
    The linear solver under the finite contact forces along those normals (`contact_loads`) gives
    the finite deflection there within 1e-3 (measured 1.3e-4) and the finite receptor SED within
    2e-3 of its peak (5.0e-4). The same forces along the approach, the linear contact solver's
    direction, change the SED by more than 2 % of its peak (measured 4.2 %): this mesh's small-depth
    differences between the kinematics come from that direction, not from the finite solver."""
    folder = shop.preset("monkey")
    model, info = read_model(folder)
    sn = model.surface_nodes(CONTACT_REGION[3])
    ind = make_indentor("C5", **placement(Experiment.from_dict({"indentor": "C5", "depth_mm": 0.0015}), model, info, sn)[0])
    a = ind.approach
    fc = FiniteContact(model, CONTACT_REGION[3], held_regions(model))
    (r,) = fc.indent(ind, [0.0015])
    active = np.flatnonzero(r.contact_force_N > 0)
    assert len(active) == 1 and abs(r.normal[active[0]] @ a) < 0.999       # a leaning normal
    rc = Receptors()
    sampler = ReceptorSampler(model, receptor_grid(*receptor_surface(model, sn), np.asarray(rc.depths_mm, float),
                                                   rc.spacing_mm))
    sed = sampler.with_energy().measures(fc.observe(r.u, sampler), ["sed_MPa"])["sed_MPa"]
    system = model.system(held_regions(model))
    for along, tol in ((None, 2e-3), (a, None)):
        u = system.solve(fc.contact_loads(r, along))
        linear = sampler.measures(sampler.operator @ u, ["sed_MPa"])["sed_MPa"]
        off = np.abs(sed - linear).max() / linear.max()
        if tol is None:
            assert off > 0.02
            continue
        assert off < tol
        j = fc.dofs[active[0]]
        assert r.u[j] @ a == pytest.approx(u[j] @ a, rel=1e-3)


def test_work_equals_stored_energy_and_the_constraint_holds(c5_course):
    """Frictionless quasi-static contact stores the indentor's work: the integral of force over
    depth (Simpson on the 8 depths and 0) equals the stored energy at 0.4 mm within 0.5 %
    (measured 0.04 %), and at every later depth within 1 % (`indentation_work_Nmm`, measured at
    most 0.2 %); at the first, 0.05 mm, within 2 % (measured 1.16 %; linear 0.6 %: the integral over
    [0, 0.05 mm] rests on a power law through the first two depths, the quadrature's error); no
    candidate penetrates beyond GAP_TOL_MM, no contact force is tensile, and the nodes that carry
    force touch."""
    _, finite, _ = c5_course
    force = [r.force_N for r in finite]
    work = simpson(np.r_[0.0, force], x=np.r_[0.0, DEPTHS_MM])
    assert abs(work / finite[-1].energy_Nmm - 1) < 5e-3
    balance = indentation_work_Nmm(DEPTHS_MM, force) / [r.energy_Nmm for r in finite] - 1
    assert abs(balance[0]) < 2e-2 and np.abs(balance[1:]).max() < 1e-2
    for r in finite:
        assert r.penetration_mm <= GAP_TOL_MM and r.contact_force_N.min() >= 0
        assert np.abs(r.gap_mm[r.contact_force_N > 0]).max() <= GAP_TOL_MM
        assert r.min_J > 0.5


def test_linear_contact_stores_its_work_too(c5_course):
    """The linear solver's stored energy f . w / 2 (`fem.io.runfolder.stored_energy_Nmm`, the step
    table's energy_Nmm) equals the integral of its force over depth within 0.5 % (measured
    +0.012 %): node-to-surface contact on the undeformed surface is frictionless and conservative."""
    linear = c5_course[2]
    force = [r.total_force_N for r in linear]
    work = simpson(np.r_[0.0, force], x=np.r_[0.0, DEPTHS_MM])
    assert abs(work / stored_energy_Nmm(linear[-1]) - 1) < 5e-3
    balance = indentation_work_Nmm(DEPTHS_MM, force) / [stored_energy_Nmm(r) for r in linear] - 1
    assert abs(balance[0]) < 2e-2 and np.abs(balance[1:]).max() < 1e-2


def test_refuses_what_it_cannot_model(c5_course):
    fc = c5_course[0]
    for code in ("wedge", "cone", "ellipsoid:1,2,3", "two-point:3"):
        with pytest.raises(InputError, match="finite kinematics"):
            fc.indent(make_indentor(code), [0.1])
    with pytest.raises(InputError, match="increasing"):
        fc.indent(make_indentor("C5"), [0.2, 0.1])


def test_indent_with_finite_kinematics(section, tmp_path, capsys):
    """`indent --kinematics finite`: the step table carries the finite forces and stored energy, the
    receptor table measures of the finite state that equal the linear run's at 0.02 mm (within 2 %
    of the largest value at every receptor point; measured 1.1 %; at the most strained point SED
    +0.2 %, compressive strain +0.02 %, stress_yy +0.07 %), run.json names the
    kinematics; under force control it finds the depth whose force it is (0.3 mm to 1e-5 mm); what
    it does not run yet ends in one error line, exit 2, nothing written."""
    common = ["indent", str(section), "--indentor", "C5", "--material", "m43338", "--quiet", "--no-plots"]
    runs = {}
    for kin in ("finite", "linear"):
        out = tmp_path / kin
        assert pipeline.main(common + ["--depth", "0.02,0.3", "--kinematics", kin, "--out", str(out)]) == 0
        runs[kin] = out
    steps = {k: csv_rows(v / "C5.csv") for k, v in runs.items()}
    recs = {k: csv_rows(v / "C5_receptors.csv") for k, v in runs.items()}
    model, _ = read_model(section, "m43338")
    direct = FiniteContact(model, CONTACT_REGION[2], held_regions(model)).indent(make_indentor("C5"), [0.02, 0.3])
    for row, r in zip(steps["finite"], direct):
        assert float(row["force_N"]) == pytest.approx(r.force_N, rel=1e-9)
        assert float(row["energy_Nmm"]) == pytest.approx(r.energy_Nmm, rel=1e-9) and row["kkt_ok"] == "True"
    for name in ("sed_MPa", "max_compressive_strain"):
        fin = np.array([float(r[name]) for r in recs["finite"] if r["step"] == "0"])
        lin = np.array([float(r[name]) for r in recs["linear"] if r["step"] == "0"])
        assert np.abs(fin - lin).max() <= 0.02 * np.abs(lin).max()
    assert json.loads((runs["finite"] / "run.json").read_text())["kinematics"]["name"] == "finite"
    assert not list(runs["finite"].glob("*.vtu"))
    by_force = tmp_path / "force"                   # force control: the depth whose force it is
    assert pipeline.main(common + ["--force", steps["finite"][1]["force_N"], "--kinematics", "finite",
                                   "--out", str(by_force)]) == 0
    row = csv_rows(by_force / "C5.csv")[0]
    assert float(row["force_N"]) == pytest.approx(float(steps["finite"][1]["force_N"]), rel=1e-6)
    assert float(row["depth_mm"]) == pytest.approx(0.3, abs=1e-5)
    capsys.readouterr()
    base = ["indent", str(section), "--material", "m43338", "--quiet", "--kinematics", "finite"]
    for bad in (["--indentor", "wedge", "--depth", "0.2"], ["--indentor", "ellipsoid:2,3,2", "--depth", "0.2"]):
        out = tmp_path / "refused"
        code = pipeline.main(base + bad + ["--out", str(out)])
        err = capsys.readouterr().err.strip().splitlines()
        assert code == 2 and len(err) == 1 and "kinematics = finite" in err[0] and not out.exists()


FLATS_STEPS_BARS = {"bar:2": (0.0, 1e-2), "plate": (0.0, 1e-2), "grating:1:1,2": (0.0, 1e-2),
                    "step:0": (-0.5, 1e-2), "step:2": (-0.5, 2e-2)}
"""code: (x of the placement mm, tolerance of the 0.05 mm force against the linear solver's)."""


@pytest.mark.parametrize("code", list(FLATS_STEPS_BARS))
def test_flat_step_and_grating_indentors_by_the_same_checks(section, code):
    """A 2 mm flat bar (face, sides and edges: the gap to the nearest), a 20 mm plate (its face
    covers the section's pad), a grating of three 1 mm bars (the nearest bar's gap), a sharp step
    (step 0: its face and edge, and the level 0.5 mm behind) and a smooth one (step 2: the closest
    point of its profile) on the section, 0.05-0.2 mm: the linear force at 0.05 mm (measured +0.7 %
    bar, plate and grating, -0.55 % step 0, -1.07 % step 2: on the ramp, sloped up to 33 deg, the
    linear solver measures the gap and pushes along the approach, the finite one along the
    normal, a difference of -1.0 % already at 0.005 mm, hence 2 % there); work = stored energy
    within 0.5 % (measured 0.01-0.11 %); the constraint to GAP_TOL_MM."""
    x_mm, tol = FLATS_STEPS_BARS[code]
    model, info = read_model(section, "m43338")
    ind = make_indentor(code, position_mm=(x_mm, 0.0))
    depths = np.linspace(0.0, 0.2, 5)[1:]
    finite = FiniteContact(model, CONTACT_REGION[2], held_regions(model)).indent(ind, depths)
    linear = ContactModel.from_fe(model, factorise(model, info), CONTACT_REGION[2]).indent(ind, depth_mm=0.05)
    assert abs(finite[0].force_N / linear.total_force_N - 1) < tol
    work = simpson(np.r_[0.0, [r.force_N for r in finite]], x=np.r_[0.0, depths])
    assert abs(work / finite[-1].energy_Nmm - 1) < 5e-3
    assert max(r.penetration_mm for r in finite) <= GAP_TOL_MM


def test_two_point_presses_with_both_tips(section):
    """Two spheres 1 mm in radius 3 mm apart: at 0.2 mm both carry force, the force is the sum of
    the contact forces along the approach, no candidate penetrates."""
    model, _ = read_model(section, "m43338")
    ind = make_indentor("two-point:3:1")
    res = FiniteContact(model, CONTACT_REGION[2], held_regions(model)).indent(ind, [0.1, 0.2])[-1]
    x = model.surface_nodes(CONTACT_REGION[2]).x[:, 0]
    pressed = res.contact_force_N > 0
    assert np.any(pressed & (x < -1.0)) and np.any(pressed & (x > 1.0)) and not np.any(pressed & (np.abs(x) < 0.5))
    assert res.force_N == pytest.approx(float(res.contact_force_N @ (res.normal @ ind.approach)), rel=1e-12)
    assert res.penetration_mm <= GAP_TOL_MM


def test_sweep_moves_the_contact_with_the_indentor(section, tmp_path):
    """A finite sweep indents each position from rest: its middle position is the unswept run to
    the last digit, and at 0.2 mm (near the linear range) the centre of the contact forces is the
    linear sweep's at every offset, within a node spacing (0.125 mm on the 0.25 mm section's pad;
    on the curved pad it is not under the cylinder's axis: measured 0.36 mm from it at 0.5 mm)."""
    common = ["indent", str(section), "--material", "m43338", "--indentor", "C5", "--depth", "0.2",
              "--no-plots", "--quiet"]
    swept, single, linear = tmp_path / "swept", tmp_path / "single", tmp_path / "linear"
    assert pipeline.main(common + ["--kinematics", "finite", "--sweep", "x=-0.5:0.5:0.5", "--out", str(swept)]) == 0
    assert pipeline.main(common + ["--kinematics", "finite", "--out", str(single)]) == 0
    assert pipeline.main(common + ["--sweep", "x=-0.5:0.5:0.5", "--out", str(linear)]) == 0
    rows = csv_rows(swept / "C5.csv")
    assert [float(r["offset_x_mm"]) for r in rows] == [-0.5, 0.0, 0.5]
    assert rows[1]["force_N"] == csv_rows(single / "C5.csv")[0]["force_N"]
    def centres(run):
        surface = csv_rows(run / "C5_surface.csv")
        out = []
        for step in range(3):
            at = [r for r in surface if r["step"] == str(step)]
            f = np.array([float(r["force_N"]) for r in at])
            out.append(f @ np.array([float(r["x_mm"]) for r in at]) / f.sum())
        return np.array(out)
    finite, lin = centres(swept), centres(linear)
    assert np.abs(finite - lin).max() < 0.125 and finite[0] < finite[1] < finite[2]


def test_time_course_reads_one_increasing_series(section, tmp_path):
    """A finite ramp-and-hold solves its distinct depths once, in order: the hold repeats the end of
    the ramp, the release passes the ramp's states backwards (no memory of the path), and the full
    depth's force is the single indentation's to Newton's tolerance."""
    scene = tmp_path / "rh.toml"
    scene.write_text('kinematics = "finite"\nmaterial = "m43338"\n[output]\nplots = false\n[[experiment]]\n'
                     'name = "rh"\nindentor = "C5"\ndepth_mm = 0.3\n[experiment.trace]\nshape = "ramp_hold"\n'
                     'ramp_s = 0.1\nhold_s = 0.05\nsamples = 12\n')
    assert pipeline.main(["indent", str(section), "--scene", str(scene), "--out", str(tmp_path / "rh"), "--quiet"]) == 0
    rows = csv_rows(tmp_path / "rh" / "rh.csv")
    depth = np.array([float(r["depth_mm"]) for r in rows])
    force = np.array([float(r["force_N"]) for r in rows])
    held = depth == depth.max()
    ramp = np.arange(len(rows)) < np.argmax(held)
    assert held.sum() >= 2 and np.ptp(force[held]) == 0 and np.all(np.diff(force[ramp]) > 0)
    for d, f in zip(depth[~held & ~ramp], force[~held & ~ramp]):
        if np.any(depth[ramp] == d):
            assert f == force[ramp][depth[ramp] == d][0]
    model, _ = read_model(section, "m43338")
    single = FiniteContact(model, CONTACT_REGION[2], held_regions(model)).indent(make_indentor("C5"), [0.3])[0]
    assert force[held][0] == pytest.approx(single.force_N, rel=1e-6)


def test_pvd_holds_the_deformed_state(section, tmp_path):
    """--pvd under finite kinematics: each VTU's points are the deformed geometry (rest + the
    displacement it holds), and its cell SED (the finite stored energy per reference volume at
    the centroids) summed over the reference areas is the step's stored energy within 6 % (measured
    -4.3 % at 0.2 mm and -3.5 % at 0.4 mm on this coarse mesh: one point per triangle for a field
    concentrated under the contact)."""
    import meshio
    out = tmp_path / "pvd"
    assert pipeline.main(["indent", str(section), "--material", "m43338", "--indentor", "C5", "--depth", "0.2,0.4",
                          "--kinematics", "finite", "--pvd", "--no-plots", "--quiet", "--out", str(out)]) == 0
    steps = csv_rows(out / "C5.csv")
    model, _ = read_model(section, "m43338")
    rest = np.zeros((model.nnodes, 3))
    rest[:, :2] = model.nodes
    corners = model.nodes[model.element_nodes[:3]]                   # (3, M, 2) triangle vertices
    area = 0.5 * np.abs(np.cross(corners[1] - corners[0], corners[2] - corners[0]))
    for k, row in enumerate(steps):
        mesh = meshio.read(out / f"C5_{k:03d}.vtu")
        np.testing.assert_allclose(mesh.points, rest + mesh.point_data["displacement_mm"], atol=1e-12)
        assert np.abs(mesh.point_data["displacement_mm"]).max() >= float(row["depth_mm"]) * 0.9
        energy = float(mesh.cell_data["sed_MPa"][0] @ area)
        assert energy == pytest.approx(float(row["energy_Nmm"]), rel=0.06)


def test_plate_gap_is_the_signed_distance_to_its_box():
    """A plate's gap is the signed distance to the semi-infinite box behind its face (outside: the
    length of the positive part of (|u| - L/2, |v| - W/2, ahead); inside: the largest of them), its
    normal that distance's gradient (central differences, 1e-6 mm)."""
    from fem.contact.surfaces import RigidSurface
    ind = make_indentor("plate:4", orientation=30.0, approach=[0.2, -1.0, 0.1])
    surf = RigidSurface(ind)
    rng = np.random.default_rng(1)
    x = surf.tip + rng.uniform(-4, 4, (400, 3))

    def sdf(y):
        rel = y - surf.tip
        d = np.stack([np.abs(rel @ ind.e1) - 2.0, np.abs(rel @ ind.e2) - 2.0, rel @ ind.approach], axis=1)
        return np.where(d.max(axis=1) > 0, np.linalg.norm(np.maximum(d, 0), axis=1), d.max(axis=1))
    g, n, *_ = surf.distance(x, 0.0)
    np.testing.assert_allclose(g, sdf(x), atol=1e-12)
    h = 1e-6
    grad = np.stack([(sdf(x + h * e) - sdf(x - h * e)) / (2 * h) for e in np.eye(3)], axis=1)
    np.testing.assert_allclose(n, grad, atol=1e-5)


@pytest.mark.parametrize("code", ["C5", "sphere:3", "bar:2", "plate:4", "punch:3", "step:0", "step:2"])
def test_curvature_is_the_hessian_of_the_gap(code):
    """The geometric stiffness of finite contact is the gap's Hessian: the derivative of the normal
    (central differences, 1e-6 mm) equals k (I - n n^T - t t^T) with the curvature k and straight
    direction t the surface returns (a cylinder's axis, a bar's edge line, a punch's rim tangent, up
    to the rim's own curvature, at most 1 / radius), at points outside the solid in any
    placement. Before t (I - n n^T alone) a cylinder across the 1 mm monkey converged linearly from
    0.7 mm and not at all at 1 mm."""
    from fem.contact.surfaces import RigidSurface
    ind = make_indentor(code, orientation=25.0, approach=[0.1, -1.0, 0.2])
    surf = RigidSurface(ind)
    x = surf.tip + np.random.default_rng(3).uniform(-3, 3, (500, 3))
    g, n, k, t = surf.distance(x, 0.3)
    h = 1e-6
    plus, minus = (np.stack([surf.distance(x + s * h * e, 0.3)[1] for e in np.eye(3)], axis=2) for s in (1, -1))
    dn = (plus - minus) / (2 * h)                                       # (n, 3, 3): d n_i / d x_j
    hess = k[:, None, None] * (np.eye(3) - n[:, :, None] * n[:, None, :] - t[:, :, None] * t[:, None, :])
    # away from the pieces' seams (where the nearest piece changes, the normal jumps)
    smooth = np.abs(plus - n[:, :, None]).max(axis=(1, 2)) < 1e-4
    ok = (g > 0.05) & smooth
    assert ok.sum() > 100
    atol = 1.0 / 1.5 if code.startswith("punch") else 1e-4            # the rim's own curvature
    np.testing.assert_allclose(hess[ok], dn[ok], atol=atol)


def _profile_boundary(code) -> np.ndarray:
    """(k, 2) points 1e-3 mm apart along the boundary of an extruded indentor's profile in its
    (v, ahead) plane: a step's surface at -h(v) (its sharp edge a vertical segment), a grating's
    bar faces and sides (to 10 mm behind them)."""
    shape = make_indentor(code).parts[0]
    if code.startswith("step"):
        v = np.arange(-8.0, 8.0, 1e-3)
        pts = [np.column_stack([v, -shape.height(0 * v, v)[0]])]
        if shape.half_wavelength_mm == 0:
            w = np.linspace(-shape.height_mm, 0.0, 501)
            pts.append(np.column_stack([0 * w, w]))
        return np.vstack(pts)
    pts = []
    for lo, hi in shape.bar_edges_mm():
        v, w = np.linspace(lo, hi, 1001), np.linspace(-10.0, 0.0, 10001)
        pts += [np.column_stack([v, 0 * v]), np.column_stack([0 * w + lo, w]), np.column_stack([0 * w + hi, w])]
    return np.vstack(pts)


def test_contact_curvature_is_added_into_the_tangents_own_entries():
    """`FiniteContact._bent` adds -lambda k (I - n n^T - t t^T) on the active nodes' DOF blocks into
    the tangent's stored entries: the same matrix as adding it as a sparse matrix, on the same
    pattern (so one PARDISO analysis serves every tangent of a run)."""
    import scipy.sparse as sp
    model, held = quarter_block(0.48, 0.4, 4.0, E_MPa=0.01)
    fc = FiniteContact(model, "top", held)
    _, K, _ = fc.nh.tangent(np.zeros(model.ndof))
    rng = np.random.default_rng(3)
    m = len(fc.dofs)
    act = np.sort(rng.choice(m, 7, replace=False))
    lam, curv = rng.uniform(0.0, 1.0, m), rng.uniform(0.1, 1.0, m)
    lam[act[0]], curv[act[1]] = 0.0, 0.0                          # neither bends
    n = rng.standard_normal((m, 3))
    n /= np.linalg.norm(n, axis=1)[:, None]
    t = np.cross(n, rng.standard_normal((m, 3)))
    t /= np.linalg.norm(t, axis=1)[:, None]
    t[act[2]] = 0.0                                                 # a sphere: no straight direction
    expected = K.toarray()
    for i in act[2:]:
        d = fc.dofs[i]
        expected[np.ix_(d, d)] -= lam[i] * curv[i] * (np.eye(3) - np.outer(n[i], n[i]) - np.outer(t[i], t[i]))
    indices = K.indices.copy()
    bent = fc._bent(K, act, lam, n, curv, t)
    assert sp.issparse(bent) and np.array_equal(bent.indices, indices)
    np.testing.assert_allclose(bent.toarray(), expected, rtol=0, atol=1e-15 * np.abs(expected).max())


@pytest.mark.parametrize("code", ["step:2", "step:0", "grating:1:1,2"])
def test_step_and_grating_gaps_are_distances_to_their_profile(code):
    """Outside the solid (gap > 0.05 mm) a step's and a grating's gap is the distance to their
    profile (brute force over its boundary sampled every 1e-3 mm: error below 3e-6 mm there) for any
    placement and approach, wherever the point lies along the length axis; the normal is the
    gap's gradient (central differences) everywhere but at the sharp step's re-entrant corner."""
    from fem.contact.surfaces import RigidSurface
    ind = make_indentor(code, orientation=20.0, approach=[0.1, -1.0, 0.2])
    surf = RigidSurface(ind)
    x = surf.tip + np.random.default_rng(2).uniform(-3, 3, (600, 3))
    g, n, *_ = surf.distance(x, 0.3)
    rel = x - (surf.tip + 0.3 * ind.approach)
    vw = np.column_stack([rel @ ind.e2, rel @ ind.approach])
    boundary = _profile_boundary(code)
    far = g > 0.05
    brute = np.array([np.sqrt(((boundary - p) ** 2).sum(axis=1)).min() for p in vw[far]])
    np.testing.assert_allclose(g[far], brute, atol=1e-5)
    h = 1e-6
    grad = np.stack([(surf.distance(x + h * e, 0.3)[0] - surf.distance(x - h * e, 0.3)[0]) / (2 * h)
                     for e in np.eye(3)], axis=1)
    np.testing.assert_allclose(n, grad, atol=1e-5)


def test_a_depth_newton_cannot_reach_ends_in_one_error_line(section, tmp_path, capsys):
    """The 1.5 mm bar on m33338 stops near 1.25 mm (1.238 mm: under its edge every cut step
    inverts an element or cycles its active set; the depth depends on the iteration's path): one
    `error:` line naming the depth reached, exit 2, no run folder."""
    out = tmp_path / "run"
    assert pipeline.main(["indent", str(section), "--indentor", "bar:1.5", "--material", "m33338", "--depth", "1.5",
                          "--kinematics", "finite", "--out", str(out), "--quiet", "--no-plots"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error:")
    assert 1.2 < float(re.search(r"stopped at depth ([0-9.]+) mm", err[0]).group(1)) < 1.3
    assert "nothing written" in err[0] and not out.exists()


def test_newton_krylov_steps_give_the_factorised_answer_with_fewer_factorisations(monkeypatch):
    """3D Newton-Krylov steps (GMRES on the last factorisation, `FiniteContact._krylov`), on
    single-precision factorisations: a 2 mm sphere 0.25 and 0.5 mm into a soft quarter block (0.4
    mm P2 under it) gives the forces and stored energies of Newton with a double-precision
    factorisation in every non-chord iteration within 1e-7 (both solve to a relative residual of
    1e-8; measured within 1.1e-9), with fewer factorisations (measured 1 against 6), and so with
    no column of K_T^-1 C^T kept between iterations. Where GMRES cannot use a single-precision
    factorisation (here: asked for 1e-14 of the residual and allowed no iteration), the tangent is
    factorised in double precision and the run ends with the same answer. One Newton-Krylov step at the last state, with the sphere
    0.05 mm further and GMRES driven to 1e-7 of the right-hand side, solves the bordered system of
    that state's tangent: its direct solve on its own factorisation within 1e-6, the constraint
    rows exactly."""
    import scipy.sparse as sp

    import fem.contact.finite as finite
    model, held = quarter_block(0.48, 0.4, 4.0, E_MPa=0.01)
    ind = make_indentor("sphere:2")
    made = []

    class Counted(finite.SaddleFactor):
        def __init__(self, *args, **kw):
            made.append(kw.get("single", False))
            super().__init__(*args, **kw)

    monkeypatch.setattr(finite, "SaddleFactor", Counted)
    borders = []

    class Spied(finite._Border):
        def __init__(self, *args):
            borders.append(args[1] is not None)                   # whole columns kept
            super().__init__(*args)

    monkeypatch.setattr(finite, "_Border", Spied)
    runs, factorisations, whole, single = {}, {}, {}, {}
    rows_only = 8 * 3 * len(FiniteContact(model, "top", held).dofs) ** 2   # every candidate's rows, few whole columns
    for krylov, budget, gmres in ((False, finite.COLUMNS_MAX_BYTES, 12), (True, 0, 12), (True, rows_only, 12),
                                  (True, finite.COLUMNS_MAX_BYTES, 0), (True, finite.COLUMNS_MAX_BYTES, 12)):
        monkeypatch.setattr(finite, "COLUMNS_MAX_BYTES", budget)     # 0: no column kept between iterations
        monkeypatch.setattr(finite, "COLUMN_BLOCK", 3 if krylov else 64)   # several blocks per solve
        monkeypatch.setattr(finite, "KRYLOV_MAX", gmres)
        monkeypatch.setattr(finite, "ETA", 3e-2 if gmres else 1e-14)    # out of single precision's reach
        fc = FiniteContact(model, "top", held)
        assert fc.krylov and fc.single                    # the 3D defaults
        fc.krylov = fc.single = krylov
        made.clear()
        borders.clear()
        runs[krylov, budget, gmres] = fc.indent(ind, [0.25, 0.5])
        factorisations[krylov, gmres], whole[budget], single[gmres] = list(made), set(borders), fc.single
    assert not single[0] and factorisations[True, 0][:2] == [True, False]     # refactorised in double
    reference = runs[False, finite.COLUMNS_MAX_BYTES, 12]
    for key in runs:
        for a, b in zip(reference, runs[key]):
            assert b.force_N == pytest.approx(a.force_N, rel=1e-7)
            assert b.energy_Nmm == pytest.approx(a.energy_Nmm, rel=1e-7)
    assert set(factorisations[True, 12]) == {True} and set(factorisations[False, 12]) == {False}
    assert len(factorisations[True, 12]) < len(factorisations[False, 12])
    assert whole[0] == {False} and False in whole[rows_only] and whole[finite.COLUMNS_MAX_BYTES] == {True}

    # one step at the last state, on the (single-precision) factorisation of the state before (fc holds it)
    r = runs[True, finite.COLUMNS_MAX_BYTES, 12][-1]
    surf = finite.RigidSurface(ind)
    travel = float(ind.standoff(fc.X).min()) + r.depth_mm
    g, n, curv, straight = surf.distance(fc._positions(r.u), travel + 0.05)
    act = np.flatnonzero(r.contact_force_N > 0)
    f, K, G = fc.nh.tangent(r.u)
    K = fc._bent(K, act, r.contact_force_N, n, curv, straight)
    C = sp.csr_matrix((n[act].ravel(), (np.repeat(np.arange(len(act)), 3), fc.dofs[act].ravel())),
                      shape=(len(act), model.ndof))[:, fc.free]
    rhs = -f[fc.free]
    monkeypatch.setattr(finite, "KRYLOV_MAX", 30)     # an aged factorisation: 20 iterations measured
    du, lam, its = fc._krylov(fc._tangent(K, G), C, rhs, g[act], act, 1e-7 * np.linalg.norm(rhs))
    assert its > 0
    fc.single = False                                 # the direct solve on a double-precision factorisation
    direct_du, direct_lam = fc._solve(K, G, C, rhs, g[act], act, 0.0)
    np.testing.assert_allclose(C @ du, -g[act], atol=1e-12)
    assert np.abs(du - direct_du).max() < 1e-6 * np.abs(direct_du).max()
    np.testing.assert_allclose(lam, direct_lam, rtol=1e-6, atol=1e-9 * np.abs(direct_lam).max())
