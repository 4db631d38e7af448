"""Biomechanical verification (thesis 4.7, 6.2): waterbed and beam curves, deflection profiles under a
line load, the layer study, fitting layer moduli and the force scale; bad input."""
import numpy as np
import pytest

import pipeline
from fem.biomech.deflection import (
    DeflectionExperiment,
    Profile,
    code_of,
    cylinder_series,
    fit_free_length,
    layer_study,
    parse_code,
    side_profile,
)
from fem.biomech.fit import fit_force_scale, fit_material
from fem.biomech.measured import read_deflection_csv, read_force_csv
from fem.verify.closed_forms import (
    WATERBED_PER_BEAM,
    beam_deflection,
    waterbed_deflection,
)
from fingertip.errors import InputError
from tests.helpers import write_csv


# --------------------------------------------------------------------------- closed forms
def test_waterbed_and_beam_follow_their_equations():
    x = np.linspace(0, 3, 31)
    Lw, Lb, d0 = 3.0, 1.7, 1.3
    s = x / Lw
    np.testing.assert_allclose(waterbed_deflection(x, d0, Lw), d0 * (3 * s**2 - 4 * s + 1), atol=1e-15)
    inside = x <= Lb
    t = x[inside] / Lb
    np.testing.assert_allclose(beam_deflection(x, d0, Lb)[inside], d0 * (0.5 * t**3 - 1.5 * t + 1), atol=1e-15)
    assert np.all(beam_deflection(x[~inside], d0, Lb) == 0)                 # clamped beyond Lb
    # waterbed: d0 under the load, zero at Lw/3 and Lw, bulge -d0/3 at 2Lw/3; symmetric in x
    np.testing.assert_allclose(waterbed_deflection([0, Lw / 3, 2 * Lw / 3, Lw, -Lw / 3], d0, Lw),
                               [d0, 0, -d0 / 3, 0, 0], atol=1e-12)
    # beam: zero deflection and zero slope at the clamp
    h = 1e-6
    assert abs(beam_deflection(Lb - h, d0, Lb)) < 1e-10
    assert abs((beam_deflection(Lb, d0, Lb) - beam_deflection(Lb - h, d0, Lb)) / h) < 1e-5


def test_waterbed_equals_beam_near_the_load_when_Lw_is_8_thirds_Lb():
    Lb, d0 = 2.0, 1.0
    x = np.linspace(0, 0.05 * Lb, 20)[1:]
    slope = lambda f, L: (f(1e-7, d0, L) - d0) / 1e-7                      # noqa: E731
    assert slope(waterbed_deflection, WATERBED_PER_BEAM * Lb) == pytest.approx(slope(beam_deflection, Lb), rel=1e-5)
    # the difference is second order in x for Lw = 8/3 Lb, first order for any other ratio
    diff = np.abs(waterbed_deflection(x, d0, WATERBED_PER_BEAM * Lb) - beam_deflection(x, d0, Lb))
    assert np.all(diff <= 3.1 * d0 * (x / (WATERBED_PER_BEAM * Lb)) ** 2)
    other = np.abs(waterbed_deflection(x, d0, 2.0 * Lb) - beam_deflection(x, d0, Lb))
    assert np.all(other > 10 * diff)
    # fitting the waterbed to beam deflections near the load gives Lw = 8/3 Lb
    near = np.linspace(0, 0.08 * Lb, 30)
    fit = fit_free_length(near, beam_deflection(near, d0, Lb), d0, "waterbed")
    assert fit.length_mm / Lb == pytest.approx(WATERBED_PER_BEAM, rel=0.03)


@pytest.mark.parametrize("kind, f, L", [("waterbed", waterbed_deflection, 7.5), ("beam", beam_deflection, 2.2)])
def test_free_length_fit_recovers_length_and_d0(kind, f, L):
    x = np.linspace(0, 4, 41)
    y = f(x, 1.7, L) + np.random.default_rng(0).normal(0, 1e-3, x.size)
    fit = fit_free_length(x, y, None, kind)
    assert fit.length_mm == pytest.approx(L, rel=0.01) and fit.d0_mm == pytest.approx(1.7, abs=0.005)
    assert fit.rms_mm < 1.5e-3 and not fit.at_bound
    fixed = fit_free_length(x, y, 1.7, kind, max_distance_mm=1.0)
    assert fixed.n_points == 11 and fixed.length_mm == pytest.approx(L, rel=0.02)


