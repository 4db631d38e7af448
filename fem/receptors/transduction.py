"""Spiking transduction of the TouchSim afferent model: stress at a receptor -> spike times.

TouchSim (Saal, Delhaye, Rayhaun & Bensmaia, "Simulating tactile signals from the whole hand with
millisecond precision", PNAS 2017, 114(28):E5693-E5702, doi:10.1073/pnas.1704856114; code at
github.com/hsaal/touchsim, touchsim/transduction.py) drives a leaky integrate-and-fire neuron at
5 kHz with two mechanical inputs at the afferent's depth: the static one, the vertical stress [MPa],
and the dynamic one, E* x surface deflection velocity / depth^2 [MPa/(mm s)]. Each of the published
models (SA1: 4, RA: 9, PC: 4, fitted to macaque recordings) has 13 parameters p[0..12]: a
3rd-order Butterworth low-pass (cutoff 10*p0 Hz), rectified gains on the input, on its derivative
and on the derivative's increment (p1..p6), a current saturation (p7), current noise (p8), the
membrane time constant (p9, samples), a post-spike current (p10, p11) and a delay (p12, ms). This is
a vectorised numpy/scipy reimplementation (loop over time, vector over afferents) that gives spikes
identical to the original's with noise off (the noise stream differs); the tables live in
data/touchsim_afferents.json.

All three classes run here. PC afferents are tuned to 40-400 Hz vibration, where the finger's
mechanics is not quasi-static; scenes drive them with quasi-static mechanics, as the published
model does on its half-space (`fem.experiments.traces.frequency_warning`).

Usage (stress and deflection sampled at times t_s, afferent under the deflection at 0.3 mm):

    _, s = resample(t_s, stress_MPa, 1.0)
    _, d = resample(t_s, dynamic_input(t_s, deflection_mm, 0.3, E_star_MPa), 1.0)
    spikes = spike_trains(["SA1"] * len(s), [0] * len(s), s, d)
"""
from __future__ import annotations

import json
import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from fingertip.errors import InputError
from fingertip.resources import shipped

LIF_RATE_HZ = 5000.0
CLASSES = ("SA1", "RA", "PC")
N_PARAMETERS = 13
REFRACTORY_SAMPLES = 5          # a spike needs more than 5 samples since the last one
DATA_FILE = "data/touchsim_afferents.json"
"""The published parameters, a shipped file (`fingertip.resources.shipped`)."""


@dataclass(frozen=True)
class ClassData:
    """Published data of one afferent class (TouchSim constants.py)."""
    name: str                   # "SA1", "RA" or "PC"
    depth_mm: float             # receptor depth below the skin surface
    density_per_cm2: float      # fingertip innervation density
    parameters: np.ndarray      # (k, 13) one row per model, read-only; units in the JSON "units"


@lru_cache(maxsize=1)
def _tables() -> dict:
    path = shipped(DATA_FILE)
    try:
        raw = json.loads(path.read_text())
    except OSError as e:
        raise InputError(f"cannot read the TouchSim afferent tables {path}: {e.strerror}") from None
    basis = np.array(raw["post_spike_basis"], float)
    basis.setflags(write=False)
    classes = {}
    for name in CLASSES:
        c = raw["classes"][name]
        p = np.array(c["parameters"], float)
        if p.ndim != 2 or p.shape[1] != N_PARAMETERS:
            raise InputError(f"{path}: class {name} parameters must be rows of {N_PARAMETERS} numbers")
        p.setflags(write=False)
        classes[name] = ClassData(name, float(c["depth_mm"]), float(c["density_per_cm2"]), p)
    skin = raw["skin"]
    return {"basis": basis, "classes": classes, "skin_E_star_MPa": float(skin["E_MPa"]) / (1.0 - float(skin["nu"]) ** 2)}


def skin_E_star_MPa() -> float:
    """E / (1 - nu^2) of the published model's half-space skin (E 0.05 MPa, nu 0.4): 0.0595 MPa, the
    constant its dynamic input carries and its weights p3-p6 were fit with [MPa]."""
    return _tables()["skin_E_star_MPa"]


