"""Thesis chapter 4 (the 2D plane-strain models) and appendices A-B, claim by claim: each function
takes a `fem.thesis.findings.Workshop` and returns `Finding`s (fem.thesis.claims lists them in thesis order).
Units: mm, N/mm (forces per unit length), MPa.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fem.thesis.findings import DIFFERS, REPRODUCED, Finding, Series, Workshop
from fem.contact.indentors import CYLINDERS_MM

#: Cylinder of thesis figure 4-22 (3/32 in) and its depth there in the solid model, mm: the force
#: it takes sets the constant force of figures 4-24 and 4-25.
FIG_4_22_DIAMETER_MM, FIG_4_22_DEPTH_MM = 2.3805, 0.76


# ----------------------------------------------------------------------------- 4.1: Flamant
def flamant_block(shop: Workshop) -> list[Finding]:
    """Thesis 4.1: the 40 x 18 mm block matches the line-load (Flamant) solution in the region of
    interest. Radial stress under a point force at the top centre, against the closed form, at
    r = 1 and 3 mm and 0-75 deg from the load axis, sides held (the preset) and free, two sizes."""
    from fem.geometry import mesh2d
    from fem.verify import closed_forms as reference
    from fem.core.model import Model

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
LINE_LOAD_MODELS = (("square", "finite square", {}), ("block", "semi-infinite (sides held)", {}),
                    ("cylinder8", "cylinder", {}), ("cylinder8_bone", "cylinder with bone (held)",
                                                    {"rigid_bone": True}))


def line_load_order(shop: Workshop) -> list[Finding]:
    """Thesis 4.7, figure 4-27: deflection 2 mm from a 1 mm line load orders the four models'
    stiffness: finite square, semi-infinite, cylinder, cylinder with bone. Also the block with free
    sides and the cylinder with a free (elastic) bone."""
    from fem.biomech.deflection import DeflectionExperiment

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
    from fem.contact.indentors import make_indentor
    from fem.geometry.mesh2d import SOLID_FLUID_SHELL_MM
    from fem.io.modelfolder import folder_info

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


# ----------------------------------------------------------------------------- 4.2-4.5: receptors
#: Thesis candidates for the SA-I relevant stimulus in figures 4-3, 4-4 and 4-7 (fem.core.measures names).
CANDIDATES = (("sed_MPa", "SED"), ("max_compressive_strain", "max compressive strain"),
              ("abs:strain_xy", "|shear strain|"))
RECEPTOR_DEPTHS_MM = (0.5, 0.75, 1.0)
#: Receptor sites 0.05 mm apart (the spacing of the thesis's traces) across the pad's middle, mm.
SITES_MM = np.round(np.arange(-3.0, 3.0001, 0.05), 3)
CENTRE = int(np.flatnonzero(SITES_MM == 0.0)[0])


def _probe(folder, depths_mm=(0.75,), sites_mm=SITES_MM, **material):
    """fem.receptors.probes.Probe2D on a 2D model folder, material m33338 (material: e.g. rigid_bone=True)."""
    from fem.core.materials import Material
    from fem.receptors.probes import Probe2D

    return Probe2D(folder, sites_mm, depths_mm, Material("m33338", **material))


def _contrast(values, centre) -> float:
    """Michelson contrast of a profile's peak against its value at the centre."""
    peak = float(np.max(values))
    return (peak - centre) / (peak + centre)


