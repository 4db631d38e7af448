"""The jobs of `study-layers`, `fit-material`, `contact-series` and `line-load` (thesis 4.7, 6.2):
run the fem.biomech experiments, write the tables, JSON and figures into the output folder
atomically, and return the summary text. Lists of depths, layers and offsets come as lists
(the command line reads them from words).

CSV tables format floats with `.9g`.
"""
from __future__ import annotations

import time

import numpy as np

from fem import plots
from fem.biomech.deflection import (
    DeflectionExperiment,
    code_of,
    cylinder_series,
    idealised_fits,
    layer_study,
    parse_code,
)
from fem.biomech.fit import fit_force_scale, fit_material, profile_residuals
from fem.biomech.line_load import compare_line_load
from fem.biomech.measured import read_deflection_csv, read_force_csv
from fem.contact.indentors import orientation_deg, shapes_for
from fem.io.modelfolder import check_folder_material, folder_info, folder_material
from fingertip.distribute import parse_scheduler, require_dask
from fingertip.errors import InputError
from fingertip.jobs.tasks import task_map
from fingertip.progress import as_progress
from fingertip.staging import check_output_dir, holding, staged_output, write_json
from fingertip.tables import write_csv

DPI = 100


MARKERS = {"study-layers": "layer_study.json", "fit-material": "fit.json", "contact-series": "cylinder_series.json",
           "line-load": "line_load.json"}
"""The file that marks each command's output folder: a rerun replaces such a folder as a whole."""


def _check_start(command, out_dir, *indentors, orientation=None, scheduler=None):
    """The refusals that need no model, before any is read: output folder (new, empty or an
    earlier output of `command`), indentor codes, orientation, the scheduler (Dask installed when
    it needs it); returns the Scheduler."""
    check_output_dir(out_dir, marker=MARKERS[command], what=f"{command} output")
    for code in indentors:
        shapes_for(code)
    if orientation is not None:
        orientation_deg(orientation)
    sched = parse_scheduler(scheduler)
    require_dask(sched)
    return sched


def _experiment(model_dir, indentor, orientation, position_mm, nu, side, progress=False, map=None):
    return DeflectionExperiment(model_dir, indentor=indentor, orientation=orientation,
                                position_mm=position_mm, nu=nu, side=side, progress=progress, map=map)


def _columns(names, rows) -> dict[str, list]:
    """Row tuples -> {name: column values} for fingertip.tables.write_csv."""
    return {n: [r[i] for r in rows] for i, n in enumerate(names)}


def _force_unit(dim: int) -> str:
    return "N per mm (2D plane strain)" if dim == 2 else "N"