def test_side_profile_averages_both_sides():
    v = np.array([-2.0, -1.0, -0.5, 0.0, 0.5, 1.5, 3.0])
    w = 1.0 - 0.2 * np.abs(v) + 0.05 * v                           # asymmetric by +-0.05 v
    d, m = side_profile(v, w)
    np.testing.assert_allclose(d, [0.0, 0.5, 1.0, 1.5, 2.0])
    np.testing.assert_allclose(m, 1.0 - 0.2 * d, atol=1e-12)
    d, p = side_profile(v, w, "positive")
    np.testing.assert_allclose(p, 1.0 - 0.15 * d)
    with pytest.raises(InputError):
        side_profile(np.array([0.0, 1.0, 2.0]), np.ones(3))


# --------------------------------------------------------------------------- CSV and codes
def test_csv_reading(tmp_path):
    prof = read_deflection_csv(write_csv(tmp_path, "# synthetic\ndepth_mm,distance_mm,deflection_mm\n"
                                                "2,0.1,1.9\n2,0.5,1.2\n1,0.1,0.95\n1,0.4,0.7\n"))
    assert [p.depth_mm for p in prof] == [1.0, 2.0]
    np.testing.assert_allclose(prof[1].distance_mm, [0.1, 0.5])
    np.testing.assert_allclose(prof[1].deflection_mm, [1.9, 1.2])
    prof = read_deflection_csv(write_csv(tmp_path, "0.1,0.9,1\n0.2,0.8,1\n"))      # no header: column order
    np.testing.assert_allclose(prof[0].deflection_mm, [0.9, 0.8])
    depth, force = read_force_csv(write_csv(tmp_path, "Depth_mm,Force_N\n0.5,0.1\n1.0,0.3\n", "f.csv"))
    np.testing.assert_allclose(force, [0.1, 0.3])


@pytest.mark.parametrize("text, message", [
    ("", "no data rows"),
    ("distance_mm,deflection_mm,depth_mm\n", "no data rows"),
    ("distance_mm,deflection,depth_mm\n0.1,1,2\n", "lacks column"),
    ("0.1,1,2\n0.2,abc,2\n", "is not 3 numbers"),
    ("0.1,abc,2\n0.2,1,2\n", "data row 1: "),
    ("0.1,1\n0.2,1\n", "is not 3 numbers"),
    ("0.1,1,2\n0.3,0.9,2\n0.2,0.8,2\n", "not increasing"),
    ("0.1,1,2\n0.1,0.9,2\n", "not increasing"),
    ("0.1,1,2\n", "single point"),
    ("-0.1,1,2\n0.1,1,2\n", ">= 0 mm"),
    ("0.1,nan,2\n0.2,1,2\n", "non-finite"),
])
def test_bad_deflection_csv(tmp_path, text, message):
    with pytest.raises(InputError, match=message) as err:
        read_deflection_csv(write_csv(tmp_path, text))
    assert "\n" not in str(err.value)


def test_codes():
    np.testing.assert_allclose(parse_code("m43338"), [4, 3, 3, 3, 8])
    assert code_of([4.4, 2.6, 3.0, 3.49, 8]) == "m43338"
    for bad in ("m4333", "m433381", "43338", "mabcde"):
        with pytest.raises(InputError, match="digit"):
            parse_code(bad)


# --------------------------------------------------------------------------- on a finite-element model
# `section` (tests/conftest.py): this module's copy of the coarse five-layer monkey section (~4k DOFs)
@pytest.fixture(scope="module")
def exp(section):
    return DeflectionExperiment(section)


