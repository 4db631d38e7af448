"""Thesis chapter 4, section 4.5: gratings of bars on the 2D plane-strain models, claim by claim
(4.5.2-4.5.4 aperiodic gratings, 4.5.5 the gap between two bars). Each claim function takes a
`fem.thesis.findings.Workshop` and returns `Finding`s (fem.thesis.claims lists them in thesis order).
Units: mm, N/mm (forces per unit length), MPa.
"""
from __future__ import annotations

import numpy as np

from fem.contact.indentors import make_indentor
from fem.receptors.probes import gap_analysis
from fem.thesis.chapter4_receptors import CENTRE, SITES_MM, receptor_probe
from fem.thesis.findings import Check, Finding, Series, Workshop
from fem.thesis.quotes import QUOTES

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
    grating = make_indentor(f"grating:{GRATING_BAR_MM:g}", orientation="parallel")
    edges = grating.parts[0].bar_edges_mm()
    # the grating's left end relative to the receptor at x = 0, in 0.25 mm steps (the thesis's 0.2 mm)
    # so that every bar centre, and receptors 1 and 2 mm off-centre, fall on the steps; the right end
    # stays inside the 40 mm block, whose held sides no bar may press
    pos = np.round(np.arange(-18.5, 2.0001, 0.25), 3)
    out = {"positions_mm": pos, "edges_mm": edges, "gaps_mm": np.array(grating.parts[0].gaps_mm)}
    names = ["sed_MPa", "max_compressive_strain"]
    for name, label, kw in shop.progress.bar(GRATING_MODELS, desc="grating sweeps", unit="model"):
        probe = receptor_probe(shop.folder(name), **kw)
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


def _along(runs) -> list:
    """Receptor position along the grating, mm from its left end, at each grating position of `runs`."""
    return (-runs["positions_mm"]).tolist()


def grating_findings(runs: dict) -> list[Finding]:
    """Figures 4-9 to 4-12 and 4-18 from `grating_runs`."""
    under = {label: _under_bars(runs, label)[0] for _, label, _ in GRATING_MODELS}
    at = _under_bars(runs, GRATING_MODELS[0][1])[1]       # the positions with each bar over the central receptor
    return [_contact_finding(runs), _neighbours_finding(runs, under, at), _more_bars_finding(runs, at),
            _rightmost_finding(runs, under, at), _off_centre_finding(runs), _central_profile_finding(runs, under, at)]


def _contact_finding(runs) -> Finding:
    """Figures 4-9, 4-10: a few bars on the cylinder, all of them on the semi-infinite model."""
    l8, l16, block = (label for _, label, _ in GRATING_MODELS)
    n = len(runs["edges_mm"])
    t8, t16, tb = runs[l8]["touching"], runs[l16]["touching"], runs[block]["touching"]
    return Finding(
        "fig4-10_bars_in_contact", "4.5.2, figures 4-9 and 4-10", "Bars of a grating touching each model",
        QUOTES["fig4-10_bars_in_contact"],
        [Check(f"largest number of the {n} bars touching the 8 mm cylinder at once", float(t8.max()), "<",
               n / 2 + 0.5, why="'only a few' read as at most half of them"),
         Check(f"fewest of the {n} bars touching the semi-infinite block", float(tb.min()), ">", n - 0.5,
               why="'contact with all the bars'")],
        f"Over {len(runs['positions_mm'])} grating positions 0.25 mm apart: {t8.min()}-{t8.max()} bars touch the 8 mm "
        f"cylinder (mean {t8.mean():.1f}), {t16.min()}-{t16.max()} the 16 mm one. Force per indentation: cylinder "
        f"{runs[l8]['force'].min():.3g}-{runs[l8]['force'].max():.3g} N/mm over "
        f"{runs[l8]['width'].min():.2f}-{runs[l8]['width'].max():.2f} mm of contact, block "
        f"{runs[block]['force'].min():.3g}-{runs[block]['force'].max():.3g} N/mm over "
        f"{runs[block]['width'].min():.2f}-{runs[block]['width'].max():.2f} mm. The thesis lists neither its number "
        "of bars nor its gaps; this grating's are fem.contact.indentors' default.",
        "receptor position along the grating [mm]", "bars touching",
        [Series(label, _along(runs), runs[label]["touching"].tolist(), "-") for _, label, _ in GRATING_MODELS], [])


