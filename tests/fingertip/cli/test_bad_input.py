"""Bad input ends with one `error:` line, exit code 2, no traceback, nothing written, before any
work (well under 2 s); a corrupt mesh cache entry is rebuilt; an interrupt ends with one line."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import pipeline
from fem.core import inverse
from tests.helpers import ROOT, cli, default_sigint, snapshot

DATA = ROOT / "data"
REFUSAL_S = 2.0          # the bound on a refusal: no meshing or factorising before it


def assert_refused(argv, watch, pattern=None):
    """argv ends with exactly one `error:` line on stderr (matching `pattern`), exit 2, no
    traceback, nothing new under `watch`, within REFUSAL_S."""
    before = snapshot(*watch)
    code, _, err, seconds = cli(*argv)
    lines = err.strip().splitlines()
    assert code == 2, (argv, code, err)
    assert len(lines) == 1 and lines[0].startswith("error: "), (argv, err)
    assert "Traceback" not in err
    assert snapshot(*watch) == before, argv
    assert seconds < REFUSAL_S, (argv, seconds)
    if pattern is not None:
        assert pattern in lines[0], lines[0]
    return lines[0]


@pytest.fixture(scope="module")
def work(tmp_path_factory):
    """A 2D cylinder8 model folder with a run folder of it, and an existing plain file."""
    base = tmp_path_factory.mktemp("bad_input")
    model = base / "cyl8"
    assert cli("mesh", "--preset", "cylinder8", "--bone", "--out", model, "--quiet")[0] == 0
    run = base / "run"
    assert cli("indent", model, "--indentor", "C5", "--depth", "0.5", "--out", run, "--quiet", "--no-pvd")[0] == 0
    afile = base / "a_file"
    afile.write_text("not a folder\n")
    return {"base": base, "model": model, "run": run, "file": afile}


def _commands(w, out):
    """Each subcommand with valid inputs and the output folder `out`."""
    m = w["model"]
    return {
        "mesh": ["mesh", "--preset", "cylinder8", "--out", out],
        "indent": ["indent", m, "--indentor", "C5", "--depth", "0.5", "--out", out],
        "study-layers": ["study-layers", m, "--out", out],
        "fit-material": ["fit-material", m, "--force", DATA / "synthetic_force_depth_plate.csv", "--out", out],
        "line-load": ["line-load", m, "--depth", "0.5", "--out", out],
        "contact-series": ["contact-series", m, "--force", "0.01", "--out", out],
        "analyze": ["analyze", w["run"], "--neural", DATA / "synthetic_sa1_gratings.csv", "--out", out],
    }


@pytest.mark.parametrize("command", ["mesh", "indent", "study-layers", "fit-material", "line-load",
                                     "contact-series", "analyze"])
def test_out_is_an_existing_file(work, command):
    line = assert_refused(_commands(work, work["file"])[command], [work["base"]], "existing file")
    assert "--out" in line


@pytest.mark.parametrize("command", ["mesh", "indent", "study-layers", "fit-material", "line-load",
                                     "contact-series", "analyze"])
def test_out_cannot_be_created(work, command):
    if not Path("/proc").is_dir():
        pytest.skip("needs /proc (a folder nobody can create entries in)")
    assert_refused(_commands(work, "/proc/x")[command], [work["base"]], "cannot be created")


def test_run_checks_every_stage_first(tmp_path):
    out = tmp_path / "X"
    assert_refused(["run", ROOT / "sample_images", "--out", out, "--size", "-1"], [tmp_path], "--size")
    assert not out.exists()


def test_run_checks_mesh_sizes_before_reconstructing(tmp_path):
    out = tmp_path / "X"
    assert_refused(["run", ROOT / "sample_images", "--out", out, "--size", "0.01"], [tmp_path], "size")
    assert not out.exists()


@pytest.mark.parametrize("flags, pattern", [
    (["--indentor", "C5", "--depth", "0.5", "--axis", "perpendicular"], "parallel"),
    (["--indentor", "C5", "--depth", "0.5", "--axis", "30"], "parallel"),
    (["--indentor", "C5", "--force", "0.02", "--max-depth", "-1"], "--max-depth"),
    (["--indentor", "C5", "--force", "-0.01"], "--force"),
    (["--indentor", "C5", "--force", "nan"], "--force"),
    (["--indentor", "wedge:abc", "--depth", "1"], "wedge half-angle"),
    (["--indentor", "two-point:x", "--depth", "1"], "two-point separation"),
    (["--indentor", "two-point:-1", "--depth", "1"], "two-point separation"),
    (["--indentor", "C5", "--depth", "-1"], "--depth must be finite and >= 0, got -1"),
    (["--indentor", "C5", "--depth", "0.5", "--axis", "sideways"], "orientation"),
    (["--indentor", "C5", "--depth", "0.5", "--material", "mXYZ"], "material code"),
    (["--indentor", "C5", "--depth", "0.5", "--nu", "0.7"], "Poisson"),
    (["--indentor", "C5", "--depth", "0.5", "--receptor-depths", "a,b"], "value list"),
    (["--indentor", "C5", "--depth", "0.5", "--sweep", "z=-1:1:0.5"], "sweep"),
])
def test_indent_refusals(work, flags, pattern):
    """Each refused before the model is factorised (under 2 s; factorising alone takes longer)."""
    assert_refused(["indent", work["model"], *flags, "--out", work["base"] / "o"], [work["base"]], pattern)


def test_indent_scene_types_checked_before_the_model(work, tmp_path):
    scene = tmp_path / "s.toml"
    scene.write_text('[[experiment]]\nindentor = "C5"\nforce_N = -1\n')
    assert_refused(["indent", work["model"], "--scene", scene], [work["base"]], "force_N")
    scene.write_text('[[experiment]]\nindentor = "C5"\ndepth_mm = "0.5"\nstart = "zero"\n')
    assert_refused(["indent", work["model"], "--scene", scene], [work["base"]], "unknown key")


@pytest.mark.parametrize("argv, pattern", [
    (["mesh", "--preset", "monkey", "--size", "-1"], "--size"),
    (["mesh", "--preset", "monkey", "--coarse", "0"], "--coarse"),
    (["mesh", "--preset", "monkey", "--epidermis", "nan"], "--epidermis"),
    (["mesh", "--preset", "monkey", "--size", "0.01"], "--size 0.01 mm is below 0.1 mm"),
    (["mesh", "--preset", "cylinder8", "--growth", "-2"], "--growth"),
    (["mesh", "--preset", "monkey", "--layer3-scale", "3"], "--layer3-scale"),
    (["study-layers", "{model}", "--depth", "-1"], "depths"),
    (["study-layers", "{model}", "--layers", "x"], "layers"),
    (["study-layers", "{model}", "--indentor", "wedge:abc"], "wedge"),
    (["fit-material", "{model}", "--force", "{data}/synthetic_force_depth_plate.csv", "--bounds", "7", "1"],
     "--bounds"),
    (["line-load", "{model}", "--step", "0"], "--step"),
    (["line-load", "{model}", "--material", "m4"], "--material m4 has 1 digit"),
    (["contact-series", "{model}", "--force", "0"], "forces"),
    (["contact-series", "{model}", "--depth", "1", "--cylinders", "C9"], "cylinder"),
    (["contact-series", "{model}", "--force", "0.01", "--axis", "diagonal"], "orientation"),
])
def test_option_refusals(work, argv, pattern):
    argv = [str(a).format(model=work["model"], data=DATA) for a in argv]
    out = work["base"] / "o"
    assert_refused([*argv, "--out", out], [work["base"]], pattern)


def _fake_tetrahedralize(model, sizing, threads=0, progress=None):
    """A deterministic stand-in for pytetwild: the tets of a coarse grid over the model's box."""
    import pyvista as pv

    v = model.vertices()
    lo, hi = v.min(0), v.max(0)
    grid = pv.ImageData(dimensions=(4, 4, 6), spacing=tuple((hi - lo) / (3, 3, 5)), origin=lo).to_tetrahedra()
    return np.asarray(grid.points, float), grid.cells_dict[10].astype(np.int64)


