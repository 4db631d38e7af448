"""Receptor analysis (SPEC.md section 5, thesis 3.6, 4.2-4.5, 6.3): from indentation results to
what a neurophysiologist compares with recordings.

Linear receptor model (thesis eq. 4.1): the discharge rate at stimulus position i is

    d_i = a S_i + b

with S_i a candidate measure at the receptor (one receptor, the stimulus stepped: the *spatial
response profile*). a and b are least-squares values, which maximise the thesis goodness

    R^2 = (sum d_i^2 - sum e_i^2) / sum d_i^2,     e_i = d_i - (a S_i + b)

(uncentred: it is high whenever the rates are far from zero, so compare candidates with it, not
with 0). RMS error = sqrt(mean e_i^2) imp/s (thesis tables 4.3-4.4 rank by it). Free parameters:
receptor depth (the depths of the indentation run inside 0.5-1.0 mm) and, with two 2D runs of
different model diameters (8 and 16 mm), the diameter, the fields of intermediate diameters
being the linear interpolation of the two runs' fields (thesis 4.5.3).

Candidates are `fem.measures` names, or `abs:<name>` for the magnitude of a signed one
(`abs:strain_xy` is the thesis's "absolute shear strain"). `THESIS_CANDIDATES` is the list of
thesis tables 4.1-4.4.

    runs = {8.0: IndentRun("out/cyl8/gratings"), 16.0: IndentRun("out/cyl16/gratings")}
    neural = read_neural_csv("data/sa1_gratings.csv")
    table = rank_candidates(runs, neural)                      # combined data, best first
    fit = fit_measure(runs, neural, "sed_MPa", fit_stimuli=["step1"])
    fit.evaluate(runs, neural.only(stimuli=["step3"]))         # R^2, RMS on unseen stimuli

In-process 2D experiments (`Probe2D`): receptors at exact points below the surface, receptive
fields from a point-load sweep, two-point intensive cues under equal displacement and equal
force, shear-strain peaks across grating gaps.
"""
from __future__ import annotations

import csv
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from fem.measures import MEASURES
from fem.neural import NeuralData
from common.errors import InputError

DEPTH_RANGE_MM = (0.5, 1.0)
RECEPTOR_COLUMNS = ("step", "site", "x_mm", "y_mm", "z_mm", "depth_mm")
"""Columns of `<name>_receptors.csv` that are not measures."""
DIAMETER_STEP_MM = 1.0
THESIS_CANDIDATES = {
    "sed_MPa": "strain energy density",
    "max_compressive_strain": "max. compressive strain",
    "abs:stress_xy_MPa": "shear stress",
    "abs:strain_xy": "shear strain",
    "max_tensile_strain": "max. tensile strain",
    "principal_stress_3_MPa": "max. compressive stress",
    "strain_xx": "horizontal strain",
    "strain_yy": "vertical strain",
    "stress_yy_MPa": "vertical stress",
    "stress_zz_MPa": "axial stress",
    "principal_stress_1_MPa": "max. tensile stress",
    "stress_xx_MPa": "horizontal stress",
    "mean_stress_MPa": "mean stress",
}
"""Candidate relevant stimuli of thesis tables 4.1-4.4 (+ mean stress, SPEC 5) -> thesis name."""


def base_measure(candidate: str) -> str:
    """Registry name behind a candidate ('abs:strain_xy' -> 'strain_xy'); InputError if unknown."""
    name = candidate[4:] if candidate.startswith("abs:") else candidate
    if name not in MEASURES:
        raise InputError(f"unknown measure '{candidate}': use a fem.measures name (e.g. sed_MPa, "
                         f"max_compressive_strain) or abs:<name>; known: {', '.join(MEASURES)}")
    return name


def check_candidates(candidates) -> list[str]:
    out = list(candidates)
    for c in out:
        base_measure(c)
    return out


