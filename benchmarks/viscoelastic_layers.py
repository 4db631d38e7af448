#!/usr/bin/env python
"""Layers with their own relaxation spectra against one spectrum for all, on the shipped
viscoelastic ramp-and-hold (scenes/ramp_hold_viscoelastic.toml: a 2 mm probe 1 mm into the monkey
pad in 0.1 s, held 0.5 s, released in 0.1 s; SA1, RA and PC afferents within 7 mm): the scene as
shipped (g = 0.2, 0.2, 0.2 at Pawluk and Howe's times in every layer: the correspondence
principle), and with the epidermis relaxing faster and further (g = 0.5 at 20 ms) and the bone
elastic (stepped in time, `fem.experiments.stepping`). Prints the run times, the force at the end
of the ramp, at the end of the hold and its least value in the release, and the afferents' spike
counts; writes the table to benchmarks/results/viscoelastic_layers.md.

    python benchmarks/viscoelastic_layers.py [--size 1.0] [--work out/viscoelastic_bench] [--no-write]
"""
from __future__ import annotations

import argparse
import dataclasses
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from fem.core.viscoelastic import LayerLaws, Prony  # noqa: E402
from fem.experiments.runner import run_scene  # noqa: E402
from fem.experiments.scene import load_scene  # noqa: E402
from fem.geometry.build import MeshSpec, build_folder  # noqa: E402

RESULTS = ROOT / "benchmarks" / "results" / "viscoelastic_layers.md"
EPIDERMIS = Prony((0.5,), (0.02,))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--size", type=float, default=1.0, help="volar element size of the monkey mesh (mm)")
    ap.add_argument("--work", type=Path, default=ROOT / "out" / "viscoelastic_bench")
    ap.add_argument("--no-write", action="store_true", help="print only (no results file)")
    args = ap.parse_args()
    folder = args.work / f"monkey_{args.size:g}"
    build_folder(folder, MeshSpec(preset="monkey", sizes={"size_mm": args.size}))
    shipped = dataclasses.replace(load_scene("ramp_hold_viscoelastic"),
                                  afferents=dataclasses.replace(load_scene("ramp_hold_viscoelastic").afferents,
                                                                nwb=False))
    layered = dataclasses.replace(shipped, viscoelastic=LayerLaws(shipped.viscoelastic,
                                                                  ((1, EPIDERMIS), (5, None))))
    rows = ["| layers | method | run s | force at 0.1 s mN | at 0.6 s mN | least in the release mN | "
            "spikes SA1 / RA / PC |", "|---|---|---|---|---|---|---|"]
    for name, scene in (("every layer g = 0.2, 0.2, 0.2", shipped),
                        ("epidermis g = 0.5 at 20 ms, bone elastic, others g = 0.2, 0.2, 0.2", layered)):
        t0 = time.perf_counter()
        run = run_scene(folder, scene)
        seconds = time.perf_counter() - t0
        e = run.experiments[0]
        t = e.experiment.times_s
        force = 1e3 * np.array([r.total_force_N for _, r in e.steps])
        pop, responses = run.afferents
        cls = pop.afferent_class.astype(str)
        n = np.array([len(s) for s in responses[e.name].spikes])
        spikes = " / ".join(str(int(n[cls == c].sum())) for c in ("SA1", "RA", "PC"))
        method = e.viscoelastic["method"].split(" (")[0]
        at = [force[np.argmin(np.abs(t - s))] for s in (0.1, 0.6)]
        rows.append(f"| {name} | {method} | {seconds:.1f} | {at[0]:.2f} | {at[1]:.2f} | "
                    f"{force[t > 0.6].min():.2f} | {spikes} |")
        print(rows[-1], flush=True)
    text = (f"# Viscoelastic layers: one spectrum and a spectrum per layer\n\n`python benchmarks/viscoelastic_layers.py`"
            f": the monkey preset at {args.size:g} mm ({run.model.ndof} DOFs), the mesh from the cache.\n\n"
            + "\n".join(rows) + "\n")
    if not args.no_write:
        RESULTS.write_text(text)
        print(f"results: {RESULTS}")


if __name__ == "__main__":
    main()
