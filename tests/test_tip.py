"""Rounded distal tip (`mesh --tip rounded`) and the force-displacement experiment of thesis 6.2.3
on the finger tilted by its 30 deg support, distal end up. One coarse monkey mesh (0.8 mm) is
built once per module."""
import json

import meshio
import numpy as np
import pytest

import pipeline
from fem.mesh import tet_volumes

ARGS = ["mesh", "--preset", "monkey", "--size", "0.8", "--tip", "rounded", "--support-incline", "-30", "--quiet"]
Z1, TIP = 7.5, 3.5                     # monkey preset: body 0-7.5 mm, ellipsoidal cap 3.5 mm long


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    mp = pytest.MonkeyPatch()
    mp.setenv("FINGERTIP_CACHE_DIR", str(tmp_path_factory.mktemp("cache")))
    out = tmp_path_factory.mktemp("monkey_tip")
    assert pipeline.main([*ARGS, "--out", str(out)]) == 0
    yield out
    mp.undo()


def test_every_layer_wraps_round_the_tip(built):
    m = meshio.read(built / "mesh.vtu")
    info = json.loads((built / "model.json").read_text())
    tets, layer = m.cells_dict["tetra"], m.cell_data["layer"][0]
    vol = tet_volumes(m.points, tets)
    assert np.bincount(layer, vol, minlength=6)[1:] == pytest.approx(info["model_layer_volumes_mm3"], rel=0.02)
    assert info["mesh"]["straddle"]["straddling_tets"] == 0
    assert "distal" not in m.point_data and "distal" not in info["regions"]
    domes = info["regions"]["tip"]["dome_lengths_mm"]
    assert domes[0] == TIP and np.all(np.diff(domes) < 0)
    # each layer reaches past the body into the tip, the outer ones further: its dome's length
    c = m.points[tets].mean(axis=1)
    for L in range(1, 6):
        assert c[layer == L, 2].max() == pytest.approx(Z1 + domes[L - 1], abs=0.6), L
    z = m.points[:, 2]
    assert z.max() == pytest.approx(Z1 + TIP, abs=0.05)
    # the pad (volar region) and the nail go on over the tip's two sides
    for region in ("volar", "nail"):
        assert z[m.point_data[region] > 0].max() > Z1 + 0.7 * TIP, region


@pytest.mark.slow
def test_force_displacement_on_the_inclined_finger_presses_the_distal_pad(built, tmp_path):
    """Thesis 6.2.3 (Fig. 6-23): cone, punch and plate aimed at the "top" point of the finger tilted
    30 deg distal end up first touch the pad where the tip curves away (the exploration region),
    not a cut rim; force grows with depth, and plate >= punch >= cone at every depth."""
    from pathlib import Path

    from fem.contact import load_scene, run_scene

    spec = load_scene(Path(pipeline.__file__).parent / "scenes" / "force_displacement.toml")
    spec["output"] = {"plots": False, "pvd": False}
    run_scene(built, tmp_path / "fd", spec, progress=False)
    forces = {}
    for name in ("cone", "punch", "plate"):
        rows = np.genfromtxt(tmp_path / "fd" / f"{name}.csv", delimiter=",", names=True, dtype=None,
                             encoding="utf-8")
        assert all(rows["kkt_ok"]) and np.all(np.diff(rows["force_N"]) > 0), name
        assert rows["depth_mm"].tolist() == pytest.approx(np.arange(0.25, 2.01, 0.25).tolist())
        forces[name] = rows["force_N"]
        s = np.genfromtxt(tmp_path / "fd" / f"{name}_surface.csv", delimiter=",", names=True)
        first = s[(s["step"] == 0) & (s["pressure_MPa"] > 0)]
        # a 30 deg tilt puts the top of an ellipsoidal cap at z1 + tip sin(30 deg)-ish: on the tip,
        # clear of the body's end and of the apex
        assert Z1 + 0.2 < first["z_mm"].min() and first["z_mm"].max() < Z1 + TIP - 0.5, name
        last = s[(s["step"] == 7) & (s["pressure_MPa"] > 0)]
        assert last["z_mm"].min() > 2.0, name                 # never near the proximal cut
    assert np.all(forces["plate"] >= forces["punch"] * (1 - 1e-9))
    assert np.all(forces["punch"] > forces["cone"])
