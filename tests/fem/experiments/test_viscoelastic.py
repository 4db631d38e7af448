"""Viscoelastic layers on a finite-element block through the scene runner (fem.experiments.viscoelastic):
the standard linear solid's relaxation, creep and ramp-and-hold against their closed forms, the fast
and slow limits against the elastic model with the instantaneous and the relaxed moduli, and the
run.json record (absent without [viscoelastic])."""
import numpy as np
import pytest

from fem.core.model import Model
from fem.experiments.runner import run_experiments
from fem.experiments.scene import Scene
from fem.io.runfolder import experiment_record, run_tables
from fem.verify.closed_forms import box, sls_creep, sls_ramp_hold, sls_relaxation

E_MPA, G_INF, TAU_S = 0.01, 0.4, 0.1
SLS = {"g": [1.0 - G_INF], "tau_s": [TAU_S]}
WIDTH_MM, HEIGHT_MM, DEPTH_MM, FORCE_N = 4.0, 4.0, 0.1, 0.001
STEP = {"shape": "table", "times_s": [0.0, 1.0], "levels": [1.0, 1.0], "samples": 41}
"""Full depth (or force) from t = 0, held 1 s: a step at the first sample."""
RECEPTORS = {"depths_mm": [1.0, 2.0], "measures": ["stress_yy_MPa", "strain_yy"]}


def plate_block(nu=0.0, E=E_MPA, cells_across=4):
    """2D plane-strain block WIDTH_MM x HEIGHT_MM of cells_across x 4 squares split in triangles,
    bottom fixed (`fixed`), top the contact region (`surface`), modulus E [MPa]. With nu = 0 a
    frictionless plate compresses it uniformly, sigma_yy = E eps_yy, whatever the fixed bottom:
    force E W d / H per mm, which P2 represents exactly."""
    p, cells, r = box(np.linspace(-WIDTH_MM / 2, WIDTH_MM / 2, cells_across + 1), np.linspace(-HEIGHT_MM, 0.0, 5))
    return Model(p, cells, np.ones(len(cells), int), {"surface": r["ymax"], "fixed": r["ymin"]},
                 material=[E], nu=nu)


def run(model, experiments, viscoelastic=SLS):
    """The SceneRun of these [[experiment]] tables on `model` (in memory), with RECEPTORS."""
    scene = {"experiment": experiments, "receptors": RECEPTORS}
    if viscoelastic is not None:
        scene["viscoelastic"] = viscoelastic
    return run_experiments(model, {}, Scene.from_dict(scene))


def named(scene_run) -> dict:
    return {e.name: e for e in scene_run.experiments}


def course(e):
    """(times s, total force N/mm, depth mm) per sample of an experiment run."""
    return (e.experiment.times_s, np.array([r.total_force_N for _, r in e.steps]),
            np.array([r.depth_mm.max() for _, r in e.steps]))


@pytest.fixture(scope="module")
def plate_runs():
    model = plate_block()
    experiments = [{"name": "relax", "indentor": "plate", "depth_mm": DEPTH_MM, "trace": STEP},
                   {"name": "creep", "indentor": "plate", "force_N": FORCE_N, "trace": STEP},
                   {"name": "ramp", "indentor": "plate", "depth_mm": DEPTH_MM,
                    "trace": {"shape": "table", "times_s": [0.0, 0.05, 0.55], "levels": [0.0, 1.0, 1.0], "samples": 56}},
                   {"name": "release", "indentor": "plate", "depth_mm": DEPTH_MM,
                    "trace": {"shape": "ramp_hold", "ramp_s": 0.05, "hold_s": 0.5, "release_s": 0.05, "samples": 61}}]
    return run(model, experiments)