def _bad_class(name) -> InputError:
    return InputError(f"unknown afferent class {name!r}: use one of {', '.join(CLASSES)}")


def class_data(name: str) -> ClassData:
    """Depth, density and the (k, 13) parameter table of the class 'SA1', 'RA' or 'PC'."""
    if not isinstance(name, str) or name not in CLASSES:
        raise _bad_class(name)
    return _tables()["classes"][name]


def post_spike_basis() -> np.ndarray:
    """(2, n) dimensionless basis of the post-spike current, one column per 5 kHz sample after a
    spike (n = 190); the current is p10 * basis[0] + p11 * basis[1]."""
    return _tables()["basis"].copy()


def _time_axis(t_s, name="t_s", minimum=1) -> np.ndarray:
    t = np.asarray(t_s, float)
    if t.ndim != 1 or t.size < minimum:
        raise InputError(f"{name} must be a 1-D array of at least {minimum} times in s, got shape {t.shape}")
    if not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0):
        raise InputError(f"{name} must be finite and strictly increasing")
    return t


def _samples(values, m, name) -> np.ndarray:
    v = np.asarray(values, float)
    if v.ndim not in (1, 2) or v.shape[-1] != m:
        raise InputError(f"{name} must have shape (n, {m}) or ({m},) to match the times, got {v.shape}")
    if not np.all(np.isfinite(v)):
        raise InputError(f"{name} has non-finite values")
    return v


def lif_times(duration_s) -> np.ndarray:
    """(T,) times [s] of the transduction's samples over a course: arange(T) / 5000, T =
    floor(duration_s x 5000)."""
    duration = float(duration_s)
    if not math.isfinite(duration) or duration <= 0:
        raise InputError(f"duration_s must be a positive number of seconds, got {duration_s}")
    return np.arange(math.floor(duration * LIF_RATE_HZ + 1e-9)) / LIF_RATE_HZ  # 1e-9: 0.7 * 5000 is 3500


def resample(t_s, values, duration_s=None):
    """Piecewise-linear input at the LIF rate from mechanical samples.

    t_s (m,) strictly increasing times [s]; values (n, m) (or (m,)) samples at those times.
    Returns times (T,) = arange(T) / 5000 s and values (n, T) (or (T,)), T = floor(duration_s * 5000)
    with duration_s defaulting to t_s[-1]; values outside [t_s[0], t_s[-1]] are held at the ends.
    (TouchSim resamples with a Fourier method instead; both agree for smooth traces.)
    """
    t = _time_axis(t_s)
    v = _samples(values, t.size, "values")
    times = lif_times(t[-1] if duration_s is None else duration_s)
    T = times.size
    v2 = np.atleast_2d(v)
    if t.size == 1:
        out = np.repeat(v2, T, axis=1)
    else:
        k = np.clip(np.searchsorted(t, times, side="right") - 1, 0, t.size - 2)
        w = np.clip((times - t[k]) / (t[k + 1] - t[k]), 0.0, 1.0)
        out = v2[:, k] * (1.0 - w) + v2[:, k + 1] * w
    return times, (out[0] if v.ndim == 1 else out)


