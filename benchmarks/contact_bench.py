#!/usr/bin/env python
"""Contact benchmark: time per indentation and in total (setup included), next to the error against
a full re-solve, for the issue-5 cases; plus the 3D Hertz verification on a large block.

    python benchmarks/contact_bench.py grating                  # (a) 2D cylinder with bone, 150 positions
    python benchmarks/contact_bench.py steps --model out/monkey # (b) 40 constant-force step positions, 3D
    python benchmarks/contact_bench.py c5 --model out/human     # (c) C5 to 3 mm in 0.5 mm steps, 3D
    python benchmarks/contact_bench.py dorsal --model out/human # thesis trend: dorsal half < 10 %
    python benchmarks/contact_bench.py hertz                    # rigid sphere on a 40 mm quarter block

Setup = reading the mesh, assembling and factorising, building the receptor operators (meshing is
its own cached stage and is not counted). "Full re-solve" = the same indentation solved cold (a new
contact model: no cached compliance, no warm start) followed by one full FE solve with the contact
forces, whose displacement field is sampled at the receptors. Reported: max relative difference in
total force and in receptor strain energy density. Appends a section to
benchmarks/results/contact_bench.md.
"""
from __future__ import annotations

import argparse
import math
import os
import platform
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from fem.contact.indentors import make_indentor  # noqa: E402
from fem.contact.linear import MAX_DEPTH_MM, ContactModel, reach  # noqa: E402
from fem.core.model import Model  # noqa: E402
from fem.geometry.build import MeshSpec, build_folder  # noqa: E402
from fem.io.modelfolder import CONTACT_REGION, factorise, read_model, receptor_surface  # noqa: E402
from fem.receptors.grid import ReceptorSampler, receptor_grid  # noqa: E402
from fem.verify.closed_forms import box, fine_then_growing, hertz_sphere  # noqa: E402

RESULTS = Path(__file__).resolve().parent / "results" / "contact_bench.md"


def _setup(model_dir, middle_line=False, plan=None):
    """Model, factorisation, receptors (3 depths; along the section through the middle of the pad
    when middle_line) and the contact model; returns them with the setup time in s. plan:
    optional (indentor, offsets (k, 3) mm, deepest depth mm): as in `pipeline.py indent`, only the
    candidates the indentor (moved by `_middle`) can reach are condensed (fem.contact.linear.reach)."""
    t = time.perf_counter()
    model, info = read_model(model_dir)
    region = CONTACT_REGION[model.dim]
    sn = model.surface_nodes(region)
    touched = None
    if plan is not None:
        indentor, offsets, deepest = plan
        touched = sn.nodes[reach(sn.x, _middle(indentor, sn.x), offsets, deepest)]
    system = factorise(model, info, touched)
    line = (2, 0.5 * (sn.x[:, 2].min() + sn.x[:, 2].max())) if middle_line and model.dim == 3 else None
    grid = receptor_grid(*receptor_surface(model, sn), (0.5, 0.75, 1.0), 1.0 if model.dim == 3 else 0.5, line)
    sampler = ReceptorSampler(model, grid)
    cm = ContactModel.from_fe(model, system, region, observe=sampler.operator)
    return model, system, region, sampler, cm, time.perf_counter() - t


def _middle(indentor, points_mm):
    """3D: the indentor moved along z to the middle of the candidates (m, 3); 2D: as is."""
    if points_mm.shape[1] != 3:
        return indentor
    return indentor.shifted([0.0, 0.0, 0.5 * (points_mm[:, 2].min() + points_mm[:, 2].max())])


def _check(model, system, region, sampler, indentor, result, load):
    """Relative differences (force, receptor SED) of `result` against a cold solve + full field."""
    cold = ContactModel.from_fe(model, system, region).indent(indentor, **load)
    u = system.solve(ContactModel.from_fe(model, system, region).compliance(indentor.approach).B @ cold.force_N)
    sed_full = sampler.measures(sampler.operator @ u, ["sed_MPa"])["sed_MPa"]
    sed = sampler.measures(result.observed, ["sed_MPa"])["sed_MPa"]
    return (abs(result.total_force_N - cold.total_force_N) / cold.total_force_N,
            np.abs(sed - sed_full).max() / np.abs(sed_full).max())


