#!/usr/bin/env python
"""Spiking afferents after setup: the shipped ramp-and-hold scene (scenes/ramp_hold.toml: a 2 mm
probe 1 mm deep, 100 sample times plus the course's corners, SA1 and RA within 7 mm) on a 3D preset,
timed phase by phase, against the plain peer a user would write in the same run.

    python benchmarks/afferents_bench.py                      # human preset, 1 mm elements
    python benchmarks/afferents_bench.py --preset monkey --work out/aff_bench

Setup (not counted in "after setup"): reading the model, assembly and factorisation with the
probe's reachable candidates condensed. After setup: the contact solves of every sample time (each
distinct depth once), the afferents' placement, receptor operators at their sites, their inputs
(one solve with a right-hand side per distinct depth), and the transduction of every afferent at
5 kHz. The peer: one full solve and one sampling per sample time (no repeated depth skipped, one
right-hand side at a time), then the same transduction; its inputs must equal the project's (the
difference is printed). Files are not written (the command's CSVs and PNGs add about 2-4 s).
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from fem.experiments.runner import run_experiments
from fem.experiments.scene import load_scene
from fem.experiments.spiking import scene_responses
from fem.io.modelfolder import read_model
from fem.receptors.afferents import respond, sampler_of
from fem.thesis.findings import Workshop

SCENE = Path(__file__).resolve().parents[1] / "scenes" / "ramp_hold.toml"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--preset", default="human", choices=("human", "monkey"))
    ap.add_argument("--size", type=float, default=1.0, help="volar element size of the preset mesh (mm)")
    ap.add_argument("--work", default="out/afferents_bench", help="folder for the meshed preset (cached)")
    args = ap.parse_args()
    folder = Workshop(args.work, quick=True).preset(args.preset, args.size)
    scene = load_scene(SCENE)

    t0 = time.perf_counter()
    model, info = read_model(folder, scene.material, scene.nu)
    run = run_experiments(model, info, scene)
    t1 = time.perf_counter()
    solve_s = sum(e.seconds for e in run.experiments)
    setup = t1 - t0 - solve_s
    pop, responses = scene_responses(run)
    t2 = time.perf_counter()
    exp = run.experiments[0]
    resp = responses[exp.name]
    after = solve_s + (t2 - t1)

    # the peer: every sample time on its own
    t4 = time.perf_counter()
    e = exp
    comp = run.contact.compliance(e.indentor.approach)
    sampler = sampler_of(model, pop)
    static = np.empty((len(pop), len(e.steps)))
    for j, (_, r) in enumerate(e.steps):
        u = comp.displacement(r.force_N)
        stress = sampler.state(sampler.operator @ u).stress
        static[:, j] = -np.einsum("ni,nij,nj->n", pop.normal, stress, pop.normal)
    deflection = np.stack([pop.at_sites(r.deflection_mm) for _, r in e.steps], axis=1)
    peer = respond(pop, resp.times_s, static, deflection, noisy=True, seed=0)
    t5 = time.perf_counter()
    counts = [sum(len(x) for x in r.spikes) for r in (resp, peer)]
    diff = float(np.abs(static - resp.static).max() / max(np.abs(resp.static).max(), 1e-30))

    cls = pop.afferent_class.astype(str)
    distinct = len({id(r) for _, r in e.steps})
    print(f"{args.preset} preset, {args.size:g} mm elements: {model.ndof} DOFs; {len(e.steps)} sample times "
          f"({distinct} distinct depths); {len(pop)} afferents ({', '.join(f'{(cls == c).sum()} {c}' for c in np.unique(cls))})")
    print(f"setup (read, assemble, factorise): {setup:.2f} s")
    print(f"after setup: {after:.2f} s = contact solves {solve_s:.3f} s + afferents (placement, operators, "
          f"inputs, transduction) {t2 - t1:.2f} s")
    print(f"peer (one solve per sample time): {t5 - t4:.2f} s; ratio {(t5 - t4) / (t2 - t1):.1f}x; inputs at the "
          f"sample times differ by {diff:.1e} (relative); spikes {counts[0]} (the project: load table of "
          f"{resp.table_loads} depths read at 5 kHz) and {counts[1]} (the peer: samples linear in time)")
    rates = resp.rates_hz
    for c in np.unique(cls):
        sel = cls == c
        print(f"  {c}: mean rate ramp {rates(0.0, 0.1)[sel].mean():.1f} Hz, hold {rates(0.15, 0.6)[sel].mean():.1f} Hz, "
              f"release {rates(0.6, 0.7)[sel].mean():.1f} Hz; fired {int((rates()[sel] > 0).sum())} of {sel.sum()}")


if __name__ == "__main__":
    main()