def _neighbours_finding(runs, under, at) -> Finding:
    """Figure 4-11: the receptor under one bar feels its neighbours across gaps under 1.5 mm.
    under: label -> measure with each bar centred over the receptor, over the rightmost's
    (_under_bars); at: those grating positions."""
    l8 = GRATING_MODELS[0][1]
    edges, gaps = runs["edges_mm"], runs["gaps_mm"]
    n = len(edges)
    r8 = under[l8]
    c8, _ = _under_bars(runs, l8, "max_compressive_strain")
    near = [k for k in range(n) if min(gaps[max(k - 1, 0):k + 1]) < 1.5]
    same, felt = float(np.max(np.abs(r8[-3:] - 1))), float(np.min(np.abs(r8[near] - 1)))
    rows = [{"bar_from_right": n - k, "gap_left_mm": float(gaps[k - 1]) if k else 0.0,
             "gap_right_mm": float(gaps[k]) if k < n - 1 else 0.0,
             **{f"SED {label}": float(r[k]) for label, r in under.items()},
             "max compressive strain 8 mm": float(c8[k])} for k in range(n)]
    return Finding(
        "fig4-11_neighbours", "4.5.2, figure 4-11", "Strain under a bar and its neighbours (8 mm model)",
        QUOTES["fig4-11_neighbours"],
        [Check("largest difference of SED at 0.75 mm under the three rightmost bars from the rightmost's", 100 * same,
               "<", 5.0, "%", why="'almost identical' read as within 5 %"),
         Check("smallest difference of SED under a bar next to a gap under 1.5 mm from the rightmost's", 100 * felt,
               ">", 10.0, "%", why="'influenced' read as beyond 10 %")],
        "SED at the central receptor, 0.75 mm deep, with each bar centred over it, over the rightmost bar's "
        "(bars from the left, gaps " + ", ".join(f"{g:g}" for g in gaps) + " mm): "
        + ", ".join(f"{v:.3f}" for v in r8) + f"; {len(near)} bars lie next to a gap under 1.5 mm. Max compressive "
        "strain: " + ", ".join(f"{v:.3f}" for v in c8) + ". The recorded SA-I profile of the figure is printed as a "
        "curve only and is not compared.",
        "receptor position along the grating [mm]", "SED at 0.75 mm / under the rightmost bar",
        [Series("8 mm cylinder with bone", _along(runs),
                (runs[l8]["sed_MPa"][:, CENTRE] / runs[l8]["sed_MPa"][at[-1], CENTRE]).tolist(), "-"),
         Series("bar centred over the receptor", edges.mean(axis=1).tolist(), r8.tolist(), "o")], rows)


def _more_bars_finding(runs, at) -> Finding:
    """Figure 4-12 and 4.5.3: the 16 mm model reaches more bars."""
    l8, l16, _ = (label for _, label, _ in GRATING_MODELS)
    gaps = runs["gaps_mm"]
    n = len(runs["edges_mm"])
    t8, t16 = runs[l8]["touching"], runs[l16]["touching"]
    second, last = at[-2], at[-1]
    bars8 = [np.flatnonzero(runs[l8]["bar_force"][i] > 0) for i in (last, second)]
    bars16 = [np.flatnonzero(runs[l16]["bar_force"][i] > 0) for i in (last, second)]
    reach = {R: float(np.sqrt(2 * R - 1)) for R in (4.0, 8.0)}    # half-chord of a 1 mm deep cap, mm
    return Finding(
        "fig4-12_diameter", "4.5.2, figure 4-12", "More bars touch the 16 mm model", QUOTES["fig4-12_diameter"],
        [Check("bars touching with the second bar from the right centred, 16 mm minus 8 mm model",
               float(len(bars16[1]) - len(bars8[1])), ">", 0.0, why="'in the 16 mm model both bars 1 and 3 indent'"),
         Check("bars touching the 16 mm model with the second bar from the right centred", float(len(bars16[1])), ">",
               2.5, why="bars 1, 2 and 3"),
         Check("bars touching with the rightmost bar centred, 16 mm minus 8 mm model",
               float(len(bars16[0]) - len(bars8[0])), "<", 1.5,
               why="'no significant difference in loading' as bar 2 'barely touches' the 16 mm model")],
        f"Bars touching (numbered from the right as in the thesis), rightmost bar centred: 8 mm "
        f"{_from_right(bars8[0], n)}, 16 mm {_from_right(bars16[0], n)}; second bar centred: 8 mm "
        f"{_from_right(bars8[1], n)}, 16 mm {_from_right(bars16[1], n)}. Mean over the sweep {t16.mean():.2f} bars "
        f"(16 mm) against {t8.mean():.2f} (8 mm). An undeformed cylinder indented 1 mm is reached within "
        f"{reach[4.0]:.2f} mm (8 mm) or {reach[8.0]:.2f} mm (16 mm) of its top; the gaps next to the second bar are "
        f"{gaps[-2]:g} mm (to bar 3) and {gaps[-1]:g} mm (to bar 1) on this grating, the thesis lists none.",
        "receptor position along the grating [mm]", "bars touching",
        [Series(label, _along(runs), runs[label]["touching"].tolist(), "-") for _, label, _ in GRATING_MODELS[:2]], [])


