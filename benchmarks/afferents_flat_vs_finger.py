#!/usr/bin/env python
"""The same stimulus on the published model's flat skin and on the finger: how curvature and layers
change what the afferents get. The shipped ramp-and-hold (scenes/ramp_hold.toml: a 2 mm probe to
1 mm in 0.1 s, held 0.5 s, released in 0.1 s) on the 1 mm human preset with the scene's material,
and on TouchSim's half-space (E = 0.05 MPa, nu = 0.4: Sneddon's flat punch, stress and surface
deflection in closed form; tests/fem/verify/test_sneddon.py checks the solver against it). Both carry 0.119 N
in the hold. Afferents on the line across the pad through the point the probe touches first:
an SA1 (0.3 mm deep) and an RA (1.6 mm) below every pad node within 0.3 mm of it, model 0 of each
class, noise off; the flat skin's afferents at the same distances from the probe's centre, and on
its own line every 0.01 mm (the published model's profile, not its sampling at the finger's nodes).
Every course runs as a scene's does (`fem.experiments.spiking`: inputs tabulated over the depth,
read at the course's depth at 5 kHz).

    python benchmarks/afferents_flat_vs_finger.py [--work out/afferents_bench] [--no-write]

Prints, per class, the peak static input in the hold (and where), the half-peak width of its
profile across the line, the span of the afferents that fire (SA1 in the hold, RA in the ramp)
and their peak rate, and the surface deflection 3 mm either side of the probe; writes the table
to benchmarks/results/afferents_flat_vs_finger.md and draws docs/img/afferents_flat_vs_finger.png.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from fem.experiments.runner import run_experiments  # noqa: E402
from fem.experiments.scene import load_scene  # noqa: E402
from fem.experiments.spiking import fine_loads, load_value, tabulate  # noqa: E402
from fem.io.modelfolder import read_model  # noqa: E402
from fem.receptors.afferents import LoadTable, Population, respond, sampler_of  # noqa: E402
from fem.thesis.findings import Workshop  # noqa: E402
from fem.verify.closed_forms import sneddon_punch_force_N, sneddon_punch_stress_zz_MPa  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results" / "afferents_flat_vs_finger.md"
FIGURE = ROOT / "docs" / "img" / "afferents_flat_vs_finger.png"
E_MPA, NU, RADIUS_MM, DEPTHS = 0.05, 0.4, 1.0, {"SA1": 0.3, "RA": 1.6}
DENSE_STEP_MM = 0.01


def half_width(x, y) -> float:
    """Width [mm] of the region where y >= max(y) / 2 (outermost crossings)."""
    on = x[y >= 0.5 * y.max()]
    return float(on.max() - on.min())


def line_population(k: int, candidate, site, normal) -> Population:
    """An SA1 and an RA (model 0) below each of k sites."""
    both = np.r_[candidate, candidate]
    return Population(np.array(["SA1"] * k + ["RA"] * k, dtype=object), np.zeros(2 * k, int), both,
                      np.r_[site, site], np.r_[normal, normal], np.r_[np.full(k, DEPTHS["SA1"]), np.full(k, DEPTHS["RA"])])


def flat_response(x, exp):
    """The half-space's afferents at signed distances x (k,) from the probe's centre through the course of exp."""
    k = len(x)
    pop = line_population(k, np.zeros(k, int), np.c_[x, 0 * x, 0 * x], np.tile([0.0, 0.0, 1.0], (k, 1)))
    r = np.abs(pop.site_mm[:, 0])
    full = load_value(exp.loads[0])
    stress = sneddon_punch_stress_zz_MPa(r, pop.depth_mm, RADIUS_MM, sneddon_punch_force_N(RADIUS_MM, full, E_MPA, NU))
    w = full * np.where(r <= RADIUS_MM, 1.0, 2 / np.pi * np.arcsin(RADIUS_MM / np.maximum(r, RADIUS_MM)))
    table = LoadTable(np.array([0.0, full]), np.c_[0 * stress, stress], np.c_[0 * w, w])
    samples = table.at([load_value(load) for _, load in exp.indentations])
    return respond(pop, exp.times_s, *samples, noisy=False, fine=table.at(fine_loads(exp)))


def summary(x, resp, hold: int) -> dict:
    """Per class: peak input [kPa] and its x, half-peak width, firing span and peak rate."""
    k = len(x)
    out = {}
    for c, sl, window in (("SA1", slice(0, k), (0.15, 0.6)), ("RA", slice(k, 2 * k), (0.0, 0.12))):
        s, rate = resp.static[sl, hold], resp.rates_hz(*window)[sl]
        fired = rate > 0
        out[c] = {"peak_kPa": 1e3 * s.max(), "at_mm": float(x[np.argmax(s)]), "width_mm": half_width(x, s),
                  "span": f"{x[fired].min():+.2f} to {x[fired].max():+.2f} mm" if fired.any() else "none",
                  "rate_hz": rate.max()}
    d = resp.deflection_mm[:k, hold]
    out["deflection_mm"] = (float(np.interp(-3, x, d)), float(np.interp(3, x, d)))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--work", default="out/afferents_bench", help="folder for the meshed preset (cached)")
    ap.add_argument("--no-write", action="store_true", help="print only (no results file, no figure)")
    args = ap.parse_args()
    t0 = time.perf_counter()
    scene = load_scene(ROOT / "scenes" / "ramp_hold.toml")
    model, info = read_model(Workshop(args.work, quick=True).preset("human"), scene.material, scene.nu)
    run = run_experiments(model, info, scene)
    e = run.experiments[0]
    sn = run.surface
    touch = run.contact.points_mm[np.argmin(e.indentor.standoff(run.contact.points_mm))]
    line = np.flatnonzero((np.abs(sn.x[:, 2] - touch[2]) < 0.3) & (np.abs(sn.x[:, 0] - touch[0]) < 6.0)
                          & (sn.normal[:, 1] > 0.5))
    line = line[np.argsort(sn.x[line, 0])]
    k = len(line)
    pop = line_population(k, line, sn.x[line], sn.normal[line])
    table = tabulate(sampler_of(model, pop), pop, run.contact, e)
    exp = e.experiment
    samples = table.at([load_value(load) for _, load in exp.indentations])
    finger = respond(pop, exp.times_s, *samples, noisy=False, fine=table.at(fine_loads(exp)))
    x = sn.x[line, 0] - touch[0]
    dense = np.arange(-6.0, 6.0 + DENSE_STEP_MM / 2, DENSE_STEP_MM)
    flat_nodes, flat_line = flat_response(x, exp), flat_response(dense, exp)

    hold = int(np.argmin(np.abs(exp.times_s - 0.35)))
    force = e.steps[hold][1].total_force_N
    P = float(sneddon_punch_force_N(RADIUS_MM, 1.0, E_MPA, NU))
    rows = {f"flat, its own line (every {DENSE_STEP_MM:g} mm)": (dense, flat_line),
            f"flat, at the finger's {k} nodes": (x, flat_nodes), "finger (1 mm human preset)": (x, finger)}
    stats = {name: summary(xs, resp, hold) for name, (xs, resp) in rows.items()}
    lines = [f"hold force: finger {force:.4f} N, flat {P:.4f} N; {k} SA1 and {k} RA on the finger's line (x from "
             f"{x.min():+.1f} to {x.max():+.1f} mm); inputs from load tables of {len(table.load)} depths "
             f"(finger) and 2 (flat: linear); {time.perf_counter() - t0:.0f} s", "",
             "| skin | SA1 peak input | SA1 half-peak width | SA1 firing in the hold | SA1 peak hold rate | "
             "RA peak input | RA firing in the ramp | RA peak ramp rate | deflection at x = -3, +3 mm |",
             "|---|---|---|---|---|---|---|---|---|"]
    for name, st in stats.items():
        a, b = st["SA1"], st["RA"]
        lines.append(f"| {name} | {a['peak_kPa']:.1f} kPa at x = {a['at_mm']:+.2f} mm | {a['width_mm']:.2f} mm | "
                     f"{a['span']} | {a['rate_hz']:.0f} Hz | {b['peak_kPa']:.1f} kPa | {b['span']} | "
                     f"{b['rate_hz']:.0f} Hz | {st['deflection_mm'][0]:.3f}, {st['deflection_mm'][1]:.3f} mm |")
    text = "\n".join(lines)
    print(text)
    if args.no_write:
        return
    RESULTS.write_text("# The same ramp-and-hold on the published model's flat skin and on the finger\n\n"
                       "`python benchmarks/afferents_flat_vs_finger.py`\n\n" + text + "\n")

    from matplotlib.figure import Figure
    fig = Figure(figsize=(10, 4), layout="constrained")
    ax = fig.subplots(1, 2)
    for (name, (xs, resp)), style in zip(list(rows.items())[::2], ("--", "-")):
        n = len(xs)
        ax[0].plot(xs, 1e3 * resp.static[:n, hold], "g" + style, label=f"SA1 0.3 mm, {name}")
        ax[0].plot(xs, 1e3 * resp.static[n:, hold], "b" + style, label=f"RA 1.6 mm, {name}")
        ax[1].plot(xs, resp.rates_hz(0.15, 0.6)[:n], "g" + style, label=f"SA1 hold, {name}")
        ax[1].plot(xs, resp.rates_hz(0.0, 0.12)[n:], "b" + style, label=f"RA ramp, {name}")
    ax[0].set(xlabel="x from the probe's centre, mm", ylabel="static input (normal stress), kPa",
              title=f"input in the hold, {P:.3f} N")
    ax[1].set(xlabel="x from the probe's centre, mm", ylabel="mean rate, Hz", title="rates (model 0, no noise)")
    for a in ax:
        a.legend(fontsize="x-small")
        a.axvspan(-RADIUS_MM, RADIUS_MM, color="0.9")
    fig.savefig(FIGURE, dpi=90)
    print(f"results: {RESULTS}; figure: {FIGURE}")


if __name__ == "__main__":
    main()
