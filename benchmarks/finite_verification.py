#!/usr/bin/env python
"""Large-deformation contact verified on the 2D cylinder8 with bone under C5 (m43338):

- energy balance: depths 0.05:2:0.05 mm with both kinematics; at every depth the work of the
  indentor, the integral of its force over depth from first touch, against the stored strain
  energy `energy_Nmm` of the step table (frictionless contact stores the work), the integral
  by `fem.verify.energy.indentation_work_Nmm` (a power law on the first interval, then Simpson);
  with --energy-3d MODEL also on a 3D model folder, C5 across the finger, 0.05:1.5:0.05 mm;
- mesh convergence at 2 mm: finite kinematics at three sizes (`--sizes`, default 0.25, 0.125
  and 0.0625 mm; each halving refines every layer), force and receptor strain energy density at
  0.75 mm depth, under the cylinder's axis (the point 0.75 mm below the apex, the same on every
  mesh) and the peak over the receptor grid (1 mm spacing; its sites are the surface nodes nearest
  to multiples of 1 mm, so they move with the mesh), their changes from the next coarser size, the
  observed order from the three and a Richardson estimate of the limit.

Every run goes through `run_scene`, the command line's path; meshes are built anew
(`build_folder`). Prints the tables with run times and writes
benchmarks/results/finite_verification.md.

    python benchmarks/finite_verification.py [--sizes 0.25 0.125 0.0625] [--energy-size 0.125] [--energy-3d MODEL] [--no-write]
"""
from __future__ import annotations

import argparse
import logging
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from fem.experiments.runner import run_scene  # noqa: E402
from fem.experiments.scene import Scene  # noqa: E402
from fem.geometry.build import MeshSpec, build_folder  # noqa: E402
from fem.io.runfolder import run_tables  # noqa: E402
from fem.verify.energy import indentation_work_Nmm  # noqa: E402

MATERIAL = "m43338"
RECEPTOR_DEPTH_MM = 0.75
ENERGY_DEPTHS = "0.05:2:0.05"
ENERGY_DEPTHS_3D = "0.05:1.5:0.05"


def cylinder(work: Path, size_mm: float) -> Path:
    """The 2D cylinder8 with bone meshed at size_mm in work/ (built anew)."""
    folder = work / f"cylinder8_bone_{size_mm:g}"
    build_folder(folder, MeshSpec(preset="cylinder8", bone=True, sizes={"size_mm": size_mm}), force=True)
    return folder


def run(folder: Path, depths, kinematics: str, across: bool = False) -> tuple[dict, float]:
    """(step table, seconds) of C5 at `depths` with `kinematics`, receptors at RECEPTOR_DEPTH_MM;
    across: perpendicular to the finger (3D)."""
    experiment = {"name": "C5", "indentor": "C5", "depth_mm": depths} | ({"orientation": "perpendicular"} if across else {})
    scene = Scene.from_dict({"material": MATERIAL, "kinematics": kinematics,
                             "receptors": {"depths_mm": [RECEPTOR_DEPTH_MM], "measures": ["sed_MPa"]},
                             "output": {"pvd": False, "plots": False}, "experiment": [experiment]})
    t0 = time.perf_counter()
    sr = run_scene(folder, scene)
    seconds = time.perf_counter() - t0
    tables = run_tables(sr.experiments[0], sr)
    steps = {k: np.asarray(v) for k, v in tables["steps"].items()}
    sed = tables["values"]["sed_MPa"]                                   # (steps, receptor points)
    x = np.asarray(tables["receptors"]["x_mm"])[:sed.shape[1]]
    steps["peak_sed_MPa"], steps["axis_sed_MPa"] = sed.max(axis=1), sed[:, np.argmin(np.abs(x))]
    return steps, seconds