def _rightmost_finding(runs, under, at) -> Finding:
    """4.5.3: the two rightmost bars on the 16 mm model."""
    l8, l16, _ = (label for _, label, _ in GRATING_MODELS)
    r8, r16 = under[l8], under[l16]
    last = at[-1]
    d8, d16 = float(abs(r8[-2] - 1)), float(abs(r16[-2] - 1))
    return Finding(
        "sec4-5-3_rightmost_bars", "4.5.3, figures 4-13 and 4-14", "The two rightmost bars on the 16 mm model",
        QUOTES["sec4-5-3_rightmost_bars"],
        [Check("SED difference under the two rightmost bars, 16 mm model", 100 * d16, ">", 5.0, "%",
               why="'not identical' read as more than 5 % apart"),
         Check("SED difference under the two rightmost bars, 8 mm model", 100 * d8, "<", 5.0, "%",
               why="'as was the case for 8 mm diameter model' (identical): within 5 %")],
        f"SED at the central receptor under the second bar from the right over that under the rightmost: "
        f"{r8[-2]:.3f} (8 mm), {r16[-2]:.3f} (16 mm). The fits to the recorded profiles are not run (recordings "
        "printed as curves only).",
        "receptor position along the grating [mm]", "SED at 0.75 mm / under the rightmost bar",
        [Series(label, _along(runs), (runs[label]["sed_MPa"][:, CENTRE] / runs[label]["sed_MPa"][last, CENTRE]).tolist(),
                "-") for _, label, _ in GRATING_MODELS[:2]], [])


def _off_centre_finding(runs) -> Finding:
    """Figure 4-18: receptors off the centre see other spatial profiles on the cylinder only."""
    l8, _, block = (label for _, label, _ in GRATING_MODELS)
    pos = runs["positions_mm"]
    off = {(label, x): _off_centre(runs, label, x) for _, label, _ in GRATING_MODELS for x in (1.0, 2.0)}
    v = runs[l8]["sed_MPa"]
    shifted = [Series(f"receptor {x:g} mm off-centre, shifted", (x - pos).tolist(),
                      (v[:, np.flatnonzero(np.isclose(SITES_MM, x))[0]] / v[:, CENTRE].max()).tolist(), "--")
               for x in (1.0, 2.0)]
    return Finding(
        "fig4-18_off_centre", "4.5.4, figure 4-18", "Spatial profiles of off-centre receptors",
        QUOTES["fig4-18_off_centre"],
        [Check("RMS difference of the shifted SED profile from the central one, receptor 1 mm off-centre, 8 mm "
               "model, over that on the semi-infinite block", off[l8, 1.0] / max(off[block, 1.0], 1e-12), ">", 2.0,
               why="'different' on the cylinder where 'identical' on a semi-infinite model: at least twice the block's"),
         Check("the same, receptor 2 mm off-centre", off[l8, 2.0] / max(off[block, 2.0], 1e-12), ">", 2.0)],
        "RMS difference of the shifted profile from the central one, over the central peak, 1 and 2 mm "
        "off-centre: " + "; ".join(f"{label} {off[label, 1.0]:.3f}, {off[label, 2.0]:.3f}" for _, label, _ in
                                   GRATING_MODELS) + " (a half-space, invariant under translation, gives 0).",
        "receptor position along the grating [mm]", "SED at 0.75 mm / central peak (8 mm model)",
        [Series("central receptor", _along(runs), (v[:, CENTRE] / v[:, CENTRE].max()).tolist(), "-")] + shifted,
        [{"model": label, "receptor_off_centre_mm": x, "rms_difference": d} for (label, x), d in off.items()])


