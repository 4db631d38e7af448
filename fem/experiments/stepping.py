"""Time stepping of viscoelastic layers whose relaxation spectra differ (a scene's [viscoelastic]
with `layers`, `fem.core.viscoelastic.LayerLaws`).

Layer L's moduli relax as G0 g_L(t), K0 g_L(t) (nu fixed). The mixed formulation keeps each
layer's pressure to itself, so the stiffness splits into layer groups of one law, K = sum_G K_G,
and the internal force of a displacement history is a sum of hereditary integrals,

    f_int(t) = sum_G int g_G(t - s) d(K_G u)(s).

With the exponential integrator of `fem.core.viscoelastic.StepHistory` (the input linear over a
step) each sample time is one elastic contact problem with a history load r_n:

    K_a u_{n+1} + r_n = f_contact,    K_a = sum_G alpha_G(dt) K_G,    r_n = sum_G rest_G(dt).

K_a of the most common step dt* is the stiffness of the model with moduli alpha_G(dt*) E_L: it is
factorised once (candidates condensed as a scene's run does) and every step reuses it; steps of
another length move (K_a - K_a*) u to the right-hand side and iterate (defect correction, to
CORRECTION_TOL). The history load enters the contact problem as a preload of the candidates
(`fem.contact.linear.ContactModel.preload_mm`). Receptor stresses are the hereditary integrals of
each group's elastic stress at the points. Unlike the correspondence principle
(`fem.experiments.viscoelastic`) this holds when the contact shrinks (a release, a scan).

    steps, record, stepped = stepped_course(model, info, run, laws, sampler, candidates)
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from fem.contact.linear import ContactModel
from fem.core.materials import FLUID_LAYER, Material
from fem.core.viscoelastic import StepHistory
from fem.io.modelfolder import CONTACT_REGION, factorise
from fingertip.errors import InputError

METHOD = ("time stepping (a relaxation function per layer; exponential integrator, the input linear over each "
          "step; one factorisation at the most common step, defect correction for the others)")
"""How run.json describes the method of a stepped viscoelastic experiment."""
CORRECTION_TOL = 1e-9
"""Relative change of the displacement at which a step's defect correction stops."""
MAX_CORRECTIONS = 60
MAX_PRELOAD_COLUMNS = 512
"""Up to this many candidates in reach, their preload comes from precomputed columns K_a*^-1 B
(one multi-column solve) instead of a solve per step."""


@dataclass
class Stepped:
    """What a stepped course leaves for its afferents and files: the layer groups [(law, layers,
    group model: the layers of the group at twice their moduli)] and the displacement (ndof, k)
    [mm] at the k sample times."""
    groups: list
    displacement_mm: np.ndarray

    def group_values(self, model, operator_of) -> list:
        """[(law, values (r, k))] of a linear operator of the elastic fields at the sample times,
        per group (`group_operators`)."""
        return [(law, op @ self.displacement_mm)
                for (law, _, _), op in zip(self.groups, group_operators(model, self.groups, operator_of))]


def group_operators(model, groups, operator_of) -> list:
    """[sparse (r, ndof)] each group's part of a linear operator of the elastic fields:
    operator_of(model) -> sparse (r, ndof) (e.g. a stress operator), the group's part the
    difference between its model (its layers at twice their moduli) and the base `model`."""
    base = operator_of(model)
    return [(operator_of(m) - base).tocsr() for _, _, m in groups]


def _scaled(model, scale: dict):
    """The model with layer k's modulus times scale[k] (1 for the layers not named), nu as it is."""
    mat = model.material
    return model.with_material(Material({k: v * scale.get(k, 1.0) for k, v in mat.E_MPa.items()}, dict(mat.nu),
                                        rigid=mat.rigid))


def group_models(model, laws) -> list:
    """[(law, layers, model with those layers' moduli doubled)] per group of one law."""
    layers = np.unique(model.layer)
    if FLUID_LAYER in layers:
        raise InputError("[viscoelastic] layers with their own spectra: this model has a fluid core, which has "
                         "no shear modulus to relax; give every layer the same law")
    return [(law, ids, _scaled(model, dict.fromkeys(ids, 2.0))) for law, ids in laws.groups(layers)]


def _finished(where: str, indentor, cm, comp, res, u, observed):
    """A step's ContactResult with the deflection and gaps of its displacement u (ndof,) and its
    receptor values `observed`; InputError when the skin touches outside the candidates in reach."""
    deflection = comp.B.T @ u
    standoff = indentor.part_standoff(cm.points_mm) - res.travel_mm
    gap = standoff[np.arange(len(standoff)), res.part] + deflection
    if np.nanmin(gap) < -cm.tol_mm:           # only the candidates in reach were preloaded and solved for
        raise InputError(f"{where}: the skin touches the indentor outside the candidates condensed when the model "
                         f"was factorised: give the scene a larger depth range or reach margin "
                         f"(fem.contact.linear.reach)")
    return dataclasses.replace(res, kkt=dict(res.kkt), _gap_mm=gap, _deflection_mm=deflection, _observed=observed,
                               _source=None, _unseen=None)


