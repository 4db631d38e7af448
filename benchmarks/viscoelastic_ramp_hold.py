#!/usr/bin/env python
"""The shipped ramp-and-hold (scenes/ramp_hold.toml: a 2 mm flat probe pressed 1 mm into the pad in 0.1
s, held 0.5 s, released in 0.1 s) on the 3D monkey preset, elastic and with viscoelastic layers
([viscoelastic] g, Pawluk and Howe's relaxation times): how much the contact force relaxes during
the hold against the closed form of a flat punch on a block (its elastic force linear in the depth,
so a linear ramp: F(t) / F_e(t_r) = g_inf + sum g_i tau_i / t_r (e^-(t - t_r)/tau_i - e^-t/tau_i),
`fem.verify.closed_forms.prony_ramp_hold`), and how the SA1 and RA hold rates fall with it. Prints
the table, appends it to benchmarks/results/viscoelastic_ramp_hold.md and draws
docs/img/viscoelastic_ramp_hold.png.

    python benchmarks/viscoelastic_ramp_hold.py                    # g = 0.2 0.2 0.2, monkey at 1 mm
    python benchmarks/viscoelastic_ramp_hold.py --g 0.3 0.2 0.1 --size 0.7
    python benchmarks/viscoelastic_ramp_hold.py --density-factor 10      # ten times the afferents
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

from fem.core.viscoelastic import PAWLUK_HOWE_TAU_S, Prony  # noqa: E402
from fem.experiments.runner import run_scene  # noqa: E402
from fem.experiments.scene import load_scene  # noqa: E402
from fem.geometry.build import MeshSpec, build_folder  # noqa: E402
from fem.receptors.transduction import class_data  # noqa: E402
from fem.verify.closed_forms import prony_ramp_hold  # noqa: E402

RESULTS = ROOT / "benchmarks" / "results" / "viscoelastic_ramp_hold.md"
FIGURE = ROOT / "docs" / "img" / "viscoelastic_ramp_hold.png"
SETTLE_S = 0.1
"""The hold's first 0.1 s (the on-transient of RA, the fast SA1 decay) is left out of its rates."""


def course(run) -> tuple[np.ndarray, np.ndarray]:
    """(times (k,) s, contact force (k,) N) of a scene run's first experiment."""
    e = run.experiments[0]
    return np.asarray(e.experiment.times_s, float), np.array([r.total_force_N for _, r in e.steps])