# ----------------------------------------------------------------------------- 4.2: point load
def point_load_fields(shop: Workshop) -> list[Finding]:
    """Thesis 4.2, figures 4-3 and 4-4: a line load (the sharp wedge, 1 mm deep) on the four
    models. Profiles across receptors 0.5-1.0 mm deep under the central load (the thesis's
    construction of a receptive field), and the field measured directly: the load swept over
    the receptor at 0.75 mm. Half-peak thresholds."""
    from fem.contact.indentors import make_indentor
    from fem.receptors.probes import receptive_field

    names = [c for c, _ in CANDIDATES]
    label_of = dict(CANDIDATES)
    wedge = make_indentor("wedge", orientation="parallel")
    d75 = RECEPTOR_DEPTHS_MM.index(0.75)
    profile, sweep, peak = {}, {}, {}
    for name, label, kw in shop.progress.bar(LINE_LOAD_MODELS, desc="line-load sweeps", unit="model"):
        probe = _probe(shop.folder(name), RECEPTOR_DEPTHS_MM, **kw)
        x = np.sort(probe.contact.points_mm[:, 0])
        # the load on surface nodes: between them the wedge's contact, and its force, jumps from
        # node to node (by up to 30 % on 0.25 mm elements)
        pos = x[np.abs(x) <= 2.0]
        vals, _ = probe.measure(wedge, pos, names, depth_mm=1.0)
        i0 = int(np.argmin(np.abs(pos)))
        for c in names:
            for j, d in enumerate(RECEPTOR_DEPTHS_MM):
                v = vals[c][i0, j]
                profile[label, c, d] = receptive_field(SITES_MM, v, 0.5 * v.max(), pos[i0])
                peak[label, c, d] = float(v.max())
            v = vals[c][:, d75, CENTRE]
            sweep[label, c] = receptive_field(pos, v, 0.5 * v.max())
    main = LINE_LOAD_MODELS[-1][1]              # the cylinder with bone, the thesis's model from 4.4 on
    labels = [label for _, label, _ in LINE_LOAD_MODELS]

    # figure 4-3: blurring with depth, SED sharper than max compressive strain
    width = {c: np.array([profile[main, c, d].diameter_mm for d in RECEPTOR_DEPTHS_MM]) for c in names}
    peaks = {c: np.array([peak[main, c, d] for d in RECEPTOR_DEPTHS_MM]) for c in names}
    blurs = all(np.all(np.diff(width[c]) > 0) and np.all(np.diff(peaks[c]) < 0) for c in names)
    sharper = bool(np.all(width["sed_MPa"] < width["max_compressive_strain"]))
    styles = dict(zip(RECEPTOR_DEPTHS_MM, ("-", "--", ":")))
    blur = Finding(
        "fig4-3_depth", "4.2, figure 4-3", "Strain measures under a line load blur with depth",
        "Under a line load on the cylinder with bone, each strain measure is the more blurred the deeper "
        "the receptor (0.5-1.0 mm): the elastic medium is a spatial low-pass filter; at a given depth "
        "SED is less blurred than the maximum compressive strain (SED ~ eps^2, appendix A).",
        "half-peak width of SED over that of max compressive strain at 0.75 mm", None,
        float(width["sed_MPa"][1] / width["max_compressive_strain"][1]),
        REPRODUCED if blurs and sharper else DIFFERS,
        "Half-peak widths at 0.5, 0.75, 1.0 mm: " + "; ".join(
            f"{label_of[c]} {', '.join(f'{w:.2f}' for w in width[c])} mm" for c in names)
        + f" ({'each widening and its peak falling' if blurs else 'not all widening with falling peaks'} "
        f"with depth; |shear strain| is the outer extent of its two lobes). SED is "
        f"{'narrower than max compressive strain at every depth' if sharper else 'not narrower at every depth'}.",
        "receptor position relative to the load [mm]", "measure / its peak at 0.5 mm depth",
        [Series(f"{label_of[c]}, {d} mm", profile[main, c, d].positions_mm.tolist(),
                (profile[main, c, d].values / peak[main, c, 0.5]).tolist(), styles[d])
         for c in names for d in RECEPTOR_DEPTHS_MM],
        [{"measure": label_of[c], "depth_mm": d, "half_peak_width_mm": float(width[c][j]),
          "peak": peak[main, c, d]} for c in names for j, d in enumerate(RECEPTOR_DEPTHS_MM)])

    # the other three models: same profiles, other magnitudes; yardstick: 0.25 mm of receptor depth
    at75 = {c: np.array([profile[m, c, 0.75].diameter_mm for m in labels]) for c in names}
    spread = {c: float(np.ptp(at75[c]) / np.diff(width[c]).min()) for c in names}
    size = {c: max(peak[m, c, 0.75] for m in labels) / min(peak[m, c, 0.75] for m in labels) for c in names}
    alike = max(spread.values()) < 1.0
    models = Finding(
        "fig4-3_models", "4.2 (figure 4-3, the other models)", "The four models give the same profiles",
        "For the finite square, semi-infinite and homogeneous cylinder the magnitudes under a given line "
        "load differ from the cylinder with bone's, but the spatial profile of each measure is about the same.",
        "largest spread of half-peak widths at 0.75 mm over the four models, in units of the widening "
        "per 0.25 mm of depth", None, max(spread.values()), REPRODUCED if alike else DIFFERS,
        "Half-peak widths at 0.75 mm (" + ", ".join(labels) + "): " + "; ".join(
            f"{label_of[c]} {', '.join(f'{w:.2f}' for w in at75[c])} mm" for c in names)
        + ". The spread over the models is " + ", ".join(f"{spread[c]:.2f}" for c in names)
        + " times the smallest widening caused by 0.25 mm more depth on the cylinder with bone "
        f"({'all' if alike else 'not all'} below 1: the models differ less than receptors 0.25 mm apart "
        "in depth). The peaks differ by factors of " + ", ".join(f"{size[c]:.2f}" for c in names)
        + " over the models (1 mm deep wedge).",
        "receptor position relative to the load [mm]", "SED at 0.75 mm / its peak",
        [Series(m, profile[m, "sed_MPa", 0.75].positions_mm.tolist(),
                (profile[m, "sed_MPa", 0.75].values / peak[m, "sed_MPa", 0.75]).tolist(), "-")
         for m in labels],
        [{"model": m, "measure": label_of[c], "half_peak_width_mm": profile[m, c, 0.75].diameter_mm,
          "peak": peak[m, c, 0.75]} for m in labels for c in names])

    # figure 4-4: receptive fields by sweeping the load over the receptor at 0.75 mm
    shear = sweep[main, "abs:strain_xy"]
    shapes = {c: sweep[main, c].shape for c in names}
    ok = (shapes == {"sed_MPa": "disk", "max_compressive_strain": "disk", "abs:strain_xy": "annulus"}
          and abs(shear.hole_mm - 0.3) <= 0.1)
    fracs = (0.3, 0.4, 0.5, 0.6, 0.7)
    rows = []
    for c in names:
        for q in fracs:
            f = receptive_field(sweep[main, c].positions_mm, sweep[main, c].values, q * sweep[main, c].values.max())
            rows.append({"measure": label_of[c], "threshold_of_peak": q, "shape": f.shape,
                         "diameter_mm": f.diameter_mm, "hole_mm": f.hole_mm})
    holes = [r["hole_mm"] for r in rows if r["measure"] == label_of["abs:strain_xy"]]
    fields = Finding(
        "fig4-4_receptive_fields", "4.2, figure 4-4", "Receptive fields for a point load",
        "With a threshold on the relevant stimulus at 0.75 mm, maximum compressive strain and SED predict "
        "circular receptive fields centred over the receptor; absolute shear strain an annulus, OFF directly "
        "over the receptor, the OFF circle about 0.3 mm across.",
        "OFF hole of the |shear strain| field [mm] (half-peak threshold)", 0.3, float(shear.hole_mm),
        REPRODUCED if ok else DIFFERS,
        f"Load swept over the receptor (cylinder with bone, 1 mm deep on each surface node): SED a "
        f"{shapes['sed_MPa']} of {sweep[main, 'sed_MPa'].diameter_mm:.2f} mm, max compressive strain a "
        f"{shapes['max_compressive_strain']} of {sweep[main, 'max_compressive_strain'].diameter_mm:.2f} mm, "
        f"|shear strain| an {shapes['abs:strain_xy']} of {shear.diameter_mm:.2f} mm with a {shear.hole_mm:.2f} mm "
        f"OFF hole. The thesis's threshold is arbitrary and the hole follows it: {min(holes):.2f}-{max(holes):.2f} mm "
        f"for thresholds of 30-70 % of the peak. The recorded fields of 2-8 mm (von Frey hairs) also depend "
        "on a threshold and are not compared.",
        "load position relative to the receptor [mm]", "measure at the receptor / its peak",
        [Series(label_of[c], sweep[main, c].positions_mm.tolist(),
                (sweep[main, c].values / sweep[main, c].values.max()).tolist(), "-") for c in names]
        + [Series("threshold (half peak)", [-2.0, 2.0], [0.5, 0.5], "k-.")], rows)

    # the thesis's shortcut: the response below B to a load at A taken for that below A to a load at B
    rel = {(m, c): profile[m, c, 0.75].diameter_mm / sweep[m, c].diameter_mm - 1 for m in labels for c in names}
    worst = {m: max(abs(rel[m, c]) for c in names) for m in labels}
    block = LINE_LOAD_MODELS[1][1]
    swap = Finding(
        "sec4-2_reciprocity", "4.2 (construction of figure 4-4)", "Profile under one load as the receptive field",
        "The state of stress below B under a load at A is taken as that below A under a load at B: exact "
        "on the semi-infinite model, a reasonable approximation on the cylinder for points a short "
        "distance apart; the profile under one central load then gives the receptive field.",
        "largest relative difference of the half-peak field diameters, profile over sweep, cylinder with bone",
        None, worst[main], REPRODUCED if worst[main] <= 0.1 else DIFFERS,
        "Field diameter from the profile under the central load over that from sweeping the load, minus 1: "
        + "; ".join(f"{m} " + ", ".join(f"{100 * rel[m, c]:+.1f} %" for c in names) for m in labels)
        + f" (SED, max compressive strain, |shear strain|). On the flat semi-infinite model the two agree within "
        f"{100 * worst[block]:.1f} % and on the flat-topped square within {100 * worst[labels[0]]:.1f} %; on the "
        f"cylinders the profile overstates the field by up to {100 * max(worst[m] for m in labels[2:]):.0f} % "
        f"(judged against 10 %): the curved surface breaks the translation invariance that makes the two "
        f"the same. The OFF hole of |shear strain| is {profile[main, 'abs:strain_xy', 0.75].hole_mm:.2f} mm "
        f"from the profile and {shear.hole_mm:.2f} mm from the sweep.",
        "load position relative to the receptor [mm]", "SED at 0.75 mm / its peak",
        # a profile's positions are the receptor's relative to the load: mirrored onto the sweep's
        [Series(f"{m}, {how}", (sign * f.positions_mm).tolist(), (f.values / f.values.max()).tolist(), style)
         for m in (main, block) for how, f, sign, style in (("load swept", sweep[m, "sed_MPa"], 1, "-"),
                                                             ("profile under one load", profile[m, "sed_MPa", 0.75], -1, "--"))],
        [{"model": m, "measure": label_of[c], "sweep_diameter_mm": sweep[m, c].diameter_mm,
          "profile_diameter_mm": profile[m, c, 0.75].diameter_mm, "relative_difference": rel[m, c]}
         for m in labels for c in names])
    return [blur, models, fields, swap]