def test_step_strain_relaxes_as_the_standard_linear_solid(plate_runs):
    """Force and receptor stress under a step of depth: (E W d / H) g(t) and -E (d / H) g(t) within 1 %
    (measured: 1e-15); the strain stays the elastic -d / H; the contact never shrinks."""
    e = named(plate_runs)["relax"]
    t, force, _ = course(e)
    elastic = E_MPA * WIDTH_MM * DEPTH_MM / HEIGHT_MM
    assert np.abs(force / (elastic * sls_relaxation(t, G_INF, TAU_S)) - 1).max() < 0.01
    values = run_tables(e, plate_runs)["values"]
    want = -E_MPA * DEPTH_MM / HEIGHT_MM * sls_relaxation(t, G_INF, TAU_S)[:, None]
    assert np.abs(values["stress_yy_MPa"] / want - 1).max() < 0.01
    np.testing.assert_allclose(values["strain_yy"], -DEPTH_MM / HEIGHT_MM, rtol=1e-9)
    assert e.viscoelastic["control"] == "depth" and e.viscoelastic["contact_shrinks_at_s"] is None


def test_step_stress_creeps_as_the_standard_linear_solid(plate_runs):
    """Depth under a step of force: (F H / (E W)) J(t) within 1 % (measured: 1e-15); the relaxed force
    stays the prescribed one to the sampling of the elastic course (record's force_deviation,
    0.04 % at 25 ms samples against the 0.25 s retardation time)."""
    e = named(plate_runs)["creep"]
    t, force, depth = course(e)
    want = FORCE_N * HEIGHT_MM / (E_MPA * WIDTH_MM) * sls_creep(t, G_INF, TAU_S)
    assert np.abs(depth / want - 1).max() < 0.01
    assert np.abs(force / FORCE_N - 1).max() == pytest.approx(e.viscoelastic["force_deviation"])
    assert e.viscoelastic["force_deviation"] < 0.005


def test_ramp_and_hold_relaxes_by_the_predicted_amount(plate_runs):
    """Force through a 50 ms ramp and a 0.5 s hold: the closed form (E W d / H) R(t) within 1 %
    (measured: 1e-15), which predicts a hold relaxing from R(ramp) = 0.87 to 0.40 of the elastic force."""
    t, force, _ = course(named(plate_runs)["ramp"])
    want = E_MPA * WIDTH_MM * DEPTH_MM / HEIGHT_MM * sls_ramp_hold(t, 0.05, G_INF, TAU_S)
    loaded = want > 0
    assert np.abs(force[loaded] / want[loaded] - 1).max() < 0.01 and np.all(force[~loaded] == 0)
    peak, end = force[np.argmin(np.abs(t - 0.05))], force[-1]
    assert end / peak == pytest.approx(sls_ramp_hold(0.55, 0.05, G_INF, TAU_S) / sls_ramp_hold(0.05, 0.05, G_INF, TAU_S))
    assert end / peak < 0.5


def test_release_is_the_limit_of_lee_and_radok(plate_runs):
    """Released after the hold, the plate's contact shrinks to nothing: run.json records when (the
    first sample after the hold), and the relaxed force turns tensile at the end (the method's limit:
    Ting's correction is not made)."""
    e = named(plate_runs)["release"]
    t, force, depth = course(e)
    assert e.viscoelastic["contact_shrinks_at_s"] == pytest.approx(t[np.flatnonzero(depth == 0)[-1]])
    assert force[-1] < 0 and e.viscoelastic["final_force_N"] == pytest.approx(force[-1])


