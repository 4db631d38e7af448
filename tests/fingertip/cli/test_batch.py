"""`pipeline.py batch`: a cohort of three small 2D subjects in this process and on Dask
(`--scheduler local:2`, an existing cluster whose worker is killed mid-run), failures per subject,
and the one-line errors (bad subjects, Dask missing) that write nothing."""
import json
import operator
import os
import signal
import sys
import threading
import time

import numpy as np
import pytest

import pipeline
from fingertip.jobs.batch import MeshOptions, parse_subjects, run_batch
from tests.helpers import csv_rows

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
depth_mm = 0.5
"""
SUBJECTS = ["preset:cylinder8", "preset:cylinder8:bone", "preset:square"]
MESH = ["--size", "0.25"]


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    path = tmp_path_factory.mktemp("scene") / "tiny.toml"
    path.write_text(SCENE)
    return path


@pytest.fixture(scope="module")
def serial(tmp_path_factory, scene):
    """The serial run (--scheduler none) every parallel run must reproduce byte for byte."""
    out = tmp_path_factory.mktemp("serial") / "cohort"
    assert pipeline.main(["batch", *SUBJECTS, "--scene", str(scene), "--out", str(out), *MESH, "--quiet"]) == 0
    return out


def test_serial_summary_compares_the_subjects(serial):
    rows = csv_rows(serial / "summary.csv")
    assert [r["subject"] for r in rows] == ["cylinder8"] * 5 + ["cylinder8_bone"] * 5 + ["square"] * 5
    assert all(r["error"] == "" for r in rows)
    assert {"peak_sed_MPa", "peak_max_compressive_strain", "max_pressure_MPa", "peak_pressure_MPa", "contact_area_mm2"} <= set(rows[0])
    force = {(r["subject"], r["experiment"], float(r["depth_mm"])): float(r["force_N"]) for r in rows}
    for subject in ("cylinder8", "cylinder8_bone", "square"):
        curve = [force[(subject, "C5", d)] for d in (0.25, 0.5, 0.75, 1.0)]
        assert np.all(np.diff(curve) > 0) and curve[0] > 0          # deeper presses harder
    # the rigid bone 2 mm under the centre stiffens the 8 mm cylinder: more force at every depth
    for d in (0.25, 0.5, 0.75, 1.0):
        assert force[("cylinder8_bone", "C5", d)] > 1.05 * force[("cylinder8", "C5", d)]
    assert (serial / "cohort.png").stat().st_size > 10_000
    for subject in ("cylinder8", "cylinder8_bone", "square"):
        assert (serial / subject / "mesh.vtu").is_file() and (serial / subject / "tiny" / "run.json").is_file()


def test_local_cluster_gives_the_serial_bytes(tmp_path, scene, serial):
    pytest.importorskip("distributed")
    out = tmp_path / "cohort"
    assert pipeline.main(["batch", *SUBJECTS, "--scene", str(scene), "--out", str(out), *MESH,
                          "--scheduler", "local:2", "--quiet"]) == 0
    assert (out / "summary.csv").read_bytes() == (serial / "summary.csv").read_bytes()
    for subject in ("cylinder8", "cylinder8_bone", "square"):
        assert (out / subject / "tiny" / "C5.csv").read_bytes() == (serial / subject / "tiny" / "C5.csv").read_bytes()


@pytest.fixture(scope="module")
def cluster():
    """An existing two-worker cluster (reached by its tcp:// address) on which a task may lose one worker."""
    distributed = pytest.importorskip("distributed")
    import dask

    with dask.config.set({"distributed.scheduler.allowed-failures": 1}), \
            distributed.LocalCluster(n_workers=2, threads_per_worker=1, dashboard_address=None) as c:
        yield c


def test_killed_worker_is_retried_and_the_run_completes(tmp_path, scene, serial, cluster):
    killed = {}

    def kill_first_busy_worker():
        """SIGKILL the worker process of the first subject task seen running (the scheduler's own
        view: no second client in this process)."""
        deadline = time.monotonic() + 60
        while not killed and time.monotonic() < deadline:
            for address, ws in list(cluster.scheduler.workers.items()):
                keys = [str(ts.key) for ts in list(ws.processing)]
                if any("run_subject" in k for k in keys):
                    time.sleep(0.2)                         # the task has started on that worker
                    os.kill(ws.pid, signal.SIGKILL)
                    killed[address] = keys
                    return
            time.sleep(0.02)

    watcher = threading.Thread(target=kill_first_busy_worker, daemon=True)
    watcher.start()
    out = tmp_path / "cohort"
    text = run_batch(parse_subjects(SUBJECTS), scene, out, MeshOptions(sizes={"size_mm": 0.25}),
                     scheduler=cluster.scheduler_address, progress=False)
    watcher.join()
    assert killed, "no worker was busy with a subject to kill"
    assert "0 failed" in text
    assert (out / "summary.csv").read_bytes() == (serial / "summary.csv").read_bytes()


def test_a_task_that_keeps_killing_workers_is_reported(cluster):
    from fingertip.distribute import TaskFailed, TaskRunner, parse_scheduler

    with TaskRunner(parse_scheduler(cluster.scheduler_address), retries=0) as runner:
        results = runner.map(operator.call, [(abs, -2), (abs, -5), (os._exit, 3)])
    assert results[:2] == [2, 5], results
    assert isinstance(results[2], TaskFailed) and "KilledWorker" in str(results[2])


def test_a_failing_subject_is_reported_and_the_others_go_on(tmp_path, scene, serial):
    bad = tmp_path / "broken"
    bad.mkdir()
    (bad / "sections.json").write_text("{not json")
    out = tmp_path / "cohort"
    assert pipeline.main(["batch", "preset:square", str(bad), "--scene", str(scene), "--out", str(out),
                          *MESH, "--quiet"]) == 0
    rows = csv_rows(out / "summary.csv")
    square = [r for r in rows if r["subject"] == "square"]
    assert [r["error"] for r in square] == [""] * 5
    assert square == [r for r in csv_rows(serial / "summary.csv") if r["subject"] == "square"]
    (failed,) = [r for r in rows if r["subject"] == "broken"]
    assert "sections.json" in failed["error"] and "\n" not in failed["error"]
    assert failed["force_N"] == "" and failed["experiment"] == ""


def test_without_dask_local_scheduler_says_how_to_install(tmp_path, scene, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)          # import distributed -> ImportError
    out = tmp_path / "cohort"
    assert pipeline.main(["batch", "preset:square", "--scene", str(scene), "--out", str(out),
                          "--scheduler", "local:2"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error: ") and 'pip install -e ".[dask]"' in err[0]
    assert not out.exists()


@pytest.mark.parametrize("words, says", [
    (["preset:nope"], "unknown preset"),
    (["preset:square:bone"], ":bone"),
    (["no/such/folder"], "does not exist"),
    (["preset:square", "preset:square"], "both named"),
    (["preset:square", "--scheduler", "local:0"], "at least one worker"),
    (["preset:square", "--scheduler", "somewhere"], "tcp://HOST:PORT"),
    (["preset:square", "--size", "0"], "--size"),
])
def test_bad_input_is_one_line_and_writes_nothing(tmp_path, scene, capsys, words, says):
    out = tmp_path / "cohort"
    assert pipeline.main(["batch", *words, "--scene", str(scene), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error: ") and says in err[0]
    assert not out.exists()


@pytest.mark.slow
def test_3d_batch_meshes_again_on_dask_and_gives_the_same_bytes_as_in_process(tmp_path, scene):
    """Trust issue: `batch ... preset:monkey --force` on a two-worker Dask cluster meshes the 3D
    preset anew in a worker process; with the reproducible mesher it writes the same mesh and the
    same summary, byte for byte, as the in-process run on the mesh this test process made (or
    found in the mesh cache: the coarse 1.5 mm monkey, the tiny scene)."""
    pytest.importorskip("distributed")
    runs = {}
    for name, extra in (("serial", []), ("dask", ["--scheduler", "local:2", "--force"])):
        out = tmp_path / name
        assert pipeline.main(["batch", "preset:monkey", "--scene", str(scene), "--out", str(out), "--size", "1.5",
                              "--quiet", *extra]) == 0
        runs[name] = out
    assert (runs["serial"] / "summary.csv").read_bytes() == (runs["dask"] / "summary.csv").read_bytes()
    assert (runs["serial"] / "monkey" / "mesh.vtu").read_bytes() == (runs["dask"] / "monkey" / "mesh.vtu").read_bytes()
    assert [r["error"] for r in csv_rows(runs["serial"] / "summary.csv")] == [""] * 5
    assert json.loads((runs["dask"] / "monkey" / "model.json").read_text())["mesh"]["from_cache"] is False
