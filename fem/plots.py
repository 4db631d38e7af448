"""Every figure the FE stage writes, drawn on `matplotlib.figure.Figure` objects (no pyplot, no
global backend switch: importing or calling this module changes no matplotlib state).

Each `*_figure` function takes result objects and arrays and returns a Figure; `save` writes one.
"""
from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure
from matplotlib.ticker import FuncFormatter, MaxNLocator, ScalarFormatter

from fem.contact.facets import PEAK_PRESSURE_RADIUS_MM
from fem.io.runfolder import pad3
from fem.receptors.analysis import model_values


def save(fig: Figure, path, dpi: int = 110) -> None:
    """Lay out and write a figure (PNG by the path's suffix): constrained layout unless the figure
    chose one, so labels, titles and colour bars stay inside the canvas; every linear axis labels
    its ticks with plain numbers (`plain_numbers`)."""
    if fig.get_layout_engine() is None:
        fig.set_layout_engine("constrained")
    plain_numbers(fig)
    fig.savefig(path, dpi=dpi)


def plain_numbers(fig: Figure) -> Figure:
    """Tick labels as the numbers themselves, to 4 significant digits (2.5e-05, 0.9999, 1.2e+04),
    on every linear axis of the figure: never an offset or a shared multiplier beside the axis,
    which a reader misses ("1e-6+9.9992e-1")."""
    for ax in fig.axes:
        for axis in (ax.xaxis, ax.yaxis):
            if axis.get_scale() == "linear":
                axis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:.4g}" if v != 0 else "0"))
    return fig


UNITS = {"MPa": "MPa", "mm": "mm", "N": "N", "mm2": "mm$^2$", "Nmm": "N mm", "deg": "deg"}


def axis_label(name: str, dim: int = 3) -> str:
    """A column or measure name as an axis label with its unit: 'max_pressure_MPa' -> 'max pressure,
    MPa'; forces per mm of length and contact widths in 2D (plane strain); names without a unit
    suffix (strains) are dimensionless."""
    stem, _, unit = name.rpartition("_")
    if not stem or unit not in UNITS:
        return name.replace("_", " ") + ", -" if "strain" in name else name.replace("_", " ")
    text = UNITS[unit]
    if dim == 2 and unit == "N":
        text = "N/mm"
    if dim == 2 and unit == "mm2":
        text = "mm (width)"
    return f"{stem.replace('_', ' ')}, {text}"


def force_unit(dim: int) -> str:
    """Force unit of a model: N in 3D, N per mm of length in 2D plane strain."""
    return "N/mm" if dim == 2 else "N"


# --------------------------------------------------------------------------- indentation runs
KEY_LABELS = {"depth_mm": "depth, mm", "time_s": "time, s", "offset_x_mm": "indentor offset along x, mm",
              "offset_z_mm": "indentor offset along z, mm"}


def indent_force_figure(name: str, key: str, x, force_N, peak_pressure_MPa, max_pressure_MPa, dim: int = 3,
                        depth_mm=None) -> Figure:
    """Total force (N; N/mm in 2D) and peak contact pressure of one experiment against x (k,)
    (its column `key`: depth or sweep offset, mm): the peak averaged over PEAK_PRESSURE_RADIUS_MM
    (k,) and the nodal peak (k,). depth_mm (k,): a sweep at constant force, whose depth reached is
    drawn instead of the force."""
    fig = Figure(figsize=(10, 4))
    ax = fig.subplots(1, 2)
    if depth_mm is not None:
        ax[0].plot(x, depth_mm, "o-")
        ax[0].set(xlabel=KEY_LABELS.get(key, key), ylabel="depth reached, mm",
                  title=f"{name}: depth at {np.mean(force_N):.3g} {force_unit(dim)}")
    else:
        ax[0].plot(x, force_N, "o-")
        ax[0].set(xlabel=KEY_LABELS.get(key, key), ylabel=f"force, {force_unit(dim)}", title=f"{name}: force")
    ax[1].plot(x, peak_pressure_MPa, "o-", label=f"averaged over {PEAK_PRESSURE_RADIUS_MM:g} mm")
    ax[1].plot(x, max_pressure_MPa, ".--", label="at a node")
    ax[1].set(xlabel=KEY_LABELS.get(key, key), ylabel="peak pressure, MPa", title="peak contact pressure")
    ax[1].legend(fontsize=8)
    return fig


