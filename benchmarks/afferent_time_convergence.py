#!/usr/bin/env python
"""Are a scene's spike counts converged in time? Three courses on the 1 mm monkey preset with the
shipped afferent material (a 2 mm flat probe and a 3 mm sphere pressed 1 mm in a ramp-and-hold; the
sphere in a 40 Hz sine about half the depth, 8 cycles), SA1, RA and PC within 7 mm, noise off:
spike counts per class against the load table's tolerance (`fem.experiments.spiking.tabulate`, the
scene default TABLE_TOLERANCE) and the trace's sample count, and, for comparison, driven from the
samples linearly in time (how the inputs reached the transduction before the load tables).

    python benchmarks/afferent_time_convergence.py [--work out/afferents_bench] [--no-write]

Writes the table to benchmarks/results/afferent_time_convergence.md.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from fem.experiments.runner import run_experiments  # noqa: E402
from fem.experiments.scene import Scene, load_scene  # noqa: E402
from fem.experiments.spiking import TABLE_TOLERANCE, fine_loads, load_value, tabulate  # noqa: E402
from fem.io.modelfolder import read_model  # noqa: E402
from fem.receptors.afferents import experiment_inputs, place, respond, sampler_of  # noqa: E402
from fem.receptors.transduction import CLASSES  # noqa: E402
from fem.thesis.findings import Workshop  # noqa: E402

RESULTS = ROOT / "benchmarks" / "results" / "afferent_time_convergence.md"
TOLERANCES = (0.1, 0.01, TABLE_TOLERANCE, 0.0003)
COURSES = {                               # name: (indentor, trace, sample counts)
    "flat probe, ramp and hold": ("punch:2", {"shape": "ramp_hold"}, (25, 100, 400)),
    "sphere, ramp and hold": ("sphere:3", {"shape": "ramp_hold"}, (25, 100, 400)),
    "sphere, 40 Hz sine about half the depth": ("sphere:3", {"shape": "sine", "frequency_hz": 40, "cycles": 8,
                                                             "offset": 0.5}, (64, 160, 640)),
}


def counts(pop, resp) -> str:
    cls = pop.afferent_class.astype(str)
    n = np.array([len(s) for s in resp.spikes])
    return " / ".join(str(int(n[cls == c].sum())) for c in CLASSES)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--work", default="out/afferents_bench", help="folder for the meshed preset (cached)")
    ap.add_argument("--no-write", action="store_true", help="print only (no results file)")
    args = ap.parse_args()
    material = load_scene(ROOT / "scenes" / "ramp_hold.toml").material
    model, info = read_model(Workshop(args.work, quick=True).preset("monkey"), material)
    rows = ["| course | samples | inputs | loads | spikes SA1 / RA / PC | time |", "|---|---|---|---|---|---|"]
    pop = None
    for name, (indentor, trace, sample_counts) in COURSES.items():
        for samples in sample_counts:
            scene = Scene.from_dict({"material": list(material), "experiment": [
                {"indentor": indentor, "depth_mm": 1.0, "trace": {**trace, "samples": samples}}]})
            run = run_experiments(model, info, scene)
            e = run.experiments[0]
            exp = e.experiment
            if pop is None:                         # one population for every course: where the probe touches
                points = run.contact.points_mm
                pop = place(model, run.surface, CLASSES, None, points[np.argmin(e.indentor.standoff(points))], 7.0, 0)
                sampler = sampler_of(model, pop)
            t0 = time.perf_counter()
            static, deflection = experiment_inputs(sampler, pop, run.contact, e)
            linear = respond(pop, exp.times_s, static, deflection, noisy=False)
            rows.append(f"| {name} | {samples} | samples, linear in time | - | {counts(pop, linear)} | "
                        f"{time.perf_counter() - t0:.1f} s |")
            for tol in TOLERANCES:
                t0 = time.perf_counter()
                table = tabulate(sampler, pop, run.contact, e, tolerance=tol)
                at = table.at([load_value(load) for _, load in exp.indentations])
                resp = respond(pop, exp.times_s, *at, noisy=False, fine=table.at(fine_loads(exp)))
                mark = " (default)" if tol == TABLE_TOLERANCE else ""
                rows.append(f"| {name} | {samples} | load table, tolerance {tol:g}{mark} | {len(table.load)} | "
                            f"{counts(pop, resp)} | {time.perf_counter() - t0:.1f} s |")
            print(*rows[-1 - len(TOLERANCES):], sep="\n", flush=True)
    head = (f"# Spike counts against the time sampling\n\n`python benchmarks/afferent_time_convergence.py`: "
            f"the 1 mm monkey preset ({model.ndof} DOFs), {len(pop)} afferents "
            f"({', '.join(f'{int((pop.afferent_class == c).sum())} {c}' for c in CLASSES)}) within 7 mm, noise off. "
            f"Time: computing the inputs and the spikes (the course's contact solves are the run's).\n\n")
    if not args.no_write:
        RESULTS.write_text(head + "\n".join(rows) + "\n")
        print(f"results: {RESULTS}")


if __name__ == "__main__":
    main()
