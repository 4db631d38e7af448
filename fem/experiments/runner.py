"""The experiments of a scene on a model: plan, factorise once, indent.

    model, info = read_model("out/cyl8", scene.material, scene.nu)        # fem.io.modelfolder
    run = run_experiments(model, info, load_scene("scenes/bars.toml"))
    for e in run.experiments:
        e.name, e.indentor, e.steps, e.seconds       # steps: [(offset (3,) mm, ContactResult)]

Only the candidate nodes the scene's indentors can reach (`fem.contact.linear.reach`) are condensed
when the model is factorised. No files are read or written here (`fem.io.runfolder` writes them)
except through a given `fem.experiments.response.ResponseStore`.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from fingertip.errors import InputError
from fingertip.progress import as_progress
from fem.contact.linear import ContactModel, reach
from fem.contact.indentors import approach_direction, make_indentor
from fem.io.modelfolder import CONTACT_REGION, approach_down, factorise, receptor_surface
from fem.receptors.grid import ReceptorSampler, receptor_grid
from fem.experiments.response import contact_model, stored_responses
from fem.experiments.scene import AXES, Experiment, Scene


@dataclass
class ExperimentRun:
    """One experiment of a scene: its placement (orientation, position_mm, incline_deg), indentor,
    indentations in order [(offset (3,) mm, ContactResult)] and the seconds they took."""
    experiment: Experiment
    placement: dict
    indentor: object
    steps: list = field(default_factory=list)
    seconds: float = 0.0

    @property
    def name(self) -> str:
        return self.experiment.name


@dataclass
class SceneRun:
    """Every experiment of a scene on one model, with what their outputs need: the contact model,
    its candidate nodes (`fem.core.model.SurfaceNodes`), the receptor grid and sampler, the measures,
    the receptor line ((axis, mm) or None), warnings about the placement and the stored response
    models used ([(key, "stored" or "built", build seconds, bytes)], `fem.experiments.response`)."""
    model: object
    info: dict
    scene: Scene
    contact: ContactModel
    surface: object
    grid: object
    sampler: ReceptorSampler
    measures: list
    line: tuple | None
    experiments: list
    warnings: list
    responses: list = field(default_factory=list)


def top_point(points, place) -> int:
    """Index of the contact-region point (P, dim) highest against the approach of `place` (its
    "approach", else its "incline_deg"): where a plate would touch first."""
    a = place.get("approach")
    a = approach_direction(place.get("incline_deg", 0.0)) if a is None else np.asarray(a, float)
    return int(np.argmax(points @ -a[:points.shape[1]]))


def scene_position(position, points, place) -> tuple:
    """A scene's position_mm: (x, z) or (x, y, z) mm as given, or "top": the `top_point` of the
    contact region (P, dim), e.g. the pad of a finger on an inclined support."""
    if isinstance(position, str) and position != "top":
        raise InputError(f'position_mm "{position}": give [x, z] in mm or "top"')
    if position != "top":
        return tuple(position)
    p = points[top_point(points, place)]
    return tuple(float(v) for v in p) if len(p) == 3 else (float(p[0]), 0.0)


def placement(exp: Experiment, model, info, sn) -> tuple[dict, str | None]:
    """(keyword arguments of fem.contact.indentors.place for one experiment, warning or None). The
    approach is the experiment's, else its incline, else (3D) the model's support; the default
    position is x = 0 at the middle of the pad."""
    place = {"orientation": exp.orientation}
    if exp.approach is not None:
        place["approach"] = list(exp.approach)
    elif exp.incline_deg is not None:
        place["incline_deg"] = exp.incline_deg
    elif model.dim == 3:
        place["approach"] = approach_down(info)
    middle_z = 0.5 * (sn.x[:, 2].min() + sn.x[:, 2].max()) if model.dim == 3 else 0.0
    position = (0.0, middle_z) if exp.position_mm is None else exp.position_mm
    place["position_mm"] = scene_position(position, sn.x, place)
    warning = None
    if exp.position_mm == "top" and model.dim == 3:        # 2D models have no end cuts
        top = sn.nodes[top_point(sn.x, place)]
        cuts = [r for r in ("distal", "proximal") if r in model.regions and top in model.region_nodes(r)]
        if cuts:
            warning = (f"experiment '{exp.name}': the top point is on the rim of the {cuts[0]} cut, not "
                       "the pad; for an inclined finger mesh with --tip rounded")
    return place, warning


def deepest_mm(exp: Experiment) -> float:
    """Deepest travel beyond first touch an experiment may need (mm): its largest depth, or the
    depth limit of force control."""
    return max(exp.depth_mm) if exp.force_N is None else exp.max_depth_mm


def receptor_line(line, sn, dim) -> tuple[int, float] | None:
    """A scene's receptor line [axis, mm | "middle"] as (axis index, mm) on the contact region."""
    if line is None:
        return None
    axis = AXES[str(line[0])]
    if axis >= dim:
        raise InputError(f"bad receptor line {list(line)}: use z=<mm> or z=middle (3D), x=<mm>")
    value = 0.5 * (sn.x[:, axis].min() + sn.x[:, axis].max()) if line[1] == "middle" else float(line[1])
    return axis, value