def indent_profile_figure(name: str, across_mm, results, dim: int = 3) -> Figure:
    """Surface deflection and pressure across the indentor: across_mm (n,) positions of the
    chosen surface nodes, in order; results: [(label, deflection (n,) mm, pressure (n,) MPa)]. In
    3D the nodes of a band along the indentor's centre line are drawn as points (their distances
    along the indentor differ, so a line through them would zigzag); in 2D as lines."""
    fig = Figure(figsize=(8, 6))
    ax = fig.subplots(2, 1, sharex=True)
    style = dict(marker=".", ms=3, ls="none") if dim == 3 else {}
    for k, (label, deflection, pressure) in enumerate(results):
        colour = f"C{k % 10}"
        ax[0].plot(across_mm, -deflection, label=label, color=colour, **style)
        ax[1].plot(across_mm, pressure, color=colour, **style)
    ax[0].set(ylabel="surface displacement, mm", title=f"{name}: surface profile (displacement along the "
                                                          "approach, down negative)")
    ax[0].legend(fontsize=7, title="depth", title_fontsize=7)
    ax[1].set(xlabel="position across the indentor, mm", ylabel="contact pressure, MPa")
    return fig


def indent_receptors_figure(curves: dict, xlabel: str, title: str = "") -> Figure:
    """Receptor measures, one panel per measure: curves {measure: [(label, x (k,), values (k,),
    style)]} (labels: the receptor depths; a profile across the pad or against the sweep
    position); title: which indentation(s) it shows."""
    fig = Figure(figsize=(8, 1.2 + 2.2 * len(curves)))
    axes = fig.subplots(len(curves), 1, sharex=True, squeeze=False)
    for (m, lines), a in zip(curves.items(), axes[:, 0]):
        for label, x, vals, style in lines:
            a.plot(x, vals, style, label=label)
        a.set_ylabel(axis_label(m), fontsize=8)
        a.legend(fontsize=7, title="receptor depth", title_fontsize=7, loc="best")
    axes[-1, 0].set_xlabel(xlabel)
    if title:
        fig.suptitle(title, fontsize=10)
    return fig


def indent_pressure_figure(name: str, along_mm, across_mm, pressure_MPa, depth_mm: float) -> Figure:
    """Contact pressure map (3D) of one indentation seen along the approach: surface nodes at
    (along, across) (m,) mm in the indentor's axes."""
    fig = Figure(figsize=(6, 5), layout="constrained")      # set before the colour bar is added
    ax = fig.subplots()
    sc = ax.scatter(along_mm, across_mm, c=pressure_MPa, s=6, cmap="viridis")
    ax.set(xlabel="along the indentor, mm", ylabel="across the indentor, mm", aspect="equal",
           title=f"{name}: contact pressure, depth {depth_mm:.2f} mm")
    fig.colorbar(sc, ax=ax, label="contact pressure, MPa")
    return fig



def judged_step(run) -> int:
    """Index of the indentation an experiment's single-state figures show: the deepest one (a
    trace's hold, not its release; the last of a depth series; the first of equal depths)."""
    depth = np.array([r.depth_mm.max() for _, r in run.steps])
    return int(np.flatnonzero(depth >= depth.max() - 1e-12)[0])


def profile_steps(run, sweep: bool, most: int = 8) -> list[int]:
    """Indices of the indentations whose surface profiles are drawn: a sweep's judged one; else up
    to `most` of the distinct depths up to the deepest, evenly spread (a trace's ramp, a series)."""
    if sweep:
        return [judged_step(run)]
    depth = np.array([r.depth_mm.max() for _, r in run.steps])
    last = judged_step(run)
    levels, first = np.unique(np.round(depth[:last + 1], 9), return_index=True)
    pick = np.unique(np.round(np.linspace(0, len(levels) - 1, min(most, len(levels)))).astype(int))
    return sorted(first[pick].tolist())


