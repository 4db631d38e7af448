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
from fem.contact.indentors import CYLINDERS_MM, make_indentor
from fem.core.model import Model
from fem.geometry import mesh2d
from fem.geometry.mesh2d import SOLID_FLUID_SHELL_MM
from fem.io.modelfolder import folder_info, held_regions, read_model
from fem.thesis.findings import DIFFERS, REPRODUCED, Finding, Series, Workshop
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
    rows, series = [], []
    err3 = {}
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
                if r == 3.0:
                    series.append(Series(label, angles.tolist(), ratio.tolist(), "-o" if held else "--s"))
                    err3[(w, held)] = float(ratio[angles == 60][0] - 1)
    held, free = err3[(40.0, True)], err3[(40.0, False)]
    ok = abs(held) < 0.05
    return [Finding(
        "sec4-1_flamant", "4.1 (construction of the models)", "Semi-infinite block against Flamant",
        "A 40 x 18 mm block of 8-node plane-strain elements matched the analytical line-load solution "
        "(Timoshenko and Goodier) in the region of interest.",
        "radial stress error at r = 3 mm, 60 deg from the load axis [%] (40 x 18 mm, sides held)",
        0.0, 100 * held, REPRODUCED if ok else DIFFERS,
        f"With the block's sides held, as a model of a half-space at rest far from the load, the "
        f"radial stress is within {100 * abs(held):.1f} % of Flamant at r = 3 mm, 60 deg "
        f"(80 x 36 mm: {100 * abs(err3[(80.0, True)]):.1f} %); with free sides it is "
        f"{100 * abs(free):.1f} % off (80 x 36 mm: {100 * abs(err3[(80.0, False)]):.1f} %), the error "
        "falling with the block's size: a finite-domain effect, not a discretisation one. The "
        "project's block preset holds its sides.",
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
    thesis_order = [label for _, label, _ in LINE_LOAD_MODELS]
    order = sorted(thesis_order, key=lambda k: -at2[k])
    ok = order == thesis_order
    sq, blk, blk_free = at2["finite square"], at2["semi-infinite (sides held)"], at2["semi-infinite, sides free"]
    held, free = at2["cylinder with bone (held)"], at2["cylinder with bone (free)"]
    return [Finding(
        "fig4-27_line_load", "4.7, figure 4-27", "Stiffness order of the four 2D models under a line load",
        "By the deflection 2 mm from a 1 mm line load, the models in increasing order of stiffness are "
        "the finite square, semi-infinite, cylinder and cylinder with bone; square and semi-infinite "
        "close together, as are the two cylinders.",
        "deflection 2 mm from the load, finite square over semi-infinite", 1.0, sq / blk,
        REPRODUCED if ok else DIFFERS,
        f"Order found: {', '.join(order)}. Deflections at 2 mm: square {sq:.3f}, semi-infinite "
        f"{blk:.3f} mm with its sides held ({blk_free:.3f} mm with free sides, which would put it "
        f"before the square: the thesis's order needs the held sides that also make the block match "
        f"Flamant, section 4.1), cylinder {at2['cylinder']:.3f}, cylinder with bone {held:.3f} mm "
        f"held ({free:.3f} mm with the elastic bone free: the order does not depend on it).",
        "distance from the load [mm]", "surface deflection [mm]", series, rows)]


# ----------------------------------------------------------------------------- 4.6: cylinders
@dataclass
class CylinderRuns:
    """Constant-force indentations by C1-C8 on the 2D cylinder models (figures 4-24, 4-25)."""
    force_N: dict          # force level name -> N/mm
    results: dict          # (model label, level) -> dict of arrays over C1-C8
    hertz: dict            # (model label, level) -> C1-C8 depth differences from plane-strain Hertz
    volume: dict           # level -> max |fluid volume change| / fluid area


def cylinder_runs(shop: Workshop) -> CylinderRuns:
    """C1-C8 at constant force on the cylinder with a held bone (the thesis's rigid bone), with a
    free elastic bone, and the solid-fluid cylinder. Force levels: F*, the force taking the
    figure 4-22 cylinder 0.76 mm into the held-bone model, and F*/10 (the solid-fluid model is
    about 15x softer: at F* it would go deeper than half its diameter)."""
    codes = list(CYLINDERS_MM)
    D = np.array([CYLINDERS_MM[c] for c in codes])
    models = {"solid, bone held": shop.contact_model("cylinder8_bone", rigid_bone=True),
              "solid, bone free": shop.contact_model("cylinder8_bone"),
              "solid-fluid": shop.contact_model("cylinder8_fluid")}
    cm_held = models["solid, bone held"][0]
    f_star = cm_held.indent(make_indentor(f"cylinder:{FIG_4_22_DIAMETER_MM}"),
                            depth_mm=FIG_4_22_DEPTH_MM).total_force_N
    levels = {"F*": f_star, "F*/10": f_star / 10}
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
            r = {"depth_mm": [], "width_mm": [], "max_pressure_MPa": [], "volume_change": []}
            for code in shop.progress.bar(codes, desc=f"{label} at {level}", unit="cylinder"):
                ind = make_indentor(code)
                res = cm.indent(ind, force_N=F, max_depth_mm=4.0)
                r["depth_mm"].append(float(res.depth_mm.max()))
                r["width_mm"].append(float(res.contact_area_mm2))
                r["max_pressure_MPa"].append(float(res.max_pressure_MPa))
                if label == "solid-fluid":
                    u = cm.compliance(ind.approach).displacement(res.force_N)
                    r["volume_change"].append(abs(model.fluid_volume_change(u)))
            out[(label, level)] = {k: np.array(v) for k, v in r.items()}
            hertz[(label, level)] = F / (np.pi * E_star) * shape
            if label == "solid-fluid":
                volume[level] = float(np.max(r["volume_change"]) / core_mm2)
    return CylinderRuns(levels, out, hertz, volume)


def _slope(D, depth):
    return float(np.polyfit(np.log(2.0 / D), np.log(depth), 1)[0])


def cylinders(shop: Workshop) -> list[Finding]:
    """Thesis 4.6, figures 4-24 and 4-25 (and the solid-fluid model's volume)."""
    return cylinder_findings(cylinder_runs(shop), shop.size_mm)


def cylinder_findings(runs: CylinderRuns, size_mm: float) -> list[Finding]:
    """Figures 4-24 and 4-25 from `cylinder_runs` on models with `size_mm` surface elements."""
    D = np.array(list(CYLINDERS_MM.values()))
    kappa = 2.0 / D
    R = runs.results
    held, free, fluid = (R[("solid, bone held", "F*")], R[("solid, bone free", "F*")],
                         R[("solid-fluid", "F*/10")])
    held10 = R[("solid, bone held", "F*/10")]
    slope = _slope(D, held["depth_mm"])
    fe_diff = held["depth_mm"][0] - held["depth_mm"][-1]
    hz_diff = runs.hertz[("solid, bone held", "F*")][0]
    fe10 = held10["depth_mm"][0] - held10["depth_mm"][-1]
    hz10 = runs.hertz[("solid, bone held", "F*/10")][0]
    deeper = bool(np.all(fluid["depth_mm"] > held10["depth_mm"]))
    spread = lambda d: float((d.max() - d.min()) / d.mean())
    rows = [{"model": f"{label} at {level} = {runs.force_N[level]:.4g} N/mm", "cylinder": c,
             "diameter_mm": float(D[i]), "depth_mm": float(r["depth_mm"][i]),
             "contact_width_mm": float(r["width_mm"][i]), "max_pressure_MPa": float(r["max_pressure_MPa"][i])}
            for (label, level), r in R.items() for i, c in enumerate(CYLINDERS_MM)]
    series = [Series(f"{label}, {level}", kappa.tolist(), r["depth_mm"].tolist(), "--s" if "free" in label else "-o")
              for (label, level), r in R.items()]
    series.append(Series("plane-strain Hertz (held bone, F*)", kappa.tolist(),
                         (held["depth_mm"][-1] + runs.hertz[("solid, bone held", "F*")]).tolist(), ":"))
    series.append(Series("square-root law through C8 (held bone, F*)", kappa.tolist(),
                         (held["depth_mm"][-1] * np.sqrt(kappa / kappa[-1])).tolist(), "-."))
    depth = Finding(
        "fig4-24_depth", "4.6, figure 4-24", "Depth at constant force against cylinder curvature",
        "Under constant force the depth of the solid model (rigid bone) grew in proportion to the "
        "square root of the cylinder curvature; the solid-fluid model had to be indented deeper "
        "for every cylinder, with no appreciable change of depth across the cylinders.",
        "log-log slope of depth against curvature, C1-C8, solid model (bone held, F*)", 0.5, slope, DIFFERS,
        f"Slope {slope:.3f} (bone free: {_slope(D, free['depth_mm']):.3f}; at F*/10: "
        f"{_slope(D, held10['depth_mm']):.3f}); C1/C8 depth ratio {held['depth_mm'][0] / held['depth_mm'][-1]:.2f} "
        f"against 4.0 for a square-root law. The plane-strain Hertz solution (a rigid cylinder on an "
        f"elastic one of radius 4 mm) gives depth differences that grow only with the logarithm of "
        f"the curvature: C1 - C8 = (P / pi E*) ln[(R8 / (R8 + 4)) / (R1 / (R1 + 4))] = {hz_diff:.3f} mm at "
        f"F* against the model's {fe_diff:.3f} mm ({100 * (fe_diff / hz_diff - 1):+.1f} %), and "
        f"{hz10:.4f} against {fe10:.4f} mm at F*/10 ({100 * (fe10 / hz10 - 1):+.1f} %). A linear plane-strain "
        f"model therefore cannot give a square-root law; the thesis's ABAQUS runs were large-"
        f"deformation contact, which this comparison does not cover. Solid-fluid (F*/10): deeper "
        f"than the solid model for {'every' if deeper else 'not every'} cylinder "
        f"({fluid['depth_mm'].min():.2f}-{fluid['depth_mm'].max():.2f} mm against "
        f"{held10['depth_mm'].min():.3f}-{held10['depth_mm'].max():.3f} mm); relative spread of depth "
        f"over C1-C8 {100 * spread(fluid['depth_mm']):.0f} % against the solid model's "
        f"{100 * spread(held10['depth_mm']):.0f} % (in mm the fluid model's spread is the larger). "
        f"Fluid volume kept to {runs.volume['F*/10']:.1e} of the core's area.",
        "cylinder curvature 1/R [1/mm]", "depth at constant force [mm]", series, rows, logx=True)
    narrower = bool(np.all(held10["width_mm"] <= fluid["width_mm"] + 1e-9))
    sharper = bool(np.all(held10["max_pressure_MPa"] > fluid["max_pressure_MPa"]))
    # widths come in steps of the surface node spacing: judged on C1 against C8
    falls = all(r["width_mm"][0] < r["width_mm"][-1] for r in (held10, fluid))
    drop = lambda r: float(1 - r["width_mm"][0] / r["width_mm"][-1])
    faster = drop(fluid) > drop(held10)
    contact = Finding(
        "fig4-25_contact", "4.6, figure 4-25", "Contact width and peak pressure against curvature",
        "For each cylinder the solid model had the higher peak pressure and the smaller contact width; "
        "the width fell with increasing curvature, faster for the solid-fluid model.",
        "relative fall of contact width C8 -> C1, solid-fluid over solid (F*/10)", None,
        drop(fluid) / drop(held10), REPRODUCED if (narrower and sharper and falls and faster) else DIFFERS,
        f"At F*/10, C1-C8: the solid model's contact is {'no wider than' if narrower else 'not always narrower than'} "
        f"the solid-fluid model's (widths step with the {size_mm} mm surface nodes), its peak "
        f"pressure {'higher for every cylinder' if sharper else 'not always higher'}; the width "
        f"{'falls' if falls else 'does not fall'} from C8 to C1 in both, by {100 * drop(held10):.0f} % "
        f"(solid) and {100 * drop(fluid):.0f} % (solid-fluid).",
        "cylinder curvature 1/R [1/mm]", "contact width [mm]",
        [Series(f"{label}, {level}", kappa.tolist(), r["width_mm"].tolist()) for (label, level), r in R.items()],
        [], logx=True)
    return [depth, contact]


# ----------------------------------------------------------------------------- appendices A and B
def appendices(shop: Workshop) -> list[Finding]:
    """Appendix A: in plane strain with nu -> 0.5, SED = (2/3) E eps1^2; appendix B: under prescribed
    displacements a homogeneous model's strains do not depend on E. On the cylinder (no bone)."""
    folder = shop.folder("cylinder8")
    pts = np.column_stack([np.linspace(-1.5, 1.5, 13), np.full(13, 4.0 - 0.75)])
    model, _ = read_model(folder, material="m33338", nu=0.4999)
    presc = {**held_regions(model), "surface": (None, -0.1)}
    sol = model.solve(prescribed=presc)
    sed, eps1 = sol.sample("sed_MPa", pts), sol.sample("max_compressive_strain", pts)
    ratio = sed / (2.0 / 3.0 * model.material.E_MPa[1] * eps1**2)
    stiff, _ = read_model(folder, material="m55558", nu=0.4999)
    eps_stiff = stiff.solve(prescribed=presc).sample("max_compressive_strain", pts)
    rel = float(np.max(np.abs(eps_stiff - eps1)) / np.max(np.abs(eps1)))
    a = float(np.max(np.abs(ratio - 1)))
    return [Finding(
        "appA_sed", "appendix A", "Strain energy density and maximum compressive strain",
        "In plane strain with an incompressible material, SED = (2/3) E eps1^2 (eps1 the maximum "
        "compressive strain).", "largest |SED / ((2/3) E eps1^2) - 1| at 0.75 mm depth, nu = 0.4999",
        None, a, REPRODUCED if a < 0.01 else DIFFERS,
        f"Largest deviation {a:.2e} over 13 receptor sites 0.75 mm deep (nu = 0.4999 rather than 0.5).",
        "x [mm]", "SED / ((2/3) E eps1^2)", [Series("receptors 0.75 mm deep", pts[:, 0].tolist(), ratio.tolist())]),
        Finding(
        "appB_modulus", "appendix B", "Strains independent of the modulus under prescribed displacement",
        "Under prescribed displacements the strains of a homogeneous model do not depend on Young's modulus.",
        "largest relative change of eps1 at 0.75 mm from E = 1 kPa to 100 kPa", None, rel,
        REPRODUCED if rel < 1e-6 else DIFFERS,
        f"Relative change {rel:.1e} (round-off) between m33338 and m55558.",
        "x [mm]", "max compressive strain", [Series("E = 1 kPa", pts[:, 0].tolist(), eps1.tolist()),
                                             Series("E = 100 kPa", pts[:, 0].tolist(), eps_stiff.tolist(), "--")])]
