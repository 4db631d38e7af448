"""Afferent populations over the pad of a 3D finger, driven by its finite-element mechanics.

Afferents of each class sit below sites drawn uniformly over the pad's surface (at the class's
density per cm^2 and depth, `fem.receptors.transduction`), or below given points; a site lies
anywhere on a surface facet, its values interpolated from the facet's nodes. At every sample
time of a traced experiment (`fem.experiments.traces`) each afferent receives
- the static input: the normal stress across the plane parallel to the skin at its site,
  -n.sigma.n with n the surface normal above it (compression positive; in MPa), the quantity the
  published model takes from Sneddon's half-space solution, or optionally the strain energy
  density (the thesis's candidate; the published parameters are fit to stress, so give a gain);
- the dynamic input: E* times the velocity of the surface above it along the approach, over
  depth^2, as the published model's (`fem.receptors.transduction.dynamic_input`), with its constant E* =
  0.0595 MPa (`fem.receptors.transduction.skin_E_star_MPa`: its weights were fit with it), so that the
  finger's kinematics, not its moduli, set this input;
and `fem.receptors.transduction` turns both into spike trains.

    pop = place(model, surface, ("SA1", "RA", "PC"), seed=0)
    static, deflection = experiment_inputs(sampler_of(model, pop), pop, contact, run)   # (n, k) per step
    resp = respond(pop, run.experiment.times_s, static, deflection)
    resp.spikes, resp.rates_hz(0.1, 0.6)

A scene's afferents (`fem.experiments.spiking.scene_responses`) take their 5 kHz inputs from a
LoadTable of the experiment's load instead of from the samples linear in time.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fem.contact.facets import fe_facets, midside_edges
from fem.io.modelfolder import CONTACT_REGION, pad_nodes
from fem.receptors.grid import ReceptorGrid, ReceptorSampler
from fem.receptors.transduction import (
    class_data,
    dynamic_input,
    lif_times,
    rates_hz,
    resample,
    skin_E_star_MPa,
    spike_trains,
)
from fingertip.errors import InputError

MAX_SITE_DISTANCE_MM = 1.0
"""An explicit afferent site may lie at most this far from the pad surface it is projected onto."""


@dataclass(frozen=True)
class Population:
    """n afferents: afferent_class (n,) names, model_index (n,) row of the class's parameter table,
    site_mm (n, 3) the point of the skin surface above each, normal (n, 3) the outward unit normal
    there, depth_mm (n,) below it; candidate (n, c) the contact candidates
    (fem.core.model.SurfaceNodes rows) whose values weights (n, c) interpolate to the site (the
    quadratic shape functions of its surface facet), or candidate (n,) with weights None: the site
    is that candidate's node."""
    afferent_class: np.ndarray
    model_index: np.ndarray
    candidate: np.ndarray
    site_mm: np.ndarray
    normal: np.ndarray
    depth_mm: np.ndarray
    weights: np.ndarray | None = None

    def __len__(self) -> int:
        return len(self.depth_mm)

    @property
    def points_mm(self) -> np.ndarray:
        """(n, 3) afferent positions: depth_mm below the site along the inward normal."""
        return self.site_mm - self.depth_mm[:, None] * self.normal

    def at_sites(self, values) -> np.ndarray:
        """(n, ...) a field given at the contact candidates (m, ...) (e.g. the surface deflection)
        at the afferents' sites."""
        v = np.asarray(values)[self.candidate]
        return v if self.weights is None else np.einsum("nc,nc...->n...", self.weights, v)


