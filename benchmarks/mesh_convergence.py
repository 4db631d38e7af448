#!/usr/bin/env python
"""Run time against error for the fingertip itself: what users read, against `--size`.

    python benchmarks/mesh_convergence.py                         # 2D section, 3D monkey and human
    python benchmarks/mesh_convergence.py --models 2d monkey --sizes-3d 1.0 0.7
    python benchmarks/mesh_convergence.py --models --sensitivity   # nu and bone modulus only

Models: the monkey section at z = 5 mm (2D, `--section-z 5`) under C5 at 0.5 mm; the 3D monkey
and human presets under C5 perpendicular to the finger at 1 mm, at the middle of the pad. Measures:
force, contact area (2D: width), peak pressure (the nodal peak `max_pressure_MPa`, and the peak of
the pressure averaged over PEAK_PRESSURE_RADIUS_MM, `peak_pressure_MPa`, both as the step tables
have them; in 2D also averaged over FINE_AVERAGE_MM, meaningful where the size is at most half of
it), and at the receptor depth 0.75 mm the peak strain energy density
and the peak maximum compressive strain over the sites of a 1 mm grid. Per size:
meshing time (`build_folder`, the mesh cache bypassed), run time (`run_scene`: reading,
factorising, indenting), the peak resident memory of the process that ran it (each size runs in a
fresh process), DOFs, the achieved fine-zone edge, the change of each measure from the previous
(coarser) size and the observed order of convergence from three successive sizes.

--sensitivity: the same measures at one size per model (2D 0.125 mm, 3D 1.0 mm) for Poisson's
ratio 0.45, 0.48, 0.49, 0.499 and the bone modulus 10, 100 (the default) and 1000 MPa, relative
to the default material (m43338, nu 0.49 unless the model says otherwise).

Sizes run one after another, coarse to fine; run nothing else heavy meanwhile. Prints the tables
and writes benchmarks/results/mesh_convergence.md, replacing the sections of the models run and
keeping the others.
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

from fem.contact.facets import PEAK_PRESSURE_RADIUS_MM  # noqa: E402

MODELS = {"2d": "2D monkey section at z = 5 mm, C5 at 0.5 mm",
          "monkey": "3D monkey preset, C5 perpendicular at 1 mm",
          "human": "3D human preset, C5 perpendicular at 1 mm"}
FINE_AVERAGE_MM = 0.1
"""Radius over which the 2D peak pressure is also averaged (`averaged_peak_pressure`): the finest
pressure feature the finest 2D sizes resolve."""
AVERAGED = f"peak pressure over {PEAK_PRESSURE_RADIUS_MM:g} mm MPa"
MEASURES = {"2d": ("force N/mm", "contact width mm", "peak pressure MPa", AVERAGED,
                   f"peak pressure over {FINE_AVERAGE_MM:g} mm MPa", "SED kPa", "compressive strain"),
            "3d": ("force N", "contact area mm2", "peak pressure MPa", AVERAGED, "SED kPa", "compressive strain")}
RECEPTOR_DEPTH_MM = 0.75
NU = (0.45, 0.48, 0.49, 0.499)
BONE_DIGITS = {"10 MPa": "7", "100 MPa": "8", "1000 MPa": "9"}
SENSITIVITY_SIZE_MM = {"2d": 0.125, "monkey": 1.0, "human": 1.0}


def kind(model: str) -> str:
    return "2d" if model == "2d" else "3d"


def scene(model: str, material: str | None = None, nu: float | None = None):
    """C5 across the finger (3D) or the section's C5 (2D), receptors at 0.75 mm, no files."""
    from fem.experiments.scene import Scene

    d = {"receptors": {"depths_mm": [RECEPTOR_DEPTH_MM], "spacing_mm": 1.0,
                       "measures": ["sed_MPa", "max_compressive_strain"]},
         "output": {"pvd": False, "plots": False},
         "experiment": [{"name": "C5", "indentor": "C5", "depth_mm": 0.5 if model == "2d" else 1.0,
                         "orientation": "parallel" if model == "2d" else "perpendicular"}]}
    d |= {k: v for k, v in (("material", material), ("nu", nu)) if v is not None}
    return Scene.from_dict(d)


