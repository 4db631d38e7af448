#!/usr/bin/env python
"""Receptor-analysis experiments on the 2D cylinder (8 mm) with bone: the numbers and figures of
docs/receptors-and-analysis.md (thesis 4.2, 4.3, 4.5.4, 4.5.5, 8.4).

    python benchmarks/analysis_bench.py [--work out/analysis_bench]     (about 1 min on 2 cores)

1. receptive fields from a line-load sweep at 0.75 mm, half-peak threshold (and the shear hole
   against the threshold);
2. two-point intensive cue: max SED at 0.75 mm vs separation, equal displacement vs equal force,
   with one load alone at the same place as reference;
3. shear-strain peaks across grating gaps (two 1 mm bars);
4. spatial response profile of central and off-centre receptors vs the population response
   (grating 0.5 mm, examples/analysis_gratings.toml);
5. lumped receptor model driven by the SED at the central receptor under a C5 ramp-and-hold.
Writes benchmarks/results/analysis_bench.md and analysis_bench_*.png.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

from matplotlib.figure import Figure  # noqa: E402

from fem.contact.indentors import make_indentor  # noqa: E402
from fem.experiments.response import ResponseStore  # noqa: E402
from fem.experiments.runner import run_scene  # noqa: E402
from fem.experiments.scene import load_scene  # noqa: E402
from fem.geometry.build import MeshSpec, build_folder  # noqa: E402
from fem.io.runfolder import IndentRun, write_run  # noqa: E402
from fem.plots import save  # noqa: E402
from fem.receptors.dynamics import LumpedReceptor, measure_time_course, ramp_and_hold  # noqa: E402
from fem.receptors.probes import (  # noqa: E402
    Probe2D,
    gap_analysis,
    point_load_field,
    receptive_field,
    settling_separation,
    two_point_curves,
)
from fingertip.staging import staged_output  # noqa: E402

RESULTS = HERE / "results"


def _subplots(*grid, figsize, **kw):
    """(Figure, axes) like pyplot.subplots, without pyplot."""
    fig = Figure(figsize=figsize)
    return fig, fig.subplots(*grid, **kw)


def _save(fig, name):
    save(fig, RESULTS / f"analysis_bench_{name}.png", dpi=100)


def _receptive_fields(probe) -> list[str]:
    """1. Receptive fields from a wedge swept over the receptor at 0.75 mm (half-peak threshold), and
    the shear hole against the threshold: markdown lines; writes analysis_bench_fields.png."""
    t0 = time.perf_counter()
    pos = np.round(np.arange(-2.0, 2.0001, 0.05), 3)
    fields = {c: point_load_field(probe, c, pos) for c in ("sed_MPa", "max_compressive_strain", "abs:strain_xy")}
    md = ["", "## Receptive fields (wedge line load 1 mm deep swept in 0.05 mm steps, half-peak threshold)", "",
           "| measure | shape | ON extent mm | OFF hole mm |", "|---|---|---|---|"]
    md += [f"| {c} | {f.shape} | {f.diameter_mm:.2f} | {f.hole_mm:.2f} |" for c, f in fields.items()]
    shear = fields["abs:strain_xy"]
    md += ["", "Shear hole against the threshold (fraction of the peak): " + ", ".join(
        f"{q:.1f}: {receptive_field(shear.positions_mm, shear.values, q * shear.values.max()).hole_mm:.2f} mm"
        for q in (0.3, 0.4, 0.5, 0.6, 0.7))]
    fig, ax = _subplots(2, 3, figsize=(11, 6))
    for k, (c, f) in enumerate(fields.items()):
        ax[0, k].plot(f.positions_mm, f.values, "-")
        ax[0, k].axhline(f.threshold, color="k", ls="-.")
        ax[0, k].set(title=c, xlabel="load position - receptor, mm")
        x, y, on = f.map2d(121)
        ax[1, k].imshow(on, extent=(x[0], x[-1], y[0], y[-1]), cmap="Greys", origin="lower")
        ax[1, k].set(title=f"{f.shape}: {f.diameter_mm:.2f} mm" + (f", hole {f.hole_mm:.2f}" if f.shape == "annulus"
                                                                     else ""))
    _save(fig, "fields")
    return md + [f"\n({time.perf_counter() - t0:.1f} s)"]


def _two_point(probe) -> list[str]:
    """2. The two-point intensive cue (max SED at 0.75 mm) against the separation: markdown lines;
    writes analysis_bench_two_point.png."""
    t0 = time.perf_counter()
    seps = np.round(np.arange(0.0, 4.0001, 0.2), 3)
    c = two_point_curves(probe, seps, depth_mm=0.5)
    in3 = seps <= 3.0 + 1e-9
    md = ["", "## Two-point intensive cue (tips 0.5 mm deep; equal force = half the single-tip force each)", "",
           f"force per load {c['force_per_load_N']:.4g} N/mm; settling = smallest separation after which max SED "
           f"stays within 5 % of the reference", "",
           "| protocol | vs last value, 0-3 mm | vs last value, 0-4 mm | max abs(two / alone - 1) from 1.6 mm |",
           "|---|---|---|---|"]
    far = seps >= 1.6 - 1e-9
    for key in ("force", "displacement"):
        md.append(f"| equal {key} | {settling_separation(seps[in3], c[key][in3]):.1f} | "
                  f"{settling_separation(seps, c[key]):.1f} | "
                  f"{np.abs(c[key][far] / c['alone_' + key][far] - 1).max():.3f} |")
    md += ["", "| separation mm | " + " | ".join(f"{s:g}" for s in seps[::2]) + " |",
           "|---|" + "---|" * len(seps[::2])]
    for key in ("force", "displacement"):
        md.append(f"| {key} / last | " + " | ".join(f"{v:.3f}" for v in (c[key] / c[key][-1])[::2]) + " |")
        md.append(f"| {key} / alone | " + " | ".join(f"{v:.3f}" for v in (c[key] / c['alone_' + key])[::2]) + " |")
    fig, ax = _subplots(1, 2, figsize=(10, 3.6))
    for a, key in zip(ax, ("force", "displacement")):
        a.plot(0.5 * seps, c[key], "o-", label="two loads")
        a.plot(0.5 * seps, c["alone_" + key], "s--", label="one load alone at +s/2")
        a.set(title=f"equal {key}", xlabel="half separation, mm", ylabel="max SED at 0.75 mm, MPa")
        a.legend(fontsize=8)
    _save(fig, "two_point")
    return md + [f"\n({time.perf_counter() - t0:.1f} s)"]


def _gaps(probe) -> list[str]:
    """3. |strain_xy| peaks across the gap between two 1 mm bars: markdown lines; writes
    analysis_bench_gaps.png."""
    t0 = time.perf_counter()
    gaps = [0.5, 0.75, 1.0, 1.5, 2.0, 3.0]
    rows, prof = gap_analysis(probe, 1.0, gaps)
    md = ["", "## Shear-strain peaks across gaps (two 1 mm bars 1 mm deep, |strain_xy| at 0.75 mm)", "",
           "| gap mm | inter-peak mm | peak left | peak right | slope per mm |", "|---|---|---|---|---|"]
    md += [f"| {r['gap_mm']:g} | {r['interpeak_mm']:.3f} | {r['peak_left']:.4f} | {r['peak_right']:.4f} | "
           f"{r['slope_per_mm']:.4f} |" for r in rows]
    fig, ax = _subplots(figsize=(8, 3.6))
    for g, v in zip(gaps, prof):
        ax.plot(probe.sites_x_mm, v, label=f"gap {g:g} mm")
    ax.set(xlabel="receptor x, mm", ylabel="|strain_xy| at 0.75 mm")
    ax.legend(fontsize=7)
    _save(fig, "gaps")
    return md + [f"\n({time.perf_counter() - t0:.1f} s)"]


def _profiles(model: Path) -> list[str]:
    """4. Spatial response profiles of central and off-centre receptors against the population
    response (grating 0.5 mm, examples/analysis_gratings.toml run on the model if not yet, as
    `pipeline.py indent` runs it): markdown lines; writes analysis_bench_profiles.png and
    analysis_bench_population.png."""
    t0 = time.perf_counter()
    runs_dir = model / "gratings"
    if not (runs_dir / "grating_0.5_receptors.csv").is_file():
        run = run_scene(model, load_scene(HERE.parent / "examples" / "analysis_gratings.toml"),
                        store=ResponseStore.existing(model))
        with staged_output(runs_dir) as tmp:
            write_run(tmp, model, run, run.afferents)
    run = IndentRun(runs_dir)
    fig, ax = _subplots(3, 1, figsize=(8, 7), sharex=True)
    x_sites = run.population("grating_0.5", "sed_MPa", 0.75, 0.0)[0]
    pos, central = run.profile("grating_0.5", "sed_MPa", 0.75, 0.0, align=False)
    pos = pos - x_sites[run.site_index("grating_0.5", 0.0)]          # stimulus position relative to the receptor
    md = ["", "## Spatial response profile vs population (grating 0.5 mm, SED at 0.75 mm)", "",
           "Receptor sites are those of the indent grid (spacing 0.5 mm): the most central one is not at x = 0.", "",
           "| receptor x mm | rms difference to the most central profile (both shifted), % of its peak |",
           "|---|---|"]
    for a, rx in zip(ax, (0.0, 1.0, 2.0)):
        p, v = run.profile("grating_0.5", "sed_MPa", 0.75, rx, align=False)
        x_site = x_sites[run.site_index("grating_0.5", rx)]
        a.plot(pos, central, color="0.7", label="most central receptor")
        a.plot(p - x_site, v, label=f"receptor at x = {x_site:.2f} mm, shifted")
        xp, vp = run.population("grating_0.5", "sed_MPa", 0.75, -8.0)
        a.legend(fontsize=7)
        shifted = np.interp(pos, p - x_site, v, left=np.nan, right=np.nan)
        ok = np.isfinite(shifted)
        md.append(f"| {x_site:.2f} | {100 * np.sqrt(np.mean((shifted[ok] - central[ok]) ** 2)) / central.max():.1f} |")
    ax[-1].set_xlabel("grating position relative to the receptor, mm")
    _save(fig, "profiles")
    fig, a = _subplots(figsize=(8, 3))
    a.plot(xp, vp, ".-")
    a.set(title="population response: all receptors at 0.75 mm, grating at -8 mm", xlabel="receptor x, mm",
          ylabel="sed_MPa")
    _save(fig, "population")
    return md + [f"\n({time.perf_counter() - t0:.1f} s)"]


def _dynamics(probe) -> list[str]:
    """5. Lumped SA and RA receptor models driven by the SED at the central receptor under a C5
    ramp-and-hold: markdown lines; writes analysis_bench_dynamics.png."""
    depths = np.round(np.arange(0.1, 1.0001, 0.1), 3)
    c5 = make_indentor("C5", orientation="parallel")
    sed = [probe.measure(c5, [0.0], ["sed_MPa"], depth_mm=d)[0]["sed_MPa"][0, 0, 60] for d in depths]
    t, depth_t = ramp_and_hold(1.0, 0.1, 1.0, 0.1)
    S = measure_time_course(depth_t, depths, sed)
    fig, ax = _subplots(3, 1, figsize=(7, 6), sharex=True)
    ax[0].plot(t, S)
    ax[0].set(ylabel="SED at 0.75 mm, MPa", title="C5 ramp 0.1 s to 1 mm, hold 1 s, release 0.1 s")
    md = ["", "## Lumped receptor model driven by the SED under a C5 ramp-and-hold", "",
           "| receptor | tau s | rate end of ramp | end of hold / peak | firing time in withdrawal, ms of 100 |",
           "|---|---|---|---|---|"]
    for a, (name, tau) in zip(ax[1:], (("SA", 5.0), ("RA", 0.01))):
        out = LumpedReceptor(tau_s=tau, gain=1.0 / max(sed)).respond(t, S)
        a.plot(t, out["rate"])
        a.set(ylabel=f"{name} rate (a.u.)")
        ramp_end = np.argmin(np.abs(t - 0.2))
        hold_end = np.argmin(np.abs(t - 1.2))
        rel = (t > 1.2) & (t < 1.3)
        fire = np.count_nonzero(out["rate"][rel] > 0) * (t[1] - t[0]) * 1e3
        md.append(f"| {name} | {tau:g} | {out['rate'][ramp_end]:.3f} | "
                  f"{out['rate'][hold_end] / out['rate'].max():.3f} | {fire:.0f} |")
    ax[-1].set_xlabel("time, s")
    _save(fig, "dynamics")
    return md


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--work", default="out/analysis_bench")
    args = ap.parse_args(argv)
    work = Path(args.work)
    model = work / "cyl8"
    if not (model / "mesh.vtu").is_file():
        build_folder(model, MeshSpec(preset="cylinder8", bone=True))
    md = ["# Receptor analysis benchmark (2D cylinder 8 mm with bone, m33338, nu 0.48)", ""]
    t0 = time.perf_counter()
    probe = Probe2D(model, np.round(np.arange(-3.0, 3.0001, 0.05), 3), depths_mm=(0.75,))
    md.append(f"Probe setup (121 receptors at 0.75 mm): {time.perf_counter() - t0:.1f} s")
    md += _receptive_fields(probe)
    md += _two_point(probe)
    md += _gaps(probe)
    md += _profiles(model)
    md += _dynamics(probe)
    (RESULTS / "analysis_bench.md").write_text("\n".join(md) + "\n")
    print("\n".join(md))


if __name__ == "__main__":
    main()
