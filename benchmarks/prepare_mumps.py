#!/usr/bin/env python
"""The whole-pad response model (`pipeline.py prepare`) by another direct solver: MUMPS computing
the needed entries of the inverse, against this project's PARDISO path, on one model's matrix.

`prepare` needs, per contact candidate j (a unit load along the approach), the displacement at
every candidate and at every unknown the receptor operators read. The project's path factorises
with the candidates ordered last (a PARDISO Schur complement) and runs one full backward
substitution per candidate (`fem.experiments.response.build_response`). MUMPS (ICNTL(30)) computes
entries of the inverse directly: a factorisation with no ordering constraint, and per block of
candidates a solve that exploits the unit right-hand sides (a pruned forward substitution) and
stops the backward one at the requested rows. This script times both on a block of candidates,
extrapolates to all of them, and compares the entries they give.

Needs MUMPS and its Python binding, which are not dependencies of the project (python-mumps has no
binary package on PyPI for Linux; it builds against the system's library):

    apt-get install libmumps-seq-dev libopenblas0-pthread     # Debian: MUMPS 5.5 with SCOTCH
    pip install python-mumps
    python benchmarks/prepare_mumps.py /work/models/human05 [--block 128] [--blocks 3] [--ooc]

Prints, for each solver, the factorisation's seconds and memory, milliseconds per candidate,
the extrapolated total, and the largest difference between the two solvers' entries relative to
the largest entry; writes benchmarks/results/prepare_mumps.md.
"""
from __future__ import annotations

import argparse
import resource
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
OUT = ROOT / "benchmarks" / "results" / "prepare_mumps.md"


