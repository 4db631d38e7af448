"""Layer moduli from measurements (thesis 6.2.3, appendix B): log10 moduli of chosen layers fitted
to measured deflection profiles (modulus ratios: one layer stays at its base value), and the common
modulus scale fitted to force-depth data (at prescribed depth every force is proportional to it).

    fit = fit_material(exp, read_deflection_csv("data.csv"), base="m43338", free_layers=(2, 3, 4))
    scale = fit_force_scale(exp.forces_N(fit.log10_Pa, depths), measured_N, fit.log10_Pa, depths)
"""
from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from fem.biomech.deflection import (
    DeflectionExperiment,
    Profile,
    as_log10,
    code_of,
    parse_code,
    ratio_key,
)
from fingertip.errors import InputError


@dataclass
class MaterialFit:
    """Layer moduli fitted to deflection profiles.

    log10_Pa (5,) continuous optimum; free_layers; std_log10 (p,) one-sigma uncertainty of the
    free log10 moduli from the Jacobian (sigma^2 (J^T J)^-1, sigma^2 from the residuals unless
    given); factor (p,) = 10 ** std_log10; sensitivity_mm (p,) rms change of the deflection per
    decade of each layer's modulus; correlation (p, p); residuals_mm at the optimum (per data
    point, depth-major); best_code: the best of the integer roundings (by rms), with its rms."""
    log10_Pa: np.ndarray
    free_layers: tuple
    rms_mm: float
    residuals_mm: np.ndarray
    std_log10: np.ndarray
    factor: np.ndarray
    sensitivity_mm: np.ndarray
    correlation: np.ndarray
    best_code: str
    best_code_rms_mm: float
    code_rms_mm: dict
    evaluations: int
    nfev: int
    status: str

    def report(self) -> dict:
        return {"continuous_log10_Pa": [round(float(v), 4) for v in self.log10_Pa],
                "continuous_E_Pa": [float(f"{10 ** v:.4g}") for v in self.log10_Pa],
                "free_layers": list(self.free_layers), "rms_mm": self.rms_mm,
                "std_log10": self.std_log10.tolist(), "uncertainty_factor": self.factor.tolist(),
                "sensitivity_mm_per_decade": self.sensitivity_mm.tolist(),
                "correlation": self.correlation.tolist(), "best_code": self.best_code,
                "best_code_rms_mm": self.best_code_rms_mm, "code_rms_mm": self.code_rms_mm,
                "model_evaluations": self.evaluations, "optimizer_evaluations": self.nfev,
                "status": self.status}


def profile_residuals(exp: DeflectionExperiment, log10_Pa, data: list[Profile]) -> np.ndarray:
    """Model minus measured deflection [mm] at the data distances, depth after depth (n_points,)."""
    depths = [p.depth_mm for p in data]
    model = exp.profiles(log10_Pa, depths)
    return np.concatenate([m.at(p.distance_mm) - p.deflection_mm for m, p in zip(model, data)])


def _start(exp: DeflectionExperiment, base: str, free_layers, bounds_log10, start):
    """The checked fit set-up: base log10 moduli (n_layers,), the sorted free layers, their indices, the
    bounds (lo, hi) and the start point (p,) inside them, all in log10 Pa (InputError if invalid)."""
    b = parse_code(base, exp.n_layers)
    free = tuple(sorted({int(k) for k in free_layers}))
    if not free or any(not 1 <= k <= exp.n_layers for k in free):
        raise InputError(f"free layers must be a non-empty subset of 1-{exp.n_layers}, got {list(free_layers)}")
    if len(free) == exp.n_layers:
        raise InputError("fitting every layer is degenerate (only modulus ratios change the deflections): "
                         "hold one layer at its base value")
    idx = np.array(free) - 1
    lo, hi = float(bounds_log10[0]), float(bounds_log10[1])
    if not lo < hi:
        raise InputError(f"bounds must be low < high (log10 Pa), got {bounds_log10}")
    x0 = np.clip(b[idx] if start is None else as_log10(start, exp.n_layers)[idx], lo + 1e-6, hi - 1e-6)
    return b, free, idx, (lo, hi), x0


