"""Spiking afferents driven by the finite-element finger (fem.experiments.traces, fem.receptors.afferents, fem.experiments.scene's
[afferents] and [experiment.trace]): the shipped ramp-and-hold scene end to end, and the
behaviours every afferent paper shows, on the 1 mm monkey preset (the session Workshop)."""
import dataclasses

import numpy as np
import pytest

import pipeline
from fem.experiments.runner import run_experiments
from fem.experiments.scene import Scene, load_scene
from fem.experiments.traces import course, fractions, frequency_warning
from fem.io.modelfolder import read_model
from fem.receptors.afferents import Population, experiment_inputs, pad_facets, place, respond, sampler_of
from fingertip.errors import InputError
from tests.helpers import ROOT, csv_rows

SCENE = ROOT / "scenes" / "ramp_hold.toml"


def test_ramp_hold_scene_end_to_end(shop, tmp_path):
    """The shipped scene on the monkey preset. Measured (seed 0, noise on): 45 SA1 and 89 RA
    afferents within 7 mm (the monkey pad away from its end cuts), 17 and 18 of them fire; the SA1
    with the largest input (26 kPa; the next has 8 kPa) fires through the hold; the RA give 23
    spikes in the ramp, 35 in the release, 0 in the middle of the hold."""
    out = tmp_path / "run"
    assert pipeline.main(["indent", str(shop.preset("monkey")), "--scene", str(SCENE), "--out", str(out),
                          "--quiet"]) == 0
    spikes, aff = csv_rows(out / "ramp_hold" / "spikes.csv"), csv_rows(out / "ramp_hold" / "afferents.csv")
    assert {"afferent_id", "class", "time_s", "x_mm", "z_mm", "depth_mm"} <= set(spikes[0])
    assert (out / "ramp_hold" / "raster.png").stat().st_size > 5000
    assert (out / "ramp_hold" / "rate_map.png").stat().st_size > 5000
    cls = np.array([a["class"] for a in aff])
    peak = np.array([float(a["peak_input"]) for a in aff])
    t = np.array([float(s["time_s"]) for s in spikes])
    who = np.array([int(s["afferent_id"]) for s in spikes])
    sa1, ra = np.flatnonzero(cls == "SA1"), np.flatnonzero(cls == "RA")
    assert len(ra) == pytest.approx(2 * len(sa1), abs=2)             # 140 against 70 per cm^2
    for i in sa1[np.argsort(peak[sa1])[-1:]]:                        # the most strongly pressed SA1
        mine = t[who == i]
        for t0 in np.arange(0.15, 0.6, 0.1):                         # at least a spike in every 0.1 s of the hold
            assert ((mine >= t0) & (mine < t0 + 0.1)).any(), (i, t0)
    in_ra = np.isin(who, ra)
    ramp, release = ((t < 0.12) & in_ra).sum(), ((t > 0.6) & in_ra).sum()
    mid_hold = ((t > 0.25) & (t < 0.55) & in_ra).sum()
    assert ramp > 5 and release > 5 and mid_hold <= 0.05 * ramp


@pytest.fixture(scope="module")
def monkey_line(shop):
    """(model, surface, line of pad nodes across x at the pad's middle z, sorted by x) with the
    shipped scene's material."""
    model, info = read_model(shop.preset("monkey"), load_scene(SCENE).material)
    sn = model.surface_nodes("volar")
    zmid = 0.5 * (sn.x[:, 2].min() + sn.x[:, 2].max())
    line = np.flatnonzero((np.abs(sn.x[:, 2] - zmid) < 0.3) & (np.abs(sn.x[:, 0]) < 3.5) & (sn.x[:, 1] > 0))
    return model, info, sn, line[np.argsort(sn.x[line, 0])], zmid


def _line_population(sn, line) -> Population:
    """An SA1 (0.3 mm deep) and an RA (1.6 mm deep) afferent below every node of the line, model 0."""
    k = len(line)
    both = np.r_[line, line]
    return Population(np.array(["SA1"] * k + ["RA"] * k, dtype=object), np.zeros(2 * k, int), both, sn.x[both],
                      sn.normal[both], np.r_[np.full(k, 0.3), np.full(k, 1.6)])


def _drive(monkey_line, experiment: dict, population, zmid_position: float | None = None):
    """PopulationResponse of a population to one traced experiment on the monkey (noise off);
    zmid_position: x of the indentor at the pad's middle z (default: the scene's default place)."""
    model, info, _, _, zmid = monkey_line
    if zmid_position is not None:
        experiment = {**experiment, "position_mm": [zmid_position, zmid]}
    run = run_experiments(model, info, Scene.from_dict({"experiment": [experiment]}))
    e = run.experiments[0]
    static, deflection = experiment_inputs(sampler_of(model, population), population, run.contact, e)
    return respond(population, e.experiment.times_s, static, deflection, noisy=False)