# ----------------------------------------------------------------------------- 4.3: two points
#: Separation from which the thesis finds the force-controlled intensive cue constant (figure 4-6), mm.
FIG_4_6_SETTLING_MM = 1.6


def two_point_resolution(shop: Workshop) -> list[Finding]:
    """Thesis 4.3, figures 4-5 and 4-6: the intensive cue (max SED at 0.75 mm) on the cylinder with
    bone under two sharp tips 0-3 mm apart, both 0.5 mm deep (equal displacement) or each carrying
    half the force that takes one tip 0.5 mm deep (equal force: the same load at separation 0);
    and how far one tip's surface deflection and SED reach."""
    from fem.contact.indentors import make_indentor
    from fem.receptors.probes import settling_separation, two_point_curves

    probe = _probe(shop.folder("cylinder8_bone"), sites_mm=np.round(np.arange(-3.5, 3.5001, 0.05), 3),
                   rigid_bone=True)
    seps = np.round(np.arange(0.0, 3.0001, 0.2), 3)
    with shop.progress.task("two-point loads"):
        c = two_point_curves(probe, seps, depth_mm=0.5)
    vals, (one,) = probe.measure(make_indentor("two-point:0", orientation="parallel"), [0.0], ["sed_MPa"],
                                 depth_mm=0.5)
    x = probe.contact.points_mm[:, 0]
    o = np.argsort(x)
    defl = lambda r: float(np.mean(np.interp([-r, r], x[o], one.deflection_mm[o])) / one.deflection_mm.max())
    sed = vals["sed_MPa"][0, 0]
    reach = lambda r: float(np.mean(np.interp([-r, r], probe.sites_x_mm, sed)) / sed.max())
    d, f = c["displacement"], c["force"]
    rows = [{"separation_mm": float(s), "equal_displacement_MPa": float(d[i]), "equal_force_MPa": float(f[i]),
             "one_tip_alone_displacement_MPa": float(c["alone_displacement"][i]),
             "one_tip_alone_force_MPa": float(c["alone_force"][i]), "depth_equal_force_mm": float(c["depth_force_mm"][i])}
            for i, s in enumerate(seps)]

    # figure 4-5: the shapes of the two curves
    low = int(np.argmin(d))
    rises, dips, recovers = d[1] > d[0], 0 < low < len(d) - 1 and d[low] < d[0], d[-1] > 1.05 * d[low]
    near = int(np.argmax(np.abs(f / f[-1] - 1) <= 0.05))          # first separation within 5 % of the last
    falls = bool(np.all(np.diff(f[:near + 1]) < 0))
    shapes = Finding(
        "fig4-5_two_point", "4.3, figure 4-5", "Peak SED under two point loads against their separation",
        "Prescribed displacement: as the separation grows from zero the peak SED at 0.75 mm first increases, "
        "then decreases sharply, then increases gradually to a steady value. Prescribed force: it decreases "
        "monotonically to a steady value.",
        "peak SED at 0.2 mm separation over one load (separation 0), equal displacement", None, float(d[1] / d[0]),
        REPRODUCED if rises and dips and recovers and falls else DIFFERS,
        f"Equal displacement (tips 0.5 mm deep): {d[1] / d[0]:.2f} of the single load's peak SED at 0.2 mm "
        f"({'up' if rises else 'not up'}), {'down to' if dips else 'its least value'} {d[low] / d[0]:.2f} at "
        f"{seps[low]:.1f} mm, then {'rising' if recovers else 'not rising'} to {d[-1] / d[0]:.2f} at 3 mm. Equal "
        f"force ({c['force_per_load_N']:.3g} N/mm per tip): {'falls monotonically' if falls else 'does not fall monotonically'} "
        f"from 1 to {f[near] / f[0]:.2f} by {seps[near]:.1f} mm, where it comes within 5 % of its 3 mm value.",
        "separation of the loads [mm]", "peak SED at 0.75 mm / one load's",
        [Series("equal displacement", seps.tolist(), (d / d[0]).tolist()),
         Series("equal force", seps.tolist(), (f / f[0]).tolist(), "-s")], rows)

    # figure 4-6: where the intensive cue stops changing
    s_force = settling_separation(seps, f, 0.05)
    s_disp = settling_separation(seps, d, 0.05)
    at = int(np.flatnonzero(seps >= s_force)[0]) if np.isfinite(s_force) else len(seps) - 1
    later = bool(np.isnan(s_disp) or s_disp > s_force)
    ok = abs(s_force - FIG_4_6_SETTLING_MM) <= 0.4 and later
    alone = c["alone_force"][1:]                  # one tip carrying the per-tip force, at +s/2
    jitter = float(np.max(np.abs(np.diff(alone)) / alone[:-1]))
    drift = float(alone[-1] / np.interp(FIG_4_6_SETTLING_MM / 2, seps[1:] / 2, alone) - 1)
    cue = Finding(
        "fig4-6_intensive_cue", "4.3, figure 4-6", "Intensive cue under force and displacement control",
        "Under force control the intensive cue (peak SED at 0.75 mm) settles to a constant value from a load "
        "separation of 1.6 mm; under displacement control it keeps varying with the separation. The reason: "
        "one load's surface displacement spreads wider (semi-width about 2 mm) than its SED at 0.5-1.0 mm "
        "(about 1 mm).",
        "separation from which the equal-force cue stays within 5 % of its 3 mm value [mm]",
        FIG_4_6_SETTLING_MM, s_force, REPRODUCED if ok else DIFFERS,
        f"Equal force settles at {s_force:.1f} mm; equal displacement "
        + (f"only at {s_disp:.1f} mm" if np.isfinite(s_disp) else "not within 3 mm")
        + f" and is still {100 * abs(d[at] / d[-1] - 1):.0f} % off at {seps[at]:.1f} mm (judged: within 0.4 mm "
        f"of 1.6 mm, two steps of the separations, and displacement later). One tip alone carrying the per-tip "
        f"force changes by up to {100 * jitter:.1f} % between neighbouring places, the jitter of a concentrated "
        f"load on {shop.size_mm} mm elements against a 5 % settling band, and drifts by {100 * drift:+.1f} % from "
        f"0.8 to 1.5 mm off the top as it moves down the cylinder's flank. The thesis's explanation, one tip "
        f"0.5 mm deep: the surface deflection is still {100 * defl(1.0):.0f} % and {100 * defl(2.0):.0f} % of its peak 1 "
        f"and 2 mm away, the SED at 0.75 mm {100 * reach(1.0):.0f} % and {100 * reach(2.0):.1f} %.",
        "half separation of the loads [mm]", "peak SED at 0.75 mm / its value at 3 mm",
        [Series("equal force", (seps / 2).tolist(), (f / f[-1]).tolist()),
         Series("equal displacement", (seps / 2).tolist(), (d / d[-1]).tolist(), "-s"),
         Series("+5 %", [0.0, 1.5], [1.05, 1.05], "k:"), Series("-5 %", [0.0, 1.5], [0.95, 0.95], "k:")], rows)
    return [shapes, cue]


