"""Time courses of viscoelastic layers (a scene's [viscoelastic]) by the correspondence principle.

Every layer's moduli relax by the same g(t) (`fem.core.viscoelastic.Prony`), so the viscoelastic
contact of a time course follows from its elastic one (Lee and Radok 1960): while the contact area
does not shrink, the displacements, strains, deflections and contact area at each sample are the
elastic ones at that sample's depth, and the nodal forces, contact pressure and stresses are the
hereditary integral of the elastic ones, sigma(t) = int g(t - s) d sigma_e(s).

Under depth control the elastic course is solved at the trace's depths and relaxed. Under force
control the depth creeps: the elastic solves are made at the elastic force F_e = J * F (the creep
compliance convolved with the prescribed force, `elastic_indentations`), whose depths the
viscoelastic body reaches under F, and their forces relaxed give back F (to the sampling of F_e,
linear between samples in the relaxation recursion: `record`'s force_deviation).

Where the contact area shrinks (a release, a scan moving on) Lee and Radok's result is no longer
the solution: Ting's (1966) correction is not made, so there the numbers are the method's limit
(forces may turn tensile). run.json records when that first happens (`record`).

    todo = elastic_indentations(exp, law)           # [(offset (3,) mm, load)], solved elastically
    steps, info = relaxed_steps(steps, exp, law, sampler.sizes)
"""
from __future__ import annotations

import dataclasses

import numpy as np

METHOD = ("correspondence principle (Lee and Radok 1960): displacements, strains and contact area are the "
          "elastic ones at each sample's depth, forces, pressures and stresses their hereditary integral; "
          "exact while the contact area does not shrink (Ting's correction is not made: after "
          "contact_shrinks_at_s the results are the method's limit, and forces may turn tensile)")
"""How run.json describes the method of a viscoelastic experiment."""
NEGLIGIBLE_FORCE = 1e-9
"""Elastic forces below this fraction of the largest one of a course are taken as no contact."""


def elastic_indentations(exp, law) -> list[tuple[np.ndarray, dict]]:
    """The indentations (`fem.experiments.scene.Experiment.indentations`) that the elastic model
    solves for a viscoelastic one: as given under depth control (or without a law or a trace);
    under force control each force F(t) replaced by the elastic force F_e = law.creep(F) [N]."""
    todo = exp.indentations
    if law is None or exp.trace is None or exp.force_N is None:
        return todo
    elastic = law.creep(exp.times_s, np.array([load.get("force_N", 0.0) for _, load in todo]))
    full, least = exp.loads[0], NEGLIGIBLE_FORCE * elastic.max(initial=0.0)
    return [(off, {**full, "force_N": float(f)} if f > least else {"depth_mm": 0.0})
            for (off, _), f in zip(todo, elastic)]


def relaxed_steps(steps, exp, law, sizes) -> tuple[list, dict]:
    """([(offset, ContactResult)] viscoelastic, run.json record) of the elastic steps (observed:
    one result per distinct indentation may repeat) at the sample times of a traced experiment
    `exp` (fem.experiments.scene.Experiment) under `law` (fem.core.viscoelastic.Prony). Forces and
    pressures (m,) and the stress block of `observed` (the last of the blocks `sizes`: the
    receptor sampler's displacement, strain, stress) are relaxed; every other field is the
    elastic result's, which keeps its forces as `elastic_force_N` (its displacement field's)."""
    results, times_s = [r for _, r in steps], exp.times_s
    force = law.relax(times_s, np.stack([r.force_N for r in results]))
    pressure = law.relax(times_s, np.stack([r.pressure_MPa for r in results]))
    observed = np.stack([r.observed for r in results])
    stress = slice(int(sum(sizes[:-1])), None)
    observed[:, stress] = law.relax(times_s, observed[:, stress])
    out = [(off, dataclasses.replace(r, force_N=force[k], pressure_MPa=pressure[k], kkt=dict(r.kkt),
                                     _gap_mm=r.gap_mm, _deflection_mm=r.deflection_mm, _observed=observed[k],
                                     _source=None, _unseen=None, elastic_force_N=r.force_N))
           for k, (off, r) in enumerate(steps)]
    return out, record(results, exp, force.sum(axis=1))


def record(elastic, exp, force_N) -> dict:
    """run.json's "viscoelastic" entry of a traced experiment from its elastic results and the
    relaxed total force per sample (n,) [N]: the method, the control, the first sample time at
    which a node leaves the contact (None: the area never shrinks and the result is exact), the
    peak and final force against the elastic peak, and under force control the largest
    |relaxed force - prescribed| / force_N (the sampling of the elastic course)."""
    active = np.stack([r.force_N > 0 for r in elastic])
    lost = np.flatnonzero((active[:-1] & ~active[1:]).any(axis=1))
    out = {"method": METHOD, "control": "depth" if exp.force_N is None else "force",
           "contact_shrinks_at_s": float(exp.times_s[lost[0] + 1]) if lost.size else None,
           "peak_force_N": float(force_N.max(initial=0.0)), "final_force_N": float(force_N[-1]),
           "elastic_peak_force_N": max(r.total_force_N for r in elastic)}
    if exp.force_N is not None:
        given = np.array([load.get("force_N", 0.0) for _, load in exp.indentations])
        out["force_deviation"] = float(np.abs(force_N - given).max() / exp.force_N)
    return out