def _run(name, model_dir, indentor, offsets, loads, target_s, checks=5, middle_line=False):
    """Every load at every offset (k, 3) mm from the middle of the pad; one table row."""
    deepest = max(ld.get("depth_mm", ld.get("max_depth_mm", MAX_DEPTH_MM)) for ld in loads)
    model, system, region, sampler, cm, setup_s = _setup(model_dir, middle_line, (indentor, offsets, deepest))
    indentor = _middle(indentor, cm.points_mm)
    cases = [(off, load) for off in offsets for load in loads]
    t = time.perf_counter()
    results = [cm.sweep(indentor, off[None], **load)[0] for off, load in cases]
    assert all(r.observed is not None for r in results)     # receptor responses, computed in blocks
    run_s = time.perf_counter() - t
    picks = np.unique(np.linspace(0, len(cases) - 1, checks).astype(int))
    errs = np.array([_check(model, system, region, sampler, indentor.shifted(cases[i][0]), results[i], cases[i][1])
                     for i in picks])
    total = setup_s + run_s
    pen = max(r.kkt["penetration_mm"] for r in results)
    row = (f"| {name} | {model.ndof} | {len(cases)} | {setup_s:.2f} | {1e3 * run_s / len(cases):.1f} | "
           f"{total:.2f} | {target_s:g} | {'yes' if total < target_s else 'NO'} | {errs[:, 0].max():.1e} | "
           f"{errs[:, 1].max():.1e} | {pen:.1e} |")
    print(row, flush=True)
    return row


def case_grating(args):
    folder = Path(args.model) if args.model else Path(tempfile.mkdtemp()) / "cyl8"
    if not (folder / "mesh.vtu").exists():
        build_folder(folder, MeshSpec(preset="cylinder8", bone=True))
    offsets = np.zeros((150, 3))
    offsets[:, 0] = -28.6 + 0.2 * np.arange(150)
    ind = make_indentor("grating:0.5:0.5,0.75,1,1.5,2,3,5,5,5", orientation="parallel")
    return _run("(a) grating 0.5 mm bars, 1 mm deep, 150 positions, 2D cylinder 8 mm + bone", folder, ind,
                offsets, [{"depth_mm": 1.0}], 5.0)


def case_steps(args):
    offsets = np.zeros((40, 3))
    offsets[:, 0] = np.linspace(-4.0, 5.75, 40)
    ind = make_indentor("step:3", orientation="parallel")
    return _run("(b) step 3 at 0.02 N, 40 positions, 3D monkey", args.model or "out/monkey", ind, offsets,
                [{"force_N": 0.02}], 60.0, checks=2, middle_line=True)


def case_c5(args):
    ind = make_indentor("C5", orientation="perpendicular")
    return _run("(c) C5 perpendicular to 3 mm in 0.5 mm steps, 3D human", args.model or "out/human", ind,
                np.zeros((1, 3)), [{"depth_mm": d} for d in (0.5, 1.0, 1.5, 2.0, 2.5, 3.0)], 30.0, checks=2,
                middle_line=True)


def case_dorsal(args):
    """Thesis 6.2.1 trend: under a 2 mm line load (wedge perpendicular to the axis, middle of the
    pad) the dorsal half moves vertically less than 10 % of the largest vertical displacement; the
    proximal cut's core is held (fem.io.modelfolder.HELD). Dorsal half: the nodes of the outer surface
    below the section centroid, the reference of the model's volar half and nail span, on the
    surface the thesis draws its contours (figures 6-5, 6-7); the centroid's y(z) is a
    volume-weighted quadratic fit of the tets' y against z (within 0.01 mm of the presets' section
    centroids). y < 0 would depend on where the replica's turntable axis sat in the section.
    Also reported: the ratio over every node with y < 0 (the definition used before), where the
    largest dorsal displacement sits, and the largest on the distal and proximal end cuts."""
    model, system, region, sampler, cm, setup_s = _setup(args.model or "out/human")
    z = cm.points_mm[:, 2]
    ind = make_indentor("wedge", orientation="perpendicular", position_mm=(0.0, 0.5 * (z.min() + z.max())))
    t = time.perf_counter()
    res = cm.indent(ind, depth_mm=2.0)
    uy = np.abs(cm.compliance(ind.approach).displacement(res.force_N).reshape(-1, 3)[:, 1])
    x, mesh = model.nodes, model.mesh
    tet = mesh.p.T[mesh.t.T]                                            # (T, 4, 3) vertices
    vol = np.abs(np.einsum("ij,ij->i", tet[:, 1] - tet[:, 0], np.cross(tet[:, 2] - tet[:, 0], tet[:, 3] - tet[:, 0])))
    c, w = tet.mean(axis=1), np.sqrt(vol)                               # centroid y(z): volume-weighted
    centroid_y = np.linalg.lstsq(np.vander(c[:, 2], 3) * w[:, None], c[:, 1] * w, rcond=None)[0]   # quadratic fit
    bf = mesh.boundary_facets()
    surface = np.union1d(np.unique(mesh.facets[:, bf]), mesh.nvertices + np.unique(mesh.f2e[:, bf]))
    dorsal = surface[x[surface, 1] < np.polyval(centroid_y, x[surface, 2])]
    at = dorsal[np.argmax(uy[dorsal])]
    ratio = uy[at] / uy.max()
    ratio_y0 = uy[x[:, 1] < 0].max() / uy.max()
    ends = " / ".join(f"{uy[model.region_nodes(e)].max() / uy.max():.1%}" if e in model.regions else "-"
                      for e in ("distal", "proximal"))
    row = (f"| dorsal half under a 2 mm line load, 3D {Path(args.model or 'out/human').name} | {model.ndof} | "
           f"{res.total_force_N:.4g} N | {ratio:.1%} (all nodes with y < 0: {ratio_y0:.1%}) | "
           f"({', '.join(f'{v:.2f}' for v in x[at])}) | {ends} | {'yes' if ratio < 0.1 else 'NO'} | "
           f"{setup_s + time.perf_counter() - t:.1f} s |")
    print(row, flush=True)
    return row


