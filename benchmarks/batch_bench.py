"""Cohorts on Dask: wall time of a small cohort in this process and on 1 and 2 local workers, the
per-task overhead of the scheduler, bytes shipped per task, the peak memory of a worker, and a
projection of 100 subjects on 1, 10 and 100 workers from the measured task times and sizes.

    python benchmarks/batch_bench.py                    # 2D cohort (4 subjects), about a minute
    python benchmarks/batch_bench.py --with-3d          # also one coarse 3D subject (monkey, size 1.5)
    python benchmarks/batch_bench.py --out benchmarks/results/batch_bench.md

Each subject is one task (`subject_task`: what a subject of `pipeline.py batch` does, from the science
API: mesh the preset, run the scene, write the run folder, BLAS and PARDISO on one thread): a few
hundred bytes of paths and options go to the worker, which reads and writes the subject's folder
under the shared output folder, and the subject's rows of batch's summary.csv come back.
"""
from __future__ import annotations

import argparse
import math
import operator
import platform
import resource
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from fem.core.linalg import blas_threads, load_mkl  # noqa: E402
from fem.experiments.response import ResponseStore  # noqa: E402
from fem.experiments.runner import run_scene  # noqa: E402
from fem.experiments.scene import load_scene  # noqa: E402
from fem.geometry.build import MeshSpec, build_folder  # noqa: E402
from fem.geometry.presets import PRESETS_2D  # noqa: E402
from fem.io.runfolder import write_run  # noqa: E402
from fingertip.distribute import Scheduler, TaskFailed, TaskRunner  # noqa: E402
from fingertip.staging import staged_output  # noqa: E402
from fingertip.tables import columns_of, csv_text  # noqa: E402

SCENE = """\
[receptors]
depths_mm = [0.5, 1.0]
spacing_mm = 1.0

[output]
plots = false
pvd = false

[[experiment]]
name = "C5"
indentor = "C5"
depth_mm = "0.25:1:0.25"
"""
SUBJECTS_2D = ["preset:cylinder8", "preset:cylinder8:bone", "preset:cylinder16", "preset:square"]
STEP_COLUMNS = ("depth_mm", "force_N", "max_pressure_MPa", "contact_area_mm2")
"""Columns of batch's summary.csv taken from a run's step table (after subject, experiment, step)."""


def subject_of(word: str, size_mm: float) -> tuple[str, MeshSpec]:
    """(name, MeshSpec) of a `preset:NAME[:bone]` subject word as batch meshes it: the cohort's
    size; a 3D preset with a flat distal cut (tip_mm 0, batch's default)."""
    preset, _, suffix = word[len("preset:"):].partition(":")
    params = {} if preset in PRESETS_2D else {"tip_mm": 0.0}
    return preset + ("_bone" if suffix else ""), MeshSpec(preset=preset, bone=suffix == "bone", params=params,
                                                          sizes={"size_mm": size_mm})


def summary_rows(subject: str, tables: dict) -> list[dict]:
    """A subject's rows of batch's summary.csv from its run tables (`fem.io.runfolder.write_run`): one
    per experiment and step, with the step's STEP_COLUMNS and per receptor measure its peak, the
    largest absolute value over the receptor points."""
    rows = []
    for name, table in tables.items():
        steps = table["steps"]
        peaks = {m: np.abs(v).max(axis=1) for m, v in table["values"].items()}
        rows += [{"subject": subject, "experiment": name, "step": i, **{c: float(steps[c][i]) for c in STEP_COLUMNS},
                  **{f"peak_{m}": float(v[i]) for m, v in peaks.items()}} for i in range(len(steps["step"]))]
    return rows


def subject_task(name: str, spec: MeshSpec, out_dir: str, scene_path: str) -> dict:
    """One task: the subject meshed into out_dir/<name>/ and the scene run and written to its run
    folder out_dir/<name>/<scene stem>/, on one BLAS and PARDISO thread. Returns its summary rows,
    the task's own seconds and the worker's peak resident memory (MB)."""
    t0 = time.perf_counter()
    folder = Path(out_dir) / name
    load_mkl()                                      # so that blas_threads limits MKL too
    with blas_threads(1):
        build_folder(folder, spec)
        run = run_scene(folder, load_scene(scene_path), store=ResponseStore.existing(folder))
        with staged_output(folder / Path(scene_path).stem) as tmp:
            tables = write_run(tmp, folder, run, run.afferents)
    return {"rows": summary_rows(name, tables), "task_s": time.perf_counter() - t0,
            "peak_rss_MB": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}


