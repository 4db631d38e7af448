"""`pipeline.py indent` on a 2D cylinder model with bone: outputs, scenes, bad input, thesis trends."""
import json

import numpy as np
import pytest

import pipeline
from fem.contact.indentors import make_indentor
from fem.contact.linear import ContactModel
from fem.io.modelfolder import open_model
from tests.helpers import ROOT, csv_rows


def test_depth_series_outputs(cyl8, tmp_path):
    out = tmp_path / "c5"
    assert pipeline.main(["indent", str(cyl8), "--indentor", "C5", "--depth", "0.25:1:0.25", "--pvd",
                          "--out", str(out), "--quiet"]) == 0
    rows = csv_rows(out / "C5.csv")
    depth = [float(r["depth_mm"]) for r in rows]
    force = [float(r["force_N"]) for r in rows]
    assert depth == [0.25, 0.5, 0.75, 1.0]
    assert all(b > a for a, b in zip(force, force[1:]))                  # stiffening with depth
    assert all(f2 / f1 > d2 / d1 for (d1, f1), (d2, f2) in zip(zip(depth, force), zip(depth[1:], force[1:])))
    assert all(r["kkt_ok"] == "True" for r in rows)
    assert all(float(r["penetration_mm"]) < 1e-8 for r in rows)
    for r in rows:       # a C5 contact a few mm wide: its mean < the peak over 1 mm < the nodal peak
        mean = float(r["force_N"]) / float(r["contact_width_mm"])
        assert mean < float(r["peak_pressure_MPa"]) < float(r["max_pressure_MPa"]), r
    assert json.loads((out / "run.json").read_text())["peak_pressure_radius_mm"] == 1.0
    for name in ("C5_surface.csv", "C5_receptors.csv", "C5.pvd", "C5_003.vtu", "C5_force.png",
                 "C5_profile.png", "C5_receptors.png"):
        assert (out / name).is_file(), name
    rec = csv_rows(out / "C5_receptors.csv")
    assert {"sed_MPa", "max_compressive_strain", "depth_mm"} <= set(rec[0])
    assert {float(r["depth_mm"]) for r in rec} == {0.5, 0.75, 1.0}


def test_scene_with_force_control_and_sweep(cyl8, tmp_path):
    scene = tmp_path / "s.toml"
    scene.write_text('[receptors]\ndepths_mm = [0.75]\nspacing_mm = 0.5\n\n'
                     '[[experiment]]\nname = "bar"\nindentor = "bar:1.5"\nforce_N = 0.002\n'
                     'sweep = "x=-1:1:0.5"\n')
    before = sorted((cyl8 / "response").iterdir()) if (cyl8 / "response").is_dir() else []
    out = tmp_path / "s"
    assert pipeline.main(["indent", str(cyl8), "--scene", str(scene), "--out", str(out), "--quiet"]) == 0
    rows = csv_rows(out / "bar.csv")
    assert [float(r["offset_x_mm"]) for r in rows] == [-1, -0.5, 0, 0.5, 1]
    np.testing.assert_allclose([float(r["force_N"]) for r in rows], 0.002, rtol=1e-5)
    d = [float(r["depth_mm"]) for r in rows]
    assert abs(d[0] - d[-1]) < 0.02 * d[2]                                # symmetric model
    assert not list(out.glob("*.pvd"))                                     # PVD only when asked
    assert len(sorted((cyl8 / "response").iterdir())) > len(before)         # the store was built