def one(model: str, size_mm: float, work: Path, variants: list) -> list[dict]:
    """Mesh one size (no cache) and indent it once per (label, material, nu) variant -> rows.
    Runs in a child process (`--one`), so its peak memory is its own."""
    import logging

    from fem.contact.facets import averaged_peak_pressure
    from fem.experiments.runner import run_scene
    from fem.geometry.build import MeshSpec, build_folder
    from fem.io.modelfolder import CONTACT_REGION

    logging.getLogger("fem").setLevel(logging.ERROR)         # the validity warning of every 1 mm run
    folder = work / f"{model}_{size_mm:g}"
    sizes = {"size_mm": size_mm}
    spec = (MeshSpec(preset="monkey", section_z_mm=5.0, sizes=sizes) if model == "2d"
            else MeshSpec(preset=model, sizes=sizes))
    t0 = time.perf_counter()
    build_folder(folder, spec, force=True)
    mesh_s = time.perf_counter() - t0
    mesh = json.loads((folder / "model.json").read_text())["mesh"]
    fine_edge_mm = mesh["sizing_achieved"]["fine_zone_median_edge_mm"]
    rows = []
    for label, material, nu in variants:
        t0 = time.perf_counter()
        sr = run_scene(folder, scene(model, material, nu))
        run_s = time.perf_counter() - t0
        res = sr.experiments[0].steps[-1][1]
        x = sr.model.surface_nodes(CONTACT_REGION[sr.model.dim]).x
        m = sr.sampler.measures(res.observed, ["sed_MPa", "max_compressive_strain"])
        names = MEASURES[kind(model)]
        row = {"variant": label, "size mm": size_mm, "mesh s": mesh_s, "run s": run_s,
               "peak MB": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
               "DOFs": sr.model.ndof, "fine median edge mm": fine_edge_mm,
               names[0]: res.total_force_N, names[1]: res.contact_area_mm2, names[2]: res.max_pressure_MPa,
               names[3]: averaged_peak_pressure(res.force_N, x, PEAK_PRESSURE_RADIUS_MM),
               names[-2]: 1e3 * float(m["sed_MPa"].max()), names[-1]: float(m["max_compressive_strain"].max())}
        if model == "2d":
            row[names[4]] = averaged_peak_pressure(res.force_N, x, FINE_AVERAGE_MM)
        rows.append(row)
    return rows


def in_child(model: str, size_mm: float, work: Path, variants: list) -> list[dict]:
    """`one` in a fresh Python process -> its rows."""
    args = [sys.executable, __file__, "--one", json.dumps([model, size_mm, str(work), variants])]
    done = subprocess.run(args, capture_output=True, text=True, check=False)
    if done.returncode:
        raise SystemExit(f"{model} at {size_mm} mm failed:\n{done.stderr}")
    return json.loads(done.stdout.splitlines()[-1])


def observed_order(h: list, q: list) -> float | None:
    """Order p of q(h) = q* + C h^p from three sizes h (decreasing) and values q: the root of
    (h0^p - h1^p) / (h1^p - h2^p) = (q0 - q1) / (q1 - q2), None where the changes do not shrink
    monotonically (no asymptotic range yet)."""
    r = (q[0] - q[1]) / (q[1] - q[2]) if q[1] != q[2] else np.inf
    if not 1.0 < r < 1e6:
        return None
    f = lambda p: (h[0] ** p - h[1] ** p) / (h[1] ** p - h[2] ** p) - r  # noqa: E731
    lo, hi = 1e-3, 8.0
    if f(lo) * f(hi) > 0:
        return None
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if f(lo) * f(mid) > 0 else (lo, mid)
    return 0.5 * (lo + hi)


def fmt(v) -> str:
    if v is None:
        return ""
    return f"{v:.4g}" if isinstance(v, float) else str(v)