def peak_gb() -> float:
    """The process's peak resident memory so far [GB]."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2 ** 20


def problem(model_dir):
    """(model, free DOFs (n_free,), the saddle matrix's upper triangle on them (`Model.free_saddle`),
    candidate nodes (k,), their free positions (k,) sorted, their coordinates (k, 3) [mm], the
    requested free positions (r,): candidates and the receptor operators' support, the approach
    (3,)) for the default material, approach and receptor grid of a model folder."""
    from fem.core.system import condense_plan
    from fem.experiments import runner as R
    from fem.io.modelfolder import CONTACT_REGION, approach_down, held_regions
    from fem.receptors.grid import ReceptorSampler

    model, info = R.read_model(model_dir, None, None)
    sn = model.surface_nodes(CONTACT_REGION[model.dim])
    a = approach_down(info)
    free, upper = model.free_saddle(held_regions(model))
    nodes, _, pos, T = condense_plan(model, free, sn.nodes, a)
    if T is not None:
        print("error: this benchmark handles approaches along a coordinate axis only", file=sys.stderr)
        raise SystemExit(2)
    rec = R.Receptors()
    grid = R.receptor_grid(*R.receptor_surface(model, sn), np.asarray(rec.depths_mm, float), rec.spacing_mm,
                           R.receptor_line(rec.line, sn, model.dim))
    sampler = ReceptorSampler(model, grid)
    read = sampler.operator[:sampler.independent].tocsc()          # displacement and strain rows
    support = np.flatnonzero(np.diff(read.indptr))
    is_free = np.zeros(model.ndof, bool)
    is_free[free] = True
    order = np.argsort(pos)
    rows = np.union1d(np.searchsorted(free, support[is_free[support]]), pos)
    xyz = sn.x[np.searchsorted(sn.nodes, nodes[order])]
    return model, free, upper, nodes[order], pos[order], xyz, rows, a


def timed_blocks(xyz, block: int, blocks: int) -> list[np.ndarray]:
    """`blocks` of the blocks of neighbouring candidates that `prepare` solves together
    (`fem.core.inverse.local_blocks`), spread evenly over them, since the cost of a solve depends
    on where its loads sit."""
    from fem.core.inverse import local_blocks

    every = local_blocks(xyz, block)
    return [every[i] for i in np.linspace(0, len(every) - 1, blocks).astype(int)]


def mumps_entries(upper, cols, rows, timed, ooc: bool):
    """MUMPS through `fem.core.inverse.InverseEntries`: (analysis and factorisation s, MUMPS's
    memory MB, factor non-zeros, seconds per candidate, entries (r, blocks * block) of the inverse
    at `rows` for the timed columns)."""
    from fem.core.inverse import InverseEntries

    t0 = time.perf_counter()
    entries = InverseEntries(upper, out_of_core=ooc)
    factor_s = time.perf_counter() - t0
    out, solve_s = [], 0.0
    for block in timed:
        t = time.perf_counter()
        out.append(entries.block(rows, cols[block]))
        solve_s += time.perf_counter() - t
    return factor_s, entries.stats.memory, entries.stats.nonzeros, solve_s / sum(map(len, timed)), np.hstack(out)


def pardiso_entries(model, free, nodes, rows, a, timed):
    """This project's path: (factorisation s, seconds per candidate, the same entries (r, blocks *
    block)) from `Model.system(condense=...)` and `LinearSystem.solve_condensed`."""
    from fem.io.modelfolder import held_regions

    t0 = time.perf_counter()
    system = model.system(held_regions(model), condense=(nodes, a))
    factor_s = time.perf_counter() - t0
    sign = float(np.sign(a[np.argmax(np.abs(a))]))       # a unit load along a: -1 on the y DOF for -y
    out, solve_s = [], 0.0
    for block in timed:
        t = time.perf_counter()
        u = system.solve_condensed(nodes[block], a, check=False)
        solve_s += time.perf_counter() - t
        out.append(sign * u[free[rows]])
    model.release_factors()
    return factor_s, solve_s / sum(map(len, timed)), np.hstack(out)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("model", type=Path)
    ap.add_argument("--block", type=int, default=128, help="candidates per solve")
    ap.add_argument("--blocks", type=int, default=3, help="blocks timed (then extrapolated)")
    ap.add_argument("--ooc", action="store_true", help="MUMPS out of core (factors on disk)")
    ap.add_argument("--no-write", action="store_true")
    args = ap.parse_args()
    from fem.core.inverse import available, loaded_openblas_kernel

    if not available():                              # refused before any computation
        print("error: python-mumps is not installed: apt-get install libmumps-seq-dev libopenblas0-pthread, "
              "then pip install python-mumps", file=sys.stderr)
        raise SystemExit(2)
    if not (args.model / "mesh.vtu").is_file():
        print(f"error: {args.model} is not a model folder (no mesh.vtu): give one made by pipeline.py mesh",
              file=sys.stderr)
        raise SystemExit(2)

    model, free, upper, nodes, cols, xyz, rows, a = problem(args.model)
    k = len(cols)
    timed = timed_blocks(xyz, args.block, args.blocks)
    print(f"{args.model}: {upper.shape[0]:,} unknowns, {k:,} candidates, {len(rows):,} requested rows", flush=True)
    m_f, m_mb, m_nnz, m_per, m_x = mumps_entries(upper, cols, rows, timed, args.ooc)
    m_peak = peak_gb()
    del upper
    print(f"MUMPS: factorisation {m_f:.1f} s ({m_mb} MB, {m_nnz / 1e6:.0f} M non-zeros), "
          f"{1e3 * m_per:.2f} ms per candidate, process peak {m_peak:.2f} GB", flush=True)
    p_f, p_per, p_x = pardiso_entries(model, free, nodes, rows, a, timed)
    err = float(np.abs(m_x - p_x).max() / np.abs(p_x).max())
    print(f"PARDISO: factorisation with the Schur complement {p_f:.1f} s, {1e3 * p_per:.2f} ms per candidate; "
          f"largest difference {err:.1e}", flush=True)
    lines = [f"| solver | factorisation s | ms per candidate | {k:,} candidates s (extrapolated) | total s | note |",
             "|---|---|---|---|---|---|",
             f"| MUMPS 5.5 ({'out of core' if args.ooc else 'in core'}, `fem.core.inverse`) | "
             f"{m_f:.1f} | {1e3 * m_per:.2f} | {m_per * k:.0f} | {m_f + m_per * k:.0f} | "
             f"{m_mb} MB, {m_nnz / 1e6:.0f} M non-zeros, process peak {m_peak:.2f} GB, "
             f"OpenBLAS kernel {loaded_openblas_kernel()} |",
             f"| PARDISO (this project: Schur complement, backward substitutions) | {p_f:.1f} | {1e3 * p_per:.2f} | "
             f"{p_per * k:.0f} | {p_f + p_per * k:.0f} | |",
             "", f"Largest difference of the {m_x.size:,} entries compared, relative to the largest: {err:.1e}."]
    text = "\n".join(lines)
    print(text)
    if not args.no_write:
        if not OUT.exists():
            OUT.write_text("# The whole-pad response model by MUMPS (inverse entries) against PARDISO\n")
        with OUT.open("a") as f:
            f.write(f"\n## {time.strftime('%Y-%m-%d %H:%M')}: `python benchmarks/prepare_mumps.py {args.model} "
                    f"--block {args.block} --blocks {args.blocks}"
                    f"{' --ooc' if args.ooc else ''}`\n\n{what_was_timed(k, len(rows), args)}\n\n{text}\n")


def what_was_timed(k: int, r: int, args) -> str:
    """One line on what was timed."""
    return (f"{args.blocks} blocks of {args.block} neighbouring candidates of the {k:,} timed (spread over them), "
            f"{r:,} rows requested per candidate (the candidates and the receptor operators' unknowns); totals exclude "
            f"rounding and writing.")


if __name__ == "__main__":
    main()
