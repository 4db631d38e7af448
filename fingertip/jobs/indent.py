"""The `indent` job: a scene on a model folder (`fem.experiments.runner.run_scene`), written
atomically as a run folder (fem.io.runfolder) with its figures; and the `prepare` job: a stored
response model. Each returns the summary text the command line prints.

    indent_folder("out/cyl8", "out/cyl8/bars", load_scene("scenes/bars.toml"))   # model -> run folder
"""
from __future__ import annotations

import logging
import os
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from fem.experiments.response import ResponseStore
from fem.experiments.runner import linear_note, prepare_responses, run_scene, validity_warning
from fem.experiments.scene import Receptors, Scene
from fem.io.modelfolder import check_folder_material, folder_info
from fem.io.runfolder import write_run
from fingertip.distribute import parse_scheduler, require_dask
from fingertip.jobs.tasks import task_map
from fingertip.progress import as_progress
from fingertip.staging import check_output_dir, check_writable_folder, claimed, staged_output

logger = logging.getLogger(__name__)

RUN_MARKER = "run.json"
"""The file that marks a run folder (fem.io.runfolder): a rerun replaces such a folder as a whole."""


def indent_folder(model_dir, out_dir, scene: Scene, progress=True, scheduler=None) -> str:
    """Run every experiment of a scene on a model folder and write the run folder atomically into
    out_dir (CSV, run.json, and PNG and PVD as the scene says); returns the summary text (2D
    forces in N/mm). A folder that keeps stored response models answers from them where the
    scene allows. progress: True (on stderr), False, or a progress object. scheduler: none
    (default), local:N or tcp://HOST:PORT: a scene of several experiments runs one task per
    experiment on Dask workers (the files are those of none). Placement warnings are logged."""
    return run_indent(model_dir, out_dir, scene, progress, scheduler).summary


@dataclass
class Indented:
    """What `run_indent` wrote: the summary text and, per experiment, its tables
    (`fem.io.runfolder.run_tables`: "steps" columns and receptor "values" (k, n) per measure)."""
    summary: str
    tables: dict


def run_indent(model_dir, out_dir, scene: Scene, progress=True, scheduler=None) -> Indented:
    """`indent_folder`, returning the tables it wrote with the summary."""
    t_start = time.perf_counter()
    check_output_dir(out_dir, marker=RUN_MARKER, what="indent run")
    check_folder_material(model_dir, scene.material, scene.nu)
    sched = parse_scheduler(scheduler)
    require_dask(sched)
    progress = as_progress(progress)
    with claimed(out_dir):
        with task_map(sched, "experiment", progress) as map_:
            run = run_scene(model_dir, scene, store=response_store(model_dir), map=map_, progress=progress)
        for warning in run.warnings:
            logger.warning(warning)
        tables = _write(out_dir, model_dir, scene, run, progress)
    total = time.perf_counter() - t_start
    model = run.model
    lines = [(f"indentation results in {out_dir} ({total:.1f} s; model {model.ndof} DOFs, "
              f"{len(run.surface.nodes)} contact candidates, {len(run.grid.points_mm)} receptor points)")]
    lines += [experiment_line(e, model.dim) for e in run.experiments]
    lines += validity_lines(run.experiments)
    lines += [afferent_line(name, resp) for name, resp in run.afferents[1].items()]
    lines += [f"  response model: {how} {key} ({size / 2**20:.1f} MB, built in {built:.2f} s)"
              for key, how, built, size in run.responses]
    return Indented("\n".join(lines), tables)


def response_store(model_dir) -> ResponseStore | None:
    """The store `indent` answers from: the model folder's, built on the first run and kept for the
    next (a read-only model folder: its existing store, if any, else None: factorised)."""
    return ResponseStore(model_dir) if os.access(model_dir, os.W_OK) else ResponseStore.existing(model_dir)


def _write(out_dir, model_dir, scene: Scene, run, progress) -> dict:
    """The run folder of a scene run, replacing an earlier one as a whole; returns its tables."""
    with staged_output(out_dir, replace=True) as tmp:
        tables = write_run(tmp, model_dir, run, run.afferents, progress)
        if scene.output.plots:
            from fem import (
                plots,  # matplotlib: 0.4 s of import, which a run without figures does without
            )

            for e in progress.bar(run.experiments, desc="figures", unit="experiment"):
                for name, fig in plots.indent_figures(e, run, tables[e.name]).items():
                    plots.save(fig, tmp / name)
                if e.name in run.afferents[1]:
                    depth = tables[e.name]["steps"]["depth_mm"]
                    for name, fig in plots.afferent_figures(e.name, run.afferents[1][e.name], depth).items():
                        plots.save(fig, tmp / name)
    return tables


