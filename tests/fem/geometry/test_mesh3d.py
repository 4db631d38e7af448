"""3D mesh of the monkey preset through `pipeline.py mesh`: the mesh.vtu / model.json contract and
the mesher's checks. One coarse mesh (0.7 mm, shared with tests/fem/geometry/test_sizing.py through
the mesh cache) is built once per module."""
import json

import meshio
import numpy as np
import pytest

import pipeline
from fem.geometry.layered import model_from_args, params_for
from fem.geometry.mesh3d import (
    Sizing,
    boundary_faces,
    cache_dir,
    label_tets,
    quality,
    straddle_check,
    surface_model,
    tet_volumes,
)
from fingertip.errors import InputError
from tests.helpers import write_sections

ARGS = ["mesh", "--preset", "monkey", "--size", "0.7", "--quiet"]


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    """(model folder, its mesh cache entry)."""
    out = tmp_path_factory.mktemp("monkey")
    assert pipeline.main([*ARGS, "--out", str(out)]) == 0
    return out, cache_dir() / f"{load(out)[1]['mesh']['cache_key']}.npz"


def load(out):
    m = meshio.read(out / "mesh.vtu")
    return m, json.loads((out / "model.json").read_text())


def test_file_contract(built):
    m, info = load(built[0])
    assert list(m.cells_dict) == ["tetra"]
    layer = m.cell_data["layer"][0]
    assert layer.dtype == np.int32 and set(np.unique(layer)) == {1, 2, 3, 4, 5}
    for name in ("nail", "support", "volar", "proximal", "distal"):
        assert m.point_data[name].dtype == np.uint8
    assert np.all(tet_volumes(m.points, m.cells_dict["tetra"]) > 0)          # positive orientation
    assert info["material"] == "m43338" and info["nu"] == 0.48
    p = info["params"]
    assert p["epidermis_mm"] == 0.5 and p["dermis_mm"] == 1.0 and p["bone_offset_mm"] == 0.15
    assert info["regions"]["support"]["normal"] == [0.0, 1.0, 0.0]
    assert info["sizing"]["size_mm"] == 0.7 and len(info["sections_sha256"]) == 64


def test_layer_volumes_within_2_percent_of_the_model_shells(built):
    m, info = load(built[0])
    model = model_from_args(None, "monkey", params_for("monkey"))
    vol = tet_volumes(m.points, m.cells_dict["tetra"])
    per_layer = np.bincount(m.cell_data["layer"][0], vol, minlength=6)[1:]
    # pytetwild keeps interfaces within epsilon_mm = 0.02 of the model; the 2 mm bone loses most
    assert per_layer == pytest.approx(model.layer_volumes_mm3(), rel=0.02)
    assert info["mesh"]["layer_volumes_mm3"] == pytest.approx(per_layer.tolist(), rel=1e-9)


def test_no_tet_straddles_an_interface(built):
    m, info = load(built[0])
    model = surface_model(model_from_args(None, "monkey", params_for("monkey")), Sizing(size_mm=info["sizing"]["size_mm"]))
    tets, layer = m.cells_dict["tetra"], m.cell_data["layer"][0]
    assert np.array_equal(label_tets(model, m.points, tets), layer)
    # On the end cuts every shell's cap lies in one plane: the envelope (0.02 mm) keeps the mesh on
    # that plane, not the layer curves within it, and runs have put a cut vertex 0.073 mm across
    # one (pytetwild is not deterministic). Elsewhere nothing crosses by more than 2 envelopes.
    z = m.points[:, 2]
    on_cut = np.isclose(z[tets], z.min(), atol=1e-6).any(axis=1) | np.isclose(z[tets], z.max(), atol=1e-6).any(axis=1)
    inside = straddle_check(model, m.points, tets[~on_cut], layer[~on_cut], tol_mm=0.041)
    assert inside["straddling_tets"] == 0 and inside["max_crossing_mm"] < 0.041
    assert straddle_check(model, m.points, tets[on_cut], layer[on_cut], tol_mm=0.1)["straddling_tets"] == 0
    # the check does find a straddling tet: relabel bone tets as layer 3
    wrong = layer.copy()
    wrong[layer == 5] = 3
    assert straddle_check(model, m.points, tets, wrong, tol_mm=0.041)["straddling_tets"] > 0


def test_regions_are_non_empty_and_on_the_right_side(built):
    m, info = load(built[0])
    model = model_from_args(None, "monkey", params_for("monkey"))
    bf = boundary_faces(m.cells_dict["tetra"])
    cy = np.interp(m.points[:, 2], model.z_mm, model.centroids[:, 1])
    zf = model.z_frac(m.points[:, 2])
    for name, side in (("nail", -1), ("support", -1), ("volar", 1)):
        flag = m.point_data[name].astype(bool)
        assert flag[bf].all(axis=1).sum() > 5, name                      # boundary facets in the region
        dy = side * (m.points[flag, 1] - cy[flag])
        assert dy.min() >= -1e-9 and np.median(dy) > 1.0, name     # volar span 180 deg reaches the sides
    nail, support = m.point_data["nail"].astype(bool), m.point_data["support"].astype(bool)
    assert zf[nail].min() >= 0.3 - 1e-6 and zf[support].max() <= 0.3 + 1e-6
    assert info["mesh"]["regions"]["nail"]["facets"] == m.point_data["nail"][bf].all(axis=1).sum()
    for name, z in (("proximal", model.z_mm[0]), ("distal", model.z_mm[-1])):
        flag = m.point_data[name].astype(bool)
        assert flag[bf].all(axis=1).sum() > 20 and np.allclose(m.points[flag, 2], z, atol=0.03), name


