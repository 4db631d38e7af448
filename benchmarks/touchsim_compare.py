#!/usr/bin/env python
"""The project's afferent chain against the published afferent model run from its own code
(TouchSim, github.com/hsaal/touchsim), on the published model's flat skin: a flat pin pressed into
its elastic half-space (E = 0.05 MPa, nu = 0.4; Sneddon's flat punch, the mechanics both use).

TouchSim generates the stimulus (`stim_sine`: an offset sine, pre_indent + amp (1 - cos 2 pi f t),
at 5 kHz) and drives every published model of each class (SA1 4, RA 9, PC 4; noise off) at the
pin's centre and 2 mm from it. The project runs the same course as a scene trace (`sine` with
`offset`, sampled at the minimum of 8 samples per period), the half-space's inputs tabulated over
the depth (`fem.receptors.afferents.LoadTable`; exact for a flat punch: its mechanics is linear in
the depth) and read at the course's depth at 5 kHz, as a scene's afferents are
(`fem.experiments.spiking`). The row "samples, linear in time" drives the same afferents from the
8 samples per period linearly in between instead (the project before the load tables).

Prints, per stimulus and class, the total spike count of TouchSim and of the project and their
difference, and how many afferents fire as many spikes as under TouchSim fed the project's course
written out at 5 kHz (its `stim_sine` runs at f N / (N - 1) over its N samples); writes the table
to benchmarks/results/touchsim_compare.md.

    pip install numba scikit-image && pip install --no-deps git+https://github.com/hsaal/touchsim
    python benchmarks/touchsim_compare.py [--no-write]
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from fem.experiments.scene import Scene  # noqa: E402
from fem.experiments.spiking import fine_loads, load_value  # noqa: E402
from fem.receptors.afferents import LoadTable, Population, respond  # noqa: E402
from fem.receptors.transduction import CLASSES, class_data  # noqa: E402
from fem.verify.closed_forms import sneddon_punch_force_N, sneddon_punch_stress_zz_MPa  # noqa: E402

RESULTS = ROOT / "benchmarks" / "results" / "touchsim_compare.md"
E_MPA, NU = 0.05, 0.4                       # the published model's skin
DISTANCES_MM = (0.0, 2.0)                   # afferents at the pin's centre and 2 mm away
DURATION_S = 1.0
SAMPLES_PER_PERIOD = 8
STIMULI = (                                 # (label, frequency Hz, pre-indentation mm, amplitude mm, pin radius mm)
    ("offset sine 10 Hz", 10.0, 0.5, 0.3, 0.5),
    ("offset sine 40 Hz", 40.0, 0.5, 0.3, 0.5),
    ("PC sine 40 Hz", 40.0, 0.1, 0.05, 0.5),
    ("PC sine 250 Hz", 250.0, 0.1, 0.01, 0.5),
)


def population() -> Population:
    """Every published model of every class at each of DISTANCES_MM on the flat skin."""
    cls, idx, site = [], [], []
    for name in CLASSES:
        for k in range(len(class_data(name).parameters)):
            for r in DISTANCES_MM:
                cls.append(name), idx.append(k), site.append((r, 0.0, 0.0))
    n = len(cls)
    return Population(np.array(cls, dtype=object), np.array(idx), np.zeros(n, int), np.array(site),
                      np.tile([0.0, 0.0, 1.0], (n, 1)), np.array([class_data(c).depth_mm for c in cls]))


def project_spikes(pop, freq, pre_mm, amp_mm, pin_mm):
    """(spikes from the load table, spikes from the samples linear in time, sample count)."""
    depth = pre_mm + 2 * amp_mm
    cycles = freq * DURATION_S
    exp = Scene.from_dict({"experiment": [{"indentor": f"punch:{2 * pin_mm}", "depth_mm": depth, "trace": {
        "shape": "sine", "frequency_hz": freq, "cycles": cycles, "offset": pre_mm / depth,
        "samples": int(SAMPLES_PER_PERIOD * cycles) + 1}}]}).experiments[0]
    r = np.linalg.norm(pop.site_mm[:, :2], axis=1)
    stress = sneddon_punch_stress_zz_MPa(r, pop.depth_mm, pin_mm, sneddon_punch_force_N(pin_mm, depth, E_MPA, NU))
    deflection = depth * np.where(r <= pin_mm, 1.0, 2 / np.pi * np.arcsin(pin_mm / np.maximum(r, pin_mm)))
    table = LoadTable(np.array([0.0, depth]), np.c_[0 * stress, stress], np.c_[0 * deflection, deflection])
    samples = table.at([load_value(load) for _, load in exp.indentations])
    tabled = respond(pop, exp.times_s, *samples, noisy=False, fine=table.at(fine_loads(exp)))
    linear = respond(pop, exp.times_s, *samples, noisy=False)
    return tabled.spikes, linear.spikes, len(exp.times_s)


def touchsim_spikes(ts, pop, freq, pre_mm, amp_mm, pin_mm, own_generator=True):
    """TouchSim's spikes of the same afferents under its own offset sine (`stim_sine`, whose phase
    steps 2 pi f len / (N - 1) over its N samples: the frequency f N / (N - 1)), or under the
    project's course written out at 5 kHz (own_generator False)."""
    if own_generator:
        stim = ts.stim_sine(freq=freq, amp=amp_mm, phase=-90.0, len=DURATION_S, fs=5000.0, ramp_len=0.0,
                            pin_radius=pin_mm, pre_indent=pre_mm + amp_mm, loc=[0.0, 0.0])
    else:
        t = np.arange(round(5000 * DURATION_S)) / 5000.0
        trace = pre_mm + amp_mm * (1 - np.cos(2 * np.pi * freq * t))
        stim = ts.Stimulus(trace=trace[None], location=np.zeros((1, 2)), fs=5000.0, pin_radius=pin_mm)
    affs = [ts.Afferent(c, idx=int(k), location=np.array([s[:2]]), noisy=False)
            for c, k, s in zip(pop.afferent_class, pop.model_index, pop.site_mm)]
    return ts.AfferentPopulation(*affs).response(stim).spikes


