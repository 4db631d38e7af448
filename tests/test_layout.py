"""The house's floor plan, held against the code: layers and import cycles read from the code's own
imports (docs/layout.py), the code map of docs/index.md, the sizes of modules and functions,
what `fem/` holds directly, who may import the command layer, and what the package installs."""
from __future__ import annotations

import ast
import importlib.util
import re
import tomllib

from setuptools import find_packages

from tests.helpers import ROOT

spec = importlib.util.spec_from_file_location("layout", ROOT / "docs" / "layout.py")
layout = importlib.util.module_from_spec(spec)
spec.loader.exec_module(layout)

MAX_MODULE_LINES, MAX_FUNCTION_LINES = 650, 80
COMMAND_LAYER = ("pipeline", "fingertip.cli", "fingertip.jobs")


def _python_files(*folders):
    for folder in folders:
        path = ROOT / folder
        yield from ([path] if path.suffix == ".py" else sorted(path.rglob("*.py")))


def test_imports_run_down_the_layers_and_never_in_a_circle():
    assert layout.problems() == []


def test_every_module_belongs_to_a_layer():
    for module in layout.modules():
        layout.unit_of(module)                       # KeyError names a module no layer holds


def test_code_map_in_the_index_is_the_codes():
    text = (ROOT / "docs" / "index.md").read_text()
    assert layout.MAP_BEGIN in text and layout.MAP_END in text
    assert text == layout.with_code_map(text), "docs/index.md's code map is stale: run python docs/layout.py"


def test_modules_and_functions_stay_small():
    for path in _python_files("fem", "reconstruct", "fingertip", "pipeline.py"):
        lines = len(path.read_text().splitlines())
        assert lines <= MAX_MODULE_LINES, f"{path.relative_to(ROOT)}: {lines} lines"
    for path in _python_files("fem", "reconstruct", "fingertip", "pipeline.py", "benchmarks", "examples", "docs"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                n = node.end_lineno - node.lineno + 1
                assert n <= MAX_FUNCTION_LINES, f"{path.relative_to(ROOT)}:{node.lineno} {node.name}: {n} lines"


def test_fem_holds_subpackages_and_few_modules():
    direct = sorted(p.name for p in (ROOT / "fem").glob("*.py"))
    assert len(direct) <= 8, direct
    assert {p.name for p in (ROOT / "fem").iterdir() if (p / "__init__.py").is_file()} >= {
        "core", "geometry", "io", "contact", "receptors", "experiments", "biomech", "thesis", "verify"}


def _imported(source: str) -> set[str]:
    names = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.ImportFrom) and node.module:
            names |= {node.module} | {f"{node.module}.{a.name}" for a in node.names}
        elif isinstance(node, ast.Import):
            names |= {a.name for a in node.names}
    return names


def test_nothing_outside_the_command_layer_imports_it():
    fence = re.compile(r"^```python[ \t]*\n(.*?)^```[ \t]*$", re.S | re.M)
    sources = {p: p.read_text() for p in _python_files("fem", "reconstruct", "benchmarks", "examples", "docs")}
    sources |= {p: p.read_text() for p in _python_files("fingertip") if "cli" not in p.parts and "jobs" not in p.parts}
    for page in (ROOT / "docs").glob("*.md"):
        sources[page] = "\n".join(m.group(1) for m in fence.finditer(page.read_text()))
    for path, source in sources.items():
        bad = {n for n in _imported(source) if any(n == c or n.startswith(c + ".") for c in COMMAND_LAYER)}
        assert not bad, f"{path.relative_to(ROOT)} imports the command layer: {sorted(bad)}"


def test_the_package_installs_one_namespace_besides_fem_reconstruct_and_pipeline():
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    packages = find_packages(str(ROOT), include=config["packages"]["find"]["include"])
    top = {p.split(".")[0] for p in packages} | set(config.get("py-modules", []))
    assert top == {"fem", "reconstruct", "fingertip", "pipeline"}
    assert config["packages"]["find"].get("include") and "tests" not in top