# --------------------------------------------------------------------------- indentation results
class IndentRun:
    """The results folder of `pipeline.py indent`: per experiment `<name>.csv` (one row per
    indentation, `offset_x_mm`, `offset_z_mm`, ...), `<name>_receptors.csv` (per indentation
    every receptor point: site, x_mm, y_mm, z_mm, depth_mm and the measures the run computed) and
    `run.json` (model, indentor, sweep axis, receptors; see README "Indentation").

    Receptor sites are identified by the `site` column (the same id at every depth, step and
    position). `diameter_mm` (2D cylinders) and each stimulus's sweep axis come from run.json.
    Folders written before run.json and the site column still load: sites by row order (depth
    by depth), the diameter from `../model.json`, the sweep axis from the larger offset range."""

    def __init__(self, folder, diameter_mm: float | None = None):
        import json

        self.folder = Path(folder)
        if not self.folder.is_dir():
            raise InputError(f"no indentation results folder '{folder}': run `pipeline.py indent` first")
        self.stimuli = sorted(p.name[:-len("_receptors.csv")] for p in self.folder.glob("*_receptors.csv")
                              if (self.folder / (p.name[:-len("_receptors.csv")] + ".csv")).is_file())
        if not self.stimuli:
            raise InputError(f"'{folder}' holds no <name>.csv + <name>_receptors.csv pairs from "
                             f"`pipeline.py indent`")
        record = self.folder / "run.json"
        try:
            self.run = json.loads(record.read_text()) if record.is_file() else None
            self._experiments = {e["name"]: e for e in self.run["experiments"]} if self.run else {}
        except (ValueError, KeyError, TypeError):
            raise InputError(f"'{record}' is not a run.json written by `pipeline.py indent`") from None
        if diameter_mm is None:
            if self.run is not None:
                diameter_mm = self.run.get("model", {}).get("diameter_mm")
            elif (self.folder.parent / "model.json").is_file():
                diameter_mm = json.loads((self.folder.parent / "model.json").read_text()).get(
                    "params", {}).get("diameter_mm")
        self.diameter_mm = None if diameter_mm is None else float(diameter_mm)
        self._cache = {}

    def sweep_axis(self, stimulus) -> str | None:
        """'x' or 'z' for a sweep, None for fixed positions or a stimulus run.json does not list
        (a folder keeps the files of earlier runs; run.json describes the last one)."""
        sweep = self._experiments.get(stimulus, {}).get("sweep")
        return None if sweep is None else sweep["axis"]

    def __repr__(self):
        return f"IndentRun('{self.folder}', stimuli={self.stimuli}, diameter_mm={self.diameter_mm})"

    def _load(self, stimulus):
        if stimulus in self._cache:
            return self._cache[stimulus]
        if stimulus not in self.stimuli:
            raise InputError(f"stimulus '{stimulus}' is not in '{self.folder}': it holds {self.stimuli} "
                             f"(the neural CSV's stimulus must name an indentation experiment)")
        steps = _read_csv(self.folder / f"{stimulus}.csv")
        offx = np.array([float(r["offset_x_mm"]) for r in steps])
        offz = np.array([float(r["offset_z_mm"]) for r in steps])
        if stimulus in self._experiments:
            along_z = self.sweep_axis(stimulus) == "z"
        else:                       # not recorded: the axis with the larger offset range
            along_z = np.ptp(offz) > np.ptp(offx)
        position = offz if along_z else offx
        path = self.folder / f"{stimulus}_receptors.csv"
        with open(path) as fh:
            header = fh.readline().strip().split(",")
        table = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
        step = table[:, 0].astype(int)
        n_steps = len(steps)
        per = np.bincount(step, minlength=n_steps)
        if per.min() != per.max() or per[0] == 0:
            raise InputError(f"'{stimulus}_receptors.csv' does not hold the same receptor points for every step")
        n = per[0]
        has_site = "site" in header
        keys = (table[:, header.index("depth_mm")], table[:, header.index("site")], step) if has_site else (step,)
        table = table[np.lexsort(keys)]     # by step (then site and depth: row order does not matter)
        cols = {h: table[:, k].reshape(n_steps, n) for k, h in enumerate(header)}
        depth = cols["depth_mm"][0]
        depths = np.unique(depth)
        if has_site:
            site = cols["site"][0].astype(int)
            if np.any(cols["site"] != site) or np.any(cols["depth_mm"] != depth):
                raise InputError(f"'{stimulus}_receptors.csv': the receptor sites differ between steps")
        else:                       # written before the site column: depth by depth, same sites
            site = np.empty(n, int)
            for d in depths:
                site[depth == d] = np.arange((depth == d).sum())
        sites = set(site[depth == depths[0]])
        if any(set(site[depth == d]) != sites or (depth == d).sum() != len(sites) for d in depths):
            raise InputError(f"'{stimulus}_receptors.csv': not every receptor site appears once at every depth")
        data = {"position": position, "along_z": along_z, "depth": depth, "site": site, "depths": depths,
                "x": cols["x_mm"][0], "y": cols["y_mm"][0], "z": cols["z_mm"][0],
                "values": {h: cols[h] for h in header if h not in RECEPTOR_COLUMNS}, "steps": steps}
        self._cache[stimulus] = data
        return data

    def positions(self, stimulus) -> np.ndarray:
        """(k,) stimulus offsets of the sweep (mm)."""
        return self._load(stimulus)["position"]

    def depths(self, stimulus) -> np.ndarray:
        return self._load(stimulus)["depths"]

    def measures(self, stimulus) -> list[str]:
        return list(self._load(stimulus)["values"])

    def values(self, stimulus, candidate) -> np.ndarray:
        """(k_steps, n_points) values of a candidate measure at every receptor point."""
        name = base_measure(candidate)
        vals = self._load(stimulus)["values"]
        if name not in vals:
            raise InputError(f"measure '{name}' was not computed in '{self.folder / stimulus}_receptors.csv' "
                             f"(it has {list(vals)}): re-run `pipeline.py indent` with a scene whose "
                             f"[receptors] measures list it (examples/analysis_gratings.toml lists all candidates)")
        v = vals[name]
        return np.abs(v) if candidate.startswith("abs:") else v

    def site_index(self, stimulus, receptor_x_mm: float = 0.0, receptor_z_mm: float | None = None) -> int:
        """Site id (the `site` column) of the receptor site nearest the lateral position (x, and z
        in 3D; default the middle z), judged at the shallowest depth."""
        d = self._load(stimulus)
        top = d["depth"] == d["depths"][0]
        z = d["z"][top]
        rz = 0.5 * (z.min() + z.max()) if receptor_z_mm is None else receptor_z_mm
        return int(d["site"][top][np.argmin((d["x"][top] - receptor_x_mm) ** 2 + (z - rz) ** 2)])

    def profile(self, stimulus, candidate, depth_mm, receptor_x_mm=0.0, site=None, align=True):
        """Spatial response profile: (positions (k,), values (k,)) of one receptor (the site
        nearest receptor_x_mm, at the listed depth nearest depth_mm) as the stimulus steps.

        align (sweeps along x; a single indentation is never moved): the site's profile is
        translated by receptor_x_mm - site x, i.e.
        it stands for a receptor exactly at receptor_x_mm (the sites of an `indent` grid are the
        surface nodes nearest the centres of cells of its spacing, 0.015 mm off x = 0 on the 2D
        cylinders; two runs of different diameters then describe the same receptor)."""
        d = self._load(stimulus)
        depth = d["depths"][np.argmin(np.abs(d["depths"] - depth_mm))]
        s = self.site_index(stimulus, receptor_x_mm) if site is None else site
        j = np.flatnonzero((d["depth"] == depth) & (d["site"] == s))[0]
        shift = 0.0
        if align and not d["along_z"] and len(d["position"]) > 1:
            shift = receptor_x_mm - d["x"][np.flatnonzero((d["depth"] == d["depths"][0]) & (d["site"] == s))[0]]
        return d["position"] + shift, self.values(stimulus, candidate)[:, j]

    def population(self, stimulus, candidate, depth_mm, position_mm):
        """Population response: (receptor x (n,), values (n,)) of all receptors at one depth for the
        indentation nearest position_mm, ordered by x."""
        d = self._load(stimulus)
        depth = d["depths"][np.argmin(np.abs(d["depths"] - depth_mm))]
        i = int(np.argmin(np.abs(d["position"] - position_mm)))
        sel = np.flatnonzero(d["depth"] == depth)
        sel = sel[np.argsort(d["x"][sel])]
        return d["x"][sel], self.values(stimulus, candidate)[i, sel]


