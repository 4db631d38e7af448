"""Time courses of a stimulus: the fraction of an experiment's depth (or force) at each time.

Linear frictionless contact is path-independent, so a time course is a series of quasi-static
contact solves, one per sample (repeated values are solved once). Quasi-static means no inertia:
the finger's mechanics answers at once (and, without viscoelastic layers, no viscosity either).
The skin carries surface waves at about 8 m/s (the wave speed of the published afferent model,
Saal et al. 2017); at QUASI_STATIC_HZ their wavelength, 160 mm, is ten times a 16 mm human
fingertip, so below it a stimulus sees the whole pad in phase. Faster sines (the 40-400 Hz
vibration Pacinian afferents are tuned to) run, as in the published model, with quasi-static
mechanics, and the run says so (`frequency_warning`); above MAX_FREQUENCY_HZ they are refused.

    t, f = fractions(Trace(shape="ramp_hold", ramp_s=0.1, hold_s=0.5, release_s=0.1, samples=100))
    depths = 1.0 * f                                  # a probe pressed to 1 mm, held, released
    f_5khz = course(trace, np.arange(3500) / 5000.0)  # the same course at any times
"""
from __future__ import annotations

import numpy as np

from fingertip.errors import InputError

QUASI_STATIC_HZ = 50.0
"""Highest sine frequency whose quasi-static mechanics the whole pad follows in phase (Hz; module note)."""
MAX_FREQUENCY_HZ = 1000.0
"""Highest sine frequency a course may have (Hz): 5 samples per period of the afferents' 5 kHz
integration (`fem.receptors.transduction.LIF_RATE_HZ`), the top of the published model's range."""
SHAPES = ("ramp_hold", "sine", "steps", "table", "scan")


def fractions(trace, offsets_mm=None) -> tuple[np.ndarray, np.ndarray]:
    """(times (n,) s, fractions (n,) of the experiment's depth or force) of a fem.experiments.scene.Trace.

    ramp_hold: 0 -> 1 linearly over ramp_s, held hold_s, back to 0 over release_s (then 0 for
        rest_s); sine: offset + (1 - offset) (1 - cos 2 pi f t) / 2 for cycles periods (from the
        offset to 1 and back each period; the offset is held from t = 0, a pre-indentation);
    steps: each of `levels` in turn, reached by a ramp_s ramp and held hold_s, then released;
    table: times_s and levels as given (linear in between; resampled at `samples` points);
    scan: the indentor held at the full depth while the sweep's offsets_mm (k, 3) are visited at
        speed_mm_s (times are the distance travelled over the speed; one sample per offset).
    Other shapes are sampled at `samples` evenly spaced times, both ends included, and at the
    corners of the course."""
    if trace.shape == "scan":
        if offsets_mm is None or len(offsets_mm) < 2:
            raise InputError('trace shape "scan" moves the indentor along its sweep: give the experiment '
                             'a sweep, e.g. sweep = "x=-3:3:0.1"')
        path = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(offsets_mm, axis=0), axis=1))]
        return path / trace.speed_mm_s, np.ones(len(path))
    knots_t, _ = _knots(trace)
    t = np.linspace(0.0, knots_t[-1], trace.samples)
    if trace.shape != "sine":
        t = np.union1d(t, knots_t)      # corners of the course are samples, so no peak is cut
    return t, course(trace, t)


def course(trace, times_s) -> np.ndarray:
    """Fractions (m,) of the depth or force at any times_s (m,) [s] of a course (not a scan): the
    course of `fractions` in closed form, held at its last value after the end."""
    t = np.asarray(times_s, float)
    if trace.shape == "scan":
        raise InputError('a "scan" course is a path along the sweep, not a function of time alone')
    if trace.shape == "sine":
        t = np.minimum(t, trace.cycles / trace.frequency_hz)
        return trace.offset + (1.0 - trace.offset) * 0.5 * (1.0 - np.cos(2 * np.pi * trace.frequency_hz * t))
    knots_t, knots_f = _knots(trace)
    return np.interp(t, knots_t, knots_f)


