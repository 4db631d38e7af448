"""Lumped receptor model for time (thesis 8.4, figure 8-1): slowly vs rapidly adapting by the damping,
silent during stimulus withdrawal.

Elements: a receptor spring k_r in series with a dashpot c (the "Maxwell arm" that holds the
receptor), and a weak spring k_w in parallel with that arm, all between the skin point and the
datum. The skin input x(t) is any chosen measure at the receptor (a strain, the strain energy
density, a displacement...) as it evolves in time; r(t) is the receptor spring's extension.

Displacement drive (x prescribed):
    c (x' - r') = k_r r    =>   r' = x' - r / tau,   tau = c / k_r
Force drive (the input is the force F on the skin point, carried by both branches):
    F = k_r r + k_w x,  c (x' - r') = k_r r   =>   r' = F' / (k_r + k_w) - r / tau_F,
    tau_F = c (k_r + k_w) / (k_r k_w),   x = (F - k_r r) / k_w
Response: rate = gain * max(r - threshold, 0): the receptor fires only while its spring is in
tension (the thesis's second explanation). With the dashpot unable to hold a static force, r
relaxes to 0 in any hold: a large damping (tau much longer than the hold) gives a slowly adapting
(SA) receptor whose rate follows x; a small one (tau much shorter than the ramp) a rapidly adapting
(RA) receptor with r ~ tau x', firing only while x rises. During a withdrawal x' < 0 drives r down:
an RA receptor is silent at once (r ~ tau x' < 0). An SA receptor whose hold response r_h has not
adapted is NOT silent at once: its rate falls with the skin for t0 = tau ln(1 + r_h / (v tau))
(`silence_delay`; v the withdrawal speed; t0 < the withdrawal time, e.g. 80 of 100 ms for
tau = 5 s after a 1 s hold), then it is silent, with no off-response. Silence through the whole
withdrawal needs the thesis's premise that the receptor has relaxed during the hold (r_h ~ 0).
Under force drive the weak spring, discharging through the dashpot, compresses the receptor
(r = -k_w x / k_r once F = 0), so it stays silent afterwards.

The ODE is linear with a piecewise-linear input between samples, so it is integrated exactly
(exponential integrator): no step-size error.

    t, x = ramp_and_hold(amplitude=1.0, ramp_s=0.1, hold_s=1.0, release_s=0.1)
    out = LumpedReceptor(tau_s=5.0).respond(t, x)          # SA
    out = LumpedReceptor(tau_s=0.01).respond(t, x)         # RA
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fingertip.errors import InputError


def ramp_and_hold(amplitude=1.0, ramp_s=0.1, hold_s=1.0, release_s=0.1, rest_s=0.5, dt_s=1e-3,
                  start_s=0.1):
    """Trapezoid: rest start_s, linear ramp to amplitude over ramp_s, hold, linear release to 0,
    rest. Returns (t (k,), x (k,)) sampled every dt_s (corners included exactly)."""
    for name, v in (("ramp_s", ramp_s), ("release_s", release_s), ("dt_s", dt_s)):
        if not v > 0:
            raise InputError(f"{name} must be positive, got {v}")
    if hold_s < 0 or rest_s < 0 or start_s < 0:
        raise InputError("hold_s, rest_s and start_s must be >= 0")
    corners = np.cumsum([0.0, start_s, ramp_s, hold_s, release_s, rest_s])
    levels = np.array([0.0, 0.0, amplitude, amplitude, 0.0, 0.0])
    t = np.union1d(np.arange(0.0, corners[-1] + 0.5 * dt_s, dt_s), corners)
    return t, np.interp(t, corners, levels)


def phases(t, ramp_s=0.1, hold_s=1.0, release_s=0.1, start_s=0.1):
    """Masks (ramp, hold, release, after) of a `ramp_and_hold` time axis (open intervals)."""
    c = np.cumsum([start_s, ramp_s, hold_s, release_s])
    return ((t > c[0]) & (t < c[1]), (t > c[1]) & (t < c[2]), (t > c[2]) & (t < c[3]), t > c[3])


def measure_time_course(depth_of_t, depths_mm, values):
    """Quasi-static measure time course: a measure known at indentation depths (e.g. from
    `pipeline.py indent --depth 0:1:0.1`, values at one receptor) evaluated along a depth
    time course (linear interpolation; depth 0 -> the value at the smallest depth scaled to 0)."""
    d, v = np.asarray(depths_mm, float), np.asarray(values, float)
    if d[0] > 0:
        d, v = np.concatenate([[0.0], d]), np.concatenate([[0.0], v])
    return np.interp(depth_of_t, d, v)


@dataclass(frozen=True)
class LumpedReceptor:
    """Thesis 8.4 receptor. tau_s = c / k_r (s): damping / receptor stiffness, the adaptation time
    constant. k_ratio = k_w / k_r: weak-spring stiffness relative to the receptor spring (force
    drive only). gain (imp/s per unit r) and threshold (in units of the input) map tension to rate.

    Suggested parameters for a 1 s hold: SA tau_s = 5 (adapts by ~20 % during the hold),
    RA tau_s = 0.01 (a tenth of a 0.1 s ramp)."""
    tau_s: float
    k_ratio: float = 0.05
    gain: float = 1.0
    threshold: float = 0.0

    def __post_init__(self):
        if not self.tau_s > 0 or not self.k_ratio > 0:
            raise InputError("tau_s and k_ratio must be positive")

    def extension(self, t, x, drive: str = "displacement"):
        """Receptor spring extension r(t) (units of the input; force drive: of F / k_r) and the
        skin point x(t) (= the input for displacement drive)."""
        t, x = np.asarray(t, float), np.asarray(x, float)
        if t.ndim != 1 or t.shape != x.shape or np.any(np.diff(t) <= 0):
            raise InputError("time must increase strictly and match the input samples")
        if drive == "displacement":
            tau, scale = self.tau_s, 1.0
        elif drive == "force":
            # F in units of k_r * input: r' = F' / (1 + k) - r / tau_F,  tau_F = tau (1 + k) / k
            tau, scale = self.tau_s * (1 + self.k_ratio) / self.k_ratio, 1.0 / (1 + self.k_ratio)
        else:
            raise InputError(f"drive must be 'displacement' or 'force', got '{drive}'")
        h = np.diff(t)
        slope = scale * np.diff(x) / h
        decay = np.exp(-h / tau)
        gain = tau * (1 - decay)
        r = np.empty_like(x)
        r[0] = 0.0 if x[0] == 0 else scale * x[0]      # start relaxed from rest, or loaded instantly
        for i in range(len(h)):
            r[i + 1] = r[i] * decay[i] + slope[i] * gain[i]
        skin = x if drive == "displacement" else (x - r) / self.k_ratio
        return r, skin

    def respond(self, t, x, drive: str = "displacement") -> dict:
        """{"t", "input", "extension", "skin", "rate"}: rate = gain * max(r - threshold, 0)."""
        r, skin = self.extension(t, x, drive)
        return {"t": np.asarray(t, float), "input": np.asarray(x, float), "extension": r, "skin": skin,
                "rate": self.gain * np.maximum(r - self.threshold, 0.0)}


def silence_delay(tau_s: float, r_hold: float, speed: float) -> float:
    """Displacement drive: time after the start of a linear withdrawal (speed > 0, input units/s)
    until the receptor spring reaches zero tension, from extension r_hold: tau ln(1 + r_h/(v tau))."""
    return tau_s * math.log1p(max(r_hold, 0.0) / (speed * tau_s))