def _central_profile_finding(runs, under, at) -> Finding:
    """4.5.4: the central spatial profile against the semi-infinite model's."""
    l8, _, block = (label for _, label, _ in GRATING_MODELS)
    pos = runs["positions_mm"]
    r8, rb = under[l8], under[block]
    last = at[-1]
    a, b = runs[l8]["sed_MPa"], runs[block]["sed_MPa"]
    rms = lambda u, w: float(np.sqrt(np.mean((u / u.max() - w / w.max()) ** 2)))
    profile = rms(a[:, CENTRE], b[:, CENTRE])
    population = float(np.median([rms(a[i], b[i]) for i in range(len(pos))]))
    share = runs[block]["bar_force"][last] / runs[block]["force"][last]
    return Finding(
        "sec4-5-4_central_profiles", "4.5.4 (figures 4-10 and 4-11)",
        "Central spatial profiles of cylinder and semi-infinite model", QUOTES["sec4-5-4_central_profiles"],
        [Check("RMS difference of the peak-normalised central SED profiles (8 mm cylinder against semi-infinite "
               "block) over the median RMS difference of their population responses", profile / population, "<", 1.0,
               why="profiles 'similar' where the population responses are 'very different': the profiles closer")],
        f"Central spatial profiles differ by {profile:.3f} (RMS of peak-normalised SED), the population responses "
        f"across the receptors within 3 mm by {population:.3f} (median over the positions). SED under each bar over "
        "the rightmost's: cylinder " + ", ".join(f"{x:.2f}" for x in r8) + "; block " + ", ".join(f"{x:.2f}" for x in rb)
        + f". On the block, with the rightmost bar over the receptor, that bar carries {100 * share[-1]:.0f} % of the "
        f"force, the leftmost {100 * share[0]:.0f} %, the inner ones {100 * share[1:-1].min():.0f}-"
        f"{100 * share[1:-1].max():.0f} %. The thesis compares with Phillips and Johnson's half-space profiles, "
        "printed as curves only; the project's semi-infinite block stands in for them.",
        "receptor position along the grating [mm]", "SED at 0.75 mm / its peak",
        [Series(label, _along(runs),
                (runs[label]["sed_MPa"][:, CENTRE] / runs[label]["sed_MPa"][:, CENTRE].max()).tolist(), "-")
         for label in (l8, block)], [])


# ----------------------------------------------------------------------------- 4.5.5: gaps
def gap_detection(shop: Workshop) -> list[Finding]:
    """Thesis 4.5.5, figures 4-19 and 4-20: peaks of |shear strain| at 0.75 mm on both sides of the gap
    between two 2 mm bars (the bars of figure 4-19) indented 1 mm into the cylinder with bone."""
    probe = receptor_probe(shop.folder("cylinder8_bone"), sites_mm=np.round(np.arange(-3.5, 3.5001, 0.05), 3),
                           rigid_bone=True)
    gaps = np.array([0.25, 0.5, 0.75, 1.0, 1.5, 2.0, 3.0])
    rows, _ = gap_analysis(probe, 2.0, gaps)
    dist = np.array([r["interpeak_mm"] for r in rows])
    wide, narrow = gaps >= 1.0, gaps <= 0.5
    follows = float(np.max(np.abs(dist[wide] / gaps[wide] - 1)))
    slope = max(abs(r["slope_per_mm"]) for r in rows)
    return [Finding(
        "fig4-19_gaps", "4.5.5, figures 4-19 and 4-20", "Shear-strain peaks across a gap", QUOTES["fig4-19_gaps"],
        [Check("largest |inter-peak distance / gap - 1| for gaps of 1 mm and more", 100 * follows, "<", 10.0, "%",
               why="the distance follows the gap above the knee"),
         Check("smallest inter-peak distance minus the gap, gaps of 0.5 mm or less", float(np.min(dist[narrow] -
               gaps[narrow])), ">", 0.2, "mm", why="a knee: below it the distance stops following the gap")],
        "Inter-peak distance for gaps " + ", ".join(f"{g:g}" for g in gaps) + " mm: "
        + ", ".join(f"{x:.2f}" for x in dist) + f" mm. The bars are equal, so the line joining the peaks is flat "
        f"(|slope| at most {slope:.4f} per mm). The thesis states the cue as a hypothesis and relates it to d' "
        "through its grating runs; the human d' data are printed as points on a figure only and are not compared, "
        "nor is where the thesis's settling trend lies (the knee is judged here).",
        "gap [mm]", "distance between the |shear strain| peaks [mm]",
        [Series("inter-peak distance", gaps.tolist(), dist.tolist()),
         Series("distance = gap", [0.0, 3.0], [0.0, 3.0], "k:")], rows)]
