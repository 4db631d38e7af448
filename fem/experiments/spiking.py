"""A scene's afferents driven through its traced experiments (the scene's [afferents]).

The transduction integrates at 5 kHz. An elastic indentation that depends on its load alone (a
depth or a force, no sweep) gives the same inputs whatever the path to that load (linear
frictionless contact), so the inputs of a course are tabulated over the load
(`fem.receptors.afferents.LoadTable`) and read at the course's load at every 5 kHz sample
(`fem.experiments.traces.course`, in closed form): the number of sample times then sets the
rows of the output tables, not the spikes. The table starts at the loads of the sample times and
is refined by bisection until linear interpolation between its loads is within TABLE_TOLERANCE
of the inputs solved at the midpoints (`tabulate`). Frictionless contact of the hyperelastic
model (finite kinematics) has no memory of its path either: its table is built from the finite
states, their Cauchy stress or stored energy (`finite_tabulate`). Viscoelastic layers relax the tabulated
elastic stress at 5 kHz (`fem.receptors.afferents.respond`); under force control the course's
load is the elastic force that the creep gives (`fem.experiments.viscoelastic`). A scan moves the
indentor, and layers with their own spectra make the path matter (`fem.experiments.stepping`):
their inputs are the samples', linear in time in between.

    population, responses = scene_responses(scene_run)    # {experiment name: PopulationResponse}
"""
from __future__ import annotations

from itertools import pairwise

import numpy as np

from fem.experiments.traces import course
from fem.experiments.viscoelastic import NEGLIGIBLE_FORCE, elastic_indentations
from fem.receptors.afferents import (
    LoadTable,
    Population,
    experiment_inputs,
    place,
    respond,
    sampler_of,
    site_inputs,
    static_input,
)
from fem.receptors.transduction import lif_times

TABLE_TOLERANCE = 0.002
"""Largest error of the tabulated inputs interpolated at a midpoint, as a fraction of the
largest value of that input (static, deflection) in the table (`tabulate`)."""
MAX_TABLE_LOADS = 257
"""Most loads a table may hold (the refinement stops there)."""
FINITE_TABLE_TOL = 1e-5
"""Relative residual to which finite kinematics solves a table's midpoints (`finite_tabulate`):
they enter the table only to TABLE_TOLERANCE."""


def load_value(load: dict) -> float:
    """The scalar load of a ContactModel.indent keyword set: force_N [N] under force control,
    else depth_mm [mm] (a zero fraction is {"depth_mm": 0}: 0 either way)."""
    return float(load["force_N"] if "force_N" in load else load["depth_mm"])


def _indentation(full: dict, value: float) -> dict:
    """The keyword set of ContactModel.indent at load `value` on the experiment's full one."""
    if value <= 0:
        return {"depth_mm": 0.0}
    return {**full, "force_N": value} if "force_N" in full else {"depth_mm": value}


def tabulate(sampler, population: Population, contact, run, measure: str = "stress", law=None,
             tolerance: float = TABLE_TOLERANCE) -> LoadTable:
    """The population's elastic inputs over the load of a traced experiment without a sweep
    (fem.experiments.runner.ExperimentRun, solved on `contact`, a fem.contact.linear.ContactModel):
    the distinct loads of its sample times (`elastic_indentations` under `law`), then midpoints of
    every interval whose linear interpolation misses the solved inputs by more than `tolerance`
    of the table's largest value, bisected again until none does (or MAX_TABLE_LOADS)."""
    exp, pop = run.experiment, population
    comp = contact.compliance(run.indentor.approach)

    def inputs(results):
        forces = np.stack([r.force_N if r.elastic_force_N is None else r.elastic_force_N for r in results], axis=1)
        deflection = np.stack([pop.at_sites(r.deflection_mm) for r in results], axis=1)
        return site_inputs(sampler, pop, comp, forces, measure), deflection

    first = {}                        # a load reached twice (ramp and release) differs in its last bits
    for (_, load), (_, res) in zip(elastic_indentations(exp, law), run.steps):
        first.setdefault(float(f"{load_value(load):.12g}"), res)
    loads = np.array(sorted(first))
    full = exp.loads[0]
    contact.restart()                 # the table does not depend on the experiments before it
    return _refined(loads, *inputs([first[v] for v in loads]), tolerance,
                    lambda mid: inputs([contact.indent(run.indentor, **_indentation(full, v)) for v in mid]))


