"""A scene's afferents through its traced experiments (fem.experiments.spiking): inputs tabulated over
the load and read at the course's load at 5 kHz."""
import numpy as np
import pytest

from fem.experiments.runner import run_experiments
from fem.experiments.scene import Scene, load_scene
from fem.experiments.spiking import TABLE_TOLERANCE, fine_loads, load_value, tabulate
from fem.io.modelfolder import read_model
from fem.receptors.afferents import LoadTable, Population, place, respond, sampler_of, site_inputs
from fem.receptors.transduction import CLASSES, class_data, dynamic_input, skin_E_star_MPa, spike_trains
from tests.helpers import ROOT


def _flat_population() -> Population:
    """Every published model of every class at the centre of a flat pin (the half-space's axis)."""
    cls = [c for c in CLASSES for _ in class_data(c).parameters]
    idx = [k for c in CLASSES for k in range(len(class_data(c).parameters))]
    n = len(cls)
    return Population(np.array(cls, dtype=object), np.array(idx), np.zeros(n, int), np.zeros((n, 3)),
                      np.tile([0.0, 0.0, 1.0], (n, 1)), np.array([class_data(c).depth_mm for c in cls]))


def test_load_table_course_is_the_closed_form_course_at_5_khz():
    """An offset 40 Hz sine (0.5 mm held, 0.6 mm peak to peak, 1 s) on mechanics linear in the
    depth (stress and deflection proportional to it, as a flat pin on a half-space): the spikes
    through the load table at 8 samples per period are those of the course written out at 5 kHz
    by hand (every class, noise off): the sample count sets the output tables' rows, not the
    spikes (against the published model itself: benchmarks/touchsim_compare.py)."""
    pop = _flat_population()
    stress, deflection = 0.02 * np.ones(len(pop)), np.ones(len(pop))         # per mm of depth
    exp = Scene.from_dict({"experiment": [{"indentor": "punch:1", "depth_mm": 1.1, "trace": {
        "shape": "sine", "frequency_hz": 40, "cycles": 40, "offset": 0.5 / 1.1, "samples": 321}}]}).experiments[0]
    table = LoadTable(np.array([0.0, 1.1]), np.c_[0 * stress, 1.1 * stress], np.c_[0 * deflection, 1.1 * deflection])
    samples = table.at([load_value(load) for _, load in exp.indentations])
    tabled = respond(pop, exp.times_s, *samples, noisy=False, fine=table.at(fine_loads(exp)))

    t = np.arange(5000) / 5000.0
    depth = 0.5 + 0.3 * (1 - np.cos(2 * np.pi * 40 * t))
    dyn = dynamic_input(t, np.outer(deflection, depth), pop.depth_mm, skin_E_star_MPa())
    by_hand = spike_trains(pop.afferent_class, pop.model_index, np.outer(stress, depth), dyn)
    assert sum(len(s) for s in by_hand) > 1000
    assert all(np.allclose(a, b, rtol=0, atol=1e-12) for a, b in zip(tabled.spikes, by_hand))


@pytest.fixture(scope="module")
def sphere_run(shop):
    """A 3 mm sphere pressed 1 mm into the monkey pad (ramp and hold, 30 samples), with SA1, RA and
    PC within 4 mm of where it touches (the shipped afferent scene's material)."""
    model, info = read_model(shop.preset("monkey"), load_scene(ROOT / "scenes" / "ramp_hold.toml").material)
    run = run_experiments(model, info, Scene.from_dict({"experiment": [
        {"indentor": "sphere:3", "depth_mm": 1.0, "trace": {"shape": "ramp_hold", "samples": 30}}]}))
    points = run.contact.points_mm
    e = run.experiments[0]
    pop = place(model, run.surface, CLASSES, None, points[np.argmin(e.indentor.standoff(points))], 4.0, 0)
    return model, run, pop


def test_tabulated_inputs_within_tolerance_of_direct_solves(sphere_run):
    """A sphere's inputs are not linear in the depth (the contact grows): the table refines its
    loads (more than the course's distinct ones) until linear interpolation is within
    TABLE_TOLERANCE at its midpoints; at depths between its loads (here 0.13, 0.37, 0.61, 0.87 mm)
    it is within twice that of contact problems solved there."""
    model, run, pop = sphere_run
    e = run.experiments[0]
    sampler = sampler_of(model, pop)
    table = tabulate(sampler, pop, run.contact, e)
    distinct = len({round(load_value(load), 12) for _, load in e.experiment.indentations})
    assert len(table.load) > distinct
    depths = np.array([0.13, 0.37, 0.61, 0.87])
    direct = [run.contact.indent(e.indentor, depth_mm=d) for d in depths]
    static = site_inputs(sampler, pop, run.contact.compliance(e.indentor.approach),
                         np.stack([r.force_N for r in direct], axis=1))
    deflection = np.stack([pop.at_sites(r.deflection_mm) for r in direct], axis=1)
    s_tab, w_tab = table.at(depths)
    assert np.abs(s_tab - static).max() <= 2 * TABLE_TOLERANCE * np.abs(table.static).max()
    assert np.abs(w_tab - deflection).max() <= 2 * TABLE_TOLERANCE * np.abs(table.deflection_mm).max()
