"""Run time of large-deformation contact against the linear first run, whole commands: the same
`pipeline.py indent` scene with `--kinematics linear` and `--kinematics finite` on each model
folder (copied without its stored response models, so the linear run is a first run), one after
the other in this run. Prints per model both commands' seconds, their ratio, the finite
command's peak memory, the last depth's force of each, and the targets (the 2D cylinder with
bone, C5 0.25:2:0.25 mm: finite under 10 s; 3D: finite under 10 times linear; with --within
SECONDS GB: finite under both instead, the human 0.5 mm model's 10 minutes and 8 GB); writes
benchmarks/results/finite_speed.md.

    python pipeline.py mesh --preset cylinder8 --bone --out out/cyl8
    python benchmarks/finite_speed.py out/cyl8
    python benchmarks/finite_speed.py out/monkey_1mm --depth 0.5:2:0.5 --axis perpendicular
    python benchmarks/finite_speed.py out/human_05mm --depth 0.5:3:0.5 --axis perpendicular --within 600 8
"""
from __future__ import annotations

import argparse
import csv
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "benchmarks" / "results" / "finite_speed.md"
TARGET_2D_S = 10.0
"""The 2D cylinder with bone's finite run, whole command (seconds)."""
TARGET_3D_RATIO = 10.0
"""A 3D finite run against the linear first run of the same scene."""


def run(folder: Path, kinematics: str, extra: list[str]) -> tuple[float, float, float]:
    """(seconds of the whole command, its peak resident memory [GB], force [N; N/mm in 2D] at the
    last depth) of one indent."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "run"
        args = [sys.executable, str(ROOT / "pipeline.py"), "indent", str(folder), *extra, "--kinematics", kinematics,
                "--out", str(out), "--quiet", "--no-plots", "--no-pvd"]
        t0 = time.perf_counter()
        _, status, usage = os.wait4(subprocess.Popen(args).pid, 0)      # this command's own peak memory
        if os.waitstatus_to_exitcode(status) != 0:
            raise SystemExit(f"indent failed: {' '.join(args)}")
        seconds = time.perf_counter() - t0
        (table,) = [p for p in out.glob("*.csv") if not p.stem.endswith(("_receptors", "_surface"))]
        with open(table, newline="") as fh:
            force = float(list(csv.DictReader(fh))[-1]["force_N"])
    return seconds, usage.ru_maxrss / 1e6, force


def _with_section(text: str, title: str, section: str) -> str:
    """The results file `text` with the section headed `title` replaced by (or added as) `section`."""
    head = "# Finite against linear kinematics: whole `pipeline.py indent` commands, one after the other\n"
    parts = [p for p in text.split("\n## ")[1:] if not ("## " + p).startswith(title + "\n")]
    return head + "".join("\n## " + p for p in parts) + "\n" + section


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folders", nargs="+", type=Path)
    ap.add_argument("--indentor", default="C5")
    ap.add_argument("--depth", default="0.25:2:0.25", help="depths in mm (start:stop:step or a list)")
    ap.add_argument("--axis", default=None, help="indentor orientation in 3D (e.g. perpendicular)")
    ap.add_argument("--within", nargs=2, type=float, metavar=("SECONDS", "GB"), default=None,
                    help="target: the finite command under SECONDS and GB (instead of the ratio)")
    args = ap.parse_args(argv)
    extra = ["--indentor", args.indentor, "--depth", args.depth] + (["--axis", args.axis] if args.axis else [])
    title = f"## {args.indentor} at {args.depth} mm" + (f", {args.axis}" if args.axis else "")
    lines = [title, "", "| model | mesh vertices | linear s | finite s | finite / linear | finite peak GB "
             "| force linear / finite | target | met |", "|---|---:|---:|---:|---:|---:|---|---|---|"]
    for folder in args.folders:
        info = json.loads((folder / "model.json").read_text())
        dim = 3 if "tets" in info["mesh"] else 2
        with tempfile.TemporaryDirectory() as tmp:        # a copy without stored response models:
            model = Path(tmp) / folder.name                # the linear run is a first run
            shutil.copytree(folder, model, ignore=shutil.ignore_patterns("response"))
            (t_lin, _, f_lin), (t_fin, gb_fin, f_fin) = (run(model, k, extra) for k in ("linear", "finite"))
        if args.within is not None:
            target, met = (f"finite < {args.within[0]:g} s and {args.within[1]:g} GB",
                           t_fin < args.within[0] and gb_fin < args.within[1])
        else:
            target, met = ((f"finite < {TARGET_2D_S:g} s", t_fin < TARGET_2D_S) if dim == 2 else
                           (f"finite < {TARGET_3D_RATIO:g} x linear", t_fin < TARGET_3D_RATIO * t_lin))
        row = (f"| {folder.name} | {info['mesh']['points']:,} | {t_lin:.1f} | {t_fin:.1f} | {t_fin / t_lin:.1f} "
               f"| {gb_fin:.2f} | {f_lin:.5g} / {f_fin:.5g} | {target} | {'yes' if met else 'no'} |")
        print(row, flush=True)
        lines.append(row)
    OUT.write_text(_with_section(OUT.read_text() if OUT.exists() else "", title, "\n".join(lines) + "\n"))
    print(f"written to {OUT.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
