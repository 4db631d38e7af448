"""The layout of the code: its packages in layers, each importing only from the layers below it,
checked against the imports the code makes, drawn as docs/img/layout.png, and listed module by
module as the code map of docs/index.md.

    python docs/layout.py         # check; draw docs/img/layout.png; rewrite the code map in docs/index.md

tests/test_layout.py runs the check and compares the code map with docs/index.md, so neither
can drift from the code.
"""
from __future__ import annotations

import ast
import re
import sys
import textwrap
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("fingertip", "fem", "reconstruct", "pipeline")
"""Top-level names the project installs."""

LAYERS = [
    [("fingertip (infrastructure)", ["fingertip"],
      "errors, declared parameters, package faces, progress, atomic output, tables, distribution")],
    [("fem.core", ["fem.core"], "the finite-element method"),
     ("reconstruct", ["reconstruct"], "image stage: turntable photographs -> sections")],
    [("fem.geometry", ["fem.geometry"], "presets, layered model, 3D and 2D meshes, model folders")],
    [("fem.io", ["fem.io"], "model folder, run folder, VTU")],
    [("fem.contact", ["fem.contact"], "indentors, compliance, contact solver")],
    [("fem.verify", ["fem.verify"], "closed forms, half-space"),
     ("fem.receptors", ["fem.receptors"], "receptors, analysis, afferents")],
    [("fem.experiments", ["fem.experiments"], "scenes, response models, the scene runner")],
    [("fem.biomech", ["fem.biomech"], "deflection, layer study, fits, line load")],
    [("fem.thesis", ["fem.thesis"], "the thesis claim by claim")],
    [("fem.plots", ["fem.plots"], "every figure"), ("fem (the face)", ["fem"], "public API of fem")],
    [("fingertip.explore", ["fingertip.explore"], "the browser: the live explorer's web app and picture")],
    [("fingertip.jobs", ["fingertip.jobs"], "one job per command: run, write the folder, summary")],
    [("fingertip.cli", ["fingertip.cli"], "the command line: words -> objects -> job -> printed summary")],
    [("pipeline.py", ["pipeline"], "python pipeline.py = fingertip")],
]
"""Rows of units from the bottom up: (name, module prefixes, what it holds). A unit may import
from units on lower rows and from itself, never from its own row or above."""


