"""Viscoelastic layers with their own spectra, stepped in time (fem.experiments.stepping): two
standard linear solids in series against their closed forms (relaxation and creep), one law in
every layer against the correspondence principle, and the [viscoelastic] layers table."""
import dataclasses

import numpy as np
import pytest

from fem.core.model import Model
from fem.core.viscoelastic import LayerLaws, Prony
from fem.experiments.runner import run_experiments, split_laws
from fem.experiments.scene import Scene
from fem.experiments.spiking import stepped_inputs
from fem.experiments.stepping import stepped_course
from fem.io.modelfolder import read_model
from fem.receptors.afferents import place, sampler_of, site_inputs
from fem.verify.closed_forms import box, series_sls_creep, series_sls_relaxation
from fingertip.errors import InputError

WIDTH_MM, TOP_MM, BOTTOM_MM = 4.0, 1.0, 3.0
E_MPA, G_INF, TAU_S = (0.05, 0.01), (0.3, 0.7), (0.02, 0.5)
LAYERS = {"g": [0.1], "tau_s": [1.0],             # the default law, for no layer of the block
          "layers": {"1": {"g": [1 - G_INF[0]], "tau_s": [TAU_S[0]]}, "2": {"g": [1 - G_INF[1]], "tau_s": [TAU_S[1]]}}}


def two_layer_block() -> Model:
    """2D plane-strain block, WIDTH_MM wide: layer 1 (TOP_MM) over layer 2 (BOTTOM_MM), nu = 0, bottom
    fixed: a frictionless plate compresses each layer uniformly (uniaxial strain, same stress),
    which P2 represents exactly."""
    ys = np.r_[np.linspace(-TOP_MM - BOTTOM_MM, -TOP_MM, 7), np.linspace(-TOP_MM, 0.0, 3)[1:]]
    p, cells, r = box(np.linspace(-WIDTH_MM / 2, WIDTH_MM / 2, 5), ys)
    layer = np.where(p[cells][:, :, 1].mean(axis=1) > -TOP_MM, 1, 2)
    return Model(p, cells, layer, {"surface": r["ymax"], "fixed": r["ymin"]}, material=list(E_MPA), nu=0.0)


def course(e):
    return (e.experiment.times_s, np.array([r.total_force_N for _, r in e.steps]),
            np.array([r.depth_mm.max() for _, r in e.steps]))


def test_two_layers_in_series_relax_and_creep_as_their_closed_forms():
    """A step of 0.1 mm (relaxation) and of 2 mN/mm (creep) at t = 0, held 1 s, 161 samples, the
    layers' relaxation times 0.02 and 0.5 s. Measured: force within 0.01 % of the closed form of
    the two SLS in series (0.14 % at 41 samples: second order in the step), depth within 0.01 %."""
    step = {"shape": "table", "times_s": [0.0, 1.0], "levels": [1.0, 1.0], "samples": 161}
    scene = Scene.from_dict({"viscoelastic": LAYERS, "experiment": [
        {"name": "relax", "indentor": "plate", "depth_mm": 0.1, "trace": step},
        {"name": "creep", "indentor": "plate", "force_N": 0.002, "trace": step}]})
    relax, creep = run_experiments(two_layer_block(), {}, scene).experiments
    t, force, _ = course(relax)
    closed = series_sls_relaxation(t, [TOP_MM, BOTTOM_MM], E_MPA, G_INF, TAU_S) * 0.1 * WIDTH_MM
    assert np.abs(force / closed - 1).max() < 1e-3
    assert force[-1] < 0.7 * force[0]                                   # it relaxes
    t, force, depth = course(creep)
    closed = series_sls_creep(t, [TOP_MM, BOTTOM_MM], E_MPA, G_INF, TAU_S) * 0.002 / WIDTH_MM
    assert np.abs(force / 0.002 - 1).max() < 1e-6
    assert np.abs(depth / closed - 1).max() < 1e-3 and depth[-1] > 1.3 * depth[0]
    assert relax.viscoelastic["method"].startswith("time stepping") and relax.stepped is not None


