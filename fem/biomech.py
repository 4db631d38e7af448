"""Biomechanical verification (thesis 4.7, 6.2): surface deflection under a line load, the
layer-stiffness study of figure 6-10, and fitting layer moduli to measured profiles and forces.

Units mm, N, MPa at the API; material codes `mABCDE` (digit k = log10 of layer k's modulus in
Pa) and log10-moduli in Pa where the thesis uses them. A deflection is the surface displacement
along the approach direction, positive into the finger, against the horizontal distance from
the load (perpendicular to the wedge edge, in the plane normal to the approach); profiles are the
mean of both sides of the load unless `side` says otherwise (the thesis averaged the two sides).

Only modulus *ratios* matter for prescribed-displacement contact (thesis appendix B: K scales
with a common factor, the indentation depth fixes the displacements), so the deflection fit
determines ratios: one soft layer (default layer 1) stays at its base value, and the absolute
scale comes from force-depth data, where forces are proportional to that common factor
(`fit_force_scale`). Every material's result is cached by its modulus ratios, so a study or fit
never factorises the same ratios twice; within one material the contact compliance columns are
reused across depths (fem.contact.ContactModel).

    exp = DeflectionExperiment("out/monkey_section")             # wedge at the middle of the pad
    prof = exp.profiles("m43338", [1.0, 2.0])                  # [Profile, ...]
    study = layer_study(exp, "m43338", depths_mm=[2.0])        # thesis figure 6-10
    fit = fit_material(exp, read_deflection_csv("data.csv"), base="m43338", free_layers=(2, 3, 4))
    fit_free_length(prof[1].distance_mm, prof[1].deflection_mm, 2.0, "waterbed")

CSV inputs (header optional, `#` comments allowed):
    deflection: distance_mm, deflection_mm, depth_mm   (distances increasing within each depth)
    force:      depth_mm, force_N                      (N per mm of thickness for 2D models)
"""
from __future__ import annotations

import itertools
import math
import os
from dataclasses import dataclass, field

import numpy as np

from fem.reference import beam_deflection, waterbed_deflection
from common.errors import InputError

N_LAYERS = 5
BONE_LAYER = 5


# --------------------------------------------------------------------------- codes and moduli
def parse_code(code: str, n_layers: int = N_LAYERS) -> np.ndarray:
    """'m43338' -> (5,) log10 moduli in Pa. One digit per layer, exactly n_layers digits."""
    text = str(code).strip()
    if not (text.startswith("m") and text[1:].isdigit()):
        raise InputError(f"material code '{code}' is not of the form mABCDE (digit k = log10 of layer "
                         f"k's Young's modulus in Pa), e.g. m43338")
    if len(text) - 1 != n_layers:
        raise InputError(f"material code '{code}' has {len(text) - 1} digits; give one digit per layer "
                         f"({n_layers}), e.g. m43338")
    return np.array([float(c) for c in text[1:]])


def code_of(log10_Pa) -> str:
    """(5,) log10 moduli [Pa] -> nearest 'mABCDE' code (digits rounded, clipped to 0-9)."""
    return "m" + "".join(str(int(np.clip(round(float(v)), 0, 9))) for v in log10_Pa)


def moduli_MPa(log10_Pa) -> list[float]:
    return [10.0 ** (float(v) - 6.0) for v in log10_Pa]


def _as_log10(material, n_layers: int = N_LAYERS) -> np.ndarray:
    if isinstance(material, str):
        return parse_code(material, n_layers)
    v = np.asarray(material, float).ravel()
    if v.shape != (n_layers,):
        raise InputError(f"give {n_layers} log10 moduli (Pa), one per layer, got {v.size}")
    return v


def ratio_key(log10_Pa, ndigits: int = 9) -> tuple:
    """Cache key: moduli up to a common factor (deflections under prescribed depth depend on
    ratios only)."""
    v = np.asarray(log10_Pa, float)
    return tuple(np.round(v - v[0], ndigits))


# --------------------------------------------------------------------------- profiles
@dataclass
class Profile:
    """Deflection profile at one indentation depth: distance from the load (n,) mm, increasing
    from 0; deflection (n,) mm along the approach, positive into the finger."""
    depth_mm: float
    distance_mm: np.ndarray
    deflection_mm: np.ndarray
    force_N: float = float("nan")

    def at(self, distance_mm) -> np.ndarray:
        """Deflection [mm] interpolated at distances [mm] (linear); outside the profile -> error."""
        d = np.asarray(distance_mm, float)
        if d.size and d.max() > self.distance_mm[-1] + 1e-9:
            raise InputError(f"data reach {d.max():g} mm from the load but the model surface profile "
                             f"ends at {self.distance_mm[-1]:.3g} mm: drop the far points or use a larger model")
        return np.interp(d, self.distance_mm, self.deflection_mm)


def side_profile(v, w, side: str = "mean") -> tuple[np.ndarray, np.ndarray]:
    """(distance, deflection) from signed positions v (n,) across the load and deflections w (n,).

    side: 'mean' (both sides interpolated on the union of their distances, up to the shorter
    side's reach, and averaged), 'positive' (v >= 0) or 'negative' (v <= 0)."""
    v, w = np.asarray(v, float), np.asarray(w, float)

    def one(sel, sign):
        d, y = sign * v[sel], w[sel]
        order = np.argsort(d, kind="stable")
        d, y = d[order], y[order]
        keep = np.r_[True, np.diff(d) > 1e-12]
        return d[keep], y[keep]

    if side not in ("mean", "positive", "negative"):
        raise InputError(f"unknown side '{side}': use mean, positive or negative")
    if side == "positive":
        return one(v >= 0, 1.0)
    if side == "negative":
        return one(v <= 0, -1.0)
    dp, wp = one(v >= 0, 1.0)
    dn, wn = one(v <= 0, -1.0)
    if len(dp) < 2 or len(dn) < 2:
        raise InputError("the surface profile does not extend to both sides of the load: move the "
                         "load towards the middle of the pad or use side='positive'/'negative'")
    reach = min(dp[-1], dn[-1])
    d = np.union1d(dp[dp <= reach], dn[dn <= reach])
    d = d[d >= max(dp[0], dn[0])]
    return d, 0.5 * (np.interp(d, dp, wp) + np.interp(d, dn, wn))


