"""Biomechanical verification (thesis 4.7, 6.2): surface deflection under a line load, the
layer-stiffness study of figure 6-10, waterbed and beam free lengths, and cylinder series.
Fitting layer moduli to measurements is in fem.biomech.fit; the measured-data CSVs are read by
fem.biomech.measured.

Units mm, N, MPa at the API; material codes `mABCDE` (digit k = log10 of layer k's modulus in
Pa) and log10-moduli in Pa where the thesis uses them. A deflection is the surface displacement
along the approach direction, positive into the finger, against the horizontal distance from
the load (perpendicular to the wedge edge, in the plane normal to the approach); profiles are the
mean of both sides of the load unless `side` says otherwise (the thesis averaged the two sides).

Only modulus *ratios* matter for prescribed-displacement contact (thesis appendix B: K scales
with a common factor, the indentation depth fixes the displacements), so a deflection fit
determines ratios and the absolute scale comes from force-depth data. Every material's result is
cached by its modulus ratios, so a study or fit never factorises the same ratios twice; within
one material the contact compliance columns are reused across depths (fem.contact.linear.ContactModel).

    exp = DeflectionExperiment("out/monkey_section")             # wedge at the middle of the pad
    prof = exp.profiles("m43338", [1.0, 2.0])                  # [Profile, ...]
    study = layer_study(exp, "m43338", depths_mm=[2.0])        # thesis figure 6-10
    fit_free_length(prof[1].distance_mm, prof[1].deflection_mm, 2.0, "waterbed")
"""
from __future__ import annotations

import functools
import gc
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import least_squares

from fem.contact.indentors import CYLINDERS_MM, make_indentor
from fem.contact.linear import MAX_DEPTH_MM, ContactModel, tissue_mm
from fem.core.materials import FLUID_LAYER, Material
from fem.geometry.layered import N_LAYERS
from fem.io.modelfolder import CONTACT_REGION, factorise, folder_material, read_model
from fem.verify.closed_forms import beam_deflection, waterbed_deflection
from fingertip.errors import InputError
from fingertip.progress import as_progress


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


def as_log10(material, n_layers: int = N_LAYERS) -> np.ndarray:
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