def _read_csv(path):
    with open(path) as fh:
        return list(csv.DictReader(fh))


# --------------------------------------------------------------------------- linear receptor model
def goodness(d, predicted) -> float:
    """Thesis R^2 = (sum d^2 - sum e^2) / sum d^2 with e = d - predicted."""
    d = np.asarray(d, float)
    e = d - np.asarray(predicted, float)
    sd = float(d @ d)
    return (sd - float(e @ e)) / sd if sd > 0 else float("nan")


def linear_fit(S, d) -> tuple[float, float, float, float]:
    """Least-squares d = a S + b: (a, b, thesis R^2, RMS error). A constant S gives a = 0."""
    S, d = np.asarray(S, float), np.asarray(d, float)
    sc = S - S.mean()
    var = float(sc @ sc)
    a = float(sc @ (d - d.mean())) / var if var > 1e-300 * max(1.0, float(S @ S)) else 0.0
    b = float(d.mean() - a * S.mean())
    pred = a * S + b
    return a, b, goodness(d, pred), float(np.sqrt(np.mean((d - pred) ** 2)))


@dataclass
class Fit:
    """One candidate's best linear receptor model over the free parameters."""
    measure: str
    depth_mm: float
    diameter_mm: float          # nan with one run (no diameter freedom)
    a: float
    b: float
    r2: float
    rms_ips: float
    n: int
    stimuli: tuple              # stimuli the parameters were fitted on
    unit: str = ""
    receptor_x_mm: float = 0.0

    def predict(self, runs, stimulus, positions_mm) -> np.ndarray:
        """Predicted rates (imp/s) at stimulus positions with these parameters."""
        S = model_values(runs, stimulus, self.measure, self.depth_mm, self.diameter_mm,
                         positions_mm, self.receptor_x_mm)
        return self.a * S + self.b

    def evaluate(self, runs, neural: NeuralData) -> dict:
        """{stimulus: (R^2, RMS)} of these fixed parameters on recorded data (fit one, predict others)."""
        out = {}
        for s in neural.stimuli:
            part = neural.only(stimuli=[s])
            pred = self.predict(runs, s, part.position_mm)
            out[s] = (goodness(part.rate_ips, pred), float(np.sqrt(np.mean((part.rate_ips - pred) ** 2))))
        return out

    def row(self) -> dict:
        return {"unit": self.unit, "measure": self.measure, "thesis_name": THESIS_CANDIDATES.get(self.measure, ""),
                "measure_unit": MEASURES[base_measure(self.measure)].unit,
                "r2": self.r2, "rms_ips": self.rms_ips, "depth_mm": self.depth_mm,
                "diameter_mm": self.diameter_mm, "a_ips_per_measure_unit": self.a, "b_ips": self.b, "n": self.n,
                "stimuli": " ".join(self.stimuli)}


def as_runs(runs) -> dict:
    """{diameter (nan for one run): IndentRun}; accepts one run, a list, or a dict."""
    if isinstance(runs, IndentRun):
        return {math.nan: runs}
    if isinstance(runs, dict):
        return dict(sorted(runs.items()))
    runs = list(runs)
    if len(runs) == 1:
        return {math.nan: runs[0]}
    if len(runs) != 2 or any(r.diameter_mm is None for r in runs):
        raise InputError("diameter interpolation needs exactly two runs with known model diameters "
                         "(2D cylinder runs record theirs in run.json; else give --diameters D1 D2)")
    if runs[0].diameter_mm == runs[1].diameter_mm:
        raise InputError(f"the two runs have the same model diameter {runs[0].diameter_mm} mm")
    return dict(sorted((r.diameter_mm, r) for r in runs))


def model_values(runs, stimulus, candidate, depth_mm, diameter_mm, positions_mm, receptor_x_mm=0.0):
    """Candidate at the receptor, linearly interpolated at the stimulus positions and (with two
    runs) between the two model diameters."""
    runs = as_runs(runs)
    out = []
    for D, run in runs.items():
        pos, vals = run.profile(stimulus, candidate, depth_mm, receptor_x_mm)
        order = np.argsort(pos)
        out.append(np.interp(positions_mm, pos[order], vals[order]))
    if len(out) == 1:
        return out[0]
    (d1, d2) = runs
    w = (diameter_mm - d1) / (d2 - d1)
    return (1 - w) * out[0] + w * out[1]


