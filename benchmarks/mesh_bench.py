"""Mesh benchmark: tets, time and quality against the volar target edge length, human preset.

    python benchmarks/mesh_bench.py                      # 1.0 0.7 0.5 0.35 0.25 mm
    python benchmarks/mesh_bench.py --sizes 1.0 0.5 --max-seconds 120

Always re-meshes (no cache). Sizes run from coarse to fine; a size whose predicted time
(previous CPU time / 2 cores x (previous size / size)^3) exceeds --max-seconds is skipped and
reported as such. CPU time (all threads) is reported beside wall time because the machine may be
shared: on 2 idle cores the wall time lies between CPU s / 2 (both cores busy) and CPU s.
Prints a table and writes benchmarks/results/mesh_bench.md.
"""
from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

from fem.geometry.layered import model_from_args, params_for  # noqa: E402
from fem.geometry.mesh3d import (  # noqa: E402
    Sizing,
    TetMesh,
    label_tets,
    region_tags,
    report,
    tetrahedralize,
)

COLUMNS = ("size mm", "wall s", "cpu s", "tets", "points", "fine-zone median edge mm", "max volume error %",
           "bone volume error %", "min dihedral deg", "1st pct dihedral deg", "min scaled Jacobian",
           "straddling tets")


def run(size_mm: float, model) -> dict:
    sizing = Sizing(size_mm=size_mm)
    t0, c0 = time.perf_counter(), time.process_time()
    points, tets = tetrahedralize(model, sizing)
    seconds, cpu = time.perf_counter() - t0, time.process_time() - c0
    mesh = TetMesh(points, tets, label_tets(model, points, tets), region_tags(model, points, tets))
    rep = report(model, mesh, sizing)
    err = [abs(e) for e in rep["layer_volume_error_pct"]]
    q = rep["quality"]
    return {"size mm": size_mm, "wall s": seconds, "cpu s": cpu, "tets": rep["tets"], "points": rep["points"],
            "fine-zone median edge mm": rep["sizing_achieved"]["fine_zone_median_edge_mm"],
            "max volume error %": max(err), "bone volume error %": rep["layer_volume_error_pct"][4],
            "min dihedral deg": q["min_dihedral_deg"], "1st pct dihedral deg": q["p1_dihedral_deg"],
            "min scaled Jacobian": q["min_scaled_jacobian"], "straddling tets": rep["straddle"]["straddling_tets"]}


def fmt(v):
    return f"{v:.3g}" if isinstance(v, float) else str(v)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sizes", type=float, nargs="+", default=[1.0, 0.7, 0.5, 0.35, 0.25])
    ap.add_argument("--max-seconds", type=float, default=400.0, help="skip sizes predicted to take longer")
    ap.add_argument("--preset", default="human")
    args = ap.parse_args(argv)
    model = model_from_args(None, args.preset, params_for(args.preset))
    rows, skipped, prev = [], [], None
    load0 = os.getloadavg()[0]
    for size in sorted(args.sizes, reverse=True):
        if prev is not None:
            predicted = prev[1] * (prev[0] / size) ** 3
            if predicted > args.max_seconds:
                skipped.append(f"{size} mm: skipped, predicted {predicted:.0f} s > --max-seconds {args.max_seconds:.0f}")
                print(skipped[-1], flush=True)
                continue
        row = run(size, model)
        rows.append(row)
        prev = (size, row["cpu s"] / 2)          # what it would take on 2 idle cores
        print("  ".join(f"{k}={fmt(row[k])}" for k in COLUMNS), flush=True)
        write_markdown(args.preset, rows, skipped, load0)
    write_markdown(args.preset, rows, skipped, load0)
    print((HERE / "results" / "mesh_bench.md").read_text())


def write_markdown(preset, rows, skipped, load0):
    """Write benchmarks/results/mesh_bench.md (called after every size, so a killed run keeps its rows)."""
    head = "| " + " | ".join(COLUMNS) + " |\n|" + "---|" * len(COLUMNS) + "\n"
    body = "".join("| " + " | ".join(fmt(r[k]) for k in COLUMNS) + " |\n" for r in rows)
    text = (f"# Mesh benchmark ({preset} preset)\n\n"
            f"pytetwild with the default sizing (coarse 3 mm, growth 0.5, fine zone 1.5 mm deep, envelope "
            f"0.02 mm, 20 optimisation passes), {os.cpu_count()} cores, load average {load0:.1f} at the start "
            f"(the machine is shared: wall s is under that load; cpu s counts all threads, and 2 idle cores "
            f"take between cpu s / 2 and cpu s). Volume errors: tets per layer vs the "
            f"model's layer shells.\n\n" + head + body
            + "".join(f"\n- {s}" for s in skipped) + "\n")
    out = HERE / "results" / "mesh_bench.md"
    out.parent.mkdir(exist_ok=True)
    out.write_text(text)


if __name__ == "__main__":
    main()
