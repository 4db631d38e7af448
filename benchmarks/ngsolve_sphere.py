#!/usr/bin/env python
"""Large-deformation contact in 3D against an independent code: a rigid sphere pressed into a thick
nearly incompressible neo-Hookean layer to depth / radius 0.3, solved by this project's
`fem.contact.finite.FiniteContact` and by NGSolve (its own mesher, elements and Newton solver;
contact by a penalty on the penetration of the deformed surface into the sphere), force against
depth.

The problem: a quarter of a 2 BLOCK_MM x BLOCK_MM x 2 BLOCK_MM block (x, z >= 0 symmetry planes,
the top y = 0 free, the bottom y = -BLOCK_MM held, the outer sides free), one material, E = E_MPA,
nu = NU, the neo-Hookean of `fem.core.neohookean`,

    W(F, p) = mu / 2 (J^(-2/3) I1 - 3) + p (J - 1) - p^2 / (2 kappa),   kappa = lambda + 2 mu / 3,

a rigid frictionless sphere of radius RADIUS_MM over the corner x = z = 0 (the block's middle),
depths 0.1 to 0.6 mm. NGSolve: the same energy with the pressure eliminated (p = kappa (J - 1)) on
P2 displacements (`--order`), mesh size MAXH_FINE_MM (`--maxh`) in a box of FINE_MM under the sphere, load
steps of STEP_MM, a penalty max(0, -g)^2 / 2 raised 10 -> PENALTY_MPA_PER_MM within each step, g
the gap of the deformed top surface to the sphere along the normal of the last state (iterated
until the state no longer changes, as `ngsolve_contact.py`: frozen, the penalty stays convex; with
the exact distance the tangent is indefinite while the surface penetrates and Newton stalled),
Newton's method with a backtracking line search on the energy (`ngsolve_contact.solve_newton`).
Its force is the penalty's gradient applied to a unit translation along the approach, the
contact force at the solve's own quadrature points (the penalty traction integrated at other
points overstated it 50 times on a coarse mesh: the P2 surface bulges into the sphere between
quadrature points; summing the gradient's y entries instead counts NGSolve's hierarchical edge
functions, whose coefficients in a translation are 0, and understated it by 13 %); its
largest penetration, sampled on a grid over the contact, is printed. This project: P2-P1 mixed,
node-to-surface contact by Lagrange multipliers, on structured graded meshes
(`fem.verify.closed_forms.box`) of two sizes under the contact (`--sizes`), ending exactly at the
block's faces, with the contact
radius (the outermost node carrying force: it moves in steps of the node spacing).

    pip install ngsolve
    python benchmarks/ngsolve_sphere.py [--sizes 0.25 0.125] [--maxh 0.2] [--no-write]
    python benchmarks/ngsolve_sphere.py --linear --sizes 0.5 0.25 0.125 --order 3   # small strain

Prints per depth both forces [N], their ratio, the contact radii and the run times, and writes
benchmarks/results/ngsolve_sphere.md.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from ngsolve_contact import PENALTY_MPA_PER_MM, STEP_MM, force_table, report, solve_penalised  # noqa: E402

from fem.verify.closed_forms import hertz_sphere  # noqa: E402

RESULTS = ROOT / "benchmarks" / "results" / "ngsolve_sphere.md"
RADIUS_MM = 2.0
BLOCK_MM = 8.0
DEPTHS_MM = np.round(np.arange(0.1, 0.61, 0.1), 10)
E_MPA = 0.01
NU = 0.48
FINE_MM = 1.8
MAXH_FINE_MM = 0.2
MAXH_MM = 1.5
ORDER = 2
HELD = {"bottom": 0.0, "symx": (0.0, None, None), "symz": (None, None, 0.0)}
"""This project's held regions of the quarter block: the bottom, and the symmetry planes' normal."""


def lame(E: float, nu: float) -> tuple[float, float]:
    """(mu, lambda) [MPa] of Young's modulus E [MPa] and Poisson's ratio nu."""
    return E / (2 * (1 + nu)), E * nu / ((1 + nu) * (1 - 2 * nu))


def _quarter_mesh(maxh_fine_mm: float):
    """NGSolve mesh of the quarter block, finer (maxh_fine_mm) in a FINE_MM box under the sphere;
    boundaries top, bottom, symx (x = 0), symz (z = 0), side, and the inner faces of the fine box
    (interface: no condition)."""
    import ngsolve as ng
    from netgen.occ import Box, Glue, OCCGeometry, Pnt, X, Y, Z

    def named(solid, others: str, bottom: str):
        for f in solid.faces:
            f.name = others
        solid.faces.Max(Y).name, solid.faces.Min(Y).name = "top", bottom
        solid.faces.Min(X).name, solid.faces.Min(Z).name = "symx", "symz"
        return solid

    fine = named(Box(Pnt(0, -FINE_MM, 0), Pnt(FINE_MM, 0, FINE_MM)), "interface", "interface")
    block = named(Box(Pnt(0, -BLOCK_MM, 0), Pnt(BLOCK_MM, 0, BLOCK_MM)), "side", "bottom")
    fine.solids.maxh = maxh_fine_mm
    shape = Glue([block - fine, fine])
    return ng.Mesh(OCCGeometry(shape).GenerateMesh(maxh=MAXH_MM, grading=0.25))


def _space(maxh_fine_mm: float, order: int):
    """(NGSolve mesh of the quarter block, its displacement space of polynomial `order` held at the
    bottom and normal to the symmetry planes, the sphere centre's height: an ng.Parameter, R - depth)."""
    import ngsolve as ng

    mesh = _quarter_mesh(maxh_fine_mm)
    fes = ng.VectorH1(mesh, order=order, dirichlet="bottom", dirichletx="symx", dirichletz="symz")
    return mesh, fes, ng.Parameter(RADIUS_MM)


def _penalised(fes, energy, gap):
    """(the energy density `energy` [MPa] of the block plus a penalty max(0, -gap)^2 / 2 on the top,
    as an ng.BilinearForm; the penalty's ng.Parameter; force(gf) -> the contact force of the whole
    block [N]: the penalty's gradient applied to a unit translation along the approach, at the
    solve's own quadrature points)."""
    import ngsolve as ng

    kpen = ng.Parameter(PENALTY_MPA_PER_MM)
    penalty = ng.Variation(0.5 * kpen * ng.IfPos(-gap, gap * gap, 0.0) * ng.ds("top"))
    a = ng.BilinearForm(fes, symmetric=True)
    a += ng.Variation(energy * ng.dx)
    a += penalty
    contact = ng.BilinearForm(fes, symmetric=True)       # the penalty alone: its gradient is the contact force
    contact += penalty
    down = ng.GridFunction(fes)                           # the unit translation along y in the basis: with
    down.Set(ng.CoefficientFunction((0.0, 1.0, 0.0)))    # hierarchical P2, 1 on vertices, 0 on edges

    def force(gf) -> float:
        grad = gf.vec.CreateVector()
        contact.Apply(gf.vec, grad)
        return 4 * float(ng.InnerProduct(grad, down.vec))
    return a, kpen, force


def ngsolve_results(mu: float, lam: float, depths, maxh_fine_mm: float = MAXH_FINE_MM, inverse: str = "umfpack",
                    order: int = ORDER):
    """(force (n,) N of the whole block, largest penetration (n,) mm, seconds, DOFs) from NGSolve
    (module docstring)."""
    import ngsolve as ng

    t0 = time.perf_counter()
    mesh, fes, centre = _space(maxh_fine_mm, order)
    u = fes.TrialFunction()
    F = ng.Id(3) + ng.Grad(u)
    J = ng.Det(F)
    kappa = lam + 2 * mu / 3
    X = ng.CoefficientFunction((ng.x, ng.y, ng.z))
    c = ng.CoefficientFunction((0.0, centre, 0.0))
    gf = ng.GridFunction(fes)
    frozen = ng.GridFunction(fes)                         # the state whose normals the gap uses
    r_frozen = X + frozen - c
    normal = r_frozen / ng.sqrt(ng.InnerProduct(r_frozen, r_frozen))
    gap = ng.InnerProduct(X + u - c, normal) - RADIUS_MM  # affine in u: a convex penalty
    a, kpen, force = _penalised(fes, mu / 2 * (J ** (-2 / 3) * ng.InnerProduct(F, F) - 3) + kappa / 2 * (J - 1) ** 2,
                                gap)
    rg = X + gf - c
    inside = RADIUS_MM - ng.sqrt(ng.InnerProduct(rg, rg))
    pen = ng.IfPos(inside, inside, 0.0)
    xs = np.linspace(0.0, FINE_MM, 61)
    forces, pens, depth = [], [], 0.0
    for target in depths:
        while depth < target - 1e-12:
            depth = min(target, depth + STEP_MM)
            centre.Set(RADIUS_MM - depth)
            solve_penalised(a, gf, frozen, fes, kpen, f"depth {depth:.3g} mm", inverse)
        forces.append(force(gf))
        g = np.array([pen(mesh(float(x), 0.0, float(z), VOL_or_BND=ng.BND)) for x in xs for z in xs]).ravel()
        pens.append(float(g.max(initial=0.0)))
    return np.array(forces), np.array(pens), time.perf_counter() - t0, fes.ndof


def ngsolve_linear(mu: float, lam: float, depths, maxh_fine_mm: float = MAXH_FINE_MM, inverse: str = "umfpack",
                   order: int = ORDER):
    """(force (n,) N of the whole block, seconds) from NGSolve in small strain: linear elasticity
    on the same mesh and space, the gap along the approach to the sphere's true surface over
    the undeformed point (as `fem.contact.linear`), the same penalty; the small-strain baseline of
    `ngsolve_results`."""
    import ngsolve as ng

    t0 = time.perf_counter()
    _, fes, centre = _space(maxh_fine_mm, order)
    u = fes.TrialFunction()
    eps = ng.Sym(ng.Grad(u))
    r2 = RADIUS_MM ** 2 - ng.x * ng.x - ng.z * ng.z
    gap = ng.IfPos(r2, centre - ng.sqrt(ng.IfPos(r2, r2, 0.0)) - ng.y - u[1], 1.0)   # open outside the footprint
    a, kpen, force = _penalised(fes, mu * ng.InnerProduct(eps, eps) + lam / 2 * ng.Trace(eps) ** 2, gap)
    gf, frozen = ng.GridFunction(fes), ng.GridFunction(fes)
    forces = []
    for d in depths:
        centre.Set(RADIUS_MM - d)
        solve_penalised(a, gf, frozen, fes, kpen, f"depth {d:.3g} mm", inverse)
        forces.append(force(gf))
    return np.array(forces), time.perf_counter() - t0


def project_linear(size_mm: float, depths) -> np.ndarray:
    """(n,) this project's small-strain force [N] of the whole block (`fem.contact.linear`)."""
    from fem.contact.indentors import make_indentor
    from fem.contact.linear import ContactModel

    model = _project_block(size_mm)
    cm = ContactModel.from_fe(model, model.system(HELD), "top")
    return np.array([4 * cm.indent(make_indentor(f"sphere:{RADIUS_MM:g}"), depth_mm=d).total_force_N for d in depths])


def _project_block(size_mm: float):
    """This project's Model of the quarter block, structured and graded, size_mm under the contact."""
    from fem.core.model import Model
    from fem.verify.closed_forms import box, fine_then_growing

    xs = fine_then_growing(size_mm, FINE_MM, 1.5, BLOCK_MM, exact=True)
    ys = -xs[::-1]
    p, cells, reg = box(xs, ys, xs)
    regions = {"top": reg["ymax"], "bottom": reg["ymin"], "symx": reg["xmin"], "symz": reg["zmin"]}
    return Model(p, cells, np.ones(len(cells), int), regions, material=[E_MPA], nu=NU)


def project_results(size_mm: float, depths):
    """(force (n,) N of the whole block, contact radius (n,) mm, seconds, DOFs) from
    `fem.contact.finite.FiniteContact` on the quarter block, size_mm under the contact."""
    from fem.contact.finite import FiniteContact
    from fem.contact.indentors import make_indentor

    model = _project_block(size_mm)
    t0 = time.perf_counter()
    fc = FiniteContact(model, "top", HELD)
    res = fc.indent(make_indentor(f"sphere:{RADIUS_MM:g}"), depths)
    seconds = time.perf_counter() - t0
    x = fc.sn.x
    radii = [float(np.hypot(*x[r.contact_force_N > 0][:, [0, 2]].T).max(initial=0.0)) for r in res]
    return np.array([4 * r.force_N for r in res]), np.array(radii), seconds, model.ndof


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sizes", type=float, nargs="*", default=[0.25, 0.125])
    ap.add_argument("--maxh", type=float, default=MAXH_FINE_MM, help="NGSolve's mesh size under the sphere, mm")
    ap.add_argument("--depths", type=float, nargs="*", default=list(DEPTHS_MM), help="sphere depths, mm")
    ap.add_argument("--order", type=int, default=ORDER, help="NGSolve's polynomial order of the displacements")
    ap.add_argument("--inverse", default="umfpack", help="NGSolve's sparse direct solver")
    ap.add_argument("--no-write", action="store_true")
    ap.add_argument("--linear", action="store_true",
                    help="the small-strain baselines instead: NGSolve's and this project's linear forces (printed only)")
    args = ap.parse_args()
    mu, lam = lame(E_MPA, NU)
    depths = np.asarray(args.depths, float)
    if args.linear:
        ref, seconds = ngsolve_linear(mu, lam, depths, args.maxh, args.inverse, args.order)
        ours = {s: project_linear(s, depths) for s in args.sizes}
        print("| depth mm | NGSolve linear N | " + " | ".join(f"this project {s:g} mm N | / NGSolve - 1" for s in ours) + " |")
        for i, d in enumerate(depths):
            print(f"| {d:.2f} | {ref[i]:.6g} | " + " | ".join(f"{f[i]:.6g} | {100 * (f[i] / ref[i] - 1):+.2f} %"
                                                            for f in ours.values()) + " |")
        print(f"NGSolve small strain: P{args.order}, maxh {args.maxh:g} mm, {seconds:.0f} s")
        return
    ours = []
    for s in args.sizes:
        ours.append(project_results(s, depths))
        print(f"this project {s:g} mm: {ours[-1][2]:.1f} s, {ours[-1][3]:,} DOFs, forces {ours[-1][0]}", flush=True)
    ref, pen, ng_s, ng_dofs = ngsolve_results(mu, lam, depths, args.maxh, args.inverse, args.order)
    lines = force_table("N", depths, ref, pen, {s: {"force": f, "contact radius mm": a}
                                                  for s, (f, a, *_) in zip(args.sizes, ours)})
    hertz = hertz_sphere(RADIUS_MM, depths, E_MPA, NU)[0]
    lines += ["", "Hertz (half-space, small strain) for scale: "
              + ", ".join(f"{d:g} mm {f:.4g} N" for d, f in zip(depths, hertz)) + "."]
    report(RESULTS, "Neo-Hookean sphere indentation against NGSolve (3D)",
           f"Sphere radius {RADIUS_MM:g} mm into a {2 * BLOCK_MM:g} x {BLOCK_MM:g} x {2 * BLOCK_MM:g} mm block (a "
           f"quarter modelled), E {E_MPA:g} MPa, nu {NU:g} (mu {mu:.6g} MPa, lambda {lam:.6g} MPa), "
           "`python benchmarks/ngsolve_sphere.py`", lines,
           (ng_dofs, ng_s, f"mesh, {len(depths)} depths in {STEP_MM:g} mm steps, maxh {args.maxh:g} mm under "
                           "the sphere"),
           [(s, n, t) for s, (_, _, t, n) in zip(args.sizes, ours)], not args.no_write)


if __name__ == "__main__":
    main()
