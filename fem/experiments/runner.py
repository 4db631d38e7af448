"""The experiments of a scene on a model: plan, factorise once (or answer from a stored response
model, or run one experiment per task elsewhere), indent, and drive the afferents.

    run = run_scene("out/cyl8", load_scene("scenes/bars.toml"))     # what `pipeline.py indent` runs
    for e in run.experiments:
        e.name, e.indentor, e.steps, e.seconds       # steps: [(offset (3,) mm, ContactResult)]

    model, info = read_model("out/cyl8", scene.material, scene.nu)   # or on a model in memory
    run = run_experiments(model, info, scene)

Only the candidate nodes the scene's indentors can reach (`fem.contact.linear.reach`) are condensed
when the model is factorised. No files are written here (`fem.io.runfolder` writes them) except
through a given `fem.experiments.response.ResponseStore`.
"""
from __future__ import annotations

import dataclasses
import logging
import time
from dataclasses import dataclass, field

import numpy as np

from fem.contact.facets import PEAK_PRESSURE_RADIUS_MM, averaged_peak_pressure
from fem.contact.finite import FiniteContact
from fem.contact.indentors import Cylinder, Ellipsoid, Flat, Step, approach_direction, make_indentor, shapes_for
from fem.contact.linear import MAX_DEPTH_MM, ContactModel, reach, tissue_mm
from fem.core.fields import centroid_jacobians
from fem.core.materials import FLUID_LAYER
from fem.core.viscoelastic import LayerLaws
from fem.experiments.response import ResponseStore, contact_model, stored_responses
from fem.experiments.scene import AXES, Experiment, Receptors, Scene, line_text
from fem.experiments.spiking import scene_population, scene_responses
from fem.experiments.stepping import stepped_course
from fem.experiments.traces import frequency_warning
from fem.experiments.viscoelastic import elastic_indentations, relaxed_steps
from fem.io.modelfolder import (
    CONDENSE_MAX_NODES,
    CONTACT_REGION,
    approach_down,
    factorise,
    folder_dim,
    folder_info,
    held_regions,
    read_model,
    receptor_surface,
)
from fem.io.runfolder import writes_pvd
from fem.receptors.grid import ReceptorSampler, receptor_grid
from fingertip.errors import InputError
from fingertip.progress import as_progress

logger = logging.getLogger(__name__)

MAX_LINEAR_STRAIN = 0.2
"""Largest strain magnitude (max |principal strain|) at a receptor point within which a linear
(small-strain) result is taken at its word. The linear strain drops the quadratic term of the
Green-Lagrange strain, whose share grows with the strain itself (about half of it at 0.2 in simple
shear), and the contact is solved on the undeformed surface: beyond it `linear_validity` warns."""
MAX_INVERTED_FRACTION = 0.0
"""Fraction of the elements that the linear displacement may turn inside out (det(I + grad u) <= 0
at the centroid) before `linear_validity` warns: none, since such a displacement is no deformation
a body can take."""
LARGE_DEFORMATION = ("for large deformation use --kinematics finite (scene: kinematics = \"finite\"; all "
                     "indentors but wedges, cones and ellipsoids)")
"""What a warning of `validity_warning` points to beyond the linear range."""
LINEAR_ENOUGH_MM = {2: {"cylinder": 0.12, "bar": 0.13, "sphere": 0.18, "step": 0.08},
                    3: {"cylinder": 0.43, "bar": 0.1, "sphere": 0.64}}
"""Depth [mm] per model dimension and indentor class beyond which linear and finite kinematics
differ by more than 5 % in force or in the peak receptor SED at 0.75 mm, whichever comes first,
the smallest over the models measured, rounded down to 0.01 mm (benchmarks/finite_contact.py:
2D monkey section and 8 mm cylinder with bone, 0.25 mm, C1, C5, C8, a 2 mm bar, a 3 mm sphere,
step 2; 3D monkey preset, 1 mm, C5, the bar and the sphere; docs/indentation.md, "When linear is
enough"); an indentor of no class measured takes the smallest of its dimension."""


