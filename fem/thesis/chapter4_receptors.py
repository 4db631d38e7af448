"""Thesis chapter 4, the SA-I receptors on the 2D plane-strain models, claim by claim: 4.2 a point
(line) load, 4.3 two points, 4.4 a rectangular bar. Each claim function takes a
`fem.thesis.findings.Workshop` and returns `Finding`s (fem.thesis.claims lists them in thesis order).
Units: mm, N/mm (forces per unit length), MPa.
"""
from __future__ import annotations

import numpy as np

from fem.contact.indentors import make_indentor
from fem.core.materials import Material
from fem.receptors.probes import (
    Probe2D,
    receptive_field,
    settling_separation,
    two_point_curves,
)
from fem.thesis.chapter4_mechanics import LINE_LOAD_MODELS
from fem.thesis.findings import Check, Finding, Series, Workshop, folder_code
from fem.thesis.quotes import QUOTES

# ----------------------------------------------------------------------------- 4.2-4.5: receptors
#: Thesis candidates for the SA-I relevant stimulus in figures 4-3, 4-4 and 4-7 (fem.core.measures names).
CANDIDATES = (("sed_MPa", "SED"), ("max_compressive_strain", "max compressive strain"),
              ("abs:strain_xy", "|shear strain|"))
RECEPTOR_DEPTHS_MM = (0.5, 0.75, 1.0)
#: Receptor sites 0.05 mm apart (the spacing of the thesis's traces) across the pad's middle, mm.
SITES_MM = np.round(np.arange(-3.0, 3.0001, 0.05), 3)
CENTRE = int(np.flatnonzero(SITES_MM == 0.0)[0])
#: The candidates' fem.core.measures names, and their labels.
_MEASURES = [c for c, _ in CANDIDATES]
_LABEL_OF = dict(CANDIDATES)


def receptor_probe(folder, depths_mm=(0.75,), sites_mm=SITES_MM, **material):
    """fem.receptors.probes.Probe2D on a 2D model folder with its own homogeneous material
    (fem.thesis.findings.folder_code; material: e.g. rigid_bone=True)."""
    return Probe2D(folder, sites_mm, depths_mm, Material(folder_code(folder), **material))


def _contrast(values, centre) -> float:
    """Michelson contrast of a profile's peak against its value at the centre."""
    peak = float(np.max(values))
    return (peak - centre) / (peak + centre)


# ----------------------------------------------------------------------------- 4.2: point load
def _point_load_runs(shop: Workshop) -> tuple[dict, dict, dict]:
    """The sharp wedge 1 mm deep on every surface node within 2 mm of the top of each of
    LINE_LOAD_MODELS: (profile, sweep, peak). profile[label, measure, depth]: the receptive field of
    the profile across the receptors under the central load; sweep[label, measure]: that of the
    receptor at 0.75 mm over the load positions; peak[label, measure, depth]: the profile's peak."""
    wedge = make_indentor("wedge", orientation="parallel")
    d75 = RECEPTOR_DEPTHS_MM.index(0.75)
    profile, sweep, peak = {}, {}, {}
    for name, label, kw in shop.progress.bar(LINE_LOAD_MODELS, desc="line-load sweeps", unit="model"):
        probe = receptor_probe(shop.folder(name), RECEPTOR_DEPTHS_MM, **kw)
        x = np.sort(probe.contact.points_mm[:, 0])
        # the load on surface nodes: between them the wedge's contact, and its force, jumps from
        # node to node (by up to 30 % on 0.25 mm elements)
        pos = x[np.abs(x) <= 2.0]
        vals, _ = probe.measure(wedge, pos, _MEASURES, depth_mm=1.0)
        i0 = int(np.argmin(np.abs(pos)))
        for c in _MEASURES:
            for j, d in enumerate(RECEPTOR_DEPTHS_MM):
                v = vals[c][i0, j]
                profile[label, c, d] = receptive_field(SITES_MM, v, 0.5 * v.max(), pos[i0])
                peak[label, c, d] = float(v.max())
            v = vals[c][:, d75, CENTRE]
            sweep[label, c] = receptive_field(pos, v, 0.5 * v.max())
    return profile, sweep, peak


