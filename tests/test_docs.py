"""Every ```python block of docs/*.md runs: page by page, the blocks of one page in order in one
namespace, in a temporary working directory, with the repository root importable. Shell blocks
(```bash, ```sh) and ```text blocks are not run."""
from __future__ import annotations

import re
from pathlib import Path

import pytest

from tests.helpers import ROOT

DOCS = ROOT / "docs"
FENCE = re.compile(r"^```python[ \t]*\n(.*?)^```[ \t]*$", re.S | re.M)


def python_blocks(page: Path) -> list[tuple[int, str]]:
    """(line number, source) of every ```python block of a Markdown page."""
    text = page.read_text(encoding="utf-8")
    return [(text.count("\n", 0, m.start()) + 2, m.group(1)) for m in FENCE.finditer(text)]


PAGES = sorted(p for p in DOCS.glob("*.md") if python_blocks(p))


def test_docs_exist_and_cite_nothing_outside_the_repository():
    assert (DOCS / "index.md").is_file()
    for page in [ROOT / "README.md", *DOCS.glob("*.md")]:
        text = page.read_text(encoding="utf-8")
        assert not re.search(r"SPEC\.md|DESIGN\.md|\.\./shared", text), page.name


def test_relative_links_resolve():
    for page in [ROOT / "README.md", *DOCS.glob("*.md")]:
        for target in re.findall(r"\]\(([^)#:]+)(?:#[^)]*)?\)", page.read_text(encoding="utf-8")):
            assert (page.parent / target).exists(), f"{page.name}: broken link {target}"


@pytest.mark.parametrize("page", PAGES, ids=[p.name for p in PAGES])
def test_python_blocks_run(page, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.syspath_prepend(str(ROOT))
    namespace = {"__name__": f"docs_{page.stem.replace('-', '_')}"}
    for line, source in python_blocks(page):
        code = compile(source, f"{page.relative_to(ROOT)}:{line}", "exec")
        exec(code, namespace)


SHELL = re.compile(r"^```(?:bash|sh|text)[ \t]*\n(.*?)^```[ \t]*$", re.S | re.M)


def documented_commands() -> list[tuple[str, list[str]]]:
    """(where, argv) of every `python pipeline.py ...` line of a shell or text block in README.md and
    docs/*.md: comments dropped, continuation lines joined, [optional] parts left out."""
    import shlex

    out = []
    for page in [ROOT / "README.md", *sorted(DOCS.glob("*.md"))]:
        text = page.read_text(encoding="utf-8")
        for m in SHELL.finditer(text):
            block = m.group(1).replace("\\\n", " ")
            first = text.count("\n", 0, m.start()) + 2
            for k, line in enumerate(block.splitlines()):
                line = re.sub(r"\[[^\]]*\]", "", line.split("#")[0]).strip()
                for part in line.split("&&"):
                    words = shlex.split(part)
                    if words[:2] == ["python", "pipeline.py"] and len(words) > 2 and "..." not in words:
                        out.append((f"{page.name}:{first + k}", words[2:]))
    return out


COMMANDS = documented_commands()


def test_every_documented_command_parses(capsys):
    """Every command line the docs show names a real command and real flags with values the
    parser accepts (running them takes minutes each: the examples and the tests run the workflows)."""
    from fingertip.cli import build_parser

    assert len(COMMANDS) > 30
    for where, argv in COMMANDS:
        parser = build_parser(command=argv[0])
        try:
            parser.parse_args(argv)
        except SystemExit:
            pytest.fail(f"{where}: `python pipeline.py {' '.join(argv)}` does not parse: {capsys.readouterr().err}")


def test_documented_2d_commands_run(tmp_path, monkeypatch):
    """The documented commands on the 2D cylinder (meshing it, indenting it by depth and by force with
    a sweep) run as written, in order, in a fresh folder."""
    import pipeline

    monkeypatch.chdir(tmp_path)
    cyl8 = [argv for _, argv in COMMANDS if (argv[0] == "mesh" and "cylinder8" in argv)
            or (argv[0] == "indent" and argv[1] == "out/cyl8" and "--scene" not in argv)]
    runs = list(dict.fromkeys(tuple(a) for a in cyl8))
    assert runs[0][0] == "mesh" and len(runs) >= 3
    for argv in runs:
        assert pipeline.main([*argv, "--quiet"]) == 0, argv
    assert (tmp_path / "out" / "cyl8" / "model.json").is_file()


def _reproduction_module():
    import importlib.util

    spec = importlib.util.spec_from_file_location("docs_reproduction", DOCS / "reproduction.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_reproduction_table_is_the_full_runs():
    """docs/reproduction.md's table is what docs/reproduction.py renders from the stored full run."""
    import json

    rep = _reproduction_module()
    data = json.loads(rep.DATA.read_text())
    assert not data["manifest"]["quick"]
    text = rep.DOC.read_text()
    assert rep.with_table(text, data) == text, "regenerate it: python docs/reproduction.py"



def test_quick_verdicts_agree_with_the_full_run_or_say_mesh_uncertainty():
    """The trust issue's rule on the stored runs: both carry the uncertainty factor of their levels,
    and a --quick verdict that is not the full run's is 'within mesh uncertainty'."""
    import json

    from fem.thesis.findings import UNCERTAIN, Finding, levels, uncertainty_factor

    rep = _reproduction_module()
    runs = {}
    for path, quick in ((rep.DATA, False), (rep.QUICK, True)):
        data = json.loads(path.read_text())
        assert data["manifest"]["quick"] is quick and data["manifest"]["format"] == 4
        runs[quick] = {f["key"]: Finding.from_json(f) for f in data["findings"]}
        factors = {c.factor for f in runs[quick].values() for c in f.checks if c.coarse is not None}
        assert factors == {uncertainty_factor(*levels(quick))}
    full, quick = runs[False], runs[True]
    assert set(quick) == set(full)
    for key, f in quick.items():
        assert f.verdict in (full[key].verdict, UNCERTAIN), (key, f.verdict, full[key].verdict)