def test_only_modulus_ratios_matter_and_forces_scale(section):
    """Thesis appendix B on the real contact problem (two independent factorisations, no cache):
    scaling every modulus by 10 leaves the deflections unchanged and multiplies forces by 10."""
    a, b = DeflectionExperiment(section), DeflectionExperiment(section)
    pa = a.profiles("m43338", [1.0, 2.0])
    pb = b.profiles("m54449", [1.0, 2.0])
    for x, y in zip(pa, pb):
        np.testing.assert_allclose(y.deflection_mm, x.deflection_mm, rtol=1e-6, atol=1e-9)
        assert y.force_N == pytest.approx(10 * x.force_N, rel=1e-6)
        assert x.deflection_mm[0] > 0.75 * x.depth_mm and x.deflection_mm.min() < 0.3 * x.depth_mm
    # the cache solves equal ratios once and scales the force
    assert a.profiles("m32227", [2.0])[0].force_N == pytest.approx(0.1 * pa[1].force_N, rel=1e-12)
    assert a.evaluations == 1


def test_factorisation_cache_is_bounded(section):
    """max_factors=1: the second material evicts the first's factorisation; the first's solved
    depths stay cached (no re-factorisation), a new depth for it factorises again, same answer."""
    e = DeflectionExperiment(section, max_factors=1)
    p1 = e.profiles("m43338", [1.0])[0]
    e.profiles("m33338", [1.0])
    assert e.evaluations == 2 and len(e._solvers) == 1
    assert e.profiles("m43338", [1.0])[0].deflection_mm is not None and e.evaluations == 2
    p2 = e.profiles("m43338", [1.0, 2.0])
    assert e.evaluations == 3
    np.testing.assert_allclose(p2[0].deflection_mm, p1.deflection_mm)


def test_cached_results_do_not_keep_an_evicted_factorisation_alive(section):
    """The cached contact results are cut from their contact model, so an evicted factorisation is
    freed (before, a 3D fit kept all of them: 0.9 GB per material on the 1 mm monkey preset, 24 GB
    and out of memory within a 43-material fit)."""
    import gc
    import weakref

    e = DeflectionExperiment(section, max_factors=1)
    e.profiles("m43338", [1.0, 2.0])
    first = weakref.ref(next(iter(e._solvers.values())))
    e.profiles("m33338", [1.0])
    gc.collect()
    assert first() is None
    assert all(r._source is None for entry in e._cache.values() for r in entry["depth"].values())


def test_layer_study_reuses_ratios_and_finds_thesis_trends(exp):
    """Figure 6-10 trends: a stiffer outer layer spreads the load (more deflection away from it),
    stiffer inner layers 3 and 4 lower the deflection; each layer's most affected point is
    reported, further out for layer 3 than layer 1."""
    study = layer_study(exp, "m43338", layers=(1, 2, 3, 4), offsets=(-1, 0, 1), depths_mm=(2.0,))
    assert len(study.profiles) == 9 and exp.evaluations <= 9               # the base is shared
    eff = {e.layer: e for e in study.effects}
    assert eff[1].difference_mm > 0.2 and eff[3].difference_mm < -0.2 and eff[4].difference_mm < -0.1
    assert eff[3].most_affected_mm > eff[1].most_affected_mm
    for e in study.effects:
        lo, hi = study.profiles[e.codes[0]][0], study.profiles[e.codes[-1]][0]
        d = lo.distance_mm
        assert abs(hi.at([e.most_affected_mm])[0] - lo.at([e.most_affected_mm])[0]) == pytest.approx(
            np.abs(hi.at(d) - lo.at(d)).max(), rel=1e-9)
    with pytest.raises(InputError, match="fewer than two codes"):
        layer_study(exp, "m93338", layers=(1,), offsets=(0, 1))


def test_fit_recovers_layer_moduli_from_noisy_model_deflections(exp):
    """Deflections generated by the model for known moduli (layers 2, 3 off the integer codes),
    plus 5 um noise at two depths: the fit from m43338 recovers them within 3 sigma of the
    Jacobian uncertainty, which itself is tight (factor < 1.1)."""
    truth = np.array([4.0, 2.6, 3.3, 3.0, 8.0])
    dist = np.arange(0.2, 3.51, 0.1)
    rng = np.random.default_rng(7)
    data = [Profile(p.depth_mm, dist, p.at(dist) + rng.normal(0, 0.005, dist.size))
            for p in exp.profiles(truth, [1.0, 2.0])]
    fit = fit_material(exp, data, base="m43338", free_layers=(2, 3))
    err = fit.log10_Pa[[1, 2]] - truth[[1, 2]]
    assert np.all(np.abs(err) <= 3 * fit.std_log10), (err, fit.std_log10)
    assert np.all(fit.factor < 1.1) and np.all(fit.sensitivity_mm > 0.02)
    assert fit.rms_mm == pytest.approx(0.005, rel=0.3)
    assert fit.log10_Pa[0] == 4.0 and fit.log10_Pa[3] == 3.0                  # held layers
    assert fit.best_code in fit.code_rms_mm and fit.best_code_rms_mm == min(fit.code_rms_mm.values())
    with pytest.raises(InputError, match="degenerate"):
        fit_material(exp, data, free_layers=(1, 2, 3, 4, 5))