def test_rates_grow_with_depth(monkey_line):
    """A 2 mm probe held 0.5 and 1.0 mm deep on the line of afferents. Measured: SA1 hold rates
    summed over the line 78 -> 233 Hz, RA ramp rates 0 -> 350 Hz; the same afferents answer twice
    identically (noise off)."""
    _, _, sn, line, _ = monkey_line
    pop = _line_population(sn, line)
    k = len(line)
    trace = {"shape": "ramp_hold", "samples": 30}
    shallow, deep = (_drive(monkey_line, {"indentor": "punch:2", "depth_mm": d, "trace": trace}, pop) for d in (0.5, 1.0))
    hold = [r.rates_hz(0.15, 0.6)[:k].sum() for r in (shallow, deep)]
    ramp = [r.rates_hz(0.0, 0.12)[k:].sum() for r in (shallow, deep)]
    assert hold[1] > 1.5 * hold[0] > 0 and ramp[1] > ramp[0] and ramp[1] > 0
    again = respond(pop, deep.times_s, deep.static, deep.deflection_mm, noisy=False)
    assert all(np.array_equal(a, b) for a, b in zip(again.spikes, deep.spikes))


def test_sa1_resolve_grating_bars_that_ra_blur(monkey_line):
    """A grating of 1.5 mm bars and 1.5 mm gaps across the pad, 0.75 mm deep, the central gap over
    x = 0. Measured: SA1 hold rates up to 18 Hz under the two central bars and 0 over the gap
    between them (gap / bar 0.0); RA ramp rates one plateau across both (8-25 Hz, gap / bar 1.0)."""
    _, _, sn, line, _ = monkey_line
    pop = _line_population(sn, line)
    k, x = len(line), sn.x[line, 0]
    n, bar = 6, 1.5
    start = -(n * bar + (n - 1) * bar) / 2
    grating = {"indentor": f"grating:{bar}:" + ",".join([str(bar)] * (n - 1)), "depth_mm": 0.75,
               "trace": {"shape": "ramp_hold", "samples": 30}}
    resp = _drive(monkey_line, grating, pop, start)
    gap = np.abs(x) < 0.5
    bars = (np.abs(np.abs(x) - 1.5) < 0.5)
    sa1, ra = resp.rates_hz(0.15, 0.6)[:k], resp.rates_hz(0.0, 0.12)[k:]
    assert sa1[bars].max() > 10 and sa1[gap].max() / sa1[bars].max() < 0.2
    assert ra[gap].max() / ra[bars].max() > 0.6


def test_trace_shapes_and_refusals():
    """Ramp-and-hold corners are samples; the closed-form course equals the samples; an offset sine
    starts at its offset; a sine above MAX_FREQUENCY_HZ or with an offset of 1, afferents without a
    trace and a trace with several depths are one-line errors; above the quasi-static limit a sine
    runs with a warning."""
    scene = Scene.from_dict({"experiment": [{"indentor": "punch:2", "depth_mm": 1.0,
                                             "trace": {"shape": "ramp_hold", "samples": 8}}]})
    exp = scene.experiments[0]
    t, f = fractions(exp.trace)
    assert {0.1, 0.6, 0.7} <= set(np.round(t, 12)) and f.max() == 1 and f[0] == f[-1] == 0
    assert [load["depth_mm"] for _, load in exp.indentations] == pytest.approx(f * 1.0)
    sine = dataclasses.replace(exp.trace, shape="sine", frequency_hz=10, cycles=2, samples=40)
    ts, fs = fractions(sine)
    assert ts[-1] == pytest.approx(0.2) and fs.max() == pytest.approx(1, abs=0.01)
    for trace in (exp.trace, sine):
        t, f = fractions(trace)
        assert np.array_equal(course(trace, t), f)
    offset = dataclasses.replace(sine, offset=0.25)
    assert course(offset, [0.0, 0.05, 0.1]) == pytest.approx([0.25, 1.0, 0.25])
    assert frequency_warning(sine) is None and "quasi-static" in frequency_warning(
        dataclasses.replace(sine, frequency_hz=250))
    sine_at = lambda **kw: {"experiment": [{"indentor": "punch:2", "depth_mm": 1.0,  # noqa: E731
                                            "trace": {"shape": "sine", "samples": 80, **kw}}]}
    Scene.from_dict(sine_at(frequency_hz=250))
    bad = [sine_at(frequency_hz=2000), sine_at(frequency_hz=10, offset=1.0),
           {"experiment": [{"indentor": "punch:2", "depth_mm": 1.0}], "afferents": {}},
           {"experiment": [{"indentor": "punch:2", "depth_mm": [0.5, 1.0], "trace": {}}]},
           {"experiment": [{"indentor": "punch:2", "depth_mm": 1.0, "trace": {"shape": "wobble"}}]},
           {"experiment": [{"indentor": "punch:2", "depth_mm": 1.0, "trace": {}}], "afferents": {"classes": ["SA2"]}},
           {"experiment": [{"indentor": "punch:2", "depth_mm": 1.0, "trace": {}}],
            "afferents": {"sites_mm": [[0, 1, 2]], "radius_mm": 3.0}},
           {"experiment": [{"indentor": "punch:2", "depth_mm": 1.0, "trace": {}}], "afferents": {"sites_mm": [[0, 1]]}}]
    for d in bad:
        with pytest.raises(InputError):
            Scene.from_dict(d)