def test_one_law_stepped_is_the_correspondence_principle_and_releases_without_tension(section):
    """The five-layer 2D monkey section, a 2 mm bar 0.5 mm deep (ramp 0.1 s, hold 0.5 s, release
    0.1 s, 40 samples), every layer g = 0.2, 0.2, 0.2: stepped in time, the forces and receptor
    stresses of the ramp and the hold equal the correspondence principle's to the contact
    solver's tolerance (measured on the 3D monkey at 1 mm: 1e-13, at 1.5 mm: 7e-7, a node at the
    contact's edge); in the release the correspondence principle's force turns tensile, the
    stepped one stays >= 0 (the contact lets go)."""
    scene = Scene.from_dict({"viscoelastic": {"g": [0.2, 0.2, 0.2]},
                             "experiment": [{"indentor": "bar:2", "depth_mm": 0.5,
                                             "trace": {"shape": "ramp_hold", "samples": 40}}]})
    model, info = read_model(section, scene.material)
    corr = run_experiments(model, info, scene)
    e = corr.experiments[0]
    steps, record, _ = stepped_course(model, info, dataclasses.replace(e, steps=[]), LayerLaws(scene.viscoelastic),
                                      corr.sampler, corr.surface.nodes)
    t = e.experiment.times_s
    f_c, f_s = (np.array([r.total_force_N for _, r in s]) for s in (e.steps, steps))
    loaded = t <= 0.6 + 1e-12
    assert np.abs(f_s[loaded] - f_c[loaded]).max() <= 1e-5 * f_c.max()
    obs = [np.stack([r.observed for _, r in s])[loaded] for s in (e.steps, steps)]
    assert np.abs(obs[1] - obs[0]).max() <= 1e-5 * np.abs(obs[0]).max()
    assert f_c.min() < -0.1 * f_c.max() and f_s.min() >= -1e-12


def test_layers_table_and_its_refusals():
    law = Scene.from_dict({"viscoelastic": {"g": [0.2], "tau_s": [0.1], "layers": {"1": {"g": [0.5], "tau_s": [0.01]},
                                                                          "5": "elastic"}},
                           "experiment": [{"indentor": "plate", "depth_mm": 0.1, "trace": {}}]}).viscoelastic
    assert isinstance(law, LayerLaws) and law.law(5) is None and law.law(1) == Prony((0.5,), (0.01,))
    assert law.law(3) == Prony((0.2,), (0.1,))
    assert [ids for _, ids in law.groups([1, 2, 3, 4, 5])] == [(1,), (2, 3, 4), (5,)]
    block = two_layer_block()
    shared = LayerLaws(Prony((0.2,), (0.1,)), ((1, Prony((0.2,), (0.1,))),))
    assert split_laws(shared, block) == (Prony((0.2,), (0.1,)), None)
    assert split_laws(law, block)[1] is law
    for bad in ({"layers": {"skin": {"g": [0.5], "tau_s": [0.1]}}}, {"layers": {"1": {"tau_s": [0.1]}}},
                {"layers": {"1": "plastic"}}, {"layers": []}):
        bad = {"g": [0.2], "tau_s": [0.1], **bad}
        with pytest.raises(InputError):
            Scene.from_dict({"viscoelastic": bad, "experiment": [{"indentor": "plate", "depth_mm": 0.1, "trace": {}}]})


def test_afferent_inputs_of_a_stepped_course(shop):
    """Afferents under a course stepped in time (`fem.experiments.spiking.stepped_inputs`: each layer
    group's stress at the afferents relaxed by its law): with one law in every layer they are the
    correspondence principle's, the elastic inputs relaxed (coarse monkey, a 2 mm probe 1 mm deep,
    20 samples through the ramp and the hold; measured 6e-5 of the largest input: a node at the
    contact's edge, as the forces' 7e-7), until the instant release at the last sample."""
    scene = Scene.from_dict({"material": [0.314, 0.0314, 0.0314, 0.0314, 100.0], "viscoelastic": {"g": [0.2, 0.2, 0.2]},
                             "experiment": [{"indentor": "punch:2", "depth_mm": 1.0, "trace": {
                                 "shape": "ramp_hold", "release_s": 0.0, "samples": 20}}]})
    model, info = read_model(shop.preset("monkey", 1.5), scene.material)
    corr = run_experiments(model, info, scene)
    e = corr.experiments[0]
    points = corr.contact.points_mm
    pop = place(model, corr.surface, ("SA1", "RA"), None, points[np.argmin(e.indentor.standoff(points))], 3.0, 0)
    steps, _, stepped = stepped_course(model, info, dataclasses.replace(e, steps=[]), LayerLaws(scene.viscoelastic),
                                       corr.sampler, corr.surface.nodes)
    run = dataclasses.replace(e, steps=steps, stepped=stepped)
    got = stepped_inputs(model, pop, run, sampler_of(model, pop))
    elastic = site_inputs(sampler_of(model, pop), pop, corr.contact.compliance(e.indentor.approach),
                          np.stack([r.elastic_force_N for _, r in e.steps], axis=1))
    want = scene.viscoelastic.relax(e.experiment.times_s, elastic.T).T
    loaded = e.experiment.times_s < 0.6 - 1e-12                     # the last sample releases at once
    assert np.abs(got - want)[:, loaded].max() <= 1e-4 * np.abs(want).max() and np.abs(want).max() > 0