def test_force_scale(exp):
    """Forces at prescribed depth are proportional to the common modulus factor: measured forces
    of the model with every modulus x 2.5 give scale 2.5 at the unscaled ratios."""
    depths = np.array([0.5, 1.0, 2.0])
    base = parse_code("m43338")
    measured = exp.forces_N(base + np.log10(2.5), depths)
    fs = fit_force_scale(exp.forces_N(base, depths), measured, base, depths)
    assert fs.scale == pytest.approx(2.5, rel=1e-9) and fs.rms_N < 1e-12
    np.testing.assert_allclose(fs.log10_Pa, base + np.log10(2.5))
    deep = fit_force_scale(exp.forces_N(base, depths), measured * [1.3, 1.1, 1.0], base, depths, "deepest")
    assert deep.scale == pytest.approx(2.5, rel=1e-9) and deep.rms_N > 0


def test_cylinder_series_follows_the_thesis_trends(exp):
    """Thesis fig. 4-25 (constant force, 2D): a larger cylinder gives a wider contact, a lower
    peak pressure and needs less depth; fig. 5-14 (fixed depth): a larger contact. The moduli x10
    at forces x10 give the same contact (only ratios matter) and pressures x10."""
    codes = ["C1", "C3", "C5", "C7"]
    s = cylinder_series(exp, "m43338", codes, forces_N=[0.001, 0.002])
    assert s.diameters_mm.tolist() == [1.59, 4.76, 9.52, 19.05]
    np.testing.assert_allclose(s.force_N, [[0.001] * 4, [0.002] * 4], rtol=1e-5)
    for j in range(2):
        assert np.all(np.diff(s.contact_area_mm2[j]) > 0), s.contact_area_mm2
        assert np.all(np.diff(s.max_pressure_MPa[j]) < 0), s.max_pressure_MPa
        assert np.all(np.diff(s.depth_mm[j]) < 0), s.depth_mm
    assert np.all(s.contact_area_mm2[1] > s.contact_area_mm2[0])            # more force, wider
    d = cylinder_series(exp, "m43338", codes, depths_mm=[1.0])
    np.testing.assert_allclose(d.depth_mm, 1.0, rtol=1e-9)
    assert np.all(np.diff(d.contact_area_mm2[0]) > 0) and np.all(np.diff(d.force_N[0]) > 0)
    x10 = cylinder_series(exp, "m54449", codes, forces_N=[0.01, 0.02])
    np.testing.assert_allclose(x10.contact_area_mm2, s.contact_area_mm2, rtol=1e-6)
    np.testing.assert_allclose(x10.max_pressure_MPa, 10 * s.max_pressure_MPa, rtol=1e-5)
    with pytest.raises(InputError, match="unknown cylinder"):
        cylinder_series(exp, "m43338", ["C9"], forces_N=[0.001])


