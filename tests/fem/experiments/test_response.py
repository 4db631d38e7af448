"""Stored response models (fem.experiments.response): the same forces, deflections and receptor measures as
the factorised path, keys that follow every input, corrupt files rebuilt, and `prepare` + `indent`."""
import csv
import json
import logging
from pathlib import Path

import numpy as np
import pytest

import pipeline
from fem.core import inverse
from fem.experiments.response import STORED_RTOL, ResponseStore, response_key
from fem.experiments.runner import run_experiments
from fem.experiments.scene import Scene
from fem.io.modelfolder import read_model
from tests.helpers import ROOT

RTOL = STORED_RTOL
"""Stored against factorised: both solve the same linear system, once by a Schur complement of a
subset and solves, once by a stored matrix product whose rows are rounded to a step of 1e-9 (WT) and
5e-8 (RT) of their largest value; the budget the docs state for it."""


@pytest.fixture(scope="module")
def monkey(tmp_path_factory):
    """The 3D monkey preset with 1.5 mm elements (this module's own)."""
    out = tmp_path_factory.mktemp("models") / "monkey"
    assert pipeline.main(["mesh", "--preset", "monkey", "--size", "1.5", "--out", str(out), "--quiet"]) == 0
    return out


def _rel(a, b):
    return np.abs(np.asarray(a) - np.asarray(b)).max() / max(np.abs(np.asarray(a)).max(), 1e-300)


def _both(folder, scene):
    """(factorised SceneRun, first stored SceneRun (built), repeat stored SceneRun)."""
    runs = []
    for store in (None, ResponseStore(folder), ResponseStore(folder)):
        model, info = read_model(folder, scene.material, scene.nu)
        runs.append(run_experiments(model, info, scene, store=store))
    return runs


def _assert_same(ref, run):
    for (_, a), (_, b) in zip(ref.experiments[0].steps, run.experiments[0].steps, strict=True):
        assert a.total_force_N > 0
        assert _rel(a.force_N, b.force_N) < RTOL
        assert _rel(a.deflection_mm, b.deflection_mm) < RTOL
        assert _rel(a.observed, b.observed) < RTOL
        ma, mb = ref.sampler.measures(a.observed, ref.measures), run.sampler.measures(b.observed, run.measures)
        for name in ref.measures:
            assert _rel(ma[name], mb[name]) < RTOL, name


@pytest.mark.parametrize("which, indentor, depth, orientation", [
    ("cyl8", "C5", "0.25:1:0.25", "parallel"),
    ("monkey", "C5", "0.5:1.5:0.5", "perpendicular")])
def test_stored_equals_factorised(which, indentor, depth, orientation, request):
    folder = request.getfixturevalue(which)
    scene = Scene.from_dict({"experiment": [{"name": indentor, "indentor": indentor, "orientation": orientation,
                                             "depth_mm": depth}]})
    ref, first, repeat = _both(folder, scene)
    assert ref.responses == [] and first.responses[0][1] == "built" and repeat.responses[0][1] == "stored"
    assert first.responses[0][0] == repeat.responses[0][0]
    assert repeat.sampler.operator is None            # nothing but the stored matrices answered
    _assert_same(ref, first)
    _assert_same(ref, repeat)
    for (_, a), (_, b) in zip(first.experiments[0].steps, repeat.experiments[0].steps):
        assert np.array_equal(a.force_N, b.force_N) and np.array_equal(a.observed, b.observed)
    # the store holds displacement and strain only; the stress rows the runs compared were
    # completed from them (3D 9 of 15 values per receptor point, 2D 5 of 9)
    rm = ResponseStore(folder).load(first.responses[0][0])
    n, dim = len(rm.lame_MPa), ref.sampler.dim
    assert rm.RT.shape[1] == ref.sampler.independent == n * (9 if dim == 3 else 5)
    assert len(ref.experiments[0].steps[-1][1].observed) == n * (15 if dim == 3 else 9)


def test_key_follows_inputs(cyl8):
    from fem.io.modelfolder import CONTACT_REGION, receptor_surface
    from fem.receptors.grid import receptor_grid

    def key(material=None, nu=None, approach=(0, -1, 0), depths=(0.5, 0.75, 1.0), spacing=1.0):
        model, _ = read_model(cyl8, material, nu)
        sn = model.surface_nodes(CONTACT_REGION[2])
        grid = receptor_grid(*receptor_surface(model, sn), depths, spacing)
        return response_key(model, np.asarray(approach, float), grid, "mesh")

    base = key()
    assert key() == base
    assert key(approach=(0, -2, 0)) == base                  # the same direction
    others = [key(material="m43338"), key(nu=0.45), key(approach=(0.1, -1, 0)), key(depths=(0.5, 1.0)),
              key(spacing=0.5)]
    assert len({base, *others}) == 6
    model, _ = read_model(cyl8)
    sn = model.surface_nodes(CONTACT_REGION[2])
    grid = receptor_grid(*receptor_surface(model, sn))
    assert response_key(model, np.array([0, -1.0, 0]), grid, "other mesh") != base.replace("x", "")


