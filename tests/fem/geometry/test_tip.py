"""Rounded distal tip (`mesh --tip rounded`) and the force-displacement experiment of thesis 6.2.3
on the finger tilted by its 30 deg support, distal end up. One coarse monkey mesh (0.8 mm) is
built once per module."""
import json

import meshio
import numpy as np
import pytest

import pipeline
from fem.geometry.mesh3d import tet_volumes
from tests.helpers import ROOT

ARGS = ["mesh", "--preset", "monkey", "--size", "0.8", "--tip", "rounded", "--support-incline", "-30", "--quiet"]
Z1, TIP = 7.5, 3.5                     # monkey preset: body 0-7.5 mm, ellipsoidal cap 3.5 mm long


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    """The tilted rounded monkey (meshes are reproducible: a cached one is the one meshing gives)."""
    out = tmp_path_factory.mktemp("monkey_tip")
    assert pipeline.main([*ARGS, "--out", str(out)]) == 0
    return out


def test_every_layer_wraps_round_the_tip(built):
    m = meshio.read(built / "mesh.vtu")
    info = json.loads((built / "model.json").read_text())
    tets, layer = m.cells_dict["tetra"], m.cell_data["layer"][0]
    vol = tet_volumes(m.points, tets)
    assert np.bincount(layer, vol, minlength=6)[1:] == pytest.approx(info["model_layer_volumes_mm3"], rel=0.02)
    assert info["mesh"]["straddle"]["straddling_tets"] <= 1e-3 * len(tets)
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


@pytest.fixture(scope="module")
def force_displacement(built, tmp_path_factory):
    """The shipped scene on the tilted rounded monkey, plus a 3 mm punch: {name: (rows, surface)}."""
    from dataclasses import replace

    from fem.experiments.scene import Experiment, Output, load_scene
    from fingertip.jobs.indent import indent_folder

    spec = load_scene(ROOT / "scenes" / "force_displacement.toml")
    punch = Experiment.from_dict({"name": "punch3", "indentor": "punch:3", "position_mm": "top",
                                  "depth_mm": "0.25:2:0.25"})
    spec = replace(spec, output=Output(plots=False, pvd=False), experiments=(*spec.experiments, punch))
    out = tmp_path_factory.mktemp("fd")
    indent_folder(built, out, spec, progress=False)
    return {e.name: (np.genfromtxt(out / f"{e.name}.csv", delimiter=",", names=True, dtype=None,
                                   encoding="utf-8"),
                     np.genfromtxt(out / f"{e.name}_surface.csv", delimiter=",", names=True))
            for e in spec.experiments}


@pytest.mark.slow
def test_force_displacement_on_the_inclined_finger_presses_the_distal_pad(force_displacement):
    """Thesis 6.2.3 (Fig. 6-23): cone, punch and plate aimed at the "top" point of the finger tilted
    30 deg distal end up first touch the pad where the tip curves away (the exploration region),
    not a cut rim; force grows with depth, and plate >= punch >= cone at every depth."""
    forces = {}
    for name in ("cone", "punch", "plate"):
        rows, s = force_displacement[name]
        assert all(rows["kkt_ok"]) and np.all(np.diff(rows["force_N"]) > 0), name
        assert rows["depth_mm"].tolist() == pytest.approx(np.arange(0.25, 2.01, 0.25).tolist())
        forces[name] = rows["force_N"]
        first = s[(s["step"] == 0) & (s["pressure_MPa"] > 0)]
        # a 30 deg tilt puts the top of an ellipsoidal cap at z1 + tip sin(30 deg)-ish: on the tip,
        # clear of the body's end and of the apex
        assert Z1 + 0.2 < first["z_mm"].min() and first["z_mm"].max() < Z1 + TIP - 0.5, name
        last = s[(s["step"] == 7) & (s["pressure_MPa"] > 0)]
        assert last["z_mm"].min() > 2.0, name                 # never near the proximal cut
    assert np.all(forces["plate"] >= forces["punch"] * (1 - 1e-9))
    assert np.all(forces["punch"] > forces["cone"])


@pytest.mark.slow
def test_a_flat_punch_in_full_contact_responds_linearly_the_plate_keeps_stiffening(force_displacement):
    """Thesis 6.2.3: the linear model's force-displacement is non-linear only through the growing
    contact; "once the indentor is fully in contact ... (circular flat indentor) the response of
    the model to any further indentation is linear". A 3 mm punch on the monkey's tilted pad is in
    full contact from about 0.75 mm: its force then grows by the same step every 0.25 mm, while the
    plate's steps keep growing with its contact area."""
    punch_rows, plate_rows = force_displacement["punch3"][0], force_displacement["plate"][0]
    punch, plate = np.diff(punch_rows["force_N"]), np.diff(plate_rows["force_N"])
    full = punch_rows["contact_area_mm2"][2:]                     # from 0.75 mm: the face, pi 1.5^2
    assert full == pytest.approx(np.full(len(full), np.pi * 1.5**2), rel=0.1)
    assert punch[2:] == pytest.approx(np.full(len(punch) - 2, punch[-1]), rel=0.01)   # linear in full contact
    assert np.all(np.diff(plate) > 0) and plate[-1] > 3 * plate[0]     # the plate keeps stiffening