def check_coverage(runs, neural: NeuralData, receptor_x_mm=0.0) -> None:
    """Every recorded stimulus exists in every run and its positions lie inside the simulated sweep
    (as aligned to the receptor, `IndentRun.profile`)."""
    for run in as_runs(runs).values():
        for s in neural.stimuli:
            pos = run.profile(s, next(iter(run.measures(s))), run.depths(s)[0], receptor_x_mm)[0]
            got = neural.position_mm[neural.stimulus == s]
            lo, hi = pos.min(), pos.max()
            out = got[(got < lo - 1e-9) | (got > hi + 1e-9)]
            if out.size:
                raise InputError(f"stimulus '{s}': {out.size} recorded position(s) (e.g. {out[0]:g} mm) lie outside "
                                 f"the simulated sweep {lo:g} to {hi:g} mm in '{run.folder}': widen the "
                                 f"indentation sweep or drop those rows")


def depth_grid(runs, stimuli, depth_range_mm=DEPTH_RANGE_MM) -> np.ndarray:
    """Receptor depths every run has for every stimulus, inside depth_range_mm."""
    common = None
    for run in as_runs(runs).values():
        for s in stimuli:
            d = set(np.round(run.depths(s), 9))
            common = d if common is None else common & d
    lo, hi = depth_range_mm
    grid = np.array(sorted(d for d in common if lo - 1e-9 <= d <= hi + 1e-9))
    if not grid.size:
        raise InputError(f"no receptor depth in {lo}-{hi} mm is common to all runs and stimuli: "
                         f"re-run indent with [receptors] depths_mm = \"0.5:1:0.05\"")
    return grid


def diameter_grid(runs, step_mm=DIAMETER_STEP_MM) -> np.ndarray:
    runs = as_runs(runs)
    if len(runs) == 1:
        return np.array([math.nan])
    d1, d2 = runs
    n = max(1, int(round((d2 - d1) / step_mm)))
    return np.linspace(d1, d2, n + 1)


def fit_measure(runs, neural: NeuralData, candidate: str, fit_stimuli=None, depths_mm=None,
                diameters_mm=None, receptor_x_mm=0.0, unit="") -> Fit:
    """Best d = a S + b for one candidate over the depth (and diameter) grid, fitted on the rows
    of fit_stimuli (default all) pooled together: one parameter set for all of them."""
    runs = as_runs(runs)
    base_measure(candidate)
    data = neural if fit_stimuli is None else neural.only(stimuli=fit_stimuli)
    if not len(data):
        raise InputError(f"no recorded rows for the fit stimuli {fit_stimuli}")
    stimuli = data.stimuli
    check_coverage(runs, data, receptor_x_mm)
    depths = depth_grid(runs, stimuli) if depths_mm is None else np.atleast_1d(depths_mm)
    diameters = diameter_grid(runs) if diameters_mm is None else np.atleast_1d(diameters_mm)
    best = None
    for depth in depths:
        per_run = {D: np.concatenate([_at(run, s, candidate, depth, data, receptor_x_mm) for s in stimuli])
                   for D, run in runs.items()}
        d_all = np.concatenate([data.rate_ips[data.stimulus == s] for s in stimuli])
        for D in diameters:
            if len(per_run) == 1:
                S = next(iter(per_run.values()))
            else:
                d1, d2 = per_run
                w = (D - d1) / (d2 - d1)
                S = (1 - w) * per_run[d1] + w * per_run[d2]
            a, b, r2, rms = linear_fit(S, d_all)
            if best is None or rms < best.rms_ips - 1e-12:
                best = Fit(candidate, float(depth), float(D), a, b, r2, rms, len(d_all), tuple(stimuli),
                           unit, receptor_x_mm)
    return best


def _at(run, stimulus, candidate, depth, data, receptor_x_mm):
    pos, vals = run.profile(stimulus, candidate, depth, receptor_x_mm)
    order = np.argsort(pos)
    return np.interp(data.position_mm[data.stimulus == stimulus], pos[order], vals[order])


def rank_candidates(runs, neural: NeuralData, candidates=None, fit_stimuli=None, receptor_x_mm=0.0,
                    depths_mm=None, unit="") -> list[Fit]:
    """Best fit of every candidate on the pooled stimuli, ascending RMS error (thesis tables 4.3-4.4;
    candidates missing from the runs are skipped, unknown names are an error)."""
    runs = as_runs(runs)
    cands = check_candidates(candidates or default_candidates(runs, neural.stimuli))
    fits = [fit_measure(runs, neural, c, fit_stimuli, depths_mm, None, receptor_x_mm, unit) for c in cands]
    return sorted(fits, key=lambda f: f.rms_ips)


def rank_per_stimulus(runs, neural: NeuralData, candidates=None, receptor_x_mm=0.0, depths_mm=None,
                      unit="") -> dict[str, list[Fit]]:
    """{stimulus: fits sorted by descending R^2} with each stimulus fitted on its own (tables 4.1-4.2)."""
    runs = as_runs(runs)
    cands = check_candidates(candidates or default_candidates(runs, neural.stimuli))
    return {s: sorted((fit_measure(runs, neural, c, [s], depths_mm, None, receptor_x_mm, unit) for c in cands),
                      key=lambda f: -f.r2) for s in neural.stimuli}


def default_candidates(runs, stimuli) -> list[str]:
    """Thesis candidates whose base measure every run computed for every stimulus (else all the
    measures the runs have)."""
    have = None
    for run in as_runs(runs).values():
        for s in stimuli:
            m = set(run.measures(s))
            have = m if have is None else have & m
    out = [c for c in THESIS_CANDIDATES if base_measure(c) in have]
    return out or sorted(have)