def _change(n: int, reference: int) -> str:
    return f"{100 * (n - reference) / reference:+.1f} %" if reference else "-"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--no-write", action="store_true", help="print only (no results file)")
    args = ap.parse_args()
    try:
        import touchsim as ts
    except ImportError:
        print("error: TouchSim is not installed: pip install numba scikit-image && pip install --no-deps "
              "git+https://github.com/hsaal/touchsim", file=sys.stderr)
        return 2
    pop = population()
    cls = pop.afferent_class.astype(str)
    rows = ["| stimulus | class | TouchSim spikes | project (load table) | difference | "
            "project (samples, linear in time) | difference | samples | TouchSim on the project's course: "
            "afferents with the same count |", "|---|---|---|---|---|---|---|---|---|"]
    for label, freq, pre, amp, pin in STIMULI:
        t0 = time.perf_counter()
        theirs = touchsim_spikes(ts, pop, freq, pre, amp, pin)
        t1 = time.perf_counter()
        same_course = touchsim_spikes(ts, pop, freq, pre, amp, pin, own_generator=False)
        tabled, linear, samples = project_spikes(pop, freq, pre, amp, pin)
        t2 = time.perf_counter()
        for name in CLASSES:
            sel = np.flatnonzero(cls == name)
            n_ts = sum(len(theirs[i]) for i in sel)
            n_tab, n_lin = (sum(len(s[i]) for i in sel) for s in (tabled, linear))
            equal = sum(len(same_course[i]) == len(tabled[i]) for i in sel)
            rows.append(f"| {label} | {name} | {n_ts} | {n_tab} | {_change(n_tab, n_ts)} | {n_lin} | "
                        f"{_change(n_lin, n_ts)} | {samples} | {equal} of {len(sel)} |")
        print(f"{label}: TouchSim {t1 - t0:.2f} s, project {t2 - t1:.2f} s (both runs of the project)", flush=True)
    table = "\n".join(rows)
    print(table)
    if not args.no_write:
        head = (f"# The afferent chain against TouchSim on its flat skin\n\n`python benchmarks/touchsim_compare.py`"
                f" (TouchSim {getattr(ts, '__version__', 'from its repository')}); {len(pop)} afferents: every "
                f"published model at {', '.join(f'{d:g}' for d in DISTANCES_MM)} mm from the pin, noise off, "
                f"{DURATION_S:g} s.\n\n")
        RESULTS.write_text(head + table + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
