"""Thesis 4.2-4.5 claims (fem.thesis.chapter4_receptors: point load, two points, bars;
fem.thesis.chapter4_gratings: gratings, gaps) on the coarse 2D models of a quick Workshop (0.25 mm
elements). The numbers in the docstrings were measured on them; where the 0.125 mm models give
another verdict it is said."""
import numpy as np
import pytest

from fem.thesis import chapter4_gratings, chapter4_receptors
from fem.thesis.findings import DIFFERS, REPRODUCED
from tests.helpers import by_key


def test_point_load_profiles_and_receptive_fields(shop):
    """Thesis 4.2. Half-peak widths at 0.5, 0.75, 1.0 mm: SED 0.62, 0.99, 1.36 mm, max compressive
    strain 1.04, 1.53, 2.04, |shear strain| 1.59, 2.39, 3.20 (0.125 mm: 0.67, 1.03, 1.37 for SED).
    The four models spread by at most 0.76 of the widening per 0.25 mm of depth. Swept load: SED
    disk 0.85 mm, compressive disk 1.27 mm, shear annulus 1.81 mm with a 0.25 mm hole (0.125 mm:
    0.27; thesis about 0.3). The profile under one load overstates the cylinders' fields by 17-45 %
    and matches the flat models within 4 %."""
    f = by_key(chapter4_receptors.point_load_fields(shop))
    depth = f["fig4-3_depth"]
    assert depth.verdict == REPRODUCED and 0.6 < depth.checks[2].value < 0.72      # SED over compressive: 0.66
    width = {(r["measure"], r["depth_mm"]): r["half_peak_width_mm"] for r in depth.table}
    assert width["SED", 0.75] == pytest.approx(1.0, abs=0.1)             # 0.99 here, 1.03 on 0.125 mm

    assert f["fig4-3_models"].verdict == REPRODUCED and f["fig4-3_models"].checks[0].value < 0.9

    fields = f["fig4-4_receptive_fields"]
    assert fields.verdict == REPRODUCED and fields.checks[2].value == pytest.approx(0.25, abs=0.05)
    half = {r["measure"]: r for r in fields.table if r["threshold_of_peak"] == 0.5}
    assert half["SED"]["shape"] == half["max compressive strain"]["shape"] == "disk"
    assert (half["SED"]["diameter_mm"] < half["max compressive strain"]["diameter_mm"]
            < half["|shear strain|"]["diameter_mm"])
    holes = [r["hole_mm"] for r in fields.table if r["measure"] == "|shear strain|"]
    assert holes == sorted(holes) and holes[0] < 0.15 and holes[-1] > 0.35  # 0.09-0.42: set by the threshold

    swap = f["sec4-2_reciprocity"]
    assert swap.verdict == DIFFERS and 25 < swap.checks[0].value < 40          # 32 % on the cylinder with bone
    rel = {(r["model"], r["measure"]): r["relative_difference"] for r in swap.table}
    assert all(abs(v) < 0.05 for (m, _), v in rel.items() if m in ("finite square", "semi-infinite (sides held)"))


def test_two_point_cues(shop):
    """Thesis 4.3. Equal displacement: 1.34 of one load's peak SED at 0.2 mm, then down and up
    again; equal force falls (a 2.2 % rise on the way here; 0.2 mm apart the tips share the apex
    node of 0.25 mm elements, so equal force is equal travel there, fem.contact.linear). Read as the
    distance between the loads, the equal-force cue settles (5 % of its 3 mm value) at 2.2 mm here,
    1.4 mm on the 0.125 mm models: one tip alone jitters between neighbouring places on 0.25 mm
    elements. Read as the half separation it does not settle before 4 mm here."""
    shapes, by_distance, by_half = chapter4_receptors.two_point_resolution(shop)
    assert shapes.checks[0].value == pytest.approx(1.34, abs=0.05)
    assert [c.outcome for c in shapes.checks[:3]] == [REPRODUCED] * 3
    rows = shapes.table
    assert rows[0]["equal_force_MPa"] == pytest.approx(rows[0]["equal_displacement_MPa"], rel=1e-6)
    assert by_distance.reading != by_half.reading and by_distance.thesis == by_half.thesis
    settle = by_distance.checks[0]
    assert settle.limit == 1.6 and 1.6 < settle.value <= 2.4 and by_distance.verdict == DIFFERS
    assert by_half.checks[0].limit == 3.2 and np.isnan(by_half.checks[0].value) and by_half.verdict == DIFFERS
    alone = np.array([r["one_tip_alone_force_MPa"] for r in rows[1:]])
    assert np.max(np.abs(np.diff(alone)) / alone[:-1]) > 0.05             # the jitter beyond the band
    disp = np.array([r["equal_displacement_MPa"] for r in rows])
    at = [r["separation_mm"] for r in rows].index(1.6)
    assert abs(disp[at] / disp[-1] - 1) > 0.05                             # still changing at 1.6 mm


