"""Receptor analysis: thesis R^2 on hand-computed cases, fit recovery from synthetic rates (depth,
a, b, model diameter), fit one stimulus / predict another, `pipeline.py analyze` outputs and bad
input, spatial vs population response, receptive fields, two-point and gap analysis on the 2D
cylinder with bone."""
import csv
import math

import numpy as np
import pytest

import pipeline
from fem.io.runfolder import IndentRun
from fem.receptors.analysis import (
    as_runs,
    fit_measure,
    goodness,
    linear_fit,
    model_values,
    rank_candidates,
    rank_per_stimulus,
)
from fem.receptors.neural import make_neural, read_neural_csv, write_neural_csv
from fem.receptors.probes import (
    Probe2D,
    gap_analysis,
    point_load_field,
    receptive_field,
    settling_separation,
    two_point_curves,
)
from fingertip.errors import InputError
from tests.helpers import write_csv

SCENE = """[receptors]
depths_mm = "0.5:1:0.125"
spacing_mm = 0.5
measures = ["sed_MPa", "max_compressive_strain", "max_tensile_strain", "strain_xy", "strain_yy"]

[output]
pvd = false
plots = false

[[experiment]]
name = "grating"
indentor = "grating:1:1,2"
depth_mm = 1.0
sweep = "x=-6.2:1.2:0.2"

[[experiment]]
name = "bar"
indentor = "bar:1.5"
depth_mm = 1.0
sweep = "x=-2:2:0.2"
"""


@pytest.fixture(scope="module")
def models(tmp_path_factory):
    """2D cylinders with bone, 8 and 16 mm, each with the grating and bar sweeps of SCENE."""
    root = tmp_path_factory.mktemp("analysis")
    (root / "scene.toml").write_text(SCENE)
    out = {}
    for d in (8, 16):
        model = root / f"cyl{d}"
        assert pipeline.main(["mesh", "--preset", f"cylinder{d}", "--bone", "--out", str(model), "--quiet"]) == 0
        assert pipeline.main(["indent", str(model), "--scene", str(root / "scene.toml"),
                              "--out", str(model / "sweeps"), "--quiet"]) == 0
        out[d] = model
    return out


@pytest.fixture(scope="module")
def run8(models):
    return IndentRun(models[8] / "sweeps")


def covered(runs, stimulus):
    """Sweep positions of the first run inside every run's receptor-aligned profile range."""
    ranges = [run.profile(stimulus, "sed_MPa", 0.75)[0] for run in runs.values()]
    p = next(iter(runs.values())).positions(stimulus)
    return p[(p >= max(r.min() for r in ranges)) & (p <= min(r.max() for r in ranges))]


def synthetic(runs, measure="sed_MPa", depth=0.75, diameter=math.nan, peak=60.0, b=8.0, noise=2.0, seed=3,
              stimuli=None):
    """Rates from the model with known parameters; a is set so that a * max(S) = peak."""
    first = next(iter(runs.values()))
    stimuli = stimuli or first.stimuli
    where = {s: covered(runs, s) for s in stimuli}
    smax = max(np.abs(model_values(runs, s, measure, depth, diameter, where[s])).max() for s in stimuli)
    a = peak / smax
    rng = np.random.default_rng(seed)
    st, pos, rate = [], [], []
    for s in stimuli:
        p = where[s]
        S = model_values(runs, s, measure, depth, diameter, p)
        st += [s] * len(p)
        pos += list(p)
        rate += list(a * S + b + rng.normal(0.0, noise, len(p)) if noise else a * S + b)
    return make_neural(st, pos, rate), a


# ----------------------------------------------------------------------------- goodness of fit
def test_thesis_goodness_hand_computed():
    # R^2 = (sum d^2 - sum e^2) / sum d^2: d = 1, 2, 3 against 1, 2, 2 -> (14 - 1) / 14
    assert goodness([1, 2, 3], [1, 2, 2]) == pytest.approx(13 / 14)
    # least squares on S = 0..3, d = 1, 3, 2, 4: a = 0.8, b = 1.3, e = -.3, .9, -.9, .3
    a, b, r2, rms = linear_fit([0, 1, 2, 3], [1, 3, 2, 4])
    assert (a, b) == pytest.approx((0.8, 1.3))
    assert r2 == pytest.approx((30 - 1.8) / 30)
    assert rms == pytest.approx(math.sqrt(1.8 / 4))
    # uncentred: a constant model of constant rates is a perfect fit, a constant S gives a = 0
    assert linear_fit([2, 2, 2], [5, 5, 5])[:3] == pytest.approx((0.0, 5.0, 1.0))