def _fast_pardiso():
    """pypardiso looks for libmkl_rt with a recursive glob over the venv on every solver it
    creates (~0.5 s each); a study builds dozens. Locate the library once and tell pypardiso."""
    if os.environ.get("PYPARDISO_MKL_RT"):
        return
    try:
        from pypardiso import PyPardisoSolver
    except ImportError:
        return
    name = getattr(PyPardisoSolver().libmkl, "_name", None)
    if name:
        os.environ["PYPARDISO_MKL_RT"] = name


class DeflectionExperiment:
    """An indentor (default the wedge: a line load) on a model folder; its deflection profiles
    and forces per material, cached by modulus ratios.

    model_dir: folder with mesh.vtu (+ model.json) from `pipeline.py mesh` (2D or 3D).
    indentor: indentor code (default 'wedge'); orientation: default 'parallel' in 2D (the edge
    along z, i.e. the line load of the plane-strain section) and 'perpendicular' in 3D (thesis
    6.2.1); position_mm: (x, z) of the load, default the middle of the pad (2D: the section's
    centroid x); band_mm: 3D only, surface nodes within this distance of the profile line (the
    line through the load across the wedge) make the profile; side: see `side_profile`;
    max_factors: factorised models kept (least recently used dropped; their contact results stay
    cached, only a new depth for them re-factorises) - a 3D factor can take gigabytes.
    """

    def __init__(self, model_dir, indentor: str = "wedge", orientation=None, position_mm=None,
                 nu=None, band_mm: float = 0.25, side: str = "mean", max_factors: int = 4):
        from fem.contact import CONTACT_REGION, read_model

        _fast_pardiso()
        self.model_dir, self.nu, self.band_mm, self.side = model_dir, nu, band_mm, side
        self.indentor_code = indentor
        model, info = read_model(model_dir)                         # geometry only
        region = CONTACT_REGION[model.dim]
        self.dim, self.region, self.info = model.dim, region, info
        self.n_layers = len(set(model.layer.tolist()))
        sn = model.surface_nodes(region)
        self.points_mm, self.ndof = sn.x, model.ndof     # contact candidates (ContactModel.from_fe's)
        if self.dim == 2:
            cx = info.get("params", {}).get("centroid_mm", [0.5 * (sn.x[:, 0].min() + sn.x[:, 0].max())])[0]
            pos, orient, place = (cx, 0.0), "parallel", {}
        else:
            pos, orient = (0.0, 0.5 * (sn.x[:, 2].min() + sn.x[:, 2].max())), "perpendicular"
            up = info.get("regions", {}).get("support", {}).get("vertical_up")
            place = {} if up is None else {"approach": -np.asarray(up, float)}
        self._placement = {"orientation": orientation or orient,
                           "position_mm": tuple(position_mm) if position_mm is not None else pos, **place}
        self.indentor = self.indentor_for(indentor)
        self._cache: dict = {}        # ratio key -> {"log10_Pa", "depth": {depth: ContactResult}}
        self._solvers: dict = {}      # ratio key -> ContactModel, least recently used first
        self.max_factors = max(1, int(max_factors))
        self.evaluations = 0          # factorisations done (distinct modulus ratios, plus rebuilds)

    def indentor_for(self, code: str):
        """Indentor `code` placed as this experiment's (orientation, position, approach)."""
        from fem.indentors import make_indentor

        return make_indentor(code, **self._placement)

    def contact_model(self, log10_Pa):
        """(fem.contact.ContactModel of these modulus ratios, force factor): forces and pressures
        of its results times the factor are those of log10_Pa (same ratios, another scale)."""
        key, entry, scale = self._entry(log10_Pa)
        return self._solver(key, entry["log10_Pa"]), scale

    def _entry(self, log10_Pa):
        """(ratio key, cache entry, force factor of log10_Pa against the entry's moduli)."""
        log10_Pa = np.asarray(log10_Pa, float)
        if log10_Pa.size != self.n_layers:
            raise InputError(f"the model has {self.n_layers} layers; give {self.n_layers} moduli "
                             f"(a code with {self.n_layers} digits)")
        key = ratio_key(log10_Pa)
        entry = self._cache.setdefault(key, {"log10_Pa": log10_Pa.copy(), "depth": {}})
        return key, entry, 10.0 ** (log10_Pa[0] - entry["log10_Pa"][0])     # forces scale with the common factor

    def _results(self, log10_Pa, depths_mm):
        key, entry, scale = self._entry(log10_Pa)
        out = []
        for d in depths_mm:
            d = float(d)
            if d not in entry["depth"]:
                entry["depth"][d] = self._solver(key, entry["log10_Pa"]).indent(self.indentor, depth_mm=d)
            out.append((entry["depth"][d], scale))
        return out

    def _solver(self, key, log10_Pa):
        from fem.contact import ContactModel, open_model
        from fem.materials import Material

        cm = self._solvers.pop(key, None)
        if cm is None:
            nu = self.info.get("nu", 0.48) if self.nu is None else self.nu
            model, system, region, _ = open_model(self.model_dir, material=Material(moduli_MPa(log10_Pa), nu=nu))
            cm = ContactModel.from_fe(model, system, region)
            self.evaluations += 1
            while len(self._solvers) >= self.max_factors:
                self._solvers.pop(next(iter(self._solvers)))
        self._solvers[key] = cm
        return cm

    def profiles(self, material, depths_mm) -> list[Profile]:
        """Deflection profiles [mm] for a material (code or (5,) log10 moduli in Pa) at depths [mm]."""
        results = self._results(_as_log10(material, self.n_layers), depths_mm)
        x = np.zeros((len(self.points_mm), 3))
        x[:, :self.points_mm.shape[1]] = self.points_mm
        rel = x - self.indentor.origin_mm
        u, v = rel @ self.indentor.e1, rel @ self.indentor.e2
        on_line = np.ones(len(x), bool) if self.dim == 2 else np.abs(u) <= self.band_mm
        if on_line.sum() < 4:
            raise InputError(f"fewer than 4 surface nodes within {self.band_mm} mm of the profile line: "
                             f"raise band_mm")
        out = []
        for res, scale in results:
            d, w = side_profile(v[on_line], res.deflection_mm[on_line], self.side)
            out.append(Profile(float(res.depth_mm.max()), d, w, scale * res.total_force_N))
        return out

    def forces_N(self, material, depths_mm) -> np.ndarray:
        """(k,) total indentation force [N; N/mm in 2D] at depths [mm] for a material."""
        results = self._results(_as_log10(material, self.n_layers), depths_mm)
        return np.array([scale * res.total_force_N for res, scale in results])

    def clear(self) -> None:
        """Drop every cached material and factorisation."""
        self._cache.clear()
        self._solvers.clear()