class DeflectionExperiment:
    """An indentor (default the wedge: a line load) on a model folder; its deflection profiles
    and forces per material, cached by modulus ratios.

    model_dir: folder with mesh.vtu (+ model.json) from `pipeline.py mesh` (2D or 3D).
    indentor: indentor code (default 'wedge'); orientation: default 'parallel' in 2D (the edge
    along z, i.e. the line load of the plane-strain section) and 'perpendicular' in 3D (thesis
    6.2.1); rigid_bone: hold the bone (layer 5) instead of leaving it elastic and free;
    position_mm: (x, z) of the load, default the middle of the pad (2D: the section's
    centroid x); band_mm: 3D only, surface nodes within this distance of the profile line (the
    line through the load across the wedge) make the profile; side: see `side_profile`;
    max_factors: factorised models kept (least recently used dropped; their contact results stay
    cached, only a new depth for them re-factorises) - a 3D factor can take gigabytes.
    progress: optional `fingertip.progress` object (None: silent) shown the factorisations and the
    loops over materials (`layer_study`) and cylinders (`cylinder_series`).
    map: optional `map(fn, items) -> list` (results in the order of items, e.g. on worker
    processes) that `evaluate` hands batches of new materials to, one item per material; the
    workers rebuild this experiment from the model folder once each (`solve_material`). None:
    every material is solved here, when first asked for.
    """
    def __init__(self, model_dir, indentor: str = "wedge", orientation=None, position_mm=None,
                 nu=None, band_mm: float = 0.25, side: str = "mean", rigid_bone: bool = False,
                 max_factors: int = 4, progress=None, map=None):

        self.progress = as_progress(progress)
        self.map = map
        self.args = (str(model_dir), indentor, orientation, None if position_mm is None else tuple(position_mm),
                     nu, band_mm, side, rigid_bone)     # what rebuilds this experiment on a worker (`solve_material`)
        self.model_dir, self.nu, self.band_mm, self.side = model_dir, nu, band_mm, side
        self.rigid_bone = bool(rigid_bone)
        self.indentor_code = indentor
        model, info = read_model(model_dir)
        self._model = model           # the last material's model: the next shares its mesh-only parts
        region = CONTACT_REGION[model.dim]
        self.dim, self.region, self.info = model.dim, region, info
        self.n_layers = int(model.layer[model.layer != FLUID_LAYER].max())    # code digits: layers 1..n
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
        return make_indentor(code, **self._placement)

    def contact_model(self, log10_Pa):
        """(fem.contact.linear.ContactModel of these modulus ratios, force factor): forces and pressures
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
                entry["depth"][d] = _detached(self._solver(key, entry["log10_Pa"]).indent(self.indentor, depth_mm=d))
            out.append((entry["depth"][d], scale))
        return out

    def _solver(self, key, log10_Pa):
        cm = self._solvers.pop(key, None)
        if cm is None:
            cm = self._factorise(log10_Pa)
            while len(self._solvers) >= self.max_factors:
                self._solvers.pop(next(iter(self._solvers)))
                gc.collect()        # a dropped model sits in reference cycles; its factors are GBs in 3D
        self._solvers[key] = cm
        return cm

    def _factorise(self, log10_Pa):
        """A new fem.contact.linear.ContactModel of the model with these log10 moduli [Pa] (one factorisation)."""
        nu = folder_material(self.info)[1] if self.nu is None else self.nu
        model = self._model.with_material(Material(moduli_MPa(log10_Pa), nu=nu, rigid_bone=self.rigid_bone))
        system = factorise(model, self.info, progress=self.progress)
        self._model = model
        self.evaluations += 1
        return ContactModel.from_fe(model, system, self.region)

    def solve(self, log10_Pa, depths_mm) -> list:
        """[fem.contact.linear.ContactResult per depth] of a new factorisation of these moduli, indented
        at the depths [mm] in order and observed as `profiles` would: the results this experiment
        caches for a material it has not seen, picklable (no link back to the factorisation).
        The cache is neither read nor filled."""
        cm = self._factorise(np.asarray(log10_Pa, float))
        out = [_detached(cm.indent(self.indentor, depth_mm=float(d))) for d in depths_mm]
        del cm
        gc.collect()                # free the factorisation now, not at the next cyclic collection
        return out

    def evaluate(self, materials, depths_mm) -> None:
        """Solve the materials (codes or (5,) log10 moduli in Pa) whose modulus ratios are not
        cached, at depths [mm], as one batch through `map` (one task per distinct ratio) and
        cache the results as if solved here (same numbers, same order). Without `map`, or with
        fewer than two new ratios, nothing is done here: they are solved when first asked for."""
        if self.map is None:
            return
        todo = {}
        for material in materials:
            v = as_log10(material, self.n_layers)
            key = ratio_key(v)
            if key not in self._cache:
                todo.setdefault(key, v.copy())
        if len(todo) < 2:
            return
        depths = [float(d) for d in depths_mm]
        with self.progress.task(f"{len(todo)} materials on parallel tasks"):
            results = self.map(solve_material, [(self.args, v, depths) for v in todo.values()])
        for (key, v), res in zip(todo.items(), results):
            self._cache[key] = {"log10_Pa": v, "depth": dict(zip(depths, res))}
        self.evaluations += len(todo)

    def profiles(self, material, depths_mm) -> list[Profile]:
        """Deflection profiles [mm] for a material (code or (5,) log10 moduli in Pa) at depths [mm]."""
        results = self._results(as_log10(material, self.n_layers), depths_mm)
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
        results = self._results(as_log10(material, self.n_layers), depths_mm)
        return np.array([scale * res.total_force_N for res, scale in results])

    def clear(self) -> None:
        """Drop every cached material and factorisation."""
        self._cache.clear()
        self._solvers.clear()


@functools.lru_cache(maxsize=2)
def worker_experiment(args: tuple) -> DeflectionExperiment:
    """The DeflectionExperiment of `DeflectionExperiment.args`, built once per process."""
    return DeflectionExperiment(*args)


def solve_material(item: tuple) -> list:
    """One task of `DeflectionExperiment.evaluate`: item (experiment args, (5,) log10 moduli
    [Pa], depths [mm]) -> [ContactResult per depth] (`DeflectionExperiment.solve`)."""
    args, log10_Pa, depths_mm = item
    return worker_experiment(args).solve(log10_Pa, depths_mm)


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


def idealised_fits(profile: Profile, max_distance_mm=None) -> dict:
    """Waterbed and beam curves fitted to a profile, d0 = its depth: {'waterbed': fit, 'beam': fit}."""
    return {k: fit_free_length(profile.distance_mm, profile.deflection_mm, profile.depth_mm, k,
                               max_distance_mm) for k in ("waterbed", "beam")}



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


def _detached(res):
    """A contact result observed now and cut from its contact model, so that a cached result does
    not keep the model's factorisation alive (a 3D one is about 0.9 GB) after it is dropped."""
    res.deflection_mm            # noqa: B018 - observes the pending indentations
    res._source = None
    return res


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
            if 0 <= v[int(layer) - 1] <= 9:
                codes.append(code_of(v))
        if len(codes) < 2:
            raise InputError(f"layer {layer}: the offsets {list(offsets)} give fewer than two codes "
                             f"with digits 0-9 around {base}")
        study.layers[int(layer)] = codes
    todo = list(dict.fromkeys(c for codes in study.layers.values() for c in codes))
    exp.evaluate(todo, depths_mm)                           # in parallel when exp has a map
    for code in exp.progress.bar(todo, desc="materials", unit="material"):
        study.profiles[code] = exp.profiles(code, depths_mm)
    for layer, codes in study.layers.items():
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