def test_steps_table_and_scan_courses():
    """steps: each level reached by a ramp and held; table: as given, resampled; scan: one sample
    per sweep offset at the full depth, times = distance / speed."""
    steps = Scene.from_dict({"experiment": [{"indentor": "punch:2", "depth_mm": 2.0, "trace": {
        "shape": "steps", "levels": [0.25, 0.5], "ramp_s": 0.05, "hold_s": 0.2, "samples": 50}}]}).experiments[0]
    t, f = fractions(steps.trace)
    assert t[-1] == pytest.approx(3 * 0.25) and f[np.argmin(np.abs(t - 0.2))] == pytest.approx(0.25)
    assert f[np.argmin(np.abs(t - 0.45))] == pytest.approx(0.5) and f[-1] == 0
    assert max(load["depth_mm"] for _, load in steps.indentations) == pytest.approx(1.0)
    table = Scene.from_dict({"experiment": [{"indentor": "punch:2", "depth_mm": 1.0, "trace": {
        "shape": "table", "times_s": [0, 0.2, 0.4], "levels": [0, 1, 0.5], "samples": 5}}]}).experiments[0]
    t, f = fractions(table.trace)
    assert np.interp(0.3, t, f) == pytest.approx(0.75) and f[-1] == 0.5
    scan = Scene.from_dict({"experiment": [{"indentor": "punch:2", "depth_mm": 0.5, "sweep": "x=-2:2:0.5",
                                            "trace": {"shape": "scan", "speed_mm_s": 10.0}}]}).experiments[0]
    offsets = [off[0] for off, _ in scan.indentations]
    assert offsets == pytest.approx(np.arange(-2, 2.01, 0.5))
    assert scan.times_s == pytest.approx(np.arange(9) * 0.05)
    assert all(load["depth_mm"] == 0.5 for _, load in scan.indentations)
    with pytest.raises(InputError, match="sweep"):
        Scene.from_dict({"experiment": [{"indentor": "punch:2", "depth_mm": 0.5, "trace": {"shape": "scan", "speed_mm_s": 1}}]})


def test_placement_by_density_and_at_given_sites(monkey_line):
    """By density: round(density x area) sites per class, on the pad's facets, anywhere on them
    (not at nodes), with values interpolated by the facets' quadratic shape functions (exact for
    a quadratic field: x^2 + y z at the candidates gives x^2 + y z at the sites). At given sites:
    one afferent per class at each, projected onto the pad; a point 3 mm off it is refused."""
    model, _, sn, _, zmid = monkey_line
    centre = sn.x[np.argmax(sn.x[:, 1])]
    facets, area = pad_facets(model, sn, centre, 4.0)
    pop = place(model, sn, ("SA1", "RA", "PC"), {"SA1": 2000.0, "RA": 100.0, "PC": 10.0}, centre, 4.0, seed=3)
    cls = pop.afferent_class.astype(str)
    assert [int((cls == c).sum()) for c in ("SA1", "RA", "PC")] == [round(d * area.sum() / 100) for d in (2000, 100, 10)]
    field = lambda x: x[..., 0] ** 2 + x[..., 1] * x[..., 2]                      # noqa: E731
    assert np.abs(pop.at_sites(field(sn.x)) - field(pop.site_mm)).max() < 1e-9
    gap = np.linalg.norm(pop.site_mm[:, None] - sn.x[None], axis=2).min(axis=1)
    assert np.median(gap) > 0.1 and np.all(np.abs(np.linalg.norm(pop.normal, axis=1) - 1) < 1e-12)
    weight = area / area.sum()
    assert np.abs(pop.site_mm[cls == "SA1"].mean(axis=0) - weight @ sn.x[facets[:, :3]].mean(axis=1)).max() < 0.15
    assert pop.points_mm[:, 1].max() < pop.site_mm[:, 1].max()                   # below the skin

    given = [[0.0, centre[1] + 0.2, zmid], [1.0, centre[1], zmid + 1.0]]
    at = place(model, sn, ("SA1", "PC"), seed=0, sites_mm=given)
    assert list(at.afferent_class) == ["SA1", "SA1", "PC", "PC"]
    assert np.abs(at.site_mm[:2, [0, 2]] - np.array(given)[:, [0, 2]]).max() < 0.3
    assert np.array_equal(at.site_mm[:2], at.site_mm[2:]) and list(at.depth_mm) == [0.3, 0.3, 2.0, 2.0]
    with pytest.raises(InputError, match="from the pad surface"):
        place(model, sn, ("SA1",), sites_mm=[[0.0, centre[1] + 3.0, zmid]])


