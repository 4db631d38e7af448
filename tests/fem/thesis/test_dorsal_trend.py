"""Thesis 6.2.1 trend on coarse 3D fingertips (1.5 mm volar elements on the human, 1 mm on the
monkey): under a 2 mm line load the
entire dorsal half moves vertically less than 10 % of the maximum. Dorsal half: the outer surface
below the section centroid (as in benchmarks/contact_bench.py dorsal).

Human preset: it holds because the proximal cut's core is held (fem.io.modelfolder.HELD); with that cut
free this model gives 10.6 % (0.5 mm model 11.5 %), the largest motion on the free proximal cut,
against the thesis's statement that deformation fades faster proximally than distally.

Monkey preset: it does not hold (docs/verification.md): 11-14 % on the lateral flank next
to the load. The preset is the human one at half scale with the same 1.5 mm skin, so 2 mm is as
deep relative to its 3.5 mm volar half-height as 4 mm on the human; at 1 mm, the human's 2 mm
relative to the section, it holds. The tests pin both so that a change to either is noticed; the
human one is `extended` (`python -m pytest -m extended`): the default run checks the same code on the
monkey, and the human numbers are in the stored full reproduce run (docs/reproduction.md)."""
import pytest

import pipeline
from fem.thesis.chapters5_7 import dorsal_ratios


def _dorsal_ratios(tmp_path, preset, depths_mm, size_mm=1.0):
    out = tmp_path / preset
    assert pipeline.main(["mesh", "--preset", preset, "--size", str(size_mm), "--out", str(out), "--quiet"]) == 0
    return dorsal_ratios(out, preset, depths_mm)


@pytest.mark.extended         # 50 s, most of it meshing the human; the monkey test below runs by default
def test_dorsal_half_moves_less_than_10_percent_under_a_2_mm_line_load(tmp_path):
    [(surface, below_axis, proximal, distal)] = _dorsal_ratios(tmp_path, "human", [2.0], size_mm=1.5)
    assert 0.03 < surface < 0.10, surface                      # measured 7.2 % (1 mm mesh)
    assert 0.03 < below_axis < 0.10, below_axis                # measured 7.2 %
    assert proximal < distal


@pytest.mark.slow
def test_monkey_dorsal_half_is_under_10_percent_at_1_mm_but_not_at_2_mm(tmp_path):
    (surface2, _, proximal, distal), (surface1, _, _, _) = _dorsal_ratios(tmp_path, "monkey", [2.0, 1.0])
    assert 0.10 < surface2 < 0.17, surface2                    # measured 11.8-13.6 % (1.0 mm meshes)
    assert 0.03 < surface1 < 0.10, surface1                    # measured 6.1 %
    # Only the proximal cut's core is held (its skin goes on proximally, fem.io.modelfolder.HELD): on this
    # short body, the load 3.75 mm from the cut, the cut's skin moves more than the distal cut
    # (11.5 % against 8.3 %), against the thesis's order, which the human model keeps.
    assert 0.05 < proximal < 0.15 and 0.05 < distal < 0.15, (proximal, distal)
