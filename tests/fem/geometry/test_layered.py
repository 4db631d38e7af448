"""Layered model geometry (no meshing): layer thicknesses, scaling, bone, analytic volumes, errors."""
import numpy as np
import pytest

import pipeline
from fem.geometry.layered import ModelParams, build_model, model_from_args, params_for
from fem.geometry.sections import smooth_polygon
from fingertip.errors import InputError
from tests.helpers import write_sections


def circle(r, n=360, c=(0.0, 0.0)):
    t = 2 * np.pi * np.arange(n) / n
    return np.column_stack([c[0] + r * np.cos(t), c[1] + r * np.sin(t)])


def cylinder_model(R=6.0, L=5.0, **kw):
    z = np.linspace(0.0, L, 6)
    return build_model(z, [circle(R)] * len(z), ModelParams(n_theta=128, **kw))


def test_cylinder_layer_volumes_match_closed_form():
    # circle R: skin offsets are circles; f3 = (1.5 + t3) / R puts ring 3 at R-1.5-t3;
    # the bone is a circle of the given diameter. 128-gon areas are 0.04 % below the circles.
    R, L, t3, bone_d = 6.0, 5.0, 1.2, 2.0
    m = cylinder_model(R, L, layer3_mm=t3, bone_diameter_mm=bone_d, bone_offset_mm=0.8)
    radii = [R, R - 0.5, R - 1.5, R - 1.5 - t3, bone_d / 2]
    shells = np.pi * np.square(radii) * L
    expect = shells - np.append(shells[1:], 0.0)
    assert m.layer_volumes_mm3() == pytest.approx(expect, rel=2e-3)
    assert m.derived["f3"] == pytest.approx((1.5 + t3) / R, rel=1e-3)


