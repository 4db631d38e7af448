"""fem.thesis.findings: how a check judges its number (band, mesh uncertainty, outcome), how a finding's
verdict follows from its checks, and how two mesh levels merge. Generated cases (hypothesis) cover the
bands; the claims' own findings are checked by tests.helpers.assert_computed in every thesis test."""
import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from fem.thesis.findings import (
    DIFFERS,
    REPRODUCED,
    UNCERTAIN,
    Check,
    Finding,
    levels,
    uncertainty_factor,
    verdict_of,
    with_coarse,
)
from tests.helpers import assert_computed

finite = st.floats(-1e6, 1e6, allow_nan=False)


@given(value=finite, limit=finite, coarse=st.none() | finite, test=st.sampled_from(["<", ">"]),
       factor=st.sampled_from([1.0, 3.0, 6.0]))
def test_one_sided_check_outcome(value, limit, coarse, test, factor):
    c = Check("x", value, test, limit, coarse=coarse, factor=factor)
    margin = value - limit if test == ">" else limit - value
    spread = 0.0 if coarse is None else factor * abs(value - coarse)
    assert c.margin == pytest.approx(margin)
    if spread > 0 and abs(margin) <= spread:
        assert c.outcome == UNCERTAIN
    else:
        assert c.outcome == (REPRODUCED if margin > 0 else DIFFERS)


@given(value=finite, limit=finite, tol=st.floats(0, 1e3), coarse=st.none() | finite)
def test_band_check_outcome(value, limit, tol, coarse):
    c = Check("x", value, "~", limit, tol=tol, coarse=coarse)
    inside = abs(value - limit) <= tol
    if c.outcome != UNCERTAIN:
        assert (c.outcome == REPRODUCED) == inside
    else:
        assert abs(abs(value - limit) - tol) <= abs(value - coarse)


def test_not_measured_differs_and_unknown_spread_is_uncertain():
    assert Check("x", math.nan, ">", 0).outcome == DIFFERS
    assert "not measured" in Check("x", math.nan, ">", 0).text()
    assert Check("x", 1.0, ">", 0, coarse=math.nan).outcome == UNCERTAIN
    with pytest.raises(ValueError, match="one of"):
        Check("x", 1.0, ">=", 0)


def test_verdict_precedence_and_no_finding_without_checks():
    ok, off, unsure = Check("a", 2, ">", 1), Check("b", 0, ">", 1), Check("c", 1.1, ">", 1, coarse=0.9)
    assert verdict_of([ok]) == REPRODUCED
    assert verdict_of([ok, unsure]) == UNCERTAIN
    assert verdict_of([ok, unsure, off]) == DIFFERS
    with pytest.raises(ValueError, match="no check"):
        Finding("k", "1", "t", "words", [])


def test_levels_merge_by_key_and_check():
    fine = [Finding("k", "1", "t", "words", [Check("a", 2.0, ">", 1.0, "mm"), Check("b", 0.5, "<", 1.0)])]
    coarse = [Finding("k", "1", "t", "words", [Check("a", 1.5, ">", 1.0, "mm"), Check("b", 1.2, "<", 1.0)])]
    (merged,) = with_coarse(fine, coarse)
    assert [c.coarse for c in merged.checks] == [1.5, 1.2]
    assert merged.checks[0].outcome == REPRODUCED                  # 1.0 inside by more than the 0.5 spread
    assert merged.checks[1].outcome == UNCERTAIN                   # 0.5 inside, moved 0.7
    assert merged.verdict == UNCERTAIN
    assert "coarser mesh 1.5 mm: mesh uncertainty 0.5 mm" in merged.reason
    assert_computed(merged)
    other = [Finding("k", "1", "t", "words", [Check("renamed", 1.5, ">", 1.0)])]
    with pytest.raises(ValueError, match="do not match"):
        with_coarse(fine, other)


def test_quick_and_full_runs_use_two_neighbouring_levels():
    (c1, f1), (c2, f2) = levels(True), levels(False)
    assert f1 == c2 and c1.size2d_mm == 2 * f1.size2d_mm and f2.size2d_mm == 0.0625 and f2.size3d_mm == 0.5


def test_the_uncertainty_is_the_grid_convergence_index_of_the_levels():
    """3 |fine - coarse| / (r - 1): quick levels r = 1.5 (the 3D sizes 1.5 and 1 mm; 2D halves), factor
    6; full levels r = 2, factor 3; with_coarse hands it to every check."""
    assert uncertainty_factor(*levels(True)) == pytest.approx(6.0)
    assert uncertainty_factor(*levels(False)) == pytest.approx(3.0)
    fine = [Finding("k", "1", "t", "words", [Check("a", 2.0, ">", 1.0, "mm")])]
    coarse = [Finding("k", "1", "t", "words", [Check("a", 1.8, ">", 1.0, "mm")])]
    (merged,) = with_coarse(fine, coarse, 6.0)
    check = merged.checks[0]
    assert check.uncertainty == pytest.approx(1.2) and check.outcome == UNCERTAIN     # 1.0 inside, 6 x 0.2
    assert Finding.from_json(merged.to_json()).checks[0].uncertainty == pytest.approx(1.2)


def test_the_resolution_is_the_floor_of_the_uncertainty():
    """A node-counted measure that does not move between the levels is still uncertain by its
    resolution: 0.913 against 'above 1' with resolution 0.2 is within mesh uncertainty, with none
    it differs; on one level the resolution alone is the uncertainty; the text names it."""
    c = Check("contact area ratio", 0.913, ">", 1.0, coarse=0.913, factor=6.0, resolution=0.2)
    assert c.uncertainty == pytest.approx(0.2) and c.outcome == UNCERTAIN
    assert "resolution 0.2: mesh uncertainty 0.2" in c.text()
    assert Check("contact area ratio", 0.913, ">", 1.0, coarse=0.913, factor=6.0).outcome == DIFFERS
    assert Check("x", 1.1, ">", 1.0, resolution=0.2).outcome == UNCERTAIN
    assert Check("x", 1.1, ">", 1.0, coarse=0.5, factor=3.0, resolution=0.2).uncertainty == pytest.approx(1.8)