def dynamic_input(t_s, surface_deflection_mm, depth_mm, E_star_MPa):
    """TouchSim's dynamic input for quasi-static mechanics [MPa/(mm s)], shape like the deflection.

    t_s (m,) times [s], m >= 3; surface_deflection_mm (n, m) or (m,): inward (indenting) deflection
    of the skin surface directly above each afferent; depth_mm scalar or (n,); E_star_MPa the plane
    strain modulus E / (1 - nu^2) (TouchSim: E = 0.05 MPa, nu = 0.4, E* = 0.0595 MPa).
    Returns E* x dS/dt / depth^2, dS/dt by central differences, the first and last copied from their
    neighbours (TouchSim's S1p; equal to it for uniform sampling).

    Why this is TouchSim's circ_load_dyn_wave without the wave delay: TouchSim turns the pins'
    deflection velocities into loads Pdyn = D^-1 dS/dt, D the Sneddon (1946) flat-punch deflection
    matrix, D_jk = (1 - nu^2) / E x arcsin(a / r_jk) / (pi a) (1 / (2 a) inside the pin), and sums
    them at the afferent with the decay arcsin(a / r) / (pi a) (1 / (2 a) under a pin), which is the
    same Green function times E / (1 - nu^2). The sum is therefore E* times the deflection
    velocity of the surface at the afferent's location, which TouchSim divides by depth^2. The
    neglected delays, r / (8000 mm/s), stay below 1.3 ms over a 10 mm pad.
    """
    t = _time_axis(t_s, minimum=3)
    S = _samples(surface_deflection_mm, t.size, "surface_deflection_mm")
    S2 = np.atleast_2d(S)
    depth = np.asarray(depth_mm, float)
    if depth.ndim > 1 or (depth.ndim == 1 and depth.size != S2.shape[0]) or np.any(~(depth > 0)):
        raise InputError(f"depth_mm must be positive, a scalar or one per deflection row ({S2.shape[0]})")
    E_star = float(E_star_MPa)
    if not (E_star > 0 and math.isfinite(E_star)):
        raise InputError(f"E_star_MPa must be a positive modulus, got {E_star_MPa}")
    v = np.empty_like(S2)
    v[:, 1:-1] = (S2[:, 2:] - S2[:, :-2]) / (t[2:] - t[:-2])
    v[:, 0], v[:, -1] = v[:, 1], v[:, -2]
    out = E_star * v / (np.reshape(depth, (-1, 1)) ** 2)
    return out[0] if S.ndim == 1 else out


def _parameters(classes, model_index):
    cls = np.asarray(classes, dtype=object).reshape(-1)
    idx = np.asarray(model_index).reshape(-1)
    if cls.size != idx.size:
        raise InputError(f"classes ({cls.size}) and model_index ({idx.size}) must have one entry per afferent")
    if idx.size and not np.issubdtype(idx.dtype, np.integer):
        raise InputError("model_index must hold integers (rows of the class parameter table)")
    unknown = ~np.isin(cls, CLASSES)
    if unknown.any():
        raise _bad_class(cls[unknown][0])
    p = np.empty((cls.size, N_PARAMETERS))
    class_id = np.empty(cls.size, int)
    for j, name in enumerate(CLASSES):
        sel = cls == name
        if not sel.any():
            continue
        table = class_data(name).parameters
        bad = (idx[sel] < 0) | (idx[sel] >= len(table))
        if bad.any():
            raise InputError(f"model_index {idx[sel][bad][0]} out of range for {name}: use 0..{len(table) - 1}")
        p[sel] = table[idx[sel]]
        class_id[sel] = j
    return p, class_id, idx


def injected_current(parameters, static_MPa, dynamic):
    """Membrane current before noise and saturation, (n, T) in threshold units per sample.

    parameters (n, 13); static_MPa and dynamic (n, T) already low-pass filtered.
    I = p1 s | -p2 s  +  p3 ds | -p4 ds  +  p5 dd | -p6 dd  (first form for values >= 0), with
    dd[i] = ds[min(i + 1, T - 1)] - ds[i].
    """
    p = np.asarray(parameters, float)
    col = lambda k: p[:, k:k + 1]
    s, ds = static_MPa, dynamic
    dd = np.empty_like(ds)
    dd[:, :-1] = ds[:, 1:] - ds[:, :-1]
    dd[:, -1:] = 0.0
    current = np.where(s >= 0, col(1) * s, -col(2) * s)
    current += np.where(ds >= 0, col(3) * ds, -col(4) * ds)
    current += np.where(dd >= 0, col(5) * dd, -col(6) * dd)
    return current