@dataclass
class ExperimentRun:
    """One experiment of a scene: its placement (orientation, position_mm, incline_deg), indentor,
    indentations in order [(offset (3,) mm, ContactResult)] and the seconds they took."""
    experiment: Experiment
    placement: dict
    indentor: object
    steps: list = field(default_factory=list)
    seconds: float = 0.0
    tissue_mm: float = float("inf")     # the tissue over the bone along its approach (`tissue_limit_mm`)
    validity: dict | None = None        # the linear result's range (`linear_validity`), run.json's "validity"
    viscoelastic: dict | None = None    # a relaxed time course's method and forces (run.json's "viscoelastic")
    stepped: object = None              # a course stepped in time: its fem.experiments.stepping.Stepped
    finite_fields: list | None = None   # finite kinematics with a PVD: [(u (ndof,) mm, {measure: (M,)})] per step
    finite_states: list | None = None   # finite kinematics: the fem.contact.finite.FiniteResult of each step

    @property
    def name(self) -> str:
        return self.experiment.name


@dataclass
class SceneRun:
    """Every experiment of a scene on one model, with what their outputs need: the contact model,
    its candidate nodes (`fem.core.model.SurfaceNodes`), the receptor grid and sampler, the measures,
    the receptor line ((axis, mm) or None), warnings about the placement and the stored response
    models used ([(key, "stored" or "built", build seconds, bytes)], `fem.experiments.response`) and
    the afferents ((population, {experiment name: response}), `fem.receptors.afferents`; (None, {})
    without [afferents])."""
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
    afferents: tuple = (None, {})
    peak_pressure_radius_mm: float = PEAK_PRESSURE_RADIUS_MM
    finite: object = None               # finite kinematics: the fem.contact.finite.FiniteContact (no contact model)

    def peak_pressure_MPa(self, force_N) -> float:
        """The largest contact pressure [MPa] averaged over peak_pressure_radius_mm of nodal forces
        (m,) [N; N/mm in 2D] on the candidates (`fem.contact.facets.averaged_peak_pressure`)."""
        return averaged_peak_pressure(force_N, self.surface.x, self.peak_pressure_radius_mm)


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
    if exp.force_N is None:
        return max(exp.depth_mm)
    return MAX_DEPTH_MM if exp.max_depth_mm is None else exp.max_depth_mm


def tissue_limit_mm(model, sn, approach) -> float:
    """`fem.contact.linear.tissue_mm` of the contact region `sn` along `approach` (mm)."""
    return tissue_mm(model, sn.x, approach)


def within_tissue(exp: Experiment, limit_mm: float) -> Experiment:
    """The experiment with the depth limit of force control it runs with: max_depth_mm, else the
    tissue over the bone (limit_mm) capped at MAX_DEPTH_MM. InputError for a depth, or a given
    max_depth_mm, beyond the tissue (limit_mm)."""
    where = f"experiment '{exp.name}'"
    beyond = f"is beyond the {limit_mm:g} mm of tissue over the bone of this model"
    if exp.force_N is None:
        deepest = max(exp.depth_mm)
        if deepest > limit_mm:
            raise InputError(f"{where}: depth_mm {deepest:g} mm {beyond}; give depth_mm up to {limit_mm:g}")
        return exp
    if exp.max_depth_mm is None:
        return dataclasses.replace(exp, max_depth_mm=min(MAX_DEPTH_MM, limit_mm))
    if exp.max_depth_mm > limit_mm:
        raise InputError(f"{where}: max_depth_mm {exp.max_depth_mm:g} mm {beyond}; give max_depth_mm up to "
                         f"{limit_mm:g}")
    return exp


def check_receptor_depths(model, info, sn, depths_mm) -> None:
    """InputError for receptor depths at or beyond the tissue over the bone (along the model's
    support; -y in 2D), where receptor points would lie in the bone or outside the model."""
    a = approach_down(info) if model.dim == 3 else np.array([0.0, -1.0, 0.0])
    limit = tissue_limit_mm(model, sn, a)
    deepest = max(depths_mm, default=0.0)
    if deepest >= limit:
        raise InputError(f"receptor depths_mm {deepest:g} mm is not inside the {limit:g} mm of tissue over the "
                         f"bone of this model; give depths_mm below {limit:g}")