def pad_facets(model, surface, centre_mm=None, radius_mm=None) -> tuple[np.ndarray, np.ndarray]:
    """(facets (k, 6) candidate indices: the vertices, then the midside nodes of edges 01, 12 and
    02 (`fem.contact.facets.EDGES`); area_mm2 (k,)) of the pad's surface facets (every vertex a `pad_nodes` node; with radius_mm,
    centroid within radius_mm of centre_mm (3,))."""
    facets, shares = fe_facets(model, CONTACT_REGION[3], surface)
    x = surface.x
    if facets.shape[1] == 6:          # midside nodes in the order of the edges
        order = np.argsort(midside_edges(facets, x), axis=1)
        facets = np.c_[facets[:, :3], np.take_along_axis(facets[:, 3:], order, axis=1)]
    ok = pad_nodes(model, surface)[facets[:, :3]].all(axis=1)
    if radius_mm is not None:
        ok &= np.linalg.norm(x[facets[:, :3]].mean(axis=1) - np.asarray(centre_mm, float), axis=1) <= radius_mm
    return facets[ok], shares[ok].sum(axis=1)


def _shape(lam, nodes: int) -> np.ndarray:
    """(n, nodes) shape functions of a linear (3) or quadratic (6) triangle at barycentric lam (n, 3)."""
    if nodes == 3:
        return lam
    l0, l1, l2 = lam.T
    return np.c_[lam * (2 * lam - 1), 4 * l0 * l1, 4 * l1 * l2, 4 * l0 * l2]


def _sites(surface, facets, face, lam) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(candidate (n, c), weights (n, c), site_mm (n, 3), normal (n, 3)) of points at barycentric
    lam (n, 3) on the facets face (n,): the point on the flat facet, the vertex normals
    interpolated and normalised."""
    verts = facets[face, :3]
    site = np.einsum("ni,nij->nj", lam, surface.x[verts])
    normal = np.einsum("ni,nij->nj", lam, surface.normal[verts])
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    return facets[face], _shape(lam, facets.shape[1]), site, normal


def place(model, surface, classes=("SA1", "RA"), density_per_cm2=None, centre_mm=None, radius_mm=None,
          seed: int = 0, sites_mm=None) -> Population:
    """A population over the pad of a 3D model. surface: the contact region's
    fem.core.model.SurfaceNodes. By density: for each class, round(density x pad area) sites drawn
    uniformly over the pad's surface (a facet with probability proportional to its area, a uniform
    point on it; seeded); density_per_cm2 {class: density} overrides the published fingertip
    densities; centre_mm (3,), radius_mm: only the pad within radius_mm of centre_mm. Or at
    sites_mm (k, 3): one afferent of each class at each point, projected onto the pad (at most
    MAX_SITE_DISTANCE_MM away). Each afferent gets one of its class's published models at random."""
    if model.dim != 3:
        raise InputError("afferents lie over a pad: they need a 3D model (a 2D section has no pad area)")
    rng = np.random.default_rng(seed)
    facets, area = pad_facets(model, surface, centre_mm, None if sites_mm is not None else radius_mm)
    if not len(facets):
        raise InputError(f"no pad surface within {radius_mm} mm of {np.round(centre_mm, 2).tolist()} mm: "
                         f"widen radius_mm")
    if sites_mm is not None:
        face, lam = _projected(surface, facets, np.asarray(sites_mm, float).reshape(-1, 3))
        names = np.repeat(np.asarray(classes, dtype=object), len(face))
        face, lam = np.tile(face, len(classes)), np.tile(lam, (len(classes), 1))
    else:
        dens, area_cm2 = dict(density_per_cm2 or {}), float(area.sum()) / 100.0
        counts = [round(dens.get(name, class_data(name).density_per_cm2) * area_cm2) for name in classes]
        names = np.repeat(np.asarray(classes, dtype=object), counts)
        face = rng.choice(len(facets), size=len(names), p=area / area.sum())
        r = np.sqrt(rng.random(len(names)))
        u = rng.random(len(names))
        lam = np.c_[1 - r, r * (1 - u), r * u]
    model_index = np.array([rng.integers(len(class_data(name).parameters)) for name in names], int)
    depth = np.array([class_data(name).depth_mm for name in names], float)
    cand, weights, site, normal = _sites(surface, facets, face, lam)
    return Population(names, model_index, cand, site, normal, depth, weights)