@pytest.mark.parametrize("damage", ["truncate", "json"])
def test_corrupt_store_is_rebuilt(cyl8, damage, caplog):
    scene = Scene.from_dict({"experiment": [{"name": "C5", "indentor": "C5", "depth_mm": "0.5"}]})
    model, info = read_model(cyl8)
    first = run_experiments(model, info, scene, store=ResponseStore(cyl8))
    key = first.responses[0][0]
    obs = first.experiments[0].steps[0][1].observed.copy()
    del first                                   # its memory maps: a file truncated in place is not readable
    folder = ResponseStore(cyl8).path(key)
    if damage == "truncate":
        data = (folder / "RT.rows").read_bytes()
        (folder / "RT.rows").unlink()
        (folder / "RT.rows").write_bytes(data[:len(data) // 2])
    else:
        (folder / "response.json").write_text("{not json")
    with caplog.at_level(logging.WARNING, "fem.experiments.response"):
        again = run_experiments(model, info, scene, store=ResponseStore(cyl8))
    assert "unreadable" in caplog.text
    assert again.responses[0][:2] == (key, "built")
    assert ResponseStore(cyl8).load(key) is not None
    assert _rel(obs, again.experiments[0].steps[0][1].observed) < RTOL


def test_first_indent_stores_the_second_answers_and_a_read_only_folder_factorises(tmp_path, capsys, monkeypatch):
    """No command of its own: the first indent builds the store, the second answers from it with the
    same files; a model folder that cannot be written is factorised and keeps nothing."""
    folder = tmp_path / "cyl8"
    assert pipeline.main(["mesh", "--preset", "cylinder8", "--bone", "--out", str(folder), "--quiet"]) == 0
    argv = ["indent", str(folder), "--indentor", "C5", "--depth", "0.5", "--no-plots"]
    assert pipeline.main([*argv, "--out", str(tmp_path / "first")]) == 0
    assert "response model: built" in capsys.readouterr().out and (folder / "response").is_dir()
    assert pipeline.main([*argv, "--out", str(tmp_path / "second")]) == 0
    assert "response model: stored" in capsys.readouterr().out
    for name in ("C5.csv", "C5_surface.csv", "C5_receptors.csv"):
        assert (tmp_path / "first" / name).read_bytes() == (tmp_path / "second" / name).read_bytes()
    locked = tmp_path / "locked"                # a folder this user cannot write (root writes anyway)
    assert pipeline.main(["mesh", "--preset", "cylinder8", "--bone", "--out", str(locked), "--quiet"]) == 0
    monkeypatch.setattr("fingertip.jobs.indent.os.access", lambda path, mode: Path(path) != locked)
    assert pipeline.main(["indent", str(locked), *argv[2:], "--out", str(tmp_path / "third")]) == 0
    assert "response model" not in capsys.readouterr().out and not (locked / "response").exists()
    forces = [float(next(csv.DictReader(open(tmp_path / run / "C5.csv")))["force_N"]) for run in ("first", "third")]
    assert forces[0] == pytest.approx(forces[1], rel=STORED_RTOL)


def test_prepare_then_indent(cyl8, tmp_path, capsys):
    assert pipeline.main(["prepare", str(cyl8), "--material", "m43338", "--receptor-spacing", "0.5",
                          "--quiet"]) == 0
    assert pipeline.main(["prepare", str(cyl8), "--material", "m43338", "--receptor-spacing", "0.5"]) == 0
    captured = capsys.readouterr()
    assert "response model stored" in captured.out and "201 contact candidates" in captured.out
    assert "factorising" not in captured.err
    key = next(p.name for p in (cyl8 / "response").iterdir() if p.name in captured.out)
    out = tmp_path / "run"
    assert pipeline.main(["indent", str(cyl8), "--indentor", "C5", "--depth", "0.5,1", "--material", "m43338",
                          "--receptor-spacing", "0.5", "--no-pvd", "--out", str(out)]) == 0
    captured = capsys.readouterr()
    assert f"response model: stored {key}" in captured.out
    assert "factorising" not in captured.err
    # the factorised path writes the same numbers, within the stored model's budget of each column's largest
    ref = tmp_path / "ref"
    assert pipeline.main(["indent", str(cyl8), "--indentor", "C5", "--depth", "0.5,1", "--material", "m43338",
                          "--receptor-spacing", "0.5", "--pvd", "--out", str(ref), "--quiet"]) == 0
    assert (ref / "C5.pvd").is_file() and not (out / "C5.pvd").exists()
    for name in ("C5.csv", "C5_surface.csv", "C5_receptors.csv"):
        with open(out / name) as a, open(ref / name) as b:
            ra, rb = list(csv.reader(a)), list(csv.reader(b))
        assert ra[0] == rb[0] and len(ra) == len(rb)
        skip = {ra[0].index(c) for c in ("penetration_mm", "tensile_N", "complementarity_Nmm") if c in ra[0]}
        for j, column in enumerate(ra[0]):
            if j in skip or column == "kkt_ok":
                continue
            u, v = (np.array([float(r[j]) for r in rows[1:]]) for rows in (ra, rb))
            assert np.abs(u - v).max() <= STORED_RTOL * np.abs(v).max(), (name, column)
    stored, factorised = (json.loads((f / "run.json").read_text()) for f in (out, ref))
    va, vb = (r["experiments"][0].pop("validity") for r in (stored, factorised))
    assert stored == factorised
    # the linear range: the same receptor strains; only the factorised run has the full field
    assert va.pop("max_receptor_strain") == pytest.approx(vb.pop("max_receptor_strain"), rel=STORED_RTOL)
    assert (va.pop("inverted_elements"), va.pop("inversion_checked")) == (None, False)
    assert (vb.pop("inverted_elements"), vb.pop("inversion_checked")) == (0.0, True) and va == vb


def test_prepare_bad_approach(cyl8, capsys):
    assert pipeline.main(["prepare", str(cyl8), "--approach", "0,0,1"]) == 2
    assert "x-y plane" in capsys.readouterr().err


def test_mesh_hash_is_remembered_until_the_mesh_changes(cyl8, tmp_path, monkeypatch):
    """response/mesh.json spares a repeat run the second read of mesh.vtu; a new mesh file (new
    inode, size or time) is hashed again."""
    import shutil

    from fem.experiments import response

    folder = tmp_path / "copy"
    shutil.copytree(cyl8, folder, ignore=shutil.ignore_patterns("response", "indent_*"))
    store = ResponseStore(folder)
    (folder / "response").mkdir()
    sha = store.mesh_sha256()
    assert sha == response.mesh_sha256(folder)
    assert json.loads((folder / "response" / "mesh.json").read_text())["sha256"] == sha

    def no_read(_):
        raise AssertionError("mesh.vtu read again")

    monkeypatch.setattr(response, "mesh_sha256", no_read)
    assert ResponseStore(folder).mesh_sha256() == sha
    monkeypatch.undo()
    data = (folder / "mesh.vtu").read_bytes()
    (folder / "mesh.vtu").unlink()
    (folder / "mesh.vtu").write_bytes(data.replace(b"<VTKFile", b"<VTKFile ", 1))   # other bytes
    other = ResponseStore(folder).mesh_sha256()
    assert other != sha and other == response.mesh_sha256(folder)


def test_repeat_run_without_plots_imports_no_matplotlib(cyl8, tmp_path):
    """A stored model answers a --no-plots --no-pvd run: no PNG written, and neither matplotlib,
    fem.plots, the factorisation's PARDISO nor scipy.optimize (50 ms of a 0.6 s command) loaded."""
    import subprocess
    import sys

    assert pipeline.main(["prepare", str(cyl8), "--quiet"]) == 0
    out = tmp_path / "run"
    code = ("import sys, pipeline; assert pipeline.main(sys.argv[1:]) == 0; "
            "print(sorted(m for m in ('matplotlib', 'fem.plots', 'pypardiso', 'scipy.optimize') if m in sys.modules))")
    done = subprocess.run([sys.executable, "-c", code, "indent", str(cyl8), "--indentor", "C5", "--depth",
                           "0.25:1:0.25", "--no-pvd", "--no-plots", "--out", str(out), "--quiet"],
                          capture_output=True, text=True, cwd=ROOT, check=True)
    assert done.stdout.strip().splitlines()[-1] == "[]", done.stdout + done.stderr
    assert not list(out.glob("*.png")) and (out / "C5_receptors.csv").is_file()


def test_store_keeps_to_its_size_by_dropping_the_least_recently_used(cyl8, monkeypatch, caplog):
    import shutil

    import fem.experiments.response as response
    shutil.rmtree(cyl8 / "response", ignore_errors=True)      # earlier tests of this module stored models
    keys = []
    for material in ("m43338", "m33338", "m53338"):
        assert pipeline.main(["prepare", str(cyl8), "--material", material, "--quiet"]) == 0
        keys.append(max((p for p in (cyl8 / "response").iterdir() if p.is_dir()), key=lambda p: p.stat().st_mtime_ns).name)
    sizes = {k: json.loads((cyl8 / "response" / k / "response.json").read_text())["bytes"] for k in keys}
    store = ResponseStore(cyl8)
    assert store.load(keys[0]) is not None                  # used again: now the second is the oldest
    monkeypatch.setattr(response, "STORE_MAX_BYTES", sizes[keys[0]] + sizes[keys[2]])
    with caplog.at_level(logging.WARNING):
        store._evict(keep=keys[2])
    assert sorted(p.name for p in (cyl8 / "response").iterdir() if p.is_dir()) == sorted([keys[0], keys[2]])
    assert "used least recently" in caplog.text and keys[1][:12] in caplog.text


def test_a_store_holds_its_models_with_the_rows_read(cyl8, monkeypatch):
    """The explorer's answers: a store object loads a model once, and a row decoded for one contact
    problem is not decoded again for the next."""
    from fem.io.rows import RowFile

    scene = Scene.from_dict({"experiment": [{"name": "C5", "indentor": "C5", "depth_mm": "0.25:1:0.25"}]})
    model, info = read_model(cyl8)
    key = run_experiments(model, info, scene, store=ResponseStore(cyl8)).responses[0][0]
    decoded = []
    read = RowFile.__getitem__
    monkeypatch.setattr(RowFile, "__getitem__", lambda self, idx: decoded.append(len(idx)) or read(self, idx))
    store = ResponseStore(cyl8)
    first = run_experiments(model, info, scene, store=store)
    assert first.responses[0][:2] == (key, "stored") and sum(decoded) > 0
    assert store.load(key) is store.load(key) is not ResponseStore(cyl8).load(key)
    before = sum(decoded)
    again = run_experiments(model, info, scene, store=store)
    assert sum(decoded) == before
    for (_, a), (_, b) in zip(first.experiments[0].steps, again.experiments[0].steps, strict=True):
        assert np.array_equal(a.force_N, b.force_N) and np.array_equal(a.observed, b.observed)


@pytest.mark.skipif(not inverse.available(), reason="python-mumps is not installed (optional)")
def test_inverse_entries_build_the_rows_of_the_schur_path(monkey, monkeypatch):
    """The MUMPS path (`fem.core.inverse`, used from INVERSE_ENTRIES_FROM_DOFS unknowns) against the
    PARDISO path on the same model: equal within one rounding step of the stored rows, and the
    same bytes when built twice."""
    from fem.experiments import response
    from fem.experiments.runner import Receptors, receptor_grid, receptor_line, receptor_surface
    from fem.io.modelfolder import CONTACT_REGION, approach_down, folder_info
    from fem.receptors.grid import ReceptorSampler

    model, info = read_model(monkey, None, None)
    sn = model.surface_nodes(CONTACT_REGION[3])
    rec = Receptors()
    grid = receptor_grid(*receptor_surface(model, sn), np.asarray(rec.depths_mm, float), rec.spacing_mm,
                         receptor_line(rec.line, sn, 3))
    sampler, a = ReceptorSampler(model, grid), approach_down(folder_info(monkey))
    touched = np.zeros(len(sn.nodes), bool)
    touched[::3] = True                              # some candidates not condensed: WT's other columns
    built = {}
    for name, threshold in (("schur", 10**12), ("inverse", 0), ("again", 0)):
        monkeypatch.setattr(response, "INVERSE_ENTRIES_FROM_DOFS", threshold)
        built[name] = response.build_response(model, a, sampler, "key", touched)
    schur, inv = built["schur"], built["inverse"]
    assert np.array_equal(schur.reach, inv.reach) and inv.reach.sum() == touched.sum()
    assert _rel(schur.WT, inv.WT) <= response.WT_REL
    assert _rel(schur.RT, inv.RT) <= response.RT_REL
    assert np.array_equal(inv.WT, built["again"].WT) and np.array_equal(inv.RT, built["again"].RT)