# ----------------------------------------------------------------------------- 4.4: bars
BAR_WIDTH_MM = 1.5


def rectangular_bars(shop: Workshop) -> list[Finding]:
    """Thesis 4.4, figure 4-7: a 1.5 mm bar 1 mm deep on the four models (and the block with free
    sides): surface pressure, and SED, max compressive strain and |shear strain| at 0.75 mm.
    Contrast: (peak - centre) / (peak + centre) of a profile across the receptors."""
    from fem.contact.indentors import make_indentor

    free = "semi-infinite, sides free"
    names = [c for c, _ in CANDIDATES]
    label_of = dict(CANDIDATES)
    bar = make_indentor(f"bar:{BAR_WIDTH_MM:g}", orientation="parallel")
    runs = {}
    for name, label, kw in shop.progress.bar(LINE_LOAD_MODELS + (("block_free", free, {}),), desc="bar", unit="model"):
        probe = _probe(shop.folder(name), **kw)
        vals, (res,) = probe.measure(bar, [0.0], names, depth_mm=1.0)
        x = probe.contact.points_mm[:, 0]
        o = np.argsort(x)
        o = o[np.abs(x[o]) <= 3.0]
        p = res.pressure_MPa[o]
        runs[label] = {"x": x[o], "p": p, "p_centre": float(p[np.argmin(np.abs(x[o]))]),
                       "force": res.total_force_N, **{c: vals[c][0, 0] for c in names}}
    labels = [label for _, label, _ in LINE_LOAD_MODELS]
    main, cyl, square = labels[3], labels[2], labels[0]
    contrast = {(m, c): _contrast(r[c], r[c][CENTRE]) for m, r in runs.items() for c in names}
    contrast.update({(m, "pressure"): _contrast(r["p"], r["p_centre"]) for m, r in runs.items()})
    rows = [{"model": m, "force_N_per_mm": r["force"], "max_pressure_MPa": float(r["p"].max()),
             "centre_pressure_MPa": r["p_centre"], "pressure_contrast": contrast[m, "pressure"],
             **{f"{label_of[c]} peak": float(r[c].max()) for c in names},
             **{f"{label_of[c]} contrast": contrast[m, c] for c in names}} for m, r in runs.items()]

    # pressure concentrated under the bar's edges
    ratio = {m: float(runs[m]["p"].max() / runs[m]["p_centre"]) for m in labels}
    where = {m: float(abs(runs[m]["x"][np.argmax(runs[m]["p"])])) for m in labels}
    at_edge = all(abs(where[m] - BAR_WIDTH_MM / 2) <= shop.size_mm for m in labels)
    edges = Finding(
        "fig4-7_edge_pressure", "4.4, figure 4-7", "Pressure under a bar peaks at its edges",
        "For each model the surface pressure under a 1.5 mm bar indented 1 mm is very high under the "
        "bar's edges relative to its centre.", "smallest edge-over-centre pressure ratio of the four models",
        None, min(ratio.values()), REPRODUCED if at_edge and min(ratio.values()) >= 1.25 else DIFFERS,
        "Peak pressure over centre pressure: " + ", ".join(f"{m} {ratio[m]:.2f}" for m in labels)
        + ", the peaks " + ("all" if at_edge else "not all") + f" within one element ({shop.size_mm} mm) of the "
        f"edges at +-{BAR_WIDTH_MM / 2:g} mm (|x| = " + ", ".join(f"{where[m]:.2f}" for m in labels)
        + " mm; judged: at least 1.25). A rigid flat bar's edge pressure is singular, so the sampled peak "
        "grows as the elements shrink.",
        "x [mm]", "pressure / pressure at the centre",
        [Series(m, runs[m]["x"].tolist(), (runs[m]["p"] / runs[m]["p_centre"]).tolist(), "-") for m in labels], rows)

    # edge-centre contrast: the models compared, and the measures compared
    filtered = [(m, c) for m in labels for c in names[:2] if contrast[m, c] >= contrast[m, "pressure"]]
    best = {c: max(labels, key=lambda m: contrast[m, c]) for c in names[:2]}
    rival = max(contrast[m, "sed_MPa"] for m in labels if m != square)
    models = Finding(
        "fig4-7_model_contrast", "4.4, figure 4-7", "Edge contrast of the strain measures across the models",
        "The strain measures at 0.75 mm are low-pass filtered versions of the surface pressure; among the "
        "models, all strain measures of the finite square have the best contrast between the edges and "
        "the centre of the bar.", "SED contrast of the finite square over the best of the other three models",
        None, contrast[square, "sed_MPa"] / rival,
        REPRODUCED if all(b == square for b in best.values()) and not filtered else DIFFERS,
        "Contrast at 0.75 mm (" + ", ".join(labels) + "): " + "; ".join(
            f"{label_of[c]} {', '.join(f'{contrast[m, c]:.3f}' for m in labels)}" for c in names[:2])
        + "; best: " + ", ".join(f"{label_of[c]} on the {best[c]}" for c in names[:2])
        + f" (with free sides the semi-infinite block gives {contrast[free, 'sed_MPa']:.3f} and "
        f"{contrast[free, 'max_compressive_strain']:.3f}). Both are below the pressure's "
        f"{min(contrast[m, 'pressure'] for m in labels):.2f}-{max(contrast[m, 'pressure'] for m in labels):.2f} "
        + ("in every model (low-pass filtered). " if not filtered else "not in every model. ")
        + "|shear strain| vanishes over the bar's centre in every model (contrast "
        + ", ".join(f"{contrast[m, 'abs:strain_xy']:.3f}" for m in labels) + "), so it does not rank them.",
        "x [mm]", "SED at 0.75 mm / its value at the centre",
        [Series(m, SITES_MM.tolist(), (runs[m]["sed_MPa"] / runs[m]["sed_MPa"][CENTRE]).tolist(), "-")
         for m in labels + [free]], [])

    shear_best = all(contrast[m, "abs:strain_xy"] > max(contrast[m, c] for c in names[:2]) for m in labels)
    lobes = {m: float(abs(SITES_MM[np.argmax(runs[m]["abs:strain_xy"])])) for m in labels}
    shear = Finding(
        "fig4-7_shear_edges", "4.4, figure 4-7", "Absolute shear strain marks the bar's edges",
        "For each model absolute shear strain has the best edge-centre contrast among the strain measures: "
        "shear strain sensors would detect edges best.", "smallest |shear strain| contrast of the four models",
        None, min(contrast[m, "abs:strain_xy"] for m in labels), REPRODUCED if shear_best else DIFFERS,
        "Contrast of |shear strain| " + ", ".join(f"{contrast[m, 'abs:strain_xy']:.3f}" for m in labels)
        + " against at most " + f"{max(contrast[m, c] for m in labels for c in names[:2]):.3f} for SED and max "
        f"compressive strain ({', '.join(labels)}): it vanishes over the centre by symmetry and peaks at "
        f"|x| = " + ", ".join(f"{lobes[m]:.2f}" for m in labels) + f" mm, just outside the edges at "
        f"{BAR_WIDTH_MM / 2:g} mm.",
        "x [mm]", "measure at 0.75 mm / its peak (cylinder with bone)",
        [Series(label_of[c], SITES_MM.tolist(), (runs[main][c] / runs[main][c].max()).tolist(), "-") for c in names],
        [])

    # the bone: most distortion, larger loads
    sed_peak = {m: float(runs[m]["sed_MPa"].max()) for m in labels}
    highest = max(labels, key=sed_peak.get) == main
    up = {"force": runs[main]["force"] / runs[cyl]["force"],
          "max pressure": float(runs[main]["p"].max() / runs[cyl]["p"].max()), "peak SED": sed_peak[main] / sed_peak[cyl]}
    bone = Finding(
        "fig4-7_bone", "4.4, figure 4-7", "The rigid bone raises the loads and the SED",
        "For the same bar the distortion at the receptors, measured by SED, is highest in the cylinder with "
        "bone; adding the stiff bone to the homogeneous cylinder increases the maximum loads imposed and "
        "accentuates the SED profile.", "peak SED at 0.75 mm, cylinder with bone over the homogeneous cylinder",
        None, up["peak SED"], REPRODUCED if highest and min(up.values()) > 1 else DIFFERS,
        "Peak SED at 0.75 mm: " + ", ".join(f"{m} {sed_peak[m]:.3g} MPa" for m in labels)
        + f" ({'highest' if highest else 'not highest'} with the bone). The bone multiplies the cylinder's "
        "force by " + f"{up['force']:.2f}, its peak pressure by {up['max pressure']:.2f} and its peak SED by "
        f"{up['peak SED']:.2f} (bar 1 mm deep, bone held as the thesis's rigid bone). The SED's edge contrast "
        f"falls with the bone ({contrast[cyl, 'sed_MPa']:.3f} to {contrast[main, 'sed_MPa']:.3f}): what grows is "
        "its level.",
        "x [mm]", "SED at 0.75 mm [MPa]",
        [Series(m, SITES_MM.tolist(), runs[m]["sed_MPa"].tolist(), "-") for m in labels], [])
    return [edges, models, shear, bone]


