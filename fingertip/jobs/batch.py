"""The `batch` job: a cohort of subjects, each reconstruct -> mesh -> scene, in this process or on
Dask (fingertip.distribute), then `summary.csv` and `cohort.png` comparing them.

    subjects = parse_subjects(["preset:cylinder8:bone", "scans/s01", "out/s02"])   # checks, reads no pixels
    text = run_batch(subjects, "scenes/bars.toml", "out/cohort", sizes={"size_mm": 1.0}, scheduler="local:2")

A SUBJECT is a turntable folder (reconstructed first), a folder with sections.json (or the file),
or `preset:NAME` (3D human, monkey; 2D block, square, cylinder8, cylinder16, the cylinders with a
`:bone` suffix for the central bone). Subject <name> (the preset, `cylinder8_bone`, or the
folder's name) is written to DIR/<name>/ (sections.json, mesh.vtu, model.json) and its run folder
DIR/<name>/<scene stem>/; every stage skips what is current, as its own command does. A task is
one subject; it reads and writes only its own folder under DIR, which workers must share.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from fem.experiments.scene import load_scene
from fem.geometry.build import MeshSpec
from fem.geometry.layered import PRESET_PARAMS
from fem.geometry.presets import PRESETS_2D
from fingertip.distribute import TaskFailed, TaskRunner, parse_scheduler, require_dask
from fingertip.errors import InputError
from fingertip.jobs.indent import RUN_MARKER, run_indent
from fingertip.jobs.mesh import check_mesh, mesh_folder
from fingertip.jobs.reconstruct import run_reconstruct
from fingertip.jobs.tasks import task_threads
from fingertip.progress import as_progress
from fingertip.staging import check_output_dir, claimed, staged_output
from fingertip.tables import write_csv
from reconstruct.turntable import load_turntable

SUMMARY_COLUMNS = ("subject", "experiment", "step", "depth_mm", "force_N", "max_pressure_MPa", "peak_pressure_MPa",
                   "contact_area_mm2")
"""Leading columns of summary.csv; then peak_<measure> per receptor measure, then error."""


@dataclass(frozen=True)
class Subject:
    """One subject of a cohort: kind "images" (turntable folder), "sections" (sections.json
    folder or file) or "preset"; source: the path or the preset name; bone: 2D cylinder bone."""
    name: str
    kind: str
    source: str
    bone: bool = False

    @property
    def two_d(self) -> bool:
        return self.kind == "preset" and self.source in PRESETS_2D

    def mesh_spec(self, out_dir, mesh: MeshOptions) -> MeshSpec:
        """The MeshSpec of this subject in cohort folder out_dir with the cohort's mesh options."""
        source = None if self.kind == "preset" else (str(Path(out_dir) / self.name) if self.kind == "images"
                                                     else self.source)
        params = {} if self.two_d else {"tip_mm": mesh.tip_mm}
        return MeshSpec(source=source, preset=self.source if self.kind == "preset" else None, bone=self.bone,
                        params=params, sizes=dict(mesh.sizes))


@dataclass(frozen=True)
class MeshOptions:
    """The mesh options every subject shares: sizes (given `fem.geometry.build.SIZE_FIELDS`; the
    others each model's default) and the 3D distal end tip_mm (`fem.geometry.layered.parse_tip`)."""
    sizes: dict = field(default_factory=dict)
    tip_mm: float | None = 0.0


def parse_subject(word: str) -> Subject:
    """One SUBJECT word -> Subject; InputError for an unknown preset or a path that is neither a
    turntable folder nor a sections.json folder. Reads image headers only."""
    if word.startswith("preset:"):
        name, _, suffix = word[len("preset:"):].partition(":")
        known = sorted(PRESET_PARAMS) + list(PRESETS_2D)
        if name not in known:
            raise InputError(f"subject '{word}': unknown preset '{name}'; use preset:NAME with NAME one of {known}")
        if suffix not in ("", "bone") or (suffix == "bone" and name not in ("cylinder8", "cylinder16")):
            raise InputError(f"subject '{word}': only the 2D cylinders take a suffix, ':bone' "
                             f"(preset:cylinder8:bone or preset:cylinder16:bone)")
        bone = suffix == "bone"
        return Subject(name + ("_bone" if bone else ""), "preset", name, bone)
    path = Path(word)
    if path.is_file() and path.suffix == ".json":
        return Subject(path.resolve().parent.name, "sections", str(path))
    if path.exists() and not path.is_dir():
        raise InputError(f"subject '{word}' is a file but not a sections.json: give a turntable folder, a folder "
                         f"with sections.json, or preset:NAME")
    if not path.is_dir():
        raise InputError(f"subject '{word}' does not exist: give a turntable folder, a folder with "
                         f"sections.json, or preset:NAME")
    if (path / "sections.json").is_file():
        return Subject(path.resolve().name, "sections", str(path))
    load_turntable(path)                    # InputError says what the folder lacks
    return Subject(path.resolve().name, "images", str(path))