# --------------------------------------------------------------------------- CSV input
def _read_table(path, columns: tuple[str, ...]) -> np.ndarray:
    """(n, len(columns)) floats from a CSV with those columns (header optional, any order if
    given; '#' comment lines skipped). Empty or malformed -> InputError."""
    import csv

    try:
        with open(path, newline="") as fh:
            rows = [r for r in csv.reader(fh) if r and not r[0].lstrip().startswith("#")
                    and any(c.strip() for c in r)]
    except OSError as exc:
        raise InputError(f"cannot read '{path}': {exc.strerror}") from None
    want = ", ".join(columns)
    if not rows:
        raise InputError(f"'{path}' has no data rows: expected CSV columns {want}")
    order = list(range(len(columns)))
    head = [c.strip().lower() for c in rows[0]]

    def number(c):
        try:
            float(c)
            return True
        except ValueError:
            return False

    if not any(number(c) for c in head):          # a header row (a row with any number is data)
        missing = [c for c in columns if c.lower() not in head]
        if missing:
            raise InputError(f"'{path}': header {rows[0]} lacks column(s) {missing}; expected {want}")
        order = [head.index(c.lower()) for c in columns]
        rows = rows[1:]
        if not rows:
            raise InputError(f"'{path}' has a header but no data rows: expected CSV columns {want}")
    out = np.empty((len(rows), len(columns)))
    for i, r in enumerate(rows):
        try:
            out[i] = [float(r[j]) for j in order]
        except (ValueError, IndexError):
            raise InputError(f"'{path}' data row {i + 1}: {r} is not {len(columns)} numbers ({want})") from None
    if not np.all(np.isfinite(out)):
        raise InputError(f"'{path}' contains non-finite numbers (nan or inf): remove them")
    return out


def read_deflection_csv(path) -> list[Profile]:
    """Measured deflection profiles: CSV distance_mm, deflection_mm, depth_mm -> one Profile per
    depth (in order of depth). Distances must be >= 0 and strictly increasing within a depth."""
    t = _read_table(path, ("distance_mm", "deflection_mm", "depth_mm"))
    if np.any(t[:, 0] < 0) or np.any(t[:, 2] <= 0):
        raise InputError(f"'{path}': distances must be >= 0 mm and depths > 0 mm")
    out = []
    for d in np.unique(t[:, 2]):
        rows = t[t[:, 2] == d]
        if len(rows) < 2:
            raise InputError(f"'{path}': depth {d:g} mm has a single point; give at least 2 per depth")
        bad = np.flatnonzero(np.diff(rows[:, 0]) <= 0)
        if bad.size:
            raise InputError(f"'{path}': distances are not increasing at depth {d:g} mm "
                             f"({rows[bad[0], 0]:g} then {rows[bad[0] + 1, 0]:g}); sort each depth's rows by distance")
        out.append(Profile(float(d), rows[:, 0], rows[:, 1]))
    return out


def read_force_csv(path) -> tuple[np.ndarray, np.ndarray]:
    """Measured force-depth curve: CSV depth_mm, force_N -> (depths (k,) mm, forces (k,) N)."""
    t = _read_table(path, ("depth_mm", "force_N"))
    if np.any(t[:, 0] <= 0) or np.any(t[:, 1] < 0):
        raise InputError(f"'{path}': depths must be > 0 mm and forces >= 0 N")
    if np.any(np.diff(t[:, 0]) <= 0):
        raise InputError(f"'{path}': depths are not increasing; sort the rows by depth")
    return t[:, 0], t[:, 1]


# --------------------------------------------------------------------------- waterbed and beam fits
@dataclass
class FreeLengthFit:
    """A waterbed (eq. 6.1) or beam (eq. 6.2) curve fitted to a profile: free length L [mm],
    deflection under the load d0 [mm], rms residual [mm] over the n points used; at_bound: the
    length sits at a search bound (0.05 or 200 mm), i.e. the curve cannot describe the profile."""
    kind: str
    length_mm: float
    d0_mm: float
    rms_mm: float
    n_points: int
    at_bound: bool = False

    def __call__(self, distance_mm):
        f = waterbed_deflection if self.kind == "waterbed" else beam_deflection
        return f(distance_mm, self.d0_mm, self.length_mm)


def fit_free_length(distance_mm, deflection_mm, d0_mm=None, kind: str = "waterbed",
                    max_distance_mm=None) -> FreeLengthFit:
    """Fit the free length of the waterbed or beam curve to a deflection profile (least squares).

    d0_mm: deflection under the load (the indentation depth); None fits it too.
    max_distance_mm: use only points this close to the load (the thesis compared near the load).
    The 1-D search is a log grid over 0.05-200 mm refined by bounded least squares, so the kink
    of the waterbed curve at Lw cannot trap it in a poor local minimum.
    """
    from scipy.optimize import least_squares

    if kind not in ("waterbed", "beam"):
        raise InputError(f"unknown idealised model '{kind}': use waterbed or beam")
    x, y = np.asarray(distance_mm, float), np.asarray(deflection_mm, float)
    if max_distance_mm is not None:
        x, y = x[x <= max_distance_mm], y[x <= max_distance_mm]
    if len(x) < 2:
        raise InputError("need at least 2 profile points to fit a free length")
    f = waterbed_deflection if kind == "waterbed" else beam_deflection

    def resid(p):
        return f(x, p[1] if d0_mm is None else d0_mm, p[0]) - y

    d0 = float(y[np.argmin(x)]) if d0_mm is None else float(d0_mm)
    grid = np.geomspace(0.05, 200.0, 241)
    L0 = grid[np.argmin([np.sum(resid([L, d0]) ** 2) for L in grid])]
    p0 = [L0] if d0_mm is not None else [L0, d0]
    lo, hi = ([0.05], [200.0]) if d0_mm is not None else ([0.05, -np.inf], [200.0, np.inf])
    sol = least_squares(lambda p: resid(p if d0_mm is None else [p[0], d0_mm]), p0, bounds=(lo, hi))
    L = float(sol.x[0])
    d0 = float(sol.x[1]) if d0_mm is None else float(d0_mm)
    return FreeLengthFit(kind, L, d0, float(np.sqrt(np.mean(resid([L, d0]) ** 2))), len(x),
                         bool(L < 0.0501 or L > 199.9))


