"""The examples run as shipped: examples/synthetic_sa1.py makes a recording from the model with
known parameters and the receptor analysis recovers them."""
import ast
import runpy
import sys

import pytest

from tests.helpers import ROOT


def test_synthetic_sa1_example_recovers_its_ground_truth(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(sys, "argv", ["synthetic_sa1.py", "--out", str(tmp_path / "out"),
                                      "--data", str(tmp_path / "data.csv")])
    runpy.run_path(str(ROOT / "examples" / "synthetic_sa1.py"), run_name="__main__")
    recovered = capsys.readouterr().out.split("recovered    :", 1)[1]
    best = ast.literal_eval(recovered.strip())                         # the dict the example prints
    assert best["measure"] == "sed_MPa" and float(best["depth_mm"]) == 0.75
    assert float(best["a_ips_per_measure_unit"]) == pytest.approx(8e5, rel=0.05)      # a: 805,175 measured
    assert float(best["b_ips"]) == pytest.approx(10.0, abs=1.0)                       # b: 9.62 measured
    assert (tmp_path / "data.csv").read_text().startswith("# SYNTHETIC")