# --------------------------------------------------------------------------- cylinders (thesis figs. 4-24, 4-25, 5-14)
@dataclass
class CylinderSeries:
    """Cylindrical indentors of increasing diameter on one model, at constant forces or depths.

    diameters_mm (k,); loads (j,) the prescribed forces [N; N/mm in 2D] or depths [mm] (load_kind
    'force' or 'depth'); per (j, k): depth_mm, force_N, contact_area_mm2 (2D: contact width in
    mm), max_pressure_MPa (facet-averaged, fem.contact.linear). The thesis: at constant force a larger
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


def _check_series_force(exp, cm, code: str, force: float, limit: float, scale: float) -> None:
    """Refuse, before the series starts, a force the narrowest cylinder does not reach at the
    depth limit (the wider ones push more at a depth)."""
    there = cm.force_at(exp.indentor_for(f"cylinder:{code}"), limit)
    if there is not None and there[0] < force * (1 - 1e-6):
        unit = "N/mm" if exp.dim == 2 else "N"
        raise InputError(f"cylinder series: forces_N {scale * force:g} {unit} is not reached by {code} within "
                         f"{limit:g} mm (the tissue over the bone, at most {MAX_DEPTH_MM:g} mm; the force there "
                         f"is {scale * there[0]:.4g} {unit}): give smaller forces_N")


def cylinder_series(exp: DeflectionExperiment, material, codes=None, forces_N=None, depths_mm=None) -> CylinderSeries:
    """Contact of the catalogue cylinders `codes` (default C1-C8, thesis table 5.1) placed as the
    experiment's indentor, at each force or each depth (one of the two), for a material (code or
    log10 moduli in Pa). One factorisation; the compliance columns are shared by all cylinders."""
    if (forces_N is None) == (depths_mm is None):
        raise InputError("give forces or depths for the cylinder series, not both")
    codes = list(CYLINDERS_MM) if codes is None else [str(c).strip().upper() for c in codes]
    unknown = [c for c in codes if c not in CYLINDERS_MM]
    if unknown or not codes:
        raise InputError(f"unknown cylinder code(s) {unknown}: use {', '.join(CYLINDERS_MM)}")
    kind, loads = ("force", forces_N) if forces_N is not None else ("depth", depths_mm)
    loads = np.asarray(loads, float).ravel()
    if not loads.size or np.any(loads <= 0):
        raise InputError(f"cylinder series {kind}s must be positive, got {', '.join(f'{v:g}' for v in loads)}")
    tissue = tissue_mm(exp._model, exp.points_mm, exp.indentor.approach)
    if kind == "depth" and loads.max() > tissue:
        raise InputError(f"cylinder series: depths_mm {loads.max():g} mm is beyond the {tissue:g} mm of tissue over "
                         f"the bone of this model; give depths_mm up to {tissue:g}")
    limit = min(MAX_DEPTH_MM, tissue)
    cm, scale = exp.contact_model(as_log10(material, exp.n_layers))
    if kind == "force":
        _check_series_force(exp, cm, min(codes, key=CYLINDERS_MM.get), loads.max() / scale, limit, scale)
    out = np.zeros((4, len(loads), len(codes)))
    for k, code in enumerate(exp.progress.bar(codes, desc="cylinders", unit="cylinder")):
        ind = exp.indentor_for(f"cylinder:{code}")
        for j, v in enumerate(loads):
            res = (cm.indent(ind, force_N=v / scale, max_depth_mm=limit) if kind == "force"
                   else cm.indent(ind, depth_mm=v))
            out[:, j, k] = (res.depth_mm.max(), scale * res.total_force_N, res.contact_area_mm2,
                            scale * res.max_pressure_MPa)
    return CylinderSeries(codes, np.array([CYLINDERS_MM[c] for c in codes]), kind, loads, *out)