# --------------------------------------------------------------------------- layer study (fig. 6-10)
@dataclass
class LayerEffect:
    """Effect of one layer's modulus on the deflection profile at one depth.

    most_affected_mm: distance where the profiles of the extreme moduli differ most (the
    thesis's graphical rule); difference_mm there (stiffest minus softest: negative = stiffening
    the layer lowers the surface deflection there, i.e. stiffens the finger); neutral_mm:
    distances where that difference changes sign (layer 2's ~1.25 mm point in the thesis)."""
    layer: int
    depth_mm: float
    codes: list
    most_affected_mm: float
    difference_mm: float
    neutral_mm: list


@dataclass
class LayerStudy:
    base: str
    depths_mm: list
    profiles: dict = field(default_factory=dict)      # code -> [Profile per depth]
    layers: dict = field(default_factory=dict)        # layer -> [codes, softest first]
    effects: list = field(default_factory=list)       # [LayerEffect]
    evaluations: int = 0


def layer_study(exp: DeflectionExperiment, base: str = "m43338", layers=(1, 2, 3, 4),
                offsets=(-1, 0, 1), depths_mm=(2.0,)) -> LayerStudy:
    """Vary each layer's modulus by powers of ten (digit offsets) around the base code.

    Codes equal up to a common factor are solved once (the ratio cache of `exp`)."""
    b = parse_code(base, exp.n_layers)
    study = LayerStudy(base, [float(d) for d in depths_mm])
    for layer in layers:
        if not 1 <= int(layer) <= exp.n_layers:
            raise InputError(f"layer {layer} does not exist: the model has layers 1-{exp.n_layers}")
        codes = []
        for off in sorted(set(int(o) for o in offsets)):
            v = b.copy()
            v[int(layer) - 1] += off
            if not 0 <= v[int(layer) - 1] <= 9:
                continue
            code = code_of(v)
            codes.append(code)
            if code not in study.profiles:
                study.profiles[code] = exp.profiles(code, depths_mm)
        if len(codes) < 2:
            raise InputError(f"layer {layer}: the offsets {list(offsets)} give fewer than two codes "
                             f"with digits 0-9 around {base}")
        study.layers[int(layer)] = codes
        for k, depth in enumerate(study.depths_mm):
            lo, hi = study.profiles[codes[0]][k], study.profiles[codes[-1]][k]
            d = np.union1d(lo.distance_mm, hi.distance_mm)
            d = d[d <= min(lo.distance_mm[-1], hi.distance_mm[-1])]
            diff = hi.at(d) - lo.at(d)
            i = int(np.argmax(np.abs(diff)))
            s = np.sign(diff)
            cross = np.flatnonzero((s[:-1] * s[1:] < 0) & (d[:-1] > 0))
            neutral = [float(d[j] - diff[j] * (d[j + 1] - d[j]) / (diff[j + 1] - diff[j])) for j in cross]
            study.effects.append(LayerEffect(int(layer), depth, codes, float(d[i]), float(diff[i]), neutral))
    study.evaluations = exp.evaluations
    return study


# --------------------------------------------------------------------------- fitting moduli
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


def _residuals(exp, log10_Pa, data):
    depths = [p.depth_mm for p in data]
    model = exp.profiles(log10_Pa, depths)
    return np.concatenate([m.at(p.distance_mm) - p.deflection_mm for m, p in zip(model, data)])


def fit_material(exp: DeflectionExperiment, data: list[Profile], base: str = "m43338", free_layers=(2, 3, 4),
                 bounds_log10=(1.0, 7.0), start=None, step_log10: float = 0.02,
                 noise_mm: float | None = None) -> MaterialFit:
    """Fit the log10 moduli [Pa] of `free_layers` to measured profiles (several depths at once),
    the other layers held at `base` (keep one soft layer fixed: only ratios are determined).

    Bounded trust-region least squares (scipy `least_squares`, method 'trf') on the deflection
    residuals at the data distances; forward-difference Jacobian in log10 space (step_log10),
    each point one model solve (cached by ratios). noise_mm: known measurement noise (else
    estimated from the residuals) for the uncertainty.
    """
    from scipy.optimize import least_squares

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
    x0 = np.clip(b[idx] if start is None else _as_log10(start, exp.n_layers)[idx], lo + 1e-6, hi - 1e-6)

    def full(x):
        v = b.copy()
        v[idx] = x
        return v

    def fun(x):
        return _residuals(exp, full(x), data)

    def jac(x):
        r0 = fun(x)
        J = np.empty((len(r0), len(x)))
        for j in range(len(x)):
            h = step_log10 if x[j] + step_log10 <= hi else -step_log10
            xp = x.copy()
            xp[j] += h
            J[:, j] = (fun(xp) - r0) / h
        return J

    sol = least_squares(fun, x0, jac=jac, bounds=(np.full(len(idx), lo), np.full(len(idx), hi)),
                        method="trf", x_scale=1.0, xtol=1e-6, ftol=1e-10, gtol=1e-10, max_nfev=60)
    r = fun(sol.x)
    J = jac(sol.x)
    n, p = len(r), len(sol.x)
    s2 = noise_mm ** 2 if noise_mm is not None else float(r @ r) / max(n - p, 1)
    JtJ = J.T @ J
    try:
        cov = s2 * np.linalg.inv(JtJ)
        std = np.sqrt(np.clip(np.diag(cov), 0, None))
        corr = cov / np.outer(std, std)
    except np.linalg.LinAlgError:
        std, corr = np.full(p, np.inf), np.full((p, p), np.nan)
    sens = np.sqrt((J ** 2).mean(axis=0))
    codes = {}
    for digits in itertools.product(*[sorted({math.floor(v), math.ceil(v)}) for v in sol.x]):
        v = full(np.clip(np.array(digits, float), 0, 9))
        code = code_of(v)
        if code not in codes:
            rr = _residuals(exp, v, data)
            codes[code] = float(np.sqrt(np.mean(rr ** 2)))
    best = min(codes, key=codes.get)
    return MaterialFit(full(sol.x), free, float(np.sqrt(np.mean(r ** 2))), r, std, 10.0 ** std, sens,
                       corr, best, codes[best], codes, exp.evaluations, int(sol.nfev), sol.message)


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


