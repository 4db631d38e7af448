"""Thesis chapter-4 claims (fem.thesis.chapter4_mechanics) on coarse 2D models, and `pipeline.py
reproduce`: report, resume, refusals. The dorsal-half claim (3D) is pinned by tests/fem/thesis/test_dorsal_trend.py."""
import json

import numpy as np
import pytest

import pipeline
from fem.thesis import chapter4_mechanics
from fem.thesis import claims as thesis
from fem.thesis.findings import DIFFERS, REPRODUCED
from tests.helpers import by_key


def test_block_with_held_sides_matches_flamant(shop):
    """Thesis 4.1: measured 4.5 % (held) and 17.5 % (free) at r = 3 mm, 60 deg, 0.25 mm mesh."""
    (f,) = chapter4_mechanics.flamant_block(shop)
    assert f.verdict == REPRODUCED and abs(f.value) < 5.0
    rows = {(r["block"], r["r_mm"], r["angle_deg"]): r["fe_over_flamant"] for r in f.table}
    assert abs(rows[("40 x 18 mm, sides free", 3.0, 60)] - 1) > 0.12          # the free-sides block is not
    assert abs(rows[("40 x 18 mm, sides held", 1.0, 0)] - 1) < 0.02            # on the load axis: 0.1 %


def test_cylinders_follow_plane_strain_hertz_not_a_square_root_law(shop):
    """Thesis 4.6: the solid model's C1 - C8 depth difference is the plane-strain Hertz value
    (measured -4.7 % at F*, -4.1 % at F*/10), a log-log slope near 0.12, not 0.5; the solid-fluid
    model is deeper for every cylinder and keeps its volume (6.7e-11 of the core's area)."""
    runs = chapter4_mechanics.cylinder_runs(shop)
    findings = by_key(chapter4_mechanics.cylinder_findings(runs, shop.size_mm))
    depth = findings["fig4-24_depth"]
    assert depth.verdict == DIFFERS and 0.05 < depth.value < 0.2
    for level in ("F*", "F*/10"):
        fe = runs.results[("solid, bone held", level)]["depth_mm"]
        hertz = runs.hertz[("solid, bone held", level)]
        assert fe[0] - fe[-1] == pytest.approx(hertz[0], rel=0.08)
    fluid = runs.results[("solid-fluid", "F*/10")]["depth_mm"]
    solid = runs.results[("solid, bone held", "F*/10")]["depth_mm"]
    assert np.all(fluid > 5 * solid)
    assert runs.volume["F*/10"] < 1e-9
    assert findings["fig4-25_contact"].verdict == REPRODUCED


def test_line_load_order_of_the_four_models(shop):
    """Thesis 4.7: square, semi-infinite (sides held), cylinder, cylinder with bone."""
    (f,) = chapter4_mechanics.line_load_order(shop)
    assert f.verdict == REPRODUCED
    at2 = {r["model"]: r["deflection_2mm"] for r in f.table}
    assert at2["semi-infinite, sides free"] > at2["finite square"]       # free sides would swap them


def test_appendices(shop):
    a, b = chapter4_mechanics.appendices(shop)
    assert a.verdict == b.verdict == REPRODUCED
    assert a.value < 0.01 and b.value < 1e-6


def test_reproduce_writes_a_report_and_resumes(tmp_path, monkeypatch, capsys):
    out = tmp_path / "report"
    monkeypatch.setattr(thesis, "CLAIMS", (("appendices", chapter4_mechanics.appendices),))
    assert pipeline.main(["reproduce", "--quick", "--out", str(out), "--quiet"]) == 0
    md, page = (out / "index.md").read_text(), (out / "index.html").read_text()
    for text in (md, page):
        assert "appendix A" in text and "appendix B" in text and "reproduced" in text
        assert "Not run here" in text
    assert (out / "claims" / "appA_sed.png").stat().st_size > 1000
    saved = json.loads((out / "claims" / "appendices.json").read_text())
    assert [f["key"] for f in saved] == ["appA_sed", "appB_modulus"]

    def boom(shop):
        raise AssertionError("a finished claim was run again")

    monkeypatch.setattr(thesis, "CLAIMS", (("appendices", boom),))
    assert pipeline.main(["reproduce", "--quick", "--out", str(out)]) == 0
    assert "1 claims resumed" in capsys.readouterr().out
    assert (out / "index.md").read_text() == md


def test_reproduce_refuses_a_foreign_or_other_kind_of_folder(tmp_path, capsys):
    out = tmp_path / "report"
    out.mkdir()
    (out / "reproduce.json").write_text(json.dumps({"quick": True}))
    assert pipeline.main(["reproduce", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error:") and "--quick" in err[0]
    other = tmp_path / "other"
    other.mkdir()
    (other / "notes.txt").write_text("mine")
    assert pipeline.main(["reproduce", "--quick", "--out", str(other)]) == 2
    assert "not empty" in capsys.readouterr().err
    assert sorted(p.name for p in other.iterdir()) == ["notes.txt"]


def test_report_tables_take_the_union_of_row_columns():
    from fingertip.jobs.reproduce import _table

    keys, rows = _table([{"model": "3D", "layer": 2, "most_affected_mm": 1.25}, {"model": "2D", "change_mm": -0.5}])
    assert keys == ["model", "layer", "most_affected_mm", "change_mm"]
    assert rows == [["3D", "2", "1.25", ""], ["2D", "", "", "-0.5"]]
