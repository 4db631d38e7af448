"""fit-material on Dask: wall time of one deflection fit in this process and on 1 and 2 local
workers (one task per trial material: the Jacobian's columns and the integer roundings), the
speed-up, and whether fit.json is the serial run's.

    python benchmarks/fit_dask_bench.py                     # 2D monkey section, size 0.25 mm
    python benchmarks/fit_dask_bench.py --size 0.125 --free-layers 2,3,4
    python benchmarks/fit_dask_bench.py --3d --size 1.0 --free-layers 2,3,4   # the 3D monkey preset

The model and the measured-like profiles (the model's own, layer 3 at 10^3.4 Pa, at 1 and 2 mm)
are made first; every fit starts from the same model folder and writes a fresh output folder. Each
fit is the whole command as a user runs it (`python pipeline.py fit-material ... --scheduler S`
in its own process), so its wall time includes the interpreter's start-up and the imports.
"""
from __future__ import annotations

import argparse
import json
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from fem.biomech.deflection import DeflectionExperiment  # noqa: E402
from fem.geometry.build import MeshSpec, build_folder  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--size", default="0.25", help="2D mesh size in mm (default 0.25)")
    ap.add_argument("--free-layers", default="2,3", help="fitted layers (default 2,3)")
    ap.add_argument("--3d", dest="three_d", action="store_true", help="the 3D monkey preset instead of its section")
    ap.add_argument("--out", help="append the Markdown table to this file")
    args = ap.parse_args()
    work = Path(tempfile.mkdtemp())
    model = work / "msec"
    section = [] if args.three_d else ["--section-z", "5"]
    build_folder(model, MeshSpec(preset="monkey", section_z_mm=None if args.three_d else 5.0,
                                 sizes={"size_mm": float(args.size)}))
    dist = np.arange(0.2, 3.0, 0.2)
    lines = ["distance_mm,deflection_mm,depth_mm"]
    for p in DeflectionExperiment(model).profiles([4.0, 3.0, 3.4, 3.0, 8.0], [1.0, 2.0]):
        lines += [f"{d:.2f},{w:.6f},{p.depth_mm:g}" for d, w in zip(dist, p.at(dist))]
    (work / "defl.csv").write_text("\n".join(lines) + "\n")
    rows, reports = [], {}
    for sched in ("none", "local:1", "local:2"):
        out = work / sched.replace(":", "")
        t0 = time.perf_counter()
        subprocess.run([sys.executable, str(ROOT / "pipeline.py"), "fit-material", str(model), "--out", str(out),
                        "--deflection", str(work / "defl.csv"), "--free-layers", args.free_layers,
                        "--scheduler", sched, "--quiet"], check=True)
        seconds = time.perf_counter() - t0
        rep = json.loads((out / "fit.json").read_text())
        rep.pop("seconds")
        reports[sched] = rep
        fit = rep["deflection_fit"]
        rows.append((sched, seconds, fit["model_evaluations"], fit["optimizer_evaluations"]))
    same = all(r == reports["none"] for r in reports.values())
    base = rows[0][1]
    text = [f"\n## fit-material on Dask ({platform.node()}, {platform.machine()}, Python {platform.python_version()})\n",
            f"{'3D monkey preset' if args.three_d else '2D monkey section'} (`{' '.join(section)} --size {args.size}`), "
            f"free layers {args.free_layers}, profiles at "
            f"1 and 2 mm; one task per trial material (Jacobian columns, integer roundings); the whole "
            f"command in its own process: the interpreter's start-up, the imports and the cluster start-up are "
            f"inside the wall time.\n",
            "| scheduler | wall, s | speed-up vs none | materials used | optimizer steps |", "|---|---|---|---|---|"]
    text += [f"| {s} | {t:.2f} | {base / t:.2f} | {n} | {k} |" for s, t, n, k in rows]
    text.append(f"\nfit.json (without seconds) identical across the three schedulers: {'yes' if same else 'NO'}\n")
    print("\n".join(text))
    if args.out:
        with open(args.out, "a") as fh:
            fh.write("\n".join(text))


if __name__ == "__main__":
    main()