def case_hertz(args):
    """Rigid sphere R = 5 mm on a quarter block of graded P2 tets at least 40 mm wide and deep (the
    grids' first nodes beyond 40 mm: 47.9 x 58.9 x 47.9 mm), E = 1 MPa."""
    rows = []
    for nu in (0.3, 0.49):
        t = time.perf_counter()
        xs = fine_then_growing(0.1, 1.3, 1.6, 40.0)
        p, cells, r = box(xs, -fine_then_growing(0.1, 0.8, 1.5, 40.0)[::-1], xs)
        regions = {"top": r["ymax"], "bottom": r["ymin"], "symx": r["xmin"], "symz": r["zmin"]}
        model = Model(p, cells, np.ones(len(cells), int), regions, material=[1.0], nu=nu)
        system = model.system({"bottom": 0.0, "symx": (0.0, None, None), "symz": (None, None, 0.0)})
        cm = ContactModel.from_fe(model, system, "top")
        setup_s = time.perf_counter() - t
        for d in (0.05, 0.1, 0.2, 0.3):
            t = time.perf_counter()
            r = cm.indent(make_indentor("sphere:5"), depth_mm=d)
            F, a, p0 = hertz_sphere(5.0, d, 1.0, nu)
            row = (f"| {nu} | {model.ndof} | {d} | {4 * r.total_force_N / F - 1:+.2%} | "
                   f"{math.sqrt(4 * r.contact_area_mm2 / math.pi) / a - 1:+.2%} | {r.max_pressure_MPa / p0 - 1:+.2%} | "
                   f"{r.kkt['penetration_mm']:.1e} | {setup_s:.0f} | {time.perf_counter() - t:.1f} |")
            print(row, flush=True)
            rows.append(row)
    return rows


TIMING_HEADER = ("| case | DOFs | indentations | setup s | ms per indentation | total s | target s | "
                 "met | force diff | receptor SED diff | max penetration mm |\n|---|---|---|---|---|---|---|---|---|---|---|")
DORSAL_HEADER = ("| case | DOFs | force | max dorsal / max vertical displacement | at (x, y, z) mm | "
                 "distal / proximal cut | < 10 % | time |\n|---|---|---|---|---|---|---|---|")
HERTZ_HEADER = ("| nu | DOFs | depth mm | force err | contact radius err | peak pressure err | penetration mm | "
                "setup s | solve s |\n|---|---|---|---|---|---|---|---|---|")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("case", choices=["grating", "steps", "c5", "dorsal", "hertz"])
    ap.add_argument("--model", help="model folder (mesh.vtu, model.json)")
    args = ap.parse_args()
    header = {"hertz": HERTZ_HEADER, "dorsal": DORSAL_HEADER}.get(args.case, TIMING_HEADER)
    print(header)
    rows = {"grating": case_grating, "steps": case_steps, "c5": case_c5, "dorsal": case_dorsal,
            "hertz": case_hertz}[args.case](args)
    rows = rows if isinstance(rows, list) else [rows]
    RESULTS.parent.mkdir(parents=True, exist_ok=True)
    stamp = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    with open(RESULTS, "a") as fh:
        fh.write(f"\n## {args.case} ({stamp}; {platform.processor() or platform.machine()}, "
                 f"{os.cpu_count()} cores, OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS', 'unset')})\n\n"
                 f"{header}\n" + "\n".join(rows) + "\n")


if __name__ == "__main__":
    main()
