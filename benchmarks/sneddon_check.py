#!/usr/bin/env python
"""Sneddon check: a rigid flat circular punch (a = 1 mm, 0.5 mm deep, E = 0.05 MPa, nu = 0.4:
TouchSim's skin) on fem.verify.halfspace.flat_block_model, against Sneddon's (1946) closed form, run time
next to error, for a coarse and a finer mesh.

    python benchmarks/sneddon_check.py                  # coarse (tests/fem/verify/test_sneddon.py) and finer mesh:
                                                        # 60 s, 7.2 GB peak on 2 cores
    python benchmarks/sneddon_check.py --study          # + block sizes, side conditions (about 1 min more)
    python benchmarks/sneddon_check.py --tensor         # + the tensor-grid mesh (90 s, 18 GB peak)
    python benchmarks/sneddon_check.py --out results.md # also append the tables to a file

Reported per mesh: DOFs, setup time (mesh, assembly, factorisation with the punch footprint
condensed, stress operator), indentation time, the force error against 2 a E d / (1 - nu^2), and
the vertical stress error at TouchSim's afferent depths (SA1 0.3, RA 1.6, PC 2.0 mm) on the axis,
at r = 0.5 a and at r = 2 a: relative to the closed form at Sneddon's force for the depth (the
check as TouchSim uses it: depth -> force -> stress), and at the FE's own force (the stress
distribution alone). At r = 2 a, 0.3 mm deep, where the stress is 0.7 % of the axial one, the
error is given as a fraction of the axial stress at that depth (marked *).

Measured (2 cores): coarse, fine 0.25 mm (the test's): 115,593 DOFs, 10-12 s setup, 0.1 s per
indentation; force +1.63 %; stress at Sneddon's force within +2.8 %, at the FE force within 1.6 %.
Finer, 0.167 mm: 275,169 DOFs, 47 s, 0.5 s; force +1.51 %; stress within +2.1 % and 0.9 %. The
force excess is mostly the finite block (about 0.9 a / L: +5.1 / +2.8 / +1.6 / +1.1 % at L = 20,
40, 80, 160 mm, `--study`), which leaves the stresses at the FE's force unchanged (0.1 %).
"""
from __future__ import annotations

import argparse
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from fem.verify.closed_forms import sneddon_punch_force_N, sneddon_punch_stress_zz_MPa  # noqa: E402
from fem.verify.halfspace import flat_block_model  # noqa: E402

RADIUS_MM, DEPTH_MM, E_MPA, NU = 1.0, 0.5, 0.05, 0.4
AFFERENTS = (("SA1", 0.3), ("RA", 1.6), ("PC", 2.0))
OFFSETS = (0.0, 0.5, 2.0)                       # r / a
HEADER = ("| mesh | DOFs | setup s | indent s | force err | stress at | SA1 0.3 mm: r = 0 / 0.5a / 2a | "
          "RA 1.6 mm | PC 2.0 mm |\n|---|---|---|---|---|---|---|---|---|")


def run(name, **kw):
    """One block, one indentation; two table rows (stress at Sneddon's force, at the FE's)."""
    pts = np.array([[r * RADIUS_MM, -d, 0.0] for _, d in AFFERENTS for r in OFFSETS])
    t = time.perf_counter()
    block = flat_block_model(radius_mm=RADIUS_MM, E_MPa=E_MPA, nu=NU, **kw)
    cm = block.contact(observe=block.model.stress_operator(pts))
    setup_s = time.perf_counter() - t
    t = time.perf_counter()
    res = cm.indent(block.punch(), depth_mm=DEPTH_MM)
    fe = -res.observed.reshape(-1, 6)[:, 1]                    # compression positive
    indent_s = time.perf_counter() - t
    force = block.symmetry * res.total_force_N
    P = sneddon_punch_force_N(RADIUS_MM, DEPTH_MM, E_MPA, NU)
    assert res.kkt["ok"], res.kkt
    rows = []
    for label, load in (("Sneddon's force", P), ("FE force", force)):
        ref = sneddon_punch_stress_zz_MPa(pts[:, 0], -pts[:, 1], RADIUS_MM, load)
        err = (fe / ref - 1).reshape(len(AFFERENTS), len(OFFSETS))
        axial = fe.reshape(len(AFFERENTS), len(OFFSETS))[:, :1]
        small = (ref.reshape(err.shape) < 0.05 * axial)         # nearly unloaded: vs the axial stress
        err = np.where(small, ((fe - ref).reshape(err.shape)) / axial, err)
        cells = [" / ".join(f"{e:+.2%}" + ("*" if s else "") for e, s in zip(er, sm)) for er, sm in zip(err, small)]
        first = label == "Sneddon's force"
        rows.append(f"| {name if first else ''} | {block.model.ndof if first else ''} | "
                    f"{f'{setup_s:.1f}' if first else ''} | {f'{indent_s:.2f}' if first else ''} | "
                    f"{f'{force / P - 1:+.2%}' if first else ''} | {label} | " + " | ".join(cells) + " |")
    for row in rows:
        print(row, flush=True)
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--study", action="store_true", help="also block sizes 20-160 mm and side conditions")
    ap.add_argument("--tensor", action="store_true",
                    help="also the tensor-grid mesh (351k DOFs: 90 s, 18 GB peak memory on 2 cores)")
    ap.add_argument("--out", help="append the tables to this markdown file")
    args = ap.parse_args()
    print(HEADER)
    rows = run("coarse: fine 0.25 mm, 80 mm quarter block (the test's)")
    rows += run("finer: fine 0.167 mm, 80 mm quarter block", fine_mm=1 / 6)
    if args.study:
        for L in (20.0, 40.0, 160.0):
            rows += run(f"coarse, {L:g} mm block", half_width_mm=L, depth_mm=L)
        for sides in ("roller", "held"):
            rows += run(f"coarse, 20 mm block, sides {sides}", half_width_mm=20.0, depth_mm=20.0, sides=sides)
    if args.tensor:
        rows += run("coarse tensor grid (staircase punch edge)", round_punch=False)
    if args.out:
        stamp = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
        with open(args.out, "a") as fh:
            fh.write(f"\n## sneddon ({stamp}; {platform.processor() or platform.machine()}, {os.cpu_count()} cores)\n\n"
                     f"{HEADER}\n" + "\n".join(rows) + "\n")


if __name__ == "__main__":
    main()
