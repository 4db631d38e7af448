#!/usr/bin/env python
"""Solver benchmark: cost and accuracy on the Lame thick sphere, stability against nu and stiffness.

    python benchmarks/solver_bench.py            # full run (largest mesh ~200k DOFs)
    python benchmarks/solver_bench.py --quick    # small meshes only

Problem: octant of a thick sphere (a = 1, b = 2 mm), internal pressure 0.01 MPa, E = 0.01 MPa,
symmetry planes on rollers; both faceted surfaces carry the exact Lame traction, so the errors are
the solver's (fem.verify.closed_forms.radial_traction). Errors: max over P2 nodes of |u_r - exact| / max
|u_r|, and max over elements of |mean stress - exact| / max |exact| (per layer when layered).
Prints the tables and writes benchmarks/results/solver_bench.md.
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

from fem import Model
from fem.verify import closed_forms as ref  # noqa: E402

A, B, C, P, E = 1.0, 2.0, 1.5, 0.01, 0.01
SYMMETRY = {"sym_x": (0, None, None), "sym_y": (None, 0, None), "sym_z": (None, None, 0)}


def timed(make_model, prescribed):
    """Build and assemble a model, then factorise: wall-clock and CPU seconds (all threads).
    prescribed: a dict, or a callable model -> dict."""
    w0, c0 = time.perf_counter(), time.process_time()
    model = make_model()
    model.K_dev, model.discretisation.B, model.pressure_compliance    # noqa: B018  (assemble)
    w1, c1 = time.perf_counter(), time.process_time()
    prescribed = prescribed(model) if callable(prescribed) else prescribed
    model.system(prescribed)
    w2, c2 = time.perf_counter(), time.process_time()
    return model, {"assemble_s": w1 - w0, "assemble_cpu_s": c1 - c0, "factor_s": w2 - w1,
                   "factor_cpu_s": c2 - c1, "backend": model.system(prescribed).backend}


def resolve(model, system):
    """Re-solve cost with the stored factors: 1 and 64 right-hand sides (random nodal forces; the
    contact solver sends blocks of 64), wall and CPU [s], and refinement steps taken."""
    F = np.random.default_rng(0).standard_normal((model.ndof, 64)) * 1e-3
    out = {}
    for k in (1, 64):
        w0, c0 = time.perf_counter(), time.process_time()
        system.solve(F[:, 0] if k == 1 else F)
        out[f"solve{k}_s"], out[f"solve{k}_cpu_s"] = time.perf_counter() - w0, time.process_time() - c0
    out["refine"] = system._factor.refinements
    out["refine_tol"] = system._factor.refine_tol
    out["nnz_L"] = system._factor.nnz_factor / 1e6
    return out


def fingertip(path):
    """Model.from_mesh on a mesh.vtu with nail/support/volar regions (held as fem.io.modelfolder.open_model
    holds them): 0.1 N spread over `volar`. Then the factorisation again with the volar nodes'
    vertical displacement condensed (what open_model does for contact), and the compliance inverse."""
    def held(model):
        return {k: v for k, v in {"nail": 0.0, "support": (None, 0.0, None), "proximal": 0.0}.items()
                if k in model.regions}
    model, cost = timed(lambda: Model.from_mesh(path, material="m43338", nu=0.48), held)
    prescribed = held(model)
    f = model.load_vector(forces={"volar": (0.0, -0.1, 0.0)})
    system = model.system(prescribed)
    w0, c0 = time.perf_counter(), time.process_time()
    system.displacement(f)
    row = {"dofs": model.ndof, "elements": model.mesh.nelements, **cost, "solve_s": time.perf_counter() - w0,
           "solve_cpu_s": time.process_time() - c0, "residual": system.residual}
    row.update(resolve(model, system))
    model._factors = {}
    nodes = model.surface_nodes("volar").nodes
    w0, c0 = time.perf_counter(), time.process_time()
    cond = model.system(prescribed, condense=(nodes, (0.0, -1.0, 0.0)))
    w1, c1 = time.perf_counter(), time.process_time()
    cond._factor.compliance_block()
    w2, c2 = time.perf_counter(), time.process_time()
    return {**row, "condensed": len(cond.condensed[0]), "cond_factor_s": w1 - w0, "cond_factor_cpu_s": c1 - c0,
            "cond_nnz_L": cond._factor.nnz_factor / 1e6, "inverse_s": w2 - w1, "inverse_cpu_s": c2 - c1}


def run(n_arc, n_rad, nu=0.48, contrast=None):
    """One solve; returns a dict of sizes, times [s] and errors."""
    pts, cells, regions = ref.sphere_octant_shell(A, B, n_arc, n_rad)
    if contrast is None:
        layer, moduli, radii = np.ones(len(cells), dtype=int), [E], [A, B]
    else:
        layer = np.where(np.linalg.norm(pts[cells].mean(axis=1), axis=1) < C, 1, 2)
        moduli, radii = [E, E * contrast], [A, C, B]
    def field(r):
        return ref.lame_sphere_layered(r, radii, moduli, nu, P)
    traction = ref.radial_traction(field)
    model, cost = timed(lambda: Model(pts, cells, layer, regions, material=moduli, nu=nu), SYMMETRY)
    f = model.load_vector(tractions={"inner": traction, "outer": traction})
    system = model.system(SYMMETRY)
    t0 = time.perf_counter()
    u = system.displacement(f)
    cost["solve_s"] = time.perf_counter() - t0
    residual = system.residual
    cost.update(resolve(model, system))
    x = model.nodes
    r = np.linalg.norm(x, axis=1)
    ur = np.einsum("ij,ij->i", u.reshape(-1, 3), x / r[:, None])
    exact = field(r)
    centroid = np.linalg.norm(model.mesh.p[:, model.mesh.t].mean(axis=1).T, axis=1)
    mean_exact = field(centroid)["mean"]
    mean = model.solution(u).element_fields["mean_stress_MPa"]
    mean_err = max(np.abs(mean - mean_exact)[layer == k].max() / np.abs(mean_exact[layer == k]).max()
                   for k in np.unique(layer))
    return {"dofs": model.ndof, "elements": model.mesh.nelements, **cost,
            "u_err": np.abs(ur - exact["u_r"]).max() / np.abs(exact["u_r"]).max(),
            "mean_err": mean_err, "residual": residual}


def table(rows, cols):
    head = "| " + " | ".join(c for c, _ in cols) + " |"
    sep = "|" + "|".join("---" for _ in cols) + "|"
    body = ["| " + " | ".join(fmt.format(**r) for _, fmt in cols) + " |" for r in rows]
    return "\n".join([head, sep, *body])


def _size_study(quick: bool) -> tuple[list[dict], str]:
    """Cost and error against mesh size (nu = 0.48): the rows and their markdown table."""
    sizes = [(6, 4), (10, 6), (14, 10), (20, 14)] + ([] if quick else [(26, 22)])
    rows = []
    for n_arc, n_rad in sizes:
        rows.append(run(n_arc, n_rad))
        print(f"size   {rows[-1]}", flush=True)
    return rows, table(rows, [("DOFs", "{dofs}"), ("elements", "{elements}"),
                              ("assembly [s]", "{assemble_s:.2f}"), ("CPU", "{assemble_cpu_s:.2f}"),
                              ("factorisation [s]", "{factor_s:.2f}"), ("CPU", "{factor_cpu_s:.2f}"),
                              ("nnz(L) [1e6]", "{nnz_L:.1f}"), ("re-solve 1 RHS [s]", "{solve1_s:.3f}"),
                              ("CPU", "{solve1_cpu_s:.3f}"),
                              ("64 RHS [s]", "{solve64_s:.2f}"), ("CPU", "{solve64_cpu_s:.2f}"),
                              ("u error", "{u_err:.2%}"),
                              ("mean-stress error", "{mean_err:.2%}"), ("residual", "{residual:.1e}")])


def _nu_study() -> str:
    """Stability against nu (9k DOFs): markdown table."""
    nu_rows = []
    for nu in (0.3, 0.45, 0.48, 0.49, 0.499, 0.4999):
        nu_rows.append({"nu": nu, **run(10, 6, nu=nu)})
        print(f"nu     {nu_rows[-1]}", flush=True)
    return table(nu_rows, [("nu", "{nu}"), ("u error", "{u_err:.2%}"),
                           ("mean-stress error", "{mean_err:.2%}"), ("residual", "{residual:.1e}")])


def _contrast_study() -> str:
    """Stability against the stiffness contrast of two layers: markdown table."""
    contrast_rows = []
    for contrast in (1.0, 1e2, 1e4, 1e6):
        for nu in (0.48, 0.4999):
            contrast_rows.append({"contrast": contrast, "nu": nu, **run(16, 6, nu=nu, contrast=contrast)})
            print(f"stiff  {contrast_rows[-1]}", flush=True)
    return table(contrast_rows, [("E outer / E inner", "{contrast:.0e}"), ("nu", "{nu}"),
                                 ("u error", "{u_err:.2%}"),
                                 ("mean-stress error (worst layer)", "{mean_err:.2%}"),
                                 ("residual", "{residual:.1e}")])


def _mesh_section(mesh) -> str:
    """The fingertip mesh.vtu's section of the report (fingertip): markdown."""
    row = fingertip(mesh)
    print(f"mesh   {row}", flush=True)
    return f"""
## Fingertip mesh `{mesh}` (m43338, nu = 0.48, nail fixed, support, 0.1 N on volar)

""" + table([row], [("DOFs", "{dofs}"), ("elements", "{elements}"), ("assembly [s]", "{assemble_s:.1f}"),
                    ("CPU", "{assemble_cpu_s:.1f}"), ("factorisation [s]", "{factor_s:.1f}"),
                    ("CPU", "{factor_cpu_s:.1f}"), ("first solve [s]", "{solve_s:.2f}"), ("CPU", "{solve_cpu_s:.2f}"),
                    ("re-solve 1 RHS [s]", "{solve1_s:.2f}"), ("CPU", "{solve1_cpu_s:.2f}"),
                    ("64 RHS [s]", "{solve64_s:.2f}"), ("CPU", "{solve64_cpu_s:.2f}"),
                    ("nnz(L) [1e6]", "{nnz_L:.1f}"), ("refinement steps (64 RHS)", "{refine}"),
                    ("refinement tolerance", "{refine_tol:.0e}"), ("residual", "{residual:.1e}")]) + """

With the volar nodes' vertical displacement condensed (`Model.system(condense=)`, as
`fem.io.modelfolder.open_model` factorises for contact): factorisation with the Schur complement, and
the inverse of the Schur complement (the whole contact compliance).

""" + table([row], [("condensed nodes", "{condensed}"), ("factorisation [s]", "{cond_factor_s:.1f}"),
                    ("CPU", "{cond_factor_cpu_s:.1f}"), ("nnz(L) [1e6]", "{cond_nnz_L:.1f}"),
                    ("inverse [s]", "{inverse_s:.1f}"), ("CPU", "{inverse_cpu_s:.1f}")]) + "\n"