def hold_rates(run, t0_s: float, t1_s: float) -> np.ndarray:
    """(n,) mean firing rate [Hz] of each afferent of a scene run between t0_s and t1_s."""
    return next(iter(run.afferents[1].values())).rates_hz(t0_s, t1_s)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--g", type=float, nargs="+", default=[0.2, 0.2, 0.2], help="Prony weights of the layers")
    ap.add_argument("--size", type=float, default=1.0, help="volar element size of the monkey mesh (mm)")
    ap.add_argument("--work", type=Path, default=ROOT / "out" / "viscoelastic_bench")
    ap.add_argument("--density-factor", type=float, default=1.0,
                    help="afferents per cm^2 times this (1: the published fingertip densities)")
    ap.add_argument("--no-write", action="store_true", help="print only (no results file, no figure)")
    args = ap.parse_args()

    law = Prony(tuple(args.g), PAWLUK_HOWE_TAU_S)
    folder = args.work / f"monkey_{args.size:g}"
    build_folder(folder, MeshSpec(preset="monkey", sizes={"size_mm": args.size}))
    elastic_scene = load_scene("ramp_hold")
    aff = elastic_scene.afferents
    elastic_scene = dataclasses.replace(elastic_scene, afferents=dataclasses.replace(aff, density_per_cm2=tuple(
        (c, args.density_factor * class_data(c).density_per_cm2) for c in aff.classes)))
    trace = elastic_scene.experiments[0].trace
    visco_scene = dataclasses.replace(elastic_scene, viscoelastic=law)
    runs, seconds = {}, {}
    for name, sc in (("elastic", elastic_scene), ("viscoelastic", visco_scene)):
        t0 = time.perf_counter()
        runs[name] = run_scene(folder, sc)
        seconds[name] = time.perf_counter() - t0
    t, fe = course(runs["elastic"])
    _, fv = course(runs["viscoelastic"])
    t_r, t_h = trace.ramp_s, trace.ramp_s + trace.hold_s
    hold = (t >= t_r - 1e-12) & (t <= t_h + 1e-12)
    peak_e = float(np.interp(t_r, t, fe))
    closed = prony_ramp_hold(t[hold], t_r, law.g_inf, law.g, law.tau_s)
    # the elastic force is constant in the hold: the relaxation is fv / fe there
    relax = fv[hold] / fe[hold]
    end_fe, end_closed = float(relax[-1]), float(closed[-1])
    worst = float(np.max(np.abs(relax - closed) / closed))
    rates = {name: hold_rates(run, t_r + SETTLE_S, t_h) for name, run in runs.items()}
    chosen = rates["elastic"] > 0                  # those firing in the elastic hold, the same in both runs
    ramp_end = float(relax[-1] / relax[0]), float(closed[-1] / closed[0])

    lines = [f"## g = {list(args.g)}, tau_s = {list(law.tau_s)}, monkey preset at {args.size:g} mm "
             f"({runs['elastic'].model.ndof} DOFs), afferent densities x {args.density_factor:g}", "",
             "| quantity | FE (monkey) | closed form (block) | difference |", "|---|---|---|---|",
             f"| force at the end of the hold / elastic force at the end of the ramp | {end_fe:.4f} | "
             f"{end_closed:.4f} | {100 * (end_fe / end_closed - 1):+.2f} % |",
             f"| force at the end of the hold / viscoelastic force at the end of the ramp | {ramp_end[0]:.4f} | "
             f"{ramp_end[1]:.4f} | {100 * (ramp_end[0] / ramp_end[1] - 1):+.2f} % |",
             f"| largest difference over the hold | | | {100 * worst:.2f} % |",
             f"| elastic force at the end of the ramp | {peak_e * 1e3:.2f} mN | | |", ""]
    lines += ["| class (firing in the hold / placed) | elastic hold rate Hz | viscoelastic hold rate Hz | change |",
              "|---|---|---|---|"]
    classes = runs["elastic"].afferents[0].afferent_class
    for c in np.unique(classes):
        mine = chosen & (classes == c)
        e, v = (float(rates[name][mine].mean()) if mine.any() else 0.0 for name in runs)
        change = f"{100 * (v / e - 1):+.1f} %" if e else "no firing in the hold"
        lines.append(f"| {c} ({int(mine.sum())} / {int(np.sum(classes == c))}) | {e:.1f} | {v:.1f} | {change} |")
    lines += ["", f"Hold rates: mean from {t_r + SETTLE_S:g} to {t_h:g} s over the afferents of a class that fire "
              f"then in the elastic run ({int(chosen.sum())} of {len(chosen)}; the same afferents in both runs). "
              f"Run time: elastic {seconds['elastic']:.1f} s, viscoelastic {seconds['viscoelastic']:.1f} s (mesh "
              f"from the cache).", ""]
    text = "\n".join(lines)
    print(text)
    if args.no_write:
        return
    with RESULTS.open("a") as fh:
        fh.write(text + "\n")
    figure(t, fe, fv, peak_e, law, t_r, t_h, runs, chosen)


def figure(t, fe, fv, peak_e, law, t_r, t_h, runs, chosen):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (a, b) = plt.subplots(1, 2, figsize=(10, 4), constrained_layout=True)
    a.plot(t, 1e3 * fe, label="elastic")
    a.plot(t, 1e3 * fv, label="viscoelastic layers")
    th = np.linspace(t_r, t_h, 200)
    a.plot(th, 1e3 * peak_e * prony_ramp_hold(th, t_r, law.g_inf, law.g, law.tau_s), "k:",
           label="closed form, flat punch on a block")
    a.set_xlabel("time [s]")
    a.set_ylabel("contact force [mN]")
    a.legend(loc="lower center", fontsize=8)
    a.set_title("2 mm probe, 1 mm into the monkey pad")
    bins = np.arange(0.0, float(t[-1]) + 0.05, 0.05)
    pop = runs["elastic"].afferents[0]
    firing = np.flatnonzero(chosen & (pop.afferent_class == "SA1"))
    for name, run in runs.items():
        spikes = next(iter(run.afferents[1].values())).spikes
        counts = np.histogram(np.concatenate([spikes[i] for i in firing]), bins)[0] / len(firing) / 0.05
        b.step(bins[:-1], counts, where="post", label=name)
    b.set_xlabel("time [s]")
    b.set_ylabel("SA1 mean rate [Hz] (50 ms bins)")
    b.legend(loc="upper right", fontsize=8)
    b.set_title(f"the {len(firing)} SA1 afferents that fire in the elastic hold")
    fig.savefig(FIGURE, dpi=110)
    print(f"figure: {FIGURE.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