def point_load_fields(shop: Workshop) -> list[Finding]:
    """Thesis 4.2, figures 4-3 and 4-4: a line load (the sharp wedge, 1 mm deep) on the four
    models. Profiles across receptors 0.5-1.0 mm deep under the central load (the thesis's
    construction of a receptive field), and the field measured directly: the load swept over
    the receptor at 0.75 mm. Half-peak thresholds."""
    profile, sweep, peak = _point_load_runs(shop)
    main = LINE_LOAD_MODELS[-1][1]              # the cylinder with bone, the thesis's model from 4.4 on
    labels = [label for _, label, _ in LINE_LOAD_MODELS]
    width = {c: np.array([profile[main, c, d].diameter_mm for d in RECEPTOR_DEPTHS_MM]) for c in _MEASURES}
    return [_blur_finding(profile, peak, width, main), _model_profiles_finding(profile, peak, width, labels),
            _receptive_fields_finding(sweep, main), _reciprocity_finding(profile, sweep, main, labels)]


def _blur_finding(profile, peak, width, main) -> Finding:
    """Figure 4-3: blurring with depth, SED sharper than max compressive strain."""
    peaks = {c: np.array([peak[main, c, d] for d in RECEPTOR_DEPTHS_MM]) for c in _MEASURES}
    widening = min(float(np.diff(width[c]).min()) for c in _MEASURES)
    falling = max(float((peaks[c][1:] / peaks[c][:-1]).max()) for c in _MEASURES)
    sharper = float((width["sed_MPa"] / width["max_compressive_strain"]).max())
    styles = dict(zip(RECEPTOR_DEPTHS_MM, ("-", "--", ":")))
    return Finding(
        "fig4-3_depth", "4.2, figure 4-3", "Strain measures under a line load blur with depth", QUOTES["fig4-3_depth"],
        [Check("smallest widening of a measure's half-peak width from one receptor depth to the next "
               "(0.5, 0.75, 1.0 mm)", widening, ">", 0.0, "mm", why="'more blurred' read as a wider half-peak profile"),
         Check("largest ratio of a measure's peak to its peak 0.25 mm shallower", falling, "<", 1.0),
         Check("largest half-peak width of SED over that of max compressive strain, any depth", sharper, "<", 1.0)],
        "Half-peak widths at 0.5, 0.75, 1.0 mm on the cylinder with bone under a wedge 1 mm deep: " + "; ".join(
            f"{_LABEL_OF[c]} {', '.join(f'{w:.2f}' for w in width[c])} mm" for c in _MEASURES)
        + " (|shear strain|: the outer extent of its two lobes).",
        "receptor position relative to the load [mm]", "measure / its peak at 0.5 mm depth",
        [Series(f"{_LABEL_OF[c]}, {d} mm", profile[main, c, d].positions_mm.tolist(),
                (profile[main, c, d].values / peak[main, c, 0.5]).tolist(), styles[d])
         for c in _MEASURES for d in RECEPTOR_DEPTHS_MM],
        [{"measure": _LABEL_OF[c], "depth_mm": d, "half_peak_width_mm": float(width[c][j]),
          "peak": peak[main, c, d]} for c in _MEASURES for j, d in enumerate(RECEPTOR_DEPTHS_MM)])


def _model_profiles_finding(profile, peak, width, labels) -> Finding:
    """Figure 4-3, the other three models: same profiles, other magnitudes; yardstick: 0.25 mm of
    receptor depth."""
    at75 = {c: np.array([profile[m, c, 0.75].diameter_mm for m in labels]) for c in _MEASURES}
    spread = {c: float(np.ptp(at75[c]) / np.diff(width[c]).min()) for c in _MEASURES}
    size = {c: max(peak[m, c, 0.75] for m in labels) / min(peak[m, c, 0.75] for m in labels) for c in _MEASURES}
    return Finding(
        "fig4-3_models", "4.2 (figure 4-3, the other models)", "The four models give the same profiles",
        QUOTES["fig4-3_models"],
        [Check("largest spread of a measure's half-peak width at 0.75 mm over the four models, in units of its "
               "widening per 0.25 mm of depth on the cylinder with bone", max(spread.values()), "<", 1.0,
               why="'approximately the same' read as closer than receptors 0.25 mm apart in depth"),
         Check("largest ratio of a measure's peak at 0.75 mm between two of the models", max(size.values()), ">", 1.1,
               why="'the magnitudes ... are different' read as at least 10 % apart")],
        "Half-peak widths at 0.75 mm (" + ", ".join(labels) + "): " + "; ".join(
            f"{_LABEL_OF[c]} {', '.join(f'{w:.2f}' for w in at75[c])} mm" for c in _MEASURES)
        + "; spreads " + ", ".join(f"{spread[c]:.2f}" for c in _MEASURES) + ", peak ratios "
        + ", ".join(f"{size[c]:.2f}" for c in _MEASURES) + " (SED, max compressive strain, |shear strain|; "
        "the wedge 1 mm deep on each model).",
        "receptor position relative to the load [mm]", "SED at 0.75 mm / its peak",
        [Series(m, profile[m, "sed_MPa", 0.75].positions_mm.tolist(),
                (profile[m, "sed_MPa", 0.75].values / peak[m, "sed_MPa", 0.75]).tolist(), "-")
         for m in labels],
        [{"model": m, "measure": _LABEL_OF[c], "half_peak_width_mm": profile[m, c, 0.75].diameter_mm,
          "peak": peak[m, c, 0.75]} for m in labels for c in _MEASURES])


