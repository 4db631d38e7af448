"""Back end of `pipeline.py indent`: a scene (a TOML file, or one experiment from the flags) on a
model folder, written atomically as a run folder (fem.io.runfolder); returns the summary text.

    indent_folder("out/cyl8", "out/cyl8/bars", load_scene("scenes/bars.toml"))   # model -> run folder
"""
from __future__ import annotations

import dataclasses
import sys
import time
from pathlib import Path

from fingertip.distribute import TaskRunner, parse_scheduler, require_dask
from fingertip.errors import InputError
from fingertip.progress import as_progress
from fingertip.staging import check_output_dir, staged_output
from fem.experiments.runner import run_experiments
from fem.core.materials import Material
from fem.io.modelfolder import folder_dim, folder_info, read_model
from fem.io.runfolder import write_run
from fem.experiments.scene import Scene, load_scene


def parse_position(words: list[str]):
    """--position: 'top' or X Z in mm."""
    if words == ["top"]:
        return "top"
    try:
        x, z = (float(w) for w in words)
    except ValueError:
        raise InputError(f"--position {' '.join(words)}: give X Z in mm or top") from None
    return [x, z]


def scene_of_flags(indentor, orientation="parallel", position=None, incline=None, depth=None, force=None,
                   equal_force=False, max_depth=5.0, sweep=None, receptor_depths="0.5,0.75,1.0",
                   receptor_spacing=1.0, line=None) -> Scene:
    """The one-experiment Scene the `indent` flags describe (named after the indentor code)."""
    if not indentor or (depth is None and force is None):
        raise InputError("indent needs --scene, or --indentor with --depth or --force")
    exp = {"name": indentor.replace(":", "_").replace(",", "_"), "indentor": indentor, "orientation": orientation}
    if position is not None:
        exp["position_mm"] = parse_position(position)
    if depth is not None:
        exp["depth_mm"] = depth
    else:
        exp.update(force_N=force, equal_force=equal_force, max_depth_mm=max_depth)
    if sweep:
        exp["sweep"] = sweep
    if incline is not None:
        exp["incline_deg"] = incline
    receptors = {"depths_mm": receptor_depths, "spacing_mm": receptor_spacing}
    if line:
        axis, _, value = line.partition("=")
        receptors["line"] = [axis, value]
    return Scene.from_dict({"experiment": [exp], "receptors": receptors})


def indent_folder(model_dir, out_dir, scene: Scene, progress: bool = True, scheduler=None) -> str:
    """Run every experiment of a scene on a model folder and write the run folder atomically into
    out_dir (CSV, run.json, and PNG and PVD as the scene says). Placement warnings go to stderr;
    progress: True (a `fingertip.progress.Progress` on stderr), False, or a progress object. Returns
    the summary text (2D forces in N/mm). scheduler: none (default), local:N or tcp://HOST:PORT:
    a scene of several experiments runs one task per experiment on Dask workers, each
    factorising the model itself (`distributed_run`); the files are those of none."""
    t_start = time.perf_counter()
    check_output_dir(out_dir)
    sched = parse_scheduler(scheduler)
    require_dask(sched)
    scene.check_dim(folder_dim(folder_info(model_dir)))
    model, info = read_model(model_dir, scene.material, scene.nu)
    store = response_store(model_dir, scene, progress)
    if sched.kind != "none" and _distributable(scene, store, progress):
        run = distributed_run(model_dir, model, info, scene, sched, progress)
    else:
        run = run_experiments(model, info, scene, progress=as_progress(progress), store=store)
    for warning in run.warnings:
        print(f"warning: {warning}", file=sys.stderr)
    afferents = (None, {})
    if scene.afferents is not None:
        from fem.receptors.afferents import scene_responses

        with as_progress(progress).task("afferent inputs and spike trains", kind="afferents"):
            afferents = scene_responses(run)
    with staged_output(out_dir) as tmp:
        tables = write_run(tmp, model_dir, run, afferents)
        if scene.output.plots:
            from fem import plots  # matplotlib: only when figures are written

            for e in run.experiments:
                for name, fig in plots.indent_figures(e, run, tables[e.name]).items():
                    plots.save(fig, tmp / name)
                if e.name in afferents[1]:
                    depth = tables[e.name]["steps"]["depth_mm"]
                    for name, fig in plots.afferent_figures(e.name, afferents[1][e.name], depth).items():
                        plots.save(fig, tmp / name)
    total = time.perf_counter() - t_start
    lines = [(f"indentation results in {out_dir} ({total:.1f} s; model {model.ndof} DOFs, "
              f"{len(run.surface.nodes)} contact candidates, {len(run.grid.points_mm)} receptor points)")]
    lines += [experiment_line(e, model.dim) for e in run.experiments]
    lines += [afferent_line(name, resp) for name, resp in afferents[1].items()]
    lines += [f"  response model: {how} {key} ({size / 2**20:.1f} MB, built in {built:.2f} s)"
              for key, how, built, size in run.responses]
    return "\n".join(lines)


def _distributable(scene: Scene, store, progress) -> bool:
    """Whether a scene's experiments can run as tasks: several of them, no stored response
    models (they answer without factorising) and no PVD (full fields need the factorisation in
    this process); says why not in one line on stderr (if progress)."""
    from fem.io.runfolder import writes_pvd

    why = ("it has one experiment" if len(scene.experiments) < 2 else
           "its afferents need the factorised model in this process" if scene.afferents is not None else
           "the stored response models answer it without factorising" if store is not None else
           "its PVD output needs the full fields in this process (--no-pvd distributes it)"
           if any(writes_pvd(scene.output, len(e.indentations)) for e in scene.experiments) else None)
    if why and progress:
        print(f"scheduler: running the scene in this process: {why}", file=sys.stderr, flush=True)
    return why is None