def test_finite_kinematics_tables_the_afferent_inputs_of_its_own_states(shop):
    """A scene with kinematics = "finite" drives afferents from the finite states: the table of a
    ramp to 2 um (a 3 mm sphere, the 1 mm monkey) starts at the course's distinct depths (0, 2 um)
    and adds the midpoint solved from rest; its inputs at an afferent under the first touch are
    the finite state's -n.sigma.n (Cauchy) and its deflection the state's. At this depth they are
    the linear model's within 5 % (measured: static -2.0 %, deflection -1.1 %; the 1 mm mesh's
    few contact nodes and their leaning normals, docs/indentation.md "When linear is enough")."""
    from fem.experiments.spiking import finite_tabulate, tabulate

    folder = shop.preset("monkey")
    table = {"material": list(load_scene(SCENE).material), "receptors": {"depths_mm": [0.75]},
             "experiment": [{"name": "press", "indentor": "sphere:3", "depth_mm": 0.002,
                             "trace": {"shape": "ramp_hold", "ramp_s": 0.01, "hold_s": 0.01, "release_s": 0.01,
                                       "samples": 4}}]}
    tables = {}
    for kinematics in ("finite", "linear"):
        scene = Scene.from_dict({**table, "kinematics": kinematics}, "test")
        model, info = read_model(folder, scene.material)
        run = run_experiments(model, info, scene)
        (exp_run,) = run.experiments
        points = run.surface.x
        site = points[np.argmin(exp_run.indentor.standoff(points))]
        pop = place(model, run.surface, ("SA1",), sites_mm=site[None])
        sampler = sampler_of(model, pop)
        tables[kinematics] = (finite_tabulate(run.finite, sampler, pop, exp_run, tolerance=0.05)
                              if kinematics == "finite" else tabulate(sampler, pop, run.contact, exp_run, tolerance=0.05))
        if kinematics == "finite":
            last = exp_run.finite_states[int(np.argmax([r.depth_mm for r in exp_run.finite_states]))]
            values = run.finite.observe(last.u, sampler)
            stress = sampler.with_energy().state(values).stress
            own = -np.einsum("ni,nij,nj->n", pop.normal, stress, pop.normal)
            fin = tables["finite"]
            assert np.allclose(fin.load, [0.0, 0.001, 0.002], rtol=0, atol=1e-12)
            assert fin.static[:, -1] == pytest.approx(own, rel=1e-12)
            assert fin.deflection_mm[:, -1] == pytest.approx(pop.at_sites(last.u[run.finite.dofs]
                                                                          @ exp_run.indentor.approach), rel=1e-12)
    fin, lin = tables["finite"], tables["linear"]
    assert fin.static[:, -1] == pytest.approx(lin.static[:, -1], rel=0.05)
    assert fin.deflection_mm[:, -1] == pytest.approx(lin.deflection_mm[:, -1], rel=0.05)


def test_a_site_off_the_pad_is_refused_before_anything_is_solved(shop, tmp_path, capsys, monkeypatch):
    """An afferent site 10 mm from the pad: one error line, exit 2, no run folder, and no
    factorisation or large-deformation solve started (both kinematics)."""
    from fem.contact.finite import FiniteContact
    from fem.core.model import Model

    def solving(*args, **kwargs):
        raise AssertionError("solved before the refusal")

    monkeypatch.setattr(Model, "system", solving)
    monkeypatch.setattr(FiniteContact, "indent", solving)
    for kinematics in ("linear", "finite"):
        scene = tmp_path / f"{kinematics}.toml"
        scene.write_text(f'kinematics = "{kinematics}"\n[afferents]\nclasses = ["SA1"]\nsites_mm = [[0.0, 30.0, 5.0]]\n'
                         '[[experiment]]\nindentor = "sphere:3"\ndepth_mm = 0.5\n'
                         '[experiment.trace]\nshape = "ramp_hold"\nsamples = 10\n')
        out = tmp_path / f"run_{kinematics}"
        assert pipeline.main(["indent", str(shop.preset("monkey")), "--scene", str(scene), "--out", str(out)]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith("error:") and "from the pad surface" in err[0], err
        assert not out.exists()