def test_fit_recovers_a_b_depth_from_synthetic_rates(run8):
    """Noise-free: exact. sigma = 2 imp/s on a 60 imp/s peak: depth exact on the 0.125 mm grid,
    a within 3 %, b within 1 imp/s, RMS within 20 % of sigma, the true measure ranked first."""
    runs = {math.nan: run8}
    exact, a_true = synthetic(runs, noise=0.0)
    f = fit_measure(runs, exact, "sed_MPa")
    assert f.depth_mm == 0.75 and f.a == pytest.approx(a_true, rel=1e-9) and f.b == pytest.approx(8.0, abs=1e-9)
    assert f.r2 == pytest.approx(1.0, abs=1e-12) and f.rms_ips < 1e-9
    noisy, _ = synthetic(runs, noise=2.0)
    table = rank_candidates(runs, noisy)
    best = table[0]
    assert best.measure == "sed_MPa" and best.depth_mm == 0.75, [(t.measure, t.depth_mm) for t in table]
    assert abs(best.a / a_true - 1) < 0.03 and abs(best.b - 8.0) < 1.0
    assert 1.6 < best.rms_ips < 2.4
    assert [t.rms_ips for t in table] == sorted(t.rms_ips for t in table)
    assert {t.measure for t in table} == {"sed_MPa", "max_compressive_strain", "max_tensile_strain",
                                          "abs:strain_xy", "strain_yy"}      # thesis candidates in the run
    # a deeper receptor is recovered too
    deep, a_deep = synthetic(runs, depth=1.0, noise=1.0, seed=5)
    f = fit_measure(runs, deep, "sed_MPa")
    assert f.depth_mm == 1.0 and abs(f.a / a_deep - 1) < 0.03


def test_diameter_recovered_by_interpolating_8_and_16_mm(models):
    runs = {8.0: IndentRun(models[8] / "sweeps"), 16.0: IndentRun(models[16] / "sweeps")}
    data, a_true = synthetic(runs, measure="max_compressive_strain", depth=0.625, diameter=12.0, noise=1.0)
    f = fit_measure(runs, data, "max_compressive_strain")
    assert f.diameter_mm == 12.0 and f.depth_mm == 0.625
    assert abs(f.a / a_true - 1) < 0.03
    # the two models really differ for these stimuli (the diameter is identifiable)
    s8 = model_values(runs, "grating", "sed_MPa", 0.75, 8.0, covered(runs, "grating"))
    s16 = model_values(runs, "grating", "sed_MPa", 0.75, 16.0, covered(runs, "grating"))
    assert np.abs(s8 - s16).max() > 0.1 * s8.max()


def test_fit_on_one_stimulus_predicts_the_other(run8):
    runs = {math.nan: run8}
    data, _ = synthetic(runs, noise=1.5, seed=7)
    f = fit_measure(runs, data, "sed_MPa", fit_stimuli=["grating"])
    assert f.stimuli == ("grating",)
    pred = f.evaluate(runs, data.only(stimuli=["bar"]))["bar"]
    assert pred[0] > 0.98 and pred[1] < 2.5                     # R^2, RMS on the unseen stimulus
    wrong = fit_measure(runs, data, "abs:strain_xy", fit_stimuli=["grating"])
    assert wrong.evaluate(runs, data.only(stimuli=["bar"]))["bar"][1] > 2 * pred[1]
    per = rank_per_stimulus(runs, data)
    assert set(per) == {"grating", "bar"} and all(fl[0].r2 >= fl[-1].r2 for fl in per.values())