# --------------------------------------------------------------------------- cylinders (thesis figs. 4-24, 4-25, 5-14)
@dataclass
class CylinderSeries:
    """Cylindrical indentors of increasing diameter on one model, at constant forces or depths.

    diameters_mm (k,); loads (j,) the prescribed forces [N; N/mm in 2D] or depths [mm] (load_kind
    'force' or 'depth'); per (j, k): depth_mm, force_N, contact_area_mm2 (2D: contact width in
    mm), max_pressure_MPa (facet-averaged, fem.contact). The thesis: at constant force a larger
    cylinder makes a wider contact and a lower peak pressure (fig. 4-25, 2D), and at a fixed depth
    a larger contact area (fig. 5-14, human fingertip)."""
    codes: list
    diameters_mm: np.ndarray
    load_kind: str
    loads: np.ndarray
    depth_mm: np.ndarray
    force_N: np.ndarray
    contact_area_mm2: np.ndarray
    max_pressure_MPa: np.ndarray

    def report(self) -> dict:
        return {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in self.__dict__.items()}


def cylinder_series(exp: DeflectionExperiment, material, codes=None, forces_N=None, depths_mm=None) -> CylinderSeries:
    """Contact of the catalogue cylinders `codes` (default C1-C8, thesis table 5.1) placed as the
    experiment's indentor, at each force or each depth (one of the two), for a material (code or
    log10 moduli in Pa). One factorisation; the compliance columns are shared by all cylinders."""
    from fem.indentors import CYLINDERS_MM

    if (forces_N is None) == (depths_mm is None):
        raise InputError("give forces or depths for the cylinder series, not both")
    codes = list(CYLINDERS_MM) if codes is None else [str(c).strip().upper() for c in codes]
    unknown = [c for c in codes if c not in CYLINDERS_MM]
    if unknown or not codes:
        raise InputError(f"unknown cylinder code(s) {unknown}: use {', '.join(CYLINDERS_MM)}")
    kind, loads = ("force", forces_N) if forces_N is not None else ("depth", depths_mm)
    loads = np.asarray(loads, float).ravel()
    if not loads.size or np.any(loads <= 0):
        raise InputError(f"cylinder series {kind}s must be positive, got {loads.tolist()}")
    cm, scale = exp.contact_model(_as_log10(material, exp.n_layers))
    out = np.zeros((4, len(loads), len(codes)))
    for k, code in enumerate(codes):
        ind = exp.indentor_for(f"cylinder:{code}")
        for j, v in enumerate(loads):
            res = cm.indent(ind, force_N=v / scale) if kind == "force" else cm.indent(ind, depth_mm=v)
            out[:, j, k] = (res.depth_mm.max(), scale * res.total_force_N, res.contact_area_mm2,
                            scale * res.max_pressure_MPa)
    return CylinderSeries(codes, np.array([CYLINDERS_MM[c] for c in codes]), kind, loads, *out)


# --------------------------------------------------------------------------- command back ends
def _parse_ints(text, what) -> list[int]:
    try:
        return [int(t) for t in str(text).replace(" ", "").split(",") if t]
    except ValueError:
        raise InputError(f"bad {what} '{text}': give integers separated by commas, e.g. 1,2,3") from None


def _parse_floats(text, what) -> list[float]:
    from fem.contact import parse_values

    vals = parse_values(text)
    if not len(vals) or np.any(vals <= 0):
        raise InputError(f"bad {what} '{text}': give positive values in mm, e.g. 2.0 or 0.5:2:0.5")
    return [float(v) for v in vals]


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def _profile_axes(plt, title):
    fig, ax = plt.subplots(1, 2, figsize=(11, 4))
    ax[0].set(xlabel="distance from the load, mm", ylabel="deflection, mm (into the finger +)", title=title)
    ax[1].set(xlabel="distance from the load, mm (log)", title=title + " (log distance)")
    ax[1].set_xscale("log")
    return fig, ax


def _plot_data(ax, data, label="data"):
    for p in data:
        pos = p.distance_mm > 0
        for a in ax:
            a.plot(p.distance_mm[pos] if a.get_xscale() == "log" else p.distance_mm,
                   p.deflection_mm[pos] if a.get_xscale() == "log" else p.deflection_mm,
                   "kx", ms=5, label=f"{label} {p.depth_mm:g} mm")


def _plot_profile(ax, p, style="-", label=""):
    pos = p.distance_mm > 0
    ax[0].plot(p.distance_mm, p.deflection_mm, style, label=label)
    ax[1].plot(p.distance_mm[pos], p.deflection_mm[pos], style, label=label)


def idealised_fits(profile: Profile, max_distance_mm=None) -> dict:
    """Waterbed and beam curves fitted to a profile, d0 = its depth: {'waterbed': fit, 'beam': fit}."""
    return {k: fit_free_length(profile.distance_mm, profile.deflection_mm, profile.depth_mm, k,
                               max_distance_mm) for k in ("waterbed", "beam")}


