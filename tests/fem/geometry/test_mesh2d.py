"""2D plane-strain meshes (thesis ch. 4): element size in the top 1 mm, conformity, areas, regions."""
import json

import meshio
import numpy as np
import pytest

import pipeline
from fem.geometry.mesh2d import Sizing2D, mesh_domain, section_domain


def read(out):
    m = meshio.read(out / "mesh.vtu")
    return m, m.points[:, :2], m.cells_dict["triangle"], m.cell_data["layer"][0], json.loads(
        (out / "model.json").read_text())


def edge_stats(p, t):
    x = p[t]
    e = np.mean([np.linalg.norm(x[:, (i + 1) % 3] - x[:, i], axis=1) for i in range(3)], axis=0)
    return x.mean(axis=1), e


def areas(p, t):
    x = p[t]
    return 0.5 * ((x[:, 1, 0] - x[:, 0, 0]) * (x[:, 2, 1] - x[:, 0, 1])
                  - (x[:, 1, 1] - x[:, 0, 1]) * (x[:, 2, 0] - x[:, 0, 0]))


@pytest.mark.parametrize("preset, bone, exact_area", [
    ("cylinder8", True, np.pi * 16), ("cylinder16", False, np.pi * 64), ("square", False, 64.0),
    ("block", False, 720.0)])
def test_thesis_2d_models(tmp_path, preset, bone, exact_area):
    out = tmp_path / preset
    args = ["mesh", "--preset", preset, "--out", str(out), "--quiet"] + (["--bone"] if bone else [])
    assert pipeline.main(args) == 0
    m, p, t, layer, info = read(out)
    a = areas(p, t)
    assert np.all(a > 0)                                                  # counter-clockwise
    assert a.sum() == pytest.approx(exact_area, rel=3e-3)                 # 48+ segments per circle
    c, e = edge_stats(p, t)
    cyl = preset.startswith("cylinder")
    R = {"cylinder8": 4.0, "cylinder16": 8.0}.get(preset)
    depth = R - np.hypot(c[:, 0], c[:, 1]) if cyl else -c[:, 1]
    top = (depth < 1.0) & ((c[:, 1] > 0) if cyl else True)
    # thesis: 0.125 mm elements in the top 1 mm; lattice spacing is exactly 0.125 there
    assert np.median(e[top]) == pytest.approx(0.125, rel=0.03)
    assert np.percentile(e[top], 95) < 0.125 * 1.4
    far = (c[:, 1] < -1.5) if cyl else (depth > 2.5)                      # away from the contact surface
    assert np.median(e[far & (layer == 1)]) > 3 * 0.125                   # graded coarser there
    if bone:
        assert set(np.unique(layer)) == {1, 5}
        assert a[layer == 5].sum() == pytest.approx(np.pi, rel=3e-3)     # 2 mm bone
        cb = c[layer == 5]
        assert np.hypot(cb[:, 0], cb[:, 1]).max() < 1.0
        assert np.hypot(c[layer == 1, 0], c[layer == 1, 1]).min() > 1.0 - 0.05
    fixed, surf = m.point_data["fixed"].astype(bool), m.point_data["surface"].astype(bool)
    assert fixed.sum() >= 5 and surf.sum() >= 20
    if cyl:
        ang = np.degrees(np.arctan2(p[fixed, 1], p[fixed, 0]))
        assert np.all(np.abs(ang + 90) <= 60 + 1e-6)                      # bottom third
        assert np.ptp(ang) > 100                                          # ... all of it
        assert np.all(p[surf, 1] >= -1e-9)
    else:                                   # bottom edge; the block (semi-infinite model) also its sides
        bottom = np.isclose(p[:, 1], p[:, 1].min())
        sides = np.isclose(np.abs(p[:, 0]), np.abs(p[:, 0]).max())
        assert np.array_equal(fixed, bottom | sides if p[:, 0].max() > 10 else bottom)
        assert np.allclose(p[surf, 1], 0.0)
    assert info["mesh"]["min_angle_deg"] > 10


def test_section_of_the_3d_model_has_five_conforming_layers(tmp_path):
    from fem.geometry.layered import model_from_args, params_for

    model = model_from_args(None, "human", params_for("human"))
    dom = section_domain(model, 7.0)
    p, t, layer = mesh_domain(dom, Sizing2D(size_mm=0.25))
    assert set(np.unique(layer)) == {1, 2, 3, 4, 5}
    a = areas(p, t)
    poly = [0.5 * abs(np.dot(r[:, 0], np.roll(r[:, 1], -1)) - np.dot(r[:, 1], np.roll(r[:, 0], -1)))
            for r in dom.curves] + [0.0]
    for L in range(1, 6):
        # interface samples lie on the ring polygons (64 vertices): areas agree to 1 %
        assert a[layer == L].sum() == pytest.approx(poly[L - 1] - poly[L], rel=0.01), L
    # no triangle straddles: every vertex of a layer-L triangle is inside ring L-1 and outside ring L
    from matplotlib.path import Path

    for L in range(1, 6):
        v = p[np.unique(t[layer == L])]
        assert Path(dom.curves[L - 1]).contains_points(v, radius=1e-6).all()
        if L < 5:
            assert not Path(dom.curves[L]).contains_points(v, radius=-1e-6).any()


def test_section_cli_and_epidermis_resolution(tmp_path):
    out = tmp_path / "sec"
    assert pipeline.main(["mesh", "--preset", "monkey", "--section-z", "3", "--out", str(out), "--quiet"]) == 0
    m, p, t, layer, info = read(out)
    assert set(np.unique(layer)) == {1, 2, 3, 4, 5} and info["material"] == "m43338"
    assert info["params"]["section_z_mm"] == 3.0
    c, e = edge_stats(p, t)
    cx, cy = info["params"]["centroid_mm"]
    volar_epi = (layer == 1) & (c[:, 1] > cy)
    assert np.median(e[volar_epi]) == pytest.approx(0.125, rel=0.05)
    fixed = m.point_data["fixed"].astype(bool)
    assert fixed.sum() > 5 and np.all(p[fixed, 1] < cy)
