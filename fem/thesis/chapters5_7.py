"""Thesis chapters 5-7 (the 3D models and their sections), claim by claim: each function takes a
`fem.thesis.findings.Workshop` and returns `Finding`s (fem.thesis.claims lists them in thesis order).
Units: mm, N, MPa.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fem.biomech.deflection import (
    DeflectionExperiment,
    cylinder_series,
    layer_study,
    side_profile,
)
from fem.biomech.line_load import compare_line_load
from fem.contact.indentors import STEP_HALF_WAVELENGTH_MM, make_indentor
from fem.contact.linear import ContactModel, reach
from fem.geometry.layered import model_from_args, params_for
from fem.geometry.mesh2d import section_domain
from fem.io.modelfolder import (
    CONTACT_REGION,
    approach_down,
    factorise,
    open_model,
    read_model,
)
from fem.receptors.grid import ReceptorGrid, ReceptorSampler
from fem.thesis.chapter4_receptors import BAR_WIDTH_MM
from fem.thesis.findings import Check, Finding, Series, Workshop
from fem.thesis.quotes import QUOTES


# ----------------------------------------------------------------------------- 6.2.1: dorsal half
def dorsal_ratios(model_dir, preset: str, depths_mm) -> list[tuple[float, float, float, float]]:
    """Per depth of a wedge perpendicular to the axis at the middle of the pad of a 3D preset model
    folder: (largest |u_y| on the outer surface below the section centroid, over all nodes with
    y < 0, on the proximal cut, on the distal cut), each over the largest |u_y| (the depth).
    preset: the 3D preset the folder was meshed from ('human' or 'monkey')."""
    model, system, region, _ = open_model(model_dir)
    cm = ContactModel.from_fe(model, system, region)
    z = cm.points_mm[:, 2]
    wedge = make_indentor("wedge", orientation="perpendicular", position_mm=(0.0, 0.5 * (z.min() + z.max())))
    sections = model_from_args(None, preset, params_for(preset))
    x, mesh = model.nodes, model.mesh
    bf = mesh.boundary_facets()
    surface = np.union1d(np.unique(mesh.facets[:, bf]), mesh.nvertices + np.unique(mesh.f2e[:, bf]))
    dorsal = surface[x[surface, 1] < np.interp(x[surface, 2], sections.z_mm, sections.centroids[:, 1])]
    rows = []
    for depth in depths_mm:
        res = cm.indent(wedge, depth_mm=depth)
        uy = np.abs(cm.compliance(wedge.approach).displacement(res.force_N).reshape(-1, 3)[:, 1])
        rows.append(tuple(float(uy[nodes].max() / uy.max()) for nodes in
                          (dorsal, x[:, 1] < 0, model.region_nodes("proximal"), model.region_nodes("distal"))))
    return rows


def dorsal_half(shop: Workshop) -> list[Finding]:
    """Thesis 6.2.1 (figure 6-5, the monkey) and 6.2.2 (of figure 6-7, the human): under a 2 mm
    line load the dorsal half and the proximal end move vertically less than 10 % of the maximum
    (3D presets; the monkey also at 1 mm depth)."""
    rows = {preset: dorsal_ratios(shop.preset(preset), preset, [1.0, 2.0]) for preset in ("monkey", "human")}
    (m1, _, _, _), (m2, _, m_prox, _) = rows["monkey"]
    _, (h2, _, h_prox, _) = rows["human"]
    table = [{"preset": p, "depth_mm": d, "dorsal_surface": r[0], "below_axis": r[1], "proximal_cut": r[2],
              "distal_cut": r[3]} for p, rr in rows.items() for d, r in zip((1.0, 2.0), rr)]
    band = "'less than 10% of the maximum deformations' read as of the largest vertical displacement"
    return [Finding(
        "sec6-2-1_dorsal", "6.2.1, figure 6-5 (monkey); 6.2.2 (human, of figure 6-7)", "Dorsal half under a 2 mm line load",
        QUOTES["sec6-2-1_dorsal"],
        [Check("largest dorsal-surface |u_y| over the largest |u_y|, 2 mm deep, monkey preset", 100 * m2, "<", 10.0, "%",
               why=band),
         Check("the same on the proximal cut, monkey preset", 100 * m_prox, "<", 10.0, "%", why="'and the proximal end'"),
         Check("largest dorsal-surface |u_y| over the largest |u_y|, 2 mm deep, human preset", 100 * h2, "<", 10.0, "%",
               why="6.2.2 states the same bound for the human under a line load"),
         Check("the same on the proximal cut, human preset", 100 * h_prox, "<", 10.0, "%")],
        f"A wedge across the finger at the middle of the pad, m43338. The monkey's dorsal surface moves "
        f"{100 * m1:.1f} % at 1 mm deep. The thesis's model rested on a table that held its dorsal nodes vertically "
        "where the finger touched it; the presets here hold the nail and the proximal cut's core "
        "(fem.io.modelfolder.HELD).",
        "depth [mm]", "dorsal |u_y| / max |u_y|",
        [Series(p, [1.0, 2.0], [r[0] for r in rr]) for p, rr in rows.items()] +
        [Series("thesis bound", [1.0, 2.0], [0.1, 0.1], "k:")], table)]


# ----------------------------------------------------------------------------- 6.2.1: layers (fig. 6-10)
LAYER2_CODES = ("m42338", "m44338")      # layer 2 tenfold softer and stiffer than m43338
THIN_SKIN_MM = (0.25, 0.25)              # epidermis, dermis of the thin-skin section
THIN_LABEL = f"2D section, skin {THIN_SKIN_MM[0]:g} + {THIN_SKIN_MM[1]:g} mm"


def layer2_change(lo, hi, reach_mm: float = 3.0) -> tuple[float, list[float]]:
    """(deflection change 0.5 mm from the load [mm], distances where it changes sign [mm]) when
    layer 2 is stiffened: lo, hi map distances [mm] to deflections [mm] (softer, stiffer);
    (nan, []) where either is not finite (a solve that did not reach the depth)."""
    d = np.linspace(0.05, reach_mm, 296)
    diff = hi(d) - lo(d)
    if not np.all(np.isfinite(diff)):
        return float("nan"), []
    flips = np.flatnonzero(np.sign(diff[1:]) != np.sign(diff[:-1]))
    return float(hi(np.array([0.5]))[0] - lo(np.array([0.5]))[0]), \
        [float(d[i] - diff[i] * (d[i + 1] - d[i]) / (diff[i + 1] - diff[i])) for i in flips]


def _line_profile(folder, code: str, large_deformation: bool):
    """distance [mm] -> deflection [mm] under a prescribed nodal line 2 mm deep (the surface
    vertex at the section's centre pushed down and held sideways; both sides averaged)."""
    c = compare_line_load(folder, depths_mm=(2.0,), material=code, large_deformation=large_deformation)
    d, w = side_profile(c.distance_mm, (c.deflection_nonlinear_mm if large_deformation else c.deflection_linear_mm)[0])
    return lambda x: np.interp(x, d, w)


def monkey_section(z_mm: float, **skin):
    """fem.geometry.mesh2d.Domain2D: the monkey preset's five-layer cross-section at z_mm; skin: optional
    epidermis_mm, dermis_mm (default thesis 6.1's 0.5 and 1.0 mm)."""
    return section_domain(model_from_args(None, "monkey", params_for("monkey", **skin)), z_mm)


def layer2_reasons(shop: Workshop) -> dict:
    """{case: layer2_change} of the candidate reasons on the monkey section at z = 5 mm: the
    thesis's prescribed nodal line instead of the wedge (linear, and neo-Hookean on elements of at
    least 0.25 mm: a node pushed 2 mm into 0.125 mm elements inverts them before the depth), and a
    thin skin (THIN_SKIN_MM) under the wedge."""
    out = {"2D section, nodal line": layer2_change(
        *(_line_profile(shop.folder("monkey_section", monkey_section(5.0)), code, False) for code in LAYER2_CODES))}
    coarse = shop.folder("monkey_section", monkey_section(5.0), size_mm=max(0.25, shop.size_mm))
    out["2D section, nodal line, neo-Hookean"] = layer2_change(
        *(_line_profile(coarse, code, True) for code in LAYER2_CODES))
    epi, der = THIN_SKIN_MM
    thin = shop.folder(f"monkey_section_skin{epi:g}+{der:g}", monkey_section(5.0, epidermis_mm=epi, dermis_mm=der))
    exp = DeflectionExperiment(thin, progress=shop.progress)
    out[THIN_LABEL] = layer2_change(*(exp.profiles(code, (2.0,))[0].at for code in LAYER2_CODES))
    return out


def layer_effects(shop: Workshop) -> list[Finding]:
    """Thesis 6.2.1, figure 6-10: vary each layer's modulus tenfold around m43338 under a 2 mm line
    load (a wedge across the finger), on the 3D monkey preset and on its five-layer cross-section
    at z = 5 mm (2D, plane strain). Layer 2's sense is then measured on the section under the
    thesis's load (a prescribed nodal line, linear and neo-Hookean) and with a thinner skin."""
    folders = {"3D monkey": shop.preset("monkey"), "2D section": shop.folder("monkey_section", monkey_section(5.0))}
    d = np.linspace(0.0, 3.5, 36)
    series, table, change, eff = [], [], {}, {}
    for label, folder in folders.items():
        study = layer_study(DeflectionExperiment(folder, progress=shop.progress), "m43338", depths_mm=(2.0,))
        eff[label] = {e.layer: e for e in study.effects}
        lo, hi = (study.profiles[code][0] for code in LAYER2_CODES)
        change[label] = layer2_change(lo.at, hi.at)
        series += [Series(f"{label}, {code}", d.tolist(), study.profiles[code][0].at(d).tolist(),
                          "-" if label.startswith("3D") else "--") for code in study.layers[2]]
        table += [{"model": label, "layer": e.layer, "codes": " ".join(e.codes), "most_affected_mm": e.most_affected_mm,
                   "difference_mm": e.difference_mm, "neutral_mm": " ".join(f"{v:.2f}" for v in e.neutral_mm)}
                  for e in study.effects]
    change.update(layer2_reasons(shop))
    table += [{"model": k, "layer": 2, "codes": " ".join(LAYER2_CODES), "change_at_0.5mm": v[0],
               "neutral_mm": " ".join(f"{x:.2f}" for x in v[1])} for k, v in change.items()]
    near, flips = change["3D monkey"]
    sense = {k: "the solve did not reach 2 mm" if np.isnan(v[0]) else
             f"{v[0]:+.3f} mm, sign change at {', '.join(f'{x:.2f}' for x in v[1]) or 'none'} mm"
             for k, v in change.items()}
    e3, e2 = eff["3D monkey"], eff["2D section"]

    def candidate(label, what):         # a candidate reason turns the sense the 3D model gives
        if np.isnan(change[label][0]):
            return f"{what}: not measured ({sense[label]})"
        kept = np.sign(change[label][0]) == np.sign(near)
        return f"{what}: {sense[label]}, {'the same sense' if kept else 'the thesis sense'}"
    epi, der = THIN_SKIN_MM
    return [Finding(
        "fig6-10_layers", "6.2.1, figure 6-10", "Effect of each layer's stiffness on the line-load profile",
        QUOTES["fig6-10_layers"],
        [Check("deflection change 0.5 mm from the load when layer 2 is stiffened, 3D monkey", near, ">", 0.0, "mm",
               why="'a decrease in stiffness' near the load: more deflection"),
         Check("distance where stiffening layer 2 changes the sign of its effect, 3D monkey", flips[0] if flips else
               float("nan"), "~", 1.25, "mm", tol=0.25, why="'about 1.25 mm'"),
         Check("distance most affected by layer 3's modulus, 3D monkey", e3[3].most_affected_mm, "~", 1.3, "mm",
               tol=0.25, why="'around 1.3 mm'"),
         Check("distance most affected by layer 4's modulus, 3D monkey", e3[4].most_affected_mm, "~", 2.0, "mm",
               tol=0.25, why="'approximately around 2.0 mm'")],
        f"A wedge 2 mm deep across the 3D monkey and its plane-strain section at z = 5 mm (epidermis 0.5, dermis "
        f"1.0 mm, thesis 6.1); layer 2 from {LAYER2_CODES[0]} to {LAYER2_CODES[1]} (the thesis gives no base model for "
        f"it). Change 0.5 mm from the load and where it changes sign: 3D {sense['3D monkey']}; "
        f"{candidate('2D section', 'plane-strain section')}; "
        f"{candidate('2D section, nodal line', 'the section under a prescribed nodal line')}; "
        f"{candidate('2D section, nodal line, neo-Hookean', 'the same line, neo-Hookean (large deformation)')}; "
        f"{candidate(THIN_LABEL, f'a {epi:g} mm epidermis and {der:g} mm dermis')}. Layers 3 and 4 on the section: "
        f"most affected at {e2[3].most_affected_mm:.2f} and {e2[4].most_affected_mm:.2f} mm.",
        "distance from the load [mm]", "surface deflection [mm]", series, table)]


# ----------------------------------------------------------------------------- 3D indentation helpers
@dataclass
class Indentation3D:
    """One indentation of a 3D model folder: the model, the placed indentor, its contact model,
    the result and the displacement (ndof,) mm."""
    model: object
    indentor: object
    contact: object
    result: object
    u: np.ndarray

    def first_touch_z_mm(self) -> float:
        """z of the contact candidate the indentor touches first, pushed the full depth [mm]."""
        return float(self.contact.points_mm[np.argmin(self.indentor.standoff(self.contact.points_mm)), 2])

    def line_force_N_per_mm(self, z_mm: float, half_width_mm: float = 0.75) -> float:
        """Contact force on the candidates within half_width_mm of the plane z = z_mm, per mm of z."""
        near = np.abs(self.contact.points_mm[:, 2] - z_mm) <= half_width_mm
        return float(self.result.force_N[near].sum() / (2 * half_width_mm))


def indent_3d(folder, material: str, indentor: str, depth_mm: float, **place) -> Indentation3D:
    """`indentor` (a fem.contact.indentors code) `depth_mm` beyond first touch into a 3D model folder with
    `material`, placed by `place` (fem.contact.indentors.place; default approach: the folder's support,
    default position: x = 0 at the middle of the pad);
    only the candidates it can reach are condensed."""
    model, info = read_model(folder, material=material)
    sn = model.surface_nodes(CONTACT_REGION[3])
    place.setdefault("approach", list(approach_down(info)))
    place.setdefault("position_mm", (0.0, 0.5 * (sn.x[:, 2].min() + sn.x[:, 2].max())))   # middle of the pad
    ind = make_indentor(indentor, **place)
    near = reach(sn.x, ind, np.zeros((1, 3)), depth_mm)
    cm = ContactModel.from_fe(model, factorise(model, info, sn.nodes[near]), CONTACT_REGION[3])
    res = cm.indent(ind, depth_mm=depth_mm)
    return Indentation3D(model, ind, cm, res, cm.compliance(ind.approach).displacement(res.force_N))


def section_receptors(section, x_mm, depth_mm: float, z_mm: float | None = None):
    """fem.receptors.grid.ReceptorGrid of points `depth_mm` below the volar outer curve of a section
    (fem.geometry.mesh2d.section_domain) at x_mm (k,), along the curve's inward normal; in the section's
    plane (2D) or, with z_mm, at that z of the 3D model."""
    x = np.asarray(x_mm, float)
    ring = section.curves[0]
    upper = ring[ring[:, 1] > section.params["centroid_mm"][1]]
    upper = upper[np.argsort(upper[:, 0])]
    y = np.interp(x, upper[:, 0], upper[:, 1])
    normal = np.column_stack([-np.gradient(y, x), np.ones_like(x)])
    normal /= np.linalg.norm(normal, axis=1)[:, None]
    sites = np.column_stack([x, y])
    if z_mm is not None:
        sites, normal = (np.column_stack([a, np.full(len(x), b)]) for a, b in ((sites, z_mm), (normal, 0.0)))
    return ReceptorGrid(sites - depth_mm * normal, np.full(len(x), float(depth_mm)), np.arange(len(x)), sites)


def sample(model, u, grid, names=("sed_MPa", "max_compressive_strain")) -> dict:
    """{measure: (n,)} of displacement u (ndof,) at a receptor grid's points."""
    s = ReceptorSampler(model, grid)
    return s.measures(s.operator @ u, list(names))


def _section_cells(shop: Workshop, name: str, section):
    """(centroids (m, 2) mm, areas (m,) mm^2) of the triangles of a section's 2D mesh."""
    model, _ = read_model(shop.folder(name, section))
    p, t = model.mesh.p, model.mesh.t[:3]
    a, b, c = (p[:, t[k]] for k in range(3))
    area = 0.5 * np.abs((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))
    return ((a + b + c) / 3).T, area


BAR_DEPTH_MM = 1.0
"""Thesis 6.3.1 and 7.1: the bar (BAR_WIDTH_MM, as in 4.4) along the finger axis, 1 mm beyond first touch."""
PROFILE_X_MM = np.linspace(-3.0, 3.0, 61)
SURFACE_MM = 0.05
"""Depth at which surface deflections are sampled (inside the mesh, whose surface strays 0.02 mm)."""


# ----------------------------------------------------------------------------- 6.3.1, 7.1.2: bars in 3D
def bars_3d(shop: Workshop) -> list[Finding]:
    """Thesis 6.3.1 (figure 6-25) and 7.1.2 (figure 7-4): the 1.5 mm bar 1 mm into the 3D monkey
    model, homogeneous-skin m33338 against the stiff-epidermis m43338: strain energy density at
    0.75 and 1.0 mm below the surface, how much of the cross-section it reaches, contact width."""
    folder = shop.preset("monkey")
    runs = {m: indent_3d(folder, m, f"bar:{BAR_WIDTH_MM}", BAR_DEPTH_MM, orientation="parallel")
            for m in shop.progress.bar(("m33338", "m43338"), desc="3D bar", unit="material")}
    z0 = runs["m33338"].first_touch_z_mm()
    section = monkey_section(z0)
    centroids, area = _section_cells(shop, f"monkey_section_z{z0:.2f}", section)
    cells = _cell_grid(centroids, z0)
    rows, series, fraction, peak, outside, cumulative, surface = [], [], {}, {}, {}, [], []
    edge = 0.5 * BAR_WIDTH_MM + 1.0          # 1 mm beyond the bar's edges
    levels = np.linspace(0.0, 0.5, 51)
    for m, run in runs.items():
        for d in (0.75, 1.0):
            sed = sample(run.model, run.u, section_receptors(section, PROFILE_X_MM, d, z0))["sed_MPa"]
            peak[(m, d)] = float(sed.max())
            series.append(Series(f"{m}, {d} mm deep", PROFILE_X_MM.tolist(), sed.tolist(),
                                 "-" if d == 0.75 else "--"))
        skin = section_receptors(section, np.r_[PROFILE_X_MM, -edge, edge], SURFACE_MM, z0)
        v = -sample(run.model, run.u, skin, ("displacement_y_mm",))["displacement_y_mm"]
        outside[m] = float(v[-2:].mean())
        surface.append(Series(m, PROFILE_X_MM.tolist(), v[:-2].tolist()))
        sed = sample(run.model, run.u, cells, ("sed_MPa",))["sed_MPa"]
        fraction[m] = float(area[sed < 0.1 * sed.max()].sum() / area.sum())
        below = [float(area[sed < t * sed.max()].sum() / area.sum()) for t in levels]
        cumulative.append(Series(m, levels.tolist(), below))
        rows.append({"material": m, "sed_peak_0.75mm_MPa": peak[(m, 0.75)], "sed_peak_1.0mm_MPa": peak[(m, 1.0)],
                     "section_below_10pct": fraction[m], "deflection_1mm_outside_mm": outside[m],
                     "contact_area_mm2": run.result.contact_area_mm2, "force_N": run.result.total_force_N})
    deeper = {m: peak[(m, 1.0)] / peak[(m, 0.75)] for m in runs}
    touched = {m: (run.result.contact_area_mm2, run.contact.edge_area_mm2(run.result)) for m, run in runs.items()}
    wider = touched["m43338"][0] / touched["m33338"][0]
    wider_resolution = wider * sum(edge / a for a, edge in touched.values())    # each area within its edge nodes'
    spread = outside["m43338"] / outside["m33338"]
    epidermis = params_for("monkey").epidermis_mm
    return [Finding(
        "fig6-25_bar_depth", "6.3.1, figure 6-25", "Strain energy density below a bar, 0.75 against 1.0 mm deep",
        QUOTES["fig6-25_bar_depth"],
        [Check("peak SED 1.0 mm deep over 0.75 mm deep, m43338, section through the first touch", deeper["m43338"],
               ">", 1.0, why="'higher magnitudes of strains at a depth of 1.0 mm'")],
        f"Homogeneous skin m33338: {deeper['m33338']:.3f} ({'higher' if deeper['m33338'] > 1 else 'lower'} at "
        f"1.0 mm). Section z = {z0:.2f} mm, through the point the bar touched first; the epidermis (layer 1) is "
        f"{epidermis:g} mm thick, so both depths lie below it.",
        "x across the pad [mm]", "strain energy density [MPa]", series, rows),
        Finding(
        "fig7-4_local", "7.1.2, figure 7-4", "How much of the cross-section a bar reaches", QUOTES["fig7-4_local"],
        [Check(f"fraction of the section area with SED below 10 % of its maximum, {m}", 100 * fraction[m], "~", 85.0,
               "%", tol=5.0, why="'(85%)' read as 80-90 %") for m in ("m33338", "m43338")],
        f"Section z = {z0:.2f} mm, sampled at the {len(area)} triangle centroids of its 2D mesh.",
        "threshold, fraction of the maximum SED", "fraction of the section below it", cumulative, rows),
        Finding(
        "sec7-1-2_gradual", "7.1.2, figure 7-4", "Surface deformation beside a bar, homogeneous against stiff epidermis",
        QUOTES["sec7-1-2_gradual"],
        [Check("surface deflection 1 mm beyond the bar's edges, m43338 over m33338", spread, ">", 1.0,
               why="'more gradual' read as more deflection beside the bar"),
         Check("contact area, m43338 over m33338", wider, ">", 1.0, resolution=wider_resolution,
               why="'a wider area of contact'")],
        f"Deflection 1 mm outside the bar: m43338 {outside['m43338']:.3f} mm, m33338 {outside['m33338']:.3f} mm "
        f"(section z = {z0:.2f} mm); contact areas {touched['m43338'][0]:.2f} and {touched['m33338'][0]:.2f} mm^2, "
        f"each known to within its edge nodes' area ({touched['m43338'][1]:.2f} and {touched['m33338'][1]:.2f} "
        f"mm^2).",
        "x across the pad [mm]", "surface deflection [mm]", surface, rows)]


def _cell_grid(centroids, z_mm: float):
    """ReceptorGrid at the section's cell centroids (m, 2) placed at z_mm of the 3D model (no
    depth: nothing is moved off a layer interface)."""
    pts = np.column_stack([centroids, np.full(len(centroids), z_mm)])
    return ReceptorGrid(pts, np.zeros(len(pts)), np.arange(len(pts)), pts)


# ----------------------------------------------------------------------------- 7.1.1: 2D section against 3D
def sections_2d_3d(shop: Workshop) -> list[Finding]:
    """Thesis 7.1.1 (figures 7-2, 7-3): the 1.5 mm bar 1 mm into the 3D monkey model (m33338)
    against the same bar on the plane-strain section of the model through the point it touched first, and
    a section 2 mm from it. Receptors 0.75 mm below the surface."""
    folder = shop.preset("monkey")
    run = indent_3d(folder, "m33338", f"bar:{BAR_WIDTH_MM}", BAR_DEPTH_MM, orientation="parallel")
    z = run.contact.points_mm[:, 2]
    z0 = run.first_touch_z_mm()
    z1 = max(z0 - 2.0, z.min() + 1.0)
    name = f"monkey_section_z{z0:.2f}"
    section = monkey_section(z0)
    shop.folder(name, section)
    cm2, model2 = shop.contact_model(name, "m33338")
    bar = make_indentor(f"bar:{BAR_WIDTH_MM}")
    res2 = cm2.indent(bar, depth_mm=BAR_DEPTH_MM)
    u2 = cm2.compliance(bar.approach).displacement(res2.force_N)
    x = PROFILE_X_MM
    two = sample(model2, u2, section_receptors(section, x, 0.75))
    three = sample(run.model, run.u, section_receptors(section, x, 0.75, z0))
    off = sample(run.model, run.u, section_receptors(monkey_section(z1), x, 0.75, z1))
    eps = {k: np.abs(v["max_compressive_strain"]) for k, v in (("2D", two), ("3D", three), ("off", off))}
    sed = {k: v["sed_MPa"] for k, v in (("2D", two), ("3D", three), ("off", off))}
    eps_ratio = float(eps["3D"].max() / eps["2D"].max())
    sed_ratio = float(sed["2D"].max() / sed["3D"].max())
    form = float(np.corrcoef(eps["3D"], eps["2D"])[0, 1])
    f3, f2 = run.line_force_N_per_mm(z0), res2.total_force_N
    rows = [{"model": k, "eps1_peak": float(eps[k].max()), "sed_peak_MPa": float(sed[k].max())}
            for k in ("2D", "3D", "off")]
    labels = {"2D": "2D section (plane strain)", "3D": f"3D, section z = {z0:.2f} mm", "off": f"3D, z = {z1:.2f} mm"}
    style = {"2D": "--", "3D": "-", "off": ":"}
    nu = float(run.model.material.nu[1])
    plane = 1.0 / (1.0 - nu**2)          # plane strain: modulus E / (1 - nu^2) against E
    force = (f"The bar 1 mm beyond first touch, m33338. The 2D model here is the plane-strain section of the 3D "
             f"model through the first touch (the thesis's 2D model is its round cylinder). The sections carry "
             f"{f3:.2e} (3D, contact forces within 0.75 mm of it) and {f2:.2e} N/mm (plane strain): "
             f"{100 * (f3 / f2 - 1):+.0f} %; under the same load plane strain's modulus E / (1 - nu^2) lowers strains "
             f"by 1 / {plane:.2f} at nu = {nu:g}.")
    return [Finding(
        "fig7-2_eps1", "7.1.1, figure 7-2", "Maximum compressive strain, 2D section against 3D", QUOTES["fig7-2_eps1"],
        [Check("correlation of the 2D and 3D max compressive strain profiles at 0.75 mm", form, ">", 0.95,
               why="'approximately equal in ... form'"),
         Check("peak max compressive strain at 0.75 mm, 3D over 2D", eps_ratio, "~", 1.075, tol=0.075,
               why="'slightly higher' in 3D read as 1 to 1.15 times")],
        force + f" 3D / 2D peak strain {eps_ratio:.2f} against the plane-strain factor times the load ratio, "
        f"{plane * f3 / f2:.2f}.",
        "x across the pad [mm]", "max compressive strain at 0.75 mm",
        [Series(labels[k], x.tolist(), eps[k].tolist(), style[k]) for k in eps], rows),
        Finding(
        "fig7-2_sed", "7.1.1, figure 7-2", "Strain energy density, 2D section against 3D", QUOTES["fig7-2_sed"],
        [Check("peak SED at 0.75 mm, 2D over 3D", sed_ratio, ">", 1.0, why="'the 2D model being stiffer predicts a "
               "higher strain energy density'")],
        force, "x across the pad [mm]", "SED at 0.75 mm [MPa]",
        [Series(labels[k], x.tolist(), sed[k].tolist(), style[k]) for k in sed], rows),
        Finding(
        "fig7-3_off_centre", "7.1.1, figure 7-3", "A 3D section away from the most indented point",
        QUOTES["fig7-3_off_centre"],
        [Check("peak SED at 0.75 mm, off-centre over central section", float(sed["off"].max() / sed["3D"].max()),
               "<", 1.0, why="'all the strain measures in this cross-section are lower'"),
         Check("peak max compressive strain at 0.75 mm, off-centre over central section",
               float(eps["off"].max() / eps["3D"].max()), "<", 1.0)],
        f"Section z = {z1:.2f} mm against z = {z0:.2f} mm ({z0 - z1:.2f} mm apart); peak SED {sed['off'].max():.2e} "
        f"against {sed['3D'].max():.2e} MPa.", "x across the pad [mm]", "SED at 0.75 mm [MPa]",
        [Series(labels[k], x.tolist(), sed[k].tolist(), style[k]) for k in ("3D", "off")], rows)]


# ----------------------------------------------------------------------------- 5.2, 6.3.2: contact against diameter
def _rank_correlation(a, b) -> float:
    """Spearman rank correlation of two (k,) arrays."""
    ra, rb = (np.argsort(np.argsort(v)) for v in (a, b))
    return float(np.corrcoef(ra, rb)[0, 1])


def _rank_resolution(a, a_resolution, b, draws: int = 256) -> float:
    """Largest change of the rank correlation of a (k,) with b (k,) when each a moves uniformly
    within +- its resolution (seeded draws): what node-counted areas cannot tell apart."""
    rng = np.random.default_rng(0)
    base = _rank_correlation(a, b)
    moved = a + rng.uniform(-1.0, 1.0, (draws, len(a))) * a_resolution
    return float(max(abs(_rank_correlation(m, b) - base) for m in moved))


def _extreme_spread(x, a, a_resolution, k: int) -> float:
    """Farthest position [mm] from x[k] whose node-counted area a cannot be told from a[k]'s (the
    two differ by less than their resolutions together): how far the extreme at k may lie."""
    same = np.abs(a - a[k]) <= a_resolution + a_resolution[k]
    return float(np.abs(x[same] - x[k]).max())


def contact_vs_diameter(shop: Workshop) -> list[Finding]:
    """Thesis 6.3.2 (figure 6-30): cylinders C1-C8 across the 3D monkey pad at constant force (the
    force taking C4 1 mm deep): contact radius up, peak pressure down with the cylinder's radius.
    Thesis 5.2.3 (figure 5-14, in vivo human fingertips): at the smaller depths the contact area
    varies linearly with the cylinder's diameter; on the 3D human preset."""
    def experiment(folder):          # 3D default placement: across the finger, middle of the pad
        return DeflectionExperiment(folder, indentor="cylinder:C4", progress=shop.progress)

    monkey = experiment(shop.preset("monkey"))
    force = float(cylinder_series(monkey, "m43338", codes=["C4"], depths_mm=[1.0]).force_N[0, 0])
    at_force = cylinder_series(monkey, "m43338", forces_N=[force])
    radius = np.sqrt(at_force.contact_area_mm2[0] / np.pi)
    pressure = at_force.max_pressure_MPa[0]
    R = at_force.diameters_mm / 2
    r_up, p_down = _rank_correlation(R, radius), _rank_correlation(R, pressure)
    human_depths = (0.5, 1.0, 2.0)
    human = cylinder_series(experiment(shop.preset("human")), "m43338", depths_mm=list(human_depths))
    D = human.diameters_mm
    fits = []
    for k in range(len(human_depths)):
        area = human.contact_area_mm2[k]
        resid = area - np.polyval(np.polyfit(D, area, 1), D)
        fits.append(float(np.sqrt(np.mean(resid**2)) / np.mean(area)))
    rises = int(np.sum(np.diff(pressure) >= 0))
    rows_m = [{"cylinder": c, "radius_mm": float(R[i]), "contact_radius_mm": float(radius[i]),
               "max_pressure_kPa": 1e3 * float(pressure[i]), "depth_mm": float(at_force.depth_mm[0, i])}
              for i, c in enumerate(at_force.codes)]
    rows_h = [{"cylinder": c, "diameter_mm": float(D[i]),
               **{f"area_{d:g}mm_mm2": float(human.contact_area_mm2[k, i]) for k, d in enumerate(human_depths)}}
              for i, c in enumerate(human.codes)]
    series = [Series("contact radius [mm]", R.tolist(), radius.tolist()),
              Series("peak pressure [kPa]", R.tolist(), (1e3 * pressure).tolist(), "--s", axis=1)]
    at = (f"At {1e3 * force:.2f} mN (the force taking C4 1 mm deep, m43338, across the pad; the thesis does not "
          f"state its force): contact radius {radius[0]:.2f} mm (C1) to {radius[-1]:.2f} mm (C8), rank correlation "
          f"with the cylinder radius {r_up:+.2f}; peak pressure {1e3 * pressure[0]:.2f} to {1e3 * pressure[-1]:.2f} kPa, "
          f"rank correlation {p_down:+.2f}.")
    contact = [Finding(
        f"fig6-30_contact_{name}", "6.3.2, figure 6-30", "Contact radius and peak pressure against cylinder radius (3D monkey)",
        QUOTES["fig6-30_contact"], [check], at, "cylinder radius [mm]", "equivalent contact radius [mm]", series,
        rows_m, logx=True, y2label="peak pressure [kPa]", reading=how)
        for name, check, how in (
            ("trend", Check("rank correlation of peak pressure with cylinder radius, C1-C8", p_down, "<", -0.9),
             "'the maximum pressure also reduces with increase in radius' as a trend over C1-C8"),
            ("every_step", Check("cylinders C2-C8 whose peak pressure is not below the next smaller one's", rises, "<",
                                 0.5, why="none"), "'reduces with increase in radius' from every cylinder to the next"))]
    return [Finding(
        "fig5-14_area", "5.2.3, figure 5-14 (in vivo)", "Contact area against cylinder diameter at fixed depths (3D human)",
        QUOTES["fig5-14_area"],
        [Check(f"RMS deviation of the contact area from a straight line in the diameter, {human_depths[0]:g} mm deep, "
               "over the mean area", 100 * fits[0], "<", 10.0, "%", why="'varies linearly' (with an offset) at the "
               "smallest depth")],
        "Deviation from a straight line " + ", ".join(f"{100 * f:.1f} % at {d:g} mm" for f, d in zip(fits, human_depths))
        + ". The thesis states this of its in vivo measurements (one subject, printed as curves only) and runs no "
        "model for it; the 3D human preset's trend is compared with it.", "cylinder diameter [mm]", "contact area [mm^2]",
        [Series(f"{d:g} mm deep", D.tolist(), human.contact_area_mm2[k].tolist()) for k, d in enumerate(human_depths)],
        rows_h), *contact]


# ----------------------------------------------------------------------------- 6.3.3: step shapes
STEP_DEPTH_MM = 0.5
"""Depth of the step's lower flat alone in the pad that sets the constant force of the sweep."""


def steps_3d(shop: Workshop) -> list[Finding]:
    """Thesis 6.3.3 (figure 6-39): step 5 (a 0.5 mm half-sinusoid rise over 3.134 mm, its edge
    along the finger) stepped across the 3D monkey pad at constant force (the force taking the
    step's lower flat STEP_DEPTH_MM deep, m43338): contact area against peak pressure at each position."""
    model, info = read_model(shop.preset("monkey"), material="m43338")
    sn = model.surface_nodes(CONTACT_REGION[3])
    L = STEP_HALF_WAVELENGTH_MM[5]
    z_mid = 0.5 * (sn.x[:, 2].min() + sn.x[:, 2].max())
    positions = np.arange(-L - 3.0, 3.0 + 1e-9, 0.5 if shop.quick else 0.25)
    down = approach_down(info)
    steps = [make_indentor("step:5", orientation="parallel", position_mm=(float(x), z_mid), approach=list(down))
             for x in positions]
    near = np.zeros(len(sn.nodes), bool)
    for ind in steps:
        near |= reach(sn.x, ind, np.zeros((1, 3)), 2 * STEP_DEPTH_MM)
    receptors_x = np.arange(-2.5, 2.5 + 1e-9, 0.25)       # the population: 0.75 mm deep across the section z_mid
    sampler = ReceptorSampler(model, section_receptors(monkey_section(z_mid), receptors_x, 0.75, z_mid))
    cm = ContactModel.from_fe(model, factorise(model, info, sn.nodes[near], shop.progress), CONTACT_REGION[3],
                              observe=sampler.operator)
    force = cm.indent(steps[-1], depth_mm=STEP_DEPTH_MM).total_force_N    # the lower flat alone under the pad
    results = [cm.indent(ind, force_N=force)
               for ind in shop.progress.bar(steps, desc="step 5 across the pad", unit="position")]
    area = np.array([r.contact_area_mm2 for r in results])
    area_resolution = np.array([cm.edge_area_mm2(r) for r in results])
    pressure = np.array([1e3 * r.max_pressure_MPa for r in results])
    # where on the step it peaks
    at_v = [float(cm.points_mm[np.argmax(r.pressure_MPa), 0] - x) for r, x in zip(results, positions)]
    sed = np.array([sampler.measures(r.observed, ["sed_MPa"])["sed_MPa"] for r in results])   # (positions, receptors)
    rho = _rank_correlation(area, pressure)
    rho_resolution = _rank_resolution(area, area_resolution, pressure)
    opposite = float(100 * np.mean(np.sign(np.diff(area)) * np.sign(np.diff(pressure)) < 0))
    # the pad's top, from the model's geometry: the point of the section's outer curve farthest against the
    # approach; the datum puts it over the rise's convex half (v in [0, L/2]) for datums in [x_top - L/2,
    # x_top] and over its concave half for datums in [x_top - L, x_top - L/2]
    ring = monkey_section(z_mid).curves[0]
    x_top = float(ring[np.argmax(ring @ -np.asarray(down, float)[:2]), 0])
    step = float(positions[1] - positions[0])
    x_min, x_max = float(positions[np.argmin(area)]), float(positions[np.argmax(area)])
    k = int(np.argmax(pressure))
    rows = [{"step_position_mm": float(x), "contact_area_mm2": float(a), "max_pressure_kPa": float(p),
             "peak_at_v_mm": v} for x, a, p, v in zip(positions, area, pressure, at_v)]
    where = (f"{len(positions)} positions {step:g} mm apart at {1e3 * force:.2f} mN (the force taking the step's "
             f"lower flat {STEP_DEPTH_MM:g} mm deep, m43338; the thesis does not state its force); the pad's top "
             f"(x = {x_top:+.2f} mm on the section's outer curve) is over the rise's convex half for datums "
             f"{x_top - L / 2:+.2f} to {x_top:+.2f} mm and its concave half for {x_top - L:+.2f} to "
             f"{x_top - L / 2:+.2f} mm")
    half = L / 4 + step / 2
    by_place = [Series("contact area [mm^2]", positions.tolist(), area.tolist()),
                Series("peak pressure [kPa]", positions.tolist(), pressure.tolist(), "--s", axis=1)]
    scatter = [Series("positions of step 5", area.tolist(), pressure.tolist(), "o")]
    inverse = [Finding(
        f"fig6-39_step_inverse_{name}", "6.3.3, figure 6-39",
        "Contact area against peak pressure as step 5 crosses the pad (3D monkey)", QUOTES["fig6-39_step_inverse"],
        [check], f"{where}. The highest peak pressure, {pressure[k]:.3f} kPa, is at datum {positions[k]:+.2f} mm "
        f"with {area[k]:.2f} mm^2 of contact, {at_v[k]:+.2f} mm into the rise (its convex half is {L / 2:.2f} mm long).",
        "contact area [mm^2]", "peak pressure [kPa]", scatter, rows, reading=how)
        for name, check, how in (
            ("trend", Check("rank correlation of contact area with peak pressure over the positions", rho, "<", -0.8,
                            resolution=rho_resolution, why="an inverse trend"),
             "'always accompanied by a decrease' as an inverse trend"),
            ("every_step", Check("moves between neighbouring positions where area and peak pressure change in "
                                 "opposite senses", opposite, ">", 99.9, "%", why="all of them"),
             "'always accompanied by a decrease ... and vice-versa' at every move of the step"))]
    return [Finding(
        "fig6-39_step_extremes", "6.3.3, figure 6-39",
        "Where the contact is smallest and largest as step 5 crosses the pad (3D monkey)", QUOTES["fig6-39_step_extremes"],
        [Check("datum of the smallest contact, from the middle of the convex-half datums", x_min - (x_top - L / 4), "~",
               0.0, "mm", tol=half, resolution=_extreme_spread(positions, area, area_resolution, np.argmin(area)),
               why="the convex half over the pad's top, widened by half a position step"),
         Check("datum of the largest contact, from the middle of the concave-half datums", x_max - (x_top - 3 * L / 4),
               "~", 0.0, "mm", tol=half, resolution=_extreme_spread(positions, area, area_resolution, np.argmax(area)),
               why="the concave half over the pad's top, widened by half a position step")],
        f"Smallest contact {area.min():.2f} mm^2 at datum {x_min:+.2f} mm, largest {area.max():.2f} mm^2 at "
        f"{x_max:+.2f} mm; {where}.", "step position (datum) [mm]", "contact area [mm^2]", by_place, rows,
        y2label="peak pressure [kPa]"), *inverse, _spatial_response(positions, receptors_x, sed, force)]


def _spatial_response(positions, receptors_x, sed, force_N: float, chosen=(-1.5, 0.0, 1.5)) -> Finding:
    """Thesis 6.3.3, figures 6-35..6-38: the spatial response profile of a receptor (its SED as
    step 5 crosses the pad) depends on where the receptor sits. sed (positions, receptors) MPa at
    0.75 mm depth across the middle section; profiles of the chosen receptors, each over its own
    peak, against the step position minus the receptor's x: identical on a flat half-space."""
    cols = [int(np.argmin(np.abs(receptors_x - x))) for x in chosen]
    lo = max(positions[0] - receptors_x[j] for j in cols)
    hi = min(positions[-1] - receptors_x[j] for j in cols)
    rel = np.linspace(lo, hi, 200)
    prof = {j: np.interp(rel, positions - receptors_x[j], sed[:, j] / sed[:, j].max()) for j in cols}
    spread = max(float(np.abs(prof[a] - prof[b]).max()) for a in cols for b in cols if a < b)
    rows = [{"receptor_x_mm": float(receptors_x[j]), "peak_sed_Pa": float(1e6 * sed[:, j].max()),
             "peak_at_step_minus_receptor_mm": float(positions[np.argmax(sed[:, j])] - receptors_x[j]),
             "population_peak_sed_Pa_per_position": " ".join(f"{1e6 * v:.3g}" for v in sed.max(axis=1))} for j in cols]
    shifts = ", ".join(f"{r['peak_at_step_minus_receptor_mm']:+.2f}" for r in rows)
    peaks = ", ".join(f"{r['peak_sed_Pa']:.3g}" for r in rows)
    return Finding(
        "fig6-38_spatial_response", "6.3.3, figures 6-35 to 6-38",
        "Spatial response profiles of receptors at different places (step 5 across the 3D monkey)",
        QUOTES["fig6-38_spatial_response"],
        [Check("largest difference between the receptors' peak-normalised SED profiles, aligned on the receptor",
               100 * spread, ">", 10.0, "% of peak", why="'can influence the form': a difference beyond 10 % of the "
               "peak (a flat half-space gives 0)")],
        f"SED 0.75 mm deep at {len(receptors_x)} receptors across the middle section, {len(positions)} step positions "
        f"at {1e3 * force_N:.2f} mN (rates are not modelled). Receptors at x = "
        f"{', '.join(f'{receptors_x[j]:+.2f}' for j in cols)} mm: peaks {peaks} Pa, with the step's datum {shifts} mm "
        "from the receptor.",
        "step datum minus receptor x [mm]", "SED / its peak",
        [Series(f"receptor at x = {receptors_x[j]:+.2f} mm", rel.tolist(), prof[j].tolist(), "-") for j in cols], rows)