def frequency_warning(trace) -> str | None:
    """What a run says of a sine above QUASI_STATIC_HZ (None otherwise)."""
    if trace is None or trace.shape != "sine" or trace.frequency_hz <= QUASI_STATIC_HZ:
        return None
    return (f"a {trace.frequency_hz:g} Hz sine is above the quasi-static limit ({QUASI_STATIC_HZ:g} Hz): the "
            f"mechanics answer at once, without the inertia and surface-wave delays of the real finger "
            f"(as in the published afferent model's half-space, less its wave delays)")


def _knots(trace) -> tuple[np.ndarray, np.ndarray]:
    """Corner times (s) and fractions of a piecewise-linear course (sine: its end only)."""
    if trace.shape == "ramp_hold":
        t = np.cumsum([0.0, trace.ramp_s, trace.hold_s, trace.release_s, trace.rest_s])
        return t, np.array([0.0, 1.0, 1.0, 0.0, 0.0])
    if trace.shape == "sine":
        return np.array([0.0, trace.cycles / trace.frequency_hz]), np.zeros(2)
    if trace.shape == "steps":
        t, f = [0.0], [0.0]
        for level in (*trace.levels, 0.0):
            t += [t[-1] + trace.ramp_s, t[-1] + trace.ramp_s + trace.hold_s]
            f += [level, level]
        return np.array(t), np.array(f)
    return np.asarray(trace.times_s, float), np.asarray(trace.levels, float)      # table


def check(trace, where: str) -> None:
    """Raise InputError for a trace that cannot be sampled (values, lengths, the frequency limit)."""
    def need(ok, what):
        if not ok:
            raise InputError(f"{where} trace: {what}")

    need(trace.shape in SHAPES, f'shape "{trace.shape}" is not one of {", ".join(SHAPES)}')
    need(trace.samples >= 2, f"samples must be >= 2, got {trace.samples}")
    for key in ("ramp_s", "hold_s", "release_s", "rest_s"):
        need(getattr(trace, key) >= 0, f"{key} must be >= 0 s, got {getattr(trace, key)}")
    if trace.shape == "ramp_hold":
        need(trace.ramp_s + trace.hold_s + trace.release_s > 0, "ramp_s + hold_s + release_s must be > 0 s")
    if trace.shape == "sine":
        need(0 < trace.frequency_hz <= MAX_FREQUENCY_HZ,
             f"frequency_hz must be in (0, {MAX_FREQUENCY_HZ:g}] Hz (5 samples per period of the afferents' "
             f"5 kHz integration), got {trace.frequency_hz}")
        need(0 <= trace.offset < 1, f"offset must be a fraction in [0, 1), got {trace.offset}")
        need(trace.cycles > 0, f"cycles must be > 0, got {trace.cycles}")
        need(trace.samples >= 8 * trace.cycles, f"samples ({trace.samples}) must be >= 8 per cycle "
                                                f"({8 * trace.cycles:g} for {trace.cycles:g} cycles)")
    if trace.shape in ("steps", "table"):
        need(len(trace.levels) > 0 and all(0 <= v <= 1 for v in trace.levels),
             f"levels must be fractions of the depth (or force) in [0, 1], got {list(trace.levels)}")
    if trace.shape == "steps":
        need(trace.ramp_s + trace.hold_s > 0, "ramp_s + hold_s must be > 0 s")
    if trace.shape == "table":
        t = np.asarray(trace.times_s, float)
        need(len(t) == len(trace.levels) and len(t) >= 2 and t[0] == 0 and np.all(np.diff(t) > 0),
             "times_s must start at 0, increase, and pair with levels")
    if trace.shape == "scan":
        need(trace.speed_mm_s > 0, f"speed_mm_s must be > 0 mm/s, got {trace.speed_mm_s}")
