"""The `analyze` job: read the indentation runs and the recorded rates, rank the
candidate measures per unit (fem.receptors.analysis), write the tables (CSV and Markdown; floats `.6g`, NaN
as an empty cell), the profile and scatter figures and analysis.json atomically, and return the
summary text."""
from __future__ import annotations

import math
from pathlib import Path

from fem import plots
from fem.io.runfolder import IndentRun
from fem.receptors.analysis import UnitAnalysis, analyze, as_runs
from fem.receptors.neural import NeuralData, read_neural_csv
from fingertip.errors import InputError
from fingertip.progress import as_progress
from fingertip.staging import check_output_dir, claimed, staged_output, write_json
from fingertip.tables import columns_of, write_csv, write_markdown

DPI = 110
FLOAT_FORMAT = "%.6g"
MARKER = "analysis.json"
"""The file that marks an analysis folder: a rerun replaces such a folder as a whole."""


def write_table(folder: Path, stem: str, rows: list[dict], title: str) -> None:
    """rows (dicts with the same keys) as <stem>.csv and a Markdown table <stem>.md; nothing for no rows."""
    if not rows:
        return
    columns = columns_of(rows)
    write_csv(folder / f"{stem}.csv", columns, float_format=FLOAT_FORMAT, nan="")
    write_markdown(folder / f"{stem}.md", columns, title, float_format=FLOAT_FORMAT, nan="")


def _safe(s: str) -> str:
    """A unit id as a file-name part."""
    return "".join(c if c.isalnum() or c in "-_." else "_" for c in s)


def write_report(out_dir, runs, neural: NeuralData, results: list[UnitAnalysis], top: int = 3) -> list[str]:
    """Tables (CSV + Markdown), profile and scatter figures and analysis.json into out_dir
    (atomically, replacing an earlier analysis there as a whole). Returns the file names."""
    runs = as_runs(runs)
    with staged_output(out_dir, replace=True) as tmp:
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
            plots.save(plots.response_profiles_figure(runs, data, ua.combined[:top]),
                       tmp / f"profiles_{_safe(ua.unit)}.png", dpi=DPI)
            plots.save(plots.response_scatter_figure(runs, data, ua.combined[:min(len(ua.combined), 4)]),
                       tmp / f"scatter_{_safe(ua.unit)}.png", dpi=DPI)
        write_json(tmp / "analysis.json", {
            "neural": neural.source, "runs": {str(k): str(v.folder) for k, v in runs.items()},
            "goodness": "R^2 = (sum d^2 - sum e^2) / sum d^2 (thesis eq. after 4.1); rms_ips = sqrt(mean e^2)",
            "units": {ua.unit: [f.row() for f in ua.combined] for ua in results}})
        names = sorted(p.name for p in tmp.iterdir())
    return names


def run_analyze(results, neural_csv, out_dir=None, diameters_mm=None, measures=None, fit_on=None,
                orientation=None, receptor_x_mm=0.0, progress=False) -> str:
    """`pipeline.py analyze`: read runs and recordings, rank, write the report. Returns a summary.
    progress: True (on stderr), False, or a progress object: a line per step that takes long."""
    results = [results] if isinstance(results, (str, Path)) else list(results)
    if len(results) > 2:
        raise InputError("give one results folder, or two (2D models of two diameters)")
    if diameters_mm is not None and len(results) != 2:
        raise InputError("--diameters needs two results folders")
    out = check_output_dir(out_dir if out_dir is not None else Path(results[0]) / "analysis", marker=MARKER,
                           what="analysis")
    progress = as_progress(progress)
    with progress.task("reading the runs and the recordings"):
        runs = as_runs([IndentRun(r, None if diameters_mm is None else diameters_mm[i])
                        for i, r in enumerate(results)])
        neural = read_neural_csv(neural_csv)
    cands = list(measures) if measures else None
    fit = list(fit_on) if fit_on else None
    with claimed(out):
        with progress.task("fitting the receptor model to every candidate"):
            res = analyze(runs, neural, cands, fit, receptor_x_mm, orientation)
        with progress.task("writing the report"):
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
