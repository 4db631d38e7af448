"""Linear viscoelastic layers: a Prony series relaxation function shared by every layer.

The moduli relax as G(t) = G0 g(t), K(t) = K0 g(t) with one normalised relaxation function

    g(t) = g_inf + sum_i g_i exp(-t / tau_i),      g_inf = 1 - sum_i g_i > 0,

so the Poisson ratio stays fixed and every stiffness of the model scales by g(t): the elastic
problem at each time is the instantaneous one (moduli of the `Material`) times a number. That is
what lets the correspondence principle turn the elastic contact results of a time course into
viscoelastic ones by a convolution in time (`fem.experiments.viscoelastic`). A shear-only spectrum
with an elastic bulk modulus would change nu over time and need time stepping instead; at
nu = 0.48 the bulk modulus is 25 times the shear modulus, and the contact response of a nearly
incompressible body follows G / (1 - nu), so relaxing both together changes little but keeps
the method exact.

Hereditary integrals y(t) = w_inf x(t) + sum_i w_i int_0^t exp(-(t - s) / tau_i) dx(s) are
evaluated by the exponential-integrator recursion of the Prony internal variables h_i,

    h_i(t_k) = a h_i(t_{k-1}) + b (x_k - x_{k-1}),   a = exp(-dt / tau_i),   b = tau_i (1 - a) / dt,

O(n) in the samples and exact for an input linear between samples; x before the first sample is
0 (a step at t_0 when x_0 != 0). Relaxation (`Prony.relax`) uses (g_inf, g_i, tau_i); creep
(`Prony.creep`) the creep compliance J(t) = 1 / g_inf - sum_k j_k exp(-t / lambda_k), J(0) = 1,
whose retardation times lambda_k (`Prony.retardation`) are the roots of s g^(s) = 0 in the
Laplace domain, one in each gap between the relaxation rates (SLS: lambda = tau / g_inf).

    law = Prony(g=(0.2, 0.2, 0.2))                  # weights given; relaxation times PAWLUK_HOWE_TAU_S
    law.relax(t_s, elastic_force_N)                 # force of a viscoelastic body at the same depths
    law.creep(t_s, force_N)                         # elastic force whose depth it creeps to
"""
from __future__ import annotations

from dataclasses import dataclass
from itertools import pairwise

import numpy as np

from fingertip.errors import InputError

PAWLUK_HOWE_TAU_S = (0.004, 0.07, 1.4)
"""Relaxation times of the human fingerpad (s): Pawluk and Howe 1999, "Dynamic lumped element
response of the human fingerpad", J Biomech Eng 121(2):178-183, a quasi-linear viscoelastic fit
to the force of a flat probe held in the fingerpad in vivo: three decaying exponentials of about
4 ms, 70 ms and 1.4 s plus a constant."""


