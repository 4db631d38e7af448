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
from fem.thesis.findings import DIFFERS, REPRODUCED, Finding, Series, Workshop

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
    """fem.receptors.probes.Probe2D on a 2D model folder, material m33338 (material: e.g. rigid_bone=True)."""
    return Probe2D(folder, sites_mm, depths_mm, Material("m33338", **material))


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
    blurs = all(np.all(np.diff(width[c]) > 0) and np.all(np.diff(peaks[c]) < 0) for c in _MEASURES)
    sharper = bool(np.all(width["sed_MPa"] < width["max_compressive_strain"]))
    styles = dict(zip(RECEPTOR_DEPTHS_MM, ("-", "--", ":")))
    return Finding(
        "fig4-3_depth", "4.2, figure 4-3", "Strain measures under a line load blur with depth",
        "Under a line load on the cylinder with bone, each strain measure is the more blurred the deeper "
        "the receptor (0.5-1.0 mm): the elastic medium is a spatial low-pass filter; at a given depth "
        "SED is less blurred than the maximum compressive strain (SED ~ eps^2, appendix A).",
        "half-peak width of SED over that of max compressive strain at 0.75 mm", None,
        float(width["sed_MPa"][1] / width["max_compressive_strain"][1]),
        REPRODUCED if blurs and sharper else DIFFERS,
        "Half-peak widths at 0.5, 0.75, 1.0 mm: " + "; ".join(
            f"{_LABEL_OF[c]} {', '.join(f'{w:.2f}' for w in width[c])} mm" for c in _MEASURES)
        + f" ({'each widening and its peak falling' if blurs else 'not all widening with falling peaks'} "
        f"with depth; |shear strain| is the outer extent of its two lobes). SED is "
        f"{'narrower than max compressive strain at every depth' if sharper else 'not narrower at every depth'}.",
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
    alike = max(spread.values()) < 1.0
    return Finding(
        "fig4-3_models", "4.2 (figure 4-3, the other models)", "The four models give the same profiles",
        "For the finite square, semi-infinite and homogeneous cylinder the magnitudes under a given line "
        "load differ from the cylinder with bone's, but the spatial profile of each measure is about the same.",
        "largest spread of half-peak widths at 0.75 mm over the four models, in units of the widening "
        "per 0.25 mm of depth", None, max(spread.values()), REPRODUCED if alike else DIFFERS,
        "Half-peak widths at 0.75 mm (" + ", ".join(labels) + "): " + "; ".join(
            f"{_LABEL_OF[c]} {', '.join(f'{w:.2f}' for w in at75[c])} mm" for c in _MEASURES)
        + ". The spread over the models is " + ", ".join(f"{spread[c]:.2f}" for c in _MEASURES)
        + " times the smallest widening caused by 0.25 mm more depth on the cylinder with bone "
        f"({'all' if alike else 'not all'} below 1: the models differ less than receptors 0.25 mm apart "
        "in depth). The peaks differ by factors of " + ", ".join(f"{size[c]:.2f}" for c in _MEASURES)
        + " over the models (1 mm deep wedge).",
        "receptor position relative to the load [mm]", "SED at 0.75 mm / its peak",
        [Series(m, profile[m, "sed_MPa", 0.75].positions_mm.tolist(),
                (profile[m, "sed_MPa", 0.75].values / peak[m, "sed_MPa", 0.75]).tolist(), "-")
         for m in labels],
        [{"model": m, "measure": _LABEL_OF[c], "half_peak_width_mm": profile[m, c, 0.75].diameter_mm,
          "peak": peak[m, c, 0.75]} for m in labels for c in _MEASURES])


def _receptive_fields_finding(sweep, main) -> Finding:
    """Figure 4-4: receptive fields by sweeping the load over the receptor at 0.75 mm."""
    shear = sweep[main, "abs:strain_xy"]
    shapes = {c: sweep[main, c].shape for c in _MEASURES}
    ok = (shapes == {"sed_MPa": "disk", "max_compressive_strain": "disk", "abs:strain_xy": "annulus"}
          and abs(shear.hole_mm - 0.3) <= 0.1)
    fracs = (0.3, 0.4, 0.5, 0.6, 0.7)
    rows = []
    for c in _MEASURES:
        for q in fracs:
            f = receptive_field(sweep[main, c].positions_mm, sweep[main, c].values, q * sweep[main, c].values.max())
            rows.append({"measure": _LABEL_OF[c], "threshold_of_peak": q, "shape": f.shape,
                         "diameter_mm": f.diameter_mm, "hole_mm": f.hole_mm})
    holes = [r["hole_mm"] for r in rows if r["measure"] == _LABEL_OF["abs:strain_xy"]]
    return Finding(
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
        [Series(_LABEL_OF[c], sweep[main, c].positions_mm.tolist(),
                (sweep[main, c].values / sweep[main, c].values.max()).tolist(), "-") for c in _MEASURES]
        + [Series("threshold (half peak)", [-2.0, 2.0], [0.5, 0.5], "k-.")], rows)


def _reciprocity_finding(profile, sweep, main, labels) -> Finding:
    """The thesis's shortcut: the response below B to a load at A taken for that below A to a load at B."""
    shear = sweep[main, "abs:strain_xy"]
    rel = {(m, c): profile[m, c, 0.75].diameter_mm / sweep[m, c].diameter_mm - 1 for m in labels for c in _MEASURES}
    worst = {m: max(abs(rel[m, c]) for c in _MEASURES) for m in labels}
    block = LINE_LOAD_MODELS[1][1]
    return Finding(
        "sec4-2_reciprocity", "4.2 (construction of figure 4-4)", "Profile under one load as the receptive field",
        "The state of stress below B under a load at A is taken as that below A under a load at B: exact "
        "on the semi-infinite model, a reasonable approximation on the cylinder for points a short "
        "distance apart; the profile under one central load then gives the receptive field.",
        "largest relative difference of the half-peak field diameters, profile over sweep, cylinder with bone",
        None, worst[main], REPRODUCED if worst[main] <= 0.1 else DIFFERS,
        "Field diameter from the profile under the central load over that from sweeping the load, minus 1: "
        + "; ".join(f"{m} " + ", ".join(f"{100 * rel[m, c]:+.1f} %" for c in _MEASURES) for m in labels)
        + f" (SED, max compressive strain, |shear strain|). On the flat semi-infinite model the two agree within "
        f"{100 * worst[block]:.1f} % and on the flat-topped square within {100 * worst[labels[0]]:.1f} %; on the "
        f"cylinders the profile overstates the field by up to {100 * max(worst[m] for m in labels[2:]):.0f} % "
        f"(judged against 10 %): the curved surface breaks the translation invariance that makes the two "
        f"the same. The OFF hole of |shear strain| is {profile[main, 'abs:strain_xy', 0.75].hole_mm:.2f} mm "
        f"from the profile and {shear.hole_mm:.2f} mm from the sweep.",
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
#: Separation from which the thesis finds the force-controlled intensive cue constant (figure 4-6), mm.
FIG_4_6_SETTLING_MM = 1.6


def two_point_resolution(shop: Workshop) -> list[Finding]:
    """Thesis 4.3, figures 4-5 and 4-6: the intensive cue (max SED at 0.75 mm) on the cylinder with
    bone under two sharp tips 0-3 mm apart, both 0.5 mm deep (equal displacement) or each carrying
    half the force that takes one tip 0.5 mm deep (equal force: the same load at separation 0);
    and how far one tip's surface deflection and SED reach."""
    probe = receptor_probe(shop.folder("cylinder8_bone"), sites_mm=np.round(np.arange(-3.5, 3.5001, 0.05), 3),
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
             "one_tip_alone_force_MPa": float(c["alone_force"][i]),
             "depth_equal_force_mm": float(c["depth_force_mm"][i])}
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
        f"force ({c['force_per_load_N']:.3g} N/mm per tip): "
        f"{'falls monotonically' if falls else 'does not fall monotonically'} "
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
        f"0.5 mm deep: the surface deflection is still {100 * defl(1.0):.0f} % and {100 * defl(2.0):.0f} % "
        f"of its peak 1 "
        f"and 2 mm away, the SED at 0.75 mm {100 * reach(1.0):.0f} % and {100 * reach(2.0):.1f} %.",
        "half separation of the loads [mm]", "peak SED at 0.75 mm / its value at 3 mm",
        [Series("equal force", (seps / 2).tolist(), (f / f[-1]).tolist()),
         Series("equal displacement", (seps / 2).tolist(), (d / d[-1]).tolist(), "-s"),
         Series("+5 %", [0.0, 1.5], [1.05, 1.05], "k:"), Series("-5 %", [0.0, 1.5], [0.95, 0.95], "k:")], rows)
    return [shapes, cue]


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
    return [_edge_pressure_finding(runs, contrast, labels, shop.size_mm), _bar_contrast_finding(runs, contrast, labels),
            _shear_edges_finding(runs, contrast, labels), _bone_finding(runs, contrast, labels)]


def _edge_pressure_finding(runs, contrast, labels, size_mm) -> Finding:
    """Figure 4-7: pressure concentrated under the bar's edges (elements of size_mm)."""
    rows = [{"model": m, "force_N_per_mm": r["force"], "max_pressure_MPa": float(r["p"].max()),
             "centre_pressure_MPa": r["p_centre"], "pressure_contrast": contrast[m, "pressure"],
             **{f"{_LABEL_OF[c]} peak": float(r[c].max()) for c in _MEASURES},
             **{f"{_LABEL_OF[c]} contrast": contrast[m, c] for c in _MEASURES}} for m, r in runs.items()]
    ratio = {m: float(runs[m]["p"].max() / runs[m]["p_centre"]) for m in labels}
    where = {m: float(abs(runs[m]["x"][np.argmax(runs[m]["p"])])) for m in labels}
    at_edge = all(abs(where[m] - BAR_WIDTH_MM / 2) <= size_mm for m in labels)
    return Finding(
        "fig4-7_edge_pressure", "4.4, figure 4-7", "Pressure under a bar peaks at its edges",
        "For each model the surface pressure under a 1.5 mm bar indented 1 mm is very high under the "
        "bar's edges relative to its centre.", "smallest edge-over-centre pressure ratio of the four models",
        None, min(ratio.values()), REPRODUCED if at_edge and min(ratio.values()) >= 1.25 else DIFFERS,
        "Peak pressure over centre pressure: " + ", ".join(f"{m} {ratio[m]:.2f}" for m in labels)
        + ", the peaks " + ("all" if at_edge else "not all") + f" within one element ({size_mm} mm) of the "
        f"edges at +-{BAR_WIDTH_MM / 2:g} mm (|x| = " + ", ".join(f"{where[m]:.2f}" for m in labels)
        + " mm; judged: at least 1.25). A rigid flat bar's edge pressure is singular, so the sampled peak "
        "grows as the elements shrink.",
        "x [mm]", "pressure / pressure at the centre",
        [Series(m, runs[m]["x"].tolist(), (runs[m]["p"] / runs[m]["p_centre"]).tolist(), "-") for m in labels], rows)


def _bar_contrast_finding(runs, contrast, labels) -> Finding:
    """Figure 4-7, edge-centre contrast: the models compared, and the measures compared."""
    square = labels[0]
    filtered = [(m, c) for m in labels for c in _MEASURES[:2] if contrast[m, c] >= contrast[m, "pressure"]]
    best = {c: max(labels, key=lambda m: contrast[m, c]) for c in _MEASURES[:2]}
    rival = max(contrast[m, "sed_MPa"] for m in labels if m != square)
    return Finding(
        "fig4-7_model_contrast", "4.4, figure 4-7", "Edge contrast of the strain measures across the models",
        "The strain measures at 0.75 mm are low-pass filtered versions of the surface pressure; among the "
        "models, all strain measures of the finite square have the best contrast between the edges and "
        "the centre of the bar.", "SED contrast of the finite square over the best of the other three models",
        None, contrast[square, "sed_MPa"] / rival,
        REPRODUCED if all(b == square for b in best.values()) and not filtered else DIFFERS,
        "Contrast at 0.75 mm (" + ", ".join(labels) + "): " + "; ".join(
            f"{_LABEL_OF[c]} {', '.join(f'{contrast[m, c]:.3f}' for m in labels)}" for c in _MEASURES[:2])
        + "; best: " + ", ".join(f"{_LABEL_OF[c]} on the {best[c]}" for c in _MEASURES[:2])
        + f" (with free sides the semi-infinite block gives {contrast[_FREE_BLOCK, 'sed_MPa']:.3f} and "
        f"{contrast[_FREE_BLOCK, 'max_compressive_strain']:.3f}). Both are below the pressure's "
        f"{min(contrast[m, 'pressure'] for m in labels):.2f}-{max(contrast[m, 'pressure'] for m in labels):.2f} "
        + ("in every model (low-pass filtered). " if not filtered else "not in every model. ")
        + "|shear strain| vanishes over the bar's centre in every model (contrast "
        + ", ".join(f"{contrast[m, 'abs:strain_xy']:.3f}" for m in labels) + "), so it does not rank them.",
        "x [mm]", "SED at 0.75 mm / its value at the centre",
        [Series(m, SITES_MM.tolist(), (runs[m]["sed_MPa"] / runs[m]["sed_MPa"][CENTRE]).tolist(), "-")
         for m in labels + [_FREE_BLOCK]], [])


def _shear_edges_finding(runs, contrast, labels) -> Finding:
    """Figure 4-7: |shear strain| has the best edge-centre contrast."""
    main = labels[3]
    shear_best = all(contrast[m, "abs:strain_xy"] > max(contrast[m, c] for c in _MEASURES[:2]) for m in labels)
    lobes = {m: float(abs(SITES_MM[np.argmax(runs[m]["abs:strain_xy"])])) for m in labels}
    return Finding(
        "fig4-7_shear_edges", "4.4, figure 4-7", "Absolute shear strain marks the bar's edges",
        "For each model absolute shear strain has the best edge-centre contrast among the strain measures: "
        "shear strain sensors would detect edges best.", "smallest |shear strain| contrast of the four models",
        None, min(contrast[m, "abs:strain_xy"] for m in labels), REPRODUCED if shear_best else DIFFERS,
        "Contrast of |shear strain| " + ", ".join(f"{contrast[m, 'abs:strain_xy']:.3f}" for m in labels)
        + " against at most " + f"{max(contrast[m, c] for m in labels for c in _MEASURES[:2]):.3f} for SED and max "
        f"compressive strain ({', '.join(labels)}): it vanishes over the centre by symmetry and peaks at "
        f"|x| = " + ", ".join(f"{lobes[m]:.2f}" for m in labels) + f" mm, just outside the edges at "
        f"{BAR_WIDTH_MM / 2:g} mm.",
        "x [mm]", "measure at 0.75 mm / its peak (cylinder with bone)",
        [Series(_LABEL_OF[c], SITES_MM.tolist(), (runs[main][c] / runs[main][c].max()).tolist(), "-")
         for c in _MEASURES], [])


def _bone_finding(runs, contrast, labels) -> Finding:
    """Figure 4-7, the bone: most distortion, larger loads."""
    main, cyl = labels[3], labels[2]
    sed_peak = {m: float(runs[m]["sed_MPa"].max()) for m in labels}
    highest = max(labels, key=sed_peak.get) == main
    up = {"force": runs[main]["force"] / runs[cyl]["force"],
          "max pressure": float(runs[main]["p"].max() / runs[cyl]["p"].max()),
          "peak SED": sed_peak[main] / sed_peak[cyl]}
    return Finding(
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