def stepped_course(model, info, run, laws, sampler, candidates, progress=None):
    """([(offset, ContactResult)] one per sample time, run.json record, Stepped) of a traced
    experiment (fem.experiments.runner.ExperimentRun without steps) under per-layer laws
    (fem.core.viscoelastic.LayerLaws); sampler: the scene's fem.receptors.grid.ReceptorSampler
    (its stress block becomes the viscoelastic stress); candidates: P2 node ids to condense."""
    exp = run.experiment
    times = np.asarray(exp.times_s, float)
    dts = np.diff(times)
    groups = group_models(model, laws)
    histories = [StepHistory(law, model.ndof) for law, _, _ in groups]
    lengths, counts = np.unique(np.round(dts[dts > 0], 12), return_counts=True)
    dt_star = float(lengths[np.argmax(counts)]) if lengths.size else 0.0
    alpha_star = [h.alpha(dt_star) for h in histories]
    star = _scaled(model, {layer: a for a, (_, ids, _) in zip(alpha_star, groups) for layer in ids})
    system = factorise(star, info, candidates, progress)
    cm = ContactModel.from_fe(star, system, CONTACT_REGION[model.dim])
    comp = cm.compliance(run.indentor.approach)
    reach = np.flatnonzero(comp.reach)
    # the preload of the candidates that can touch: Z^T r with Z = K_a*^-1 B (one solve, r columns)
    Z = system.solve(np.asfortranarray(comp.B[:, reach].toarray())) if len(reach) <= MAX_PRELOAD_COLUMNS else None
    relaxing = [g for g, (law, _, _) in enumerate(groups) if law is not None]

    def group_forces(u) -> dict:
        """{group index: K_G u} of the relaxing groups (the model's K applied once)."""
        Ku = model.K @ u
        return {g: groups[g][2].K @ u - Ku for g in relaxing}

    stress = sampler.stress_rows
    stress_ops = group_operators(model, groups, lambda m: m.stress_operator(sampler.points_mm))
    stress_hist = [StepHistory(law, stress_ops[0].shape[0]) for law, _, _ in groups]

    u = np.zeros(model.ndof)
    steps, U, corrections = [], np.empty((model.ndof, len(times))), 0
    for k, (off, load) in enumerate(exp.indentations):
        dt = float(dts[k - 1]) if k else 0.0
        differs = abs(dt - dt_star) > 1e-9 * dt_star      # a step of another length: correct for it
        alpha = [h.alpha(dt) for h in histories] if differs else alpha_star
        rest = sum(h.rest(dt) for h in histories)
        indentor = run.indentor.shifted(off) if exp.sweep is not None else run.indentor
        for _ in range(MAX_CORRECTIONS):
            other = rest
            if differs:
                other = other + sum((alpha[g] - alpha_star[g]) * Kg for g, Kg in group_forces(u).items())
            if Z is None:
                preload = comp.B.T @ -system.solve(other)
            else:
                preload = np.zeros(comp.m)
                preload[reach] = -(Z.T @ other)
            cm.preload_mm = preload
            cm.restart()
            res = cm.indent(indentor, **load)
            cm.discard_pending()
            u_new = system.solve(comp.B @ res.force_N - other)
            change = np.linalg.norm(u_new - u) / max(np.linalg.norm(u_new), 1e-300)
            u = u_new
            if not differs or change <= CORRECTION_TOL:
                break
            corrections += 1
        else:
            raise InputError(f"experiment '{exp.name}': the viscoelastic step at t = {times[k]:g} s did not converge "
                             f"in {MAX_CORRECTIONS} corrections (a step much longer or shorter than the others): "
                             f"sample the course evenly")
        for g, Kg in group_forces(u).items():
            histories[g].advance(dt, Kg)
        sigma = sum(h.advance(dt, S @ u) for h, S in zip(stress_hist, stress_ops))
        observed = sampler.operator @ u
        observed[stress] = sigma
        steps.append((off, _finished(f"experiment '{exp.name}' at t = {times[k]:g} s", indentor, cm, comp, res, u,
                                     observed)))
        U[:, k] = u
    cm.preload_mm = None
    force = np.array([r.total_force_N for _, r in steps])
    record = {"method": METHOD, "control": "depth" if exp.force_N is None else "force", "laws": laws.record(),
              "factorised_step_s": dt_star, "corrections": corrections,
              "peak_force_N": float(force.max(initial=0.0)), "final_force_N": float(force[-1])}
    return steps, record, Stepped(groups, U)