def test_skin_thickness_is_constant_all_round_on_the_human_preset():
    from fem.geometry.layered import _min_gap
    from fem.geometry.sections import check_polygon, preset_sections

    z, polys, _ = preset_sections("human")
    m = build_model(z, polys, params_for("human"))
    for k in (0, len(z) // 2, len(z) - 1):
        outline = check_polygon(polys[k], "test")
        for ring, depth in ((1, 0.5), (2, 1.5)):
            # every ring vertex lies exactly `depth` inside the section outline (exact erosion)
            pts = m.rings[k, ring]
            d = [_min_gap(outline, p[None]) for p in pts]
            assert np.allclose(d, depth, atol=1e-6)
    # the resampled 64-gon's chords cut the most curved (dorsal-lateral) corners: thinnest 3.3 % less
    assert m.derived["min_thickness"][0] == pytest.approx(0.5, rel=0.05)


def test_presets_have_the_thesis_sizes_and_nested_outward_shells():
    for preset, width in (("human", 16.0), ("monkey", 8.0)):
        m = model_from_args(None, preset, params_for(preset))
        w = np.ptp(m.rings[:, 0, :, 0], axis=1)
        assert w.min() == pytest.approx(width, rel=0.03), preset
        shells = m.shell_volumes_mm3()
        assert np.all(shells > 0) and np.all(np.diff(shells) < 0), preset
        bone_w = np.ptp(m.rings[:, 4, :, 0], axis=1)
        mid = len(m.z_mm) // 2
        assert bone_w[mid] == pytest.approx(2.0, rel=0.05), preset      # about 2 mm bone


def test_outer_volume_matches_the_parametric_fingertip():
    from fem.geometry.presets import make_shape

    m = model_from_args(None, "monkey", params_for("monkey"))
    shape = make_shape("fingertip", preset="monkey", rod=False)
    exact = shape.volume_mm3(m.z_mm[0], m.z_mm[-1])
    assert m.shell_volumes_mm3()[0] == pytest.approx(exact, rel=0.01)


def test_bone_is_shifted_towards_the_nail_by_the_offset():
    m = cylinder_model(bone_offset_mm=1.3)
    bone_c = m.rings[:, 4].mean(axis=1)           # regular polygon: vertex mean = centroid
    assert np.allclose(bone_c - m.centroids, [0.0, -1.3], atol=1e-9)


def test_bone_profile_table_sets_the_bone_width_along_z():
    m = cylinder_model(R=6.0, L=5.0, bone_profile=((0.0, 0.3), (1.0, 0.1)))
    w = np.ptp(m.rings[:, 4, :, 0], axis=1) / np.ptp(m.rings[:, 0, :, 0], axis=1)
    assert w == pytest.approx(np.linspace(0.3, 0.1, len(m.z_mm)), rel=1e-6)


def test_shells_are_closed_and_consistently_oriented():
    import trimesh

    m = model_from_args(None, "monkey", params_for("monkey"))
    for i in range(5):
        s = trimesh.Trimesh(m.vertices(), m.faces(i))
        assert s.is_watertight and s.is_winding_consistent and s.volume > 0
    merged = m.faces()
    assert len(np.unique(np.sort(merged, axis=1), axis=0)) == len(merged)   # each face once


# ------------------------------------------------------------------ rounded distal tip
def test_rounded_tip_on_a_cylinder_gives_hemispheres_of_every_layer():
    """Cylinder R = 6 with a 6 mm tip: every shell is its own cylinder closed by a hemisphere (skin
    radii R - 0.5, R - 1.5; ring 3 and the bone scaled, so their domes are hemispheres too), so the
    layer volumes are closed-form and the skin is as thick round the tip as on the pad. The 128-gon
    rings and dome levels lose under 0.3 % of each volume."""
    import trimesh

    R, L, t3, bone_d = 6.0, 5.0, 1.2, 2.0
    m = cylinder_model(R, L, layer3_mm=t3, bone_diameter_mm=bone_d, bone_offset_mm=0.8, tip_mm=R)
    radii = np.array([R, R - 0.5, R - 1.5, R - 1.5 - t3, bone_d / 2])
    assert m.derived["tip_lengths_mm"] == pytest.approx(radii, rel=1e-3)
    shells = np.pi * radii**2 * L + 2 / 3 * np.pi * radii**3
    assert m.shell_volumes_mm3() == pytest.approx(shells, rel=3e-3)
    assert m.layer_volumes_mm3() == pytest.approx(shells - np.append(shells[1:], 0.0), rel=5e-3)
    # thickness round the tip: epidermis 0.5, dermis 1.0, layer 3 1.2 mm (the rings' chords cut 0.2 %)
    assert m.derived["min_thickness_tip"][:3] == pytest.approx([0.5, 1.0, t3], abs=0.02)
    for i in range(5):
        s = trimesh.Trimesh(m.vertices(), m.faces(i))
        assert s.is_watertight and s.is_winding_consistent
    assert len(np.unique(np.sort(m.faces(), axis=1), axis=0)) == len(m.faces())   # each face once
    # the outer radius follows the dome: at z1 + R sin(phi) it is R cos(phi)
    phi = np.linspace(0.1, 1.4, 5)
    assert m.outer_radius(np.full(5, 1.0), L + R * np.sin(phi)) == pytest.approx(R * np.cos(phi), rel=2e-3)
    assert "tip" in m.to_json()["regions"] and "distal" not in m.to_json()["regions"]


def test_rounded_tip_length_comes_from_the_preset_or_the_sections(tmp_path):
    from dataclasses import replace

    rounded = replace(params_for(None), tip_mm=None)
    m = model_from_args(None, "human", replace(params_for("human"), tip_mm=None))
    assert m.derived["tip_lengths_mm"][0] == 7.0                     # the preset's ellipsoidal cap
    # a cylinder R 5 closed by a hemisphere, sections every 0.5 mm up to 0.5 mm short of the apex:
    # the quarter ellipse from the cut at z = 8 through the last section's width gives R back
    z_body, z_tip = np.arange(0.0, 8.5, 0.5), 8.0 + np.arange(0.5, 5.0, 0.5)
    polys = [circle(5.0)] * len(z_body) + [circle(np.sqrt(25.0 - (zi - 8.0) ** 2)) for zi in z_tip]
    src = write_sections(tmp_path / "s", polys, np.append(z_body, z_tip))
    m = model_from_args(str(src), None, rounded, z_range_mm=(0.0, 8.0))
    assert m.derived["tip_lengths_mm"][0] == pytest.approx(5.0, rel=1e-3)
    # cut where the width drops below 90 % (z = 10), only 2.8 mm of tip is left: too short for the
    # 1.5 mm skin plus the inner layers to wrap round, which the error says
    with pytest.raises(InputError, match="too short to wrap the layers"):
        model_from_args(str(src), None, rounded)
    with pytest.raises(InputError, match="no sections beyond"):
        model_from_args(str(src), None, rounded, z_range_mm=(0.0, 12.5))


def test_tilted_distal_end_up_the_top_is_the_flat_cut_rim_or_the_rounded_pad():
    """Why the inclined experiments need the rounded tip: with the finger tilted 30 deg distal end
    up, the outer surface's highest point against the approach (where a plate touches first) is the
    rim of a flat distal cut, but on the pad of a rounded tip, where the tip has turned 30 deg."""
    from dataclasses import replace

    from fem.contact.indentors import approach_direction
    from fem.experiments.runner import scene_position

    place = {"approach": approach_direction(-30.0)}
    for tip in (0.0, 3.5):
        m = model_from_args(None, "monkey", replace(params_for("monkey"), tip_mm=tip))
        outer = m.vertices()[np.unique(m.faces(0))]                  # the outer shell
        x, y, z = scene_position("top", outer, place)
        if tip == 0:
            assert z == m.z_mm[-1]
        else:        # ellipsoidal cap: the normal turns 30 deg where (z - z1) / tip = sin 30 / ~1
            assert m.z_mm[-1] + 0.3 * tip < z < m.z_mm[-1] + 0.7 * tip
            assert y > 0                                          # on the pad (volar, +y)


def test_rounded_tip_too_short_for_the_layers_is_refused(tmp_path, capsys):
    with pytest.raises(InputError, match="too short to wrap the layers"):
        cylinder_model(6.0, 5.0, layer3_mm=1.2, tip_mm=2.0)      # layer 3's dome would pass the dermis'
    err = run_bad(["--preset", "monkey", "--tip", "1"], tmp_path / "o", capsys)
    assert "use at least" in err
    assert "--tip: 'round'" in run_bad(["--preset", "monkey", "--tip", "round"], tmp_path / "o", capsys)
    run_bad(["--preset", "monkey", "--tip", "-3"], tmp_path / "o", capsys)


# ------------------------------------------------------------------ bad input: exit 2, nothing written
def run_bad(args, out, capsys):
    assert pipeline.main(["mesh", *args, "--out", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: ") and "\n" not in err
    assert not out.exists()
    return err


def test_open_section_is_refused(tmp_path, capsys):
    arc = circle(6.0, 360)[:180]                      # half a circle: a gap of 12 mm
    src = write_sections(tmp_path / "s", [circle(6.0), arc, circle(6.0)])
    assert "not closed" in run_bad([str(src)], tmp_path / "o", capsys)


def test_self_intersecting_section_is_refused(tmp_path, capsys):
    bowtie = [[-5, -5], [5, 5], [5, -5], [-5, 5]]
    src = write_sections(tmp_path / "s", [circle(6.0), bowtie])
    assert "intersects itself" in run_bad([str(src)], tmp_path / "o", capsys)


def test_layer_thicker_than_section_is_refused(tmp_path, capsys):
    src = write_sections(tmp_path / "s", [circle(1.2)] * 3)
    assert "thicker than the section" in run_bad([str(src)], tmp_path / "o", capsys)
    src = write_sections(tmp_path / "s2", [circle(6.0)] * 3)
    assert "thicker than the section" in run_bad([str(src), "--layer3", "5"], tmp_path / "o", capsys)


def test_bone_outside_the_section_is_refused(tmp_path, capsys):
    src = write_sections(tmp_path / "s", [circle(6.0)] * 3)
    assert "bone" in run_bad([str(src), "--bone-offset", "4"], tmp_path / "o", capsys)
    assert "bone" in run_bad(["--preset", "human", "--bone-diameter", "12"], tmp_path / "o", capsys)


@pytest.mark.parametrize("preset, args", [
    ("monkey", ["--size", "0"]), ("monkey", ["--size", "-0.5"]), ("monkey", ["--coarse", "0"]),
    ("monkey", ["--epidermis", "0"]), ("monkey", ["--dermis", "-1"]), ("monkey", ["--bone-diameter", "0"]),
    ("monkey", ["--growth", "0"]), ("cylinder8", ["--size", "0"]), ("block", ["--coarse", "-1"]),
    ("square", ["--fine-depth", "0"])])
def test_zero_or_negative_sizes_are_refused(tmp_path, capsys, preset, args):
    run_bad(["--preset", preset, *args], tmp_path / "o", capsys)


def test_other_bad_options_are_refused(tmp_path, capsys):
    run_bad(["--preset", "dog"], tmp_path / "o", capsys)
    run_bad([], tmp_path / "o", capsys)                                           # no source, no preset
    run_bad(["--preset", "monkey", "--bone"], tmp_path / "o", capsys)
    run_bad(["--preset", "monkey", "--bone-profile", "0:0.2,x"], tmp_path / "o", capsys)
    run_bad(["--preset", "monkey", "--nail-z", "0.8", "0.2"], tmp_path / "o", capsys)
    run_bad(["--preset", "monkey", "--section-z", "99"], tmp_path / "o", capsys)
    run_bad([str(tmp_path / "missing")], tmp_path / "o", capsys)


def test_sections_json_with_the_tip_is_cut_before_the_rounded_tip(tmp_path):
    from fem.geometry.presets import make_shape

    shape = make_shape("fingertip", preset="human", rod=False)
    z = np.arange(0.0, 21.75, 0.5)                      # body 0-15 mm, rounded tip 15-22 mm
    polys = [shape.convex_section(zi, 90 + 7 * i) for i, zi in enumerate(z)]   # unequal counts
    src = write_sections(tmp_path / "s", polys, z)
    m = model_from_args(str(src), None, params_for(None))
    # widest section is about z = 7.5 (taper); width stays >= 90 % of it to about 4 mm into the tip
    assert 15.0 <= m.z_mm[-1] <= 19.0 and m.z_mm[0] == 0.0
    assert len(m.sections_sha256) == 64 and m.preset is None
    full = model_from_args(str(src), None, params_for(None), z_range_mm=(2.0, 9.0))
    assert full.z_mm[0] == 2.0 and full.z_mm[-1] == 9.0
    with pytest.raises(InputError, match="thicker than the section"):        # 0.37 x width at 21.5
        model_from_args(str(src), None, params_for(None), z_range_mm=(0.0, 21.5))


def test_inclined_support_is_recorded_with_the_vertical_direction():
    m = cylinder_model(support_incline_deg=30.0)
    sup = m.to_json()["regions"]["support"]
    assert sup["normal"] == [0.0, 1.0, 0.0] and sup["incline_deg"] == 30.0
    assert sup["vertical_up"] == pytest.approx([0.0, np.cos(np.pi / 6), -0.5])
    with pytest.raises(InputError):
        cylinder_model(support_incline_deg=95.0)


# ------------------------------------------------------------------ layer-3 and bone-offset defaults by size
def preset_replica(tmp_path, preset, scale=1.0):
    """sections.json of a preset's sections scaled in x and y by `scale` (a replica of that size)."""
    from fem.geometry.sections import preset_sections

    z, polys, _ = preset_sections(preset)
    return write_sections(tmp_path / f"{preset}_{scale:g}", [scale * p for p in polys], z)


def test_preset_middle_widths_and_size_rule_reproduce_the_presets():
    from fem.geometry.layered import (
        PRESET_MIDDLE_WIDTH_MM,
        PRESET_PARAMS,
        size_defaults,
    )
    from fem.geometry.sections import preset_sections

    for preset, width in PRESET_MIDDLE_WIDTH_MM.items():
        z, polys, _ = preset_sections(preset)
        mid = np.interp(0.5 * (z[0] + z[-1]), z, [np.ptp(p[:, 0]) for p in polys])
        assert mid == pytest.approx(width, abs=0.01), preset
        assert size_defaults(width) == PRESET_PARAMS[preset]
    assert size_defaults(4.0) == PRESET_PARAMS["monkey"] and size_defaults(25.0) == PRESET_PARAMS["human"]
    half = size_defaults(0.5 * sum(PRESET_MIDDLE_WIDTH_MM.values()))
    assert half == pytest.approx({"layer3_mm": 1.025, "bone_offset_mm": 0.575}, abs=1e-3)


def test_sections_json_gets_layer_defaults_by_its_size(tmp_path):
    monkey = preset_replica(tmp_path, "monkey")
    with pytest.raises(InputError, match="bone"):            # the human values do not fit a monkey section
        model_from_args(str(monkey), None, params_for(None, layer3_mm=1.5, bone_offset_mm=1.0))
    m = model_from_args(str(monkey), None, params_for(None))
    assert (m.params.layer3_mm, m.params.bone_offset_mm) == (0.55, 0.15)
    rec = m.to_json()["size_defaults"]
    assert rec["chosen"] == {"layer3_mm": 0.55, "bone_offset_mm": 0.15}
    assert rec["middle_width_mm"] == pytest.approx(8.56, abs=0.01) and "monkey" in rec["rule"]
    human = model_from_args(str(preset_replica(tmp_path, "human")), None, params_for(None))
    assert (human.params.layer3_mm, human.params.bone_offset_mm) == (1.5, 1.0)
    mid = model_from_args(str(preset_replica(tmp_path, "monkey", 1.5)), None, params_for(None))
    t = (1.5 * 8.56 - 8.56) / (17.12 - 8.56)                 # 1.5 x the monkey width: halfway
    assert mid.params.layer3_mm == pytest.approx(0.55 + t * 0.95, abs=2e-3)
    assert mid.params.bone_offset_mm == pytest.approx(0.15 + t * 0.85, abs=2e-3)


def test_explicit_layer_flags_override_the_size_defaults(tmp_path):
    src = preset_replica(tmp_path, "monkey")
    m = model_from_args(str(src), None, params_for(None, bone_offset_mm=0.3))
    assert (m.params.layer3_mm, m.params.bone_offset_mm) == (0.55, 0.3)
    assert m.derived["size_defaults"]["chosen"] == {"layer3_mm": 0.55}
    scaled = model_from_args(str(src), None, params_for(None, layer3_scale=0.7))
    assert scaled.params.layer3_mm is None and scaled.derived["f3"] == 0.7
    preset = model_from_args(None, "human", params_for("human"))        # presets keep their values
    assert (preset.params.layer3_mm, preset.params.bone_offset_mm) == (1.5, 1.0)
    assert preset.derived["size_defaults"]["chosen"] == {}


def test_smooth_polygon_follows_the_curve_through_the_vertices():
    """A 720-vertex ellipse (the presets' sampling) as a smooth curve: every sample within 1e-8 mm
    of the ellipse (measured 1.5e-10; the polygon's own chords sag up to 4e-5 mm), at most the
    spacing apart, convex and counter-clockwise, and its turning angle per length is the ellipse's
    curvature (b / a^2 = 0.203 to a / b^2 = 0.379 1/mm) within 1 %, where the polygon's is all at
    its vertices."""
    a, b = 4.0, 3.25
    t = np.linspace(0.0, 2 * np.pi, 720, endpoint=False)
    q = smooth_polygon(np.column_stack([a * np.cos(t), b * np.sin(t)]), spacing_mm=0.005)
    assert np.abs((q[:, 0] / a) ** 2 + (q[:, 1] / b) ** 2 - 1).max() * b / 2 < 1e-8
    step = np.linalg.norm(np.diff(np.vstack([q, q[:1]]), axis=0), axis=1)
    assert step.max() <= 0.005 + 1e-12
    e = np.diff(np.vstack([q, q[:2]]), axis=0)
    turn = (e[:-1, 0] * e[1:, 1] - e[:-1, 1] * e[1:, 0]) / (np.linalg.norm(e[:-1], axis=1) * np.linalg.norm(e[1:], axis=1))
    assert turn.min() > 0                                        # convex, CCW
    curvature = turn / step                                      # 1/mm
    assert 0.99 * b / a ** 2 < curvature.min() and curvature.max() < 1.01 * a / b ** 2
