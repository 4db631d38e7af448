#!/usr/bin/env python
"""The project against the plain peer a competent user would write, on the same mesh and scene, in
one process, interleaved; time ratio next to the force difference, and peak memory.

    python benchmarks/peer_bench.py 2d                      # cylinder8 with bone, C5 at 0.25:1:0.25 mm
    python benchmarks/peer_bench.py 3d --size 1.0           # monkey, C5 perpendicular at 0.5:1.5:0.5 mm
    python benchmarks/peer_bench.py 2d 3d --rounds 2 --work out/peer_bench

The peer (`peer_indent`): scikit-fem P2 assembly of the model folder's mesh with the standard
displacement formulation (2 mu eps:eps + lambda div div, per-element Lame parameters of the same
material), the same held regions, contact candidates (the contact region's P2 nodes) and indentor
geometry, and an active-set loop per depth that imposes the indentor's travel on the active
candidates' DOF along the approach and re-factorises K_ff with pypardiso every iteration (warm
started from the previous depth's active set), until no candidate is in tension or penetrates.

The project, each round: its first run (`indent` below, the work of `pipeline.py indent`:
`fem.experiments.runner.run_scene` and the run folder written, with no stored response model:
assembly, factorisation with the reachable candidates condensed, receptor operators), its build
(`fem.experiments.runner.prepare_responses`, as `pipeline.py prepare`: every candidate condensed)
and its repeat run (answered by the stored response model), all with no PVD and no plots (CSVs and
run.json written, receptor measures computed; the peer computes forces only). The repeat run is
also timed as its own command (`python pipeline.py indent ...`: wall time including interpreter
start-up and imports; best of CLI_RUNS runs).

Timed: reading the mesh onward; meshing is not counted (cached). Memory: the process's resident
set before each phase and its peak during it (VmHWM after resetting it through
/proc/self/clear_refs; on other systems the process peak so far). Memory an earlier phase freed
but the allocators kept (MKL, glibc) stays resident, so a phase's peak is at least the "before"
column; the whole repeat command runs in its own process, whose peak is its own. Force difference: max over depths of |F_peer / F_project - 1|,
the difference of the two elements (the project's mixed P2-P1 pressure against plain P2, which
is stiffer at nu = 0.48). Writes benchmarks/results/peer_bench.md (one section per run).
"""
from __future__ import annotations

import argparse
import csv
import os
import platform
import resource
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pypardiso
from skfem import Basis, BilinearForm, asm
from skfem.helpers import ddot, div, sym_grad

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from fem.contact.indentors import make_indentor  # noqa: E402
from fem.core.linalg import _thread_controller  # noqa: E402
from fem.experiments.response import ResponseStore  # noqa: E402
from fem.experiments.runner import placement, prepare_responses, run_scene  # noqa: E402
from fem.experiments.scene import Scene  # noqa: E402
from fem.geometry.build import MeshSpec, build_folder  # noqa: E402
from fem.io.modelfolder import CONTACT_REGION, held_regions, read_model  # noqa: E402
from fem.io.runfolder import write_run  # noqa: E402
from fingertip.staging import staged_output  # noqa: E402

RESULTS = ROOT / "benchmarks" / "results" / "peer_bench.md"
CLI_RUNS = 3
"""Runs of the whole repeat command per round (the best is kept: a single start-up of the
interpreter varies by 0.1-0.3 s on the shared machine)."""
CASES = {"2d": {"preset": "cylinder8", "bone": True, "indentor": "C5", "orientation": "parallel",
                    "depth": "0.25:1:0.25"},
         "3d": {"preset": "monkey", "bone": False, "indentor": "C5", "orientation": "perpendicular",
                    "depth": "0.5:1.5:0.5"}}