def _receptive_fields_finding(sweep, main) -> Finding:
    """Figure 4-4: receptive fields by sweeping the load over the receptor at 0.75 mm."""
    shear = sweep[main, "abs:strain_xy"]
    fracs = (0.3, 0.4, 0.5, 0.6, 0.7)
    rows = []
    for c in _MEASURES:
        for q in fracs:
            f = receptive_field(sweep[main, c].positions_mm, sweep[main, c].values, q * sweep[main, c].values.max())
            rows.append({"measure": _LABEL_OF[c], "threshold_of_peak": q, "shape": f.shape,
                         "diameter_mm": f.diameter_mm, "hole_mm": f.hole_mm})
    holes = [r["hole_mm"] for r in rows if r["measure"] == _LABEL_OF["abs:strain_xy"]]

    def hole(c):            # an OFF hole only a disk (0) or an annulus has
        f = sweep[main, c]
        return float(f.hole_mm) if f.shape in ("disk", "annulus") else float("nan")
    return Finding(
        "fig4-4_receptive_fields", "4.2, figure 4-4", "Receptive fields for a point load",
        QUOTES["fig4-4_receptive_fields"],
        [Check("OFF hole of the max compressive strain field", hole("max_compressive_strain"), "<", 0.01, "mm",
               why="a circle centred over the receptor has none"),
         Check("OFF hole of the SED field", hole("sed_MPa"), "<", 0.01, "mm", why="the same"),
         Check("OFF hole of the |shear strain| field", hole("abs:strain_xy"), "~", 0.3, "mm", tol=0.1,
               why="'about 0.3 mm' read as 0.2-0.4 mm")],
        f"The load swept over the receptor at 0.75 mm (cylinder with bone, the wedge 1 mm deep on each surface node), "
        f"half-peak threshold: SED a {sweep[main, 'sed_MPa'].shape} of {sweep[main, 'sed_MPa'].diameter_mm:.2f} mm, "
        f"max compressive strain a {sweep[main, 'max_compressive_strain'].shape} of "
        f"{sweep[main, 'max_compressive_strain'].diameter_mm:.2f} mm, |shear strain| a(n) {shear.shape} of "
        f"{shear.diameter_mm:.2f} mm. The thesis's threshold is \"an arbitrarily assumed threshold value\" and the "
        f"hole follows it: {np.nanmin(holes):.2f}-{np.nanmax(holes):.2f} mm for thresholds of 30-70 % of the peak.",
        "load position relative to the receptor [mm]", "measure at the receptor / its peak",
        [Series(_LABEL_OF[c], sweep[main, c].positions_mm.tolist(),
                (sweep[main, c].values / sweep[main, c].values.max()).tolist(), "-") for c in _MEASURES]
        + [Series("threshold (half peak)", [-2.0, 2.0], [0.5, 0.5], "k-.")], rows)


