#!/usr/bin/env python
"""Large-deformation contact against an independent code: a rigid cylinder pressed into a thick
nearly incompressible neo-Hookean block in plane strain, solved by this project's
`fem.contact.finite.FiniteContact` and by NGSolve (its own mesher, elements and Newton solver;
contact by a penalty on the penetration of the deformed surface into the cylinder), force against
depth to depth / radius 0.3.

The problem: the 2D block preset (40 x 18 mm, bottom and sides held; `mesh --preset block`),
one material, m4 (E = 0.01 MPa, nu 0.48), the 2D neo-Hookean of `fem.core.neohookean`,

    W(F, p) = mu / 2 (I1 / J - 2) + p (J - 1) - p^2 / (2 kappa),   kappa = lambda + mu,

a rigid frictionless cylinder of radius 2 mm (`cylinder:4`) over the block's middle, depths 0.1 to
0.6 mm. NGSolve: the same energy with the pressure eliminated (p = kappa (J - 1)) on P2
displacements (ORDER), mesh size MAXH_TOP_MM along the top edge, load steps of 0.05 mm, a penalty
on max(0, -g)^2 / 2 raised 10 -> PENALTY_MPA_PER_MM within each step, g the gap of the deformed top
edge to the cylinder along the normal of the last state (iterated until the state no longer
changes, so g is the distance to the axis minus the radius; frozen, the penalty stays convex),
Newton's method with a backtracking line search on the energy; its largest penetration, sampled
along the edge, is printed. (P3 with a 0.05 mm top edge stalled at 0.25 mm: no energy descent at
penalty 10.) This project: P2-P1 mixed, node-to-surface contact by Lagrange multipliers, two mesh
sizes (`--sizes`).

    pip install ngsolve
    python benchmarks/ngsolve_contact.py [--sizes 0.25 0.125] [--no-write]

Prints per depth both forces [N/mm], their ratio and the run times, and writes
benchmarks/results/ngsolve_contact.md.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

RESULTS = ROOT / "benchmarks" / "results" / "ngsolve_contact.md"
RADIUS_MM = 2.0
DEPTHS_MM = np.round(np.arange(0.1, 0.61, 0.1), 10)
MATERIAL = "m4"
MAXH_TOP_MM = 0.2
PENALTY_MPA_PER_MM = 1e4
PENALTY_RAMP_MPA_PER_MM = (1e1, 1e2, 1e3, PENALTY_MPA_PER_MM)
STEP_MM = 0.05
ORDER = 2
NEWTON_TOL_N = 1e-12
ROUND_OFF_N = 1e-7


def _block_mesh(maxh_top_mm: float):
    """NGSolve mesh of the 40 x 18 mm block (top edge at y = 0, edges named top, bottom, left, right)."""
    import ngsolve as ng
    from netgen.occ import OCCGeometry, Rectangle, X, Y

    face = Rectangle(40.0, 18.0).Face().Move((-20.0, -18.0, 0.0))
    face.edges.Max(Y).name, face.edges.Min(Y).name = "top", "bottom"
    face.edges.Min(X).name, face.edges.Max(X).name = "left", "right"
    face.edges.Max(Y).maxh = maxh_top_mm
    return ng.Mesh(OCCGeometry(face, dim=2).GenerateMesh(maxh=2.0, grading=0.2))


def solve_newton(a, gf, fes, where: str, inverse: str = "umfpack") -> int:
    """Newton's method on NGSolve's energy `a` (a BilinearForm of Variations) from gf, with a
    backtracking line search on the energy, to NEWTON_TOL_N, or to the round-off floor (a step
    that no longer halves a residual already below ROUND_OFF_N) -> iterations. RuntimeError naming
    `where` after 100 iterations."""
    import ngsolve as ng

    free = np.array(list(fes.FreeDofs()), bool)
    res, du, trial = gf.vec.CreateVector(), gf.vec.CreateVector(), gf.vec.CreateVector()

    def energy(vec) -> float:
        e = a.Energy(vec)
        return e if np.isfinite(e) else np.inf

    last, norms = np.inf, []
    for it in range(100):
        a.AssembleLinearization(gf.vec)
        a.Apply(gf.vec, res)
        norm = np.linalg.norm(res.FV().NumPy()[free])
        norms.append(norm)
        if norm < NEWTON_TOL_N or (norm < ROUND_OFF_N and norm > 0.5 * last):
            return it
        last = norm
        du.data = a.mat.Inverse(fes.FreeDofs(), inverse=inverse) * res
        e0, slope, alpha = energy(gf.vec), ng.InnerProduct(res, du), 1.0
        while alpha > 1e-6:
            trial.data = gf.vec - alpha * du
            if energy(trial) <= e0 - 1e-4 * alpha * slope:
                break
            alpha /= 2
        gf.vec.data = trial
    raise RuntimeError(f"NGSolve Newton did not converge at {where}: residuals {np.array(norms[-6:])}")


def solve_penalised(a, gf, frozen, fes, kpen, where: str, inverse: str = "umfpack") -> None:
    """The penalty `kpen` (an ng.Parameter) raised through PENALTY_RAMP_MPA_PER_MM, each solve
    starting near its answer; at each level the gap's normals (those of the state `frozen`) iterated
    to a fixed point with `solve_newton`. RuntimeError when the normals do not settle."""
    for k in PENALTY_RAMP_MPA_PER_MM:
        kpen.Set(k)
        for _ in range(50):
            frozen.vec.data = gf.vec
            solve_newton(a, gf, fes, f"{where}, penalty {k:g}", inverse=inverse)
            if np.abs(gf.vec.FV().NumPy() - frozen.vec.FV().NumPy()).max() < 1e-10:
                break
        else:
            raise RuntimeError(f"NGSolve: the contact normals did not settle at {where}")


def force_table(unit: str, depths, reference, penetration, ours: dict) -> list[str]:
    """Markdown lines: per depth (n,) NGSolve's force (n,) [unit] and largest penetration (n,) [mm],
    then for each mesh size of `ours` ({size mm: {column: (n,) values}}, the force [unit] first)
    this project's force, its difference from NGSolve's and any further columns."""
    head = ["depth mm", f"NGSolve {unit}", "NGSolve penetration mm"]
    for s, cols in ours.items():
        names = list(cols)
        head += [f"this project {s:g} mm {unit}", f"/ NGSolve - 1 ({s:g} mm)"] + [f"{c} ({s:g} mm)" for c in names[1:]]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for i, d in enumerate(depths):
        cells = [f"{d:.2f}", f"{reference[i]:.6g}", f"{penetration[i]:.1e}"]
        for cols in ours.values():
            f, *rest = cols.values()
            cells += [f"{f[i]:.6g}", f"{100 * (f[i] / reference[i] - 1):+.2f} %"] + [f"{v[i]:.4g}" for v in rest]
        lines.append("| " + " | ".join(cells) + " |")
    return lines


def report(path: Path, heading: str, setup: str, lines: list[str], ngsolve: tuple, runs, write: bool) -> None:
    """Print the table `lines` and a line of run times (NGSolve's (DOFs, seconds, settings); this
    project's runs [(size mm, DOFs, seconds)]) and, with `write`, put them in the results file
    `path` under `heading` and the `setup` paragraph."""
    dofs, seconds, settings = ngsolve
    text = "\n".join(lines + ["", f"NGSolve: {dofs:,} DOFs, {seconds:.1f} s ({settings}); this project: "
                               + ", ".join(f"{s:g} mm {n:,} DOFs {t:.1f} s" for s, n, t in runs) + "."])
    print(text)
    if write:
        path.write_text(f"# {heading}\n\n{setup}\n\n{text}\n")


def ngsolve_forces(mu: float, lam: float, depths, maxh_top_mm: float = MAXH_TOP_MM, order: int = ORDER):
    """(force (n,) N/mm at depths, largest penetration (n,) mm, seconds, DOFs) from NGSolve: the
    displacement-only energy (the pressure eliminated, p = kappa (J - 1)) of order `order`, the
    penalty PENALTY_MPA_PER_MM, Newton's method with a backtracking line search on the energy."""
    import ngsolve as ng

    t0 = time.perf_counter()
    mesh = _block_mesh(maxh_top_mm)
    fes = ng.VectorH1(mesh, order=order, dirichlet="bottom|left|right")
    u = fes.TrialFunction()
    F = ng.Id(2) + ng.Grad(u)
    J = ng.Det(F)
    centre = ng.Parameter(RADIUS_MM)                      # the axis's height: R - depth
    gf = ng.GridFunction(fes)
    frozen = ng.GridFunction(fes)                         # the state whose normals the gap uses
    r_frozen = ng.CoefficientFunction((ng.x, ng.y)) + frozen - ng.CoefficientFunction((0.0, centre))
    normal = r_frozen / ng.sqrt(ng.InnerProduct(r_frozen, r_frozen))
    r = ng.CoefficientFunction((ng.x, ng.y)) + u - ng.CoefficientFunction((0.0, centre))
    gap = ng.InnerProduct(r, normal) - RADIUS_MM          # affine in u: a convex penalty
    a = ng.BilinearForm(fes, symmetric=True)
    a += ng.Variation((mu / 2 * (ng.InnerProduct(F, F) / J - 2) + (lam + mu) / 2 * (J - 1) ** 2) * ng.dx)
    kpen = ng.Parameter(PENALTY_MPA_PER_MM)
    a += ng.Variation(0.5 * kpen * ng.IfPos(-gap, gap * gap, 0.0) * ng.ds("top"))

    xg = ng.CoefficientFunction((ng.x, ng.y)) + gf - ng.CoefficientFunction((0.0, centre))
    dist = ng.sqrt(ng.InnerProduct(xg, xg))
    gap_g = dist - RADIUS_MM
    along = ng.IfPos(-gap_g, -gap_g, 0.0) * PENALTY_MPA_PER_MM * (-xg[1] / dist)    # traction along -y
    xs = np.linspace(-3.0, 3.0, 6001)
    forces, pens, depth = [], [], 0.0
    for target in depths:
        while depth < target - 1e-12:
            depth = min(target, depth + STEP_MM)
            centre.Set(RADIUS_MM - depth)
            solve_penalised(a, gf, frozen, fes, kpen, f"depth {depth:.3g} mm")
        forces.append(ng.Integrate(along, mesh, definedon=mesh.Boundaries("top")))
        g = gap_g(mesh(xs, np.zeros_like(xs), VOL_or_BND=ng.BND))
        pens.append(max(0.0, -float(np.min(g))))
    return np.array(forces), np.array(pens), time.perf_counter() - t0, fes.ndof


def project_forces(size_mm: float, work: Path, depths):
    """(force (n,) N/mm, seconds, DOFs) from `fem.contact.finite` on the block preset at size_mm."""
    from fem.contact.finite import FiniteContact
    from fem.contact.indentors import make_indentor
    from fem.geometry.build import MeshSpec, build_folder
    from fem.io.modelfolder import CONTACT_REGION, held_regions, read_model

    folder = work / f"block_{size_mm:g}"
    build_folder(folder, MeshSpec(preset="block", sizes={"size_mm": size_mm}))
    model, _ = read_model(folder, MATERIAL)
    t0 = time.perf_counter()
    fc = FiniteContact(model, CONTACT_REGION[2], held_regions(model))
    res = fc.indent(make_indentor(f"cylinder:{2 * RADIUS_MM:g}"), depths)
    return np.array([r.force_N for r in res]), time.perf_counter() - t0, model.ndof, model


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sizes", type=float, nargs="*", default=[0.25, 0.125])
    ap.add_argument("--work", type=Path, default=ROOT / "out" / "ngsolve_bench")
    ap.add_argument("--no-write", action="store_true")
    args = ap.parse_args()
    ours = [project_forces(s, args.work, DEPTHS_MM) for s in args.sizes]
    model = ours[0][3]
    mu, lam = float(model.mu[0]), float(model.lam[0])
    ref, pen, ng_s, ng_dofs = ngsolve_forces(mu, lam, DEPTHS_MM)
    lines = force_table("N/mm", DEPTHS_MM, ref, pen, {s: {"force": f} for s, (f, *_) in zip(args.sizes, ours)})
    report(RESULTS, "Neo-Hookean contact against NGSolve (plane strain)",
           f"Cylinder radius {RADIUS_MM:g} mm into the 40 x 18 mm block, {MATERIAL} (mu {mu:.6g} MPa, "
           f"lambda {lam:.6g} MPa), `python benchmarks/ngsolve_contact.py`", lines,
           (ng_dofs, ng_s, f"mesh, {len(DEPTHS_MM)} depths in {STEP_MM:g} mm steps"),
           [(s, n, t) for s, (_, t, n, _) in zip(args.sizes, ours)], not args.no_write)


if __name__ == "__main__":
    main()