# --------------------------------------------------------------------------- the peer
def peer_indent(model_dir, scene, max_iterations: int = 50) -> dict:
    """Forces (N; N/mm in 2D) at the scene's depths by the plain peer (module docstring) for the
    first experiment of `scene` (a depth-controlled one along a coordinate axis). Returns
    {"force_N": [...], "factorisations": int, "iterations": [...] per depth, "active": [...]}."""
    model, info = read_model(model_dir, scene.material, scene.nu)       # meshio + the same regions
    dim = model.dim
    basis = Basis(model.mesh, model.element, intorder=2)                # skfem's vector P2 basis

    @BilinearForm
    def elasticity(u, v, w):
        return 2 * w.mu * ddot(sym_grad(u), sym_grad(v)) + w.lam * div(u) * div(v)

    mu, lam = model.material.lame(model.layer)                          # per element, MPa
    nqp = basis.X.shape[1]
    K = asm(elasticity, basis, mu=np.repeat(mu[:, None], nqp, 1), lam=np.repeat(lam[:, None], nqp, 1)).tocsr()
    fixed, _ = model.discretisation.constraints(held_regions(model), model.material.rigid)   # all held values are 0

    exp = scene.experiments[0]
    sn = model.surface_nodes(CONTACT_REGION[dim])
    place, _ = placement(exp, model, info, sn)
    ind = make_indentor(exp.indentor, **place)
    a = np.asarray(ind.approach, float)[:dim]
    axis = int(np.argmax(np.abs(a)))
    if abs(abs(a[axis]) - 1) > 1e-12:
        raise ValueError("the peer handles approaches along a coordinate axis only")
    sign = a[axis]
    dof = sn.dofs[:, axis]
    ok = ~np.isin(dof, fixed)                                           # held candidates cannot move
    standoff = ind.standoff(sn.x)[ok]
    g0 = standoff - standoff[np.isfinite(standoff)].min()                # gap at first touch, mm
    dof = dof[ok]
    n = K.shape[0]
    active = np.zeros(len(dof), bool)
    out = {"force_N": [], "factorisations": 0, "iterations": [], "active": []}
    for depth in exp.depth_mm:
        target = sign * (depth - g0)                                    # u[dof] on an active candidate
        active |= g0 < depth
        for it in range(1, max_iterations + 1):
            held = np.union1d(fixed, dof[active])
            free = np.setdiff1d(np.arange(n), held)
            u = np.zeros(n)
            u[dof[active]] = target[active]
            rhs = -(K[free][:, held] @ u[held])
            u[free] = pypardiso.spsolve(K[free][:, free].tocsr(), rhs)
            out["factorisations"] += 1
            reaction = sign * (K[dof] @ u)                               # along the approach, N
            tension = active & (reaction < 0)
            penetrates = ~active & (sign * u[dof] < depth - g0 - 1e-12)
            if not tension.any() and not penetrates.any():
                break
            active = (active & ~tension) | penetrates
        out["force_N"].append(float(reaction[active].sum()))
        out["iterations"].append(it)
        out["active"].append(int(active.sum()))
    return out


# --------------------------------------------------------------------------- measurement
def _reset_peak() -> None:
    try:
        Path("/proc/self/clear_refs").write_text("5")
    except OSError:
        pass


def _status_mb(key: str) -> float:
    """VmHWM or VmRSS of this process in MB (the process peak from getrusage without /proc)."""
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith(key + ":"):
                return int(line.split()[1]) / 1024
    except OSError:
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def _timed(fn):
    """(result, wall seconds, (resident MB before, peak resident MB during the call))."""
    _reset_peak()
    before = _status_mb("VmRSS")
    t = time.perf_counter()
    result = fn()
    return result, time.perf_counter() - t, (before, _status_mb("VmHWM"))


def _command(command, report: Path):
    """(wall seconds, (NaN, peak resident MB)) of a command in its own process; the peak from GNU
    time (getrusage of a forked child would count the parent's pages), NaN without it."""
    gnu_time = shutil.which("time") or ("/usr/bin/time" if Path("/usr/bin/time").is_file() else None)
    t = time.perf_counter()
    if gnu_time:
        subprocess.run([gnu_time, "-f", "%M", "-o", str(report), *command], check=True)
        seconds = time.perf_counter() - t
        return seconds, (float("nan"), int(report.read_text().split()[-1]) / 1024)
    subprocess.run(command, check=True)
    return time.perf_counter() - t, (float("nan"), float("nan"))


def _warm_up() -> None:
    """Once-per-process costs out of the timings of whoever runs first: the BLAS thread scan (the
    imports both sides use, scikit-fem and pypardiso with its library search, are at the top)."""
    _thread_controller()


def indent(model_dir, out_dir, scene) -> None:
    """What the `indent` command does but its summary: the scene on the model folder (answered by
    its stored response model when it keeps one, else factorised) written as a run folder."""
    run = run_scene(model_dir, scene, store=ResponseStore.existing(model_dir))
    with staged_output(out_dir) as tmp:
        write_run(tmp, model_dir, run, run.afferents)


def _forces(run_dir, name) -> list[float]:
    with open(Path(run_dir) / f"{name}.csv") as fh:
        return [float(r["force_N"]) for r in csv.DictReader(fh)]