def _projected(surface, facets, points) -> tuple[np.ndarray, np.ndarray]:
    """(face (k,), barycentric (k, 3)) of the points of the pad's flat facets closest to points (k, 3)."""
    from trimesh.triangles import closest_point, points_to_barycentric

    tri = surface.x[facets[:, :3]]                                   # (f, 3, 3)
    face, closest = np.empty(len(points), int), np.empty((len(points), 3))
    for i, p in enumerate(points):                                   # every facet against each point
        c = closest_point(tri, np.broadcast_to(p, (len(tri), 3)))
        face[i] = np.argmin(np.linalg.norm(c - p, axis=1))
        closest[i] = c[face[i]]
    distance = np.linalg.norm(closest - points, axis=1)
    far = np.flatnonzero(distance > MAX_SITE_DISTANCE_MM)
    if far.size:
        raise InputError(f"afferent site {np.round(points[far[0]], 3).tolist()} mm is {distance[far[0]]:.2f} mm from "
                         f"the pad surface (at most {MAX_SITE_DISTANCE_MM:g} mm): give points on the pad (the "
                         f"run's <experiment>_surface.csv lists its nodes)")
    lam = np.clip(points_to_barycentric(tri[face], closest), 0.0, 1.0)
    return face, lam / lam.sum(axis=1, keepdims=True)


def sampler_of(model, population: Population):
    """fem.receptors.grid.ReceptorSampler at the afferents (one point each, in their order)."""
    n = len(population)
    return ReceptorSampler(model, ReceptorGrid(population.points_mm, population.depth_mm, np.arange(n),
                                               population.site_mm))


def site_inputs(sampler, population: Population, compliance, forces_N, measure: str = "stress") -> np.ndarray:
    """(n, k) static input at each afferent (`sampler_of`) for k nodal contact force vectors
    forces_N (m, k) [N] along the compliance's approach: 'stress' -n.sigma.n [MPa] (compression
    positive) or 'sed' [MPa]. The displacement fields come from one solve with k right-hand sides
    on the compliance's factors."""
    values = sampler.operator @ compliance.displacement(np.asarray(forces_N, float).reshape(len(forces_N), -1))
    out = np.empty((len(population), values.shape[1]))
    for j in range(values.shape[1]):
        out[:, j] = static_input(sampler, population, values[:, j], measure)
    return out


def static_input(sampler, population: Population, values, measure: str = "stress") -> np.ndarray:
    """(n,) static input at each afferent from one output `values` of its sampler (`sampler_of`,
    or its `with_energy` for a finite state): 'stress' -n.sigma.n [MPa] (compression positive) or
    'sed' [MPa]."""
    if measure == "sed":
        return sampler.measures(values, ["sed_MPa"])["sed_MPa"]
    stress = sampler.state(values).stress
    return -np.einsum("ni,nij,nj->n", population.normal, stress, population.normal)


def experiment_inputs(sampler, population: Population, contact, run, measure: str = "stress"):
    """(static (n, k), deflection_mm (n, k)) of a population at the k steps of an experiment run
    (fem.experiments.runner.ExperimentRun) on its contact model: the static input (`site_inputs`) of each
    distinct contact result once (a hold repeats one), and the surface deflection above each afferent."""
    unique = list({id(r): r for _, r in run.steps}.values())
    column = {id(r): j for j, r in enumerate(unique)}
    static = site_inputs(sampler, population, contact.compliance(run.indentor.approach),
                         np.stack([r.force_N for r in unique], axis=1), measure)
    deflection = np.stack([population.at_sites(r.deflection_mm) for _, r in run.steps], axis=1)
    return static[:, [column[id(r)] for _, r in run.steps]], deflection