def test_fast_and_slow_limits_are_the_elastic_model():
    """A 4 mm cylinder on a nearly incompressible (nu = 0.48) block (0.25 mm cells across): at the end
    of a ramp 1000 times faster than tau the force (depth control) and the depth (force control) are
    the elastic ones with the instantaneous modulus (within 0.1 %; measured 0.03 % and 0.02 %, the
    relaxation during the ramp); after a hold of 100 tau those with the relaxed modulus g_inf E
    (measured 3e-15 and 2e-7). Under force control the contact widens as the depth creeps."""
    ramp = {"shape": "table", "times_s": [0.0, TAU_S / 1000, 100 * TAU_S], "levels": [0.0, 1.0, 1.0], "samples": 200}
    cylinder = {"indentor": "cylinder:4", "orientation": "parallel"}
    ve = named(run(plate_block(0.48, cells_across=16), [{"name": "depth", **cylinder, "depth_mm": DEPTH_MM, "trace": ramp},
                                       {"name": "force", **cylinder, "force_N": FORCE_N, "trace": ramp}]))
    elastic = [{"name": "depth", **cylinder, "depth_mm": DEPTH_MM}, {"name": "force", **cylinder, "force_N": FORCE_N}]
    fast = named(run(plate_block(0.48, cells_across=16), elastic, viscoelastic=None))
    slow = named(run(plate_block(0.48, G_INF * E_MPA, cells_across=16), elastic, viscoelastic=None))
    t, force, _ = course(ve["depth"])
    top = int(np.argmin(np.abs(t - TAU_S / 1000)))
    f0, finf = fast["depth"].steps[0][1].total_force_N, slow["depth"].steps[0][1].total_force_N
    assert abs(force[top] / f0 - 1) < 0.001 and abs(force[-1] / finf - 1) < 0.001
    assert finf == pytest.approx(G_INF * f0, rel=1e-9)
    _, _, creep = course(ve["force"])
    assert abs(creep[top] / fast["force"].steps[0][1].depth_mm.max() - 1) < 0.001
    assert abs(creep[-1] / slow["force"].steps[0][1].depth_mm.max() - 1) < 0.001
    widths = [r.contact_area_mm2 for _, r in ve["force"].steps]
    assert widths[top] == fast["force"].steps[0][1].contact_area_mm2 and widths[-1] > widths[top] > 0.5
    assert ve["force"].viscoelastic["contact_shrinks_at_s"] is None


def test_run_json_records_the_law_only_when_given(plate_runs):
    """run.json's experiment entry carries "viscoelastic" (method, control, forces) only for a
    viscoelastic course; an elastic run's entry has no such key (its bytes are unchanged)."""
    assert experiment_record(named(plate_runs)["relax"])["viscoelastic"]["method"].startswith("correspondence")
    elastic = run(plate_block(), [{"name": "relax", "indentor": "plate", "depth_mm": DEPTH_MM, "trace": STEP}],
                  viscoelastic=None)
    assert "viscoelastic" not in experiment_record(elastic.experiments[0])



@pytest.mark.parametrize("scene, message", [
    ('viscoelastic = 3\n', "expected a [viscoelastic] table with the weights g"),
    ('[viscoelastic]\ntau_s = [0.1]\n', "needs the weights g"),
    ('[viscoelastic]\ng = [0.7, 0.5]\ntau_s = [0.1, 1.0]\n', "sum below 1"),
    ('[viscoelastic]\ng = [0.5]\ntau = [0.1]\n', "unknown key(s) ['tau'] in [viscoelastic]"),
    ('[viscoelastic]\ng = [0.2, 0.2, 0.2]\n', "has no time course"),
    ('[viscoelastic]\ng = [0.2, 0.2, 0.2]\n[afferents]\ninput = "sed"\n', 'only stresses relax'),
])
def test_bad_viscoelastic_scene_is_one_error_line_exit_2(tmp_path, capsys, scene, message):
    """Refused while the scene is read, before any model is opened: one `error:` line, exit 2."""
    import pipeline

    trace = "" if "time course" in message else '[experiment.trace]\nshape = "ramp_hold"\n'
    path = tmp_path / "s.toml"
    path.write_text(scene + f'[[experiment]]\nindentor = "C5"\ndepth_mm = 1.0\n{trace}')
    assert pipeline.main(["indent", str(tmp_path / "no_model"), "--scene", str(path), "--out",
                          str(tmp_path / "out"), "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error:") and message in err and "\n" not in err
    assert not (tmp_path / "out").exists()
