#!/usr/bin/env python
"""When is linear contact enough? Cylinders, a bar and a sphere pressed into the fingertip with linear
kinematics (fem.contact.linear: small strain, gap along the approach) and with finite kinematics
(fem.contact.finite: neo-Hookean layers, gap by normal projection in the deformed configuration),
depth by depth: the force ratio finite / linear, where it first differs by 5 %, the work against
the stored energy (frictionless contact stores the indentor's work), the largest penetration and
the run time. Models: the five-layer 2D monkey section (z = 5 mm, 0.25 mm elements, m43338; the
thesis's cylinders C1, C5, C8 and a 2 mm bar to 2 mm) and, with --3d, the 1 mm monkey preset (a
3 mm sphere to 0.5 mm).

    python benchmarks/finite_contact.py [--3d] [--work out/finite_bench] [--no-write]

Writes the table to benchmarks/results/finite_contact.md.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
from scipy.integrate import simpson

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from fem.contact.finite import FiniteContact  # noqa: E402
from fem.contact.indentors import make_indentor  # noqa: E402
from fem.contact.linear import ContactModel  # noqa: E402
from fem.geometry.build import MeshSpec, build_folder  # noqa: E402
from fem.io.modelfolder import CONTACT_REGION, factorise, held_regions, read_model  # noqa: E402

RESULTS = ROOT / "benchmarks" / "results" / "finite_contact.md"
CASES_2D = tuple((code, np.arange(0.25, 2.01, 0.25)) for code in ("C1", "C5", "C8", "bar:2"))
CASES_3D = (("sphere:3", np.arange(0.1, 0.51, 0.1)),)


def compare(model, info, code, depths):
    """One indentor: (rows of the table, the finite solve's seconds)."""
    ind = make_indentor(code)
    region = CONTACT_REGION[model.dim]
    t0 = time.perf_counter()
    fc = FiniteContact(model, region, held_regions(model))
    finite = fc.indent(ind, depths, partial=True)
    seconds = time.perf_counter() - t0
    depths = depths[:len(finite)]
    cm = ContactModel.from_fe(model, factorise(model, info), region)
    linear = np.array([cm.indent(ind, depth_mm=d).total_force_N for d in depths])
    force = np.array([r.force_N for r in finite])
    work = simpson(np.r_[0.0, force], x=np.r_[0.0, depths])
    ratio = force / linear
    first = next((d for d, q in zip(depths, ratio) if abs(q - 1) > 0.05), None)
    rows = [f"| {code} | {d:.2f} | {lin:.4g} | {f:.4g} | {q:.3f} | {r.penetration_mm:.1e} | {r.min_J:.3f} |"
            for d, lin, f, q, r in zip(depths, linear, force, ratio, finite)]
    summary = (f"{code}: finite {seconds:.1f} s; differs by more than 5 % from "
               f"{'%.2f mm' % first if first is not None else 'no depth here'}; work / stored energy at "
               f"{depths[-1]:.2f} mm - 1 = {work / finite[-1].energy_Nmm - 1:+.2e}"
               + (f"; {fc.stopped}" if fc.stopped else ""))
    return rows, summary


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--3d", dest="three", action="store_true", help="also the 1 mm monkey preset (minutes)")
    ap.add_argument("--work", type=Path, default=ROOT / "out" / "finite_bench")
    ap.add_argument("--no-write", action="store_true", help="print only (no results file)")
    args = ap.parse_args()
    models = [("2D monkey section, 0.25 mm", MeshSpec(preset="monkey", section_z_mm=5.0, sizes={"size_mm": 0.25}),
               CASES_2D)]
    if args.three:
        models.append(("3D monkey preset, 1 mm", MeshSpec(preset="monkey", sizes={"size_mm": 1.0}), CASES_3D))
    lines = []
    for name, spec, cases in models:
        folder = args.work / name.split(",")[0].replace(" ", "_")
        build_folder(folder, spec)
        model, info = read_model(folder, "m43338")
        lines += [f"## {name} ({model.ndof} DOFs), m43338", "",
                  "| indentor | depth mm | linear force N | finite force N | finite / linear | penetration mm | "
                  "smallest J |", "|---|---|---|---|---|---|---|"]
        notes = []
        for code, depths in cases:
            rows, summary = compare(model, info, code, depths)
            lines += rows
            notes.append(summary)
            print(summary, flush=True)
        lines += [""] + [f"- {n}" for n in notes] + [""]
    text = "\n".join(lines)
    print(text)
    if not args.no_write:
        RESULTS.write_text("# Linear against finite kinematics\n\n`python benchmarks/finite_contact.py"
                           + (" --3d" if args.three else "") + "`\n\n" + text)


if __name__ == "__main__":
    main()
