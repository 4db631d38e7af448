#!/usr/bin/env python
"""Repeat runs without ceremony: the same `indent` command twice on a fresh model folder, against
the factorised run the folder would get without a store, each as a whole command (interpreter
start-up and imports included).

    python benchmarks/repeat_run.py                      # 2D cylinder8 with bone, monkey 1.0 mm
    python benchmarks/repeat_run.py --work out/repeat_bench --plots

Per model: a copy of its folder that cannot be written (the run factorises and stores nothing:
the first run before stored models were automatic), then a fresh writable copy where the first run
builds and stores the response model of the candidates its scene can touch and the second and
third runs (the same command; then other depths of the same indentor) answer from it. Forces of
all runs are compared. Writes benchmarks/results/repeat_run.md.
"""
from __future__ import annotations

import argparse
import csv
import os
import shutil
import stat
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

MODELS = {"cylinder8 (2D, bone)": (["--preset", "cylinder8", "--bone"], ["--indentor", "C5", "--depth", "0:1:0.25"],
                                   ["--indentor", "C5", "--depth", "0.1:0.9:0.2"]),
          "monkey 1.0 mm": (["--preset", "monkey", "--size", "1.0"],
                            ["--indentor", "C5", "--orientation", "perpendicular", "--depth", "0:1.5:0.5"],
                            ["--indentor", "C5", "--orientation", "perpendicular", "--depth", "0.25:1.25:0.5"])}


def pipeline(*argv) -> float:
    """Seconds of one whole pipeline.py command."""
    t0 = time.perf_counter()
    subprocess.run([sys.executable, str(ROOT / "pipeline.py"), *map(str, argv)], check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.perf_counter() - t0


def forces(run_dir: Path) -> list[float]:
    name = next(p for p in run_dir.glob("*.csv") if not p.stem.endswith(("_surface", "_receptors")))
    with open(name) as fh:
        return [float(r["force_N"]) for r in csv.DictReader(fh)]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--work", default="out/repeat_bench")
    ap.add_argument("--plots", action="store_true", help="write the figures too (default --no-plots)")
    args = ap.parse_args(argv)
    work = Path(args.work)
    plots = [] if args.plots else ["--no-plots"]
    lines = ["# Repeat runs", "", f"`python benchmarks/repeat_run.py{' --plots' if args.plots else ''}`: whole "
             f"`pipeline.py indent ... {' '.join(plots)}` commands in seconds (no PVD).", "",
             "| model | scene | factorised (read-only folder) | first run (builds the store) | build | second run "
             "(same command) | third run (other depths) | factorised / second | first / second |",
             "|---|---|---|---|---|---|---|---|---|"]
    for name, (mesh, scene, other) in MODELS.items():
        base = work / name.split()[0]
        model = base / "model"
        if not (model / "mesh.vtu").exists():
            pipeline("mesh", *mesh, "--out", model, "--quiet")
        shutil.rmtree(model / "response", ignore_errors=True)
        locked = base / "locked"
        shutil.rmtree(locked, ignore_errors=True)
        shutil.copytree(model, locked)
        os.chmod(locked, stat.S_IRUSR | stat.S_IXUSR)
        fresh = base / "fresh"
        shutil.rmtree(fresh, ignore_errors=True)
        shutil.copytree(model, fresh)
        t_fact = pipeline("indent", locked, *scene, *plots, "--out", base / "r0", "--quiet")
        os.chmod(locked, stat.S_IRWXU)
        t_first = pipeline("indent", fresh, *scene, *plots, "--out", base / "r1", "--quiet")
        build = sum(float(__import__("json").loads(p.read_text())["build_seconds"])
                    for p in (fresh / "response").glob("*/response.json"))
        t_second = pipeline("indent", fresh, *scene, *plots, "--out", base / "r2", "--quiet")
        t_third = pipeline("indent", fresh, *other, *plots, "--out", base / "r3", "--quiet")
        f0, f1, f2 = forces(base / "r0"), forces(base / "r1"), forces(base / "r2")
        diff = max(abs(a - b) / max(abs(b), 1e-30) for a, b in zip(f1 + f2, f0 + f0) if b)
        lines.append(f"| {name} | {' '.join(scene)} | {t_fact:.2f} | {t_first:.2f} | {build:.2f} | {t_second:.2f} | "
                     f"{t_third:.2f} | {t_fact / t_second:.1f}x | {t_first / t_second:.1f}x |")
        print(lines[-1], f"(forces equal to {diff:.1e})", flush=True)
    out = ROOT / "benchmarks" / "results" / f"repeat_run{'_plots' if args.plots else ''}.md"
    out.write_text("\n".join(lines) + "\n")
    print(f"-> {out}")


if __name__ == "__main__":
    main()