def receptor_profile(scene_run, ind):
    """(site coordinate (s,) mm, its label, sites (s,) bool) the receptor figure plots a profile
    along: the sites on the indentor's centre line across it (within 0.5 mm, or the nearest);
    where that leaves a single site per depth (a receptor line along the indentor's length, a
    line of one site), the sites along the receptor line or the indentor's length instead."""
    g = scene_run.sampler.grid
    x = pad3(g.sites_mm) - ind.origin_mm
    u, v = x @ ind.e1, x @ ind.e2
    across = np.abs(u) <= max(0.5, np.abs(u).min() + 1e-9)
    if len(np.unique(np.round(v[across], 6))) > 1:
        return v, "receptor site across the indentor (on its centre line), mm", across
    if scene_run.line is not None:              # sites on a plane: along the coordinate that varies
        free = [a for a in range(pad3(g.sites_mm).shape[1]) if a != scene_run.line[0]]
        axis = max(free, key=lambda a: np.ptp(pad3(g.sites_mm)[:, a]))
        return pad3(g.sites_mm)[:, axis], f"receptor site along {'xyz'[axis]} on the receptor line, mm", \
            np.ones(len(u), bool)
    along = np.abs(v) <= max(0.5, np.abs(v).min() + 1e-9)
    return u, "receptor site along the indentor (under its centre), mm", along


def indent_figures(run, scene_run, tables) -> dict[str, Figure]:
    """{file name: Figure} of one experiment (fem.experiments.runner.ExperimentRun of a SceneRun, with its
    fem.io.runfolder.run_tables): <name>_force.png (two or more indentations), _profile.png,
    _receptors.png and (3D) _pressure.png. Single-state figures show the judged indentation
    (`judged_step`: a trace's hold, not its release)."""
    figures = {}
    name, ind, steps, rows = run.name, run.indentor, run.steps, tables["steps"]
    sweep = len({tuple(o) for o, _ in steps}) > 1
    key = "offset_x_mm" if sweep and any(rows["offset_x_mm"]) else ("offset_z_mm" if sweep else "depth_mm")
    key = "time_s" if "time_s" in rows else key
    dim = scene_run.model.dim
    if len(steps) > 1:                    # one indentation: its values are in the profile and summary
        figures[f"{name}_force.png"] = indent_force_figure(name, key, rows[key], rows["force_N"],
                                                           rows["peak_pressure_MPa"], rows["max_pressure_MPa"], dim,
                                                           rows["depth_mm"] if key != "depth_mm" and
                                                           run.experiment.force_N is not None else None)
    # deflection and pressure across the indentor (nodes near its centre line)
    x3 = pad3(scene_run.surface.x)
    u, v = (x3 - ind.origin_mm) @ ind.e1, (x3 - ind.origin_mm) @ ind.e2
    near = np.abs(u) <= max(0.5, np.sort(np.abs(u))[min(len(u) - 1, 50)])
    order = np.argsort(v[near])
    shown = [(f"{steps[i][1].depth_mm.max():.2f} mm", steps[i][1].deflection_mm[near][order],
              steps[i][1].pressure_MPa[near][order]) for i in profile_steps(run, sweep)]
    figures[f"{name}_profile.png"] = indent_profile_figure(name, v[near][order], shown, dim)
    # receptor measures: profile along the sites (judged step) or against the sweep position
    g = scene_run.sampler.grid
    j = judged_step(run)
    coord, xlabel, on = receptor_profile(scene_run, ind)
    curves = {}
    for m in scene_run.measures:
        curves[m] = []
        for d in np.unique(g.depth_mm):
            sel = (g.depth_mm == d) & on[g.site]
            if sweep:
                k = np.flatnonzero(sel)[np.argmin(np.abs(coord[g.site[sel]]))]
                curves[m].append((f"{d:g} mm", rows[key], tables["values"][m][:, k], "-"))
            else:
                o = np.argsort(coord[g.site[sel]])
                curves[m].append((f"{d:g} mm", coord[g.site[sel]][o], tables["values"][m][j][sel][o], ".-"))
    xlabel = KEY_LABELS[key] if sweep else xlabel
    if curves:                            # a scene may ask for no receptor measures
        figures[f"{name}_receptors.png"] = indent_receptors_figure(curves, xlabel, _receptor_title(run, sweep, j, dim))
    if scene_run.model.dim == 3:          # contact pressure map of the judged indentation
        r = steps[j][1]
        figures[f"{name}_pressure.png"] = indent_pressure_figure(name, u, v, r.pressure_MPa, r.depth_mm.max())
    return figures