# --------------------------------------------------------------------------- receptive fields
@dataclass
class ReceptiveField:
    """ON set of a receptor from a point-load sweep and a threshold (thesis 4.2, figure 4-4).

    positions_mm: load positions relative to the receptor; on: (k,) bool. shape: 'disk' (one ON
    interval containing the receptor), 'annulus' (ON on both sides, OFF hole over the receptor),
    'none', or 'other'. diameter_mm: extent of the ON set; hole_mm: width of the OFF gap around
    the receptor (annulus only; the thesis finds about 0.3 mm for absolute shear strain)."""
    positions_mm: np.ndarray
    values: np.ndarray
    threshold: float
    on: np.ndarray
    shape: str
    diameter_mm: float
    hole_mm: float

    def map2d(self, n: int = 161):
        """Axisymmetric map (the thesis's rotation of the profile about the receptor): (x (n,),
        y (n,), on (n, n)); at each radius the larger of the two sides of the profile."""
        r_max = np.abs(self.positions_mm).max()
        x = np.linspace(-r_max, r_max, n)
        r = np.hypot(*np.meshgrid(x, x))
        p, v = self.positions_mm, self.values
        side = np.fmax(np.interp(r, p, v, left=np.nan, right=np.nan), np.interp(-r, p, v, left=np.nan, right=np.nan))
        with np.errstate(invalid="ignore"):
            return x, x, side >= self.threshold


def _crossing(p0, p1, v0, v1, thr):
    return p0 + (thr - v0) * (p1 - p0) / (v1 - v0) if v1 != v0 else 0.5 * (p0 + p1)


def receptive_field(positions_mm, values, threshold: float, receptor_mm: float = 0.0) -> ReceptiveField:
    """Threshold a point-load sweep profile (values at the receptor vs load position)."""
    p = np.asarray(positions_mm, float) - receptor_mm
    o = np.argsort(p)
    p, v = p[o], np.asarray(values, float)[o]
    on = v >= threshold
    if not on.any():
        return ReceptiveField(p, v, threshold, on, "none", 0.0, math.nan)
    # interval ends by linear interpolation of the threshold crossing
    runs, k = [], 0
    while k < len(p):
        if on[k]:
            j = k
            while j + 1 < len(p) and on[j + 1]:
                j += 1
            lo = _crossing(p[k - 1], p[k], v[k - 1], v[k], threshold) if k > 0 else p[k]
            hi = _crossing(p[j], p[j + 1], v[j], v[j + 1], threshold) if j + 1 < len(p) else p[j]
            runs.append((lo, hi))
            k = j + 1
        else:
            k += 1
    diameter = runs[-1][1] - runs[0][0]
    centre_on = any(lo <= 0 <= hi for lo, hi in runs)
    if len(runs) == 1 and centre_on:
        return ReceptiveField(p, v, threshold, on, "disk", diameter, 0.0)
    left = [r for r in runs if r[1] < 0]
    right = [r for r in runs if r[0] > 0]
    if not centre_on and left and right:
        return ReceptiveField(p, v, threshold, on, "annulus", diameter, right[0][0] - left[-1][1])
    return ReceptiveField(p, v, threshold, on, "other", diameter, math.nan)


# --------------------------------------------------------------------------- settling and gaps
def settling_separation(separations_mm, values, tol: float = 0.05, reference=None) -> float:
    """Smallest separation from which every later value stays within tol of the reference
    (default: the last value; e.g. the one-load-alone values of `two_point_curves`); nan if
    even the last two differ by more."""
    s, v = np.asarray(separations_mm, float), np.asarray(values, float)
    ref = v[-1] if reference is None else np.asarray(reference, float)
    ok = np.abs(v / ref - 1) <= tol
    bad = np.flatnonzero(~ok)
    if not bad.size:
        return float(s[0])
    return float(s[bad[-1] + 1]) if bad[-1] + 1 < len(s) - 1 else math.nan


def gap_peaks(x_mm, values, gap_start_mm: float, gap_end_mm: float, search_mm: float):
    """Peaks of a population profile on each side of a gap (thesis 4.5.5, figure 4-19): the
    largest local maximum within search_mm outside the gap's middle on each side. Returns
    (x_left, v_left, x_right, v_right, distance_mm, slope per mm); nan where a side has no
    interior maximum (the peaks have merged)."""
    x, v = np.asarray(x_mm, float), np.asarray(values, float)
    mid = 0.5 * (gap_start_mm + gap_end_mm)

    def peak(lo, hi):
        sel = np.flatnonzero((x >= lo) & (x <= hi))
        if sel.size < 3:
            return math.nan, math.nan
        inner = sel[1:-1]
        is_max = (v[inner] >= v[inner - 1]) & (v[inner] >= v[inner + 1])
        if not is_max.any():
            return math.nan, math.nan
        k = inner[is_max][np.argmax(v[inner][is_max])]
        # parabola through the peak and its neighbours for a sub-sample position
        y0, y1, y2 = v[k - 1], v[k], v[k + 1]
        den = y0 - 2 * y1 + y2
        t = 0.5 * (y0 - y2) / den if den < 0 else 0.0
        h = 0.5 * (x[k + 1] - x[k - 1])
        return float(x[k] + t * h), float(y1 - 0.25 * (y0 - y2) * t)

    xl, vl = peak(gap_start_mm - search_mm, mid)
    xr, vr = peak(mid, gap_end_mm + search_mm)
    dist = xr - xl
    return xl, vl, xr, vr, dist, (vr - vl) / dist if dist > 0 else math.nan