def run_experiments(model, info, scene: Scene, progress=None, store=None, only: int | None = None) -> SceneRun:
    """Every experiment of `scene` on a model folder's model (`fem.io.modelfolder.read_model`).
    progress: optional `fingertip.progress` object (None: silent): the receptor sampler build, the
    factorisation and a bar over the indentations.
    store: optional `fem.experiments.response.ResponseStore` of the model folder: the contact problems and
    receptor measures are then answered by its response models (built and stored when missing,
    `fem.experiments.response.stored_responses`); such a run has no full displacement fields (no PVD).
    only: index of the one experiment to indent (`run_experiment`); the model is still
    factorised for every candidate the whole scene can reach, so its numbers are the full run's."""
    progress = as_progress(progress)
    sn, runs, warnings, touched, line, grid = _plan(model, info, scene)
    rc = scene.receptors
    used = []
    if store is None:
        with progress.task(f"receptor operators at {len(grid.points_mm)} points", kind=f"sampler-{model.dim}d",
                           size=len(grid.points_mm)):
            sampler = ReceptorSampler(model, grid)
        system = factorise(model, info, sn.nodes[touched], progress)     # only what the scene can touch
        cm = ContactModel.from_fe(model, system, CONTACT_REGION[model.dim], observe=sampler.operator)
    else:
        responses, sampler, used = stored_responses(store, model, [r.indentor.approach for r in runs], grid,
                                                    touched, progress)
        cm, system = contact_model(model, sn, responses), None
    todo = [(run, off, load) for k, run in enumerate(runs) if only is None or k == only
            for off, load in run.experiment.indentations]
    solved = {}                       # a trace repeats indentations (a hold): each is solved once
    for i, (run, off, load) in enumerate(progress.bar(todo, desc="indentations", unit="indentation")):
        t0 = time.perf_counter()
        key = (id(run), tuple(off), tuple(sorted(load.items())))
        if key not in solved:
            solved[key] = _indent_one(cm, run, off, load)
        run.steps.append((off, solved[key]))
        if i + 1 == len(todo) or todo[i + 1][0] is not run:
            if system is not None:    # an experiment's numbers do not depend on those before it:
                system.restart_refinement()             # the serial run writes its tasks' bytes
            cm.observe_pending()      # one block per experiment, as a task of `run_experiment` does
            cm.restart()
        run.seconds += time.perf_counter() - t0
    return SceneRun(model, info, scene, cm, sn, grid, sampler, list(rc.measures), line, runs, warnings, used)


def _plan(model, info, scene: Scene):
    """(contact region's SurfaceNodes, [ExperimentRun without steps], placement warnings,
    (P,) bool candidates the scene can reach, receptor line, receptor grid) of a scene."""
    scene.check_dim(model.dim)
    sn = model.surface_nodes(CONTACT_REGION[model.dim])
    runs, warnings, touched = [], [], np.zeros(len(sn.nodes), bool)
    for exp in scene.experiments:
        place, warning = placement(exp, model, info, sn)
        if warning:
            warnings.append(warning)
        ind = make_indentor(exp.indentor, **place)
        touched |= reach(sn.x, ind, exp.offsets_mm, deepest_mm(exp))
        runs.append(ExperimentRun(exp, place, ind))
    rc = scene.receptors
    line = receptor_line(rc.line, sn, model.dim)
    grid = receptor_grid(*receptor_surface(model, sn), np.asarray(rc.depths_mm, float), rc.spacing_mm, line)
    return sn, runs, warnings, touched, line, grid


def run_experiment(model, info, scene: Scene, index: int, progress=None) -> ExperimentRun:
    """Experiment `index` of a scene alone (one task of a scene run on several processes): its
    own factorisation, of every candidate the whole scene can reach, so that its indentations
    are those of `run_experiments`; the results are observed and detached from the contact
    model (picklable)."""
    run = run_experiments(model, info, scene, progress, only=index).experiments[index]
    for _, res in run.steps:
        res.observed                 # noqa: B018 - observes the pending indentations
        res._source = None
    return run


def assemble_run(model, info, scene: Scene, runs: list, progress=None) -> SceneRun:
    """The SceneRun of a scene whose experiments ran elsewhere (`run_experiment`, `runs` in the
    scene's order): the receptor sampler is built here; there is no contact model (no PVD)."""
    progress = as_progress(progress)
    sn, _, warnings, _, line, grid = _plan(model, info, scene)
    with progress.task(f"receptor operators at {len(grid.points_mm)} points", kind=f"sampler-{model.dim}d",
                       size=len(grid.points_mm)):
        sampler = ReceptorSampler(model, grid)
    return SceneRun(model, info, scene, None, sn, grid, sampler, list(scene.receptors.measures), line, list(runs),
                    warnings)


def _indent_one(cm: ContactModel, run: ExperimentRun, off, load):
    """One indentation of an experiment: at offset `off` (3,) mm with `load` (depth or force)."""
    if run.experiment.sweep is not None:
        return cm.sweep(run.indentor, off[None], **load)[0]
    return cm.indent(run.indentor, **load)