def _receptor_title(run, sweep: bool, j: int, dim: int) -> str:
    """The receptor figure's title: which indentation it shows, at what load."""
    name, steps, exp = run.name, run.steps, run.experiment
    r = steps[j][1]
    load = f"force {r.total_force_N:.3g} {force_unit(dim)}" if exp.force_N is not None else f"depth {r.depth_mm.max():.3g} mm"
    if sweep:
        return f"{name}: receptors under the indentor's centre line at each offset ({load})"
    when = f" at t = {exp.times_s[j]:.3g} s" if exp.times_s is not None else ""
    reached = f", depth reached {r.depth_mm.max():.3g} mm" if exp.force_N is not None else ""
    return f"{name}: receptors of indentation {j + 1} of {len(steps)}{when} ({load}{reached})"


# --------------------------------------------------------------------------- afferents
CLASS_COLOURS = {"SA1": "tab:green", "RA": "tab:blue", "PC": "tab:orange"}


def afferent_figures(name: str, resp, depth_mm) -> dict[str, Figure]:
    """{file name: Figure} of a traced experiment's afferents (fem.receptors.afferents.PopulationResponse):
    <name>/raster.png (the course, the spikes of every afferent by class and position, and the
    population rate per class in 20 ms bins) and <name>/rate_map.png (mean rate of each afferent at
    its site on the pad, one panel per class). depth_mm (k,): depth reached at each sample time."""
    pop, t = resp.population, resp.times_s
    cls = pop.afferent_class.astype(str)
    classes = [c for c in CLASS_COLOURS if c in set(cls)]
    order = np.lexsort((pop.site_mm[:, 0], pop.site_mm[:, 2], [classes.index(c) for c in cls]))
    fig = Figure(figsize=(9, 7))
    ax = fig.subplots(3, 1, sharex=True, height_ratios=(1, 3, 1.4))
    ax[0].plot(t, depth_mm, "k-")
    ax[0].set(ylabel="depth, mm", title=f"{name}: {len(pop)} afferents")
    for row, i in enumerate(order):
        if len(resp.spikes[i]):
            ax[1].plot(resp.spikes[i], np.full(len(resp.spikes[i]), row), "|", ms=3, color=CLASS_COLOURS[cls[i]])
    ax[1].set(ylabel="afferent (by class, z, x)", ylim=(-1, len(pop)))
    bins = np.arange(0.0, t[-1] + 0.02, 0.02)
    for c in classes:
        sel = np.flatnonzero(cls == c)              # not empty: c is one of the population's classes
        h, _ = np.histogram(np.concatenate([resp.spikes[i] for i in sel]), bins)
        ax[2].step(bins[:-1], h / (0.02 * sel.size), where="post", color=CLASS_COLOURS[c], label=c)
    ax[2].set(xlabel="time, s", ylabel="mean rate, Hz")
    ax[2].legend(fontsize="small")
    return {f"{name}/raster.png": fig, f"{name}/rate_map.png": rate_map_figure(resp)}


def rate_map_figure(resp, width_in: float = 4.5) -> Figure:
    """The mean rate of each afferent of a fem.receptors.afferents.PopulationResponse over its
    course, at its site on the pad (x, z), one panel per class, width_in inches each."""
    pop, rate = resp.population, resp.rates_hz()
    cls = pop.afferent_class.astype(str)
    classes = [c for c in CLASS_COLOURS if c in set(cls)]
    fig = Figure(figsize=(width_in * len(classes), width_in * 8 / 9), layout="constrained")  # before colour bars
    for a, c in zip(fig.subplots(1, len(classes), squeeze=False)[0], classes):
        sel = cls == c
        sc = a.scatter(pop.site_mm[sel, 0], pop.site_mm[sel, 2], c=rate[sel], s=14, cmap="viridis",
                       vmin=0, vmax=max(rate[sel].max(), 1e-9))
        a.set(xlabel="x, mm", ylabel="z, mm", title=f"{c}: mean rate over {resp.duration_s:.2f} s", aspect="equal")
        fig.colorbar(sc, ax=a, label="Hz")
    return fig