def experiment_task(item: tuple):
    """One task of `distributed_run`: item (model folder, Scene, experiment index) ->
    fem.experiments.runner.ExperimentRun with its observed indentations (the model is read here)."""
    from fem.experiments.runner import run_experiment

    model_dir, scene, index = item
    model, info = read_model(model_dir, scene.material, scene.nu)
    return run_experiment(model, info, scene, index)


def distributed_run(model_dir, model, info, scene: Scene, sched, progress=True):
    """fem.experiments.runner.SceneRun of a scene with one task per experiment on Dask workers
    (`fingertip.distribute`); each task factorises the model for the candidates the whole scene
    can reach, on fingertip.jobs.tasks.TASK_THREADS threads, and this process only builds the
    receptor sampler and collects the runs in the scene's order."""
    from fingertip.jobs.tasks import task_map, task_threads
    from fem.experiments.runner import assemble_run

    with TaskRunner(sched) as runner, task_threads():
        if progress:
            print(f"scheduler {sched}: {len(scene.experiments)} experiments on {runner.workers} worker(s)",
                  file=sys.stderr, flush=True)
        runs = task_map(runner, "experiment")(experiment_task, [(str(model_dir), scene, k)
                                                                for k in range(len(scene.experiments))])
        return assemble_run(model, info, scene, runs, as_progress(progress))


def response_store(model_dir, scene: Scene, progress=True):
    """The model folder's `fem.experiments.response.ResponseStore` when the folder keeps response models
    (`pipeline.py prepare` made it) and the scene's outputs can be answered by them (no experiment
    writes a PVD of full fields), else None; when a PVD keeps a stored model from being used, says
    so in one line on stderr (if progress). A folder without stored models is factorised: building
    one costs one solve per condensed candidate, far more than a first run needs."""
    from fem.experiments.response import ResponseStore
    from fem.io.runfolder import writes_pvd

    store = ResponseStore(model_dir)
    if not store.folder.is_dir():
        return None
    if scene.afferents is not None:
        if progress:
            print("response model: not used, afferents need the stresses at their own sites: factorising",
                  file=sys.stderr, flush=True)
        return None
    if not any(writes_pvd(scene.output, len(e.indentations)) for e in scene.experiments):
        return store
    if progress:
        print("response model: not used, the PVD output needs full fields: factorising (--no-pvd "
              "answers from the stored response models)", file=sys.stderr, flush=True)
    return None


def afferent_line(name: str, resp) -> str:
    """Summary of one experiment's afferents: per class the count, how many fired, the mean rate."""
    cls = resp.population.afferent_class.astype(str)
    rate = resp.rates_hz()
    parts = [f"{(cls == c).sum()} {c} ({int((rate[cls == c] > 0).sum())} fired, mean {rate[cls == c].mean():.1f} Hz)"
             for c in dict.fromkeys(cls)]
    return f"  {name} afferents: " + ", ".join(parts) + f" over {resp.duration_s:.2f} s -> {name}/spikes.csv"


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


def run_indent(model, scene=None, indentor=None, orientation="parallel", position=None, incline=None,
               depth=None, force=None, equal_force=False, max_depth=5.0, sweep=None, material=None, nu=None,
               receptor_depths="0.5,0.75,1.0", receptor_spacing=1.0, line=None, pvd=None, out=None,
               progress: bool = True, plots=None, scheduler=None) -> str:
    """`pipeline.py indent` from its option values: the --scene file, or the experiment of the
    flags; --material, --nu, --pvd and --plots override the scene's. Output folder default:
    <model>/indent_<scene file stem or experiment name>."""
    spec, out = indent_scene(model, scene, indentor, orientation, position, incline, depth, force, equal_force,
                             max_depth, sweep, material, nu, receptor_depths, receptor_spacing, line, pvd, out,
                             plots)
    return indent_folder(model, out, spec, progress=progress, scheduler=scheduler)


def indent_scene(model, scene=None, indentor=None, orientation="parallel", position=None, incline=None,
                 depth=None, force=None, equal_force=False, max_depth=5.0, sweep=None, material=None, nu=None,
                 receptor_depths="0.5,0.75,1.0", receptor_spacing=1.0, line=None, pvd=None,
                 out=None, plots=None) -> tuple[Scene, str]:
    """(validated Scene, output folder) of `run_indent`'s option values; reads the scene file
    only, not the model (the `run` chain checks its indent stage before the model exists)."""
    if scene:
        spec = load_scene(scene)
        name = Path(scene).stem
    else:
        spec = scene_of_flags(indentor, orientation, position, incline, depth, force, equal_force, max_depth,
                              sweep, receptor_depths, receptor_spacing, line)
        name = spec.experiments[0].name
    overrides = {k: v for k, v in (("material", material), ("nu", nu)) if v is not None}
    if overrides:
        Material(material or spec.material or "m33338", 0.48 if nu is None else nu)   # code form, nu range
    output = {k: v for k, v in (("pvd", pvd), ("plots", plots)) if v is not None}
    if output:
        overrides["output"] = dataclasses.replace(spec.output, **output)
    spec = dataclasses.replace(spec, **overrides)
    out = out or str(Path(model) / f"indent_{name}")
    check_output_dir(out)
    return spec, out