@holding()
def run_study_layers(model_dir, out_dir, base=None, layers=(1, 2, 3, 4), offsets=(-1, 0, 1), depths=(2.0,),
                     indentor="wedge", orientation=None, position_mm=None, nu=None, side="mean",
                     data_csv=None, progress=False, scheduler=None) -> str:
    """`pipeline.py study-layers`: layer_study.csv / .json / .png and profile.png in out_dir.
    progress (here and in the other back ends): True for progress on stderr, or a progress object.
    scheduler (here and in run_fit_material): none (default), local:N or tcp://HOST:PORT: the
    trial materials as tasks on Dask workers (fingertip.distribute), the same numbers as none."""
    t0 = time.perf_counter()
    sched = _check_start("study-layers", out_dir, indentor, orientation=orientation, scheduler=scheduler)
    depth_list, layer_list, offset_list = list(depths), list(layers), list(offsets)
    data = read_deflection_csv(data_csv) if data_csv else []
    with task_map(sched, "trial material", as_progress(progress)) as map_:
        exp = _experiment(model_dir, indentor, orientation, position_mm, nu, side, progress, map_)
        base = base or folder_material(exp.info)[0]
        study = layer_study(exp, base, layer_list, offset_list, depth_list)
        base_prof = exp.profiles(base, depth_list)
        fits = [idealised_fits(p) for p in base_prof]
    with staged_output(out_dir, replace=True) as tmp:
        rows = [(code, p.depth_mm, float(d), float(w)) for code, profs in study.profiles.items()
                for p in profs for d, w in zip(p.distance_mm, p.deflection_mm)]
        write_csv(tmp / "layer_study.csv", _columns(("code", "depth_mm", "distance_mm", "deflection_mm"), rows))
        summary = {"model": str(model_dir), "indentor": exp.indentor.name, "base": base, "depths_mm": depth_list,
                   "side": side, "layers": {str(k): v for k, v in study.layers.items()},
                   "effects": [e.__dict__ for e in study.effects],
                   "force_N": {c: [p.force_N for p in ps] for c, ps in study.profiles.items()},
                   "force_unit": _force_unit(exp.dim),
                   "idealised_fits_of_base": [{k: f.__dict__ for k, f in fd.items()} for fd in fits],
                   "distinct_moduli_ratios_solved": study.evaluations,
                   "seconds": round(time.perf_counter() - t0, 2)}
        write_json(tmp / "layer_study.json", summary)
        plots.save(plots.layer_study_figure(study, data), tmp / "layer_study.png", dpi=DPI)
        plots.save(plots.base_profiles_figure(f"{base}: deflection profile", base_prof, fits, data),
                   tmp / "profile.png", dpi=DPI)
    lines = [f"layer study around {base} in {out_dir} ({summary['seconds']} s, "
             f"{study.evaluations} distinct modulus ratios solved)"]
    for e in study.effects:
        lines.append(f"  layer {e.layer} ({e.codes[0]}..{e.codes[-1]}) at {e.depth_mm:g} mm: most affected "
                     f"{e.most_affected_mm:.2f} mm from the load (stiffer layer: {e.difference_mm:+.3f} mm)"
                     + (f", neutral at {', '.join(f'{n:.2f}' for n in e.neutral_mm)} mm" if e.neutral_mm else ""))
    for p, fd in zip(base_prof, fits):
        lines.append(f"  {base} at {p.depth_mm:g} mm: waterbed Lw {fd['waterbed'].length_mm:.3g} mm "
                     f"(rms {fd['waterbed'].rms_mm:.3g}), beam Lb {fd['beam'].length_mm:.3g} mm "
                     f"(rms {fd['beam'].rms_mm:.3g}); Lw/Lb {fd['waterbed'].length_mm / fd['beam'].length_mm:.2f} "
                     f"(8/3 near the load)")
    return "\n".join(lines)