# --------------------------------------------------------------------------- biomechanics
def _profile_pair(title: str):
    """(Figure, [linear axes, log-distance axes]) for deflection profiles against distance."""
    fig = Figure(figsize=(11, 4))
    ax = fig.subplots(1, 2)
    ax[0].set(xlabel="distance from the load, mm", ylabel="deflection, mm (into the finger +)", title=title)
    ax[1].set(xlabel="distance from the load, mm (log)", title=title + " (log distance)")
    ax[1].set_xscale("log")
    return fig, ax


def _plot_deflection(ax, distance_mm, deflection_mm, style="-", label=""):
    """A profile on a (linear, log-distance) axes pair; the log axes leave out distance 0."""
    pos = distance_mm > 0
    ax[0].plot(distance_mm, deflection_mm, style, label=label)
    ax[1].plot(distance_mm[pos], deflection_mm[pos], style, label=label)


def _plot_measured(ax, data, label="data"):
    """Measured profiles (fem.biomech.deflection.Profile) as crosses on every axes."""
    for p in data:
        pos = p.distance_mm > 0
        for a in ax:
            log = a.get_xscale() == "log"
            a.plot(p.distance_mm[pos] if log else p.distance_mm, p.deflection_mm[pos] if log else p.deflection_mm,
                   "kx", ms=5, label=f"{label} {p.depth_mm:g} mm")


def _plot_idealised(ax, fits, reach_mm):
    """The waterbed and beam curves {kind: fem.biomech.deflection.FreeLengthFit} from 0 to reach_mm."""
    x = np.linspace(0, reach_mm, 400)
    for kind, f in fits.items():
        lab = f"{kind} L={f.length_mm:.3g} mm" + (" (at bound)" if f.at_bound else "")
        _plot_deflection(ax, x, f(x), ":" if kind == "waterbed" else "--", lab)


def _legends(ax, data=()):
    """Add the measured profiles (if any) and small legends to every axes."""
    _plot_measured(ax, data)
    for a in ax:
        a.legend(fontsize=6)


def layer_study_figure(study, data=()) -> Figure:
    """Thesis figure 6-10 from a fem.biomech.deflection.LayerStudy at its last depth: one row per varied layer,
    its codes' profiles (linear and log distance), the measured profiles of that depth, and a line
    where the layer matters most."""
    k = len(study.depths_mm) - 1
    depth = study.depths_mm[k]
    fig = Figure(figsize=(11, 3.2 * len(study.layers)))
    axes = fig.subplots(len(study.layers), 2, squeeze=False)
    for row, (layer, codes) in zip(axes, study.layers.items()):
        row[1].set_xscale("log")
        for code in codes:
            p = study.profiles[code][k]
            _plot_deflection(row, p.distance_mm, p.deflection_mm, "-", code)
        _plot_measured(row, [p for p in data if abs(p.depth_mm - depth) < 1e-9])
        eff = next(e for e in study.effects if e.layer == layer and e.depth_mm == depth)
        for a in row:
            a.axvline(eff.most_affected_mm, color="0.6", lw=0.8)
            a.legend(fontsize=7)
        row[0].set(ylabel=f"layer {layer}: deflection, mm",
                   title=f"layer {layer}, depth {depth:g} mm: most affected at {eff.most_affected_mm:.2f} mm")
    axes[-1, 0].set_xlabel("distance from the load, mm")
    axes[-1, 1].set_xlabel("distance from the load, mm (log)")
    return fig


def base_profiles_figure(title: str, profiles, fits, data=()) -> Figure:
    """Model profiles (one per depth) with their waterbed and beam fits ({kind: FreeLengthFit} per
    profile) and the measured profiles."""
    fig, ax = _profile_pair(title)
    for p, fd in zip(profiles, fits):
        _plot_deflection(ax, p.distance_mm, p.deflection_mm, "-", f"model {p.depth_mm:g} mm")
        _plot_idealised(ax, fd, p.distance_mm[-1])
    _legends(ax, data)
    return fig


def deflection_fit_figure(data, fitted, start, base: str, fits) -> Figure:
    """Measured profiles against the fitted material's and the base material's (one Profile per
    measured depth each), with the waterbed and beam fits of the measured profiles."""
    fig, ax = _profile_pair("deflection fit")
    for p, b, s, fd in zip(data, fitted, start, fits):
        _plot_deflection(ax, b.distance_mm, b.deflection_mm, "-", f"fit {p.depth_mm:g} mm")
        _plot_deflection(ax, s.distance_mm, s.deflection_mm, "-.", f"{base} {p.depth_mm:g} mm")
        _plot_idealised(ax, fd, p.distance_mm[-1])
    _legends(ax, data)
    return fig