@dataclass(frozen=True)
class Prony:
    """A normalised Prony series g(t) = g_inf + sum g_i exp(-t / tau_i), every layer's moduli
    times g(t) (module docstring). g: (N,) weights > 0 with sum < 1, always given (the published
    fingerpad fits this project could check give the times, not the weights); tau_s: (N,) distinct
    relaxation times > 0 [s]."""
    g: tuple
    tau_s: tuple = PAWLUK_HOWE_TAU_S

    def __post_init__(self):
        g, tau = np.asarray(self.g, float), np.asarray(self.tau_s, float)
        what = f"g = {list(self.g)}, tau_s = {list(self.tau_s)}"
        if g.ndim != 1 or not len(g) or g.shape != tau.shape:
            raise InputError(f"[viscoelastic] {what}: give one weight g per relaxation time tau_s (at least one)")
        if not (np.all(np.isfinite(g)) and np.all(g > 0) and g.sum() < 1):
            raise InputError(f"[viscoelastic] {what}: the weights g must be > 0 with a sum below 1 "
                             f"(g_inf = 1 - sum g is the relaxed fraction of the moduli)")
        if not (np.all(np.isfinite(tau)) and np.all(tau > 0) and len(np.unique(tau)) == len(tau)):
            raise InputError(f"[viscoelastic] {what}: the relaxation times tau_s must be distinct and > 0 s")
        object.__setattr__(self, "g", tuple(float(v) for v in g))
        object.__setattr__(self, "tau_s", tuple(float(v) for v in tau))

    @property
    def g_inf(self) -> float:
        """Relaxed fraction of the moduli, g(inf) = 1 - sum g_i."""
        return 1.0 - sum(self.g)

    def relaxation(self, t_s) -> np.ndarray:
        """g(t) = G(t) / G0 at times t_s (array, s >= 0)."""
        t = np.asarray(t_s, float)[..., None]
        return self.g_inf + (np.asarray(self.g) * np.exp(-t / np.asarray(self.tau_s))).sum(axis=-1)

    def retardation(self) -> tuple[float, np.ndarray, np.ndarray]:
        """(J_inf, j (N,), lambda_s (N,)) of the creep compliance J(t) G0 = J_inf - sum j_k
        exp(-t / lambda_k): J_inf = 1 / g_inf, sum j_k = J_inf - 1. With u = 1 / lambda, the
        roots of phi(u) = g_inf - sum g_i tau_i u / (1 - tau_i u) (= s g^(s) at s = -u), one below
        the slowest rate 1 / tau and one between each pair of rates; j_k = lambda_k / phi'(s_k)."""
        # imported here: scipy.optimize would cost every command 50 ms
        from scipy.optimize import brentq

        g, tau = np.asarray(self.g), np.asarray(self.tau_s)
        order = np.argsort(-tau)
        g, tau = g[order], tau[order]
        rates = 1.0 / tau

        def phi(u):
            return self.g_inf - np.sum(g * tau * u / (1.0 - tau * u))

        gaps = np.r_[0.0, rates]
        u = np.array([brentq(phi, lo + 1e-12 * hi, hi * (1 - 1e-12), xtol=1e-14 * hi, rtol=1e-15)
                      for lo, hi in pairwise(gaps)])
        slope = np.array([np.sum(g * tau / (1.0 - tau * uk) ** 2) for uk in u])     # d phi / ds at s = -u
        return 1.0 / self.g_inf, 1.0 / (u * slope), 1.0 / u

    def creep_compliance(self, t_s) -> np.ndarray:
        """J(t) G0 at times t_s (array, s >= 0): 1 at t = 0, 1 / g_inf at t = inf."""
        J_inf, j, lam = self.retardation()
        t = np.asarray(t_s, float)[..., None]
        return J_inf - (j * np.exp(-t / lam)).sum(axis=-1)

    def relax(self, times_s, values) -> np.ndarray:
        """int g(t - s) dx(s): the viscoelastic response (n, ...) to an elastic course x = values
        (n, ...) at the n increasing times_s [s] (depth control: force, stress, pressure)."""
        return hereditary(times_s, values, self.g_inf, self.g, self.tau_s)

    def creep(self, times_s, values) -> np.ndarray:
        """int J(t - s) G0 dx(s): the elastic course (n, ...) whose relaxation is x = values (n,
        ...) at the n increasing times_s [s] (force control: the elastic force at the depth the
        viscoelastic body creeps to under force x)."""
        J_inf, j, lam = self.retardation()
        return hereditary(times_s, values, J_inf, -j, lam)

    def record(self) -> dict:
        """run.json's description of the law."""
        return {"g": list(self.g), "tau_s": list(self.tau_s), "g_inf": self.g_inf,
                "moduli": "G(t) = G0 g(t) and K(t) = K0 g(t) in every layer (nu fixed)"}


def hereditary(times_s, values, w_inf: float, w, tau_s) -> np.ndarray:
    """y_k = w_inf x_k + sum_i w_i h_i(t_k), h_i(t) = int_0^t exp(-(t - s) / tau_i) dx(s), for x =
    values (n, ...) at n increasing times_s [s], x linear between samples and 0 before the first
    (module docstring). Vectorised over the trailing axes and the terms; one pass over the samples."""
    t = np.asarray(times_s, float)
    x = np.asarray(values, float)
    if t.ndim != 1 or len(t) != len(x) or np.any(np.diff(t) < 0):
        raise ValueError("times_s must be (n,) non-decreasing, one per row of values")
    w, tau = np.asarray(w, float), np.asarray(tau_s, float)
    dt = np.diff(t)[:, None]
    a = np.exp(-dt / tau)
    with np.errstate(invalid="ignore", divide="ignore"):
        b = np.where(dt > 0, -np.expm1(-dt / tau) * tau / dt, 1.0)        # 1 as dt -> 0 (a step)
    shape = (len(tau),) + (1,) * (x.ndim - 1)
    h = np.broadcast_to(x[0], (len(tau),) + x.shape[1:]).copy() if len(x) else None
    out = np.empty_like(x)
    for k in range(len(x)):
        if k:
            h = a[k - 1].reshape(shape) * h + b[k - 1].reshape(shape) * (x[k] - x[k - 1])
        out[k] = w_inf * x[k] + np.tensordot(w, h, axes=1)
    return out