def _reciprocity_finding(profile, sweep, main, labels) -> Finding:
    """The thesis's shortcut: the response below B to a load at A taken for that below A to a load at B."""
    shear = sweep[main, "abs:strain_xy"]
    rel = {(m, c): profile[m, c, 0.75].diameter_mm / sweep[m, c].diameter_mm - 1 for m in labels for c in _MEASURES}
    worst = {m: max(abs(rel[m, c]) for c in _MEASURES) for m in labels}
    block = LINE_LOAD_MODELS[1][1]
    flat = max(worst[labels[0]], worst[block])
    curved = max(worst[m] for m in labels[2:])
    return Finding(
        "sec4-2_reciprocity", "4.2 (construction of figure 4-4)", "Profile under one load as the receptive field",
        QUOTES["sec4-2_reciprocity"],
        [Check("largest relative difference of the half-peak field diameters, profile under one load over the "
               "load swept, cylinder with bone", 100 * worst[main], "<", 10.0, "%",
               why="'a reasonable approximation' read as within 10 %"),
         Check("the same on the semi-infinite model (sides held)", 100 * worst[block], "<", 3.0, "%",
               why="'This would be the case for a semi-infinite model': exact up to the sampling of the load "
               "positions (one element apart) and the receptors (0.05 mm apart)")],
        "Field diameter from the profile under the central load over that from sweeping the load, minus 1: "
        + "; ".join(f"{m} " + ", ".join(f"{100 * rel[m, c]:+.1f} %" for c in _MEASURES) for m in labels)
        + f" (SED, max compressive strain, |shear strain|). The flat-topped models differ by up to {100 * flat:.1f} %, "
        f"the cylinders by up to {100 * curved:.1f} %"
        + (": the curved surface is where the shortcut departs. " if curved > flat else ". ")
        + f"The OFF hole of |shear strain| is {profile[main, 'abs:strain_xy', 0.75].hole_mm:.2f} mm from the profile "
        f"and {shear.hole_mm:.2f} mm from the sweep.",
        "load position relative to the receptor [mm]", "SED at 0.75 mm / its peak",
        # a profile's positions are the receptor's relative to the load: mirrored onto the sweep's
        [Series(f"{m}, {how}", (sign * f.positions_mm).tolist(), (f.values / f.values.max()).tolist(), style)
         for m in (main, block)
         for how, f, sign, style in (("load swept", sweep[m, "sed_MPa"], 1, "-"),
                                     ("profile under one load", profile[m, "sed_MPa", 0.75], -1, "--"))],
        [{"model": m, "measure": _LABEL_OF[c], "sweep_diameter_mm": sweep[m, c].diameter_mm,
          "profile_diameter_mm": profile[m, c, 0.75].diameter_mm, "relative_difference": rel[m, c]}
         for m in labels for c in _MEASURES])


# ----------------------------------------------------------------------------- 4.3: two points
def _semi_width(x, v, level: float = 0.5) -> float:
    """Mean distance from the peak of a profile v(x) to where it falls to `level` of its peak, over
    the sides where it does (linear interpolation; NaN where it falls that far on neither side)."""
    o = np.argsort(x)
    x, v = np.asarray(x, float)[o], np.asarray(v, float)[o] / np.max(v)
    k = int(np.argmax(v))
    sides = []
    for idx in (np.arange(k, len(x)), np.arange(k, -1, -1)):
        below = np.flatnonzero(v[idx] < level)
        if below.size:
            j, i = idx[below[0]], idx[below[0] - 1]
            sides.append(abs(x[i] + (level - v[i]) * (x[j] - x[i]) / (v[j] - v[i]) - x[k]))
    return float(np.mean(sides)) if sides else float("nan")


def two_point_resolution(shop: Workshop) -> list[Finding]:
    """Thesis 4.3, figures 4-5 and 4-6: the intensive cue (max SED at 0.75 mm) on the cylinder with
    bone under two sharp tips 0-4 mm apart, both 0.5 mm deep (equal displacement) or each carrying
    half the force that takes one tip 0.5 mm deep (equal force: the same load at separation 0);
    and how far one tip's surface deflection and SED reach."""
    probe = receptor_probe(shop.folder("cylinder8_bone"), sites_mm=np.round(np.arange(-3.5, 3.5001, 0.05), 3),
                           rigid_bone=True)
    seps = np.round(np.arange(0.0, 4.0001, 0.2), 3)
    with shop.progress.task("two-point loads"):
        c = two_point_curves(probe, seps, depth_mm=0.5)
    vals, (one,) = probe.measure(make_indentor("two-point:0", orientation="parallel"), [0.0], ["sed_MPa"],
                                 depth_mm=0.5)
    x = probe.contact.points_mm[:, 0]
    d, f = c["displacement"], c["force"]
    rows = [{"separation_mm": float(s), "equal_displacement_MPa": float(d[i]), "equal_force_MPa": float(f[i]),
             "one_tip_alone_displacement_MPa": float(c["alone_displacement"][i]),
             "one_tip_alone_force_MPa": float(c["alone_force"][i]),
             "depth_equal_force_mm": float(c["depth_force_mm"][i])}
            for i, s in enumerate(seps)]
    return [_two_point_shapes(seps, d, f, c, rows),
            *_intensive_cue(seps, d, f, c, rows, _semi_width(x, one.deflection_mm, 0.1),
                            _semi_width(probe.sites_x_mm, vals["sed_MPa"][0, 0], 0.1), shop.size_mm)]