def convergence_table(model: str, rows: list) -> list[str]:
    """Markdown table: each measure with its change from the previous size, and the observed order."""
    head = ["size mm", "mesh s", "run s", "peak MB", "DOFs", "fine median edge mm"]
    names = MEASURES[kind(model)]
    cols = head + [c for m in names for c in (m, "change %")]
    out = ["| " + " | ".join(cols) + " |", "|" + "---|" * len(cols)]
    for i, r in enumerate(rows):
        cells = [fmt(r[c]) for c in head]
        for m in names:
            prev = rows[i - 1][m] if i else None
            cells += [fmt(r[m]), "" if not prev else f"{100 * (r[m] / prev - 1):+.2f}"]
        out.append("| " + " | ".join(cells) + " |")
    h = [r["fine median edge mm"] for r in rows]
    orders = []
    for m in names:
        q = [r[m] for r in rows]
        ps = [observed_order(h[i:i + 3], q[i:i + 3]) for i in range(len(rows) - 2)]
        orders.append(f"{m}: " + ", ".join("-" if p is None else f"{p:.1f}" for p in ps))
    out += ["", "Observed order from successive triples of sizes (fine-zone edge as h; - where the changes "
            "do not shrink): " + "; ".join(orders) + "."]
    return out


def sensitivity_table(model: str, rows: list) -> list[str]:
    """Markdown table of each variant's measures relative to the default material."""
    names = MEASURES[kind(model)]
    ref = next(r for r in rows if r["variant"] == "default")
    cols = ["variant"] + [c for m in names for c in (m, "vs default %")]
    out = ["| " + " | ".join(cols) + " |", "|" + "---|" * len(cols)]
    for r in rows:
        out.append("| " + " | ".join([r["variant"]] + [c for m in names for c in
                                                        (fmt(r[m]), f"{100 * (r[m] / ref[m] - 1):+.2f}")]) + " |")
    return out


def variants() -> list:
    """(label, material, nu) of the sensitivity study: the default, each nu, each bone modulus."""
    return ([("default", None, None)] + [(f"nu {nu:g}", None, nu) for nu in NU]
            + [(f"bone {k}", "m4333" + d, None) for k, d in BONE_DIGITS.items() if d != "8"])


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--models", nargs="*", default=list(MODELS), choices=list(MODELS))
    ap.add_argument("--sizes-3d", type=float, nargs="*", default=[1.0, 0.7, 0.5, 0.35])
    ap.add_argument("--sizes-2d", type=float, nargs="*", default=[0.5, 0.25, 0.125, 0.0625, 0.03125])
    ap.add_argument("--sensitivity", action="store_true", help="also nu and the bone modulus")
    ap.add_argument("--out", type=Path, default=HERE / "results" / "mesh_convergence.md")
    ap.add_argument("--one", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.one:
        model, size, work, var = json.loads(args.one)
        print(json.dumps(one(model, size, Path(work), var), default=lambda o: o.item()))
        return
    when = f"{time.strftime('%Y-%m-%d')}, load average {os.getloadavg()[0]:.1f} at the start, {os.cpu_count()} cores"
    sections = {}
    with tempfile.TemporaryDirectory() as tmp:
        for model in args.models:
            rows = []
            for size in sorted(args.sizes_2d if model == "2d" else args.sizes_3d, reverse=True):
                rows += in_child(model, size, Path(tmp), [("default", None, None)])
                print(f"{model} " + "  ".join(f"{k}={fmt(v)}" for k, v in rows[-1].items()), flush=True)
            sections[MODELS[model]] = [when, ""] + convergence_table(model, rows)
        if args.sensitivity:
            for model in MODELS:
                size = SENSITIVITY_SIZE_MM[model]
                rows = in_child(model, size, Path(tmp), variants())
                sections[f"Sensitivity: {MODELS[model]}, size {size:g} mm"] = [when, ""] + sensitivity_table(model, rows)
    text = merged(args.out.read_text() if args.out.exists() else "", sections)
    args.out.parent.mkdir(exist_ok=True)
    args.out.write_text(text)
    print(text)


def merged(old: str, sections: dict) -> str:
    """The results file `old` with the sections {title: lines} replaced (or appended), the others kept."""
    parts = old.split("\n## ")
    kept = {p.split("\n", 1)[0]: p.split("\n", 1)[1].strip("\n") for p in parts[1:]}
    kept |= {title: "\n".join(lines) for title, lines in sections.items()}
    return "\n\n".join(["# Mesh convergence"] + [f"## {t}\n\n{body}" for t, body in kept.items()]) + "\n"


if __name__ == "__main__":
    main()