def spike_trains(classes, model_index, static_MPa, dynamic, noisy=False, seed=0, delay=True):
    """Spike times of n afferents driven by inputs sampled at 5 kHz.

    classes (n,) class names ('SA1', 'RA', 'PC'); model_index (n,) row of each class table;
    static_MPa (n, T) vertical stress at the afferent; dynamic (n, T) dynamic input [MPa/(mm s)]
    (see dynamic_input); sample i is at time i / 5000 s. noisy (bool or (n,)) adds p8 x N(0, 1)
    current noise, drawn from seed (an int or a numpy Generator) so that runs repeat.
    delay adds p12 ms to every spike (TouchSim's Afferent(delay=True); its default, delay=False,
    zeroes p12). Returns n arrays of spike times [s]: index / 5000 + p12 / 1000 + 1 / 5000.
    """
    p, class_id, idx = _parameters(classes, model_index)
    n = len(p)
    s = np.array(static_MPa, float, ndmin=2)
    ds = np.array(dynamic, float, ndmin=2)
    if s.shape != ds.shape or s.shape[0] != n or s.ndim != 2:
        raise InputError(f"static_MPa {s.shape} and dynamic {ds.shape} must both have shape (n={n}, T)")
    if not (np.all(np.isfinite(s)) and np.all(np.isfinite(ds))):
        raise InputError("static_MPa and dynamic must be finite")
    T = s.shape[1]
    if n == 0 or T == 0:
        return [np.zeros(0) for _ in range(n)]
    noisy = np.broadcast_to(np.asarray(noisy, bool), (n,))

    # scipy.signal: 0.45 s of import, which every command running no afferents does without
    from scipy import signal

    # low-pass per published model: the dynamic input always, the static one for SA1 only
    groups = np.unique(np.stack([class_id, idx], axis=1), axis=0)
    for cid, k in groups:
        rows = (class_id == cid) & (idx == k)
        b, a = signal.butter(3, p[rows][0, 0] * 4.0 / 1000.0)
        if cid == 0:
            s[rows] = signal.lfilter(b, a, s[rows], axis=1)
        ds[rows] = signal.lfilter(b, a, ds[rows], axis=1)

    current = injected_current(p, s, ds)
    if noisy.any():
        rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)
        noise = rng.standard_normal((n, T))
        current[noisy] += p[noisy, 8:9] * noise[noisy]
    sat = p[:, 7] > 0
    if sat.any():
        p7 = p[sat, 7:8]
        c = p7 * current[sat] / (p7 + np.abs(current[sat]))
        current[sat] = np.where(np.isnan(c), 0.0, c)

    # post-spike current, padded with a zero column: counter == nh means "finished"
    basis = _tables()["basis"]
    nh = basis.shape[1]
    ih = np.zeros((n, nh + 1))
    ih[:, :nh] = p[:, 10:12] @ basis
    ih_flat = ih.reshape(-1)
    row0 = np.arange(n) * (nh + 1)
    tau = p[:, 9]
    drive = np.ascontiguousarray(current.T)             # (T, n): one row per time step
    V = np.zeros(n)
    counter = np.full(n, nh)
    fired = np.zeros((T, n), bool)
    for i in range(T):
        V = V + ((-V / tau + drive[i]) + ih_flat[row0 + counter])
        np.minimum(counter + 1, nh, out=counter)
        f = (V > 1.0) & (counter > REFRACTORY_SAMPLES)
        if f.any():
            fired[i] = f
            V[f] = 0.0
            counter[f] = 0

    delay_s = p[:, 12] / 1000.0 if delay else np.zeros(n)
    return [np.flatnonzero(fired[:, j]) / LIF_RATE_HZ + delay_s[j] + 1.0 / LIF_RATE_HZ for j in range(n)]


def rates_hz(spikes, t0_s, t1_s) -> np.ndarray:
    """(n,) mean rate [Hz]: spikes with t0_s <= t < t1_s divided by t1_s - t0_s."""
    t0, t1 = float(t0_s), float(t1_s)
    if not (t1 > t0):
        raise InputError(f"the rate window needs t1_s > t0_s, got [{t0_s}, {t1_s}]")
    return np.array([np.count_nonzero((np.asarray(x) >= t0) & (np.asarray(x) < t1)) for x in spikes],
                    float) / (t1 - t0)
