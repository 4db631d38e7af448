"""Sizes that converge: smooth section outlines (the model resampled on rays for the mesh size),
`--size` refining every layer in proportion (2D and 3D), distinct 3D meshes at 1.0 and 0.7 mm,
region ends at mesh vertices, and the achieved sizes model.json reports. 2D meshes, and the 3D
monkey at 1.0 and 0.7 mm once per module (through the mesh cache, as `mesh` runs, which
tests/fem/geometry/test_mesh3d.py and the thesis-claim tests share)."""
import json

import numpy as np
import pytest

from fem.geometry.build import MeshSpec, build_folder
from fem.geometry.layered import _min_gap, model_from_args, params_for
from fem.geometry.mesh2d import (
    SECTION_FACET_MM,
    Sizing2D,
    boundary_points,
    mesh_domain,
    preset_domain,
    section_domain,
)
from fem.geometry.mesh3d import SURFACE_FACET, Sizing, sizing_values, surface_model
from fem.io.modelfolder import read_model
from fingertip.errors import InputError


def facets(ring):
    return np.linalg.norm(np.roll(ring, -1, axis=-2) - ring, axis=-1)


@pytest.fixture(scope="module")
def monkey():
    return model_from_args(None, "monkey", params_for("monkey"))


@pytest.fixture(scope="module")
def monkey_3d(tmp_path_factory):
    """{size: model.json} of the monkey preset meshed at 1.0 and 0.7 mm."""
    out = {}
    for size in (1.0, 0.7):
        folder = tmp_path_factory.mktemp("monkey") / f"m{size:g}"
        build_folder(folder, MeshSpec(preset="monkey", sizes={"size_mm": size}))
        out[size] = json.loads((folder / "model.json").read_text())
    return out


# ------------------------------------------------------------------ smooth outlines
@pytest.mark.parametrize("size", [1.0, 0.5, 0.35])
def test_3d_surfaces_have_facets_of_at_most_half_the_size(monkey, size):
    m = surface_model(monkey, Sizing(size_mm=size))
    assert facets(m.rings[:, 0]).max() <= SURFACE_FACET * size + 1e-9
    assert m.rings.shape[2] % 8 == 0 and m.rings.shape[2] >= monkey.params.n_theta
    assert surface_model(m, Sizing(size_mm=size)) is m                     # resampled once
    # the same model on more rays: exact erosions of the same outlines, same scale factors
    outline = m.polygons[4]
    assert [_min_gap(outline, p[None]) for p in m.rings[4, 1]] == pytest.approx(np.full(m.rings.shape[2], 0.5), abs=1e-6)
    assert m.derived["f3"] == monkey.derived["f3"] and m.derived["bone_ratio"] == monkey.derived["bone_ratio"]
    assert m.layer_volumes_mm3() == pytest.approx(monkey.layer_volumes_mm3(), rel=0.01)


def test_the_2d_section_is_as_smooth_as_the_presets_circles(monkey):
    dom = section_domain(monkey, 5.0)
    for curve in dom.curves:
        assert facets(curve).max() <= 1.05 * SECTION_FACET_MM      # estimated on 64 rays: within 5 %
    assert len(dom.curves[0]) > 10 * monkey.params.n_theta
    # turning between facets of the outer curve: under 1 deg (a 64-gon turns 5.6 deg at each vertex)
    e = np.roll(dom.curves[0], -1, axis=0) - dom.curves[0]
    turn = np.degrees(np.abs(np.angle(np.exp(1j * np.diff(np.unwrap(np.arctan2(e[:, 1], e[:, 0])))))))
    assert turn.max() < 1.0


def test_rounded_tip_domes_follow_the_rays(monkey):
    from dataclasses import replace

    tip = model_from_args(None, "monkey", replace(params_for("monkey"), tip_mm=3.5))
    m = surface_model(tip, Sizing(size_mm=0.35))
    assert m.derived["tip_levels"] > tip.derived["tip_levels"]
    assert m.derived["tip_lengths_mm"] == tip.derived["tip_lengths_mm"]


# ------------------------------------------------------------------ sizes in proportion
def test_coarse_growth_and_envelope_follow_the_size_unless_given():
    assert (Sizing().coarse_mm, Sizing().growth, Sizing().epsilon_mm) == (3.0, 0.5, 0.02)     # the defaults
    assert (Sizing2D().coarse_mm, Sizing2D().growth) == (1.0, 0.5)
    s = Sizing(size_mm=0.35)
    assert (s.coarse_mm, s.growth, s.epsilon_mm) == pytest.approx((2.1, 0.35, 0.014))
    assert (Sizing(size_mm=1.0).coarse_mm, Sizing(size_mm=1.0).epsilon_mm) == (3.0, 0.02)     # at most
    assert (Sizing2D(size_mm=0.0625).coarse_mm, Sizing2D(size_mm=0.0625).growth) == (0.5, 0.25)
    assert Sizing2D(size_mm=0.5).growth == 0.5
    assert Sizing(size_mm=0.35, coarse_mm=3.0).coarse_mm == 3.0                               # given wins
    with pytest.raises(InputError, match="larger than coarse_mm 3 mm \\(the default of 3D models\\)"):
        Sizing(size_mm=4.0).check()
    with pytest.raises(InputError, match="larger than coarse_mm 1 mm \\(the default of 2D models\\)"):
        Sizing2D(size_mm=1.5).check()


