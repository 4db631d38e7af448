"""The `reproduce` job: run the thesis's claims (fem.thesis.claims.CLAIMS) on two mesh levels into a
folder and write index.html and index.md there, one section per thesis figure or table.

Each claim runs on the coarser and the finer level of the run (fem.thesis.findings.levels); its
findings are judged on the finer level, their mesh uncertainty the change from the coarser times
`fem.thesis.findings.uncertainty_factor` (a grid convergence index: 6 in a quick run, 3 in a full one).
A claim's findings at each level are kept as claims/levels/<level>/<name>.json and, merged, as
claims/<name>.json with their PNGs; a rerun into the same folder skips what is there (resume after
an interrupt) and re-meshes nothing it has.

    run_reproduce("out/thesis", quick=True)
"""
from __future__ import annotations

import html
import json
from pathlib import Path

from fem.plots import finding_figure, save
from fem.thesis import claims as thesis
from fem.thesis.claims import NOT_RUN
from fem.thesis.findings import VERDICTS, Finding, Workshop, levels, number, uncertainty_factor, with_coarse
from fem.thesis.kinematics import side_by_side
from fingertip.errors import InputError
from fingertip.progress import as_progress
from fingertip.provenance import provenance
from fingertip.staging import atomic_write, check_output_dir, write_json

MANIFEST = "reproduce.json"
#: Format of reproduce.json and claims/*.json: 2 adds the checks, the two mesh levels and the provenance;
#: 3 the checks' uncertainty factor; 4 each finding's kinematics.
FORMAT = 4


def check_out(out, quick: bool) -> Path:
    """Refuse an --out that is not a new, empty or earlier `reproduce` folder of the same kind."""
    out = check_output_dir(out)
    manifest = out / MANIFEST
    if manifest.is_file():
        try:
            data = json.loads(manifest.read_text())
            kind, fmt = data["quick"], data.get("format", 1)
        except (OSError, ValueError, KeyError, TypeError, AttributeError):
            raise InputError(f"{manifest} is unreadable: remove it or give a new --out folder") from None
        if fmt != FORMAT:
            raise InputError(f"--out {out} holds a reproduce run of an older version (format {fmt}): "
                             "give a new or empty folder")
        if bool(kind) != bool(quick):
            raise InputError(f"--out {out} holds a {'quick' if kind else 'full'} run: "
                             f"{'add' if kind else 'drop'} --quick to resume it, or give a new folder")
    elif out.is_dir() and any(out.iterdir()):
        raise InputError(f"--out {out} is not empty and holds no {MANIFEST}: give a new or empty folder")
    return out


def _slug(level) -> str:
    return f"{level.size2d_mm:g}mm_{level.size3d_mm:g}mm"


def _claim_at(shop: Workshop, name: str, claim, out: Path, progress) -> list[Finding]:
    """A claim's findings at the workshop's level, from claims/levels/<level>/<name>.json if there."""
    path = out / "claims" / "levels" / _slug(shop.level) / f"{name}.json"
    if path.is_file():
        return [Finding.from_json(f) for f in json.loads(path.read_text())]
    kind = f"reproduce-{name}-{_slug(shop.level)}"
    with progress.task(f"claim '{name}' on the {shop.level.name} meshes", kind=kind):
        found = claim(shop)
    path.parent.mkdir(parents=True, exist_ok=True)
    write_json(path, [f.to_json() for f in found])
    return found


def run_reproduce(out, quick: bool = False, progress=True) -> str:
    """Run every claim not yet in `out` on both mesh levels, then write the report; returns the summary."""
    out = check_out(out, quick)
    progress = as_progress(progress)
    out.mkdir(parents=True, exist_ok=True)
    coarse_level, fine_level = levels(quick)
    made_by = provenance()
    write_json(out / MANIFEST, {"format": FORMAT, "quick": bool(quick), "claims": [name for name, _ in thesis.CLAIMS],
                                "levels": [vars(coarse_level), vars(fine_level)], "provenance": made_by})
    (out / "claims").mkdir(exist_ok=True)
    shop = Workshop(out / "models", quick, progress)
    coarse, fine = shop.at(coarse_level), shop.at(fine_level)
    findings, resumed = [], 0
    for name, claim in progress.bar(thesis.CLAIMS, desc="thesis claims", unit="claim"):
        path = out / "claims" / f"{name}.json"
        if path.is_file():
            findings += [Finding.from_json(f) for f in json.loads(path.read_text())]
            resumed += 1
            continue
        new = with_coarse(_claim_at(fine, name, claim, out, progress), _claim_at(coarse, name, claim, out, progress),
                          uncertainty_factor(coarse_level, fine_level))
        with progress.task(f"figures of claim '{name}'"):
            for f in new:
                save(finding_figure(f), out / "claims" / f"{f.key}.png")
        write_json(path, [f.to_json() for f in new])      # last: the claim counts as done
        findings += new
    meshes = mesh_table(out / "models")
    atomic_write(out / "index.md", lambda p: Path(p).write_text(markdown_report(findings, quick, made_by, meshes)))
    atomic_write(out / "index.html", lambda p: Path(p).write_text(html_report(findings, quick, made_by, meshes)))
    lines = [f"index.html and index.md in {out}: {len(findings)} findings, {counts(findings)}"
             + (f"; {resumed} claims resumed" if resumed else "")]
    lines += [f"  {f.verdict:23s} {f.section}: {f.title}" for f in findings]
    return "\n".join(lines)