def test_corrupt_cache_entry_is_rebuilt(tmp_path, monkeypatch):
    from fem.geometry import mesh3d as mesh
    from fem.geometry.layered import model_from_args, params_for

    monkeypatch.setenv("FINGERTIP_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setattr(mesh, "tetrahedralize", _fake_tetrahedralize)
    model = model_from_args(None, "monkey", params_for("monkey"))
    sizing = mesh.Sizing(size_mm=1.5)
    first, info = mesh.build_mesh(model, sizing)
    entry = mesh.cache_dir() / f"{info['key']}.npz"
    assert not info["cached"] and entry.is_file() and info["warnings"] == []
    assert [p.name for p in entry.parent.iterdir()] == [entry.name]          # no temporary left
    entry.write_bytes(entry.read_bytes()[:200])                             # truncated
    with pytest.raises(mesh.CacheEntryError):
        mesh.read_cache_entry(entry)
    again, info = mesh.build_mesh(model, sizing)
    assert not info["cached"] and len(info["warnings"]) == 1 and "discarded" in info["warnings"][0]
    np.testing.assert_array_equal(again.points, first.points)
    np.testing.assert_array_equal(again.tets, first.tets)
    third, info = mesh.build_mesh(model, sizing)                            # the rebuilt entry is whole
    assert info["cached"] and info["warnings"] == []
    np.testing.assert_array_equal(third.tets, first.tets)


def test_cache_entry_of_wrong_arrays_is_refused(tmp_path):
    from fem.geometry import mesh3d as mesh

    path = tmp_path / "e.npz"
    np.savez(path, points=np.zeros((3, 3)), tets=np.array([[0, 1, 2, 7]]))
    with pytest.raises(mesh.CacheEntryError):
        mesh.read_cache_entry(path)


def test_internal_error_is_one_line(monkeypatch, tmp_path):
    """A bug (not bad input) ends with one line naming the variable that shows the traceback."""
    import fingertip.cli.mesh

    def boom(*args, **kwargs):
        raise RuntimeError("unexpected\nstate")

    monkeypatch.setattr(fingertip.cli.mesh, "mesh_folder", boom)
    monkeypatch.delenv(pipeline.DEBUG_ENV, raising=False)
    code, _, err, _ = cli("mesh", "--preset", "cylinder8", "--out", tmp_path / "m")
    assert code == 1 and err.count("\n") == 1 and err.startswith("error: internal error RuntimeError")
    assert "Traceback" not in err and pipeline.DEBUG_ENV in err
    monkeypatch.setenv(pipeline.DEBUG_ENV, "1")
    code, _, err, _ = cli("mesh", "--preset", "cylinder8", "--out", tmp_path / "m")
    assert code == 1 and "Traceback" in err and err.splitlines()[-1].startswith("error: internal error")


def _interrupt(argv, env, sig, ready, after_s):
    """Run the command, wait until ready() (at most 60 s) and after_s more, send sig -> (exit code,
    stderr, seconds from the signal to the exit)."""
    proc = subprocess.Popen([sys.executable, str(ROOT / "pipeline.py"), *map(str, argv)], cwd=ROOT, env=env,
                            preexec_fn=default_sigint,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 60
    while not ready() and time.monotonic() < deadline and proc.poll() is None:
        time.sleep(0.05)
    time.sleep(after_s)
    t0 = time.perf_counter()
    proc.send_signal(sig)
    out, err = proc.communicate(timeout=60)
    return proc.returncode, err, time.perf_counter() - t0


@pytest.mark.slow
@pytest.mark.parametrize("sig, code", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_interrupt_while_meshing(tmp_path, sig, code):
    """Ctrl-C or SIGTERM during pytetwild: one line within seconds, nothing in --out, no lock or
    partial folder beside it, and nothing in the mesh cache but the fixed-seed library (no entry
    a later run could read)."""
    cache = tmp_path / "cache"
    env = {**os.environ, "FINGERTIP_CACHE_DIR": str(cache)}
    out = tmp_path / "m"
    argv = ["mesh", "--preset", "monkey", "--size", "1.5", "--out", out, "--quiet"]
    # pytetwild runs once the fixed-seed library is in the cache (built just before it): then Ctrl-C
    rc, err, seconds = _interrupt(argv, env, sig, lambda: any((cache / "native").glob("*.so")), 1.0)
    assert rc == code, err
    assert err.strip().splitlines() == ["error: interrupted; nothing was written"]
    assert seconds < 5
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cache"]
    assert {p.relative_to(cache).parts[0] for p in cache.rglob("*") if p.is_file()} <= {"native"}


# --------------------------------------------------------------------------- escapes found by a user
@pytest.mark.parametrize("flags, pattern", [
    (["--depth", "30"], "--depth 30 mm is beyond the 3 mm of tissue over the bone of this model; give --depth up to 3"),
    (["--force", "0.01", "--max-depth", "4"], "--max-depth 4 mm is beyond the 3 mm of tissue"),
    (["--depth", "0.5", "--receptor-depths", "50"], "--receptor-depths 50 mm is not inside the 3 mm of tissue"),
    (["--depth", "0:inf:1"], "finite"),
    (["--depth", "0:1e12:1"], "1000000000001 values, more than the 100000"),
    (["--depth", "0:3:1e-6"], "3000001 values"),
    (["--depth", "0.5", "--sweep", "x=0:inf:1"], "finite"),
    (["--depth", "0.5", "--receptor-depths", "1,nan"], "finite"),
    (["--depth", "0:3:0.0001"], "30001 indentations, more than --max-indentations 10000"),
    (["--depth", "0:1:0.01", "--sweep", "x=-1:1:0.01", "--max-indentations", "100"],
     "20301 indentations, more than --max-indentations 100"),
    (["--depth", "0.5", "--max-indentations", "0"], "--max-indentations"),
])
def test_indent_value_refusals(work, flags, pattern):
    """Depths beyond the model's tissue and value lists that would overflow or run for hours:
    refused before the model is factorised, naming the flag."""
    assert_refused(["indent", work["model"], "--indentor", "C5", *flags, "--out", work["base"] / "o"],
                   [work["base"]], pattern)


def test_scene_file_messages_name_its_keys(work, tmp_path):
    """An experiment from a --scene file names the file's keys, not the flags."""
    scene = tmp_path / "s.toml"
    scene.write_text('[[experiment]]\nindentor = "C5"\ndepth_mm = 30\n')
    line = assert_refused(["indent", work["model"], "--scene", scene, "--out", work["base"] / "o"], [work["base"]],
                          "depth_mm 30 mm is beyond the 3 mm")
    assert "--depth" not in line
    scene.write_text('max_indentations = 5\n[[experiment]]\nindentor = "C5"\ndepth_mm = "0.5:3:0.5"\n')
    assert_refused(["indent", work["model"], "--scene", scene, "--out", work["base"] / "o"], [work["base"]],
                   "6 indentations, more than max_indentations 5")


def test_force_control_depth_limit_is_the_tissue(work, tmp_path):
    """Without --max-depth, force control stops at the tissue over the bone (3 mm on cylinder8)."""
    import json

    out = tmp_path / "f"
    assert cli("indent", work["model"], "--indentor", "C5", "--force", "0.002", "--out", out, "--quiet")[0] == 0
    loading = json.loads((out / "run.json").read_text())["experiments"][0]["loading"]
    assert loading["max_depth_mm"] == pytest.approx(3.0, abs=0.01)


@pytest.mark.parametrize("argv, pattern", [
    (["indent", "{model}", "--indentor", "C5", "--force", "1000"],
     "--force 1000 N/mm is not reached within the 3 mm of tissue over the bone"),
    (["indent", "{model}", "--indentor", "C5", "--force", "1000", "--max-depth", "2"],
     "not reached within --max-depth 2 mm (the force there is"),
    (["contact-series", "{model}", "--force", "100"], "--force 100 N/mm is not reached by C1"),
])
def test_force_not_reached_prints_only_its_line(work, argv, pattern):
    """Found after factorising, before any bar: without --quiet the error line is all stderr has,
    and the force there is a number, not a Python list."""
    argv = [str(a).format(model=work["model"]) for a in argv]
    before = snapshot(work["base"])
    code, out, err, _ = cli(*argv, "--out", work["base"] / "o")
    assert code == 2 and out == "", err
    assert err.count("\n") == 1 and err.startswith("error: ") and pattern in err, err
    assert "[" not in err and "Traceback" not in err
    assert snapshot(work["base"]) == before


def test_empty_out_is_refused_by_every_command(work, tmp_path, monkeypatch):
    """`--out ""` would write into the current folder."""
    monkeypatch.chdir(tmp_path)
    commands = {**_commands(work, ""), "reproduce": ["reproduce", "--out", ""],
                "render": ["render", "fingertip", "--out", ""], "reconstruct": ["reconstruct", "--out", ""],
                "run": ["run", "--out", ""], "batch": ["batch", "preset:cylinder8", "--scene", "bars", "--out", ""]}
    for argv in commands.values():
        assert_refused(argv, [tmp_path, work["base"]], "--out is empty")
    assert list(tmp_path.iterdir()) == []


def test_prepare_refuses_a_read_only_model_folder(work, monkeypatch):
    """prepare stores <model>/response/: a model folder it cannot write to is refused up front
    (root writes anywhere, so the probe is made to fail)."""
    import fingertip.staging

    real = fingertip.staging._writable
    monkeypatch.setattr(fingertip.staging, "_writable", lambda folder: real(folder) and folder != work["model"])
    line = assert_refused(["prepare", work["model"]], [work["base"]], "is not writable")
    assert str(work["model"]) in line and "response" not in line.split("not writable")[0]


@pytest.mark.skipif(os.geteuid() == 0, reason="root may write anywhere")
def test_prepare_refuses_a_read_only_model_folder_for_real(work):
    work["model"].chmod(0o555)
    try:
        assert_refused(["prepare", work["model"]], [work["base"]], "is not writable")
    finally:
        work["model"].chmod(0o755)


@pytest.mark.parametrize("argv, pattern", [
    (["mesh", "--preset", "monkey", "--size", "1e9"],
     "--size 1e+09 mm is larger than --coarse 3 mm (the default of 3D models); give --coarse at least as large "
     "as --size"),
    (["batch", "preset:cylinder8", "--scene", "bars", "--size", "1.5"],
     "subject 'cylinder8': --size 1.5 mm is larger than --coarse 1 mm (the default of 2D models)"),
    (["batch", "{file}", "--scene", "bars"], "is a file but not a sections.json"),
    (["reconstruct", "{file}"], "is a file, not a folder"),
    (["indent", "{file}", "--indentor", "C5", "--depth", "0.5"], "is a file"),
    (["analyze", "{file}", "--neural", "{data}/synthetic_sa1_gratings.csv"], "is a file, not an indentation"),
    (["contact-series", "{model}", "--depth", "30"], "--depth 30 mm is beyond the 3 mm of tissue"),
])
def test_messages_in_the_users_words(work, argv, pattern):
    argv = [str(a).format(model=work["model"], file=work["file"], data=DATA) for a in argv]
    line = assert_refused([*argv, "--out", work["base"] / "o"], [work["base"]], pattern)
    assert "_mm" not in line.replace("sections.json", ""), line


def test_output_folder_in_use_is_refused(work, tmp_path):
    """A second command on a folder another one is writing: one line naming the pid."""
    out = tmp_path / "run"
    holder = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(30)"])
    try:
        (tmp_path / ".run.lock").write_text(f"{holder.pid}\n")
        line = assert_refused(["indent", work["model"], "--indentor", "C5", "--depth", "0.5", "--out", out],
                              [work["base"]], f"is in use by another command (pid {holder.pid})")
        assert line.startswith(f"error: --out {out} is in use")
        assert not out.exists()
    finally:
        holder.kill()
        holder.wait()
    assert cli("indent", work["model"], "--indentor", "C5", "--depth", "0.5", "--out", out, "--quiet")[0] == 0
    assert not (tmp_path / ".run.lock").exists()                        # the dead holder's lock: taken over


def test_interrupted_reproduce_says_what_it_keeps(tmp_path, monkeypatch):
    """Ctrl-C in `reproduce` keeps the claims done (a rerun resumes them): the message says so."""
    import fingertip.cli.reproduce

    out = tmp_path / "thesis"

    def interrupted(folder, quick=False, progress=True):
        (out / "claims").mkdir(parents=True)
        for name in ("flamant", "cylinders"):
            (out / "claims" / f"{name}.json").write_text("[]")
        raise KeyboardInterrupt

    monkeypatch.setattr(fingertip.cli.reproduce, "run_reproduce", interrupted)
    code, _, err, _ = cli("reproduce", "--out", out, "--quick")
    assert code == 130
    assert err.strip().splitlines() == [f"error: interrupted; the 2 claims done are kept in {out} and a rerun "
                                        f"resumes them"]
    fresh = tmp_path / "fresh"
    monkeypatch.setattr(fingertip.cli.reproduce, "run_reproduce", lambda *a, **k: (_ for _ in ()).throw(
        KeyboardInterrupt))
    code, _, err, _ = cli("reproduce", "--out", fresh)
    assert code == 130 and err.strip() == "error: interrupted; nothing was written"


@pytest.mark.slow
def test_ctrl_c_while_factorising_acts_within_a_second(tmp_path):
    """Ctrl-C while the first `indent` factorises for its response model (monkey preset at 1 mm,
    68k DOFs: several seconds; MUMPS where python-mumps is installed, else PARDISO) ends the
    command within about a second, with the one interrupt line; a depth beyond the tissue over the
    bone (2.7 mm here) is refused before the factorisation."""
    import select

    model = tmp_path / "monkey"
    assert cli("mesh", "--preset", "monkey", "--size", "1.0", "--out", model, "--quiet").code == 0
    assert_refused(["indent", model, "--indentor", "C5", "--depth", "40", "--out", tmp_path / "o"], [tmp_path],
                   "--depth 40 mm is beyond the 2.66 mm of tissue over the bone")
    out = tmp_path / "run"
    proc = subprocess.Popen([sys.executable, str(ROOT / "pipeline.py"), "indent", str(model), "--indentor", "C5",
                             "--depth", "1", "--no-pvd", "--out", str(out)], cwd=ROOT, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, preexec_fn=default_sigint)
    seen, deadline = b"", time.monotonic() + 120
    while b"factorising" not in seen and time.monotonic() < deadline and proc.poll() is None:
        if select.select([proc.stderr], [], [], 1.0)[0]:
            seen += os.read(proc.stderr.fileno(), 4096)
    assert b"factorising" in seen, seen                      # its task line shows from its first second on
    time.sleep(0.5)
    t0 = time.perf_counter()
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    seconds = time.perf_counter() - t0
    assert proc.returncode == 130, err
    assert err.decode().strip().splitlines()[-1] == "error: interrupted; nothing was written"
    assert (b"DOFs (MUMPS)" in seen + err) == inverse.available(), seen + err
    assert seconds < 1.5, seconds                            # it took 4-21 s while PARDISO ran on
    assert not out.exists() and not [p for p in tmp_path.iterdir() if p.name.startswith(".")]