def run_case(case: str, work: Path, size: float, rounds: int) -> list[str]:
    """Mesh (cached, not timed) and `rounds` interleaved rounds; returns the Markdown lines."""
    spec = CASES[case]
    name = f"{spec['preset']}{'_' + str(size) if case == '3d' else ''}"
    model_dir = work / name
    if not (model_dir / "mesh.vtu").is_file():
        build_folder(model_dir, MeshSpec(preset=spec["preset"], bone=spec["bone"],
                                         sizes={"size_mm": size} if case == "3d" else {}))
    exp = spec["indentor"]
    scene = Scene.from_dict({"experiment": [{"name": exp, "indentor": spec["indentor"],
                                             "orientation": spec["orientation"], "depth_mm": spec["depth"]}],
                             "output": {"pvd": False, "plots": False}})
    command = [sys.executable, str(ROOT / "pipeline.py"), "indent", str(model_dir), "--indentor", spec["indentor"],
               "--orientation", spec["orientation"], "--depth", spec["depth"], "--no-pvd", "--no-plots",
               "--quiet", "--out", str(work / "run_cli")]
    rows = {k: [] for k in ("first", "build", "repeat", "repeat_cli", "peer")}
    _warm_up()
    for r in range(rounds):
        shutil.rmtree(model_dir / "response", ignore_errors=True)
        for folder in ("run_first", "run_repeat", "run_cli"):
            shutil.rmtree(work / folder, ignore_errors=True)
        _, t, mb = _timed(lambda: indent(model_dir, work / "run_first", scene))
        rows["first"].append((t, mb))
        first = _forces(work / "run_first", exp)
        _, t, mb = _timed(lambda: prepare_responses(model_dir))
        rows["build"].append((t, mb))
        _, t, mb = _timed(lambda: indent(model_dir, work / "run_repeat", scene))
        rows["repeat"].append((t, mb))
        repeat = _forces(work / "run_repeat", exp)
        rows["repeat_cli"].append(min(_command(command, work / "time.txt") for _ in range(CLI_RUNS)))
        peer, t, mb = _timed(lambda: peer_indent(model_dir, scene))
        rows["peer"].append((t, mb))
        print(f"{case} round {r + 1}: first {rows['first'][-1][0]:.2f} s, build {rows['build'][-1][0]:.2f} s, "
              f"repeat {rows['repeat'][-1][0]:.3f} s (command {rows['repeat_cli'][-1][0]:.2f} s), "
              f"peer {rows['peer'][-1][0]:.2f} s", file=sys.stderr, flush=True)
    best = {k: min(v) for k, v in rows.items()}
    peer_t = best["peer"][0]
    diff = max(abs(p / f - 1) for p, f in zip(peer["force_N"], first))
    same = max(abs(b / f - 1) for b, f in zip(repeat, first))
    model, _ = read_model(model_dir)
    unit = "N/mm" if model.dim == 2 else "N"
    lines = [f"### {case.upper()}: {name} ({model.ndof} DOFs), {spec['indentor']} {spec['orientation']}, "
             f"depths {spec['depth']} mm", "",
             "| run | wall s | peer / run | MB before | peak MB | forces |", "|---|---:|---:|---:|---:|---|"]
    fmt = ", ".join

    def row(label, key, ratio, note):
        t, (before, peak) = best[key]
        return f"| {label} | {t:.3g} | {ratio} | {before:.0f} | {peak:.0f} | {note} |".replace("| nan |", "| |")

    lines += [row("project first run (factorised)", "first", f"{peer_t / best['first'][0]:.1f}x",
                  f"{fmt(f'{v:.5g}' for v in first)} {unit}"),
              row("project prepare (build)", "build", "", ""),
              row("project repeat run (stored)", "repeat", f"{peer_t / best['repeat'][0]:.0f}x",
                  f"equal to the first run's within {same:.1e}"),
              row("project repeat run, whole command", "repeat_cli", f"{peer_t / best['repeat_cli'][0]:.1f}x",
                  "with interpreter start-up and imports; its own process"),
              row("peer (P2, active set, pypardiso)", "peer", "1", f"{fmt(f'{v:.5g}' for v in peer['force_N'])} {unit}")]
    lines += ["", f"Peer: {peer['factorisations']} factorisations, active-set iterations per depth "
              f"{peer['iterations']}, active candidates {peer['active']}. Force difference peer / project "
              f"first run: max {diff * 100:.2f} %. Best of {rounds} round{'s' if rounds > 1 else ''}.", ""]
    return lines


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("cases", nargs="+", choices=sorted(CASES))
    ap.add_argument("--size", type=float, default=1.0, help="3D volar edge length in mm (default 1.0)")
    ap.add_argument("--rounds", type=int, default=1, help="interleaved rounds; the best is reported (default 1)")
    ap.add_argument("--work", default="out/peer_bench", help="model and run folders (default out/peer_bench)")
    ap.add_argument("--no-write", action="store_true", help=f"print only, do not append to {RESULTS.name}")
    args = ap.parse_args(argv)
    work = Path(args.work)
    work.mkdir(parents=True, exist_ok=True)
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    lines = [f"## {time.strftime('%Y-%m-%d %H:%M')}: {platform.machine()}, {os.cpu_count()} cores, "
             f"load average {load:.1f} at the start", ""]
    for case in args.cases:
        lines += run_case(case, work, args.size, args.rounds)
    text = "\n".join(lines)
    print(text)
    if not args.no_write:
        RESULTS.parent.mkdir(exist_ok=True)
        head = "" if RESULTS.exists() else ("# Project against the plain peer\n\n`python benchmarks/peer_bench.py`; "
                                            "see docs/benchmarks.md.\n\n")
        with open(RESULTS, "a") as fh:
            fh.write(head + text + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