def modules() -> dict[str, Path]:
    """{dotted module name: path} of every module of the project (tests, docs, benchmarks excluded)."""
    out = {"pipeline": ROOT / "pipeline.py"}
    for package in PACKAGES[:-1]:
        for path in sorted((ROOT / package).rglob("*.py")):
            parts = path.relative_to(ROOT).with_suffix("").parts
            out[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = path
    return out


def imports(path: Path, known: set[str]) -> set[str]:
    """The project's modules a module imports, anywhere in it (module level or in functions)."""
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            base = node.module
            found |= {f"{base}.{a.name}" if f"{base}.{a.name}" in known else base for a in node.names}
        elif isinstance(node, ast.Import):
            found |= {a.name for a in node.names}
    return {m for m in found if m in known}


def unit_of(module: str) -> tuple[int, str]:
    """(row, unit name) of a module: the unit with the longest matching prefix."""
    best = None
    for row, units in enumerate(LAYERS):
        for name, prefixes, _ in units:
            for p in prefixes:
                if (module == p or module.startswith(p + ".")) and (best is None or len(p) > best[2]):
                    best = (row, name, len(p))
    if best is None:
        raise KeyError(f"module {module} belongs to no unit of docs/layout.py LAYERS")
    return best[0], best[1]


def graph() -> dict[str, set[str]]:
    """{module: the project's modules it imports}."""
    mods = modules()
    return {m: imports(p, set(mods)) - {m} for m, p in mods.items()}


def problems() -> list[str]:
    """Every import that runs sideways or up the layers, and every import cycle between modules."""
    g = graph()
    out = []
    for m, deps in sorted(g.items()):
        row, unit = unit_of(m)
        for d in sorted(deps):
            drow, dunit = unit_of(d)
            if dunit != unit and drow >= row:
                out.append(f"{m} ({unit}) imports {d} ({dunit}): {'sideways' if drow == row else 'upwards'}")
    state = {}

    def visit(m, stack):
        state[m] = 1
        for d in sorted(g[m]):
            if state.get(d) == 1:
                out.append("import cycle: " + " -> ".join(stack[stack.index(d):] + [d]))
            elif d not in state:
                visit(d, stack + [d])
        state[m] = 2

    for m in sorted(g):
        if m not in state:
            visit(m, [m])
    return out


def summary(path: Path) -> str:
    """First sentence of a module's docstring (its first line when it has no full stop there)."""
    doc = ast.get_docstring(ast.parse(path.read_text())) or ""
    first = " ".join(doc.split("\n\n")[0].split())
    end = re.search(r"\.\s+(?=[A-Z`])", first)        # a full stop before a new sentence, not "ch. 4"
    return first if end is None else first[:end.start() + 1]


MAP_BEGIN = "<!-- code map: generated by docs/layout.py, checked by tests/test_layout.py -->"
MAP_END = "<!-- end of the code map -->"


def code_map() -> str:
    """The code map of docs/index.md: each unit from the bottom up, each module with its summary."""
    mods = modules()
    lines = [MAP_BEGIN, ""]
    for row, units in enumerate(LAYERS):
        for name, prefixes, what in units:
            lines.append(f"- **{name}** ({what})")
            for m in sorted(mods):
                if unit_of(m) == (row, name):
                    lines.append(f"  - `{m}`: {summary(mods[m])}")
    return "\n".join(lines + ["", MAP_END])


def with_code_map(text: str) -> str:
    """docs/index.md's text with its code map replaced by the current one."""
    head, _, rest = text.partition(MAP_BEGIN)
    _, _, tail = rest.partition(MAP_END)
    return head + code_map() + tail


def draw(path: Path) -> None:
    """The layers as a picture: one box per unit, rows from the bottom up, each box naming the
    units it imports (every one on a lower row)."""
    from matplotlib.figure import Figure
    from matplotlib.patches import FancyBboxPatch

    g = graph()
    uses = {}
    for m, deps in g.items():
        uses.setdefault(unit_of(m)[1], set()).update(unit_of(d)[1] for d in deps)
    fig = Figure(figsize=(11, 10))
    ax = fig.add_axes([0, 0, 1, 1])
    ax.set_xlim(0, 11), ax.set_ylim(-0.3, len(LAYERS) * 0.8 + 0.3), ax.axis("off")
    for row, units in enumerate(LAYERS):
        width = 10.4 / len(units)
        for k, (name, _, what) in enumerate(units):
            x, y = 0.3 + k * width, row * 0.8
            colour = "#dcebf7" if name.startswith("fem") else "#fbe9d0" if name.startswith("fingertip") else "#e3f1df"
            ax.add_patch(FancyBboxPatch((x + 0.08, y), width - 0.16, 0.62, boxstyle="round,pad=0.02", fc=colour,
                                        ec="#555555", lw=0.8))
            below = sorted(uses.get(name, set()) - {name}, key=lambda u: -unit_rank(u))
            ax.text(x + width / 2, y + 0.46, name, ha="center", va="center", fontsize=10, weight="bold")
            ax.text(x + width / 2, y + 0.27, what, ha="center", va="center", fontsize=7.5, color="#222222")
            text = ("uses " + ", ".join(u.split(" (")[0] for u in below)) if below else "uses nothing of the project"
            ax.text(x + width / 2, y + 0.1, textwrap.fill(text, int(width * 19)), ha="center", va="center",
                    fontsize=6.3, color="#666666", linespacing=1.0)
    ax.text(0.3, len(LAYERS) * 0.8 + 0.05, "The code in layers: each box imports only from boxes below it "
            "(read from the code by docs/layout.py; tests/test_layout.py holds it).", fontsize=9)
    fig.savefig(path, dpi=110)


def unit_rank(name: str) -> int:
    """Row of a unit by name."""
    return next(row for row, units in enumerate(LAYERS) for n, _, _ in units if n == name)


if __name__ == "__main__":
    found = problems()
    print("\n".join(found) or "layers hold: no import runs sideways or up, no import cycle")
    draw(ROOT / "docs" / "img" / "layout.png")
    index = ROOT / "docs" / "index.md"
    index.write_text(with_code_map(index.read_text()))
    sys.exit(1 if found else 0)