def test_bone_offset_matches_the_parameter(built):
    _, info = load(built[0])
    # measured from bone tets against the section centroids; 0.15 mm +- 0.03 (mesh faceting)
    assert info["mesh"]["bone_offset_mm"] == pytest.approx(0.15, abs=0.03)


def test_quality_and_sizing_are_reported_and_sane(built):
    m, info = load(built[0])
    q = quality(m.points, m.cells_dict["tetra"])
    assert q.pop("edge_mm") == pytest.approx(info["mesh"]["quality"].pop("edge_mm"))
    assert q == pytest.approx(info["mesh"]["quality"])
    assert q["min_dihedral_deg"] > 5 and q["min_scaled_jacobian"] > 0.05
    fine = info["mesh"]["sizing_achieved"]["fine_zone_median_edge_mm"]
    assert fine == pytest.approx(0.7, rel=0.25)


def test_cache_returns_the_same_mesh_and_keys_change_with_inputs(built, tmp_path):
    out, entry = built
    assert entry.is_file()
    again = tmp_path / "again"
    assert pipeline.main([*ARGS, "--out", str(again)]) == 0
    m1, _ = load(out)
    m2, info2 = load(again)
    assert info2["mesh"]["from_cache"] is True
    assert np.array_equal(m1.points, m2.points) and np.array_equal(m1.cells_dict["tetra"], m2.cells_dict["tetra"])
    # a changed parameter changes the key (no stale mesh): bone offset 0.1 must not hit the cache
    from fem.geometry.mesh3d import Sizing, mesh_key

    base = model_from_args(None, "monkey", params_for("monkey"))
    other = model_from_args(None, "monkey", params_for("monkey", bone_offset_mm=0.1))
    assert mesh_key(base, Sizing(size_mm=0.7)) != mesh_key(other, Sizing(size_mm=0.7))
    assert mesh_key(base, Sizing(size_mm=0.7)) != mesh_key(base, Sizing(size_mm=0.8))


def test_sizing_field_is_fine_under_the_pad_and_grows_inwards_and_dorsally():
    from fem.geometry.mesh3d import Sizing, sizing_values

    model = model_from_args(None, "human", params_for("human"))
    k = len(model.z_mm) // 2
    c, z = model.centroids[k], model.z_mm[k]
    r_volar = np.linalg.norm(model.rings[k, 0, 16] - c)                    # ray 16 of 64 points to +y
    r_dorsal = np.linalg.norm(model.rings[k, 0, 48] - c)
    pts = np.array([[c[0], c[1] + r_volar - 1.0, z],                        # 1 mm under the pad
                    [c[0], c[1] + r_volar - 3.5, z],                        # 3.5 mm under the pad
                    [c[0], c[1] - r_dorsal + 0.3, z]])                      # dorsal skin
    h = sizing_values(model, Sizing(size_mm=0.5, growth=0.5, coarse_mm=3.0), pts)
    assert h[0] == pytest.approx(0.5)
    assert h[1] == pytest.approx(0.5 + 0.5 * (3.5 - 1.5), rel=0.02)        # grows 0.5 mm per mm
    assert h[2] == pytest.approx(3.0)                                       # capped at coarse


def test_force_rebuilds_while_a_normal_run_uses_the_cache(built, monkeypatch):
    import fem.geometry.mesh3d as fm

    with np.load(built[1]) as d:
        points, tets = d["points"], d["tets"]
    calls = []

    def mesher(model, sizing):                       # stands in for pytetwild: count the calls
        calls.append(sizing.size_mm)
        return points, tets

    monkeypatch.setattr(fm, "tetrahedralize", mesher)
    model = model_from_args(None, "monkey", params_for("monkey"))
    _, info = fm.build_mesh(model, fm.Sizing(size_mm=0.7))
    assert info["cached"] and calls == []
    _, info = fm.build_mesh(model, fm.Sizing(size_mm=0.7), force=True)
    assert not info["cached"] and calls == [0.7]


def test_rerun_skips_current_outputs_and_region_changes_reuse_the_tets(built, tmp_path):
    out, _ = built
    stamp = [(out / f).stat().st_mtime_ns for f in ("mesh.vtu", "model.json")]
    assert pipeline.main([*ARGS, "--out", str(out)]) == 0
    assert [(out / f).stat().st_mtime_ns for f in ("mesh.vtu", "model.json")] == stamp   # skipped
    narrow = tmp_path / "narrow"
    assert pipeline.main([*ARGS, "--nail-span", "60", "--out", str(narrow)]) == 0
    m1, _ = load(out)
    m2, info2 = load(narrow)
    assert info2["mesh"]["from_cache"] is True                     # same tets, new tags
    assert 0 < m2.point_data["nail"].sum() < m1.point_data["nail"].sum()