def force_scale_figure(scale) -> Figure:
    """Measured forces and the scaled model forces of a fem.biomech.fit.ForceScale against depth."""
    fig = Figure(figsize=(5, 4))
    a = fig.subplots()
    a.plot(scale.depths_mm, scale.measured_N, "kx", label="measured")
    a.plot(scale.depths_mm, scale.scale * scale.model_N, "o-", label=f"model x {scale.scale:.3g}")
    a.set(xlabel="depth_mm", ylabel="force_N", title="force scale")
    a.legend()
    return fig


def cylinder_series_figure(s, dim: int) -> Figure:
    """Contact area (2D: width), peak pressure and depth (or force) against cylinder diameter, one
    line per load, of a fem.biomech.deflection.CylinderSeries (thesis figs. 4-25, 5-14)."""
    force_unit = "N/mm" if dim == 2 else "N"
    fig = Figure(figsize=(14, 4))
    ax = fig.subplots(1, 3)
    for j, v in enumerate(s.loads):
        lab = f"{v:g} " + (force_unit if s.load_kind == "force" else "mm")
        ax[0].plot(s.diameters_mm, s.contact_area_mm2[j], "o-", label=lab)
        ax[1].plot(s.diameters_mm, s.max_pressure_MPa[j], "o-", label=lab)
        ax[2].plot(s.diameters_mm, s.depth_mm[j] if s.load_kind == "force" else s.force_N[j], "o-", label=lab)
    ax[0].set(xlabel="cylinder diameter, mm", ylabel="contact width, mm" if dim == 2 else "contact area, mm^2",
              title=f"contact vs diameter at constant {s.load_kind}")
    ax[1].set(xlabel="cylinder diameter, mm", ylabel="max contact pressure, MPa", title="peak pressure")
    ax[2].set(xlabel="cylinder diameter, mm",
              ylabel="depth, mm" if s.load_kind == "force" else f"force, {force_unit}",
              title="depth needed" if s.load_kind == "force" else "force needed")
    _legends(ax)
    return fig


def line_load_figure(c, large_deformation: bool) -> Figure:
    """Surface deflection per depth and force against depth of a fem.biomech.line_load.LineLoadComparison
    (linear; with large_deformation also the neo-Hookean solve)."""
    fig = Figure(figsize=(12, 4))
    ax = fig.subplots(1, 2)
    for k, d in enumerate(c.depths_mm):
        line = ax[0].plot(c.distance_mm, c.deflection_linear_mm[k], "-", label=f"linear {d:g} mm")[0]
        if large_deformation:
            ax[0].plot(c.distance_mm, c.deflection_nonlinear_mm[k], "--", color=line.get_color(),
                       label=f"large deformation {d:g} mm")
    ax[0].set(xlabel="undeformed distance from the load, mm", ylabel="deflection, mm (into the finger +)",
              title="surface deflection under the line load")
    ax[1].plot(c.depths_mm, c.force_linear_N, "o-", label="linear")
    if large_deformation:
        ax[1].plot(c.depths_mm, c.force_nonlinear_N, "s--", label="large deformation")
    ax[1].set(xlabel="depth, mm", ylabel="force, " + ("N/mm" if c.dim == 2 else "N"), title="force vs depth")
    _legends(ax)
    return fig




# --------------------------------------------------------------------------- cohorts
COHORT_PANELS = 6
"""Experiments drawn by cohort_figure (the first ones; summary.csv has them all)."""