class _Objective:
    """The fit's residuals (fun) and forward-difference Jacobian (jac) in the free log10 moduli x,
    for scipy's least_squares; `used` holds the ratio keys of the materials it asked for, `trials`
    the rms (mm) of every trial point."""

    def __init__(self, exp: DeflectionExperiment, data: list[Profile], base_log10: np.ndarray, idx: np.ndarray,
                 hi: float, step_log10: float, free_layers):
        self.exp, self.data, self.base, self.idx, self.hi, self.step = exp, data, base_log10, idx, hi, step_log10
        self.free_layers = free_layers
        self.depths = [p.depth_mm for p in data]
        self.used = set()
        self.trials = []

    def full(self, x) -> np.ndarray:
        """All five log10 moduli with the free ones at x."""
        v = self.base.copy()
        v[self.idx] = x
        return v

    def residuals(self, v) -> np.ndarray:
        self.used.add(ratio_key(v))
        return profile_residuals(self.exp, v, self.data)

    def columns(self, x):
        """(steps, points) of the forward-difference Jacobian at x (a step down at the upper bound)."""
        steps = [self.step if v + self.step <= self.hi else -self.step for v in x]
        shifted = [x + h * np.eye(len(x))[j] for j, h in enumerate(steps)]
        return steps, shifted

    def fun(self, x) -> np.ndarray:
        exp = self.exp
        if exp.map is not None:         # the trial point with its columns, in parallel
            exp.evaluate([self.full(x)] + [self.full(xp) for xp in self.columns(x)[1]], self.depths)
        r = self.residuals(self.full(x))
        self.trials.append(float(np.sqrt(np.mean(r ** 2))))
        exp.progress.note(f"fit trial {len(self.trials)}: log10 Pa of layers {list(self.free_layers)} = "
                          f"{np.round(x, 3).tolist()}, rms {self.trials[-1]:.4g} mm, best {min(self.trials):.4g} mm "
                          f"({len(self.used)} distinct materials solved)")
        return r

    def jac(self, x) -> np.ndarray:
        steps, shifted = self.columns(x)
        self.exp.evaluate([self.full(x)] + [self.full(xp) for xp in shifted], self.depths)   # the columns in parallel
        r0 = self.residuals(self.full(x))
        J = np.empty((len(r0), len(x)))
        for j, (h, xp) in enumerate(zip(steps, shifted)):
            J[:, j] = (self.residuals(self.full(xp)) - r0) / h
        return J


def _uncertainty(r: np.ndarray, J: np.ndarray, noise_mm: float | None):
    """One-sigma std (p,) of the free log10 moduli, their correlation (p, p) and the rms
    sensitivity (p,) mm per decade, from the residuals r (n,) mm and the Jacobian J (n, p)."""
    n, p = len(r), J.shape[1]
    s2 = noise_mm ** 2 if noise_mm is not None else float(r @ r) / max(n - p, 1)
    JtJ = J.T @ J
    try:
        cov = s2 * np.linalg.inv(JtJ)
        std = np.sqrt(np.clip(np.diag(cov), 0, None))
        corr = cov / np.outer(std, std)
    except np.linalg.LinAlgError:
        std, corr = np.full(p, np.inf), np.full((p, p), np.nan)
    sens = np.sqrt((J ** 2).mean(axis=0))
    return std, corr, sens


def _rounded_codes(obj: _Objective, x: np.ndarray) -> dict:
    """{material code: rms (mm)} of the integer roundings of the free log10 moduli x (one batch)."""
    codes = {}
    roundings = [obj.full(np.clip(np.array(digits, float), 0, 9))
                 for digits in itertools.product(*[sorted({math.floor(v), math.ceil(v)}) for v in x])]
    obj.exp.evaluate(roundings, obj.depths)
    for v in roundings:
        code = code_of(v)
        if code not in codes:
            rr = obj.residuals(v)
            codes[code] = float(np.sqrt(np.mean(rr ** 2)))
    return codes