def test_bar_on_the_four_models(shop):
    """Thesis 4.4. Edge over centre pressure 1.87, 1.78, 1.43, 1.44 (square, block, cylinder,
    cylinder with bone; 0.125 mm: 2.47-1.95). SED contrast 0.080 (square) against 0.186 (block,
    0.169 with free sides): the square is not the best, differs. |shear strain| contrast 0.96-1.0
    against at most 0.19. The bone: peak SED x 2.12, force x 1.32, SED contrast x 0.50."""
    f = by_key(chapter4_receptors.rectangular_bars(shop))
    edge = f["fig4-7_edge_pressure"]
    assert edge.verdict == REPRODUCED and 1.3 < edge.checks[0].value < 2.0
    rows = {r["model"]: r for r in edge.table}
    best, cylinders = f["fig4-7_model_contrast_all_models"], f["fig4-7_model_contrast_cylinders"]
    assert best.verdict == DIFFERS and best.checks[1].value < 0.7               # 0.43: the block has more
    assert cylinders.verdict == REPRODUCED and cylinders.checks[1].value > 1.3  # 1.54 over the cylinders
    for block in ("semi-infinite (sides held)", "semi-infinite, sides free"):
        # 2.3, 2.1 here; 1.7, 1.5 on 0.125 mm
        assert rows[block]["SED contrast"] > 1.3 * rows["finite square"]["SED contrast"]
    shear = f["fig4-7_shear_edges"]
    assert shear.checks[0].value == pytest.approx(0.3, abs=0.1) and shear.checks[0].outcome == REPRODUCED
    assert shear.checks[1].value == pytest.approx(1.13, abs=0.1)                # its peak is not the sharpest
    level, contrast = f["fig4-7_bone_level"], f["fig4-7_bone_contrast"]
    assert level.verdict == REPRODUCED and level.checks[3].value == pytest.approx(2.15, abs=0.1)
    assert contrast.verdict == DIFFERS and contrast.checks[3].value == pytest.approx(0.50, abs=0.05)
    cyl, held = rows["cylinder"], rows["cylinder with bone (held)"]
    assert held["force_N_per_mm"] / cyl["force_N_per_mm"] == pytest.approx(1.32, abs=0.03)


def test_gratings_on_cylinders_and_block(shop):
    """Thesis 4.5.2-4.5.4 with the 0.5 mm-bar grating. Bars touching: 1-4 on the 8 mm cylinder,
    1-5 on the 16 mm one, all 8 on the block. SED under each bar over the rightmost's (8 mm): 0.743,
    0.541, 0.657, 0.824, 0.966, 1.001, 1.000, 1.000. Two rightmost bars on the 16 mm model 1.8 %
    apart (differs: the 5 mm last gap). Off-centre profiles 0.191, 0.377 (8 mm), 0.0067, 0.0127
    (block: nearly a half-space's 0). Central profiles cylinder against block 0.267, population responses 0.188 (differs)."""
    runs = chapter4_gratings.grating_runs(shop)
    f = by_key(chapter4_gratings.grating_findings(runs))
    l8, l16, block = (label for _, label, _ in chapter4_gratings.GRATING_MODELS)
    assert runs[l8]["touching"].max() == 4 and runs[l16]["touching"].max() == 5
    assert np.all(runs[block]["touching"] == 8)
    assert np.allclose(runs[l8]["force"], runs[l8]["bar_force"].sum(axis=1))
    assert f["fig4-10_bars_in_contact"].verdict == REPRODUCED

    ratio = [r[f"SED {l8}"] for r in f["fig4-11_neighbours"].table]          # bars from the left
    assert f["fig4-11_neighbours"].verdict == REPRODUCED
    np.testing.assert_allclose(ratio, [0.737, 0.528, 0.635, 0.814, 0.954, 0.999, 1.0, 1.0], atol=0.03)

    more = f["fig4-12_diameter"]                                               # bars 2 and 3, not 1, 2, 3
    assert more.verdict == DIFFERS and [c.value for c in more.checks] == [1.0, 2.0, 0.0]
    assert f["sec4-5-3_rightmost_bars"].verdict == DIFFERS and f["sec4-5-3_rightmost_bars"].checks[0].value < 3.0

    off = f["fig4-18_off_centre"]
    assert off.verdict == REPRODUCED and off.checks[1].value == pytest.approx(30, abs=3)
    rms = {(r["model"], r["receptor_off_centre_mm"]): r["rms_difference"] for r in off.table}
    assert rms[block, 2.0] < 0.1 < rms[l8, 1.0]                              # 0.013 against 0.191

    central = f["sec4-5-4_central_profiles"]
    assert central.verdict == DIFFERS and central.checks[0].value == pytest.approx(1.42, abs=0.1)
    share = runs[block]["bar_force"][0] / runs[block]["force"][0]
    assert share[-1] > share[1:-1].max()                                      # the end bars carry the most


def test_gap_peaks(fine_shop):
    """Thesis 4.5.5, two 2 mm bars, on 0.125 mm elements (on 0.25 mm ones a 0.25 mm gap is one
    element: its peaks 0.40 mm apart, differs). Inter-peak distance 0.67, 0.79, 0.84, 1.04, 1.56,
    2.07, 3.09 mm for gaps 0.25-3 mm: within 3.8 % of the gap from 1 mm up, levelling off near the
    receptor depth below."""
    (f,) = chapter4_gratings.gap_detection(fine_shop)
    assert f.verdict == REPRODUCED and f.checks[0].value == pytest.approx(3.8, abs=1.0)
    dist = {r["gap_mm"]: r["interpeak_mm"] for r in f.table}
    assert dist[0.5] - dist[0.25] < 0.25                                   # 0.12 mm for 0.25 mm more gap
    assert dist[3.0] - dist[1.0] == pytest.approx(2.0, abs=0.2)            # slope 1 above it