def _two_point_shapes(seps, d, f, c, rows) -> Finding:
    """Figure 4-5: the shapes of the equal-displacement and equal-force curves."""
    low = int(np.argmin(d[1:])) + 1
    near = int(np.argmax(np.abs(f / f[-1] - 1) <= 0.05))          # first separation within 5 % of the last
    rise = float(np.max(np.diff(f[:near + 1])) / f[0]) if near else float("nan")
    return Finding(
        "fig4-5_two_point", "4.3, figure 4-5", "Peak SED under two point loads against their separation",
        QUOTES["fig4-5_two_point"],
        [Check("peak SED at 0.2 mm separation over one load's (separation 0), equal displacement",
               float(d[1] / d[0]), ">", 1.0, why="'increases at first'"),
         Check("least peak SED over 0.2 mm separation's, equal displacement", float(d[low] / d[1]), "<", 1.0,
               why="'then decreases sharply'"),
         Check("peak SED at 4 mm over its least value, equal displacement", float(d[-1] / d[low]), ">", 1.0,
               why="'followed by a gradual increase'"),
         Check("largest rise between neighbouring separations before the equal-force curve comes within 5 % of "
               "its 4 mm value, over its value at 0", 100 * rise, "<", 0.0, "%", why="'monotonically decreases'")],
        f"Equal displacement (tips 0.5 mm deep): least value {d[low] / d[0]:.2f} of the single load's at "
        f"{seps[low]:.1f} mm, {d[-1] / d[0]:.2f} at 4 mm. Equal force ({c['force_per_load_N']:.3g} N/mm per tip, "
        f"half the force that takes one tip 0.5 mm deep): {f[near] / f[0]:.2f} of the single load's by "
        f"{seps[near]:.1f} mm. The thesis states no depth or force for its loads.",
        "separation of the loads [mm]", "peak SED at 0.75 mm / one load's",
        [Series("equal displacement", seps.tolist(), (d / d[0]).tolist()),
         Series("equal force", seps.tolist(), (f / f[0]).tolist(), "-s")], rows)


#: Separation from which the thesis finds the force-controlled intensive cue constant (figure 4-6), mm.
FIG_4_6_SETTLING_MM = 1.6