@pytest.mark.parametrize("args, message", [
    (["--indentor", "C9", "--depth", "1"], "unknown indentor"),
    (["--indentor", "C5", "--force", "50", "--max-depth", "1"], "not reached"),
    (["--indentor", "punch:1", "--depth", "1", "--sweep", "x=0:20:5"], "sweep position"),
    (["--indentor", "punch:1", "--depth", "1", "--position", "9", "0"], "never touches"),
    (["--indentor", "C5"], "--depth or --force"),
    (["--indentor", "C5", "--depth", "1", "--position", "1"], "give X Z in mm or top"),
])
def test_bad_input_one_line_exit_2_nothing_written(cyl8, tmp_path, capsys, args, message):
    out = tmp_path / "bad"
    assert pipeline.main(["indent", str(cyl8), *args, "--out", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error:") and message in err and "\n" not in err
    assert not out.exists()
    assert not list(tmp_path.glob(".bad*"))


def test_thesis_trend_cylinders_at_constant_force(cyl8):
    """Thesis 4.6: at constant force a larger cylinder gives a wider contact, a lower peak pressure
    and needs less depth."""
    model, system, region, _ = open_model(cyl8)
    cm = ContactModel.from_fe(model, system, region)
    res = [cm.indent(make_indentor(c, orientation="parallel"), force_N=0.001)
           for c in ("C1", "C3", "C5", "C8")]
    width = [r.contact_area_mm2 for r in res]
    peak = [r.max_pressure_MPa for r in res]
    depth = [float(r.depth_mm[0]) for r in res]
    assert all(b > a for a, b in zip(width, width[1:])), width
    assert all(b < a for a, b in zip(peak, peak[1:])), peak
    assert all(b < a for a, b in zip(depth, depth[1:])), depth
    assert all(r.kkt["ok"] for r in res)


def test_shipped_scenes_are_valid():
    from fem.contact.indentors import shapes_for
    from fem.experiments.scene import load_scene

    scenes = sorted((ROOT / "scenes").glob("*.toml"))
    assert len(scenes) >= 8
    for path in scenes:
        for exp in load_scene(path).experiments:
            shapes_for(exp.indentor)
            if exp.depth_mm is not None:
                assert min(exp.depth_mm) > 0
            if exp.sweep is not None:
                assert len(exp.sweep[1]) > 1


@pytest.mark.parametrize("scene", ["bars", "two_point"])
def test_2d_scenes_run(cyl8, tmp_path, scene):
    path = ROOT / "scenes" / f"{scene}.toml"
    assert pipeline.main(["indent", str(cyl8), "--scene", str(path), "--out", str(tmp_path / scene),
                          "--no-pvd", "--quiet"]) == 0
    if scene == "two_point":
        rows = csv_rows(tmp_path / scene / "equal_force_2mm.csv")
        np.testing.assert_allclose([float(rows[0]["force_part0_N"]), float(rows[0]["force_part1_N"])],
                                   0.0005, rtol=1e-5)
    else:
        peaks = [float(csv_rows(tmp_path / scene / f"bar_{w}.csv")[0]["force_N"]) for w in ("0.5", "1.5", "3.0")]
        assert peaks[0] < peaks[1] < peaks[2]                 # wider bar, more force at 1 mm


def test_thesis_trend_stiff_skin_spreads_a_line_load(tmp_path):
    """Thesis 6.2.1 / 7.1.2 on the five-layer 2D cross-section of the human model: under a 2 mm
    line load the stiff-skin m43338 deflects a wider zone (width where the deflection exceeds half
    its maximum) than the homogeneous m33338, and needs more force."""
    out = tmp_path / "hsec"
    assert pipeline.main(["mesh", "--preset", "human", "--section-z", "10", "--out", str(out), "--quiet"]) == 0
    width, force = {}, {}
    for mat in ("m43338", "m33338"):
        model, system, region, _ = open_model(out, material=mat)
        cm = ContactModel.from_fe(model, system, region)
        res = cm.indent(make_indentor("wedge", orientation="parallel", position_mm=(0.6, 0.0)), depth_mm=2.0)
        x = cm.points_mm[:, 0]
        wide = x[res.deflection_mm > 0.5 * res.deflection_mm.max()]
        width[mat], force[mat] = wide.max() - wide.min(), res.total_force_N
        assert res.kkt["ok"]
    assert width["m43338"] > 2 * width["m33338"], width
    assert force["m43338"] > force["m33338"]


def test_bad_receptor_line(cyl8, tmp_path, capsys):
    out = tmp_path / "bad"
    assert pipeline.main(["indent", str(cyl8), "--indentor", "C5", "--depth", "1", "--line", "z=abc",
                          "--out", str(out), "--quiet"]) == 2
    assert "receptor line" in capsys.readouterr().err and not out.exists()


def test_3d_block_model_folder(tmp_path):
    """The 3D path of `indent`: a small block model folder (nail = bottom, volar = top), a sphere at
    two depths: forces grow, the top face is the contact region, a pressure map is drawn."""
    import meshio

    from fem.verify.closed_forms import box

    p, cells, r = box(np.linspace(-3, 3, 9), np.linspace(-2, 0, 4), np.linspace(0, 6, 9))
    model_dir = tmp_path / "block"
    model_dir.mkdir()
    meshio.write(model_dir / "mesh.vtu", meshio.Mesh(p, [("tetra", cells)], cell_data={"layer": [np.ones(len(cells), int)]},
                                                     point_data={"nail": r["ymin"].astype(np.uint8),
                                                                 "volar": r["ymax"].astype(np.uint8)}))
    out = tmp_path / "out"
    assert pipeline.main(["indent", str(model_dir), "--indentor", "sphere:3", "--depth", "0.1,0.2",
                          "--material", "m3", "--out", str(out), "--quiet"]) == 0
    rows = csv_rows(out / "sphere_3.csv")
    assert 0 < float(rows[0]["force_N"]) < float(rows[1]["force_N"])
    assert all(r["kkt_ok"] == "True" for r in rows)
    surf = csv_rows(out / "sphere_3_surface.csv")
    loaded = [s for s in surf if float(s["force_N"]) > 0]
    assert loaded and all(abs(float(s["y_mm"])) < 1e-12 for s in loaded)
    near = [abs(float(s["x_mm"])) + abs(float(s["z_mm"]) - 3.0) for s in loaded]
    assert max(near) < 2.0                                     # under the sphere at (0, 3)
    assert (out / "sphere_3_pressure.png").is_file()


def test_receptor_site_column_and_run_json(cyl8, tmp_path):
    """Every receptor row names its site (the same ids at every depth and step), and run.json
    records what produced the folder."""
    import hashlib
    import json

    scene = tmp_path / "s.toml"
    scene.write_text('material = "m43338"\n[receptors]\ndepths_mm = [0.5, 1.0]\nspacing_mm = 0.5\n'
                     '[output]\npvd = false\nplots = false\n\n'
                     '[[experiment]]\nname = "c3"\nindentor = "C3"\ndepth_mm = 0.5\nsweep = "x=-1:1:0.5"\n\n'
                     '[[experiment]]\nname = "bar"\nindentor = "bar:1.5"\nforce_N = 0.002\n')
    out = tmp_path / "s"
    assert pipeline.main(["indent", str(cyl8), "--scene", str(scene), "--out", str(out), "--quiet"]) == 0
    rec = csv_rows(out / "c3_receptors.csv")
    assert list(rec[0])[:6] == ["step", "site", "x_mm", "y_mm", "z_mm", "depth_mm"]
    by_step = {}
    for r in rec:
        by_step.setdefault(r["step"], []).append((int(r["site"]), r["depth_mm"], r["x_mm"], r["y_mm"]))
    assert len(by_step) == 5 and all(v == by_step["0"] for v in by_step.values())    # same points, ids
    first = by_step["0"]
    sites = sorted({s for s, *_ in first})
    assert sites == list(range(len(sites))) and len(first) == 2 * len(sites)
    pts = {(s, float(d)): np.array([float(x), float(y)]) for s, d, x, y in first}
    for s in sites:                         # both depths of a site on its (nearly radial) normal
        a, b = pts[(s, 0.5)], pts[(s, 1.0)]
        assert np.linalg.norm(a - b) == pytest.approx(0.5, abs=1e-7)
        assert np.linalg.norm(a) - np.linalg.norm(b) == pytest.approx(0.5, abs=1e-3)
    assert min(abs(p[0]) for p in pts.values()) < 0.07               # a site on the midline x = 0
    run = json.loads((out / "run.json").read_text())
    assert run["model"]["folder"] == str(cyl8.resolve()) and run["model"]["diameter_mm"] == 8.0
    assert run["model"]["model_json_sha256"] == hashlib.sha256((cyl8 / "model.json").read_bytes()).hexdigest()
    assert run["material"] == "m43338" and run["nu"] == 0.48 and run["version"] == "0.1.0"
    assert run["receptors"]["depths_mm"] == [0.5, 1.0] and run["receptors"]["spacing_mm"] == 0.5
    assert run["receptors"]["sites"] == len(sites) and run["receptors"]["line"] is None
    c3, bar = run["experiments"]
    assert c3["name"] == "c3" and c3["indentor"] == "C3" and c3["diameter_mm"] == 4.76
    assert c3["orientation"] == "parallel" and c3["sweep"] == {"axis": "x", "offsets_mm": [-1, -0.5, 0, 0.5, 1]}
    assert c3["loading"] == {"depth_mm": [0.5]} and c3["approach"] == [0.0, -1.0, 0.0]
    assert bar["sweep"] is None and bar["diameter_mm"] is None and bar["shapes"][0]["width_mm"] == 1.5
    assert bar["loading"] == {"force_N": 0.002, "equal_force": False, "max_depth_mm": 3.0}   # the tissue over the bone


def test_scene_position_top_and_bad_position(cyl8, tmp_path, capsys):
    """position_mm = "top": the pad point highest against the approach (the cylinder's crown, x = 0
    up to its mesh); any other word is a one-line error."""
    import json

    scene = tmp_path / "s.toml"
    scene.write_text('[[experiment]]\nname = "c"\nindentor = "C5"\nposition_mm = "top"\ndepth_mm = 0.5\n')
    out = tmp_path / "s"
    assert pipeline.main(["indent", str(cyl8), "--scene", str(scene), "--out", str(out), "--quiet"]) == 0
    x = json.loads((out / "run.json").read_text())["experiments"][0]["position_mm"][0]
    assert abs(x) < 0.2                                               # 0.125 mm elements on top
    assert pipeline.main(["indent", str(cyl8), "--indentor", "C5", "--depth", "0.5", "--position", "top",
                          "--out", str(tmp_path / "cli"), "--quiet"]) == 0
    assert json.loads((tmp_path / "cli" / "run.json").read_text())["experiments"][0]["position_mm"][0] == x
    scene.write_text('[[experiment]]\nname = "c"\nindentor = "C5"\nposition_mm = "centre"\ndepth_mm = 0.5\n')
    assert pipeline.main(["indent", str(cyl8), "--scene", str(scene), "--out", str(tmp_path / "b"),
                          "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert 'position_mm "centre"' in err and "\n" not in err and not (tmp_path / "b").exists()


def test_rerun_replaces_the_run_folder_as_a_whole(cyl8, tmp_path, capsys):
    """A rerun with fewer steps leaves no file of the earlier run (C5_001-003.vtu, its figures);
    a folder holding other files is refused, and a mesh folder keeps what else it holds."""
    out = tmp_path / "run"
    args = ["indent", str(cyl8), "--indentor", "C5", "--out", str(out), "--quiet"]
    assert pipeline.main([*args, "--depth", "0.5:2:0.5", "--pvd"]) == 0
    assert (out / "C5_003.vtu").is_file()
    assert pipeline.main([*args, "--depth", "0.5", "--no-plots", "--pvd"]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["C5.csv", "C5.pvd", "C5_000.vtu", "C5_receptors.csv",
                                                     "C5_surface.csv", "run.json"]
    assert len(csv_rows(out / "C5.csv")) == 1
    assert not [p for p in tmp_path.iterdir() if p.name != "run"]             # no staging, no lock left
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "notes.txt").write_text("keep me")
    capsys.readouterr()
    for argv in ([*args[:-3], "--depth", "0.5", "--out", str(mine)], ["line-load", str(cyl8), "--out", str(mine)],
                 ["analyze", str(out), "--neural", str(ROOT / "data" / "synthetic_sa1_gratings.csv"), "--out",
                  str(mine)]):
        assert pipeline.main(argv) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and f"--out {mine} holds files that are not an earlier" in err, err
    assert [p.name for p in mine.iterdir()] == ["notes.txt"]
    load = tmp_path / "load"                          # another command's own folder: replaced on a rerun too
    for depths in ("0.5,1", "0.5"):
        assert pipeline.main(["line-load", str(cyl8), "--depth", depths, "--out", str(load), "--quiet"]) == 0
    assert {float(r["depth_mm"]) for r in csv_rows(load / "line_load.csv")} == {0.5}