# ----------------------------------------------------------------------------- 4.5: gratings
GRATING_BAR_MM = 0.5
#: Models of the grating runs: model folder, label, material.
GRATING_MODELS = (("cylinder8_bone", "8 mm cylinder with bone", {"rigid_bone": True}),
                  ("cylinder16_bone", "16 mm cylinder with bone", {"rigid_bone": True}),
                  ("block", "semi-infinite (sides held)", {}))


def grating_runs(shop: Workshop) -> dict:
    """The aperiodic grating of 0.5 mm bars (fem.contact.indentors' default gaps, 0.5-5 mm: the thesis does
    not list its gaps) indented 1 mm and stepped across each of GRATING_MODELS: SED and max
    compressive strain at 0.75 mm under every position, the bars touching, the force on each bar.
    Returns {"positions_mm", "edges_mm", "gaps_mm", label: {...}}."""
    from fem.contact.indentors import make_indentor

    grating = make_indentor(f"grating:{GRATING_BAR_MM:g}", orientation="parallel")
    edges = grating.parts[0].bar_edges_mm()
    # the grating's left end relative to the receptor at x = 0, in 0.25 mm steps (the thesis's 0.2 mm)
    # so that every bar centre, and receptors 1 and 2 mm off-centre, fall on the steps; the right end
    # stays inside the 40 mm block, whose held sides no bar may press
    pos = np.round(np.arange(-18.5, 2.0001, 0.25), 3)
    out = {"positions_mm": pos, "edges_mm": edges, "gaps_mm": np.array(grating.parts[0].gaps_mm)}
    names = ["sed_MPa", "max_compressive_strain"]
    for name, label, kw in shop.progress.bar(GRATING_MODELS, desc="grating sweeps", unit="model"):
        probe = _probe(shop.folder(name), **kw)
        vals, res = probe.measure(grating, pos, names, depth_mm=1.0)
        x = probe.contact.points_mm[:, 0]
        along = x[None, :, None] - pos[:, None, None]             # node from the grating's left end, mm
        on_bar = (along >= edges[:, 0] - 1e-9) & (along <= edges[:, 1] + 1e-9)   # (positions, nodes, bars)
        bar_force = np.einsum("kn,knb->kb", np.array([r.force_N for r in res]), on_bar)
        out[label] = {**{c: vals[c][:, 0] for c in names}, "bar_force": bar_force,
                      "touching": (bar_force > 0).sum(axis=1), "force": bar_force.sum(axis=1),
                      "width": np.array([r.contact_area_mm2 for r in res])}
    return out