def test_monkey_size_sections_json_meshes_with_size_defaults(built, tmp_path, capsys):
    """A monkey-size replica needs no --layer3/--bone-offset: the defaults follow the section size,
    are printed and recorded in model.json; an explicit flag still wins."""
    from fem.geometry.sections import preset_sections

    z, polys, _ = preset_sections("monkey")
    src = write_sections(tmp_path / "replica", polys, z)
    out = tmp_path / "m"
    assert pipeline.main(["mesh", str(src), "--size", "0.7", "--out", str(out)]) == 0
    assert "layer3_mm 0.55, bone_offset_mm 0.15" in capsys.readouterr().out
    _, info = load(out)
    assert info["params"]["layer3_mm"] == 0.55 and info["params"]["bone_offset_mm"] == 0.15
    assert info["size_defaults"]["chosen"] == {"layer3_mm": 0.55, "bone_offset_mm": 0.15}
    assert info["size_defaults"]["middle_width_mm"] == pytest.approx(8.56, abs=0.01)
    with pytest.raises(InputError, match="bone"):
        model_from_args(str(src), None, params_for(None, bone_offset_mm=1.0))


def test_receptor_sites_skip_the_end_cuts(built):
    """Receptor sites come from the volar nodes off the end cuts (fem.io.modelfolder.receptor_surface), so
    every receptor point lies in the mesh, at least a node spacing inside the cut planes."""
    from fem.io.modelfolder import read_model, receptor_surface
    from fem.receptors.grid import ReceptorSampler, receptor_grid

    model, _ = read_model(built[0])
    sn = model.surface_nodes("volar")
    x, normal = receptor_surface(model, sn)
    z0, z1 = sn.x[:, 2].min(), sn.x[:, 2].max()
    on_cut = (sn.x[:, 2] < z0 + 0.02) | (sn.x[:, 2] > z1 - 0.02)       # the cut planes, within the envelope
    assert on_cut.sum() > 20 and len(x) == len(sn.x) - on_cut.sum()
    assert x[:, 2].min() > z0 + 0.1 and x[:, 2].max() < z1 - 0.1
    grid = receptor_grid(x, normal, depths_mm=(0.5, 0.75, 1.0), spacing_mm=1.0)
    z = grid.points_mm[:, 2]
    assert z.min() > z0 + 0.1 and z.max() < z1 - 0.1
    assert ReceptorSampler(model, grid).operator.shape[0] > 0         # every point located in the mesh


def test_bar_along_the_axis_presses_the_skin_of_the_proximal_cut(built, tmp_path):
    """Only the proximal cut's core (layers 3-5) is held, so a bar as long as the finger indents
    the cut's skin instead of stopping at a fixed rim (it did while the whole cut was held)."""
    from fem.io.modelfolder import held_regions, read_model

    model, _ = read_model(built[0])
    assert "proximal_core" in held_regions(model) and "proximal" not in held_regions(model)
    core, cut = model.regions["proximal_core"], model.regions["proximal"]
    skin_vertices = np.unique(model.mesh.t[:, model.layer <= 2])
    assert core.sum() > 10 and not core[skin_vertices].any() and cut[skin_vertices].sum() > 10
    out = tmp_path / "bar"
    assert pipeline.main(["indent", str(built[0]), "--indentor", "bar:0.5", "--axis", "parallel",
                          "--depth", "1", "--out", str(out), "--quiet"]) == 0
    rows = (out / "bar_0.5.csv").read_text().splitlines()
    assert float(rows[-1].split(",")[4]) > 0                 # force_N at 1 mm


def test_top_on_a_flat_cut_rim_is_warned_about(built, tmp_path, capsys):
    """Tilted distal end up, a flat-ended finger's highest point is its distal cut's rim: aiming at
    "top" there says so (and how to get the pad: a rounded tip)."""
    out = tmp_path / "cone"
    assert pipeline.main(["indent", str(built[0]), "--indentor", "cone", "--position", "top", "--incline", "-30",
                          "--depth", "0.25", "--out", str(out), "--quiet"]) == 0
    assert "top point is on the rim of the distal cut" in capsys.readouterr().err


def test_summary_of_a_mesh_with_an_empty_zone(built):
    """A mesh coarser than the fine zone is deep (the human preset at --size 3: every element
    centroid inside it) has no element elsewhere: the summary says 'none' where it failed with a
    TypeError after writing the folder."""
    from fem.geometry.mesh3d import summary

    rep = load(built[0])[1]["mesh"]
    achieved = {**rep["sizing_achieved"], "elsewhere_median_edge_mm": None, "elsewhere_max_edge_mm": None}
    text = summary({**rep, "sizing_achieved": achieved}, {"cached": True, "mesh_s": 0.1}, built[0])
    assert "elsewhere none mm" in text and "volar fine zone 0." in text
