#!/usr/bin/env python
"""PARDISO settings on a first run's own matrix: time, factor size, flops and memory per setting.

    python benchmarks/pardiso_options.py MODEL_DIR                       # C5 perpendicular 0:3:0.5
    python benchmarks/pardiso_options.py MODEL_DIR --options default no-schur ooc-no-schur
    python benchmarks/pardiso_options.py MODEL_DIR --indentor C5 --orientation perpendicular --depth 0:3:0.5

First the scene runs on the model folder as `pipeline.py indent` runs it
(`fem.experiments.runner.run_scene`, no stored response model) up to its factorisation, and the
upper triangle of the saddle matrix it hands to PARDISO and the condensed rows (the reachable
contact candidates) are saved in --work. Then every setting runs in its own
process (so that its peak memory is its own): PARDISO analysis (phase 11) and, unless the
setting says analysis only, factorisation (phase 22, with the Schur complement when the setting
keeps it), with the project's iparm (`fem.core.linalg.Pardiso`) plus the setting's changes. Printed
per setting: analysis and factorisation wall time, nnz(L) (iparm[17]), factorisation GFlop
(iparm[18]), PARDISO's own peak memory for the factorisation (iparm[16]) and the process's
peak resident set (getrusage). Appended to benchmarks/results/pardiso_options.md.

Settings (SETTINGS below): the project's (METIS nested dissection, Schur complement), no Schur
complement, parallel METIS and minimum degree orderings (analysis only), two-level
factorisation, out of core (iparm[59] = 2) with and without the Schur complement, with
MKL_PARDISO_OOC_MAX_CORE_SIZE = --ooc-core-mb in core, MKL's reordering optimisations, 1x1
pivots, partial solves instead of the Schur complement, and the matrix in random input orders. Out-of-core files go to the working
directory of the setting's process (--work) and are removed by PARDISO.
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import fem.core.linalg as linalg  # noqa: E402
from fem.experiments.runner import run_scene  # noqa: E402
from fem.experiments.scene import Scene  # noqa: E402

RESULTS = ROOT / "benchmarks" / "results" / "pardiso_options.md"
SETTINGS = {     # name -> (iparm changes, condensed rows: "schur" | "partial" | None, factorise, input order seed)
    "default": ({}, "schur", True, None),
    "no-schur": ({}, None, True, None),
    "parallel-metis": ({1: 3}, "schur", False, None),
    "min-degree-no-schur": ({1: 0}, None, False, None),
    "two-level": ({23: 1}, "schur", True, None),
    "ooc-no-schur": ({59: 2}, None, True, None),
    "ooc": ({59: 2}, "schur", True, None),
    "aggressive-5": ({1: 52}, "schur", True, None),
    "1x1-pivots": ({20: 0}, "schur", True, None),
    "partial-solve": ({}, "partial", False, None),
    "random-input-order-0": ({}, "schur", False, 0),
    "random-input-order-1": ({}, "schur", False, 1),
    "random-input-order-2": ({}, "schur", False, 2),
    "refactorise": ({}, "schur", True, None),
}
"""aggressive-5: iparm[1] = 52, MKL 2026's reordering optimisations (level 5 of 0-10).
partial-solve: no Schur complement; the condensed rows marked for partial solves (iparm[30] = 1,
the compliance from sparse right-hand sides), which orders them last as the Schur complement does.
random-input-order-k: the matrix symmetrically permuted at random (seed k) before PARDISO's METIS,
whose nested dissection depends on the input order.
refactorise: the project's settings, then the same matrix factorised again on the same handle
(phase 22 without a new analysis, as a loop over materials could): its time, and how far its
Schur complement's Cholesky factor lies from the first factorisation's."""


class _Captured(Exception):
    pass


def capture(model_dir: str, work: Path, indentor: str, orientation: str, depth: str) -> None:
    """Save the saddle matrix's upper triangle (upper.npz) and condensed rows (schur.npy) that a
    first run of this scene (`run_scene`, no stored response model) factorises."""
    class Capture(linalg.Pardiso):
        def __init__(self, upper, schur=None, mkl_defaults=False):
            sp.save_npz(work / "upper.npz", sp.csr_matrix(upper))
            np.save(work / "schur.npy", np.zeros(0, int) if schur is None else np.asarray(schur))
            raise _Captured

    linalg.Pardiso = Capture
    name = indentor.replace(":", "_").replace(",", "_")
    scene = Scene.from_dict({"experiment": [{"name": name, "indentor": indentor, "orientation": orientation,
                                             "depth_mm": depth}], "output": {"pvd": False, "plots": False}})
    try:
        run_scene(model_dir, scene)
    except _Captured:
        return
    raise SystemExit("the run did not factorise with PARDISO (is pypardiso installed?)")


class _AnalysisDone(Exception):
    pass


class _Timed(linalg.Pardiso):
    """The project's Pardiso with iparm `changes` applied before the analysis and each phase
    timed (`times`); phase 12 (analysis and factorisation) runs as 11 then 22, so that both are
    timed. analysis_only: stop before the factorisation."""

    def __init__(self, upper, schur, changes: dict, analysis_only: bool, partial=None):
        self.changes, self.analysis_only, self.times = changes, analysis_only, {}
        self.partial = partial
        try:
            super().__init__(upper, schur)
        except _AnalysisDone:
            pass

    def _phase(self, phase, b, x, nrhs):
        if phase == 12:
            self._phase(11, b, x, nrhs)
            self._phase(22, b, x, nrhs)
            return
        if phase == 11:
            for k, v in self.changes.items():
                self.iparm[k] = v
            if self.partial is not None:            # rows of the sparse right-hand sides
                self.iparm[30] = 1
                self._perm = np.zeros(self.n, dtype=np.int32)
                self._perm[self.partial] = 1
            self.iparm[18] = -1                     # report the factorisation's MFlop
        elif phase == 22 and self.analysis_only:
            raise _AnalysisDone
        t = time.perf_counter()
        super()._phase(phase, b, x, nrhs)
        self.times[phase] = time.perf_counter() - t


def run_setting(work: Path, name: str) -> dict:
    """One setting in this process; returns its measurements."""
    changes, condensed, factorise, seed = SETTINGS[name]
    upper, rows = sp.load_npz(work / "upper.npz"), np.load(work / "schur.npy")
    if seed is not None:
        order = np.random.default_rng(seed).permutation(upper.shape[0])
        full = (upper + sp.triu(upper, 1).T).tocsr()
        upper = sp.triu(full[order][:, order], format="csr")
        rank = np.empty_like(order)
        rank[order] = np.arange(len(order))
        rows = np.sort(rank[rows])
    solver = _Timed(upper, rows if condensed == "schur" else None, changes, analysis_only=not factorise,
                    partial=rows if condensed == "partial" else None)
    out = {"setting": name, "analysis_s": solver.times[11], "factorisation_s": solver.times.get(22, float("nan")),
           "nnz_L_M": solver.iparm[17] / 1e6, "gflop": solver.iparm[18] / 1e3,
           "pardiso_factor_MB": solver.iparm[16] / 1024 if factorise else float("nan"),
           "process_peak_MB": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}
    if name == "refactorise":
        first = np.tril(solver._schur_factor[0])
        S = np.zeros((len(rows), len(rows)), order="F")
        t = time.perf_counter()
        solver._phase(22, np.zeros(1), S, 1)
        out["factorisation_s"] = time.perf_counter() - t
        again = np.tril(sla.cho_factor(S, lower=True)[0])
        out["note"] = (f"refactorisation on the same handle: Schur complement's Cholesky factor differs from "
                       f"the first factorisation's by {np.abs(again - first).max() / np.abs(first).max():.1e} "
                       f"(max, relative)")
    solver.release()
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("model_dir")
    ap.add_argument("--options", nargs="+", default=list(SETTINGS), choices=list(SETTINGS))
    ap.add_argument("--indentor", default="C5")
    ap.add_argument("--orientation", default="perpendicular")
    ap.add_argument("--depth", default="0:3:0.5")
    ap.add_argument("--ooc-core-mb", type=int, default=1000, help="in-core memory of the out-of-core settings")
    ap.add_argument("--work", default="out/pardiso_options")
    ap.add_argument("--no-write", action="store_true", help="print only, do not append to results/pardiso_options.md")
    ap.add_argument("--one", help=argparse.SUPPRESS)           # a setting, in its own process
    args = ap.parse_args(argv)
    work = Path(args.work).resolve()
    if args.one:
        print(json.dumps(run_setting(work, args.one)))
        return
    work.mkdir(parents=True, exist_ok=True)
    capture(args.model_dir, work, args.indentor, args.orientation, args.depth)
    upper, schur = sp.load_npz(work / "upper.npz"), np.load(work / "schur.npy")
    lines = [f"## {time.strftime('%Y-%m-%d %H:%M')}: {platform.machine()}, {os.cpu_count()} cores, "
             f"load average {os.getloadavg()[0]:.1f} at the start",
             "", f"{args.model_dir}: {args.indentor} {args.orientation} at {args.depth} mm; saddle matrix "
             f"{upper.shape[0]} rows, {upper.nnz} upper non-zeros, {len(schur)} condensed rows", "",
             "| setting | analysis s | factorisation s | nnz(L) M | GFlop | PARDISO factor MB | process peak MB |",
             "|---|---:|---:|---:|---:|---:|---:|"]
    print("\n".join(lines), flush=True)
    env = {**os.environ, "MKL_PARDISO_OOC_MAX_CORE_SIZE": str(args.ooc_core_mb)}
    notes = []
    for name in args.options:
        done = subprocess.run([sys.executable, __file__, args.model_dir, "--work", str(work), "--one", name],
                              capture_output=True, text=True, env=env, cwd=work)
        if done.returncode:
            lines.append(f"| {name} | failed: {done.stderr.strip().splitlines()[-1]} |||||")
        else:
            r = json.loads(done.stdout.strip().splitlines()[-1])
            lines.append(f"| {name} | {r['analysis_s']:.2f} | {r['factorisation_s']:.2f} | {r['nnz_L_M']:.0f} "
                         f"| {r['gflop']:.0f} | {r['pardiso_factor_MB']:.0f} | {r['process_peak_MB']:.0f} |")
            notes.extend([f"- {name}: {r['note']}."] if "note" in r else [])
        print(lines[-1], flush=True)
    lines.extend([""] + notes if notes else [])
    print("\n".join(notes), flush=True)
    if not args.no_write:
        with open(RESULTS, "a") as f:
            f.write("\n".join(lines) + "\n\n")


if __name__ == "__main__":
    main()