# ----------------------------------------------------------------------------- CLI
def test_analyze_command_writes_tables_and_plots(models, tmp_path, capsys):
    runs = {8.0: IndentRun(models[8] / "sweeps"), 16.0: IndentRun(models[16] / "sweeps")}
    data, _ = synthetic(runs, diameter=10.0, noise=1.0)
    csv_path = tmp_path / "rates.csv"
    write_neural_csv(csv_path, data, "synthetic test data")
    out = tmp_path / "report"
    assert pipeline.main(["analyze", str(models[8] / "sweeps"), str(models[16] / "sweeps"), "--neural",
                          str(csv_path), "--fit-on", "grating", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "sed_MPa predicts bar" in text
    for name in ("ranking_combined.csv", "ranking_combined.md", "ranking_per_stimulus.csv", "prediction.csv",
                 "profiles_unit.png", "scatter_unit.png", "analysis.json"):
        assert (out / name).is_file(), name
    with open(out / "ranking_combined.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert rows[0]["measure"] == "sed_MPa" and float(rows[0]["diameter_mm"]) == 10.0
    assert float(rows[0]["depth_mm"]) == 0.75 and rows[0]["stimuli"] == "grating"
    assert (out / "ranking_combined.md").read_text().count("\n|") >= len(rows) + 1


@pytest.mark.parametrize("text, extra, message", [
    ("stimulus,position_mm\ngrating,0.0\n", [], "lacks column(s) ['rate_ips']"),
    ("stimulus,position_mm,rate_ips\ngrating,0.0,nan\n", [], "rate_ips is empty or NaN"),
    ("stimulus,position_mm,rate_ips\ngrating,0.0,\n", [], "rate_ips is empty or NaN"),
    ("stimulus,position_mm,rate_ips\ngrating,-3.0,4\ngrating,9.0,5\n", [], "outside the simulated sweep"),
    ("stimulus,position_mm,rate_ips\ngrating,0.0,4\n", ["--measures", "sed_MPa,shear_of_doom"],
     "unknown measure 'shear_of_doom'"),
    ("stimulus,position_mm,rate_ips\nstep9,0.0,4\n", [], "stimulus 'step9' is not in"),
    ("stimulus,position_mm,rate_ips\ngrating,0.0,4\n", ["--measures", "stress_xx_MPa"], "was not computed"),
    ("stimulus,position_mm,rate_ips,orientation\ngrating,0.0,4,parallel\ngrating,0.2,4,perpendicular\n", [],
     "mixes bar orientations"),
    ("stimulus,position_mm,rate_ips\ngrating,0.0,-4\n", [], "negative rate_ips"),
])
def test_bad_input_one_line_exit_2_nothing_written(models, tmp_path, capsys, text, extra, message):
    out = tmp_path / "report"
    code = pipeline.main(["analyze", str(models[8] / "sweeps"), "--neural", str(write_csv(tmp_path, text, "bad.csv")),
                          *extra, "--out", str(out)])
    err = capsys.readouterr().err.strip()
    assert code == 2 and err.startswith("error:") and message in err and "\n" not in err, err
    assert not out.exists()


def test_neural_csv_comments_aliases_and_defaults(tmp_path):
    p = write_csv(tmp_path, "# synthetic\nstimulus,position_mm,rate_imp_s\ngrating,0.5,12\nbar,-0.2,3.5\n")
    data = read_neural_csv(p)
    assert data.stimuli == ["grating", "bar"] and data.units == ["unit"]
    np.testing.assert_allclose(data.rate_ips, [12, 3.5])


def test_neural_csv_saved_by_excel_with_a_byte_order_mark(tmp_path):
    """Excel's "CSV UTF-8" starts with a BOM (and ends lines with CRLF): read as without it."""
    p = tmp_path / "excel.csv"
    p.write_bytes("\ufeffstimulus,position_mm,rate_ips,unit\r\ngrating,0.5,12,µ1\r\nbar,-0.2,3.5,µ1\r\n".encode())
    data = read_neural_csv(p)
    assert data.stimuli == ["grating", "bar"] and data.units == ["µ1"]
    np.testing.assert_allclose(data.rate_ips, [12, 3.5])


# ----------------------------------------------------------------------------- results folder contract
def _rewrite_receptors(folder, stimulus, change):
    """Rewrite <stimulus>_receptors.csv through change(header, rows) -> (header, rows)."""
    path = folder / f"{stimulus}_receptors.csv"
    with open(path) as fh:
        rows = list(csv.reader(fh))
    header, body = change(rows[0], rows[1:])
    with open(path, "w", newline="") as fh:
        csv.writer(fh).writerows([header, *body])


def test_receptor_sites_come_from_the_site_column(models, tmp_path):
    """Rows shuffled within each step: the site column still pairs each receptor with its values."""
    import shutil

    ref = IndentRun(models[8] / "sweeps")
    folder = tmp_path / "shuffled"
    shutil.copytree(models[8] / "sweeps", folder)
    rng = np.random.default_rng(1)
    _rewrite_receptors(folder, "grating", lambda h, rows: (h, [rows[i] for i in rng.permutation(len(rows))]))
    run = IndentRun(folder)
    for x in (0.0, 1.0):
        for depth in (0.5, 0.75):
            np.testing.assert_array_equal(run.profile("grating", "sed_MPa", depth, x)[1],
                                          ref.profile("grating", "sed_MPa", depth, x)[1])
    assert run.site_index("grating", 1.0) == ref.site_index("grating", 1.0)


def test_run_json_gives_diameter_and_sweep_axis_outside_the_model_folder(models, tmp_path):
    import json
    import shutil

    folder = tmp_path / "moved"
    shutil.copytree(models[16] / "sweeps", folder)
    run = IndentRun(folder)
    assert run.diameter_mm == 16.0 and run.sweep_axis("bar") == "x"
    (folder / "run.json").write_text("{")
    with pytest.raises(InputError, match="not a run.json"):
        IndentRun(folder)
    record = json.loads((models[16] / "sweeps" / "run.json").read_text())
    record["model"]["diameter_mm"] = None
    (folder / "run.json").write_text(json.dumps(record))
    assert IndentRun(folder).diameter_mm is None
    with pytest.raises(InputError, match="--diameters"):
        as_runs([IndentRun(models[8] / "sweeps"), IndentRun(folder)])


def test_folders_without_run_json_or_site_column_are_refused(models, tmp_path):
    """Run folders of the 0.1.0 package (no run.json, no site column) are one InputError asking
    to re-run `pipeline.py indent`."""
    import shutil

    folder = tmp_path / "models" / "cyl8" / "old"
    folder.parent.mkdir(parents=True)
    shutil.copy(models[8] / "model.json", folder.parent / "model.json")
    shutil.copytree(models[8] / "sweeps", folder)
    _rewrite_receptors(folder, "grating", lambda h, rows: ([c for c in h if c != "site"],
                                                           [r[:1] + r[2:] for r in rows]))
    with pytest.raises(InputError, match="re-run `pipeline.py indent`"):
        IndentRun(folder).profile("grating", "sed_MPa", 0.75, 1.0)
    (folder / "run.json").unlink()
    with pytest.raises(InputError, match="re-run `pipeline.py indent`"):
        IndentRun(folder)


# ----------------------------------------------------------------------------- spatial vs population
def test_spatial_profile_vs_population_response(run8):
    """The central receptor's profile at stimulus offset 0 is the population value at that receptor;
    an off-centre receptor's profile, shifted by its offset, differs from the central one on the
    curved finger (thesis 4.5.4, figure 4-18)."""
    pos, central = run8.profile("grating", "sed_MPa", 0.75, receptor_x_mm=0.0, align=False)
    x, popul = run8.population("grating", "sed_MPa", 0.75, position_mm=0.0)
    k = np.argmin(np.abs(x - 0.0))
    assert central[np.argmin(np.abs(pos))] == pytest.approx(popul[k], rel=1e-12)
    site_x = x[np.argmin(np.abs(x - 1.0))]
    pos1, off = run8.profile("grating", "sed_MPa", 0.75, receptor_x_mm=1.0, align=False)
    shifted = np.interp(pos, pos1 - site_x, off)                  # same stimulus-receptor offset
    inside = (pos - site_x >= pos1.min() - site_x) & (pos <= pos1.max() - site_x)
    diff = np.sqrt(np.mean((shifted[inside] - central[inside]) ** 2)) / central.max()
    assert diff > 0.05, diff


# ----------------------------------------------------------------------------- 2D probe experiments
@pytest.fixture(scope="module")
def probe(models):
    return Probe2D(models[8], np.round(np.arange(-3.0, 3.0001, 0.05), 3), depths_mm=(0.75,))


def test_receptive_field_on_a_flamant_profile_hand_computed():
    """|tau_xy| of a line load on a half-plane at depth h is prop. to x h^2 / (x^2 + h^2)^2: with the
    threshold at the value of x = 0.15 mm the OFF hole is 0.3 mm wide."""
    h, x = 0.75, np.linspace(-2, 2, 4001)
    f = np.abs(x) * h * h / (x * x + h * h) ** 2
    rf = receptive_field(x, f, 0.15 * h * h / (0.15 ** 2 + h * h) ** 2)
    assert rf.shape == "annulus" and rf.hole_mm == pytest.approx(0.3, abs=1e-3)
    sed = receptive_field(x, h ** 4 / (x * x + h * h) ** 2, 0.5)   # half-peak disk: x^2 + h^2 = sqrt(2) h^2
    assert sed.shape == "disk" and sed.diameter_mm == pytest.approx(2 * h * math.sqrt(math.sqrt(2) - 1), abs=1e-3)
    assert receptive_field(x, f, 10.0).shape == "none"


def test_receptive_fields_disk_for_sed_annulus_for_shear(probe):
    """Thesis 4.2: a line load swept over the central receptor at 0.75 mm, half-peak threshold:
    SED and compressive strain give disks (SED narrower: SED ~ eps^2), absolute shear strain an
    annulus with a hole of about 0.3 mm."""
    pos = np.round(np.arange(-1.5, 1.5001, 0.05), 3)
    sed = point_load_field(probe, "sed_MPa", pos)
    comp = point_load_field(probe, "max_compressive_strain", pos)
    shear = point_load_field(probe, "abs:strain_xy", pos)
    assert sed.shape == "disk" and comp.shape == "disk"
    assert 0.5 < sed.diameter_mm < comp.diameter_mm < 2.0
    assert shear.shape == "annulus" and 0.2 < shear.hole_mm < 0.4, shear.hole_mm
    x, y, on = shear.map2d(81)
    assert not on[40, 40] and on[40, 40 + 10]                     # OFF centre, ON at 0.375 mm


def test_two_point_force_control_settles_displacement_keeps_changing(probe):
    """Thesis 4.3: max SED at 0.75 mm under two loads, separations 0-3 mm. Equal force: within 5 %
    of its final value from a separation of 1-2 mm (thesis 1.6 mm); equal displacement: still
    more than 10 % off at 1.6 mm. Both protocols coincide at separation 0."""
    seps = np.round(np.arange(0.0, 3.0001, 0.2), 3)
    c = two_point_curves(probe, seps, depth_mm=0.5, isolated=False)
    assert c["force"][0] == pytest.approx(c["displacement"][0], rel=1e-6)
    assert np.all(np.diff(c["force"][:6]) < 0)                     # monotonic fall at first
    settle = settling_separation(seps, c["force"], 0.05)
    assert 1.0 <= settle <= 2.0, settle
    i16 = np.flatnonzero(seps == 1.6)[0]
    assert abs(c["displacement"][i16] / c["displacement"][-1] - 1) > 0.10
    assert settling_separation(seps, c["displacement"], 0.05) > settle + 0.6


def test_gap_interpeak_distance_follows_the_gap(probe):
    """Thesis 4.5.5: shear-strain peaks at 0.75 mm on both sides of a gap between two 1 mm bars:
    the inter-peak distance matches the gap within 0.1 mm for gaps >= 1 mm and levels off near
    0.75 mm for narrower gaps; the peaks grow with the gap."""
    rows, prof = gap_analysis(probe, 1.0, [0.5, 0.75, 1.0, 2.0, 3.0])
    dist = [r["interpeak_mm"] for r in rows]
    for r in rows[2:]:
        assert abs(r["interpeak_mm"] - r["gap_mm"]) < 0.1, r
    assert 0.6 < dist[0] < 0.9 and dist[0] > rows[0]["gap_mm"] + 0.1
    peaks = [r["peak_left"] for r in rows]
    assert all(b > a for a, b in zip(peaks, peaks[1:]))
    assert prof.shape == (5, len(probe.sites_x_mm))


def test_settling_separation_definition():
    s = np.arange(6.0)
    assert settling_separation(s, [5, 3, 2.08, 2.02, 1.99, 2.0]) == 2.0
    assert settling_separation(s, [5, 3, 2.2, 2.02, 1.99, 2.0]) == 3.0
    assert math.isnan(settling_separation(s, [1, 2, 3, 4, 5, 6]))
    with pytest.raises(InputError):
        make_neural(["a"], [0.0], [float("nan")])


def test_units_fitted_separately_and_orientation_selected(run8):
    """Two units with different depths in one file: each gets its own parameters; rows of another
    orientation are left out with --orientation."""
    from fem.receptors.analysis import analyze

    runs = {math.nan: run8}
    u1, a1 = synthetic(runs, depth=0.625, noise=0.5, seed=11)
    u2, a2 = synthetic(runs, depth=1.0, noise=0.5, seed=12)
    n1, n2 = len(u1), len(u2)
    data = make_neural(np.concatenate([u1.stimulus, u2.stimulus, u2.stimulus]),
                       np.concatenate([u1.position_mm, u2.position_mm, u2.position_mm]),
                       np.concatenate([u1.rate_ips, u2.rate_ips, 0 * u2.rate_ips]),
                       ["SA1-a"] * n1 + ["SA1-b"] * n2 + ["SA1-b"] * n2,
                       ["parallel"] * (n1 + n2) + ["perpendicular"] * n2)
    res = {ua.unit: ua for ua in analyze(runs, data, ["sed_MPa", "max_compressive_strain"], orientation="parallel")}
    assert set(res) == {"SA1-a", "SA1-b"}
    for unit, depth, a in (("SA1-a", 0.625, a1), ("SA1-b", 1.0, a2)):
        best = res[unit].combined[0]
        assert best.measure == "sed_MPa" and best.depth_mm == depth and abs(best.a / a - 1) < 0.02
        assert best.n == n1 if unit == "SA1-a" else best.n == n2
    with pytest.raises(InputError, match="no rows with orientation"):
        analyze(runs, data, ["sed_MPa"], orientation="oblique")


def test_probe_sites_must_lie_over_the_surface(models):
    with pytest.raises(InputError, match="receptor sites must lie over the contact surface"):
        Probe2D(models[8], [0.0, 5.0])


def test_single_indentation_stimuli_cylinders_at_constant_force(models, tmp_path):
    """Thesis 4.6: one constant-force indentation per cylinder, one rate each; the fit pools the
    cylinders (positions all 0: no sweep, no translation of the receptor)."""
    scene = tmp_path / "cyl.toml"
    scene.write_text('[receptors]\ndepths_mm = [0.5, 0.75, 1.0]\nspacing_mm = 0.5\n'
                     'measures = ["sed_MPa", "max_compressive_strain"]\n[output]\npvd = false\nplots = false\n'
                     + "".join(f'[[experiment]]\nname = "{c}"\nindentor = "{c}"\nforce_N = 0.001\n'
                               for c in ("C1", "C3", "C5", "C8")))
    out = tmp_path / "cyl"
    assert pipeline.main(["indent", str(models[8]), "--scene", str(scene), "--out", str(out), "--quiet"]) == 0
    run = IndentRun(out)
    runs = {math.nan: run}
    S = {c: run.profile(c, "max_compressive_strain", 1.0)[1][0] for c in run.stimuli}
    assert len({round(v, 12) for v in S.values()}) == 4                  # the cylinders differ
    data = make_neural(list(S), [0.0] * 4, [500.0 * v + 3.0 for v in S.values()])
    f = fit_measure(runs, data, "max_compressive_strain")
    assert f.depth_mm == 1.0 and f.a == pytest.approx(500.0, rel=1e-9) and f.rms_ips < 1e-9
    csv_path = tmp_path / "rates.csv"
    write_neural_csv(csv_path, data)
    assert pipeline.main(["analyze", str(out), "--neural", str(csv_path), "--out", str(tmp_path / "rep"),
                          "--quiet"]) == 0
    assert (tmp_path / "rep" / "profiles_unit.png").is_file()
