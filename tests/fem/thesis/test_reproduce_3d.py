"""Thesis chapters 6-7 claims on the 3D monkey preset (1 mm elements, fem.thesis.chapters5_7): the bar in
3D (figures 6-25, 7-4), the 2D section against 3D (figures 7-2, 7-3) and step 5 across the pad
(figure 6-39). The cylinder series and layer study behind the other 3D claims are pinned on 2D
models in tests/fem/biomech/test_biomech.py; dorsal ratios in tests/fem/thesis/test_dorsal_trend.py."""
import numpy as np
import pytest

from fem.thesis import chapters5_7 as thesis3d
from fem.thesis.findings import DIFFERS, REPRODUCED, UNCERTAIN
from tests.helpers import by_key


def test_bar_in_3d_bends_the_stiff_epidermis_and_stays_local(shop):
    """Measured on the 1 mm (reproducible) mesh: SED 1.0 / 0.75 mm deep 1.23 (m43338), 0.94
    (m33338); 86 % and 82 % of the section below 10 % of the peak SED (thesis 85 %); deflection
    1 mm beside the bar 1.34x with m43338, but the contact area 0.91x (the thesis: wider), within its
    resolution (1.5: on 1 mm elements most of each contact area is its outer ring of nodes)."""
    f = by_key(thesis3d.bars_3d(shop))
    depth, local, gradual = f["fig6-25_bar_depth"], f["fig7-4_local"], f["sec7-1-2_gradual"]
    assert depth.verdict == REPRODUCED and depth.checks[0].value == pytest.approx(1.23, abs=0.05)
    rows = {r["material"]: r for r in depth.table}
    assert rows["m33338"]["sed_peak_1.0mm_MPa"] < rows["m33338"]["sed_peak_0.75mm_MPa"]
    assert "lower at 1.0 mm" in depth.notes
    assert local.verdict == REPRODUCED
    for r in rows.values():
        assert 0.8 < r["section_below_10pct"] < 0.9
    assert gradual.checks[0].value > 1.2 and gradual.checks[0].outcome == REPRODUCED
    area = gradual.checks[1]
    assert area.value < 1 and area.resolution > 1 - area.value and gradual.verdict == UNCERTAIN


def test_2d_section_against_3d(shop):
    """Measured (1 mm elements, the reproducible mesh): 3D / 2D peak max compressive strain 1.26 with
    profiles correlated 0.997; 2D / 3D peak SED 0.78 against the thesis's > 1 (the plane-strain
    factor 1 / (1 - nu^2) = 1.30 times the load ratio 0.96 within 1 %). The section 2 mm off is
    *more* strained here (SED 1.06x)."""
    f = by_key(thesis3d.sections_2d_3d(shop))
    eps, sed, off = f["fig7-2_eps1"], f["fig7-2_sed"], f["fig7-3_off_centre"]
    assert eps.checks[0].value > 0.99 and eps.checks[1].value == pytest.approx(1.25, abs=0.06)
    assert eps.verdict == DIFFERS and "1 / 1.30 at nu = 0.48" in eps.notes
    assert sed.verdict == DIFFERS and 0.7 < sed.checks[0].value < 0.9
    assert off.verdict == DIFFERS and off.checks[0].value == pytest.approx(1.06, abs=0.03)


def test_step_across_the_pad(shop):
    """Measured: the smallest contact 0.65 mm from the middle of the convex-half datums (within its
    quarter wavelength), the largest 1.08 mm from the concave half's middle (just outside), both
    within their resolution (positions 5 and 6 mm away have areas that cannot be told apart on 1 mm
    elements); area against peak pressure rank correlation -0.54 (resolution 0.71) and opposite
    moves at 56 % of the steps, not the thesis's 'always'. Receptors 0.75 mm deep at x = -1.5, 0,
    +1.5 mm: their peak-normalised spatial response profiles, aligned on the receptor, differ by up
    to 65 % of the peak."""
    f = by_key(thesis3d.steps_3d(shop))
    ext = f["fig6-39_step_extremes"]
    assert abs(ext.checks[0].value) < 0.9 and abs(ext.checks[1].value) > 0.9
    assert min(c.resolution for c in ext.checks) > 2 and ext.verdict == UNCERTAIN
    areas = [r["contact_area_mm2"] for r in ext.table]
    assert areas[0] == pytest.approx(areas[-1], rel=0.02)       # the two flats: the same contact
    trend, every = f["fig6-39_step_inverse_trend"], f["fig6-39_step_inverse_every_step"]
    assert -0.8 < trend.checks[0].value < -0.3 and trend.verdict == UNCERTAIN
    assert every.verdict == DIFFERS and 40 < every.checks[0].value < 70
    assert trend.series[0].x == [r["contact_area_mm2"] for r in trend.table]   # its own figure: area against pressure
    spatial = f["fig6-38_spatial_response"]
    assert spatial.verdict == REPRODUCED and spatial.checks[0].value == pytest.approx(65, abs=10)
    peaks = [r["peak_sed_Pa"] for r in spatial.table]
    assert peaks[1] > 1.5 * max(peaks[0], peaks[2])          # the receptor under the pad's top feels most


def test_layer2_sense_turns_with_the_skin_thickness(shop):
    """Fig. 6-10 on the monkey section (0.25 mm elements). Measured: stiffening layer 2 changes the
    deflection 0.5 mm from a 2 mm wedge by -0.44 mm (sign change 1.55 mm); the thesis's prescribed
    nodal line gives -0.59 mm linear (sign change 1.92 mm), and neo-Hookean its Newton stalls at
    0.74 mm of the 2 mm (J 0.43 beside the pushed node: a node pushed into 0.25 mm elements); a
    0.25 + 0.25 mm skin gives +0.21 mm (more deflection from 0.23 to 2.51 mm), the thesis's sense."""
    from fem.biomech.deflection import DeflectionExperiment

    section = shop.folder("monkey_section", thesis3d.monkey_section(5.0))
    exp = DeflectionExperiment(section)
    near, flips = thesis3d.layer2_change(*(exp.profiles(c, (2.0,))[0].at for c in thesis3d.LAYER2_CODES))
    assert near == pytest.approx(-0.44, abs=0.05) and flips == [pytest.approx(1.55, abs=0.15)]
    reasons = thesis3d.layer2_reasons(shop)
    assert reasons["2D section, nodal line"][0] == pytest.approx(-0.59, abs=0.05)
    assert np.isnan(reasons["2D section, nodal line, neo-Hookean"][0])        # reported as not reaching 2 mm
    thin_near, thin_flips = reasons[thesis3d.THIN_LABEL]
    assert thin_near == pytest.approx(0.21, abs=0.05) and thin_flips[-1] == pytest.approx(2.51, abs=0.2)