@holding()
def run_fit_material(model_dir, out_dir, deflection_csv=None, force_csv=None, keep_ratios=False, base=None,
                     free_layers=(2, 3, 4), bounds=(1.0, 7.0), indentor="wedge", orientation=None,
                     position_mm=None, force_indentor="plate", match="least-squares", nu=None,
                     side="mean", noise_mm=None, progress=False, scheduler=None) -> str:
    """`pipeline.py fit-material`: fit.json, fit_profiles.csv, fit_profiles.png, force_fit.png."""
    if deflection_csv is None and force_csv is None:
        raise InputError("fit-material needs --deflection CSV and/or --force CSV")
    t0 = time.perf_counter()
    sched = _check_start("fit-material", out_dir, indentor, force_indentor, orientation=orientation,
                         scheduler=scheduler)
    free = list(free_layers)
    if not bounds[0] < bounds[1]:
        raise InputError(f"--bounds {bounds[0]:g} {bounds[1]:g}: give LO < HI (log10 modulus in Pa), e.g. 1 7")
    data = read_deflection_csv(deflection_csv) if deflection_csv else None
    forces = read_force_csv(force_csv) if force_csv else None
    with task_map(sched, "trial material", as_progress(progress)) as map_:
        exp = _experiment(model_dir, indentor, orientation, position_mm, nu, side, progress, map_)
        base = base or folder_material(exp.info)[0]
        base_v = parse_code(base, exp.n_layers)
        report, fit, scale = {"model": str(model_dir), "base": base}, None, None
        if data is not None:
            fit = fit_material(exp, data, base, free, bounds, noise_mm=noise_mm)
            report["deflection_fit"] = {**fit.report(), "indentor": exp.indentor.name,
                                        "depths_mm": [p.depth_mm for p in data], "side": side}
            base_r = profile_residuals(exp, base_v, data)
            report["deflection_fit"]["base_rms_mm"] = float(np.sqrt(np.mean(base_r ** 2)))
        if forces is not None:
            ratios = base_v if keep_ratios or fit is None else fit.log10_Pa
            fexp = exp if force_indentor == indentor else _experiment(model_dir, force_indentor, orientation,
                                                                      position_mm, nu, side, progress, map_)
            scale = fit_force_scale(fexp.forces_N(ratios, forces[0]), forces[1], ratios, forces[0], match)
            report["force_fit"] = {**scale.report(), "indentor": fexp.indentor.name, "ratios_from":
                                   "base material" if ratios is base_v else "deflection fit",
                                   "force_unit": _force_unit(exp.dim)}
    report["seconds"] = round(time.perf_counter() - t0, 2)
    with staged_output(out_dir, replace=True) as tmp:
        write_json(tmp / "fit.json", report)
        if fit is not None:
            depths = [p.depth_mm for p in data]
            best, start = exp.profiles(fit.log10_Pa, depths), exp.profiles(base_v, depths)
            rows = [(p.depth_mm, float(d), float(y), float(b.at(d)), float(s.at(d)))
                    for p, b, s in zip(data, best, start) for d, y in zip(p.distance_mm, p.deflection_mm)]
            write_csv(tmp / "fit_profiles.csv", _columns(("depth_mm", "distance_mm", "measured_mm", "fitted_mm",
                                                          "base_mm"), rows))
            fig = plots.deflection_fit_figure(data, best, start, base, [idealised_fits(p) for p in data])
            plots.save(fig, tmp / "fit_profiles.png", dpi=DPI)
        if scale is not None:
            plots.save(plots.force_scale_figure(scale), tmp / "force_fit.png", dpi=DPI)
    lines = [f"fit-material results in {out_dir} ({report['seconds']} s)"]
    if fit is not None:
        free = ", ".join(f"layer {k}: 10^{fit.log10_Pa[k - 1]:.2f} Pa (uncertainty factor {f:.3g})"
                         for k, f in zip(fit.free_layers, fit.factor))
        lines += [f"  deflection fit ({len(fit.residuals_mm)} points, rms {fit.rms_mm:.3g} mm; base {base} rms "
                  f"{report['deflection_fit']['base_rms_mm']:.3g} mm): {free}",
                  f"  best code {fit.best_code} (rms {fit.best_code_rms_mm:.3g} mm); "
                  f"{fit.evaluations} distinct modulus ratios solved"]
    if scale is not None:
        lines.append(f"  force scale x{scale.scale:.4g} ({scale.match}): moduli "
                     + ", ".join(f"{10 ** v:.3g}" for v in scale.log10_Pa)
                     + f" Pa (nearest code {code_of(scale.log10_Pa)}), rms {scale.rms_N:.3g} "
                     + ("N/mm" if exp.dim == 2 else "N"))
    return "\n".join(lines)


@holding()
def run_contact_series(model_dir, out_dir, material=None, codes=None, forces=None, depths=None,
                       orientation=None, position_mm=None, nu=None, progress=False) -> str:
    """`pipeline.py contact-series`: cylinder_series.csv / .json / .png in out_dir."""
    if (forces is None) == (depths is None):
        raise InputError("contact-series needs --force or --depth (one of the two)")
    t0 = time.perf_counter()
    _check_start("contact-series", out_dir, orientation=orientation)
    loads = list(forces if forces is not None else depths)
    exp = _experiment(model_dir, "wedge", orientation, position_mm, nu, "mean", progress)
    material = material or folder_material(exp.info)[0]
    s = cylinder_series(exp, material, codes, **({"forces_N": loads} if forces is not None else {"depths_mm": loads}))
    force_unit = "N/mm" if exp.dim == 2 else "N"
    area = "contact width, mm" if exp.dim == 2 else "contact area, mm^2"
    with staged_output(out_dir, replace=True) as tmp:
        j, k = np.meshgrid(np.arange(len(s.loads)), np.arange(len(s.codes)), indexing="ij")
        j, k = j.ravel(), k.ravel()
        write_csv(tmp / "cylinder_series.csv", {
            "code": [s.codes[i] for i in k], "diameter_mm": s.diameters_mm[k], "load": [s.load_kind] * len(j),
            "load_value": s.loads[j], "depth_mm": s.depth_mm[j, k], "force_N": s.force_N[j, k],
            "contact_area_mm2": s.contact_area_mm2[j, k], "max_pressure_MPa": s.max_pressure_MPa[j, k]})
        write_json(tmp / "cylinder_series.json", {"model": str(model_dir), "material": material,
                                                  "force_unit": _force_unit(exp.dim),
                                                  "contact_area_unit": "mm (width, 2D)" if exp.dim == 2 else "mm^2",
                                                  **s.report(), "seconds": round(time.perf_counter() - t0, 2)})
        plots.save(plots.cylinder_series_figure(s, exp.dim), tmp / "cylinder_series.png", dpi=DPI)
    lines = [f"cylinder series {', '.join(s.codes)} ({material}, constant {s.load_kind}) in {out_dir} "
             f"({time.perf_counter() - t0:.1f} s)"]
    for j, v in enumerate(s.loads):
        lines.append(f"  {v:g} {force_unit if s.load_kind == 'force' else 'mm'}: {area} "
                     + " ".join(f"{a:.3g}" for a in s.contact_area_mm2[j]) + "; max pressure MPa "
                     + " ".join(f"{p:.3g}" for p in s.max_pressure_MPa[j]))
    return "\n".join(lines)