def _report(quick: bool, load_start: float, backend: str, size_table: str, nu_table: str, contrast_table: str,
            mesh_section: str) -> str:
    """solver_bench.md; the load average at its end is read now."""
    return f"""# Solver benchmark

`python benchmarks/solver_bench.py{' --quick' if quick else ''}` on {platform.machine()}, {os.cpu_count()} cores
shared with other jobs (load average {load_start:.1f} at the start, {os.getloadavg()[0]:.1f} at the end:
times are wall-clock under that load), backend `{backend}`. Lame thick sphere octant (a = 1, b = 2 mm,
p = 0.01 MPa, E = 0.01 MPa) with exact surface tractions; P2 + per-layer P1 pressure.

## Cost and error against mesh size (nu = 0.48)

Assembly = model set-up, K_dev, divergence and pressure operators; factorisation = LDL^T of the
constrained saddle-form matrix; re-solve = `system.solve` of 1 and of 64 new right-hand sides
(random nodal forces) with the stored factors, including the residual check. Wall-clock [s] and CPU [s] """ \
        f"""summed over threads: under contention the CPU time is
the load-independent cost.

{size_table}

## Stability against nu (9k DOFs)

{nu_table}

## Stability against stiffness contrast (two layers, interface r = 1.5 mm, ~20k DOFs)

{contrast_table}
{mesh_section}"""


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="small meshes only")
    ap.add_argument("--mesh", help="also time a fingertip mesh.vtu (regions nail, support, volar)")
    ap.add_argument("--out", default=str(Path(__file__).parent / "results" / "solver_bench.md"))
    args = ap.parse_args(argv)

    load_start = os.getloadavg()[0]
    rows, size_table = _size_study(args.quick)
    nu_table = _nu_study()
    contrast_table = _contrast_study()
    mesh_section = _mesh_section(args.mesh) if args.mesh else ""
    md = _report(args.quick, load_start, rows[0]["backend"], size_table, nu_table, contrast_table, mesh_section)
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_name(out.name + ".tmp")
    tmp.write_text(md)
    os.replace(tmp, out)
    print(md)


if __name__ == "__main__":
    main()
