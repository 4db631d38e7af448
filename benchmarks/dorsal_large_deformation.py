#!/usr/bin/env python
"""Does large deformation explain the monkey's dorsal ratio above 10 %? Linear against neo-Hookean
under the same load: the volar vertices within 0.25 mm of the middle section and within
--half-length mm of the midline pushed down by --depth mm, held sideways (fem.core.neohookean's line
load), the model folder held as fem.io.modelfolder.open_model holds it, m43338, nu 0.48.

    python benchmarks/dorsal_large_deformation.py out/monkey08 [--half-length 3] [--depth 1.6]

Prints, per converged load step, the largest |u_y| over all nodes with y < 0 divided by the largest
|u_y| overall, for the neo-Hookean solve and for the linear one (the same at every depth), and the
run time. Result (0.8 mm monkey preset, 64k DOFs, 11 loaded vertices): linear 13.8 %; neo-Hookean
13.4, 12.7, 12.0, 12.7 % at 0.4, 0.8, 1.36, 1.6 mm; 347 s.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from fem.biomech.line_load import line_load_model  # noqa: E402
from fem.core.neohookean import NeoHookean  # noqa: E402
from fem.io.modelfolder import held_regions  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("model", help="3D model folder (mesh.vtu, model.json)")
    ap.add_argument("--half-length", type=float, default=3.0, help="loaded vertices within this of x = 0 (mm)")
    ap.add_argument("--depth", type=float, default=1.6, help="push depth (mm)")
    args = ap.parse_args()
    model, _ = line_load_model(args.model, material="m43338", nu=0.48, half_width_mm=0.25,
                               half_length_mm=args.half_length)
    prescribed = {**held_regions(model), "load": (0.0, -args.depth, 0.0)}
    dorsal = model.nodes[:, 1] < 0

    def ratio(u):
        uy = np.abs(u.reshape(-1, 3)[:, 1])
        return uy[dorsal].max() / uy.max()

    t = time.perf_counter()
    linear = ratio(model.system(prescribed).u0)
    print(f"{model.ndof} DOFs, {len(model.region_nodes('load'))} loaded vertices; linear ratio {linear:.1%}",
          flush=True)
    res = NeoHookean(model).solve(prescribed, steps=20, partial=True, progress=True)
    for tk, u in zip(res.t[1:], res.u[1:]):
        print(f"depth {args.depth * tk:.2f} mm: neo-Hookean ratio {ratio(u):.1%} (linear {linear:.1%})")
    print(f"stopped: {res.stopped}; {time.perf_counter() - t:.0f} s")


if __name__ == "__main__":
    main()