def counts(findings) -> str:
    """'20 reproduced, 3 within mesh uncertainty, 7 differ'."""
    n = {v: sum(f.verdict == v for f in findings) for v in VERDICTS}
    return ", ".join(f"{n[v]} {'differ' if v == 'differs' else v}" for v in VERDICTS)


def mesh_table(models: Path) -> list[dict]:
    """One row per model folder the run meshed: name, elements, fine-zone median edge [mm]."""
    rows = []
    for info_file in sorted(models.glob("*/model.json")):
        info = json.loads(info_file.read_text())
        mesh = info.get("mesh", {})
        elements = mesh.get("tets", mesh.get("triangles"))
        edge = (mesh.get("sizing_achieved", {}).get("fine_zone_median_edge_mm")
                or mesh.get("top_zone", {}).get("median_edge_mm"))
        rows.append({"model": info_file.parent.name, "kind": info.get("kind", ""),
                     "elements": elements, "requested_mm": info.get("sizing", {}).get("size_mm"),
                     "achieved_median_edge_mm": edge})
    return rows


def _summary_rows(findings):
    rows = []
    for f in findings:
        c = f.headline
        unit = f" [{c.unit}]" if c.unit else ""
        title = f"{f.title}, read: {f.reading}" if f.reading else f.title
        rows.append((f.key, f.section, title, c.what + unit, c.band(), number(c.value),
                     "-" if c.coarse is None else number(c.uncertainty, 2), f.verdict))
    return rows


HEAD = ("thesis", "claim", "quantity [unit]", "thesis, read as", "project (finer mesh)", "mesh uncertainty",
        "verdict")


def _levels_text(quick: bool) -> str:
    c, f = levels(quick)
    return (f"{'quick' if quick else 'full'} run: coarser meshes {c.size2d_mm:g} mm (2D, top 1 mm) and "
            f"{c.size3d_mm:g} mm (3D, volar), finer meshes {f.size2d_mm:g} and {f.size3d_mm:g} mm")


JUDGED = ("Every finding quotes the thesis and judges the project's numbers against the band its words "
          "give. Each number is computed on two mesh levels: the value shown is the finer mesh's, the mesh "
          "uncertainty its grid convergence index, 3 |fine - coarse| / (r - 1) with r the levels' refinement "
          "ratio (Roache's factor of safety 3 for two meshes, first order assumed): 6 times the change in a "
          "quick run (r = 1.5), 3 times in a full one (r = 2). A check is *reproduced* when its value lies inside the "
          "band by more than the mesh uncertainty, *differs* when it lies outside by more, and is *within "
          "mesh uncertainty* otherwise; a finding differs if any check differs, is within mesh uncertainty "
          "if any check is, and is reproduced otherwise.")


KINEMATICS_TEXT = ("The claims that depend on depth, with both kinematics: linear (small strain, the default) and "
                   "finite (neo-Hookean, frictionless contact in the deformed configuration; `--kinematics finite`), "
                   "on the same models and meshes at the same loads. The thesis's own kinematics is quoted with its "
                   "section; 'why' gives each check's value with both, or why there is no finite run.")
KINEMATICS_HEAD = ("thesis", "claim", "the thesis used", "linear", "finite", "why")


def _kinematics_rows(findings):
    return [(r["key"], r["section"], r["title"], f"{r['thesis_kinematics']}: {r['thesis_words']}", r["linear"],
             r["finite"], r["why"]) for r in side_by_side(findings)]


def _made_by(p: dict) -> list[str]:
    libs = ", ".join(f"{k} {v}" for k, v in p["libraries"].items())
    m = p["machine"]
    return [f"{p['package']} {p['version'] or '(not installed)'}"
            + (f", commit {p['commit']}" if p["commit"] else "") + f"; {p['date']}",
            f"Python {p['python']}; {libs}", f"{m['system']}, {m['cpu']}, {m['cores']} cores"]