# --------------------------------------------------------------------------- in-process 2D probe
class Probe2D:
    """A 2D model folder (`pipeline.py mesh --preset cylinder8 --bone`) with receptors at exact
    points below its contact surface and a contact model that observes them.

    sites_x_mm: lateral positions of the receptor sites; depths_mm: depths along the inward surface
    normal (interpolated between surface nodes). `measure(indentor, offsets, name, **load)` ->
    (k_positions, n_depths, n_sites) values."""

    def __init__(self, model_dir, sites_x_mm, depths_mm=(0.75,), material=None):
        from fem.contact import ContactModel, open_model
        from fem.receptors import ReceptorGrid, ReceptorSampler

        model, system, region, self.info = open_model(model_dir, material)
        if model.dim != 2:
            raise InputError("Probe2D needs a 2D model folder (pipeline.py mesh --preset cylinder8 --bone)")
        sn = model.surface_nodes(region)
        o = np.argsort(sn.x[:, 0])
        xs = np.asarray(sites_x_mm, float)
        if xs.min() < sn.x[o[0], 0] or xs.max() > sn.x[o[-1], 0]:
            raise InputError(f"receptor sites must lie over the contact surface "
                             f"({sn.x[o[0], 0]:.3g} to {sn.x[o[-1], 0]:.3g} mm)")
        y = np.interp(xs, sn.x[o, 0], sn.x[o, 1])
        nrm = np.column_stack([np.interp(xs, sn.x[o, 0], sn.normal[o, k]) for k in range(2)])
        nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
        sites = np.column_stack([xs, y])
        self.depths_mm = np.atleast_1d(np.asarray(depths_mm, float))
        pts = (sites[None] - self.depths_mm[:, None, None] * nrm[None]).reshape(-1, 2)
        grid = ReceptorGrid(pts, np.repeat(self.depths_mm, len(xs)), np.tile(np.arange(len(xs)), len(self.depths_mm)),
                            sites)
        self.sites_x_mm, self.grid = xs, grid
        self.sampler = ReceptorSampler(model, grid)
        self.contact = ContactModel.from_fe(model, system, region, observe=self.sampler.operator)
        self.model = model

    def measure(self, indentor, offsets_x_mm, names, **load):
        """{name: (k, n_depths, n_sites)} for the indentor at each x offset, and the results."""
        off = np.zeros((len(offsets_x_mm), 3))
        off[:, 0] = offsets_x_mm
        results = self.contact.sweep(indentor, off, **load)
        out = {c: np.empty((len(off), len(self.depths_mm), len(self.sites_x_mm))) for c in names}
        for i, r in enumerate(results):
            vals = self.sampler.measures(r.observed, sorted({base_measure(c) for c in names}))
            for c in names:
                v = vals[base_measure(c)]
                out[c][i] = (np.abs(v) if c.startswith("abs:") else v).reshape(len(self.depths_mm), -1)
        return out, results


def point_load_field(probe: Probe2D, candidate: str, positions_mm, depth_mm=1.0, indentor="wedge",
                     threshold_frac=0.5, threshold=None, site_x_mm=0.0) -> ReceptiveField:
    """Receptive field of the probe's receptor nearest site_x_mm (its first depth) from a point
    load (a line load in 2D: the sharp wedge) swept over positions_mm, indented depth_mm at each.
    threshold: absolute; default threshold_frac * the largest value of the sweep (the thesis's
    threshold is arbitrary, and the field size depends on it)."""
    from fem.indentors import make_indentor

    ind = make_indentor(indentor, orientation="parallel", position_mm=(0.0, 0.0))
    vals, _ = probe.measure(ind, positions_mm, [candidate], depth_mm=depth_mm)
    k = int(np.argmin(np.abs(probe.sites_x_mm - site_x_mm)))
    v = vals[candidate][:, 0, k]
    thr = threshold_frac * v.max() if threshold is None else threshold
    return receptive_field(positions_mm, v, thr, probe.sites_x_mm[k])


def two_point_curves(probe: Probe2D, separations_mm, depth_mm=0.5, candidate="sed_MPa", tip="",
                     isolated=True):
    """Thesis 4.3: the largest candidate value over the probe's receptors (first depth) under two
    point loads at each separation, (a) both tips indented depth_mm (equal displacement) and (b)
    each tip carrying half the force F0 that one tip needs for depth_mm (equal force), so that at
    separation 0 (the tips coincide: one load F0 at depth_mm) both protocols are the same load.
    tip: '' for the catalogue's sharp tips (cone sections), or ':<radius mm>' for round tips.
    isolated: also the value under one tip alone at +separation/2 with the same load
    ("alone_displacement", "alone_force"): on a curved finger the load position alone changes the
    value, and two / alone isolates the interaction of the two loads.
    Returns {"separation_mm", "displacement", "force", "force_per_load_N", "depth_force_mm", ...}."""
    from fem.indentors import make_indentor

    single = make_indentor(f"two-point:0{tip}", orientation="parallel")
    f0 = probe.contact.indent(single, depth_mm=depth_mm).total_force_N
    disp, force, dforce, alone_d, alone_f = [], [], [], [], []
    for s in separations_mm:
        ind = make_indentor(f"two-point:{s:g}{tip}", orientation="parallel")
        vals, _ = probe.measure(ind, [0.0], [candidate], depth_mm=depth_mm)
        disp.append(vals[candidate][0, 0].max())
        load = {"force_N": 0.5 * f0, "equal_force": True} if s > 0 else {"force_N": f0}
        vals, res = probe.measure(ind, [0.0], [candidate], **load)
        force.append(vals[candidate][0, 0].max())
        dforce.append(float(res[0].depth_mm.max()))
        if isolated:     # one tip alone where the right-hand tip sits: no interaction, same geometry
            vals, _ = probe.measure(single, [0.5 * s], [candidate], depth_mm=depth_mm)
            alone_d.append(vals[candidate][0, 0].max())
            vals, _ = probe.measure(single, [0.5 * s], [candidate], force_N=0.5 * f0 if s > 0 else f0)
            alone_f.append(vals[candidate][0, 0].max())
    out = {"separation_mm": np.asarray(separations_mm, float), "displacement": np.array(disp),
           "force": np.array(force), "force_per_load_N": 0.5 * f0, "depth_force_mm": np.array(dforce)}
    if isolated:
        out.update(alone_displacement=np.array(alone_d), alone_force=np.array(alone_f))
    return out