def finite_tabulate(fc, sampler, population: Population, run, measure: str = "stress",
                    tolerance: float = TABLE_TOLERANCE) -> LoadTable:
    """`tabulate` with finite kinematics: `fc` (a fem.contact.finite.FiniteContact) solved the
    run's `finite_states`; the static input of a state is -n.sigma.n of its Cauchy stress
    ('stress', compression positive) or its stored energy per reference volume ('sed') [MPa] at
    the afferents (`FiniteContact.observe`), the deflection its displacement along the approach
    above each. Midpoints are solved from rest: the depths as one increasing series, each force
    on its own (frictionless hyperelastic contact has no memory of its path)."""
    exp, pop, ind = run.experiment, population, run.indentor
    with_energy = sampler.with_energy()

    def inputs(states):
        static = [static_input(with_energy, pop, fc.observe(r.u, sampler), measure) for r in states]
        deflection = [pop.at_sites(r.u[fc.dofs] @ ind.approach[:fc.model.dim]) for r in states]
        return np.stack(static, axis=1), np.stack(deflection, axis=1)

    full = exp.loads[0]

    def solve(mid):
        if "force_N" not in full:
            return inputs(fc.indent(ind, list(mid), tol=FINITE_TABLE_TOL))
        return inputs([fc.indent_force(ind, v, full.get("max_depth_mm")) for v in mid])     # mid > 0

    first = {}
    for (_, load), r in zip(exp.indentations, run.finite_states):
        first.setdefault(float(f"{load_value(load):.12g}"), r)
    loads = np.array(sorted(first))
    return _refined(loads, *inputs([first[v] for v in loads]), tolerance, solve)


def _refined(loads, static, deflection, tolerance: float, solve) -> LoadTable:
    """A LoadTable from inputs static, deflection (n, m) at loads (m,) increasing, refined by
    bisection: solve(mid (k,) increasing) -> (static (n, k), deflection (n, k)) at new loads, for
    the midpoint of every interval whose linear interpolation misses them by more than `tolerance`
    of the table's largest value, until none does (or MAX_TABLE_LOADS)."""
    pending = list(pairwise(loads))
    while pending and len(loads) < MAX_TABLE_LOADS:
        pending = pending[:MAX_TABLE_LOADS - len(loads)]
        mid = np.array([0.5 * (a + b) for a, b in pending])
        s_mid, w_mid = solve(mid)
        s_lin, w_lin = LoadTable(loads, static, deflection).at(mid)
        peak_s = max(np.abs(static).max(initial=0.0), np.abs(s_mid).max(initial=0.0)) or 1.0
        peak_w = max(np.abs(deflection).max(initial=0.0), np.abs(w_mid).max(initial=0.0)) or 1.0
        miss = np.maximum(np.abs(s_mid - s_lin).max(axis=0, initial=0.0) / peak_s,
                          np.abs(w_mid - w_lin).max(axis=0, initial=0.0) / peak_w)
        order = np.argsort(np.r_[loads, mid], kind="stable")
        loads = np.r_[loads, mid][order]
        static, deflection = np.c_[static, s_mid][:, order], np.c_[deflection, w_mid][:, order]
        pending = [half for (a, b), m, e in zip(pending, mid, miss) if e > tolerance for half in ((a, m), (m, b))]
    return LoadTable(loads, static, deflection)