def parse_subjects(words: list[str]) -> list[Subject]:
    """SUBJECT words -> Subjects in order; InputError for a bad one or two with the same name
    (their output folders would collide)."""
    if not words:
        raise InputError("batch needs at least one SUBJECT (a turntable folder, a sections.json folder "
                         "or preset:NAME)")
    subjects = [parse_subject(w) for w in words]
    seen = {}
    for word, s in zip(words, subjects):
        if s.name in seen:
            raise InputError(f"subjects '{seen[s.name]}' and '{word}' are both named '{s.name}' (their "
                             f"output folder): give each subject once, or rename one folder")
        seen[s.name] = word
    return subjects


def check_batch(subjects: list[Subject], scene_path, out_dir, mesh: MeshOptions = MeshOptions(),
                scheduler: str | None = None):
    """Every check of `run_batch` before any work: the scene (and its experiments on each
    subject's dimension), the mesh options of each subject, the output folder and the scheduler
    (Dask installed when needed). Returns (Scene, fingertip.distribute.Scheduler)."""
    sched = parse_scheduler(scheduler)
    if scene_path is None:
        raise InputError("batch needs --scene S.toml (the experiments every subject runs)")
    scene = load_scene(scene_path)
    check_output_dir(out_dir)
    for s in subjects:
        try:
            scene.check_dim(2 if s.two_d else 3)
            check_mesh(Path(out_dir) / s.name, s.mesh_spec(out_dir, mesh))
            check_output_dir(Path(out_dir) / s.name / Path(scene_path).stem, marker=RUN_MARKER, what="indent run")
        except InputError as exc:
            raise InputError(f"subject '{s.name}': {exc}") from None
    require_dask(sched)
    return scene, sched


def run_subject(subject: Subject, out_dir: str, scene_path: str, mesh: MeshOptions, force: bool = False) -> dict:
    """One task: reconstruct (turntable folders) -> mesh -> the scene, into out_dir/<name>/.
    Returns {"subject", "rows" (summary rows, `run_rows`), "error" (one line or ''), "seconds"};
    a subject's InputError or internal error becomes its error, not an exception. BLAS and
    PARDISO run on TASK_THREADS threads wherever the task runs, so its sums are done in one order
    and a worker writes the bytes this process would."""
    start = time.perf_counter()
    folder = Path(out_dir) / subject.name
    try:
        with task_threads():
            if subject.kind == "images":
                run_reconstruct(subject.source, folder, force=force)
            mesh_folder(folder, subject.mesh_spec(out_dir, mesh), force=force, progress=False)
            done = run_indent(folder, folder / Path(scene_path).stem, load_scene(scene_path), progress=False)
        rows, error = run_rows(subject.name, done.tables), ""
    except InputError as exc:
        rows, error = [], " ".join(str(exc).split())
    except Exception as exc:  # noqa: BLE001 - one subject's bug must not stop the cohort
        rows, error = [], " ".join(f"internal error {type(exc).__name__}: {exc}".split())
    return {"subject": subject.name, "rows": rows, "error": error, "seconds": time.perf_counter() - start}


def run_rows(subject: str, tables: dict) -> list[dict]:
    """Summary rows of one run (`fingertip.jobs.indent.Indented.tables`), one per experiment and
    indentation step in the scene's order: depth, force (N; N/mm in 2D), peak pressure, contact
    area (2D: width) and per receptor measure its peak, the largest absolute value over the
    receptor points at that step."""
    rows = []
    for name, table in tables.items():
        steps = table["steps"]
        peaks = {m: np.abs(v).max(axis=1) for m, v in table["values"].items()}
        for i in range(len(steps["step"])):
            rows.append({"subject": subject, "experiment": name, "step": i,
                         **{c: float(steps[c][i]) for c in SUMMARY_COLUMNS[3:]},
                         **{f"peak_{m}": float(v[i]) for m, v in peaks.items()}})
    return rows