def cohort_figure(curves: dict, title: str = "") -> Figure:
    """Subjects compared per experiment: force and peak pressure against depth, one column per
    experiment (at most COHORT_PANELS), one line per subject. curves: {experiment: {subject:
    (depth_mm (k,), force (k,), max_pressure_MPa (k,))}}; forces in N, N/mm on 2D models."""
    names = list(curves)[:COHORT_PANELS]
    fig = Figure(figsize=(3.4 * len(names) + 1.0, 6.0))
    axes = fig.subplots(2, len(names), squeeze=False)
    for name, (top, bottom) in zip(names, axes.T):
        for subject, (depth, force, pressure) in curves[name].items():
            top.plot(depth, force, "o-", ms=4, label=subject)
            bottom.plot(depth, pressure, "o-", ms=4, label=subject)
        top.set(title=name, ylabel="force, N (N/mm in 2D)")
        bottom.set(xlabel="depth, mm", ylabel=f"peak pressure over {PEAK_PRESSURE_RADIUS_MM:g} mm, MPa")
    axes[0, 0].legend(fontsize=7)
    if title:
        fig.suptitle(title)
    return fig


# --------------------------------------------------------------------------- receptor analysis
def response_profiles_figure(runs, data, fits) -> Figure:
    """Recorded rates (fem.receptors.neural.NeuralData of one unit) and the rates predicted by linear receptor
    fits (fem.receptors.analysis.Fit) against stimulus position, one panel per stimulus; with one indentation
    per stimulus (e.g. cylinders at constant force, thesis figure 4-26) one panel over the stimuli."""
    stimuli = data.stimuli
    if all(len(set(data.position_mm[data.stimulus == s])) == 1 for s in stimuli):
        fig = Figure(figsize=(max(5, 0.8 * len(stimuli) + 2), 3.6))
        ax = fig.subplots()
        k = np.arange(len(stimuli))
        ax.plot(k, [data.rate_ips[data.stimulus == s].mean() for s in stimuli], "kx", ms=9, mew=2, label="recorded")
        for f in fits:
            ax.plot(k, [f.predict(runs, s, data.position_mm[data.stimulus == s][:1])[0] for s in stimuli], "o-",
                    label=f"{f.measure} (depth {f.depth_mm:g} mm)")
        ax.set_xticks(k, stimuli, rotation=30 if len(stimuli) > 6 else 0, ha="right" if len(stimuli) > 6 else "center")
        ax.set(ylabel="rate, imp/s", xlabel="stimulus")
        ax.legend(fontsize=7)
        return fig
    fig = Figure(figsize=(9, 2.4 * len(stimuli)))
    axes = fig.subplots(len(stimuli), 1, squeeze=False)
    for s, ax in zip(stimuli, axes[:, 0]):
        part = data.only(stimuli=[s])
        o = np.argsort(part.position_mm)
        ax.plot(part.position_mm[o], part.rate_ips[o], "k-", lw=1.5, label="recorded")
        for f in fits:
            dense = np.linspace(part.position_mm.min(), part.position_mm.max(), 400)
            ax.plot(dense, f.predict(runs, s, dense), lw=1,
                    label=f"{f.measure} (depth {f.depth_mm:g} mm" + ("" if np.isnan(f.diameter_mm) else
                                                                     f", D {f.diameter_mm:g} mm") + ")")
        ax.set_title(s, fontsize=9)
        ax.set_ylabel("rate, imp/s")
    axes[0, 0].legend(fontsize=7)
    axes[-1, 0].set_xlabel("stimulus position, mm")
    return fig


def response_scatter_figure(runs, data, fits) -> Figure:
    """Recorded rate against the candidate measure at the receptor, one panel per fem.receptors.analysis.Fit,
    with its line d = a S + b and a band of its RMS error."""
    fig = Figure(figsize=(3.6 * len(fits), 3.4))
    axes = fig.subplots(1, len(fits), squeeze=False)
    for f, ax in zip(fits, axes[0]):
        S = np.concatenate([model_values(runs, s, f.measure, f.depth_mm, f.diameter_mm,
                                         data.position_mm[data.stimulus == s]) for s in data.stimuli])
        d = np.concatenate([data.rate_ips[data.stimulus == s] for s in data.stimuli])
        ax.plot(S, d, ".", ms=3)
        line = np.linspace(S.min(), S.max(), 50)
        ax.plot(line, f.a * line + f.b, "r-", lw=1)
        ax.fill_between(line, f.a * line + f.b - f.rms_ips, f.a * line + f.b + f.rms_ips, color="r", alpha=0.15)
        ax.set(xlabel=f"{axis_label(f.measure)}\nat receptor depth {f.depth_mm:g} mm", ylabel="rate, imp/s",
               title=f"RMS {f.rms_ips:.3g} imp/s (band), R$^2$ {f.r2:.3f}")
        ax.title.set_fontsize(8)
        _readable_ticks(ax.xaxis)
    return fig