@holding()
def run_line_load(model_dir, out_dir, depths=(0.05, 0.5, 1.0, 2.0), material=None, nu=None, large_deformation=False,
                  slip=False, half_width_mm=0.25, half_length_mm=1.0, step_mm=0.1, position_mm=None,
                  progress=False) -> str:
    """`pipeline.py line-load`: line_load.csv / .json / .png in out_dir (linear; with
    large_deformation also the neo-Hookean solve and where the two part)."""
    t0 = time.perf_counter()
    _check_start("line-load", out_dir)
    depth_list = list(depths)
    info = folder_info(model_dir)
    material = material or folder_material(info)[0]
    check_folder_material(model_dir, material, nu)
    c = compare_line_load(model_dir, depth_list, material=material, nu=nu, half_width_mm=half_width_mm,
                          step_mm=step_mm, position_mm=position_mm, slip=slip, half_length_mm=half_length_mm,
                          large_deformation=large_deformation, progress=progress)
    with staged_output(out_dir, replace=True) as tmp:
        n = len(c.distance_mm)
        write_csv(tmp / "line_load.csv", {
            "depth_mm": np.repeat(np.asarray(c.depths_mm, float), n),
            "distance_mm": np.tile(np.asarray(c.distance_mm, float), len(c.depths_mm)),
            "linear_mm": np.asarray(c.deflection_linear_mm, float).ravel(),
            "nonlinear_mm": np.asarray(c.deflection_nonlinear_mm, float).ravel()})
        report = {"model": str(model_dir), "material": material, "large_deformation": large_deformation,
                  "slip": slip, "half_width_mm": half_width_mm, "step_mm": step_mm,
                  "depths_mm": c.depths_mm.tolist(), "force_linear_N": c.force_linear_N.tolist(),
                  "force_nonlinear_N": c.force_nonlinear_N.tolist(), "max_difference": c.max_difference.tolist(),
                  "min_J": c.min_J.tolist(), "newton_iterations_last_step": [len(h) for h in c.newton],
                  "nonlinear_seconds": c.seconds.tolist(), "failed": {str(k): v for k, v in c.failed.items()},
                  "force_unit": _force_unit(c.dim),
                  "seconds": round(time.perf_counter() - t0, 2)}
        write_json(tmp / "line_load.json", report)
        plots.save(plots.line_load_figure(c, large_deformation), tmp / "line_load.png", dpi=DPI)
    lines = [f"line load on {model_dir} ({material}, patch half width {half_width_mm:g} mm, "
             f"{'sliding' if slip else 'held'} sideways) in {out_dir} ({report['seconds']} s)"]
    for k, d in enumerate(c.depths_mm):
        text = f"  {d:g} mm: force linear {c.force_linear_N[k]:.4g} {'N/mm' if c.dim == 2 else 'N'}"
        if float(d) in c.failed:
            text += f"; large deformation failed: {c.failed[float(d)]}"
        elif large_deformation:
            ratio = c.force_nonlinear_N[k] / c.force_linear_N[k]
            text += (f", large deformation {c.force_nonlinear_N[k]:.4g} (x{ratio:.3f}); max deflection difference "
                     f"{100 * c.max_difference[k]:.1f} % of the depth; min J {c.min_J[k]:.2f}; {c.seconds[k]:.1f} s")
        lines.append(text)
    return "\n".join(lines)