def summary_table(results: list[dict]) -> dict[str, list]:
    """summary.csv columns from the task results in subject order: a subject's rows, or one row
    with its error (the other columns empty)."""
    peaks = []
    for r in results:
        for row in r["rows"]:
            peaks += [k for k in row if k.startswith("peak_") and k not in peaks]
    columns = list(SUMMARY_COLUMNS) + peaks + ["error"]
    rows = []
    for r in results:
        if r["error"] or not r["rows"]:
            text = {"subject": r["subject"], "experiment": "", "error": r["error"] or "no experiments"}
            rows.append({c: text.get(c, math.nan) for c in columns})
        rows += [{c: row.get(c, math.nan) if c != "error" else "" for c in columns} for row in r["rows"]]
    return {c: [row[c] for row in rows] for c in columns}


def cohort_curves(results: list[dict]) -> dict:
    """{experiment: {subject: (depth_mm (k,), force (k,), peak_pressure_MPa (k,))}} of the
    subjects that ran, for fem.plots.cohort_figure."""
    curves = {}
    for r in results:
        by_exp = {}
        for row in r["rows"]:
            by_exp.setdefault(row["experiment"], []).append(row)
        for exp, rows in by_exp.items():
            curves.setdefault(exp, {})[r["subject"]] = tuple(
                np.array([row[c] for row in rows]) for c in ("depth_mm", "force_N", "peak_pressure_MPa"))
    return curves


def run_batch(subjects: list[Subject], scene_path, out_dir, mesh: MeshOptions = MeshOptions(),
              scheduler: str | None = None, force: bool = False, progress=True) -> str:
    """`pipeline.py batch`: every subject through the scene, then out_dir/summary.csv and
    cohort.png; returns the summary text. Checks everything first (`check_batch`). progress:
    True (on stderr), False, or a progress object: a line per subject as it ends."""
    _, sched = check_batch(subjects, scene_path, out_dir, mesh, scheduler)
    with claimed(out_dir):
        return _run_batch(subjects, scene_path, Path(out_dir), mesh, sched, force, progress)


def _run_batch(subjects, scene_path, out: Path, mesh: MeshOptions, sched, force: bool, progress) -> str:
    """`run_batch` after its checks, holding the cohort folder."""
    from fem import plots  # matplotlib: 0.4 s of import, not needed by the tasks

    out.mkdir(parents=True, exist_ok=True)
    calls = [(s, str(out), str(scene_path), mesh, force) for s in subjects]
    progress = as_progress(progress)

    def done(i, result):
        text = (f"failed: {result}" if isinstance(result, TaskFailed) else
                f"failed: {result['error']}" if result["error"] else f"done in {result['seconds']:.1f} s")
        progress.note(f"batch: {subjects[i].name}: {text}")

    with TaskRunner(sched) as runner:
        progress.note(f"batch: {len(subjects)} subject(s) on scheduler {sched} ({runner.workers} worker(s))")
        results = runner.map(run_subject, calls, done=done)
        stats = runner.stats
    results = [{"subject": s.name, "rows": [], "error": f"task failed: {r}", "seconds": math.nan}
               if isinstance(r, TaskFailed) else r for s, r in zip(subjects, results)]
    table = summary_table(results)
    curves = cohort_curves(results)
    with staged_output(out) as tmp:
        write_csv(tmp / "summary.csv", table, nan="")
        if curves:
            plots.save(plots.cohort_figure(curves, Path(scene_path).stem), tmp / "cohort.png")
    failed = [r for r in results if r["error"]]
    lines = [(f"batch of {len(subjects)} subject(s) in {out} ({stats.seconds:.1f} s on scheduler {sched}; "
              f"{len(failed)} failed)")]
    lines += [f"  {r['subject']}: " + (f"FAILED: {r['error']}" if r["error"] else
                                       (f"{len({row['experiment'] for row in r['rows']})} experiment(s), "
                                        f"{len(r['rows'])} indentation(s), {r['seconds']:.1f} s")) for r in results]
    lines.append(f"  summary.csv ({len(table['subject'])} rows){', cohort.png' if curves else ''}")
    return "\n".join(lines)