def _finish(plt, fig, ax, data, path):
    """Add the measured profiles (if any) and legends to the axes and save the figure."""
    _plot_data(ax, data)
    for a in ax:
        a.legend(fontsize=6)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def _plot_idealised(ax, fits, reach):
    x = np.linspace(0, reach, 400)
    for kind, f in fits.items():
        lab = f"{kind} L={f.length_mm:.3g} mm" + (" (at bound)" if f.at_bound else "")
        _plot_profile(ax, Profile(f.d0_mm, x, f(x)), ":" if kind == "waterbed" else "--", lab)


def _write_csv(path, header, rows):
    import csv

    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(header)
        w.writerows([[f"{v:.9g}" if isinstance(v, float) else v for v in r] for r in rows])


def _experiment(model_dir, indentor, orientation, position_mm, nu, side):
    return DeflectionExperiment(model_dir, indentor=indentor, orientation=orientation,
                                position_mm=position_mm, nu=nu, side=side)


def run_study_layers(model_dir, out_dir, base=None, layers="1,2,3,4", offsets="-1,0,1", depths="2.0",
                     indentor="wedge", orientation=None, position_mm=None, nu=None, side="mean",
                     data_csv=None) -> str:
    """`pipeline.py study-layers`: layer_study.csv / .json / .png and profile.png in out_dir."""
    import time

    from common.staging import staged_output, write_json

    t0 = time.perf_counter()
    data = read_deflection_csv(data_csv) if data_csv else []
    exp = _experiment(model_dir, indentor, orientation, position_mm, nu, side)
    base = base or exp.info.get("material", "m43338")
    depth_list = _parse_floats(depths, "depths")
    study = layer_study(exp, base, _parse_ints(layers, "layers"), _parse_ints(offsets, "offsets"), depth_list)
    base_prof = exp.profiles(base, depth_list)
    fits = [idealised_fits(p) for p in base_prof]
    plt = _plt()
    with staged_output(out_dir) as tmp:
        rows = [[code, p.depth_mm, float(d), float(w)] for code, profs in study.profiles.items()
                for p in profs for d, w in zip(p.distance_mm, p.deflection_mm)]
        _write_csv(tmp / "layer_study.csv", ["code", "depth_mm", "distance_mm", "deflection_mm"], rows)
        summary = {"model": str(model_dir), "indentor": exp.indentor.name, "base": base, "depths_mm": depth_list,
                   "side": side, "layers": {str(k): v for k, v in study.layers.items()},
                   "effects": [e.__dict__ for e in study.effects],
                   "force_N": {c: [p.force_N for p in ps] for c, ps in study.profiles.items()},
                   "force_unit": "N per mm (2D plane strain)" if exp.dim == 2 else "N",
                   "idealised_fits_of_base": [{k: f.__dict__ for k, f in fd.items()} for fd in fits],
                   "distinct_moduli_ratios_solved": study.evaluations,
                   "seconds": round(time.perf_counter() - t0, 2)}
        write_json(tmp / "layer_study.json", summary)
        k_last = len(depth_list) - 1
        fig, axes = plt.subplots(len(study.layers), 2, figsize=(11, 3.2 * len(study.layers)), squeeze=False)
        for row, (layer, codes) in zip(axes, study.layers.items()):
            row[1].set_xscale("log")
            for code in codes:
                _plot_profile(row, study.profiles[code][k_last], "-", code)
            _plot_data(row, [p for p in data if abs(p.depth_mm - depth_list[k_last]) < 1e-9])
            eff = next(e for e in study.effects if e.layer == layer and e.depth_mm == depth_list[k_last])
            for a in row:
                a.axvline(eff.most_affected_mm, color="0.6", lw=0.8)
                a.legend(fontsize=7)
            row[0].set(ylabel=f"layer {layer}: deflection, mm",
                       title=f"layer {layer}, depth {depth_list[k_last]:g} mm: most affected at "
                             f"{eff.most_affected_mm:.2f} mm")
        axes[-1, 0].set_xlabel("distance from the load, mm")
        axes[-1, 1].set_xlabel("distance from the load, mm (log)")
        fig.tight_layout()
        fig.savefig(tmp / "layer_study.png", dpi=100)
        plt.close(fig)
        fig, ax = _profile_axes(plt, f"{base}: deflection profile")
        for p, fd in zip(base_prof, fits):
            _plot_profile(ax, p, "-", f"model {p.depth_mm:g} mm")
            _plot_idealised(ax, fd, p.distance_mm[-1])
        _finish(plt, fig, ax, data, tmp / "profile.png")
    lines = [f"layer study around {base} in {out_dir} ({summary['seconds']} s, "
             f"{study.evaluations} distinct modulus ratios solved)"]
    for e in study.effects:
        lines.append(f"  layer {e.layer} ({e.codes[0]}..{e.codes[-1]}) at {e.depth_mm:g} mm: most affected "
                     f"{e.most_affected_mm:.2f} mm from the load (stiffer layer: {e.difference_mm:+.3f} mm)"
                     + (f", neutral at {', '.join(f'{n:.2f}' for n in e.neutral_mm)} mm" if e.neutral_mm else ""))
    for p, fd in zip(base_prof, fits):
        lines.append(f"  {base} at {p.depth_mm:g} mm: waterbed Lw {fd['waterbed'].length_mm:.3g} mm "
                     f"(rms {fd['waterbed'].rms_mm:.3g}), beam Lb {fd['beam'].length_mm:.3g} mm "
                     f"(rms {fd['beam'].rms_mm:.3g}); Lw/Lb {fd['waterbed'].length_mm / fd['beam'].length_mm:.2f} "
                     f"(8/3 near the load)")
    return "\n".join(lines)