def _readable_ticks(axis, nbins: int = 5) -> None:
    """At most nbins tick labels, very small or large values with a shared power of ten."""
    axis.set_major_locator(MaxNLocator(nbins=nbins))
    fmt = ScalarFormatter(useMathText=True)
    fmt.set_powerlimits((-2, 3))
    axis.set_major_formatter(fmt)


def finding_figure(finding) -> Figure:
    """The curves of a `fem.thesis.findings.Finding`, titled with its thesis section and verdict.

    Series with axis 1 go on a second y axis (finding.y2label): one quantity per axis. Each series
    has its own colour and open markers of growing size, so that curves that coincide stay
    visible; the legend sits below the axes, covering no curve."""
    fig = Figure(figsize=(6.4, 4.8), layout="constrained")
    ax = fig.add_subplot()
    ax2 = ax.twinx() if any(s.axis for s in finding.series) else None
    lines = []
    for i, s in enumerate(finding.series):
        (line,) = (ax2 if s.axis else ax).plot(s.x, s.y, s.style, label=s.label, markersize=3 + 1.5 * (i % 3),
                                                 markerfacecolor="none", **({} if _has_colour(s.style) else
                                                                            {"color": f"C{i % 10}"}))
        lines.append(line)
    if finding.logx:
        ax.set_xscale("log")
    ax.set_xlabel(finding.xlabel)
    ax.set_ylabel(finding.ylabel)
    if ax2 is not None:
        ax2.set_ylabel(finding.y2label)
    ax.set_title(f"{finding.section}: {finding.verdict}", fontsize=10)
    ax.grid(alpha=0.3)
    if lines:
        fig.legend(handles=lines, loc="outside lower center", ncol=min(3, len(lines)), fontsize=7)
    return fig


def _has_colour(style: str) -> bool:
    """Whether a matplotlib format string names a colour ('k:', 'r-')."""
    return any(ch in "bgrcmykw" for ch in style)


def receptor_map_figure(x_mm, y_mm, values, measure: str, depth_mm: float, dim: int = 3) -> Figure:
    """The explorer's receptor map: one measure at the receptor points of one depth, x_mm, y_mm
    (n,) their positions in the map's plane (3D: x and z across the pad; 2D: x and y of the
    section), values (n,). Fixed margins (the figure is redrawn with new values, its tick labels
    plain numbers of at most 4 digits)."""
    fig = Figure(figsize=(4.4, 2.9))
    fig.subplots_adjust(left=0.12, right=0.8, bottom=0.16, top=0.9)
    ax = fig.subplots()
    art = ax.scatter(x_mm, y_mm, c=values, s=18, cmap="viridis")
    bar = fig.colorbar(art, ax=ax, label=axis_label(measure, dim), fraction=0.08, pad=0.03)
    bar.formatter = FuncFormatter(lambda v, _: f"{v:.3g}")
    ax.set(xlabel="x, mm", ylabel="z, mm" if dim == 3 else "y, mm", aspect="equal")
    ax.set_title(f"receptors {depth_mm:g} mm deep", fontsize=9)
    return fig


def explorer_profile_figure(along_mm, deflection_mm, pressure_MPa, xlabel: str) -> Figure:
    """The explorer's surface profile: deflection (down negative) and contact pressure of the
    surface nodes along_mm (n,), as points (in 3D a band of nodes, whose distances differ). Fixed
    margins, as `receptor_map_figure`."""
    fig = Figure(figsize=(4.4, 2.9))
    fig.subplots_adjust(left=0.2, right=0.97, bottom=0.16, top=0.96, hspace=0.12)
    ax = fig.subplots(2, 1, sharex=True)
    ax[0].plot(along_mm, -np.asarray(deflection_mm), ".", ms=3)
    ax[0].set_ylabel("deflection, mm", fontsize=8)
    ax[1].plot(along_mm, pressure_MPa, ".", ms=3, color="C3")
    ax[1].set(xlabel=xlabel)
    ax[1].set_ylabel("pressure, MPa", fontsize=8)
    return fig
