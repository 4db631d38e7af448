"""The `reproduce` job: run the thesis's claims (fem.thesis.claims.CLAIMS) into a folder
and write index.html and index.md there, one section per thesis figure or table.

Each claim's findings are kept as claims/<name>.json with their PNGs; a rerun into the same folder
skips the claims already there (resume after an interrupt) and re-meshes nothing it has.

    run_reproduce("out/thesis", quick=True)
"""
from __future__ import annotations

import html
import json
from pathlib import Path

from fem.plots import finding_figure, save
from fem.thesis import claims as thesis
from fem.thesis.claims import NOT_RUN
from fem.thesis.findings import REPRODUCED, Finding, Workshop
from fingertip.errors import InputError
from fingertip.progress import as_progress
from fingertip.staging import atomic_write, check_output_dir, write_json

MANIFEST = "reproduce.json"


def check_out(out, quick: bool) -> Path:
    """Refuse an --out that is not a new, empty or earlier `reproduce` folder of the same kind."""
    out = check_output_dir(out)
    manifest = out / MANIFEST
    if manifest.is_file():
        try:
            kind = json.loads(manifest.read_text())["quick"]
        except (OSError, ValueError, KeyError, TypeError):
            raise InputError(f"{manifest} is unreadable: remove it or give a new --out folder") from None
        if bool(kind) != bool(quick):
            raise InputError(f"--out {out} holds a {'quick' if kind else 'full'} run: "
                             f"{'add' if kind else 'drop'} --quick to resume it, or give a new folder")
    elif out.is_dir() and any(out.iterdir()):
        raise InputError(f"--out {out} is not empty and holds no {MANIFEST}: give a new or empty folder")
    return out


def run_reproduce(out, quick: bool = False, progress=True) -> str:
    """Run every claim not yet in `out`, then write the report; returns the summary text."""
    out = check_out(out, quick)
    progress = as_progress(progress)
    out.mkdir(parents=True, exist_ok=True)
    write_json(out / MANIFEST, {"quick": bool(quick), "claims": [name for name, _ in thesis.CLAIMS]})
    (out / "claims").mkdir(exist_ok=True)
    shop = Workshop(out / "models", quick, progress)
    findings, resumed = [], 0
    for name, claim in progress.bar(thesis.CLAIMS, desc="thesis claims", unit="claim"):
        path = out / "claims" / f"{name}.json"
        if path.is_file():
            findings += [Finding.from_json(f) for f in json.loads(path.read_text())]
            resumed += 1
            continue
        with progress.task(f"claim '{name}'", kind=f"reproduce-{name}-{'quick' if quick else 'full'}"):
            new = claim(shop)
        for f in new:
            save(finding_figure(f), out / "claims" / f"{f.key}.png")
        write_json(path, [f.to_json() for f in new])      # last: the claim counts as done
        findings += new
    atomic_write(out / "index.md", lambda p: Path(p).write_text(markdown_report(findings, quick)))
    atomic_write(out / "index.html", lambda p: Path(p).write_text(html_report(findings, quick)))
    same = sum(f.verdict == REPRODUCED for f in findings)
    lines = [f"index.html and index.md in {out}: {len(findings)} findings, {same} reproduced, "
             f"{len(findings) - same} differ (each with its measured reason)"
             + (f"; {resumed} claims resumed" if resumed else "")]
    lines += [f"  {f.verdict:10s} {f.section}: {f.title}" for f in findings]
    return "\n".join(lines)


def _number(v) -> str:
    return "-" if v is None else f"{v:.4g}"


def _difference(f) -> str:
    d = f.relative_difference
    return "-" if d is None else f"{100 * d:+.1f} %"


def _summary_rows(findings):
    return [(f.section, f.title, f.verdict, _number(f.thesis_value), _number(f.value), _difference(f))
            for f in findings]


HEAD = ("thesis", "claim", "verdict", "thesis value", "project value", "difference")