def test_3d_sizing_field_scales_with_the_size(monkey):
    rng = np.random.default_rng(0)
    v = monkey.vertices()
    pts = v.min(0) + rng.random((2000, 3)) * np.ptp(v, axis=0)
    h5, h35 = (sizing_values(monkey, Sizing(size_mm=s), pts) for s in (0.5, 0.35))
    below = h5 < 3.0                                   # below the 0.5 mm mesh's coarse size
    assert h35[below] == pytest.approx(0.7 * h5[below], rel=1e-9)


def test_2d_every_layer_refines_in_proportion(monkey):
    dom = section_domain(monkey, 5.0)
    counts = []
    for size in (0.5, 0.25, 0.125, 0.0625, 0.03125):
        _, tri, layer = mesh_domain(dom, Sizing2D(size_mm=size))
        counts.append(np.bincount(layer, minlength=6)[1:])
    counts = np.array(counts)
    assert np.all(np.diff(counts[:, [0, 1, 3, 4]], axis=0) > 0), counts   # the layers the fine zone reaches
    # above the default 0.125 mm the deep layer 3 keeps the coarse 1 mm and growth 0.5 caps; below it
    # every layer refines about 4x per halving
    assert np.all(counts[3:, :4] / counts[2:-1, :4] > 3), counts
    assert np.all(counts[3:, 4] / counts[2:-1, 4] > 1.8), counts            # the bone, capped by its thickness


def test_3d_sizes_one_and_seven_tenths_give_distinct_meshes_refining_every_layer(monkey_3d):
    a, b = (monkey_3d[s]["mesh"]["sizing_achieved"] for s in (1.0, 0.7))
    assert a["fine_zone_median_edge_mm"] > 1.15 * b["fine_zone_median_edge_mm"]
    assert b["dofs"] > a["dofs"]
    for L in "12":                     # the skin, under the fine zone
        assert b["per_layer"][L]["elements"] > 1.2 * a["per_layer"][L]["elements"], L
    # The deep layers are not in proportion at these coarse sizes: pytetwild's 0.02 mm envelope
    # around the thin layer 4 and the bone sets their elements (median edge 0.39 and 0.38 mm at
    # 1.0 mm, 0.44 and 0.40 mm at 0.7 mm), finer than the sizing field asks (docs/model-and-mesh.md).
    for L in "345":
        assert b["per_layer"][L]["median_edge_mm"] < 0.7 and a["per_layer"][L]["median_edge_mm"] < 0.7, L
    assert monkey_3d[1.0]["sizing"]["epsilon_mm"] == 0.02 and monkey_3d[0.7]["sizing"]["growth"] == 0.7


# ------------------------------------------------------------------ region ends and reports
@pytest.mark.parametrize("which", ["section", "cylinder8"])
def test_fixed_region_ends_are_mesh_vertices(monkey, which):
    """The fixed span's ends are sampled on the boundary, so the held arc is the span at any size
    (it varied between 110 and 117 of 120 deg with the dorsal element size)."""
    dom = section_domain(monkey, 5.0) if which == "section" else preset_domain("cylinder8", bone=True)
    c = np.array(dom.params.get("centroid_mm", (0.0, 0.0)))
    for size in (0.25, 0.0625):
        p, t, _ = mesh_domain(dom, Sizing2D(size_mm=size))
        held = boundary_points(t, len(p)) & dom.fixed(p)
        angle = np.degrees(np.arctan2(p[held, 1] - c[1], p[held, 0] - c[0]))
        assert (angle.min(), angle.max()) == pytest.approx((-150.0, -30.0), abs=1e-6), size


def test_2d_model_json_reports_the_achieved_sizes(section):
    info = json.loads((section / "model.json").read_text())
    a = info["mesh"]["sizing_achieved"]
    model, _ = read_model(section)
    assert a["dofs"] == model.ndof and a["elements"] == info["mesh"]["triangles"]
    assert a["fine_zone_median_edge_mm"] == pytest.approx(0.25, rel=0.1)
    assert a["fine_zone_median_edge_mm"] <= a["fine_zone_p90_edge_mm"] < 1.6 * 0.25
    assert sorted(a["per_layer"]) == list("12345")
    assert sum(v["elements"] for v in a["per_layer"].values()) == a["elements"]
    assert info["sizing"]["coarse_mm"] == 1.0 and info["sizing"]["growth"] == 0.5


def test_3d_model_json_reports_the_achieved_sizes(monkey_3d, tmp_path):
    info = monkey_3d[1.0]
    a = info["mesh"]["sizing_achieved"]
    assert a["elements"] == info["mesh"]["tets"] == sum(v["elements"] for v in a["per_layer"].values())
    assert a["rays_per_section"] == info["params"]["n_theta"]
    assert 0.7 < a["fine_zone_median_edge_mm"] <= a["fine_zone_p90_edge_mm"] < 1.3
    assert info["sizing"] == {**info["sizing"], "size_mm": 1.0, "coarse_mm": 3.0, "growth": 1.0}
