"""Afferent populations over the pad of a 3D finger, driven by its finite-element mechanics.

Afferents of each class sit below randomly drawn pad nodes (area-weighted, at the class's density
per cm^2 and depth, `fem.receptors.transduction`), so their surface sites are mesh nodes: positions are
resolved to the mesh's node spacing (about 0.5 mm on a 1 mm mesh). At every sample time of a
traced experiment (`fem.experiments.traces`) each afferent receives
- the static input: the normal stress across the plane parallel to the skin at its site,
  -n.sigma.n with n the surface normal above it (compression positive; in MPa), the quantity the
  published model takes from Sneddon's half-space solution, or optionally the strain energy
  density (the thesis's candidate; the published parameters are fit to stress, so give a gain);
- the dynamic input: E* times the velocity of the surface above it along the approach, over
  depth^2, as the published model's (`fem.receptors.transduction.dynamic_input`), with its constant E* =
  0.0595 MPa (`fem.receptors.transduction.skin_E_star_MPa`: its weights were fit with it), so that the
  finger's kinematics, not its moduli, set this input;
and `fem.receptors.transduction` turns both into spike trains.

    pop = place(model, surface, ("SA1", "RA"), seed=0)
    static, deflection = experiment_inputs(sampler_of(model, pop), pop, contact, run)   # (n, k) per step
    resp = respond(pop, run.experiment.times_s, static, deflection)
    resp.spikes, resp.rates_hz(0.1, 0.6)
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fem.io.modelfolder import pad_nodes
from fem.receptors.grid import ReceptorGrid, ReceptorSampler
from fem.receptors.transduction import (
    class_data,
    dynamic_input,
    rates_hz,
    resample,
    skin_E_star_MPa,
    spike_trains,
)
from fingertip.errors import InputError


@dataclass(frozen=True)
class Population:
    """n afferents: afferent_class (n,) names, model_index (n,) row of the class's parameter table,
    candidate (n,) index of the contact candidate (fem.core.model.SurfaceNodes row) above each,
    site_mm (n, 3) that node, normal (n, 3) its outward unit normal, depth_mm (n,)."""
    afferent_class: np.ndarray
    model_index: np.ndarray
    candidate: np.ndarray
    site_mm: np.ndarray
    normal: np.ndarray
    depth_mm: np.ndarray

    def __len__(self) -> int:
        return len(self.depth_mm)

    @property
    def points_mm(self) -> np.ndarray:
        """(n, 3) afferent positions: depth_mm below the site along the inward normal."""
        return self.site_mm - self.depth_mm[:, None] * self.normal


def place(model, surface, classes=("SA1", "RA"), density_per_cm2=None, centre_mm=None, radius_mm=None,
          seed: int = 0) -> Population:
    """A population over the pad of a 3D model: for each class, round(density x pad area) distinct
    pad nodes drawn with probability proportional to their tributary area (seeded), each given
    one of the class's published models at random. surface: the contact region's
    fem.core.model.SurfaceNodes; density_per_cm2: {class: density} overriding the fingertip densities;
    centre_mm (3,), radius_mm: only the pad within radius_mm of centre_mm."""
    if model.dim != 3:
        raise InputError("afferents lie over a pad: they need a 3D model (a 2D section has no pad area)")
    rng = np.random.default_rng(seed)
    ok = pad_nodes(model, surface)
    if radius_mm is not None:
        ok &= np.linalg.norm(surface.x - np.asarray(centre_mm, float), axis=1) <= radius_mm
    nodes = np.flatnonzero(ok)
    area_cm2 = float(surface.area[nodes].sum()) / 100.0
    if not nodes.size or area_cm2 <= 0:
        raise InputError(f"no pad surface within {radius_mm} mm of {np.round(centre_mm, 2).tolist()} mm: "
                         f"widen radius_mm")
    dens = dict(density_per_cm2 or {})
    parts = []
    for name in classes:
        data = class_data(name)
        count = round(dens.get(name, data.density_per_cm2) * area_cm2)
        if count > nodes.size:
            raise InputError(f"{count} {name} afferents ({dens.get(name, data.density_per_cm2):g}/cm^2 over "
                             f"{area_cm2:.2f} cm^2) exceed the {nodes.size} pad nodes: lower the density or "
                             f"mesh finer")
        picked = rng.choice(nodes, size=count, replace=False, p=surface.area[nodes] / surface.area[nodes].sum())
        parts.append((np.full(count, name), rng.integers(len(data.parameters), size=count), np.sort(picked),
                      np.full(count, data.depth_mm)))
    cls, idx, cand, depth = (np.concatenate([p[k] for p in parts]) for k in range(4))
    return Population(cls.astype(object), idx.astype(int), cand.astype(int), surface.x[cand], surface.normal[cand],
                      depth.astype(float))


def sampler_of(model, population: Population):
    """fem.receptors.grid.ReceptorSampler at the afferents (one point each, in their order)."""
    n = len(population)
    return ReceptorSampler(model, ReceptorGrid(population.points_mm, population.depth_mm, np.arange(n),
                                               population.site_mm))


def site_inputs(sampler, population: Population, compliance, results, measure: str = "stress") -> np.ndarray:
    """(n, k) static input at each afferent (`sampler_of`) for each of k contact results
    (fem.contact.linear.ContactResult) with the compliance's approach: 'stress' -n.sigma.n [MPa]
    (compression positive) or 'sed' [MPa]. The displacement fields come from one solve with k
    right-hand sides on the compliance's factors."""
    values = sampler.operator @ compliance.displacement(np.stack([r.force_N for r in results], axis=1))
    out = np.empty((len(population), len(results)))
    for j in range(len(results)):
        if measure == "sed":
            out[:, j] = sampler.measures(values[:, j], ["sed_MPa"])["sed_MPa"]
        else:
            stress = sampler.state(values[:, j]).stress
            out[:, j] = -np.einsum("ni,nij,nj->n", population.normal, stress, population.normal)
    return out


