"""The small-depth limit of large-deformation contact: linear against finite kinematics at depths
down to 0.1 % of the skin thickness (1.5 mm), on any model folders, through `pipeline.py indent`
(both kinematics, the same scene). Prints per depth the finite / linear ratio minus one of the
force, the contact area (2D: width), the peak pressure and the peak receptor SED at each receptor
depth, with each run's time, and writes them to benchmarks/results/finite_small_depth.md.

A last column solves the small-depth limit itself, in process: the linear solver under the finite
run's own contact forces, each along the indentor's normal where it acts
(`fem.contact.finite.FiniteContact.contact_loads`), against the finite receptor SED. The linear
contact solver's forces act along the approach instead; where a coarse mesh puts the few touching
nodes beside the indentor's lowest line, the two directions part by the indentor's slope there,
whatever the depth.

    python benchmarks/finite_small_depth.py out/cylinder8_bone out/monkey_1mm --indentor C5
    python benchmarks/finite_small_depth.py out/section --depths 0.005 0.015 --material m43338
"""
from __future__ import annotations

import argparse
import csv
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from fem.contact.finite import FiniteContact
from fem.contact.indentors import make_indentor
from fem.experiments.runner import placement
from fem.experiments.scene import Experiment, Receptors
from fem.io.modelfolder import CONTACT_REGION, held_regions, read_model, receptor_surface
from fem.receptors.grid import ReceptorSampler, receptor_grid

ROOT = Path(__file__).resolve().parents[1]
DEPTHS_MM = (0.0015, 0.005, 0.015, 0.05)
"""0.1, 0.33, 1 and 3.3 % of the 1.5 mm skin."""
OUT = ROOT / "benchmarks" / "results" / "finite_small_depth.md"


def _rows(path) -> list[dict]:
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def run(folder, kinematics: str, indentor: str, depth_mm: float, material: list[str]) -> tuple[dict, dict, float]:
    """(step row, {receptor depth: peak SED [MPa]}, seconds of the whole command) of one indentation."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "run"
        t0 = time.perf_counter()
        args = [sys.executable, str(ROOT / "pipeline.py"), "indent", str(folder), "--indentor", indentor, "--depth",
                f"{depth_mm:g}", "--kinematics", kinematics, "--out", str(out), "--quiet", "--no-plots", *material]
        if subprocess.run(args).returncode != 0:
            raise SystemExit(f"indent failed: {' '.join(args)}")
        seconds = time.perf_counter() - t0
        (table,) = [p for p in out.glob("*.csv") if not p.stem.endswith(("_receptors", "_surface"))]
        step = _rows(table)[0]
        receptors = _rows(next(out.glob("*_receptors.csv")))
    depth = np.array([float(r["depth_mm"]) for r in receptors])
    sed = np.array([float(r["sed_MPa"]) for r in receptors])
    return step, {float(d): float(sed[depth == d].max()) for d in np.unique(depth)}, seconds


def own_forces(folder, indentor: str, depth_mm: float, material: str | None) -> dict:
    """{receptor depth [mm]: finite peak SED / peak SED of the linear solver under the finite run's
    contact forces along their normals - 1} of one indentation (default receptors)."""
    model, info = read_model(folder, material)
    sn = model.surface_nodes(CONTACT_REGION[model.dim])
    exp = Experiment.from_dict({"indentor": indentor, "depth_mm": depth_mm})
    ind = make_indentor(indentor, **placement(exp, model, info, sn)[0])
    fc = FiniteContact(model, CONTACT_REGION[model.dim], held_regions(model))
    (r,) = fc.indent(ind, [depth_mm])
    rc = Receptors()
    grid = receptor_grid(*receptor_surface(model, sn), np.asarray(rc.depths_mm, float), rc.spacing_mm)
    sampler = ReceptorSampler(model, grid)
    finite = sampler.with_energy().measures(fc.observe(r.u, sampler), ["sed_MPa"])["sed_MPa"]
    u = model.system(held_regions(model)).solve(fc.contact_loads(r))
    linear = sampler.measures(sampler.operator @ u, ["sed_MPa"])["sed_MPa"]
    at = np.asarray(grid.depth_mm, float)
    return {float(d): float(finite[at == d].max() / linear[at == d].max() - 1) for d in np.unique(at)}


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folders", nargs="+", type=Path)
    ap.add_argument("--indentor", default="C5")
    ap.add_argument("--depths", nargs="+", type=float, default=DEPTHS_MM)
    ap.add_argument("--material", default=None)
    args = ap.parse_args(argv)
    material = ["--material", args.material] if args.material else []
    lines = ["| model | depth [mm] | force | contact area | peak pressure | peak SED at receptor depths | "
             "linear / finite command [s] | peak SED, finite / linear under the finite's own forces |",
             "|---|---|---|---|---|---|---|---|"]
    for folder in args.folders:
        for depth in args.depths:
            (lin, lin_sed, t_lin), (fin, fin_sed, t_fin) = (run(folder, k, args.indentor, depth, material)
                                                             for k in ("linear", "finite"))
            rel = {k: float(fin[k]) / float(lin[k]) - 1 for k in ("force_N", "contact_area_mm2", "max_pressure_MPa")}
            sed = ", ".join(f"{d:g} mm {fin_sed[d] / lin_sed[d] - 1:+.2%}" for d in sorted(lin_sed))
            own = ", ".join(f"{d:g} mm {v:+.2%}" for d, v in sorted(own_forces(folder, args.indentor, depth,
                                                                               args.material).items()))
            row = (f"| {folder.name} | {depth:g} | {rel['force_N']:+.3%} | {rel['contact_area_mm2']:+.2%} | "
                   f"{rel['max_pressure_MPa']:+.2%} | {sed} | {t_lin:.1f} / {t_fin:.1f} | {own} |")
            print(row, flush=True)
            lines.append(row)
    OUT.write_text(f"# Small-depth limit, {args.indentor}: finite / linear - 1\n\n" + "\n".join(lines) + "\n")
    print(f"written to {OUT.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