def run_fit_material(model_dir, out_dir, deflection_csv=None, force_csv=None, keep_ratios=False, base=None,
                     free_layers="2,3,4", bounds=(1.0, 7.0), indentor="wedge", orientation=None,
                     position_mm=None, force_indentor="plate", match="least-squares", nu=None,
                     side="mean", noise_mm=None) -> str:
    """`pipeline.py fit-material`: fit.json, fit_profiles.csv, fit_profiles.png, force_fit.png."""
    import time

    from common.staging import staged_output, write_json

    if deflection_csv is None and force_csv is None:
        raise InputError("fit-material needs --deflection CSV and/or --force CSV")
    t0 = time.perf_counter()
    data = read_deflection_csv(deflection_csv) if deflection_csv else None
    forces = read_force_csv(force_csv) if force_csv else None
    exp = _experiment(model_dir, indentor, orientation, position_mm, nu, side)
    base = base or exp.info.get("material", "m43338")
    base_v = parse_code(base, exp.n_layers)
    report, fit, scale = {"model": str(model_dir), "base": base}, None, None
    if data is not None:
        fit = fit_material(exp, data, base, _parse_ints(free_layers, "free layers"), bounds, noise_mm=noise_mm)
        report["deflection_fit"] = {**fit.report(), "indentor": exp.indentor.name,
                                    "depths_mm": [p.depth_mm for p in data], "side": side}
        report["deflection_fit"]["base_rms_mm"] = float(np.sqrt(np.mean(_residuals(exp, base_v, data) ** 2)))
    if forces is not None:
        ratios = base_v if keep_ratios or fit is None else fit.log10_Pa
        fexp = exp if force_indentor == indentor else _experiment(model_dir, force_indentor, orientation,
                                                                  position_mm, nu, side)
        scale = fit_force_scale(fexp.forces_N(ratios, forces[0]), forces[1], ratios, forces[0], match)
        report["force_fit"] = {**scale.report(), "indentor": fexp.indentor.name, "ratios_from":
                               "base material" if ratios is base_v else "deflection fit",
                               "force_unit": "N per mm (2D plane strain)" if exp.dim == 2 else "N"}
    report["seconds"] = round(time.perf_counter() - t0, 2)
    plt = _plt()
    with staged_output(out_dir) as tmp:
        write_json(tmp / "fit.json", report)
        if fit is not None:
            depths = [p.depth_mm for p in data]
            best, start = exp.profiles(fit.log10_Pa, depths), exp.profiles(base_v, depths)
            rows = [[p.depth_mm, float(d), float(y), float(b.at(d)), float(s.at(d))]
                    for p, b, s in zip(data, best, start) for d, y in zip(p.distance_mm, p.deflection_mm)]
            _write_csv(tmp / "fit_profiles.csv", ["depth_mm", "distance_mm", "measured_mm", "fitted_mm",
                                                  "base_mm"], rows)
            fig, ax = _profile_axes(plt, "deflection fit")
            for p, b, s in zip(data, best, start):
                _plot_profile(ax, b, "-", f"fit {p.depth_mm:g} mm")
                _plot_profile(ax, s, "-.", f"{base} {p.depth_mm:g} mm")
                _plot_idealised(ax, idealised_fits(p), p.distance_mm[-1])
            _finish(plt, fig, ax, data, tmp / "fit_profiles.png")
        if scale is not None:
            fig, a = plt.subplots(figsize=(5, 4))
            a.plot(scale.depths_mm, scale.measured_N, "kx", label="measured")
            a.plot(scale.depths_mm, scale.scale * scale.model_N, "o-", label=f"model x {scale.scale:.3g}")
            a.set(xlabel="depth_mm", ylabel="force_N", title="force scale")
            a.legend()
            fig.tight_layout()
            fig.savefig(tmp / "force_fit.png", dpi=100)
            plt.close(fig)
    lines = [f"fit-material results in {out_dir} ({report['seconds']} s)"]
    if fit is not None:
        free = ", ".join(f"layer {k}: 10^{fit.log10_Pa[k - 1]:.2f} Pa (uncertainty factor {f:.3g})"
                         for k, f in zip(fit.free_layers, fit.factor))
        lines += [f"  deflection fit ({len(fit.residuals_mm)} points, rms {fit.rms_mm:.3g} mm; base {base} rms "
                  f"{report['deflection_fit']['base_rms_mm']:.3g} mm): {free}",
                  f"  best code {fit.best_code} (rms {fit.best_code_rms_mm:.3g} mm); "
                  f"{fit.evaluations} distinct modulus ratios solved"]
    if scale is not None:
        lines.append(f"  force scale x{scale.scale:.4g} ({scale.match}): moduli "
                     + ", ".join(f"{10 ** v:.3g}" for v in scale.log10_Pa)
                     + f" Pa (nearest code {code_of(scale.log10_Pa)}), rms {scale.rms_N:.3g} "
                     + ("N/mm" if exp.dim == 2 else "N"))
    return "\n".join(lines)


def run_contact_series(model_dir, out_dir, material=None, cylinders=None, forces=None, depths=None,
                       orientation=None, position_mm=None, nu=None) -> str:
    """`pipeline.py contact-series`: cylinder_series.csv / .json / .png in out_dir."""
    import time

    from common.staging import staged_output, write_json

    if (forces is None) == (depths is None):
        raise InputError("contact-series needs --force or --depth (one of the two)")
    t0 = time.perf_counter()
    loads = _parse_floats(forces if forces is not None else depths, "forces" if forces is not None else "depths")
    codes = None if cylinders is None else [c for c in str(cylinders).replace(" ", "").split(",") if c]
    exp = _experiment(model_dir, "wedge", orientation, position_mm, nu, "mean")
    material = material or exp.info.get("material", "m43338")
    s = cylinder_series(exp, material, codes, **({"forces_N": loads} if forces is not None else {"depths_mm": loads}))
    unit = "N per mm (2D plane strain)" if exp.dim == 2 else "N"
    force_unit = "N/mm" if exp.dim == 2 else "N"
    area = "contact width, mm" if exp.dim == 2 else "contact area, mm^2"
    plt = _plt()
    with staged_output(out_dir) as tmp:
        rows = [[c, float(dm), s.load_kind, float(v), float(s.depth_mm[j, k]), float(s.force_N[j, k]),
                 float(s.contact_area_mm2[j, k]), float(s.max_pressure_MPa[j, k])]
                for j, v in enumerate(s.loads) for k, (c, dm) in enumerate(zip(s.codes, s.diameters_mm))]
        _write_csv(tmp / "cylinder_series.csv", ["code", "diameter_mm", "load", "load_value", "depth_mm", "force_N",
                                                 "contact_area_mm2", "max_pressure_MPa"], rows)
        write_json(tmp / "cylinder_series.json", {"model": str(model_dir), "material": material, "force_unit": unit,
                                                  "contact_area_unit": "mm (width, 2D)" if exp.dim == 2 else "mm^2",
                                                  **s.report(), "seconds": round(time.perf_counter() - t0, 2)})
        fig, ax = plt.subplots(1, 3, figsize=(14, 4))
        for j, v in enumerate(s.loads):
            lab = f"{v:g} " + (force_unit if s.load_kind == "force" else "mm")
            ax[0].plot(s.diameters_mm, s.contact_area_mm2[j], "o-", label=lab)
            ax[1].plot(s.diameters_mm, s.max_pressure_MPa[j], "o-", label=lab)
            ax[2].plot(s.diameters_mm, s.depth_mm[j] if s.load_kind == "force" else s.force_N[j], "o-", label=lab)
        ax[0].set(xlabel="cylinder diameter, mm", ylabel=area, title=f"contact vs diameter at constant {s.load_kind}")
        ax[1].set(xlabel="cylinder diameter, mm", ylabel="max contact pressure, MPa", title="peak pressure")
        ax[2].set(xlabel="cylinder diameter, mm",
                  ylabel="depth, mm" if s.load_kind == "force" else f"force, {force_unit}",
                  title="depth needed" if s.load_kind == "force" else "force needed")
        _finish(plt, fig, ax, [], tmp / "cylinder_series.png")
    lines = [f"cylinder series {', '.join(s.codes)} ({material}, constant {s.load_kind}) in {out_dir} "
             f"({time.perf_counter() - t0:.1f} s)"]
    for j, v in enumerate(s.loads):
        lines.append(f"  {v:g} {force_unit if s.load_kind == 'force' else 'mm'}: {area} "
                     + " ".join(f"{a:.3g}" for a in s.contact_area_mm2[j]) + "; max pressure MPa "
                     + " ".join(f"{p:.3g}" for p in s.max_pressure_MPa[j]))
    return "\n".join(lines)


