"""Thesis 6.2.1 trend on a coarse 3D human fingertip (1 mm volar elements): under a 2 mm line load
the entire dorsal half moves vertically less than 10 % of the maximum. It holds because the
proximal cut is held (fem.contact.open_model); with that cut free this model gives 10.6 % (0.5 mm
model 11.5 %), the largest motion on the free proximal cut, against the thesis's statement that
deformation fades faster proximally than distally."""
import numpy as np
import pytest

import pipeline
from fem.contact import ContactModel, open_model
from fem.indentors import make_indentor


@pytest.mark.slow
def test_dorsal_half_moves_less_than_10_percent_under_a_2_mm_line_load(tmp_path):
    out = tmp_path / "human"
    assert pipeline.main(["mesh", "--preset", "human", "--size", "1.0", "--out", str(out), "--quiet"]) == 0
    model, system, region, _ = open_model(out)
    cm = ContactModel.from_fe(model, system, region)
    z = cm.points_mm[:, 2]
    wedge = make_indentor("wedge", orientation="perpendicular", position_mm=(0.0, 0.5 * (z.min() + z.max())))
    res = cm.indent(wedge, depth_mm=2.0)
    uy = np.abs(cm.compliance(wedge.approach).displacement(res.force_N).reshape(-1, 3)[:, 1])
    assert uy.max() == pytest.approx(2.0, rel=1e-6)             # the wedge's depth
    ratio = uy[model.nodes[:, 1] < 0].max() / uy.max()
    assert 0.03 < ratio < 0.10, ratio                           # measured 7.2 %
    assert uy[model.region_nodes("proximal")].max() < uy[model.region_nodes("distal")].max()