def markdown_report(findings, quick: bool) -> str:
    """The report as Markdown (PNG links relative to the folder)."""
    md = [f"# The thesis, claim by claim ({'quick: coarse meshes' if quick else 'full run'})", "",
          "Every experiment of thesis chapters 4-7 this project can run, against what the thesis "
          "states. A finding is *reproduced* when the project's number agrees with the statement; "
          "otherwise its reason is measured.", "",
          "| " + " | ".join(HEAD) + " |", "|" + "---|" * len(HEAD)]
    md += ["| " + " | ".join(r) + " |" for r in _summary_rows(findings)]
    for f in findings:
        md += ["", f"## {f.section}: {f.title}", "", f"**Thesis.** {f.thesis}", "",
               f"**Project.** {f.quantity}: {_number(f.value)} (thesis: {_number(f.thesis_value)}; "
               f"difference {_difference(f)}).", "", f"**Verdict: {f.verdict}.** {f.reason}", "",
               f"![{f.key}](claims/{f.key}.png)"]
        if f.table:
            keys, rows = _table(f.table)
            md += ["", "| " + " | ".join(keys) + " |", "|" + "---|" * len(keys)]
            md += ["| " + " | ".join(r) + " |" for r in rows]
    md += ["", "## Not run here", ""] + [f"- **{s}.** {why}" for s, why in NOT_RUN]
    return "\n".join(md) + "\n"


def _cell(v) -> str:
    return f"{v:.4g}" if isinstance(v, float) else str(v)


def _table(rows: list[dict]) -> tuple[list[str], list[list[str]]]:
    """(column names in first-seen order over all rows, cells): a row without a column gets ''."""
    keys = list(dict.fromkeys(k for r in rows for k in r))
    return keys, [[_cell(r[k]) if k in r else "" for k in keys] for r in rows]


def html_report(findings, quick: bool) -> str:
    """The same report as one plain HTML page with the PNGs beside it."""
    e = html.escape

    def table(head, rows):
        return ("<table><tr>" + "".join(f"<th>{e(h)}</th>" for h in head) + "</tr>"
                + "".join("<tr>" + "".join(f"<td>{e(c)}</td>" for c in r) + "</tr>" for r in rows) + "</table>")

    body = [f"<h1>The thesis, claim by claim ({'quick: coarse meshes' if quick else 'full run'})</h1>",
            "<p>Every experiment of thesis chapters 4-7 this project can run, against what the thesis "
            "states. A finding is <em>reproduced</em> when the project's number agrees with the "
            "statement; otherwise its reason is measured.</p>", table(HEAD, _summary_rows(findings))]
    for f in findings:
        body += [f"<h2 id='{e(f.key)}'>{e(f.section)}: {e(f.title)}</h2>",
                 f"<p><b>Thesis.</b> {e(f.thesis)}</p>",
                 f"<p><b>Project.</b> {e(f.quantity)}: {_number(f.value)} (thesis: {_number(f.thesis_value)}; "
                 f"difference {_difference(f)}).</p>",
                 f"<p><b>Verdict: {e(f.verdict)}.</b> {e(f.reason)}</p>",
                 f"<img src='claims/{e(f.key)}.png' alt='{e(f.key)}'>"]
        if f.table:
            body.append(table(*_table(f.table)))
    body += ["<h2>Not run here</h2><ul>"] + [f"<li><b>{e(s)}.</b> {e(why)}</li>" for s, why in NOT_RUN] + ["</ul>"]
    style = ("body{font-family:sans-serif;max-width:60em;margin:auto}table{border-collapse:collapse;"
             "font-size:small}td,th{border:1px solid #ccc;padding:2px 6px}img{max-width:100%}")
    return ("<!DOCTYPE html><html><head><meta charset='utf-8'><title>Thesis reproduction</title>"
            f"<style>{style}</style></head><body>" + "\n".join(body) + "</body></html>\n")
