#!/usr/bin/env python
"""When is linear contact enough? Each indentor class pressed into the fingertip with linear
kinematics (fem.contact.linear: small strain, gap along the approach) and with finite kinematics
(fem.contact.finite: neo-Hookean layers, gap by normal projection in the deformed configuration),
depth by depth, through the scene runner (`run_scene`, the command line's path): the ratio finite /
linear of the force, the contact area (2D: width), the peak pressure and the peak receptor strain
energy density at 0.75 mm, the depth where each first differs by 5 % (interpolated between the
depths run), the work against the stored energy (frictionless contact stores the indentor's work)
and the run times.

Indentors: cylinders C1, C5, C8, a 2 mm bar, a 3 mm sphere (in 2D its circular section) and step 2.
Models (m43338): the five-layer 2D monkey section (z = 5 mm, 0.25 mm elements) and the 2D 8 mm
cylinder with bone (0.25 mm elements), 0.05 to 1 mm; with --3d the 1 mm monkey preset, 0.1 to
1 mm (minutes per indentor), and with --human also the 1 mm human preset.

    python benchmarks/finite_contact.py [--3d] [--human] [--models monkey] [--only C5 sphere:3] [--no-write]

Writes benchmarks/results/finite_contact.json (per model and indentor the runs and the 5 % depth
of each measure: what `fem.experiments.runner.LINEAR_ENOUGH_MM` holds; a model run again replaces
the records of the indentors it ran) and, from it, the tables of finite_contact.md.
"""
from __future__ import annotations

import argparse
import json
import logging
import sys
import time
from pathlib import Path

import numpy as np
from scipy.integrate import simpson

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from fem.experiments.runner import run_scene  # noqa: E402
from fem.experiments.scene import Scene  # noqa: E402
from fem.geometry.build import MeshSpec, build_folder  # noqa: E402

RESULTS = ROOT / "benchmarks" / "results" / "finite_contact.md"
INDENTORS = ("C1", "C5", "C8", "bar:2", "sphere:3", "step:2")
STEP_X_MM = -0.5
"""x of step 2's edge on the 2D models (its near level over the pad's top)."""
RECEPTOR_DEPTH_MM = 0.75
BAND = 0.05
MEASURES = ("force", "contact", "peak pressure", "SED")
MODELS = {
    "section": ("2D monkey section, z = 5 mm, 0.25 mm",
                MeshSpec(preset="monkey", section_z_mm=5.0, sizes={"size_mm": 0.25}), np.arange(0.05, 1.001, 0.05)),
    "cylinder8": ("2D 8 mm cylinder with bone, 0.25 mm",
                  MeshSpec(preset="cylinder8", bone=True, sizes={"size_mm": 0.25}), np.arange(0.05, 1.001, 0.05)),
    "monkey": ("3D monkey preset, 1 mm", MeshSpec(preset="monkey", sizes={"size_mm": 1.0}), np.arange(0.1, 1.001, 0.1)),
    "human": ("3D human preset, 1 mm", MeshSpec(preset="human", sizes={"size_mm": 1.0}), np.arange(0.1, 1.001, 0.1)),
}


def scene(code: str, depths, dim: int, kinematics: str) -> Scene:
    """One indentor at the pad's middle (3D: across the finger), receptors at 0.75 mm, no files."""
    exp = {"name": code.replace(":", "_"), "indentor": code, "depth_mm": [float(d) for d in depths],
           "orientation": "parallel" if dim == 2 else "perpendicular"}
    if code.startswith("step") and dim == 2:
        exp["position_mm"] = [STEP_X_MM, 0.0]
    return Scene.from_dict({"kinematics": kinematics, "experiment": [exp], "output": {"pvd": False, "plots": False},
                            "receptors": {"depths_mm": [RECEPTOR_DEPTH_MM], "spacing_mm": 0.5,
                                          "measures": ["sed_MPa"]}})


def measures(sr) -> dict:
    """{measure: (n,) per depth} of a SceneRun's only experiment, and its energies."""
    steps = [res for _, res in sr.experiments[0].steps]
    sed = [float(sr.sampler.measures(r.observed, ["sed_MPa"])["sed_MPa"].max()) for r in steps]
    return {"force": np.array([r.total_force_N for r in steps]),
            "contact": np.array([r.contact_area_mm2 for r in steps]),
            "peak pressure": np.array([r.max_pressure_MPa for r in steps]),
            "SED": np.array(sed),
            "energy": np.array([r.stored_energy_Nmm if r.stored_energy_Nmm is not None else np.nan for r in steps])}


def five_percent_depth(depths, ratio) -> float | None:
    """The depth [mm] where |ratio - 1| first reaches BAND, linear between the depths run (the first
    depth when it is beyond the band there already; None when it never is)."""
    e = np.abs(np.asarray(ratio) - 1)
    beyond = np.flatnonzero(e >= BAND)
    if not beyond.size:
        return None
    i = int(beyond[0])
    if i == 0:
        return float(depths[0])
    return float(depths[i - 1] + (BAND - e[i - 1]) / (e[i] - e[i - 1]) * (depths[i] - depths[i - 1]))