@dataclass(frozen=True)
class LoadTable:
    """Afferent inputs of an elastic indentation that depends on its load alone (no sweep), at
    increasing loads: load (m,) depth [mm] or force [N], static (n, m) [MPa], deflection_mm (n, m)
    of the surface above each afferent. Linear contact does not depend on the path, so a course
    of that load at any times has the inputs `at` its loads (`fem.experiments.spiking.tabulate`
    chooses the loads)."""
    load: np.ndarray
    static: np.ndarray
    deflection_mm: np.ndarray

    def at(self, load) -> tuple[np.ndarray, np.ndarray]:
        """(static (n, T), deflection_mm (n, T)) at loads (T,), linear between the table's (held
        beyond its ends)."""
        x = np.clip(np.asarray(load, float), self.load[0], self.load[-1])
        if len(self.load) == 1:
            return np.repeat(self.static, x.size, axis=1), np.repeat(self.deflection_mm, x.size, axis=1)
        k = np.clip(np.searchsorted(self.load, x, side="right") - 1, 0, len(self.load) - 2)
        w = (x - self.load[k]) / (self.load[k + 1] - self.load[k])
        return ((1.0 - w) * self.static[:, k] + w * self.static[:, k + 1],
                (1.0 - w) * self.deflection_mm[:, k] + w * self.deflection_mm[:, k + 1])


@dataclass
class PopulationResponse:
    """Spike trains of a population through a time course: times_s (k,) sample times, static
    (n, k) input [MPa], deflection_mm (n, k) of the surface above each afferent, spikes: n arrays
    of spike times [s]; table_loads: the loads of the LoadTable the 5 kHz inputs were read from
    (None: the samples, linear in time)."""
    population: Population
    times_s: np.ndarray
    static: np.ndarray
    deflection_mm: np.ndarray
    spikes: list
    table_loads: int | None = None

    @property
    def duration_s(self) -> float:
        return float(self.times_s[-1])

    def rates_hz(self, t0_s: float = 0.0, t1_s: float | None = None) -> np.ndarray:
        """(n,) mean firing rate of each afferent between t0_s and t1_s (default: the end)."""
        return rates_hz(self.spikes, t0_s, self.duration_s if t1_s is None else t1_s)


def respond(population: Population, times_s, static, deflection_mm, gain: float = 1.0, noisy: bool = True,
            seed: int = 0, E_star_MPa: float | None = None, fine=None, law=None) -> PopulationResponse:
    """Spike trains of the population through a course sampled at times_s (k,): static (n, k)
    [MPa, times gain] and the surface deflection above each afferent (n, k) [mm].

    The transduction runs at 5 kHz (`fem.receptors.transduction.LIF_RATE_HZ`) on inputs there:
    fine = (static (n, T), deflection_mm (n, T)) at times arange(T) / 5000 s, T = floor(duration
    x 5000) (e.g. a LoadTable `at` the course's loads), or, without it, the samples linear in
    time in between. The dynamic input is E* (E_star_MPa, default the published model's
    `fem.receptors.transduction.skin_E_star_MPa`) times the deflection's velocity at 5 kHz by
    central differences, as the published model computes it from its 5 kHz stimulus.
    law: a `fem.core.viscoelastic.Prony` whose hereditary integral relaxes the (elastic) static
    input at 5 kHz; the response's static (n, k) is then the relaxed input at the sample times."""
    t = np.asarray(times_s, float)
    static, deflection_mm = np.asarray(static, float), np.asarray(deflection_mm, float)
    if fine is None:
        t5, s5 = resample(t, static)
        _, w5 = resample(t, deflection_mm)
    else:
        t5 = lif_times(t[-1])
        s5, w5 = (np.asarray(v, float) for v in fine)
        if s5.shape != w5.shape or s5.shape[-1] != t5.size:
            raise InputError(f"fine inputs {s5.shape}, {w5.shape} must have one column per 5 kHz sample ({t5.size})")
    if law is not None:
        s5 = law.relax(t5, s5.T).T
        static = np.stack([np.interp(t, t5, row) for row in s5]) if len(s5) else static
    dyn = dynamic_input(t5, w5, population.depth_mm, skin_E_star_MPa() if E_star_MPa is None else E_star_MPa)
    spikes = spike_trains(population.afferent_class, population.model_index, gain * s5, dyn, noisy=noisy, seed=seed)
    return PopulationResponse(population, t, static, deflection_mm, spikes)
