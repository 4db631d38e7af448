#!/usr/bin/env python
"""The energy balance at small depths, where a 0.05 mm series cannot judge it: C5 (m43338) with
both kinematics on a model folder (3D: across the finger) at depths STEP:DEPTH:STEP (default
0.0025:0.2:0.0025 mm), the indentor's work (`fem.verify.energy.indentation_work_Nmm`: a power law
on the first interval, then Simpson) against the stored energy `energy_Nmm` of the step table,
printed at every 0.025 mm with the trapezoid rule's work beside it, and each run's time.

`benchmarks/finite_verification.py --energy-3d` judges the balance on 0.05:1.5:0.05 mm; there, on
the 1 mm monkey, only one to three nodes carry the force at 0.05-0.1 mm and the force's kinks as
nodes join fall between the samples. Sampled every 0.0025 mm the quadrature resolves them.

    python benchmarks/energy_fine_start.py MODEL [--step 0.0025] [--depth 0.2] [--no-write]

Writes benchmarks/results/energy_fine_start.md (one section per model folder, replaced when run
again).
"""
from __future__ import annotations

import argparse
import logging
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))
sys.path.insert(0, str(ROOT))

from finite_verification import MATERIAL, run  # noqa: E402

from fem.io.modelfolder import folder_dim, folder_info  # noqa: E402
from fem.verify.energy import indentation_work_Nmm  # noqa: E402

RESULTS = ROOT / "benchmarks" / "results" / "energy_fine_start.md"
REPORT_EVERY_MM = 0.025


def section(folder: Path, step_mm: float, depth_mm: float) -> list[str]:
    depths = f"{step_mm:g}:{depth_mm:g}:{step_mm:g}"
    across = folder_dim(folder_info(folder)) == 3
    rows, head = {}, []
    for kinematics in ("linear", "finite"):
        steps, seconds = run(folder, depths, kinematics, across)
        d, f, e = steps["depth_mm"], steps["force_N"], steps["energy_Nmm"]
        trapezoid = 0.5 * f[0] * d[0] + np.r_[0.0, np.cumsum(0.5 * (f[1:] + f[:-1]) * np.diff(d))]
        rows[kinematics] = (d, f, indentation_work_Nmm(d, f) / e - 1, trapezoid / e - 1)
        head.append(f"- {kinematics}: {len(d)} depths in {seconds:.1f} s")
        print(head[-1], flush=True)
    unit = "N" if across else "N/mm"
    lines = [f"## {folder.name}: C5{' across the finger' if across else ''}, {MATERIAL}, {depths} mm", "",
             f"`python benchmarks/energy_fine_start.py {folder.name} --step {step_mm:g} --depth {depth_mm:g}`; "
             f"{time.strftime('%Y-%m-%d')}", ""] + head + [
        "", f"| depth mm | linear force {unit} | linear work / energy - 1 | (trapezoid) | finite force {unit} | "
            "finite work / energy - 1 | (trapezoid) |", "|---|---|---|---|---|---|---|"]
    d = rows["linear"][0]
    for k in np.flatnonzero(np.abs(d / REPORT_EVERY_MM - np.round(d / REPORT_EVERY_MM)) < 1e-9):
        cells = [f"{rows[kin][1][k]:.5g} | {rows[kin][2][k]:+.1e} | {rows[kin][3][k]:+.1e}" for kin in ("linear", "finite")]
        lines.append(f"| {d[k]:.3f} | " + " | ".join(cells) + " |")
    for kin in ("linear", "finite"):
        r = rows[kin][2][d >= 0.05 - 1e-12]
        lines.append(f"\n{kin}: largest |work / energy - 1| from 0.05 mm {np.abs(r).max(initial=0.0):.1e}")
    print("\n".join(lines), flush=True)
    return lines


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("model", type=Path)
    ap.add_argument("--step", type=float, default=0.0025, help="depth step and first depth, mm")
    ap.add_argument("--depth", type=float, default=0.2, help="last depth, mm")
    ap.add_argument("--no-write", action="store_true")
    args = ap.parse_args(argv)
    logging.getLogger("fem").setLevel(logging.ERROR)
    lines = section(args.model, args.step, args.depth)
    if args.no_write:
        return
    title = "# Energy balance with a fine start (`benchmarks/energy_fine_start.py`)"
    old = RESULTS.read_text().split("\n## ") if RESULTS.exists() else [title + "\n"]
    keep = [s for s in old[1:] if not s.startswith(f"{args.model.name}:")]
    RESULTS.write_text("\n## ".join([old[0].rstrip("\n") + "\n"] + keep + ["\n".join(lines)[3:]]) + "\n")


if __name__ == "__main__":
    main()
