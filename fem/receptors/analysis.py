"""Receptor analysis (thesis 3.6, 4.2-4.5, 6.3): the linear receptor model fitted to recorded
discharge rates, and candidate measures ranked by how well they predict them.

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

Candidates are `fem.core.measures` names, or `abs:<name>` for the magnitude of a signed one
(`abs:strain_xy` is the thesis's "absolute shear strain"). `THESIS_CANDIDATES` is the list of
thesis tables 4.1-4.4.

    runs = {8.0: IndentRun("out/cyl8/gratings"), 16.0: IndentRun("out/cyl16/gratings")}   # fem.io.runfolder
    neural = read_neural_csv("data/sa1_gratings.csv")          # fem.biomech.measured
    table = rank_candidates(runs, neural)                      # combined data, best first
    fit = fit_measure(runs, neural, "sed_MPa", fit_stimuli=["step1"])
    fit.evaluate(runs, neural.only(stimuli=["step3"]))         # R^2, RMS on unseen stimuli

The in-process 2D experiments (receptive fields, two-point cues, grating gaps) are in fem.receptors.probes.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from fem.core.measures import MEASURES, base_measure
from fem.receptors.neural import NeuralData
from fingertip.errors import InputError

DEPTH_RANGE_MM = (0.5, 1.0)
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
"""Candidate relevant stimuli of thesis tables 4.1-4.4, and the mean stress -> thesis name."""


def check_candidates(candidates) -> list[str]:
    """The candidates as a list; InputError for an unknown one."""
    out = list(candidates)
    for c in out:
        base_measure(c)
    return out


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
    """{diameter (nan for one run): run}; accepts one run (fem.io.runfolder.IndentRun or any object
    with its reading methods), a list or tuple of runs, or a dict."""
    if isinstance(runs, dict):
        return dict(sorted(runs.items()))
    if not isinstance(runs, (list, tuple)):
        return {math.nan: runs}
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


# --------------------------------------------------------------------------- every unit
@dataclass
class UnitAnalysis:
    """One afferent's results: combined ranking (best first), per-stimulus rankings and, with fit
    stimuli, the prediction rows (fitted on some stimuli, evaluated on the others)."""
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