def compare(folder: Path, dim: int, code: str, depths) -> dict:
    """Linear and finite runs of one indentor -> the record of the results JSON."""
    t0 = time.perf_counter()
    lin = measures(run_scene(folder, scene(code, depths, dim, "linear")))
    t1 = time.perf_counter()
    fsr = run_scene(folder, scene(code, depths, dim, "finite"))
    t2 = time.perf_counter()
    fin = measures(fsr)
    n = len(fin["force"])                       # a finite run that stopped early has fewer depths
    d = np.asarray(depths[:n], float)
    ratio = {m: (fin[m] / lin[m][:n]).tolist() for m in MEASURES}
    work = simpson(np.r_[0.0, fin["force"]], x=np.r_[0.0, d])
    return {"indentor": code, "depths_mm": d.tolist(), "linear": {m: lin[m][:n].tolist() for m in MEASURES},
            "finite": {m: fin[m].tolist() for m in MEASURES}, "ratio": ratio,
            "five_percent_mm": {m: five_percent_depth(d, ratio[m]) for m in MEASURES},
            "work_over_energy": float(work / fin["energy"][-1]), "linear_s": t1 - t0, "finite_s": t2 - t1,
            "requested_depths": len(depths), "dofs": int(fsr.model.ndof)}


def table(label: str, ndof: int, records: list) -> list[str]:
    out = [f"## {label} ({ndof:,} DOFs)", "",
           "| indentor | depth mm | " + " | ".join(f"{m} finite / linear" for m in MEASURES) + " |",
           "|---|---|" + "---|" * len(MEASURES)]
    for r in records:
        for i, d in enumerate(r["depths_mm"]):
            out.append(f"| {r['indentor']} | {d:.2f} | " + " | ".join(f"{r['ratio'][m][i]:.3f}" for m in MEASURES) + " |")
    out += ["", "| indentor | " + " | ".join(f"{m}: 5 % from mm" for m in MEASURES)
            + " | work / stored energy - 1 | linear s | finite s |", "|---|" + "---|" * (len(MEASURES) + 3)]
    for r in records:
        cells = [("< %.2f" % r["depths_mm"][0] if v == r["depths_mm"][0] and abs(r["ratio"][m][0] - 1) >= BAND
                  else "%.2f" % v) if v is not None else f"> {r['depths_mm'][-1]:.2f}"
                 for m, v in r["five_percent_mm"].items()]
        stopped = "" if len(r["depths_mm"]) == r["requested_depths"] else f" (stopped after {r['depths_mm'][-1]:.2f} mm)"
        out.append(f"| {r['indentor']}{stopped} | " + " | ".join(cells)
                   + f" | {r['work_over_energy'] - 1:+.1e} | {r['linear_s']:.1f} | {r['finite_s']:.1f} |")
    return out + [""]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--3d", dest="three", action="store_true", help="also the 1 mm monkey preset (minutes)")
    ap.add_argument("--human", action="store_true", help="also the 1 mm human preset (longer)")
    ap.add_argument("--only", nargs="*", default=list(INDENTORS), help="indentor codes to run")
    ap.add_argument("--models", nargs="*", help="model keys (default: the 2D ones, and 3D as asked)")
    ap.add_argument("--work", type=Path, default=ROOT / "out" / "finite_bench")
    ap.add_argument("--no-write", action="store_true", help="print only (no results files)")
    args = ap.parse_args()
    logging.getLogger("fem").setLevel(logging.ERROR)      # the linear runs' validity warnings
    keys = args.models or (["section", "cylinder8"] + (["monkey"] if args.three else [])
                           + (["human"] if args.human else []))
    for key in keys:
        label, spec, depths = MODELS[key]
        folder = args.work / key
        build_folder(folder, spec)
        dim = 2 if spec.two_d else 3
        for code in args.only:
            rec = compare(folder, dim, code, depths)
            print(f"{key} {code}: 5 % from " + ", ".join(f"{m} {v}" for m, v in rec["five_percent_mm"].items())
                  + f"; finite {rec['finite_s']:.1f} s", flush=True)
            if args.no_write:
                print("\n".join(table(label, rec["dofs"], [rec])))
            else:
                save(key, label, rec)                 # after each indentor: a long run keeps what it finished


def save(key: str, label: str, rec: dict) -> None:
    """Merge one record into finite_contact.json (replacing that model's record of the indentor) and
    write the tables of finite_contact.md from all of it."""
    json_path = RESULTS.with_suffix(".json")
    kept = json.loads(json_path.read_text()) if json_path.exists() else {}
    old = {r["indentor"]: r for r in kept.get(key, {}).get("records", [])}
    old[rec["indentor"]] = rec
    kept[key] = {"label": label, "records": list(old.values())}
    kept = {k: kept[k] for k in MODELS if k in kept}
    json_path.write_text(json.dumps(kept, indent=1))
    lines = [line for r in kept.values() for line in table(r["label"], r["records"][0]["dofs"], r["records"])]
    RESULTS.write_text("# Linear against finite kinematics\n\n`python benchmarks/finite_contact.py [--models ...]` "
                       "(each model's indentors from their last run, kept in finite_contact.json)\n\nRatios finite / "
                       "linear per depth; contact: area (2D: width); SED: the peak at 0.75 mm over a 0.5 mm grid.\n\n"
                       + "\n".join(lines))


if __name__ == "__main__":
    main()