def experiment_inputs(sampler, population: Population, contact, run, measure: str = "stress"):
    """(static (n, k), deflection_mm (n, k)) of a population at the k steps of an experiment run
    (fem.experiments.runner.ExperimentRun) on its contact model: the static input (`site_inputs`) of each
    distinct contact result once (a hold repeats one), and the surface deflection above each afferent."""
    unique = list({id(r): r for _, r in run.steps}.values())
    column = {id(r): j for j, r in enumerate(unique)}
    static = site_inputs(sampler, population, contact.compliance(run.indentor.approach), unique, measure)
    deflection = np.stack([r.deflection_mm[population.candidate] for _, r in run.steps], axis=1)
    return static[:, [column[id(r)] for _, r in run.steps]], deflection


@dataclass
class PopulationResponse:
    """Spike trains of a population through a time course: times_s (k,) sample times, static
    (n, k) input [MPa], deflection_mm (n, k) of the surface above each afferent, spikes: n arrays
    of spike times [s]."""
    population: Population
    times_s: np.ndarray
    static: np.ndarray
    deflection_mm: np.ndarray
    spikes: list

    @property
    def duration_s(self) -> float:
        return float(self.times_s[-1])

    def rates_hz(self, t0_s: float = 0.0, t1_s: float | None = None) -> np.ndarray:
        """(n,) mean firing rate of each afferent between t0_s and t1_s (default: the end)."""
        return rates_hz(self.spikes, t0_s, self.duration_s if t1_s is None else t1_s)


def respond(population: Population, times_s, static, deflection_mm, gain: float = 1.0, noisy: bool = True,
            seed: int = 0, E_star_MPa: float | None = None) -> PopulationResponse:
    """Spike trains of the population from its inputs at the sample times (k,): static (n, k)
    [MPa, times gain] and the surface deflection above each afferent (n, k) [mm], sampled at the
    transduction's 5 kHz (linear in between: quasi-static mechanics). E_star_MPa: the dynamic
    input's modulus (default the published model's, `fem.receptors.transduction.skin_E_star_MPa`)."""
    t = np.asarray(times_s, float)
    static, deflection_mm = np.asarray(static, float), np.asarray(deflection_mm, float)
    dyn = dynamic_input(t, deflection_mm, population.depth_mm, skin_E_star_MPa() if E_star_MPa is None else E_star_MPa)
    _, s5 = resample(t, gain * static)
    _, d5 = resample(t, dyn)
    spikes = spike_trains(population.afferent_class, population.model_index, s5, d5, noisy=noisy, seed=seed)
    return PopulationResponse(population, t, static, deflection_mm, spikes)


def scene_responses(scene_run) -> tuple[Population | None, dict]:
    """(the population, {experiment name: PopulationResponse}) of a fem.experiments.runner.SceneRun
    whose scene has [afferents]: every traced experiment drives the same population (placed
    once); each distinct indentation is observed once. (None, {}) without [afferents]."""
    cfg = scene_run.scene.afferents
    if cfg is None:
        return None, {}
    model = scene_run.model
    first = next(r for r in scene_run.experiments if r.experiment.times_s is not None)
    points = scene_run.contact.points_mm
    centre = points[np.argmin(first.indentor.standoff(points))]        # where the first traced stimulus touches
    pop = place(model, scene_run.surface, cfg.classes, dict(cfg.density_per_cm2 or ()), centre, cfg.radius_mm,
                cfg.seed)
    sampler = sampler_of(model, pop)
    out = {}
    for run in scene_run.experiments:
        times = run.experiment.times_s
        if times is None:
            continue
        static, deflection = experiment_inputs(sampler, pop, scene_run.contact, run, cfg.input)
        out[run.name] = respond(pop, times, static, deflection, cfg.gain, cfg.noisy, cfg.seed)
    return pop, out