def gap_analysis(probe: Probe2D, bar_mm, gaps_mm, depth_mm=1.0, candidate="abs:strain_xy"):
    """Thesis 4.5.5: for each gap, a grating of two bars of width bar_mm separated by the gap,
    centred over x = 0 and indented depth_mm; the candidate across the probe's receptors (first
    depth) and its peaks on both sides of the gap. Returns rows (gap, x_left, x_right, distance,
    slope) and the profiles."""
    from fem.indentors import make_indentor

    rows, profiles = [], []
    for g in gaps_mm:
        half = bar_mm + 0.5 * g
        ind = make_indentor(f"grating:{bar_mm:g}:{g:g}", orientation="parallel", position_mm=(-half, 0.0))
        vals, _ = probe.measure(ind, [0.0], [candidate], depth_mm=depth_mm)
        v = vals[candidate][0, 0]
        xl, vl, xr, vr, dist, slope = gap_peaks(probe.sites_x_mm, v, -0.5 * g, 0.5 * g, 0.5 * bar_mm)
        rows.append({"gap_mm": g, "x_left_mm": xl, "x_right_mm": xr, "peak_left": vl, "peak_right": vr,
                     "interpeak_mm": dist, "slope_per_mm": slope})
        profiles.append(v)
    return rows, np.array(profiles)


# --------------------------------------------------------------------------- report (CLI)
def _fmt(v):
    if isinstance(v, float):
        return "" if math.isnan(v) else f"{v:.6g}"
    return str(v)


