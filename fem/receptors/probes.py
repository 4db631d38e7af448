"""In-process 2D receptor experiments on a model folder (thesis 4.2, 4.3, 4.5.5): receptors at
exact points below the contact surface (`Probe2D`), receptive fields from a point-load sweep,
two-point intensive cues under equal displacement and equal force, and shear-strain peaks across
grating gaps; and the profile analyses they use (thresholded receptive fields, settling
separations, peaks on both sides of a gap).

    probe = Probe2D("out/cyl8", sites_x_mm=np.linspace(-3, 3, 121), depths_mm=[0.75])
    rf = point_load_field(probe, "abs:strain_xy", np.linspace(-3, 3, 61))   # ReceptiveField
    curves = two_point_curves(probe, [0, 1, 2, 4])
    rows, profiles = gap_analysis(probe, 1.0, [0.5, 1.0, 2.0])
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fem.contact.indentors import make_indentor
from fem.contact.linear import ContactModel
from fem.core.measures import base_measure
from fem.io.modelfolder import open_model
from fem.receptors.grid import ReceptorGrid, ReceptorSampler
from fingertip.errors import InputError


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