def _intensive_cue(seps, d, f, c, rows, deflection_semi_mm, sed_semi_mm, size_mm) -> list[Finding]:
    """Figure 4-6, with '1.6 mm' read as the separation and as the half separation (the figure's
    axis). Each reading judges the loads up to a separation beyond its 1.6 or 3.2 mm (3 and 4 mm):
    on the cylinder the cue also drifts as the two tips move down its flanks, so where it counts as
    constant depends on how far the loads go."""
    alone = c["alone_force"][1:]                  # one tip carrying the per-tip force, at +s/2
    jitter = float(np.max(np.abs(np.diff(alone)) / alone[:-1]))
    out = []
    for name, target, end, how in (
            ("separation", FIG_4_6_SETTLING_MM, 3.0, "'a separation of 1.6 mm' as the distance between the loads"),
            ("half_separation", 2 * FIG_4_6_SETTLING_MM, 4.0, "'a separation of 1.6 mm' as the half separation on "
             "the axis of figure 4-6 (the loads 3.2 mm apart)")):
        k = seps <= end + 1e-9
        s_force = settling_separation(seps[k], f[k], 0.05)
        after = k & (seps >= (s_force if np.isfinite(s_force) else end))
        varies = float(100 * np.max(np.abs(d[after] / d[k][-1] - 1)))
        notes = (f"Loads 0-{end:g} mm apart; for the explanation one tip 0.5 mm deep (the thesis gives no depth). One "
                 f"tip alone carrying the per-tip force changes by up to {100 * jitter:.1f} % between neighbouring "
                 f"places (a concentrated load on {size_mm:g} mm elements, against the 5 % band).")
        series = [Series("equal force", (seps[k] / 2).tolist(), (f[k] / f[k][-1]).tolist()),
                  Series("equal displacement", (seps[k] / 2).tolist(), (d[k] / d[k][-1]).tolist(), "-s"),
                  Series("+5 %", [0.0, end / 2], [1.05, 1.05], "k:"), Series("-5 %", [0.0, end / 2], [0.95, 0.95], "k:")]
        out.append(Finding(
            f"fig4-6_intensive_cue_{name}", "4.3, figure 4-6", "Intensive cue under force and displacement control",
            QUOTES["fig4-6_intensive_cue"],
            [Check(f"separation from which the equal-force cue stays within 5 % of its value at {end:g} mm", s_force,
                   "~", target, "mm", tol=0.4, why="'settle down to a constant value' read as within 5 %; 0.4 mm is "
                   "two steps of the separations"),
             Check("largest change of the equal-displacement cue from there on, of its value at the same end",
                   varies, ">", 5.0, "%", why="'continue to vary'"),
             Check("semi-width of one load's surface deflection, to a tenth of its peak", deflection_semi_mm, "~",
                   2.0, "mm", tol=0.5, why="'semi-width of about 2 mm'; the thesis does not define it"),
             Check("semi-width of one load's SED at 0.75 mm, to a tenth of its peak", sed_semi_mm, "~", 1.0, "mm",
                   tol=0.5, why="'semi-width of about 1 mm for depths 0.5 to 1.0 mm'")],
            notes, "half separation of the loads [mm]", f"peak SED at 0.75 mm / its value at {end:g} mm", series, rows,
            reading=how))
    return out


# ----------------------------------------------------------------------------- 4.4: bars
BAR_WIDTH_MM = 1.5

#: Label of the block with free sides, run with the bar besides LINE_LOAD_MODELS.
_FREE_BLOCK = "semi-infinite, sides free"


def _bar_runs(shop: Workshop) -> dict:
    """The bar of BAR_WIDTH_MM 1 mm deep on each of LINE_LOAD_MODELS and the block with free sides:
    {label: {"x": surface node x within 3 mm, sorted; "p": their pressure [MPa]; "p_centre": the
    pressure nearest x = 0; "force": N/mm; measure: its values at the 0.75 mm receptors (SITES_MM)}}."""
    bar = make_indentor(f"bar:{BAR_WIDTH_MM:g}", orientation="parallel")
    runs = {}
    models = LINE_LOAD_MODELS + (("block_free", _FREE_BLOCK, {}),)
    for name, label, kw in shop.progress.bar(models, desc="bar", unit="model"):
        probe = receptor_probe(shop.folder(name), **kw)
        vals, (res,) = probe.measure(bar, [0.0], _MEASURES, depth_mm=1.0)
        x = probe.contact.points_mm[:, 0]
        o = np.argsort(x)
        o = o[np.abs(x[o]) <= 3.0]
        p = res.pressure_MPa[o]
        runs[label] = {"x": x[o], "p": p, "p_centre": float(p[np.argmin(np.abs(x[o]))]),
                       "force": res.total_force_N, **{c: vals[c][0, 0] for c in _MEASURES}}
    return runs


def rectangular_bars(shop: Workshop) -> list[Finding]:
    """Thesis 4.4, figure 4-7: a 1.5 mm bar 1 mm deep on the four models (and the block with free
    sides): surface pressure, and SED, max compressive strain and |shear strain| at 0.75 mm.
    Contrast: (peak - centre) / (peak + centre) of a profile across the receptors."""
    runs = _bar_runs(shop)
    labels = [label for _, label, _ in LINE_LOAD_MODELS]
    contrast = {(m, c): _contrast(r[c], r[c][CENTRE]) for m, r in runs.items() for c in _MEASURES}
    contrast.update({(m, "pressure"): _contrast(r["p"], r["p_centre"]) for m, r in runs.items()})
    return [_edge_pressure_finding(runs, contrast, labels, shop.size_mm), *_bar_contrast_findings(runs, contrast, labels),
            _shear_edges_finding(runs, contrast, labels), *_bone_findings(runs, contrast, labels)]


