#!/usr/bin/env python
"""The same stimulus on the published model's flat skin and on the finger: how curvature and layers
change what the afferents get. The shipped ramp-and-hold (scenes/ramp_hold.toml: a 2 mm probe to
1 mm in 0.1 s, held 0.5 s, released in 0.1 s) on the 1 mm human preset with the scene's material,
and on TouchSim's half-space (E = 0.05 MPa, nu = 0.4: Sneddon's flat punch, stress and surface
deflection in closed form; tests/fem/verify/test_sneddon.py checks the solver against it). Both carry 0.119 N
in the hold. Afferents on the line across the pad through the point the probe touches first:
an SA1 (0.3 mm deep) and an RA (1.6 mm) below every pad node within 0.3 mm of it, model 0 of each
class, noise off.

    python benchmarks/afferents_flat_vs_finger.py [--work out/afferents_bench] [--figure docs/img/afferents_flat_vs_finger.png]

Prints, per class, the peak static input and the half-peak width of its profile across the line,
the span of the afferents that fire, and the surface deflection 3 mm from the probe, flat against
finger; draws the profiles. Result (1 mm human preset, 141,633 DOFs, about 40 s):
  flat   SA1 peak 28.2 kPa, half-peak width 1.96 mm, hold spikes under the probe (|x| <= 1 mm), 24 Hz
  finger SA1 peak 47.9 kPa, width 1.63 mm, hold spikes from -1.6 to +0.3 mm, 38 Hz
  flat   RA peak 13.0 kPa, width 2.55 mm, ramp spikes under the probe, 33 Hz
  finger RA peak 9.7 kPa, width 2.64 mm, ramp spikes from -1.6 to +0.7 mm, 33 Hz
  surface deflection 3 mm from the probe: flat 0.216 mm, finger 0.264 and 0.142 mm
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from fem.experiments.runner import run_experiments
from fem.experiments.scene import load_scene
from fem.io.modelfolder import read_model
from fem.receptors.afferents import Population, experiment_inputs, respond, sampler_of
from fem.thesis.findings import Workshop
from fem.verify.closed_forms import sneddon_punch_force_N, sneddon_punch_stress_zz_MPa

ROOT = Path(__file__).resolve().parents[1]
E_MPA, NU, RADIUS_MM, DEPTHS = 0.05, 0.4, 1.0, {"SA1": 0.3, "RA": 1.6}


def half_width(x, y) -> float:
    """Width [mm] of the region where y >= max(y) / 2 (outermost crossings)."""
    on = x[y >= 0.5 * y.max()]
    return float(on.max() - on.min())


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--work", default="out/afferents_bench", help="folder for the meshed preset (cached)")
    ap.add_argument("--figure", default=str(ROOT / "docs" / "img" / "afferents_flat_vs_finger.png"))
    args = ap.parse_args()
    scene = load_scene(ROOT / "scenes" / "ramp_hold.toml")
    model, info = read_model(Workshop(args.work, quick=True).preset("human"), scene.material, scene.nu)
    run = run_experiments(model, info, scene)
    e = run.experiments[0]
    sn = run.surface
    touch = run.contact.points_mm[np.argmin(e.indentor.standoff(run.contact.points_mm))]
    line = np.flatnonzero((np.abs(sn.x[:, 2] - touch[2]) < 0.3) & (np.abs(sn.x[:, 0] - touch[0]) < 6.0)
                          & (sn.normal[:, 1] > 0.5))
    line = line[np.argsort(sn.x[line, 0])]
    k, both = len(line), np.r_[line, line]
    pop = Population(np.array(["SA1"] * k + ["RA"] * k, dtype=object), np.zeros(2 * k, int), both, sn.x[both],
                     sn.normal[both], np.r_[np.full(k, DEPTHS["SA1"]), np.full(k, DEPTHS["RA"])])
    static, deflection = experiment_inputs(sampler_of(model, pop), pop, run.contact, e)
    t = e.experiment.times_s
    finger = respond(pop, t, static, deflection, noisy=False)

    # the published mechanics on the same line: distance from the probe's centre, same times
    frac = np.array([float(r.depth_mm.max()) for _, r in e.steps])          # depth course, 0 -> 1 mm
    x = sn.x[line, 0] - touch[0]
    r = np.r_[np.abs(x), np.abs(x)]
    P = sneddon_punch_force_N(RADIUS_MM, 1.0, E_MPA, NU)
    s_flat = sneddon_punch_stress_zz_MPa(r, pop.depth_mm, RADIUS_MM, P)[:, None] * frac
    w = np.where(r <= RADIUS_MM, 1.0, 2 / np.pi * np.arcsin(RADIUS_MM / np.maximum(r, RADIUS_MM)))
    flat = respond(pop, t, s_flat, w[:, None] * frac, noisy=False)

    hold = int(np.argmin(np.abs(t - 0.35)))
    force = e.steps[hold][1].total_force_N
    print(f"hold force: finger {force:.4f} N, flat {P:.4f} N; {k} SA1 and {k} RA on the line (x from "
          f"{x.min():+.1f} to {x.max():+.1f} mm)")
    rates = {}
    for name, resp in (("flat", flat), ("finger", finger)):
        rates[name] = (resp.rates_hz(0.15, 0.6), resp.rates_hz(0.0, 0.12))
        for c, sl in (("SA1", slice(0, k)), ("RA", slice(k, 2 * k))):
            s = resp.static[sl, hold]
            fired = (rates[name][0] if c == "SA1" else rates[name][1])[sl] > 0
            span = f"{x[fired].min():+.1f} to {x[fired].max():+.1f} mm" if fired.any() else "none"
            print(f"  {name:6s} {c}: peak input {1e3 * s.max():.2f} kPa, half-peak width {half_width(x, s):.2f} mm; "
                  f"{'hold' if c == 'SA1' else 'ramp'} spikes from {span}, peak rate "
                  f"{(rates[name][0] if c == 'SA1' else rates[name][1])[sl].max():.0f} Hz")

    for name, resp in (("flat", flat), ("finger", finger)):
        d = resp.deflection_mm[:k, hold]
        print(f"  {name:6s} surface deflection in the hold at |x| = 3 mm: "
              f"{np.interp(-3, x, d):.3f} and {np.interp(3, x, d):.3f} mm (probe 1 mm)")

    from matplotlib.figure import Figure
    fig = Figure(figsize=(10, 4), layout="constrained")
    ax = fig.subplots(1, 2)
    for name, resp, style in (("flat (published model)", flat, "--"), ("finger (FE, human preset)", finger, "-")):
        ax[0].plot(x, 1e3 * resp.static[:k, hold], "g" + style, label=f"SA1 0.3 mm, {name}")
        ax[0].plot(x, 1e3 * resp.static[k:, hold], "b" + style, label=f"RA 1.6 mm, {name}")
        key = "flat" if resp is flat else "finger"
        ax[1].plot(x, rates[key][0][:k], "g" + style, label=f"SA1 hold, {name}")
        ax[1].plot(x, rates[key][1][k:], "b" + style, label=f"RA ramp, {name}")
    ax[0].set(xlabel="x from the probe's centre, mm", ylabel="static input (normal stress), kPa",
              title="input in the hold, 0.119 N")
    ax[1].set(xlabel="x from the probe's centre, mm", ylabel="mean rate, Hz", title="rates (model 0, no noise)")
    for a in ax:
        a.legend(fontsize="x-small")
        a.axvspan(-RADIUS_MM, RADIUS_MM, color="0.9")
    Path(args.figure).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.figure, dpi=90)
    print(f"figure: {args.figure}")


if __name__ == "__main__":
    main()