def aperiodic_gratings(shop: Workshop) -> list[Finding]:
    """Thesis 4.5.2-4.5.4, figures 4-9 to 4-12 and 4-18."""
    return grating_findings(grating_runs(shop))


def _under_bars(runs, label, measure="sed_MPa"):
    """The measure at the central receptor with each bar centred over it, over the rightmost bar's."""
    pos, centres = runs["positions_mm"], runs["edges_mm"].mean(axis=1)
    v = runs[label][measure][:, CENTRE]
    at = [int(np.flatnonzero(np.isclose(pos, -c))[0]) for c in centres]
    return v[at] / v[at[-1]], at


def _off_centre(runs, label, x_mm) -> float:
    """RMS difference, over the central profile's peak, between the SED spatial profile of the
    receptor x_mm off-centre, shifted by x_mm, and the central receptor's."""
    pos = runs["positions_mm"]
    v = runs[label]["sed_MPa"]
    k = int(np.flatnonzero(np.isclose(SITES_MM, x_mm))[0])
    q = pos - x_mm                               # grating position relative to that receptor
    ok = q >= pos[0] - 1e-9
    central = np.interp(q[ok], pos, v[:, CENTRE])
    return float(np.sqrt(np.mean((v[ok, k] - central) ** 2)) / v[:, CENTRE].max())


def _from_right(bars, n) -> str:
    """Bar indices (from the left) as the thesis numbers them, from the right (1 = rightmost)."""
    return "{" + ", ".join(str(n - k) for k in sorted(bars, reverse=True)) + "}"