def _edge_pressure_finding(runs, contrast, labels, size_mm) -> Finding:
    """Figure 4-7: pressure concentrated under the bar's edges (elements of size_mm)."""
    rows = [{"model": m, "force_N_per_mm": r["force"], "max_pressure_MPa": float(r["p"].max()),
             "centre_pressure_MPa": r["p_centre"], "pressure_contrast": contrast[m, "pressure"],
             **{f"{_LABEL_OF[c]} peak": float(r[c].max()) for c in _MEASURES},
             **{f"{_LABEL_OF[c]} contrast": contrast[m, c] for c in _MEASURES}} for m, r in runs.items()]
    ratio = {m: float(runs[m]["p"].max() / runs[m]["p_centre"]) for m in labels}
    where = {m: float(abs(runs[m]["x"][np.argmax(runs[m]["p"])])) for m in labels}
    off_edge = max(abs(where[m] - BAR_WIDTH_MM / 2) for m in labels)
    return Finding(
        "fig4-7_edge_pressure", "4.4, figure 4-7", "Pressure under a bar peaks at its edges",
        QUOTES["fig4-7_edge_pressure"],
        [Check("smallest peak over centre pressure of the four models", min(ratio.values()), ">", 1.25,
               why="'very high ... relative to the pressure at the center' read as at least 1.25 times"),
         Check("largest distance of the pressure peak from the bar's edge (x = +-0.75 mm), four models", off_edge,
               "<", size_mm, "mm", why="within one element")],
        "Peak over centre pressure: " + ", ".join(f"{m} {ratio[m]:.2f}" for m in labels) + "; peaks at |x| = "
        + ", ".join(f"{where[m]:.2f}" for m in labels) + " mm. Under a rigid flat edge the continuum pressure is "
        "singular, so the sampled peak depends on the element size (its mesh uncertainty above).",
        "x [mm]", "pressure / pressure at the centre",
        [Series(m, runs[m]["x"].tolist(), (runs[m]["p"] / runs[m]["p_centre"]).tolist(), "-") for m in labels], rows)


def _bar_contrast_findings(runs, contrast, labels) -> list[Finding]:
    """Figure 4-7, edge-centre contrast: low-pass filtering, and the finite square's 'superior'
    contrast read against every other model and against the cylinders."""
    square = labels[0]
    measures = _MEASURES[:2]
    filtered = max(contrast[m, c] / contrast[m, "pressure"] for m in labels for c in measures)
    series = [Series(m, SITES_MM.tolist(), (runs[m]["sed_MPa"] / runs[m]["sed_MPa"][CENTRE]).tolist(), "-")
              for m in labels + [_FREE_BLOCK]]
    notes = ("Contrast (peak - centre) / (peak + centre) at 0.75 mm (" + ", ".join(labels) + "): " + "; ".join(
        f"{_LABEL_OF[c]} {', '.join(f'{contrast[m, c]:.3f}' for m in labels)}" for c in measures)
        + "; pressure " + ", ".join(f"{contrast[m, 'pressure']:.2f}" for m in labels) + "; with free sides the "
        f"semi-infinite block gives {contrast[_FREE_BLOCK, 'sed_MPa']:.3f} and "
        f"{contrast[_FREE_BLOCK, 'max_compressive_strain']:.3f}. The thesis does not define its contrast.")
    low_pass = Check("largest strain-measure contrast over the pressure contrast, any model (SED, max "
                     "compressive strain)", filtered, "<", 1.0, why="'low-pass filtered versions of the surface pressure'")
    out = []
    for name, rivals, how in (("all_models", labels[1:], "better than each of the other three models"),
                              ("cylinders", labels[2:], "better than the two cylinders")):
        checks = [low_pass] + [Check(f"{_LABEL_OF[c]} contrast of the finite square over the best of the "
                                     f"{'other three models' if name == 'all_models' else 'cylinders'}",
                                     contrast[square, c] / max(contrast[m, c] for m in rivals), ">", 1.0)
                               for c in measures]
        out.append(Finding(
            f"fig4-7_model_contrast_{name}", "4.4, figure 4-7", "Edge contrast of the strain measures across the models",
            QUOTES["fig4-7_model_contrast"], checks, notes, "x [mm]", "SED at 0.75 mm / its value at the centre",
            series, [], reading=f"'superior contrast' as {how}"))
    return out