# --------------------------------------------------------------------------- commands
def test_study_layers_and_fit_material_commands(section, exp, tmp_path):
    import json

    truth = np.array([4.0, 3.0, 3.4, 3.0, 8.0])
    lines = ["# synthetic: model-generated (m4 3 3.4 3 8, coarse monkey section), no noise",
             "distance_mm,deflection_mm,depth_mm"]
    for p in exp.profiles(truth, [1.0, 2.0]):
        lines += [f"{d:.2f},{w:.6f},{p.depth_mm:g}" for d, w in zip(np.arange(0.2, 3.0, 0.2), p.at(np.arange(0.2, 3.0, 0.2)))]
    csv = write_csv(tmp_path, "\n".join(lines) + "\n")
    fcsv = write_csv(tmp_path, "depth_mm,force_N\n0.5,0.004\n1.0,0.01\n", "force.csv")
    out = tmp_path / "study"
    assert pipeline.main(["study-layers", str(section), "--depth", "2.0", "--layers", "1,3",
                          "--deflection", str(csv), "--out", str(out), "--quiet"]) == 0
    rep = json.loads((out / "layer_study.json").read_text())
    assert rep["layers"] == {"1": ["m33338", "m43338", "m53338"], "3": ["m43238", "m43338", "m43438"]}
    assert {p.name for p in out.iterdir()} == {"layer_study.csv", "layer_study.json", "layer_study.png",
                                               "profile.png"}
    out = tmp_path / "fit"
    assert pipeline.main(["fit-material", str(section), "--deflection", str(csv), "--free-layers", "3",
                          "--force", str(fcsv), "--out", str(out), "--quiet"]) == 0
    rep = json.loads((out / "fit.json").read_text())
    assert rep["deflection_fit"]["continuous_log10_Pa"][2] == pytest.approx(3.4, abs=0.01)
    assert rep["deflection_fit"]["best_code"] == "m43338"
    assert rep["force_fit"]["scale"] > 0 and rep["force_fit"]["indentor"] == "plate"
    assert (out / "fit_profiles.png").is_file() and (out / "force_fit.png").is_file()


def test_line_load_and_contact_series_commands(section, tmp_path):
    import json

    out = tmp_path / "ll"
    assert pipeline.main(["line-load", str(section), "--depth", "0.05,0.4", "--large-deformation", "--step", "0.2",
                          "--out", str(out), "--quiet"]) == 0
    rep = json.loads((out / "line_load.json").read_text())
    assert {p.name for p in out.iterdir()} == {"line_load.csv", "line_load.json", "line_load.png"}
    assert rep["material"] == "m43338" and not rep["failed"] and rep["slip"] is False
    ratio = np.array(rep["force_nonlinear_N"]) / np.array(rep["force_linear_N"])
    assert abs(ratio[0] - 1) < 0.01 and ratio[1] > ratio[0]                  # parts with depth
    out = tmp_path / "cs"
    assert pipeline.main(["contact-series", str(section), "--depth", "0.5", "--cylinders", "C2,C6",
                          "--out", str(out), "--quiet"]) == 0
    rep = json.loads((out / "cylinder_series.json").read_text())
    assert rep["codes"] == ["C2", "C6"] and rep["contact_area_mm2"][0][1] > rep["contact_area_mm2"][0][0]
    assert (out / "cylinder_series.png").is_file() and (out / "cylinder_series.csv").is_file()


@pytest.mark.parametrize("args, message", [
    (["study-layers", "{model}", "--base", "m4333"], "has 4 digits"),
    (["fit-material", "{model}", "--deflection", "{empty}"], "no data rows"),
    (["fit-material", "{model}", "--deflection", "{unsorted}"], "not increasing"),
    (["fit-material", "{model}"], "needs --deflection"),
    (["fit-material", "{model}", "--force", "{empty}"], "no data rows"),
    (["line-load", "{model}", "--depth", "0,1"], "give positive values"),
    (["line-load", "{model}", "--depth", "1", "--step", "0"], "--step: must be finite and > 0"),
    (["line-load", "{model}", "--material", "m433380"], "has 6 digits"),
    (["line-load", "{model}", "--depth", "a:b"], "bad value list"),
    (["contact-series", "{model}"], "needs --force or --depth"),
    (["contact-series", "{model}", "--force", "0.001", "--depth", "1"], "needs --force or --depth"),
    (["contact-series", "{model}", "--depth", "1", "--cylinders", "C1,X2"], "unknown cylinder"),
    (["contact-series", "{model}", "--force", "0.001", "--material", "m43"], "has 2 digits"),
])
def test_bad_input_one_line_exit_2(section, tmp_path, capsys, args, message):
    empty = write_csv(tmp_path, "", "empty.csv")
    unsorted = write_csv(tmp_path, "0.5,1,2\n0.2,1.5,2\n", "unsorted.csv")
    out = tmp_path / "out"
    argv = [a.format(model=section, empty=empty, unsorted=unsorted) for a in args] + ["--out", str(out)]
    assert pipeline.main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: ") and message in err and "\n" not in err
    assert not out.exists()