def grating_findings(runs: dict) -> list[Finding]:
    """Figures 4-9 to 4-12 and 4-18 from `grating_runs`."""
    l8, l16, block = (label for _, label, _ in GRATING_MODELS)
    pos, edges, gaps = runs["positions_mm"], runs["edges_mm"], runs["gaps_mm"]
    n = len(edges)
    along = (-pos).tolist()                     # receptor position along the grating, mm from its left end

    # figures 4-9, 4-10: a few bars on the cylinder, all of them on the semi-infinite model
    t8, t16, tb = runs[l8]["touching"], runs[l16]["touching"], runs[block]["touching"]
    few = t8.max() <= n // 2 and tb.min() == n
    contact = Finding(
        "fig4-10_bars_in_contact", "4.5.2, figures 4-9 and 4-10", "Bars of a grating touching each model",
        "Indented 1 mm, only a few bars of an aperiodic grating touch the cylinder with bone, against all "
        "of them on the semi-infinite model, so the loads (total force, area) differ between the two.",
        "largest number of the 8 bars touching the 8 mm cylinder at once", None, float(t8.max()),
        REPRODUCED if few else DIFFERS,
        f"Over {len(pos)} grating positions 0.25 mm apart: {t8.min()}-{t8.max()} bars touch the 8 mm "
        f"cylinder (mean {t8.mean():.1f}), {t16.min()}-{t16.max()} the 16 mm one, and {tb.min()}-{tb.max()} "
        f"the semi-infinite block (judged: at most half the bars on the cylinder, all on the block). Force per "
        f"indentation: cylinder {runs[l8]['force'].min():.3g}-{runs[l8]['force'].max():.3g} N/mm over "
        f"{runs[l8]['width'].min():.2f}-{runs[l8]['width'].max():.2f} mm of contact, block "
        f"{runs[block]['force'].min():.3g}-{runs[block]['force'].max():.3g} N/mm over "
        f"{runs[block]['width'].min():.2f}-{runs[block]['width'].max():.2f} mm.",
        "receptor position along the grating [mm]", "bars touching",
        [Series(label, along, runs[label]["touching"].tolist(), "-") for _, label, _ in GRATING_MODELS], [])

    # figure 4-11: the receptor under one bar feels its neighbours across gaps under 1.5 mm
    under = {label: _under_bars(runs, label)[0] for _, label, _ in GRATING_MODELS}
    (r8, r16, rb), at = under.values(), _under_bars(runs, l8)[1]
    c8, _ = _under_bars(runs, l8, "max_compressive_strain")
    near = [k for k in range(n) if min(gaps[max(k - 1, 0):k + 1]) < 1.5]
    same, felt = float(np.max(np.abs(r8[-3:] - 1))), float(np.min(np.abs(r8[near] - 1)))
    rows = [{"bar_from_right": n - k, "gap_left_mm": float(gaps[k - 1]) if k else 0.0,
             "gap_right_mm": float(gaps[k]) if k < n - 1 else 0.0,
             **{f"SED {label}": float(r[k]) for label, r in under.items()},
             "max compressive strain 8 mm": float(c8[k])} for k in range(n)]
    neighbours = Finding(
        "fig4-11_neighbours", "4.5.2, figure 4-11", "Strain under a bar and its neighbours (8 mm model)",
        "On the 8 mm cylinder with bone the receptor's strain under a bar depends on the neighbouring bars "
        "when two or more touch: the three rightmost bars, with the largest gaps, give almost identical strain "
        "states; across gaps under 1.5 mm the neighbouring bars influence the receptor.",
        "largest difference of SED under the three rightmost bars from the rightmost's [%]", None, 100 * same,
        REPRODUCED if same <= 0.05 and felt > 0.10 else DIFFERS,
        "SED at the central receptor, 0.75 mm deep, with each bar centred over it, over the rightmost bar's "
        "(bars from the left, gaps " + ", ".join(f"{g:g}" for g in gaps) + " mm): "
        + ", ".join(f"{v:.3f}" for v in r8) + f". The three rightmost are within {100 * same:.1f} %; the "
        f"{len(near)} bars next to a gap under 1.5 mm are {100 * felt:.0f} % or more below (judged: within 5 % "
        f"and beyond 10 %). Max compressive strain: " + ", ".join(f"{v:.3f}" for v in c8) + ". The recorded "
        "SA-I profile of the figure is printed as a curve only and is not compared.",
        "receptor position along the grating [mm]", "SED at 0.75 mm / under the rightmost bar",
        [Series("8 mm cylinder with bone", along, (runs[l8]["sed_MPa"][:, CENTRE] / runs[l8]["sed_MPa"][at[-1], CENTRE]).tolist(), "-"),
         Series("bar centred over the receptor", edges.mean(axis=1).tolist(), r8.tolist(), "o")], rows)

    # figure 4-12 and 4.5.3: the 16 mm model reaches more bars
    second, last = at[-2], at[-1]
    bars8 = [np.flatnonzero(runs[l8]["bar_force"][i] > 0) for i in (last, second)]
    bars16 = [np.flatnonzero(runs[l16]["bar_force"][i] > 0) for i in (last, second)]
    reach = {R: float(np.sqrt(2 * R - 1)) for R in (4.0, 8.0)}    # half-chord of a 1 mm deep cap, mm
    more = bool(np.all(t16 >= t8) and len(bars16[1]) > len(bars8[1]))
    wider = Finding(
        "fig4-12_diameter", "4.5.2, figure 4-12", "More bars touch the 16 mm model",
        "With the second bar from the right over the centre, its neighbours also touch the 16 mm model but "
        "barely the 8 mm one; with the rightmost bar over the centre the loads are almost the same.",
        "mean number of bars touching over the sweep, 16 mm over 8 mm model", None, float(t16.mean() / t8.mean()),
        REPRODUCED if more else DIFFERS,
        f"Bars touching (numbered from the right as in the thesis), rightmost bar centred: 8 mm "
        f"{_from_right(bars8[0], n)}, 16 mm {_from_right(bars16[0], n)}; second bar centred: 8 mm "
        f"{_from_right(bars8[1], n)}, 16 mm {_from_right(bars16[1], n)}. The 16 mm model is touched by "
        f"{'at least as many bars at every position' if np.all(t16 >= t8) else 'fewer bars at some positions'} "
        f"(mean {t16.mean():.2f} against {t8.mean():.2f}). Of the second bar's neighbours only the one across "
        f"the {gaps[-2]:g} mm gap touches: an undeformed cylinder indented 1 mm is reached within {reach[4.0]:.2f} mm (8 mm) or "
        f"{reach[8.0]:.2f} mm (16 mm) of the centre, and the rightmost bar lies {gaps[-1]:g} mm beyond its "
        f"neighbour's edge on this grating (the thesis does not list its gaps).",
        "receptor position along the grating [mm]", "bars touching",
        [Series(label, along, runs[label]["touching"].tolist(), "-") for _, label, _ in GRATING_MODELS[:2]], [])

    d8, d16 = float(abs(r8[-2] - 1)), float(abs(r16[-2] - 1))
    rightmost = Finding(
        "sec4-5-3_rightmost_bars", "4.5.3, figures 4-13 and 4-14", "The two rightmost bars on the 16 mm model",
        "On the 16 mm model the responses to the two rightmost bars are not identical, as they were on the "
        "8 mm model (which improves the fit to the recorded profiles).",
        "SED difference under the two rightmost bars, 16 mm model [%]", None, 100 * d16,
        REPRODUCED if d16 > 0.05 and d8 <= 0.05 else DIFFERS,
        f"SED at the central receptor under the second bar from the right over that under the rightmost: "
        f"{r8[-2]:.3f} on the 8 mm and {r16[-2]:.3f} on the 16 mm model (judged: "
        f"more than 5 % apart on the 16 mm, within 5 % on the 8 mm). On this grating the 16 mm model's extra "
        f"contact is the third bar from the right, across the {gaps[-2]:g} mm gap, touching at {gaps[-2] + GRATING_BAR_MM / 2:g}-"
        f"{gaps[-2] + 1.5 * GRATING_BAR_MM:g} mm from the receptor, too far to change its SED by more than "
        f"{100 * d16:.1f} %; the rightmost bar's neighbour, {gaps[-1]:g} mm away, touches neither model. The fits "
        "to the recorded profiles are not run (recordings printed as curves only).",
        "receptor position along the grating [mm]", "SED at 0.75 mm / under the rightmost bar",
        [Series(label, along, (runs[label]["sed_MPa"][:, CENTRE] / runs[label]["sed_MPa"][last, CENTRE]).tolist(), "-")
         for _, label, _ in GRATING_MODELS[:2]], [])

    # figure 4-18: receptors off the centre see other spatial profiles on the cylinder only
    off = {(label, x): _off_centre(runs, label, x) for _, label, _ in GRATING_MODELS for x in (1.0, 2.0)}
    grows = off[l8, 1.0] < off[l8, 2.0] and off[l8, 1.0] > 2 * max(off[block, 1.0], off[block, 2.0])
    v = runs[l8]["sed_MPa"]
    shifted = [Series(f"receptor {x:g} mm off-centre, shifted", (x - pos).tolist(),
                      (v[:, np.flatnonzero(np.isclose(SITES_MM, x))[0]] / v[:, CENTRE].max()).tolist(), "--")
               for x in (1.0, 2.0)]
    spatial = Finding(
        "fig4-18_off_centre", "4.5.4, figure 4-18", "Spatial profiles of off-centre receptors",
        "On the cylinder with bone the spatial profiles of receptors 1 and 2 mm off the centre, shifted by "
        "their offset, differ from the central receptor's, the more the farther off; on a semi-infinite "
        "model they would be identical.",
        "RMS difference from the central SED profile, receptor 2 mm off-centre, 8 mm model (of its peak)",
        None, off[l8, 2.0], REPRODUCED if grows else DIFFERS,
        "RMS difference of the shifted profile from the central one, over the central peak, 1 and 2 mm "
        "off-centre: " + "; ".join(f"{label} {off[label, 1.0]:.3f}, {off[label, 2.0]:.3f}" for _, label, _ in
                                   GRATING_MODELS)
        + " (judged: growing with the offset on the 8 mm model and above twice the block's; a half-space, "
        "invariant under translation, would give 0).",
        "receptor position along the grating [mm]", "SED at 0.75 mm / central peak (8 mm model)",
        [Series("central receptor", along, (v[:, CENTRE] / v[:, CENTRE].max()).tolist(), "-")] + shifted,
        [{"model": label, "receptor_off_centre_mm": x, "rms_difference": d} for (label, x), d in off.items()])

    # 4.5.4: the central spatial profile against the semi-infinite model's
    a, b = runs[l8]["sed_MPa"], runs[block]["sed_MPa"]
    rms = lambda u, w: float(np.sqrt(np.mean((u / u.max() - w / w.max()) ** 2)))
    profile = rms(a[:, CENTRE], b[:, CENTRE])
    population = float(np.median([rms(a[i], b[i]) for i in range(len(pos))]))
    share = runs[block]["bar_force"][last] / runs[block]["force"][last]
    central = Finding(
        "sec4-5-4_central_profiles", "4.5.4 (figures 4-10 and 4-11)", "Central spatial profiles of cylinder and semi-infinite model",
        "Although a grating's strain field (population response) differs drastically between the cylindrical "
        "and the semi-infinite model, the spatial profiles at a central receptor are surprisingly similar: only "
        "loads within a region of influence around the receptor matter.",
        "RMS difference of the peak-normalised central SED profiles, 8 mm cylinder against semi-infinite block",
        None, profile, REPRODUCED if profile < population else DIFFERS,
        f"Central spatial profiles differ by {profile:.3f} (RMS of peak-normalised SED), the population "
        f"responses across the receptors within 3 mm by {population:.3f} (median over the positions): the "
        f"profiles are {'closer' if profile < population else 'no closer'} than the fields. SED under each bar "
        f"over the rightmost's: cylinder " + ", ".join(f"{x:.2f}" for x in r8) + "; block "
        + ", ".join(f"{x:.2f}" for x in rb) + ". Under prescribed depth all eight bars touch the block and "
        f"share the force like one wide flat punch: with the rightmost bar over the receptor it carries "
        f"{100 * share[-1]:.0f} % of the total, the leftmost {100 * share[0]:.0f} %, the inner ones "
        f"{100 * share[1:-1].min():.0f}-{100 * share[1:-1].max():.0f} %. How the bars share it is set by the "
        "whole grating, beyond a region of influence around the receptor. The thesis compares with Phillips and "
        "Johnson's half-space profiles, printed as curves only; its own semi-infinite model stands in here.",
        "receptor position along the grating [mm]", "SED at 0.75 mm / its peak",
        [Series(label, along, (runs[label]["sed_MPa"][:, CENTRE] / runs[label]["sed_MPa"][:, CENTRE].max()).tolist(), "-")
         for label in (l8, block)], [])
    return [contact, neighbours, wider, rightmost, spatial, central]