def _shear_edges_finding(runs, contrast, labels) -> Finding:
    """Figure 4-7: |shear strain| marks the bar's edges. Its edge-centre contrast is 1 by symmetry
    (it vanishes over the centre), so it is judged by where its peaks lie and how narrow they are."""
    lobes = {m: float(abs(SITES_MM[np.argmax(runs[m]["abs:strain_xy"])])) for m in labels}
    off = max(abs(lobes[m] - BAR_WIDTH_MM / 2) for m in labels)
    widths = {(m, c): _semi_width(SITES_MM[SITES_MM > 0], runs[m][c][SITES_MM > 0]) for m in labels
              for c in _MEASURES}
    sharp = max(widths[m, "abs:strain_xy"] / min(widths[m, c] for c in _MEASURES[:2]) for m in labels)
    main = labels[3]
    return Finding(
        "fig4-7_shear_edges", "4.4, figure 4-7", "Absolute shear strain marks the bar's edges",
        QUOTES["fig4-7_shear_edges"],
        [Check("largest distance of the |shear strain| peak at 0.75 mm from the bar's edge, four models", off,
               "<", 0.75, "mm", why="an edge detector's peak within the receptor depth of the edge"),
         Check("half-peak semi-width of the |shear strain| peak over the narrower of SED's and max compressive "
               "strain's (x > 0), largest over the models", sharp, "<", 1.0,
               why="'best contrast' read as the sharpest peak; the edge-centre contrast of |shear strain| is 1 "
               "by symmetry and cannot rank it")],
        "|shear strain| peaks at |x| = " + ", ".join(f"{lobes[m]:.2f}" for m in labels) + " mm (" + ", ".join(labels)
        + f"), the edges at {BAR_WIDTH_MM / 2:g} mm; half-peak semi-widths on the cylinder with bone: "
        + ", ".join(f"{_LABEL_OF[c]} {widths[main, c]:.2f} mm" for c in _MEASURES) + ".",
        "x [mm]", "measure at 0.75 mm / its peak (cylinder with bone)",
        [Series(_LABEL_OF[c], SITES_MM.tolist(), (runs[main][c] / runs[main][c].max()).tolist(), "-")
         for c in _MEASURES], [])


def _bone_findings(runs, contrast, labels) -> list[Finding]:
    """Figure 4-7, the bone: most distortion, larger loads, an accentuated SED profile (read as a
    higher level and as a sharper contrast)."""
    main, cyl = labels[3], labels[2]
    sed_peak = {m: float(runs[m]["sed_MPa"].max()) for m in labels}
    rival = max(sed_peak[m] for m in labels if m != main)
    common = [Check("peak SED at 0.75 mm, cylinder with bone over the highest of the other three models",
                    sed_peak[main] / rival, ">", 1.0, why="'the highest in the cylindrical model with bone'"),
              Check("total force, cylinder with bone over the homogeneous cylinder", runs[main]["force"] /
                    runs[cyl]["force"], ">", 1.0, why="'increase in the maximum loads imposed'"),
              Check("peak pressure, cylinder with bone over the homogeneous cylinder",
                    float(runs[main]["p"].max() / runs[cyl]["p"].max()), ">", 1.0, why="the same")]
    accent = {"level": Check("peak SED at 0.75 mm, cylinder with bone over the homogeneous cylinder",
                             sed_peak[main] / sed_peak[cyl], ">", 1.0),
              "contrast": Check("SED edge-centre contrast, cylinder with bone over the homogeneous cylinder",
                                contrast[main, "sed_MPa"] / contrast[cyl, "sed_MPa"], ">", 1.0)}
    notes = ("Peak SED at 0.75 mm: " + ", ".join(f"{m} {sed_peak[m]:.3g} MPa" for m in labels)
             + f"; SED edge-centre contrast: cylinder {contrast[cyl, 'sed_MPa']:.3f}, with bone "
             f"{contrast[main, 'sed_MPa']:.3f} (bar 1 mm deep; the bone rigid).")
    series = [Series(m, SITES_MM.tolist(), runs[m]["sed_MPa"].tolist(), "-") for m in labels]
    return [Finding(f"fig4-7_bone_{name}", "4.4, figure 4-7", "The stiff bone raises the loads and the SED",
                    QUOTES["fig4-7_bone"], common + [check], notes, "x [mm]", "SED at 0.75 mm [MPa]", series, [],
                    reading=f"'accentuation of the strain energy density profile' as a {how}")
            for (name, check), how in zip(accent.items(), ("higher level", "sharper edge contrast"))]