def run_line_load(model_dir, out_dir, depths="0.05,0.5,1,2", material=None, nu=None, large_deformation=False,
                  slip=False, half_width_mm=0.25, half_length_mm=1.0, step_mm=0.1, position_mm=None,
                  progress=False) -> str:
    """`pipeline.py line-load`: line_load.csv / .json / .png in out_dir (linear; with
    large_deformation also the neo-Hookean solve and where the two part)."""
    import json
    import time
    from pathlib import Path

    from fem.nonlinear import compare_line_load
    from common.staging import staged_output, write_json

    t0 = time.perf_counter()
    depth_list = _parse_floats(depths, "depths")
    folder = Path(model_dir)
    info = json.loads((folder / "model.json").read_text()) if (folder / "model.json").is_file() else {}
    material = material or info.get("material", "m43338")
    parse_code(material)
    c = compare_line_load(model_dir, depth_list, material=material, nu=nu, half_width_mm=half_width_mm,
                          step_mm=step_mm, position_mm=position_mm, slip=slip, half_length_mm=half_length_mm,
                          large_deformation=large_deformation, progress=progress)
    plt = _plt()
    with staged_output(out_dir) as tmp:
        rows = [[float(d), float(x), float(a), float(b)] for k, d in enumerate(c.depths_mm)
                for x, a, b in zip(c.distance_mm, c.deflection_linear_mm[k], c.deflection_nonlinear_mm[k])]
        _write_csv(tmp / "line_load.csv", ["depth_mm", "distance_mm", "linear_mm", "nonlinear_mm"], rows)
        report = {"model": str(model_dir), "material": material, "large_deformation": large_deformation,
                  "slip": slip, "half_width_mm": half_width_mm, "step_mm": step_mm,
                  "depths_mm": c.depths_mm.tolist(), "force_linear_N": c.force_linear_N.tolist(),
                  "force_nonlinear_N": c.force_nonlinear_N.tolist(), "max_difference": c.max_difference.tolist(),
                  "min_J": c.min_J.tolist(), "newton_iterations_last_step": [len(h) for h in c.newton],
                  "nonlinear_seconds": c.seconds.tolist(), "failed": {str(k): v for k, v in c.failed.items()},
                  "force_unit": "N per mm (2D plane strain)" if c.dim == 2 else "N",
                  "seconds": round(time.perf_counter() - t0, 2)}
        write_json(tmp / "line_load.json", report)
        fig, ax = plt.subplots(1, 2, figsize=(12, 4))
        for k, d in enumerate(c.depths_mm):
            line = ax[0].plot(c.distance_mm, c.deflection_linear_mm[k], "-", label=f"linear {d:g} mm")[0]
            if large_deformation:
                ax[0].plot(c.distance_mm, c.deflection_nonlinear_mm[k], "--", color=line.get_color(),
                           label=f"large deformation {d:g} mm")
        ax[0].set(xlabel="undeformed distance from the load, mm", ylabel="deflection, mm (into the finger +)",
                  title="surface deflection under the line load")
        ax[1].plot(c.depths_mm, c.force_linear_N, "o-", label="linear")
        if large_deformation:
            ax[1].plot(c.depths_mm, c.force_nonlinear_N, "s--", label="large deformation")
        ax[1].set(xlabel="depth, mm", ylabel="force, " + ("N/mm" if c.dim == 2 else "N"), title="force vs depth")
        _finish(plt, fig, ax, [], tmp / "line_load.png")
    lines = [f"line load on {model_dir} ({material}, patch half width {half_width_mm:g} mm, "
             f"{'sliding' if slip else 'held'} sideways) in {out_dir} ({report['seconds']} s)"]
    for k, d in enumerate(c.depths_mm):
        text = f"  {d:g} mm: force linear {c.force_linear_N[k]:.4g}"
        if float(d) in c.failed:
            text += f"; large deformation failed: {c.failed[float(d)]}"
        elif large_deformation:
            ratio = c.force_nonlinear_N[k] / c.force_linear_N[k]
            text += (f", large deformation {c.force_nonlinear_N[k]:.4g} (x{ratio:.3f}); max deflection difference "
                     f"{100 * c.max_difference[k]:.1f} % of the depth; min J {c.min_J[k]:.2f}; {c.seconds[k]:.1f} s")
        lines.append(text)
    return "\n".join(lines)