def receptor_line(line, sn, dim) -> tuple[int, float] | None:
    """A scene's receptor line [axis, mm | "middle"] as (axis index, mm) on the contact region."""
    if line is None:
        return None
    axis = AXES[str(line[0])]
    if axis >= dim:
        raise InputError(f"bad receptor line {line_text(line)}: use z=<mm> or z=middle (3D), x=<mm>")
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
    factorised for every candidate the whole scene can reach, so its numbers are the full run's.
    With the scene's [viscoelastic] law, traced experiments are solved elastically
    (`fem.experiments.viscoelastic.elastic_indentations`) and relaxed in time (`relaxed_steps`);
    with a law per layer whose spectra differ, they are stepped in time instead
    (`fem.experiments.stepping.stepped_course`)."""
    progress = as_progress(progress)
    if scene.kinematics == "finite":
        return finite_experiments(model, info, scene, progress, only)
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
    law, layered = split_laws(scene.viscoelastic, model)
    chosen = [run for k, run in enumerate(runs) if only is None or k == only]
    stepped = [run for run in chosen if layered is not None and run.experiment.trace is not None]
    todo = [(run, off, load) for run in chosen if run not in stepped
            for off, load in elastic_indentations(run.experiment, law)]
    _check_forces(cm, todo)
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
            run.validity = linear_validity(run, sampler, cm if system is not None else None, model)
            if law is not None and run.experiment.trace is not None:
                run.steps, run.viscoelastic = relaxed_steps(run.steps, run.experiment, law, sampler.sizes)
            if system is not None:
                system.restart_refinement()
            cm.restart()
        run.seconds += time.perf_counter() - t0
    for run in stepped:
        t0 = time.perf_counter()
        with progress.task(f"{run.name}: {len(run.experiment.times_s)} viscoelastic time steps", kind="stepping"):
            run.steps, run.viscoelastic, run.stepped = stepped_course(model, info, run, layered, sampler,
                                                                     sn.nodes[touched])
        U = run.stepped.displacement_mm
        run.validity = linear_validity(run, sampler, None, model, displacement=lambda i, U=U: U[:, i])
        run.seconds += time.perf_counter() - t0
    return SceneRun(model, info, scene, cm, sn, grid, sampler, list(rc.measures), line, runs, warnings, used)


def finite_experiments(model, info, scene: Scene, progress, only: int | None = None) -> SceneRun:
    """`run_experiments` with finite kinematics (`fem.contact.finite`): each experiment's depths in
    turn (or its force) on the neo-Hookean model, its steps ContactResults with the force per candidate along the
    approach, the deflection along it, the normal gaps, the pressure of the normal forces over the
    reference areas (nominal), the KKT check, the stored energy, and receptor values of the finite
    state (`FiniteContact.observe`, read by the sampler `with_energy`); with a PVD, each step's
    displacement and the finite measures at the element centroids (`run.finite_fields`). No contact
    model."""
    sn, runs, warnings, _, line, grid = _plan(model, info, scene)
    with progress.task(f"receptor operators at {len(grid.points_mm)} points", kind=f"sampler-{model.dim}d",
                       size=len(grid.points_mm)):
        sampler = ReceptorSampler(model, grid)
    fc = FiniteContact(model, CONTACT_REGION[model.dim], held_regions(model))
    for k, run in enumerate(runs):
        if only is not None and k != only:
            continue
        t0 = time.perf_counter()
        course = finite_course(fc, run, progress)
        states = {id(r): (ind, r) for _, ind, r in course}     # a hold repeats a state: once each
        results = {k: fc.contact_result(ind, r, sampler) for k, (ind, r) in states.items()}
        run.steps = [(np.asarray(off, float), results[id(r)]) for off, _, r in course]
        run.finite_states = [r for _, _, r in course]
        if writes_pvd(scene.output, len(course)):
            fields = {k: (r.u, fc.element_fields(r.u)) for k, (_, r) in states.items()}
            run.finite_fields = [fields[id(r)] for _, _, r in course]
        run.seconds += time.perf_counter() - t0
    return SceneRun(model, info, scene, None, sn, grid, sampler.with_energy(), list(scene.receptors.measures), line,
                    runs, warnings, [], finite=fc)


def finite_course(fc: FiniteContact, run: ExperimentRun, progress) -> list:
    """[(offset (3,), indentor there, FiniteResult)] of an experiment, one per indentation.
    Frictionless hyperelastic contact has no memory of its path: each sweep position is indented
    from rest, and a time course's distinct depths are solved once as one increasing series (by
    force: each distinct force from rest) and read at every sample (the same result object)."""
    exp, ind = run.experiment, run.indentor
    max_depth = exp.loads[0].get("max_depth_mm")
    if exp.trace is None:
        out = []
        for off in exp.offsets_mm:
            at = ind if exp.sweep is None else ind.shifted(off)
            where = "" if exp.sweep is None else f" at offset {np.round(off[exp.sweep[0]], 6):g} mm"
            with progress.task(f"{run.name}: finite contact " + (f"at {exp.force_N:g} N" if exp.force_N is not None
                               else f"to {max(exp.depth_mm):g} mm") + where, kind="finite"):
                try:
                    results = ([fc.indent_force(at, exp.force_N, max_depth, progress=progress)]
                               if exp.force_N is not None else fc.indent(at, exp.depth_mm, progress=progress))
                except RuntimeError as exc:
                    raise _not_reached(run, exc, where) from None
            out += [(off, at, r) for r in results]
        return out
    samples = exp.indentations
    try:
        with progress.task(f"{run.name}: finite contact through its time course", kind="finite"):
            if exp.force_N is None:
                depths = sorted({round(load["depth_mm"], 12) for _, load in samples})
                solved = dict(zip(depths, fc.indent(ind, depths, progress=progress)))
                return [(off, ind, solved[round(load["depth_mm"], 12)]) for off, load in samples]
            solved = {}
            for _, load in samples:
                f = round(load.get("force_N", 0.0), 15)
                if f not in solved:
                    solved[f] = (fc.indent(ind, [0.0])[0] if f <= 0 else
                                 fc.indent_force(ind, f, max_depth, progress=progress))
            return [(off, ind, solved[round(load.get("force_N", 0.0), 15)]) for off, load in samples]
    except RuntimeError as exc:
        raise _not_reached(run, exc) from None


def _not_reached(run: ExperimentRun, exc: RuntimeError, where: str = "") -> InputError:
    """The one-line error of a finite indentation whose Newton could not reach a depth (the message
    names the depth reached); the run writes nothing."""
    return InputError(f"experiment '{run.name}'{where}: {exc}; nothing written: ask for less depth or force, or "
                      "use --kinematics linear")


def split_laws(law, model):
    """(the Prony law every layer shares or None, the LayerLaws to step in time or None) of a
    scene's [viscoelastic] on a model (fem.core.viscoelastic: a Prony, or LayerLaws whose layers
    of this model may all share one law)."""
    if not isinstance(law, LayerLaws):
        return law, None
    groups = law.groups(np.unique(model.layer[model.layer != FLUID_LAYER]))
    return (groups[0][0], None) if len(groups) == 1 else (None, law)


def linear_validity(run: ExperimentRun, sampler: ReceptorSampler, cm: ContactModel | None, model,
                    displacement=None) -> dict:
    """Whether an experiment's linear results are within their range (run.json's "validity"): the
    largest receptor strain (max |principal strain| over its points and indentations, against
    MAX_LINEAR_STRAIN), and the fraction of the elements (the fluid core's aside) that the
    displacement of its deepest indentation (`checked_indentation`; the largest force among equal
    depths) turns inside out (`fem.core.fields.centroid_jacobians` <= 0, against
    MAX_INVERTED_FRACTION). The full field takes one solve with the factorised contact model `cm`,
    or is displacement(step index) (a stepped course); neither (a stored response model answered)
    leaves the inversion unchecked (null)."""
    steps = [res for _, res in run.steps]
    strain = [float(np.abs(sampler.state(r.observed).principal_strain).max(initial=0.0)) for r in steps]
    worst = int(np.argmax(strain))
    deepest = max(range(len(steps)), key=lambda i: (float(steps[i].depth_mm.max()), steps[i].total_force_N))
    inverted = None
    if cm is not None or displacement is not None:
        u = (displacement(deepest) if displacement is not None
             else cm.compliance(run.indentor.approach).displacement(steps[deepest].force_N))
        solid = model.layer != FLUID_LAYER
        inverted = float(np.mean(centroid_jacobians(model, u)[solid] <= 0))
    linear = strain[worst] <= MAX_LINEAR_STRAIN and (inverted is None or inverted <= MAX_INVERTED_FRACTION)
    return {"checked_indentation": deepest, "depth_mm": float(steps[deepest].depth_mm.max()),
            "linear_enough_mm": linear_enough_mm(run.experiment.indentor, model.dim),
            "inverted_elements": inverted, "inversion_checked": inverted is not None,
            "max_receptor_strain": strain[worst], "max_receptor_strain_indentation": worst,
            "max_linear_strain": MAX_LINEAR_STRAIN, "max_inverted_fraction": MAX_INVERTED_FRACTION,
            "within_linear_range": bool(linear)}


def indentor_class(code: str) -> str | None:
    """The class of an indentor code in LINEAR_ENOUGH_MM ("cylinder", "bar", "sphere", "step"), or
    None for the others (plates, punches, gratings, wedges, cones, ellipsoids, two-point)."""
    parts = shapes_for(code)[1]
    shape = parts[0] if len(parts) == 1 else None
    if isinstance(shape, Cylinder):
        return "cylinder"
    if isinstance(shape, Flat) and not np.isfinite(shape.length_mm):
        return "bar"
    if isinstance(shape, Ellipsoid) and shape.is_sphere:
        return "sphere"
    return "step" if isinstance(shape, Step) else None


def linear_enough_mm(code: str, dim: int) -> float:
    """LINEAR_ENOUGH_MM's depth [mm] for an indentor code on a model of dimension `dim`."""
    table = LINEAR_ENOUGH_MM[dim]
    return table.get(indentor_class(code), min(table.values()))


def linear_note(run: ExperimentRun) -> str | None:
    """One line for a linear experiment deeper than its `linear_enough_mm` and within the linear
    range (beyond it `validity_warning` speaks), else None."""
    v = run.validity
    if v is None or not v["within_linear_range"] or v["depth_mm"] <= v["linear_enough_mm"]:
        return None
    cls = indentor_class(run.experiment.indentor)
    return (f"{run.name} reaches {v['depth_mm']:.3g} mm: beyond {v['linear_enough_mm']:.2g} mm linear and finite "
            f"kinematics differ by more than 5 % in force or receptor SED "
            f"({'for ' + cls + 's' if cls else 'the smallest depth measured for any indentor'}; docs/indentation.md, "
            f"\"When linear is enough\"): --kinematics finite for large-deformation numbers")


def validity_warning(run: ExperimentRun) -> str | None:
    """The warning of an experiment whose linear results leave their range (`linear_validity`), or
    None: "C5 at 3 mm: the linear displacement inverts 4.1 % of the elements and strains receptors
    by 0.48 (> 0.2): small-strain results are out of their range here; ..."."""
    v = run.validity
    if v is None or v["within_linear_range"]:
        return None
    inverts = v["inverted_elements"] is not None and v["inverted_elements"] > v["max_inverted_fraction"]
    strains = v["max_receptor_strain"] > v["max_linear_strain"]
    what = [f"inverts {100 * v['inverted_elements']:.2g} % of the elements"] if inverts else []
    if strains:
        what.append(f"strains receptors by {v['max_receptor_strain']:.2f} (> {v['max_linear_strain']:g})")
    else:
        what[0] += f" (receptor strains up to {v['max_receptor_strain']:.2f})"
    unchecked = "" if v["inversion_checked"] else (" (element inversion not checked: a stored response model "
                                                   "has no full displacement field)")
    return (f"{run.name} at {v['depth_mm']:.3g} mm: the linear displacement {' and '.join(what)}{unchecked}: "
            f"small-strain results are out of their range here; {LARGE_DEFORMATION}")


def _plan(model, info, scene: Scene):
    """(contact region's SurfaceNodes, [ExperimentRun without steps], warnings (placement, sines
    above the quasi-static limit), (P,) bool candidates the scene can reach, receptor line,
    receptor grid) of a scene; refuses afferents it cannot place (`scene_population`) before any solve."""
    scene.check_dim(model.dim)
    scene.check_count()
    sn = model.surface_nodes(CONTACT_REGION[model.dim])
    runs, warnings, touched = [], [], np.zeros(len(sn.nodes), bool)
    for exp in scene.experiments:
        place, warning = placement(exp, model, info, sn)
        for w in (warning, frequency_warning(exp.trace)):
            if w:
                warnings.append(w if w is warning else f"experiment '{exp.name}': {w}")
        ind = make_indentor(exp.indentor, **place)
        tissue = tissue_limit_mm(model, sn, ind.approach)
        exp = within_tissue(exp, tissue)
        touched |= reach(sn.x, ind, exp.offsets_mm, deepest_mm(exp))
        runs.append(ExperimentRun(exp, place, ind, tissue_mm=tissue))
    if scene.afferents is not None:
        scene_population(scene.afferents, model, sn, runs)
    rc = scene.receptors
    check_receptor_depths(model, info, sn, rc.depths_mm)
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


def _check_forces(cm: ContactModel, todo) -> None:
    """Refuse a force that is not reached at its depth limit before the indentations start: the
    full force of each force-controlled experiment, or the largest of its indentations `todo`
    [(run, offset, load)] where viscoelastic layers creep, at its first position."""
    for run in {id(r): r for r, _, _ in todo}.values():
        exp = run.experiment
        if exp.force_N is None:
            continue
        target = max(exp.force_N, *(load.get("force_N", 0.0) for r, _, load in todo if r is run))
        force = cm.force_at(run.indentor.shifted(exp.offsets_mm[0]), exp.max_depth_mm, exp.equal_force)
        if force is None or np.all(force >= target * (1 - 1e-6)):
            continue
        unit = "N/mm" if cm.points_mm.shape[1] == 2 else "N"
        there = f"the force there is {', '.join(f'{f:.4g}' for f in force)} {unit}"
        given = f"force_N {exp.force_N:g} {unit}" + (f" (creeping: the elastic model needs {target:.4g} {unit})"
                                                    if target > exp.force_N * (1 + 1e-9) else "")
        if exp.max_depth_mm >= run.tissue_mm:
            raise InputError(f"experiment '{exp.name}': {given} is not reached within the "
                             f"{run.tissue_mm:g} mm of tissue over the bone of this model ({there}): give a "
                             f"smaller force_N")
        raise InputError(f"experiment '{exp.name}': {given} is not reached within "
                         f"max_depth_mm {exp.max_depth_mm:g} mm ({there}): lower force_N or raise max_depth_mm "
                         f"(up to the {run.tissue_mm:g} mm of tissue over the bone)")


def _indent_one(cm: ContactModel, run: ExperimentRun, off, load):
    """One indentation of an experiment: at offset `off` (3,) mm with `load` (depth or force)."""
    if run.experiment.sweep is not None:
        return cm.sweep(run.indentor, off[None], **load)[0]
    return cm.indent(run.indentor, **load)


# --------------------------------------------------------------------------- the scene runner
def run_scene(model_dir, scene: Scene, store=None, map=None, progress=None) -> SceneRun:
    """Every experiment of `scene` on a model folder, as the command line runs it (the one call
    behind `pipeline.py indent`, `batch` and the distributed tasks).

    store: the folder's `fem.experiments.response.ResponseStore`: the contact problems and receptor
    measures are answered by its response models (built and stored when missing) unless the scene
    needs full fields (a PVD) or afferents, which factorise. map: map(fn, items) -> [fn(item)]
    in order (e.g. tasks on Dask workers, `fingertip.jobs.tasks.task_map`): a scene of several
    experiments that factorises runs one task per experiment, each reading and factorising the
    model itself, with the numbers of the run in this process. progress: a `fingertip.progress`
    object (None: silent): notes why a store or a map is not used, and the work."""
    progress = as_progress(progress)
    scene.check_dim(folder_dim(folder_info(model_dir)))
    model, info = read_model(model_dir, scene.material, scene.nu)
    if scene.afferents is not None:     # their placement refused before the notes below (`_plan`)
        _plan(model, info, scene)
    if store is not None and (why := store_blocker(scene)):
        progress.note(f"response model: not used, {why}: factorising"
                      + (" (--no-pvd answers from the stored response models)" if "PVD" in why else ""))
        store = None
    if map is not None and (why := distribution_blocker(scene, store)):
        progress.note(f"scheduler: running the scene in this process: {why}")
        map = None
    if map is not None:
        runs = map(experiment_task, [(str(model_dir), scene, k) for k in range(len(scene.experiments))])
        run = assemble_run(model, info, scene, runs, progress)
    else:
        run = run_experiments(model, info, scene, progress=progress, store=store)
    for e in run.experiments:
        if (warning := validity_warning(e)) is not None:
            logger.warning(warning)
    if scene.afferents is not None:
        with progress.task("afferent inputs and spike trains", kind="afferents"):
            run.afferents = scene_responses(run)
    return run


def store_blocker(scene: Scene) -> str | None:
    """Why stored response models cannot answer a scene (None when they can)."""
    return ("afferents need the stresses at their own sites" if scene.afferents is not None else
            "viscoelastic layers with their own spectra are stepped in time on the factorised model"
            if isinstance(scene.viscoelastic, LayerLaws) else
            "finite kinematics solves the neo-Hookean model" if scene.kinematics == "finite" else
            "the PVD output needs full fields"
            if any(writes_pvd(scene.output, len(e.indentations)) for e in scene.experiments) else None)


def distribution_blocker(scene: Scene, store=None) -> str | None:
    """Why a scene's experiments cannot run as separate tasks (None when they can): one
    experiment, afferents or a PVD (they need the factorised model in this process), or a store
    that answers without factorising."""
    return ("it has one experiment" if len(scene.experiments) < 2 else
            "its afferents need the factorised model in this process" if scene.afferents is not None else
            "the stored response models answer it without factorising" if store is not None else
            "its PVD output needs the full fields in this process (--no-pvd distributes it)"
            if any(writes_pvd(scene.output, len(e.indentations)) for e in scene.experiments) else None)


def experiment_task(item: tuple) -> ExperimentRun:
    """One task of a distributed `run_scene`: item (model folder, Scene, experiment index) ->
    its ExperimentRun with the indentations observed (the model is read where the task runs)."""
    model_dir, scene, index = item
    model, info = read_model(model_dir, scene.material, scene.nu)
    return run_experiment(model, info, scene, index)


# --------------------------------------------------------------------------- stored response models
@dataclass
class Prepared:
    """What `prepare_responses` stored: the store, its key, "stored" (found) or "built", build
    seconds and bytes, the candidates (m), the unit approach (3,), the receptor points and the
    material code."""
    store: ResponseStore
    key: str
    how: str
    built_s: float
    nbytes: int
    candidates: int
    approach: np.ndarray
    receptor_points: int
    material: str | None


def prepare_responses(model_dir, material=None, nu=None, approach=None, receptors: Receptors = Receptors(),
                      progress=None) -> Prepared:
    """Build (or find) the response model of a model folder for a material, approach (3,) (default:
    the model's support; a 2D model's lies in its x-y plane) and receptor grid, and store it in
    <model>/response/<key>/, so that later scenes with the same inputs and no PVD answer without
    factorising. Every contact candidate is condensed (InputError beyond CONDENSE_MAX_NODES)."""
    info = folder_info(model_dir)
    dim = folder_dim(info)
    a = approach_down(info) if approach is None else np.asarray(approach, float) / np.linalg.norm(approach)
    if dim == 2 and a[2] != 0:
        raise InputError(f"approach {np.round(a, 6).tolist()}: a 2D model is indented within its x-y plane: "
                         f"give z = 0")
    if dim == 2:
        a = np.array([a[0], a[1], 0.0]) / np.linalg.norm(a[:2])
    model, info = read_model(model_dir, material, nu)
    sn = model.surface_nodes(CONTACT_REGION[model.dim])
    if len(sn.nodes) > CONDENSE_MAX_NODES:
        raise InputError(f"the contact region has {len(sn.nodes)} candidates, more than the "
                         f"{CONDENSE_MAX_NODES} a response model condenses: run `pipeline.py indent` with "
                         f"your scene and --no-pvd, which stores one for the candidates it can touch")
    check_receptor_depths(model, info, sn, receptors.depths_mm)
    grid = receptor_grid(*receptor_surface(model, sn), np.asarray(receptors.depths_mm, float), receptors.spacing_mm,
                         receptor_line(receptors.line, sn, model.dim))
    store = ResponseStore(model_dir)
    _, _, used = stored_responses(store, model, [a], grid, np.ones(len(sn.nodes), bool), as_progress(progress))
    key, how, built, size = used[0]
    return Prepared(store, key, how, built, size, len(sn.nodes), a, len(grid.points_mm), model.material.code)