def markdown_report(findings, quick: bool, made_by: dict, meshes: list[dict]) -> str:
    """The report as Markdown (PNG links relative to the folder; each section anchored by its key)."""
    md = [f"# The thesis, claim by claim ({_levels_text(quick)})", "",
          f"Every experiment of thesis chapters 4-7 this project can run: {len(findings)} findings, "
          f"{counts(findings)}.", "", JUDGED, "",
          "| " + " | ".join(HEAD) + " |", "|" + "---|" * len(HEAD)]
    md += [f"| [{sec}](#{key}) | " + " | ".join(rest) + " |" for key, sec, *rest in _summary_rows(findings)]
    md += ["", "## Both kinematics", "", KINEMATICS_TEXT, "", "| " + " | ".join(KINEMATICS_HEAD) + " |",
           "|" + "---|" * len(KINEMATICS_HEAD)]
    md += [f"| [{sec}](#{key}) | " + " | ".join(rest) + " |" for key, sec, *rest in _kinematics_rows(findings)]
    for f in findings:
        md += ["", f'<a id="{f.key}"></a>', "", f"## {f.section}: {f.title}", "",
               f"**Thesis ({f.section}).** \"{f.thesis}\"", ""]
        if f.reading:
            md += [f"**Read as:** {f.reading}.", ""]
        md += [f"**Verdict: {f.verdict}.**", ""]
        md += [f"- {c.text()}" for c in f.checks]
        if f.notes:
            md += ["", f.notes]
        md += ["", f"![{f.key}](claims/{f.key}.png)"]
        if f.table:
            keys, rows = _table(f.table)
            md += ["", "| " + " | ".join(keys) + " |", "|" + "---|" * len(keys)]
            md += ["| " + " | ".join(r) + " |" for r in rows]
    md += ["", "## Not run here", ""] + [f"- **{s}.** {why}" for s, why in NOT_RUN]
    md += ["", "## What produced this report", ""] + [f"- {line}" for line in _made_by(made_by)]
    keys, rows = _table(meshes)
    md += ["", "| " + " | ".join(keys) + " |", "|" + "---|" * len(keys)] + ["| " + " | ".join(r) + " |" for r in rows]
    return "\n".join(md) + "\n"


def _cell(v) -> str:
    return f"{v:.4g}" if isinstance(v, float) else str(v)


def _table(rows: list[dict]) -> tuple[list[str], list[list[str]]]:
    """(column names in first-seen order over all rows, cells): a row without a column gets ''."""
    keys = list(dict.fromkeys(k for r in rows for k in r))
    return keys, [[_cell(r[k]) if k in r else "" for k in keys] for r in rows]


def html_report(findings, quick: bool, made_by: dict, meshes: list[dict]) -> str:
    """The same report as one plain HTML page with the PNGs beside it."""
    e = html.escape

    def table(head, rows, link=False):
        def cells(r):
            first = f"<a href='#{e(r[0])}'>{e(r[1])}</a>" if link else e(r[0])
            return [first] + [e(c) for c in (r[2:] if link else r[1:])]
        return ("<table><tr>" + "".join(f"<th>{e(h)}</th>" for h in head) + "</tr>"
                + "".join("<tr>" + "".join(f"<td>{c}</td>" for c in cells(r)) + "</tr>" for r in rows) + "</table>")

    body = [f"<h1>The thesis, claim by claim ({e(_levels_text(quick))})</h1>",
            f"<p>Every experiment of thesis chapters 4-7 this project can run: {len(findings)} findings, "
            f"{e(counts(findings))}.</p>", f"<p>{e(JUDGED)}</p>", table(HEAD, _summary_rows(findings), link=True),
            "<h2>Both kinematics</h2>", f"<p>{e(KINEMATICS_TEXT)}</p>",
            table(KINEMATICS_HEAD, _kinematics_rows(findings), link=True)]
    for f in findings:
        body += [f"<h2 id='{e(f.key)}'>{e(f.section)}: {e(f.title)}</h2>",
                 f"<p><b>Thesis ({e(f.section)}).</b> &ldquo;{e(f.thesis)}&rdquo;</p>"]
        if f.reading:
            body.append(f"<p><b>Read as:</b> {e(f.reading)}.</p>")
        body += [f"<p><b>Verdict: {e(f.verdict)}.</b></p>",
                 "<ul>" + "".join(f"<li>{e(c.text())}</li>" for c in f.checks) + "</ul>"]
        if f.notes:
            body.append(f"<p>{e(f.notes)}</p>")
        body.append(f"<img src='claims/{e(f.key)}.png' alt='{e(f.key)}'>")
        if f.table:
            body.append(table(*_table(f.table)))
    body += ["<h2>Not run here</h2><ul>"] + [f"<li><b>{e(s)}.</b> {e(why)}</li>" for s, why in NOT_RUN] + ["</ul>"]
    body += ["<h2>What produced this report</h2><ul>"] + [f"<li>{e(x)}</li>" for x in _made_by(made_by)] + ["</ul>"]
    body.append(table(*_table(meshes)))
    style = ("body{font-family:sans-serif;max-width:60em;margin:auto}table{border-collapse:collapse;"
             "font-size:small}td,th{border:1px solid #ccc;padding:2px 6px}img{max-width:100%}")
    return ("<!DOCTYPE html><html><head><meta charset='utf-8'><title>Thesis reproduction</title>"
            f"<style>{style}</style></head><body>" + "\n".join(body) + "</body></html>\n")
