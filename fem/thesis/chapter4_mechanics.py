"""Thesis chapter 4, mechanics of the 2D plane-strain models (4.1 Flamant block, 4.6 cylinders,
4.7 line-load stiffness order) and appendices A-B, claim by claim: each function takes a
`fem.thesis.findings.Workshop` and returns `Finding`s (fem.thesis.claims lists them in thesis order).
The receptor claims 4.2-4.4 are in fem.thesis.chapter4_receptors, the gratings 4.5 in
fem.thesis.chapter4_gratings. Units: mm, N/mm (forces per unit length), MPa.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fem.biomech.deflection import DeflectionExperiment
from fem.contact.finite import FiniteContact
from fem.contact.indentors import CYLINDERS_MM, make_indentor
from fem.core.model import Model
from fem.geometry import mesh2d
from fem.geometry.mesh2d import SOLID_FLUID_SHELL_MM
from fem.io.modelfolder import folder_info, held_regions, read_model
from fem.thesis.findings import Check, Finding, Series, Workshop
from fem.thesis.quotes import QUOTES
from fem.verify import closed_forms as reference

#: Cylinder of thesis figure 4-22 (3/32 in) and its depth there in the solid model, mm: the force
#: it takes sets the constant force of figures 4-24 and 4-25.
FIG_4_22_DIAMETER_MM, FIG_4_22_DEPTH_MM = 2.3805, 0.76


# ----------------------------------------------------------------------------- 4.1: Flamant
def flamant_block(shop: Workshop) -> list[Finding]:
    """Thesis 4.1: the 40 x 18 mm block matches the line-load (Flamant) solution in the region of
    interest. Radial stress under a point force at the top centre, against the closed form, at
    r = 1 and 3 mm and 0-75 deg from the load axis, sides held (the preset) and free, two sizes."""
    P = 1e-3
    angles = np.arange(0, 76, 15)
    rows, series, worst = [], [], {}
    for w, h in ((40.0, 18.0), (80.0, 36.0)):
        for held in (True, False):
            dom = mesh2d.rectangle_domain("block", w, h, held_sides=held)
            pts, tri, lay = mesh2d.mesh_domain(dom, shop.sizing())
            fixed = mesh2d.boundary_points(tri, len(pts)) & dom.fixed(pts)
            model = Model(pts, tri, lay, {"fixed": fixed}, material="m3", nu=0.48)
            top = np.flatnonzero(np.abs(pts[:, 1]) < 1e-9)
            top = top[[np.argmin(np.abs(pts[top, 0]))]]
            x0 = pts[top[0], 0]
            u = model.solve(prescribed={"fixed": 0.0}, point_forces=(top, np.array([[0.0, -P]]))).u
            label = f"{w:g} x {h:g} mm, sides {'held' if held else 'free'}"
            for r in (1.0, 3.0):
                t = np.radians(angles)
                e = np.column_stack([np.sin(t), -np.cos(t)])            # radial unit vectors
                S = (model.stress_operator(np.column_stack([x0 + r * e[:, 0], r * e[:, 1]])) @ u).reshape(-1, 4)
                sr = S[:, 0] * e[:, 0] ** 2 + S[:, 1] * e[:, 1] ** 2 + 2 * S[:, 3] * e[:, 0] * e[:, 1]
                fx, fy, fxy = reference.flamant(r * e[:, 0], r * e[:, 1], P)
                ratio = sr / (fx * e[:, 0] ** 2 + fy * e[:, 1] ** 2 + 2 * fxy * e[:, 0] * e[:, 1])
                rows += [{"block": label, "r_mm": r, "angle_deg": int(a), "fe_over_flamant": float(q)}
                         for a, q in zip(angles, ratio)]
                k = int(np.argmax(np.abs(ratio - 1)))
                worst[(w, held, r)] = (100 * float(abs(ratio[k] - 1)), int(angles[k]))
                if r == 3.0:
                    series.append(Series(label, angles.tolist(), ratio.tolist(), "-o" if held else "--s"))

    def err(w, held, r):
        return worst[(w, held, r)][0]
    shrinks = err(80.0, False, 3.0) < err(40.0, False, 3.0)
    band = "'matched' read as within 5 %"
    return [Finding(
        "sec4-1_flamant", "4.1 (construction of the models)", "Semi-infinite block against Flamant",
        QUOTES["sec4-1_flamant"],
        [Check(f"largest |FE / Flamant - 1| of the radial stress at r = {r:g} mm, 0-75 deg from the load axis, "
               "40 x 18 mm block with held sides", err(40.0, True, r), "<", 5.0, "%", why=band)
         for r in (1.0, 3.0)],
        f"The largest errors lie at {worst[(40.0, True, 1.0)][1]} and {worst[(40.0, True, 3.0)][1]} deg "
        f"(r = 1 and 3 mm). With free sides the 40 x 18 mm block is {err(40.0, False, 3.0):.1f} % off at "
        f"r = 3 mm, the 80 x 36 mm block {err(80.0, False, 3.0):.1f} % "
        + ("(the error falls as the block grows: a finite-domain effect)" if shrinks else
           "(the error does not fall as the block grows)")
        + f"; held, the 80 x 36 mm block is {err(80.0, True, 3.0):.1f} % off. The project's block preset "
        "holds its sides.",
        "angle from the load axis [deg]", "FE / Flamant radial stress at r = 3 mm", series, rows)]


# ----------------------------------------------------------------------------- 4.7: line load
#: The four 2D models of the line-load and bar runs (4.2, 4.4, 4.7): model folder, label, material.
LINE_LOAD_MODELS = (("square", "finite square", {}), ("block", "semi-infinite (sides held)", {}),
                    ("cylinder8", "cylinder", {}), ("cylinder8_bone", "cylinder with bone (held)",
                                                    {"rigid_bone": True}))


def line_load_order(shop: Workshop) -> list[Finding]:
    """Thesis 4.7, figure 4-27: deflection 2 mm from a 1 mm line load orders the four models'
    stiffness: finite square, semi-infinite, cylinder, cylinder with bone. Also the block with free
    sides and the cylinder with a free (elastic) bone."""
    runs = list(LINE_LOAD_MODELS) + [("block_free", "semi-infinite, sides free", {}),
                                     ("cylinder8_bone", "cylinder with bone (free)", {})]
    rows, series, at2 = [], [], {}
    d = np.linspace(0.0, 3.9, 40)                  # the square's surface ends 4 mm from the load
    for name, label, kw in runs:
        exp = DeflectionExperiment(shop.folder(name), **kw)
        (p,) = exp.profiles("m3" if exp.n_layers == 1 else "m33338", [1.0])
        v = p.at(d)
        at2[label] = float(p.at(np.array([2.0]))[0])
        rows.append({"model": label, "deflection_1mm": float(p.at(np.array([1.0]))[0]),
                     "deflection_2mm": at2[label], "deflection_3mm": float(p.at(np.array([3.0]))[0]),
                     "force_N_per_mm": float(p.force_N)})
        series.append(Series(label, d.tolist(), v.tolist(), "-" if "free" not in label else "--"))
    sq, blk, cyl, bone = (at2[label] for _, label, _ in LINE_LOAD_MODELS)
    blk_free, free = at2["semi-infinite, sides free"], at2["cylinder with bone (free)"]
    within = max(abs(sq - blk), abs(cyl - bone)) / abs(blk - cyl)
    order = ", ".join(sorted(at2, key=lambda k: -at2[k]))
    return [Finding(
        "fig4-27_line_load", "4.7, figure 4-27", "Stiffness order of the four 2D models under a line load",
        QUOTES["fig4-27_line_load"],
        [Check("deflection 2 mm from the load, finite square minus semi-infinite (sides held)", sq - blk, ">", 0, "mm"),
         Check("deflection 2 mm from the load, semi-infinite (sides held) minus cylinder", blk - cyl, ">", 0, "mm"),
         Check("deflection 2 mm from the load, cylinder minus cylinder with bone (held)", cyl - bone, ">", 0, "mm"),
         Check("larger difference within the pairs (square and semi-infinite; the two cylinders) over the "
               "difference between the pairs", within, "<", 1.0,
               why="'close together' read as closer to each other than to the other pair")],
        f"Deflections at 2 mm: square {sq:.3f}, semi-infinite {blk:.3f} mm with its sides held "
        f"({blk_free:.3f} mm with free sides, "
        + ("which would put it before the square; the held sides are also those that make the block match "
           "Flamant, section 4.1" if blk_free > sq else "still after the square")
        + f"), cylinder {cyl:.3f}, cylinder with bone {bone:.3f} mm held ({free:.3f} mm with the elastic bone "
        f"free). All six runs from the most to the least deflected: {order}.",
        "distance from the load [mm]", "surface deflection [mm]", series, rows)]


# ----------------------------------------------------------------------------- 4.6: cylinders
@dataclass
class CylinderRuns:
    """Constant-force indentations by C1-C8 on the 2D cylinder models (figures 4-24, 4-25)."""
    force_N: dict          # force level name -> N/mm
    results: dict          # (model label, level) -> dict of arrays over C1-C8
    hertz: dict            # (model label, level) -> C1-C8 depth differences from plane-strain Hertz
    volume: dict           # level -> max |fluid volume change| / fluid area


def cylinder_runs(shop: Workshop, kinematics: str = "linear") -> CylinderRuns:
    """C1-C8 at constant force on the cylinder with a held bone (the thesis's rigid bone), with a
    free elastic bone, and the solid-fluid cylinder. Force levels: F*, the force taking the
    figure 4-22 cylinder 0.76 mm into the held-bone model (linear kinematics), and F*/10 (the
    solid-fluid model is about 15x softer: at F* it would go deeper than half its diameter).
    kinematics 'finite': the same forces on the solid models (`fem.contact.finite`; it has no fluid
    core, `fem.core.neohookean.NO_FLUID_CORE`)."""
    codes = list(CYLINDERS_MM)
    D = np.array([CYLINDERS_MM[c] for c in codes])
    cm_held = shop.contact_model("cylinder8_bone", rigid_bone=True)[0]
    f_star = cm_held.indent(make_indentor(f"cylinder:{FIG_4_22_DIAMETER_MM}"),
                            depth_mm=FIG_4_22_DEPTH_MM).total_force_N
    levels = {"F*": f_star, "F*/10": f_star / 10}
    solver = shop.contact_model if kinematics == "linear" else shop.finite_contact
    models = {"solid, bone held": solver("cylinder8_bone", rigid_bone=True),
              "solid, bone free": solver("cylinder8_bone")}
    if kinematics == "linear":
        models["solid-fluid"] = solver("cylinder8_fluid")
    material = models["solid, bone held"][1].material
    E_star = material.E_MPa[1] / (1 - material.nu[1] ** 2)             # plane strain, MPa
    R2 = folder_info(shop.folder("cylinder8_bone"))["params"]["diameter_mm"] / 2
    R1 = D / 2
    shape = np.log((R1[-1] / (R1[-1] + R2)) / (R1 / (R1 + R2)))         # Hertz: depth(R1) - depth(C8)
    core_mm2 = np.pi * (R2 - SOLID_FLUID_SHELL_MM) ** 2
    out, hertz, volume = {}, {}, {}
    for label, (cm, model) in models.items():
        for level, F in levels.items():
            if label == "solid-fluid" and level == "F*":
                continue
            r = {"depth_mm": [], "width_mm": [], "width_resolution_mm": [], "max_pressure_MPa": [], "volume_change": []}
            for code in shop.progress.bar(codes, desc=f"{label} at {level} ({kinematics})", unit="cylinder"):
                ind = make_indentor(code)
                res = _by_force(cm, ind, F)
                r["depth_mm"].append(float(res.depth_mm.max()))
                r["width_mm"].append(float(res.contact_area_mm2))
                r["width_resolution_mm"].append(cm.edge_area_mm2(res))
                r["max_pressure_MPa"].append(float(res.max_pressure_MPa))
                if label == "solid-fluid":
                    u = cm.compliance(ind.approach).displacement(res.force_N)
                    r["volume_change"].append(abs(model.fluid_volume_change(u)))
            out[(label, level)] = {k: np.array(v) for k, v in r.items()}
            hertz[(label, level)] = F / (np.pi * E_star) * shape
            if label == "solid-fluid":
                volume[level] = float(np.max(r["volume_change"]) / core_mm2)
    return CylinderRuns(levels, out, hertz, volume)


def _by_force(solver, indentor, force_N: float):
    """The ContactResult of `indentor` pressed to force_N [N/mm] (at most 4 mm) by a linear
    ContactModel or a FiniteContact."""
    if isinstance(solver, FiniteContact):
        return solver.contact_result(indentor, solver.indent_force(indentor, force_N, 4.0))
    return solver.indent(indentor, force_N=force_N, max_depth_mm=4.0)


def _slope(D, depth):
    return float(np.polyfit(np.log(2.0 / D), np.log(depth), 1)[0])


def _r_squared(x, y) -> float:
    """Coefficient of determination of the least-squares line y = a + b x."""
    resid = y - np.polyval(np.polyfit(x, y, 1), x)
    return float(1 - np.sum(resid**2) / np.sum((y - y.mean()) ** 2))


def cylinders(shop: Workshop) -> list[Finding]:
    """Thesis 4.6, figures 4-24 and 4-25 (and the solid-fluid model's volume)."""
    return cylinder_findings(cylinder_runs(shop))


def cylinder_findings(runs: CylinderRuns) -> list[Finding]:
    """Figures 4-24 and 4-25 from linear `cylinder_runs`: the depth law (`depth_findings`), the
    solid-fluid model's depths, and the contact widths and peak pressures."""
    kappa = 2.0 / np.array(list(CYLINDERS_MM.values()))
    return [*depth_findings(runs), *_solid_fluid_findings(runs, kappa), *_contact_findings(runs, kappa)]


def depth_findings(runs: CylinderRuns) -> list[Finding]:
    """Figure 4-24 on the solid models from `cylinder_runs` (either kinematics): the square-root law
    read two ways, depth proportional to sqrt(curvature) and affine in it."""
    D = np.array(list(CYLINDERS_MM.values()))
    kappa = 2.0 / D
    R = runs.results
    held, free = R[("solid, bone held", "F*")], R[("solid, bone free", "F*")]
    held10 = R[("solid, bone held", "F*/10")]
    d = held["depth_mm"]
    slope = _slope(D, d)
    hz = runs.hertz[("solid, bone held", "F*")]
    fe_diff, hz10 = d[0] - d[-1], runs.hertz[("solid, bone held", "F*/10")][0]
    fe10 = held10["depth_mm"][0] - held10["depth_mm"][-1]
    r2_sqrt, r2_hertz = _r_squared(np.sqrt(kappa), d), _r_squared(hz, d)
    rows = [{"model": f"{label} at {level} = {runs.force_N[level]:.4g} N/mm", "cylinder": c,
             "diameter_mm": float(D[i]), "depth_mm": float(r["depth_mm"][i]),
             "contact_width_mm": float(r["width_mm"][i]), "max_pressure_MPa": float(r["max_pressure_MPa"][i])}
            for (label, level), r in R.items() for i, c in enumerate(CYLINDERS_MM)]
    series = [Series(f"{label}, {level}", kappa.tolist(), r["depth_mm"].tolist(), "--s" if "free" in label else "-o")
              for (label, level), r in R.items() if label != "solid-fluid"]
    series.append(Series("plane-strain Hertz through C8 (bone held, F*)", kappa.tolist(), (d[-1] + hz).tolist(), ":"))
    series.append(Series("proportional to sqrt(curvature), through C8", kappa.tolist(),
                         (d[-1] * np.sqrt(kappa / kappa[-1])).tolist(), "-."))
    fit = np.polyfit(np.sqrt(kappa), d, 1)
    series.append(Series("affine in sqrt(curvature), least squares", kappa.tolist(),
                         np.polyval(fit, np.sqrt(kappa)).tolist(), "k--"))
    hertz_note = (f"Plane-strain Hertz (a rigid cylinder on an elastic one of radius 4 mm) gives C1 - C8 = "
                  f"(P / pi E*) ln[(R8 / (R8 + 4)) / (R1 / (R1 + 4))] = {hz[0]:.3f} mm at F* against the "
                  f"model's {fe_diff:.3f} mm ({100 * (fe_diff / hz[0] - 1):+.1f} %), and {hz10:.4f} against "
                  f"{fe10:.4f} mm at F*/10 ({100 * (fe10 / hz10 - 1):+.1f} %).")
    proportional = Finding(
        "fig4-24_depth_proportional", "4.6, figure 4-24",
        "Depth at constant force against cylinder curvature", QUOTES["fig4-24_depth"],
        [Check("log-log slope of depth against curvature, C1-C8, solid model (bone held, F*)", slope, "~", 0.5,
               tol=0.1, why="proportional to sqrt(curvature) has slope 0.5"),
         Check("C1 over C8 depth, solid model (bone held, F*)", float(d[0] / d[-1]), "~",
               float(np.sqrt(kappa[0] / kappa[-1])), tol=0.2 * float(np.sqrt(kappa[0] / kappa[-1])),
               why="proportional to sqrt(curvature), within 20 %")],
        f"Slope with the bone free {_slope(D, free['depth_mm']):.3f}, at F*/10 {_slope(D, held10['depth_mm']):.3f}. "
        + hertz_note, "cylinder curvature 1/R [1/mm]", "depth at constant force [mm]", series, rows, logx=True,
        reading="'in proportion to the square root': depth = b sqrt(curvature)")
    affine = Finding(
        "fig4-24_depth_affine", "4.6, figure 4-24",
        "Depth at constant force against cylinder curvature", QUOTES["fig4-24_depth"],
        [Check("R^2 of depth = a + b sqrt(curvature), C1-C8, solid model (bone held, F*)", r2_sqrt, ">", 0.99,
               why="'grew in proportion' read as a straight line in sqrt(curvature) with an offset")],
        f"Least squares: depth = {fit[1]:.3f} + {fit[0]:.4f} sqrt(curvature) mm. The plane-strain Hertz law, "
        f"affine in its logarithmic shape, fits with R^2 = {r2_hertz:.4f} "
        + ("(better than the square root)" if r2_hertz > r2_sqrt else "(no better than the square root)")
        + ". " + hertz_note, "cylinder curvature 1/R [1/mm]", "depth at constant force [mm]", series, [], logx=True,
        reading="'in proportion to the square root': depth = a + b sqrt(curvature), a straight line with an offset")
    return [proportional, affine]


def _solid_fluid_findings(runs: CylinderRuns, kappa) -> list[Finding]:
    """Figure 4-24, the solid-fluid model: deeper for every cylinder, its depth's change over C1-C8
    read against the solid model's relative to the mean and in mm."""
    R = runs.results
    fluid, held10 = R[("solid-fluid", "F*/10")], R[("solid, bone held", "F*/10")]
    f_depth, s_depth = fluid["depth_mm"], held10["depth_mm"]
    deeper = Check("smallest solid-fluid over solid depth, C1-C8 at F*/10", float(np.min(f_depth / s_depth)), ">", 1.0)
    depth_series = [Series(label, kappa.tolist(), r["depth_mm"].tolist()) for (label, level), r in R.items()
                    if level == "F*/10"]
    fluid_note = (f"Solid-fluid depths {f_depth.min():.3f}-{f_depth.max():.3f} mm, the solid model's "
                  f"{s_depth.min():.4f}-{s_depth.max():.4f} mm at F*/10 (F* / 10 because the solid-fluid model, "
                  f"far softer, would go deeper than half the cylinder's diameter at F*). The fluid core keeps "
                  f"its volume to {runs.volume['F*/10']:.1e} of its area.")
    relative = lambda v: float(np.ptp(v) / v.mean())
    return [Finding(
        f"fig4-24_solid_fluid_{name}", "4.6, figure 4-24", "The solid-fluid model under the same cylinders",
        QUOTES["fig4-24_solid_fluid"],
        [deeper, Check(f"spread of depth over C1-C8, solid-fluid over solid model{what}", ratio, "<", 1.0,
                       why="'no appreciable change' read against the solid model's change")],
        fluid_note, "cylinder curvature 1/R [1/mm]", "depth at F*/10 [mm]", depth_series, [], logx=True,
        reading=f"'no appreciable change' {how}")
        for name, what, ratio, how in (
            ("relative", " (each over its mean)", relative(f_depth) / relative(s_depth), "relative to the mean depth"),
            ("absolute", " (in mm)", float(np.ptp(f_depth) / np.ptp(s_depth)), "in millimetres"))]


def _resolution(fn, widths, resolution) -> float:
    """Largest change of fn(widths) [its unit] when the C1 and C8 widths (first and last) each move
    by up to their resolution (`ContactModel.edge_area_mm2`): what node-counted widths cannot tell."""
    base = fn(widths)
    out = 0.0
    for s0 in (-1, 1):
        for s8 in (-1, 1):
            w = np.array(widths, float)
            w[0] += s0 * resolution[0]
            w[-1] += s8 * resolution[-1]
            out = max(out, abs(fn(w) - base))
    return out


def _contact_findings(runs: CylinderRuns, kappa) -> list[Finding]:
    """Figure 4-25: contact widths and peak pressures, 'the reduction was more rapid' read as a
    relative and as an absolute fall."""
    R = runs.results
    fluid, held10 = R[("solid-fluid", "F*/10")], R[("solid, bone held", "F*/10")]
    drop = {"relative": lambda w: float(100 * (1 - w[0] / w[-1])), "absolute": lambda w: float(w[-1] - w[0])}
    fall = {(name, model): (fn(r["width_mm"]), _resolution(fn, r["width_mm"], r["width_resolution_mm"]))
            for name, fn in drop.items() for model, r in (("solid", held10), ("fluid", fluid))}
    gap = fluid["width_mm"] - held10["width_mm"]
    i = int(np.argmin(gap))
    units = {"relative": "%", "absolute": "mm"}
    widths = [Series(f"{label}, {level}", kappa.tolist(), r["width_mm"].tolist()) for (label, level), r in R.items()]
    width_note = (f"Contact widths C1-C8 at F*/10: solid {held10['width_mm'].min():.2f}-"
                  f"{held10['width_mm'].max():.2f} mm, solid-fluid {fluid['width_mm'].min():.2f}-"
                  f"{fluid['width_mm'].max():.2f} mm; widths are sums of the contacting nodes' tributary lengths, so "
                  f"they step with the node spacing: each is known to within its edge nodes' length "
                  f"({min(held10['width_resolution_mm'].min(), fluid['width_resolution_mm'].min()):.3f}-"
                  f"{max(held10['width_resolution_mm'].max(), fluid['width_resolution_mm'].max()):.3f} mm), the "
                  f"checks' resolution.")
    contact = [Finding(
        f"fig4-25_contact_{name}", "4.6, figure 4-25", "Contact width and peak pressure against curvature",
        QUOTES["fig4-25_contact"],
        [Check("smallest solid-fluid minus solid contact width, C1-C8 at F*/10", float(gap[i]), ">", 0.0, "mm",
               resolution=float(fluid["width_resolution_mm"][i] + held10["width_resolution_mm"][i])),
         Check("smallest solid over solid-fluid peak pressure, C1-C8 at F*/10",
               float(np.min(held10["max_pressure_MPa"] / fluid["max_pressure_MPa"])), ">", 1.0),
         Check(f"fall of the contact width from C8 to C1, solid model (F*/10, {name})", fall[(name, "solid")][0], ">",
               0.0, units[name], resolution=fall[(name, "solid")][1]),
         Check(f"fall of the contact width from C8 to C1, solid-fluid minus solid model (F*/10, {name})",
               fall[(name, "fluid")][0] - fall[(name, "solid")][0], ">", 0.0, units[name],
               resolution=fall[(name, "fluid")][1] + fall[(name, "solid")][1])],
        width_note, "cylinder curvature 1/R [1/mm]", "contact width [mm]", widths, [], logx=True,
        reading=f"'the reduction was more rapid' {how}")
        for name, how in (("relative", "as a fall relative to the C8 width"), ("absolute", "as a fall in mm"))]
    return contact



# ----------------------------------------------------------------------------- appendices A and B
def appendices(shop: Workshop) -> list[Finding]:
    """Appendix A: in plane strain with nu -> 0.5, SED = (2/3) E eps1^2; appendix B: under prescribed
    displacements a homogeneous model's strains do not depend on E. On the cylinder (no bone)."""
    folder = shop.folder("cylinder8")
    pts = np.column_stack([np.linspace(-1.5, 1.5, 13), np.full(13, 4.0 - 0.75)])
    model, _ = read_model(folder, material="m3", nu=0.4999)
    presc = {**held_regions(model), "surface": (None, -0.1)}
    sol = model.solve(prescribed=presc)
    sed, eps1 = sol.sample("sed_MPa", pts), sol.sample("max_compressive_strain", pts)
    ratio = sed / (2.0 / 3.0 * model.material.E_MPa[1] * eps1**2)
    stiff, _ = read_model(folder, material="m5", nu=0.4999)
    eps_stiff = stiff.solve(prescribed=presc).sample("max_compressive_strain", pts)
    rel = float(np.max(np.abs(eps_stiff - eps1)) / np.max(np.abs(eps1)))
    a = float(np.max(np.abs(ratio - 1)))
    x = pts[:, 0].tolist()
    return [Finding(
        "appA_sed", "appendix A (restated in 4.2)", "Strain energy density and maximum compressive strain",
        QUOTES["appA_sed"],
        [Check("largest |SED / ((2/3) E eps1^2) - 1| at 13 receptor sites 0.75 mm deep, cylinder, nu = 0.4999",
               a, "<", 0.01, why="the identity is exact at nu = 0.5; within 1 % at nu = 0.4999")],
        "SED = (2/3) E eps1^2 is the appendix's identity for plane strain and nu = 0.5 (eps1 the maximum "
        "compressive strain); nu = 0.4999 keeps the displacement solve well posed.",
        "x [mm]", "SED / ((2/3) E eps1^2)", [Series("receptors 0.75 mm deep", x, ratio.tolist())]),
        Finding(
        "appB_modulus", "appendix B", "Strains independent of the modulus under prescribed displacement",
        QUOTES["appB_modulus"],
        [Check("largest relative change of eps1 at 0.75 mm from E = 1 kPa (m3) to 100 kPa (m5)", rel,
               "<", 1e-6, why="exact in exact arithmetic: a change above round-off would contradict it")],
        "The cylinder (no bone) with its surface pushed 0.1 mm down, nu = 0.4999.",
        "x [mm]", "max compressive strain", [Series("E = 1 kPa", x, eps1.tolist()),
                                             Series("E = 100 kPa", x, eps_stiff.tolist(), "--")])]