def write_table(folder: Path, stem: str, rows: list[dict], title: str) -> None:
    """rows as <stem>.csv and a markdown table <stem>.md."""
    if not rows:
        return
    keys = list(rows[0])
    with open(folder / f"{stem}.csv", "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(keys)
        w.writerows([[_fmt(r[k]) for k in keys] for r in rows])
    md = [f"# {title}", "", "| " + " | ".join(keys) + " |", "|" + "---|" * len(keys)]
    md += ["| " + " | ".join(_fmt(r[k]) for k in keys) + " |" for r in rows]
    (folder / f"{stem}.md").write_text("\n".join(md) + "\n")


@dataclass
class UnitAnalysis:
    unit: str
    combined: list
    per_stimulus: dict
    prediction: list = field(default_factory=list)


def analyze(runs, neural: NeuralData, candidates=None, fit_stimuli=None, receptor_x_mm=0.0,
            orientation=None) -> list[UnitAnalysis]:
    """Every unit of the recordings: combined ranking, per-stimulus ranking and (with fit_stimuli)
    the fit-on-some / predict-the-others evaluation of every candidate."""
    runs = as_runs(runs)
    orients = sorted(set(neural.orientation.tolist()))
    if orientation is not None:
        neural = neural.only(orientation=orientation)
        if not len(neural):
            raise InputError(f"no rows with orientation '{orientation}' (the data has {orients})")
    elif len(orients) > 1:
        raise InputError(f"the neural data mixes bar orientations {orients}: pick one with --orientation "
                         f"(each orientation needs its own indentation run)")
    if candidates is not None:
        check_candidates(candidates)
    check_coverage(runs, neural, receptor_x_mm)
    if fit_stimuli is not None:
        missing = [s for s in fit_stimuli if s not in neural.stimuli]
        if missing:
            raise InputError(f"--fit-on stimuli {missing} have no recorded rows (recorded: {neural.stimuli})")
    out = []
    for unit in neural.units:
        data = neural.only(unit=unit)
        ua = UnitAnalysis(unit, rank_candidates(runs, data, candidates, fit_stimuli, receptor_x_mm, unit=unit),
                          rank_per_stimulus(runs, data, candidates, receptor_x_mm, unit=unit))
        if fit_stimuli is not None:
            others = data.only(stimuli=[s for s in data.stimuli if s not in fit_stimuli])
            for f in ua.combined:
                for s, (r2, rms) in (f.evaluate(runs, others).items() if len(others) else []):
                    ua.prediction.append({"unit": unit, "measure": f.measure, "fit_on": " ".join(f.stimuli),
                                          "predicted": s, "r2": r2, "rms_ips": rms, "depth_mm": f.depth_mm,
                                          "diameter_mm": f.diameter_mm, "a_ips_per_measure_unit": f.a, "b_ips": f.b})
        out.append(ua)
    return out


def write_report(out_dir, runs, neural: NeuralData, results: list[UnitAnalysis], top: int = 3) -> list[str]:
    """Tables (CSV + markdown), profile and scatter plots into out_dir (atomically). Returns file names."""
    from common.staging import staged_output, write_json

    runs = as_runs(runs)
    with staged_output(out_dir) as tmp:
        combined = [dict(rank=i + 1, **f.row()) for ua in results for i, f in enumerate(ua.combined)]
        write_table(tmp, "ranking_combined", combined, "Candidates on all stimuli pooled (thesis tables 4.3-4.4), "
                                                       "ascending RMS error")
        per = [dict(stimulus=s, rank=i + 1, **f.row()) for ua in results for s, fits in ua.per_stimulus.items()
               for i, f in enumerate(fits)]
        write_table(tmp, "ranking_per_stimulus", per, "Candidates per stimulus (thesis tables 4.1-4.2), "
                                                      "descending R^2")
        pred = [r for ua in results for r in ua.prediction]
        write_table(tmp, "prediction", pred, "Parameters fitted on some stimuli, predicting the others")
        for ua in results:
            data = neural.only(unit=ua.unit)
            _plot_profiles(tmp / f"profiles_{_safe(ua.unit)}.png", runs, data, ua.combined[:top])
            _plot_scatter(tmp / f"scatter_{_safe(ua.unit)}.png", runs, data, ua.combined[:min(len(ua.combined), 4)])
        write_json(tmp / "analysis.json", {
            "neural": neural.source, "runs": {str(k): str(v.folder) for k, v in runs.items()},
            "goodness": "R^2 = (sum d^2 - sum e^2) / sum d^2 (thesis eq. after 4.1); rms_ips = sqrt(mean e^2)",
            "units": {ua.unit: [f.row() for f in ua.combined] for ua in results}})
        names = sorted(p.name for p in tmp.iterdir())
    return names


def _safe(s):
    return "".join(c if c.isalnum() or c in "-_." else "_" for c in s)


def _plot_profiles(path, runs, data, fits):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    stimuli = data.stimuli
    if all(len(set(data.position_mm[data.stimulus == s])) == 1 for s in stimuli):
        # one indentation per stimulus (e.g. cylinders at constant force, thesis figure 4-26)
        fig, ax = plt.subplots(figsize=(max(5, 0.8 * len(stimuli) + 2), 3.6))
        k = np.arange(len(stimuli))
        ax.plot(k, [data.rate_ips[data.stimulus == s].mean() for s in stimuli], "kx", ms=9, mew=2, label="recorded")
        for f in fits:
            ax.plot(k, [f.predict(runs, s, data.position_mm[data.stimulus == s][:1])[0] for s in stimuli], "o-",
                    label=f"{f.measure} (depth {f.depth_mm:g} mm)")
        ax.set_xticks(k, stimuli)
        ax.set(ylabel="rate, imp/s")
        ax.legend(fontsize=7)
        fig.tight_layout()
        fig.savefig(path, dpi=110)
        plt.close(fig)
        return
    fig, axes = plt.subplots(len(stimuli), 1, figsize=(9, 2.4 * len(stimuli)), squeeze=False)
    for s, ax in zip(stimuli, axes[:, 0]):
        part = data.only(stimuli=[s])
        o = np.argsort(part.position_mm)
        ax.plot(part.position_mm[o], part.rate_ips[o], "k-", lw=1.5, label="recorded")
        for f in fits:
            dense = np.linspace(part.position_mm.min(), part.position_mm.max(), 400)
            ax.plot(dense, f.predict(runs, s, dense), lw=1,
                    label=f"{f.measure} (depth {f.depth_mm:g} mm" + ("" if math.isnan(f.diameter_mm) else
                                                                     f", D {f.diameter_mm:g} mm") + ")")
        ax.set_title(s, fontsize=9)
        ax.set_ylabel("rate, imp/s")
    axes[0, 0].legend(fontsize=7)
    axes[-1, 0].set_xlabel("stimulus position, mm")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _plot_scatter(path, runs, data, fits):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(fits), figsize=(3.6 * len(fits), 3.4), squeeze=False)
    for f, ax in zip(fits, axes[0]):
        S = np.concatenate([model_values(runs, s, f.measure, f.depth_mm, f.diameter_mm,
                                         data.position_mm[data.stimulus == s]) for s in data.stimuli])
        d = np.concatenate([data.rate_ips[data.stimulus == s] for s in data.stimuli])
        ax.plot(S, d, ".", ms=3)
        line = np.linspace(S.min(), S.max(), 50)
        ax.plot(line, f.a * line + f.b, "r-", lw=1)
        ax.fill_between(line, f.a * line + f.b - f.rms_ips, f.a * line + f.b + f.rms_ips, color="r", alpha=0.15)
        ax.set(xlabel=f"{f.measure} at {f.depth_mm:g} mm", ylabel="rate, imp/s",
               title=f"RMS {f.rms_ips:.3g} imp/s (band), R^2 {f.r2:.3f}")
        ax.title.set_fontsize(8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def run_analyze(results, neural_csv, out_dir=None, diameters_mm=None, measures=None, fit_on=None,
                orientation=None, receptor_x_mm=0.0) -> str:
    """`pipeline.py analyze`: read runs and recordings, rank, write the report. Returns a summary."""
    from fem.neural import read_neural_csv

    results = [results] if isinstance(results, (str, Path)) else list(results)
    if len(results) > 2:
        raise InputError("give one results folder, or two (2D models of two diameters)")
    if diameters_mm is not None and len(results) != 2:
        raise InputError("--diameters needs two results folders")
    runs = as_runs([IndentRun(r, None if diameters_mm is None else diameters_mm[i]) for i, r in enumerate(results)])
    neural = read_neural_csv(neural_csv)
    cands = [m.strip() for m in measures.split(",") if m.strip()] if measures else None
    fit = [s.strip() for s in fit_on.split(",") if s.strip()] if fit_on else None
    res = analyze(runs, neural, cands, fit, receptor_x_mm, orientation)
    out = Path(out_dir) if out_dir else Path(results[0]) / "analysis"
    names = write_report(out, runs, neural, res)
    lines = [f"receptor analysis in {out}: {', '.join(names)}"]
    for ua in res:
        lines.append(f"  unit {ua.unit}: {len(neural.only(unit=ua.unit))} recorded rates, fit on "
                     f"{', '.join(ua.combined[0].stimuli)}")
        lines.append("    rank  measure                    RMS imp/s  R^2     depth mm  diameter mm")
        for i, f in enumerate(ua.combined):
            dia = "" if math.isnan(f.diameter_mm) else f"{f.diameter_mm:g}"
            lines.append(f"    {i + 1:>4}  {f.measure:<25} {f.rms_ips:>10.3f}  {f.r2:.4f}  {f.depth_mm:>8.3g}  {dia:>11}")
        lines += [f"    {r['measure']} predicts {r['predicted']}: R^2 {r['r2']:.4f}, RMS {r['rms_ips']:.3f} imp/s"
                  for r in ua.prediction if r["measure"] == ua.combined[0].measure]
    return "\n".join(lines)