@dataclass(frozen=True)
class LayerLaws:
    """A relaxation function per layer: `layers` ((layer, Prony or None), ...) for the layers
    named, `default` (a Prony or None) for the others; None keeps a layer elastic. Layers with
    different spectra make the body's response more than the elastic one convolved in time: a
    time course is then stepped (`fem.experiments.stepping`)."""
    default: Prony | None
    layers: tuple = ()

    def law(self, layer: int) -> Prony | None:
        return dict(self.layers).get(int(layer), self.default)

    def groups(self, layer_ids) -> list[tuple[Prony | None, tuple]]:
        """[(law, layers)] of the given layer ids, one entry per distinct law (in layer order)."""
        out: dict = {}
        for layer in sorted(int(k) for k in layer_ids):
            out.setdefault(self.law(layer), []).append(layer)
        return [(law, tuple(ids)) for law, ids in out.items()]

    def shared(self, layer_ids) -> Prony | None:
        """The one Prony of every given layer when they all have the same one, else None."""
        groups = self.groups(layer_ids)
        return groups[0][0] if len(groups) == 1 else None

    def record(self) -> dict:
        """run.json's description of the laws."""
        def one(law):
            return None if law is None else {"g": list(law.g), "tau_s": list(law.tau_s), "g_inf": law.g_inf}
        return {"default": one(self.default), "layers": {str(k): one(v) for k, v in self.layers},
                "moduli": "G(t) = G0 g_L(t) and K(t) = K0 g_L(t) in layer L (nu fixed); null: elastic"}


class StepHistory:
    """The hereditary integral y = g_inf x + sum_i g_i h_i of a Prony law, advanced one time step
    at a time for x of any shape (`hereditary`'s recursion): y_{n+1} = alpha(dt) x_{n+1} + rest(dt),
    alpha(dt) = g_inf + sum g_i b_i(dt). law None: elastic (y = x)."""

    def __init__(self, law: Prony | None, shape):
        self.law = law
        self.x = np.zeros(shape)
        self.h = None if law is None else np.zeros((len(law.g),) + tuple(np.atleast_1d(shape)))

    def _ab(self, dt: float):
        tau = np.asarray(self.law.tau_s)
        a = np.exp(-dt / tau)
        b = -np.expm1(-dt / tau) * tau / dt if dt > 0 else np.ones_like(tau)
        return a, b

    def alpha(self, dt: float) -> float:
        """Weight of x_{n+1} in y_{n+1} after a step dt [s] (1: elastic or dt = 0)."""
        if self.law is None:
            return 1.0
        return self.law.g_inf + float(np.dot(self.law.g, self._ab(dt)[1]))

    def rest(self, dt: float) -> np.ndarray:
        """The part of y_{n+1} set by the history: sum g_i (a_i h_i - b_i x_n)."""
        if self.law is None:
            return np.zeros_like(self.x)
        a, b = self._ab(dt)
        return np.tensordot(np.asarray(self.law.g), a.reshape(-1, *[1] * self.x.ndim) * self.h
                            - b.reshape(-1, *[1] * self.x.ndim) * self.x, axes=1)

    def advance(self, dt: float, x) -> np.ndarray:
        """Take the step to x_{n+1} = x; returns y_{n+1}."""
        x = np.asarray(x, float)
        if self.law is None:
            self.x = x.copy()
            return x.copy()
        a, b = self._ab(dt)
        shape = (-1,) + (1,) * x.ndim
        self.h = a.reshape(shape) * self.h + b.reshape(shape) * (x - self.x)
        self.x = x.copy()
        return self.law.g_inf * x + np.tensordot(np.asarray(self.law.g), self.h, axes=1)