# ----------------------------------------------------------------------------- 4.5.5: gaps
def gap_detection(shop: Workshop) -> list[Finding]:
    """Thesis 4.5.5, figures 4-19 and 4-20: peaks of |shear strain| at 0.75 mm on both sides of the gap
    between two 2 mm bars (the bars of figure 4-19) indented 1 mm into the cylinder with bone."""
    from fem.receptors.probes import gap_analysis

    probe = _probe(shop.folder("cylinder8_bone"), sites_mm=np.round(np.arange(-3.5, 3.5001, 0.05), 3),
                   rigid_bone=True)
    gaps = np.array([0.25, 0.5, 0.75, 1.0, 1.5, 2.0, 3.0])
    rows, _ = gap_analysis(probe, 2.0, gaps)
    dist = np.array([r["interpeak_mm"] for r in rows])
    wide, narrow = gaps >= 1.0, gaps <= 0.5
    follows = float(np.max(np.abs(dist[wide] / gaps[wide] - 1)))
    levels = bool(np.all(dist[narrow] > gaps[narrow] + 0.2))
    slope = max(abs(r["slope_per_mm"]) for r in rows)
    return [Finding(
        "fig4-19_gaps", "4.5.5, figures 4-19 and 4-20", "Shear-strain peaks across a gap",
        "The distance between the peaks of shear strain at 0.75 mm on both sides of a gap is a cue for the gap: "
        "compared with human gap detection (d') it shows the same knee, and for narrow gaps a settling trend "
        "instead of the linear extrapolation of the psychophysical data.",
        "smallest inter-peak distance (at the narrowest gap, 0.25 mm) [mm]", None, float(dist[0]),
        REPRODUCED if follows <= 0.1 and levels else DIFFERS,
        "Inter-peak distance for gaps " + ", ".join(f"{g:g}" for g in gaps) + " mm: "
        + ", ".join(f"{x:.2f}" for x in dist) + f" mm. From 1 mm up it follows the gap within {100 * follows:.1f} %; "
        f"below, it levels off at {dist[narrow].min():.2f}-{dist[narrow].max():.2f} mm, about the receptor depth "
        f"(judged: within 10 %, and more than 0.2 mm wider than gaps of 0.5 mm or less). The knee lies between "
        f"gaps of 0.75 and 1 mm. The bars here are equal, so the line joining the peaks is flat (|slope| at most "
        f"{slope:.4f} per mm): the thesis's slope cue comes from unequal neighbours in its grating. The human d' "
        "data are printed as points on a figure only and are not compared.",
        "gap [mm]", "distance between the |shear strain| peaks [mm]",
        [Series("inter-peak distance", gaps.tolist(), dist.tolist()),
         Series("distance = gap", [0.0, 3.0], [0.0, 3.0], "k:")], rows)]


# ----------------------------------------------------------------------------- appendices A and B
def appendices(shop: Workshop) -> list[Finding]:
    """Appendix A: in plane strain with nu -> 0.5, SED = (2/3) E eps1^2; appendix B: under prescribed
    displacements a homogeneous model's strains do not depend on E. On the cylinder (no bone)."""
    from fem.io.modelfolder import held_regions, read_model

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