def energy_section(title: str, folder: Path, depths: str, across: bool = False) -> list[str]:
    """The markdown section of the energy balance of C5 at `depths` on `folder` with both
    kinematics: each one's largest |work / energy - 1| and run time, then a table of every fourth
    depth (forces in N/mm in 2D, N across a 3D finger)."""
    rows, head = {}, [f"## {title}", ""]
    for kinematics in ("linear", "finite"):
        steps, seconds = run(folder, depths, kinematics, across)
        d, f = steps["depth_mm"], steps["force_N"]
        ratio = indentation_work_Nmm(d, f) / steps["energy_Nmm"] - 1.0
        rows[kinematics] = (f, ratio)
        k = int(np.argmax(np.abs(ratio)))
        head.append(f"- {kinematics}: largest |work / energy - 1| {abs(ratio[k]):.1e} (at {d[k]:.2f} mm), "
                    f"run {seconds:.1f} s")
    unit = "N" if across else "N/mm"
    lines = head + ["", f"| depth mm | linear force {unit} | linear work / energy - 1 | finite force {unit} "
                        "| finite work / energy - 1 |", "|---|---|---|---|---|"]
    (fl, rl), (ff, rf) = rows["linear"], rows["finite"]
    lines += [f"| {d[k]:.2f} | {fl[k]:.5g} | {rl[k]:+.1e} | {ff[k]:.5g} | {rf[k]:+.1e} |"
              for k in range(len(d)) if k < 4 or (k + 1) % 4 == 0]
    print("\n".join(lines), flush=True)
    return lines


def convergence_table(work: Path, sizes) -> list[str]:
    got = []
    for h in sizes:
        folder = cylinder(work, h)
        steps, seconds = run(folder, [2.0], "finite")
        got.append((h, float(steps["force_N"][-1]), float(steps["axis_sed_MPa"][-1]),
                    float(steps["peak_sed_MPa"][-1]), seconds))
        print(f"  {h:g} mm: force {got[-1][1]:.6g} N/mm, SED on the axis {got[-1][2]:.5g}, peak {got[-1][3]:.5g} MPa, "
              f"{seconds:.1f} s", flush=True)
    lines = ["| size mm | force N/mm | change % | SED on the axis, MPa | change % | peak SED, MPa | change % | run s |",
             "|---|---|---|---|---|---|---|---|"]
    for k, row in enumerate(got):
        cells = [f"{row[c]:.6g} | " + (f"{100 * (row[c] / got[k - 1][c] - 1):+.3f}" if k else "") for c in (1, 2, 3)]
        lines.append(f"| {row[0]:g} | " + " | ".join(cells) + f" | {row[4]:.1f} |")
    if len(got) >= 3:
        for name, col in (("force", 1), ("SED on the axis", 2), ("peak SED", 3)):
            a, b, c = (g[col] for g in got[-3:])
            if (b - a) * (c - b) > 0 and abs(c - b) < abs(b - a):
                order = np.log(abs(b - a) / abs(c - b)) / np.log(got[-2][0] / got[-1][0])
                limit = c + (c - b) / ((got[-2][0] / got[-1][0]) ** order - 1)
                lines.append(f"\n{name}: observed order {order:.2f}; Richardson limit {limit:.6g}, the finest "
                             f"{100 * (c / limit - 1):+.3f} % from it")
            else:
                lines.append(f"\n{name}: changes {100 * (b / a - 1):+.3f} %, {100 * (c / b - 1):+.3f} %: "
                             "not monotonic and shrinking, no order")
    return lines


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sizes", nargs="+", type=float, default=[0.25, 0.125, 0.0625])
    ap.add_argument("--energy-size", type=float, default=0.125)
    ap.add_argument("--energy-3d", type=Path, help="a 3D model folder: the energy balance there too, C5 across "
                    f"the finger, {ENERGY_DEPTHS_3D} mm (minutes: each Newton iteration factorises)")
    ap.add_argument("--no-write", action="store_true")
    args = ap.parse_args(argv)
    logging.getLogger("fem").setLevel(logging.ERROR)       # the linear validity warnings of deep runs
    out = ["# Finite-kinematics verification on the 2D cylinder8 with bone (C5, m43338)", "",
           "Written by `benchmarks/finite_verification.py`.", ""]
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        out += energy_section(f"Energy balance: work of the indentor against the stored energy, {ENERGY_DEPTHS} mm "
                              f"({args.energy_size:g} mm elements)", cylinder(work, args.energy_size), ENERGY_DEPTHS)
        if args.energy_3d is not None:
            out += [""] + energy_section(f"Energy balance in 3D: {args.energy_3d.name}, C5 across the finger, "
                                         f"{ENERGY_DEPTHS_3D} mm", args.energy_3d, ENERGY_DEPTHS_3D, across=True)
        print("mesh convergence at 2 mm, finite kinematics", flush=True)
        conv = convergence_table(work, args.sizes)
        out += ["", "## Mesh convergence at 2 mm, finite kinematics", ""] + conv
        print("\n".join(conv))
    if not args.no_write:
        (ROOT / "benchmarks" / "results" / "finite_verification.md").write_text("\n".join(out) + "\n")


if __name__ == "__main__":
    main()