def cohort(words, scene, size_mm, scheduler, work) -> dict:
    """One cohort run on a fresh output folder: start-up, map seconds, per-task numbers."""
    out = Path(tempfile.mkdtemp(dir=work))
    calls = [(*subject_of(w, size_mm), str(out), str(scene)) for w in words]
    t0 = time.perf_counter()
    with TaskRunner(scheduler) as runner:
        started = time.perf_counter() - t0
        results = runner.map(subject_task, calls)
        stats = runner.stats
    failed = [r for r in results if isinstance(r, TaskFailed)]
    if failed:
        raise SystemExit(f"a subject failed: {failed[0]}")
    return {"scheduler": str(scheduler), "startup_s": started, "map_s": stats.seconds,
            "total_s": time.perf_counter() - t0, "task_s": [r["task_s"] for r in results],
            "task_bytes": stats.task_bytes, "result_bytes": stats.result_bytes,
            "peak_rss_MB": max(r["peak_rss_MB"] for r in results),
            "summary": csv_text(columns_of([row for r in results for row in r["rows"]]), nan="")}


def overhead(scheduler, n: int = 40) -> float:
    """Seconds per trivial task (operator.call(abs, -1)) on a running cluster, warm."""
    with TaskRunner(scheduler) as runner:
        runner.map(operator.call, [(abs, -1)] * 4)                   # warm up the workers
        runner.map(operator.call, [(abs, -1)] * n)
        return runner.stats.seconds / n


def projection(task_s: float, task_bytes: float, result_bytes: float, per_task_s: float, startup_s: float,
               n: int = 100, bandwidth: float = 100e6) -> list[tuple[int, float]]:
    """Seconds for n subjects of task_s each on W workers: start-up + ceil(n / W) rounds of
    (task + overhead) + the bytes through the scheduler at `bandwidth` B/s (they are small)."""
    return [(w, (0.0 if w == 1 else startup_s) + math.ceil(n / w) * (task_s + (0.0 if w == 1 else per_task_s))
             + n * (task_bytes + result_bytes) / bandwidth) for w in (1, 10, 100)]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--with-3d", action="store_true", help="also time one coarse 3D subject (monkey, size 1.5)")
    ap.add_argument("--out", help="write the Markdown report here (default: print it)")
    args = ap.parse_args()
    work = Path(tempfile.mkdtemp(prefix="batch_bench-"))
    scene = work / "scene.toml"
    scene.write_text(SCENE)
    runs = [cohort(SUBJECTS_2D, scene, 0.25, s, work)
            for s in (Scheduler(), Scheduler("local", 1), Scheduler("local", 2))]
    same = len({r["summary"] for r in runs}) == 1
    per_task = overhead(Scheduler("local", 2))
    two = runs[2]
    lines = [f"# batch_bench: cohorts on Dask ({platform.node()}, {platform.processor() or platform.machine()}, "
             f"Python {platform.python_version()})", "",
             f"Cohort: {len(SUBJECTS_2D)} 2D subjects ({', '.join(SUBJECTS_2D)}), mesh size 0.25 mm, one "
             "experiment of 4 depths (C5). Every run starts from an empty output folder.", "",
             "| scheduler | cluster start-up, s | map, s | total, s | mean task, s | bytes per task (call / result) "
             "| worker peak RSS, MB |", "|---|---|---|---|---|---|---|"]
    for r in runs:
        lines.append(f"| {r['scheduler']} | {r['startup_s']:.2f} | {r['map_s']:.2f} | {r['total_s']:.2f} | "
                     f"{statistics.mean(r['task_s']):.2f} | {statistics.mean(r['task_bytes']):.0f} / "
                     f"{statistics.mean(r['result_bytes']):.0f} | {r['peak_rss_MB']:.0f} |")
    lines += ["", f"summary.csv rows byte-identical across the three schedulers: {'yes' if same else 'NO'}", "",
              f"Per-task overhead of the scheduler (trivial tasks, 2 warm local workers): {per_task * 1e3:.1f} ms", ""]
    cases = [("2D subject", statistics.mean(two["task_s"][1:] or two["task_s"]), two)]
    if args.with_3d:
        r3 = cohort(["preset:monkey"], scene, 1.5, Scheduler("local", 1), work)
        lines += [f"One coarse 3D subject (preset:monkey, size 1.5 mm) on one local worker: task "
                  f"{r3['task_s'][0]:.1f} s, worker peak RSS {r3['peak_rss_MB']:.0f} MB, "
                  f"{r3['task_bytes'][0]} / {r3['result_bytes'][0]} bytes shipped.", ""]
        cases.append(("3D subject (monkey, 1.5 mm)", r3["task_s"][0], r3))
    lines += ["Projection for 100 subjects (start-up and overhead as measured; tasks of the measured mean "
              "length; bytes at 100 MB/s):", "", "| subject | task, s | 1 worker, s | 10 workers, s | 100 workers, s |",
              "|---|---|---|---|---|"]
    for name, t, r in cases:
        p = projection(t, statistics.mean(r["task_bytes"]), statistics.mean(r["result_bytes"]), per_task,
                       two["startup_s"])
        lines.append(f"| {name} | {t:.2f} | " + " | ".join(f"{s:.0f}" for _, s in p) + " |")
    text = "\n".join(lines) + "\n"
    if args.out:
        Path(args.out).write_text(text)
    print(text)


if __name__ == "__main__":
    main()
