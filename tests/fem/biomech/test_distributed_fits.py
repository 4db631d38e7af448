"""`--scheduler` on study-layers, fit-material (one task per trial material) and indent (one task
per experiment of a scene): a local Dask cluster gives the serial run's numbers, and the
refusals (bad scheduler, Dask missing) are one line that writes nothing."""
import csv
import json
import sys

import numpy as np
import pytest

import pipeline
from fem.biomech.deflection import DeflectionExperiment
from fingertip.jobs.tasks import task_threads


@pytest.fixture(scope="module")
def section_profiles(section, tmp_path_factory):
    """The coarse five-layer 2D monkey section (this module's copy, tests/conftest.py), and
    measured-like profiles made by the model (layer 3 at 10^3.4 Pa) at 1 and 2 mm."""
    root = tmp_path_factory.mktemp("dfits")
    dist = np.arange(0.2, 3.0, 0.2)
    lines = ["distance_mm,deflection_mm,depth_mm"]
    for p in DeflectionExperiment(section).profiles([4.0, 3.0, 3.4, 3.0, 8.0], [1.0, 2.0]):
        lines += [f"{d:.2f},{w:.6f},{p.depth_mm:g}" for d, w in zip(dist, p.at(dist))]
    (root / "defl.csv").write_text("\n".join(lines) + "\n")
    return section, root / "defl.csv"


def _json(path) -> dict:
    """A JSON report without its timings and its own output path."""
    data = json.loads(path.read_text())
    data.pop("seconds", None)
    return data


def _both(tmp_path, words):
    """Runs the command with --scheduler none and local:2; returns the two output folders."""
    pytest.importorskip("distributed")
    outs = []
    for sched in ("none", "local:2"):
        out = tmp_path / sched.replace(":", "")
        assert pipeline.main([*words, "--out", str(out), "--scheduler", sched, "--quiet"]) == 0
        outs.append(out)
    return outs


def test_study_layers_on_a_local_cluster_gives_the_serial_numbers(section_profiles, tmp_path):
    model, _ = section_profiles
    serial, parallel = _both(tmp_path, ["study-layers", str(model), "--depth", "1,2", "--layers", "1,3"])
    assert (serial / "layer_study.csv").read_bytes() == (parallel / "layer_study.csv").read_bytes()
    a, b = _json(serial / "layer_study.json"), _json(parallel / "layer_study.json")
    assert a == b and a["distinct_moduli_ratios_solved"] == 5          # m33338 .. m43438, one solve each
    with open(serial / "layer_study.csv", newline="") as fh:
        assert len({row["code"] for row in csv.DictReader(fh)}) == 5


def test_fit_material_on_a_local_cluster_follows_the_serial_trajectory(section_profiles, tmp_path):
    model, defl = section_profiles
    serial, parallel = _both(tmp_path, ["fit-material", str(model), "--deflection", str(defl),
                                        "--free-layers", "2,3"])
    a, b = _json(serial / "fit.json"), _json(parallel / "fit.json")
    assert a == b                       # same optimum, Jacobian, evaluation counts, rounding codes
    assert a["deflection_fit"]["continuous_log10_Pa"][1:3] == pytest.approx([3.0, 3.4], abs=0.01)
    assert a["deflection_fit"]["optimizer_evaluations"] >= 2
    assert (serial / "fit_profiles.csv").read_bytes() == (parallel / "fit_profiles.csv").read_bytes()


SCENE = """\
[receptors]
depths_mm = [0.5, 1.0]
spacing_mm = 1.0

[output]
plots = false
pvd = false

[[experiment]]
name = "C5"
indentor = "C5"
depth_mm = "0.25:1:0.25"

[[experiment]]
name = "bar"
indentor = "bar:1.5"
force_N = 0.002
"""


def test_indent_scene_with_two_experiments_on_a_local_cluster(tmp_path):
    pytest.importorskip("distributed")
    model = tmp_path / "cyl8"
    assert pipeline.main(["mesh", "--preset", "cylinder8", "--bone", "--out", str(model), "--quiet"]) == 0
    scene = tmp_path / "two.toml"
    scene.write_text(SCENE)
    serial, parallel = tmp_path / "serial", tmp_path / "parallel"
    with task_threads():                # the threads of the tasks, so that the sums are the same
        assert pipeline.main(["indent", str(model), "--scene", str(scene), "--out", str(serial), "--quiet"]) == 0
    assert pipeline.main(["indent", str(model), "--scene", str(scene), "--out", str(parallel), "--quiet",
                          "--scheduler", "local:2"]) == 0
    names = sorted(p.name for p in serial.iterdir())
    assert names == sorted(p.name for p in parallel.iterdir()) and len(names) == 7
    for name in names:                  # every byte: each experiment is observed in its own block solve
        if name != "run.json":          # in both runs, as a task does
            assert (serial / name).read_bytes() == (parallel / name).read_bytes(), name
    a, b = _json(serial / "run.json"), _json(parallel / "run.json")
    assert a == b


@pytest.mark.parametrize("command", ["study-layers", "fit-material", "indent"])
def test_scheduler_refusals_are_one_line_and_write_nothing(section_profiles, tmp_path, capsys, monkeypatch, command):
    model, defl = section_profiles
    extra = {"study-layers": [], "fit-material": ["--deflection", str(defl)],
             "indent": ["--indentor", "C5", "--depth", "0.5"]}[command]
    out = tmp_path / "out"
    assert pipeline.main([command, str(model), *extra, "--out", str(out), "--scheduler", "local:0"]) == 2
    assert "at least one worker" in capsys.readouterr().err
    monkeypatch.setitem(sys.modules, "distributed", None)          # import distributed -> ImportError
    assert pipeline.main([command, str(model), *extra, "--out", str(out), "--scheduler", "local:2"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and 'pip install -e ".[dask]"' in err[0]
    assert not out.exists()