def prepare_folder(model_dir, material=None, nu=None, approach=None, receptors: Receptors = Receptors(),
                   progress=True) -> str:
    """Build (or find) the response model of a model folder (`fem.experiments.runner.
    prepare_responses`); approach: (3,) or None (the model's support); returns the summary text."""
    t0 = time.perf_counter()
    folder_info(model_dir)                              # a model folder (mesh.vtu), then a writable one
    for folder in (Path(model_dir), Path(model_dir) / "response"):     # it stores <model>/response/<key>/
        check_writable_folder(folder, "the model folder" if folder.name != "response" else "the folder")
    p = prepare_responses(model_dir, material, nu, approach, receptors, as_progress(progress))
    return (f"response model {p.how} in {p.store.path(p.key)} ({time.perf_counter() - t0:.1f} s): "
            f"{p.candidates} contact candidates along {(np.round(p.approach, 6) + 0.0).tolist()}, "
            f"{p.receptor_points} receptor points, material {p.material}, {p.nbytes / 2**20:.1f} MB, "
            f"built in {p.built_s:.2f} s")


def afferent_line(name: str, resp) -> str:
    """Summary of one experiment's afferents: per class the count, how many fired, the mean rate."""
    cls = resp.population.afferent_class.astype(str)
    rate = resp.rates_hz()
    parts = [f"{(cls == c).sum()} {c} ({int((rate[cls == c] > 0).sum())} fired, mean {rate[cls == c].mean():.1f} Hz)"
             for c in dict.fromkeys(cls)]
    return f"  {name} afferents: " + ", ".join(parts) + f" over {resp.duration_s:.2f} s -> {name}/spikes.csv"


def validity_lines(experiments) -> list[str]:
    """Summary lines on the linear range (fem.experiments.runner.linear_validity): a warning per
    experiment beyond it, a note per experiment within it but deeper than where linear and finite
    kinematics part by 5 % (`linear_note`), and, when a stored response model answered (no full
    displacement field), that element inversion was not checked."""
    lines = [f"  warning: {w}" for e in experiments if (w := validity_warning(e)) is not None]
    lines += [f"  note: {n}" for e in experiments if (n := linear_note(e)) is not None]
    unchecked = [e for e in experiments if e.validity is not None and not e.validity["inversion_checked"]]
    if unchecked:
        strain = max(e.validity["max_receptor_strain"] for e in unchecked)
        lines.append(f"  linear range: receptor strains up to {strain:.2f} (limit "
                     f"{unchecked[0].validity['max_linear_strain']:g}); element inversion not checked: a stored "
                     f"response model has no full displacement field (--pvd factorises and checks it)")
    return lines


def _span(values, fmt=".4g") -> str:
    lo, hi = min(values), max(values)
    return f"{lo:{fmt}}" if f"{lo:{fmt}}" == f"{hi:{fmt}}" else f"{lo:{fmt}}-{hi:{fmt}}"


def experiment_line(e, dim: int) -> str:
    """Summary line of one experiment run: count, time, force (N; N/mm in 2D plane strain), the
    depth reached (force control) and the worst penetration."""
    force_unit = "N/mm" if dim == 2 else "N"
    forces = [r.total_force_N for _, r in e.steps]
    depths = [float(r.depth_mm.max()) for _, r in e.steps]
    worst = max(r.kkt["penetration_mm"] for _, r in e.steps)
    text = f"  {e.name}: {len(e.steps)} indentation{'s' if len(e.steps) != 1 else ''}, {e.seconds:.2f} s, "
    if e.experiment.force_N is not None:
        text += f"force {_span(forces)} {force_unit} reached at depth {_span(depths, '.3g')} mm"
    else:
        text += f"depth {_span(depths, '.3g')} mm, force {_span(forces)} {force_unit}"
    return text + f", max penetration {worst:.1e} mm"