def fine_loads(exp, law=None) -> np.ndarray:
    """(T,) the load of a traced experiment (no sweep) at the transduction's 5 kHz times
    (`fem.receptors.transduction.lif_times`): depth [mm], or under force control the force [N],
    with viscoelastic layers (`law`) the elastic force their creep gives (`elastic_indentations`)."""
    t = lif_times(exp.times_s[-1])
    full = exp.loads[0]
    x = course(exp.trace, t) * load_value(full)
    if law is not None and "force_N" in full:
        x = law.creep(t, x)
        x[x <= NEGLIGIBLE_FORCE * x.max(initial=0.0)] = 0.0
    return x


def stepped_inputs(model, population: Population, run, sampler) -> np.ndarray:
    """(n, k) static input (-n.sigma.n, MPa) of a population (its `sampler_of`) through a course
    stepped in time (fem.experiments.stepping): each layer group's elastic stress at the
    afferents relaxed by its own law over the sample times, summed."""
    times = run.experiment.times_s
    groups = run.stepped.group_values(model, lambda m: m.stress_operator(sampler.points_mm))
    rows = sampler.operator @ run.stepped.displacement_mm
    rows[sampler.stress_rows] = sum(v if law is None else law.relax(times, v.T).T for law, v in groups)
    return np.stack([static_input(sampler, population, rows[:, j]) for j in range(len(times))], axis=1)


def scene_population(cfg, model, surface, runs) -> Population:
    """The population of a scene's [afferents] `cfg` over the contact region's candidates
    `surface` (fem.core.model.SurfaceNodes): at its sites_mm, or by density around where the
    first traced experiment of `runs` (fem.experiments.runner.ExperimentRun) touches (`place`,
    seeded: the same population every call)."""
    first = next(r for r in runs if r.experiment.times_s is not None)
    centre = surface.x[np.argmin(first.indentor.standoff(surface.x))]
    return place(model, surface, cfg.classes, dict(cfg.density_per_cm2 or ()), centre, cfg.radius_mm, cfg.seed,
                 cfg.sites_mm)


def scene_responses(scene_run) -> tuple[Population | None, dict]:
    """(the population, {experiment name: PopulationResponse}) of a fem.experiments.runner.SceneRun
    whose scene has [afferents]: every traced experiment drives the same population
    (`scene_population`). (None, {}) without [afferents]."""
    cfg = scene_run.scene.afferents
    if cfg is None:
        return None, {}
    model, law = scene_run.model, scene_run.scene.viscoelastic
    pop = scene_population(cfg, model, scene_run.surface, scene_run.experiments)
    sampler = sampler_of(model, pop)
    out = {}
    for run in scene_run.experiments:
        exp = run.experiment
        if exp.times_s is None:
            continue
        if run.stepped is not None or exp.sweep is not None:    # the inputs depend on the path
            if run.stepped is not None:   # layers with their own spectra
                static = stepped_inputs(model, pop, run, sampler)
                deflection = np.stack([pop.at_sites(r.deflection_mm) for _, r in run.steps], axis=1)
            else:                         # a scan: on the position, not on a load
                static, deflection = experiment_inputs(sampler, pop, scene_run.contact, run, cfg.input)
            out[run.name] = respond(pop, exp.times_s, static, deflection, cfg.gain, cfg.noisy, cfg.seed)
            continue
        table = (finite_tabulate(scene_run.finite, sampler, pop, run, cfg.input) if scene_run.finite is not None
                 else tabulate(sampler, pop, scene_run.contact, run, cfg.input, law))
        at_samples = table.at([load_value(load) for _, load in elastic_indentations(exp, law)])
        resp = respond(pop, exp.times_s, *at_samples, cfg.gain, cfg.noisy, cfg.seed,
                       fine=table.at(fine_loads(exp, law)), law=law)
        resp.table_loads = len(table.load)
        out[run.name] = resp
    return pop, out
