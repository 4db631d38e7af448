"""`pipeline.py run`: reconstruct -> mesh on a small rendered monkey-size fingertip (meshing a
human-size one takes half as long again), then skipped when current."""
import json

import meshio
import numpy as np

import pipeline
from fem.geometry.presets import Fingertip
from reconstruct.synthetic import render_turntable


def test_run_chains_reconstruct_and_mesh(tmp_path, capsys):
    images = tmp_path / "monkey"
    render_turntable(Fingertip("monkey"), images, n_views=60, size_px=(240, 300), mm_per_px=0.05, seed=3,
                     template_diameter_mm=6.35)
    out = tmp_path / "out"
    assert pipeline.main(["run", str(images), "--out", str(out), "--size", "2.0", "--quiet"]) == 0
    names = {p.name for p in out.iterdir()}
    assert {"sections.json", "surface.stl", "report.png", "mesh.vtu", "model.json"} <= names
    mesh = meshio.read(out / "mesh.vtu")
    layers = np.concatenate(mesh.cell_data["layer"])
    assert set(np.unique(layers)) == {1, 2, 3, 4, 5}
    # the mesh spans the reconstructed sections along z
    z = [s["z"] for s in json.loads((out / "sections.json").read_text())["sections"]]
    assert mesh.points[:, 2].min() >= z[0] - 1e-6 and mesh.points[:, 2].max() <= z[-1] + 1e-6
    stamps = {f: (out / f).stat().st_mtime_ns for f in ("sections.json", "mesh.vtu")}
    assert pipeline.main(["run", str(images), "--out", str(out), "--size", "2.0"]) == 0
    text = capsys.readouterr().out
    assert "outputs are current" in text and "mesh.vtu and model.json are current" in text
    assert {f: (out / f).stat().st_mtime_ns for f in stamps} == stamps       # nothing rewritten