def fit_material(exp: DeflectionExperiment, data: list[Profile], base: str = "m43338", free_layers=(2, 3, 4),
                 bounds_log10=(1.0, 7.0), start=None, step_log10: float = 0.02,
                 noise_mm: float | None = None) -> MaterialFit:
    """Fit the log10 moduli [Pa] of `free_layers` to measured profiles (several depths at once),
    the other layers held at `base` (keep one soft layer fixed: only ratios are determined).

    Bounded trust-region least squares (scipy `least_squares`, method 'trf') on the deflection
    residuals at the data distances; forward-difference Jacobian in log10 space (step_log10),
    each point one model solve (cached by ratios). When `exp` has a map (workers), every trial
    point is solved in one batch with the Jacobian columns around it, which the optimizer asks
    for next if it accepts the point (speculation: a rejected point wastes its columns, solved
    alongside), so an iteration is one round of 1 + p solves on the workers instead of a trial
    solve followed by p columns; the integer roundings are one batch. The fit's path and numbers
    do not depend on the map. `evaluations` counts the distinct materials the fit used (not the
    speculative ones). noise_mm: known measurement noise (else estimated from the residuals) for
    the uncertainty.
    """
    b, free, idx, (lo, hi), x0 = _start(exp, base, free_layers, bounds_log10, start)
    obj = _Objective(exp, data, b, idx, hi, step_log10, free_layers)
    sol = least_squares(obj.fun, x0, jac=obj.jac, bounds=(np.full(len(idx), lo), np.full(len(idx), hi)),
                        method="trf", x_scale=1.0, xtol=1e-6, ftol=1e-10, gtol=1e-10, max_nfev=60)
    r = obj.fun(sol.x)
    J = obj.jac(sol.x)
    std, corr, sens = _uncertainty(r, J, noise_mm)
    codes = _rounded_codes(obj, sol.x)
    best = min(codes, key=codes.get)
    return MaterialFit(obj.full(sol.x), free, float(np.sqrt(np.mean(r ** 2))), r, std, 10.0 ** std, sens,
                       corr, best, codes[best], codes, len(obj.used), int(sol.nfev), sol.message)


@dataclass
class ForceScale:
    """Absolute modulus scale from force-depth data at fixed ratios: measured ~ scale * model.

    scale: factor on every layer's modulus; log10_Pa (5,) scaled moduli; model_N (k,) forces of
    the unscaled model; rms_N residual after scaling; match: 'least-squares' or 'deepest'."""
    scale: float
    log10_Pa: np.ndarray
    depths_mm: np.ndarray
    measured_N: np.ndarray
    model_N: np.ndarray
    rms_N: float
    match: str

    def report(self) -> dict:
        return {"scale": self.scale, "scaled_log10_Pa": [round(float(v), 4) for v in self.log10_Pa],
                "scaled_E_Pa": [float(f"{10 ** v:.4g}") for v in self.log10_Pa],
                "nearest_code": code_of(self.log10_Pa), "rms_N": self.rms_N, "match": self.match,
                "depths_mm": self.depths_mm.tolist(), "measured_N": self.measured_N.tolist(),
                "model_N_unscaled": self.model_N.tolist(),
                "model_N_scaled": (self.scale * self.model_N).tolist()}


def fit_force_scale(model_N, measured_N, log10_Pa, depths_mm, match: str = "least-squares") -> ForceScale:
    """Scale every modulus by one factor so that the model forces match measured ones (thesis
    6.2.3 / appendix B: at prescribed depth forces are proportional to the common modulus factor).

    match 'least-squares': scale = sum(F_model F_meas) / sum(F_model^2) over all depths;
    'deepest': forces equal at the deepest depth (the thesis matched the plate at 2 mm)."""
    F, M = np.asarray(model_N, float), np.asarray(measured_N, float)
    if not np.all(F > 0):
        raise InputError("the model carries no force at some data depth (the indentor does not touch): "
                         "check the indentor and its position")
    if match == "least-squares":
        s = float(F @ M / (F @ F))
    elif match == "deepest":
        k = int(np.argmax(depths_mm))
        s = float(M[k] / F[k])
    else:
        raise InputError(f"unknown force match '{match}': use least-squares or deepest")
    if not s > 0:
        raise InputError("the measured forces are all zero: nothing to scale the moduli to")
    v = np.asarray(log10_Pa, float) + math.log10(s)
    return ForceScale(s, v, np.asarray(depths_mm, float), M, F, float(np.sqrt(np.mean((s * F - M) ** 2))), match)
