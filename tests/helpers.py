"""Helpers shared by several test modules: `from tests.helpers import ...`.

A helper that one module uses stays in that module; shared fixtures are in tests/conftest.py.
"""
from __future__ import annotations

import contextlib
import csv
import io
import json
import signal
import time
from pathlib import Path
from typing import NamedTuple

import numpy as np

import pipeline

ROOT = Path(__file__).resolve().parents[1]
"""The repository root (pipeline.py, data/, docs/, sample_images/, scenes/)."""


class Ran(NamedTuple):
    """What `cli` saw: exit code, stdout, stderr, seconds."""
    code: int
    out: str
    err: str
    seconds: float


def cli(*argv, accept=()) -> Ran:
    """`pipeline.main` in this process on argv (each word str()-ed), stdout and stderr captured.
    accept: exception types that end the run as accepted, exit code 0 (a stand-in raised where a
    long computation would begin)."""
    out, err = io.StringIO(), io.StringIO()
    t0 = time.perf_counter()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = pipeline.main([str(a) for a in argv])
        except accept:
            code = 0
    return Ran(code, out.getvalue(), err.getvalue(), time.perf_counter() - t0)


def snapshot(*folders) -> set:
    """Every path below the folders (to show that nothing was written)."""
    return {p for f in folders if Path(f).exists() for p in Path(f).rglob("*")}


def csv_rows(path) -> list[dict]:
    """The rows of a CSV file with a header, as dicts of strings."""
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def write_csv(folder, text, name="data.csv") -> Path:
    """`text` written to folder/name; returns the path."""
    path = Path(folder) / name
    path.write_text(text)
    return path


def write_sections(folder, polys, zs=None) -> Path:
    """folder/sections.json (folder made if needed) of the outline polygons `polys` (each (n, 2) mm)
    at heights `zs` (default 0, 1, 2, ... mm); returns the folder."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    zs = zs if zs is not None else np.arange(len(polys), dtype=float)
    data = {"units": "mm", "sections": [{"z": float(z), "points": np.asarray(p).tolist()} for z, p in zip(zs, polys)]}
    (folder / "sections.json").write_text(json.dumps(data))
    return folder


def by_key(findings) -> dict:
    """Thesis findings by their key, each first checked by `assert_computed`."""
    for f in findings:
        assert_computed(f)
    return {f.key: f for f in findings}


def _moved(check, inside: bool):
    """The check with its value moved clearly inside (or outside) its band, one level only and no
    resolution (a resolution wider than a band keeps a check uncertain wherever its value lies:
    tests/fem/thesis/test_findings.py checks the floor)."""
    from dataclasses import replace

    step = max(abs(check.limit), check.tol, 1.0)
    if check.test == ">":
        value = check.limit + step if inside else check.limit - step
    elif check.test == "<":
        value = check.limit - step if inside else check.limit + step
    else:
        value = check.limit if inside else check.limit + check.tol + step
    return replace(check, value=value, coarse=None, resolution=0.0)


def assert_computed(finding) -> None:
    """A finding's verdict and reason follow its numbers: for each check, with every other check
    moved inside its band, moving this one across its band turns the verdict from reproduced to
    differs and changes the reason; the check's number appears in the reason; a coarse value one
    band-width away makes it 'within mesh uncertainty'; and the JSON round trip recomputes both."""
    from dataclasses import replace

    from fem.thesis.findings import DIFFERS, REPRODUCED, UNCERTAIN, Finding, number

    assert finding.checks, finding.key
    for i, check in enumerate(finding.checks):
        assert number(check.value) in finding.reason, (finding.key, check.what)
        base = [_moved(c, True) for c in finding.checks]
        inside = replace(finding, checks=base)
        outside = replace(finding, checks=base[:i] + [_moved(check, False)] + base[i + 1:])
        assert (inside.verdict, outside.verdict) == (REPRODUCED, DIFFERS), (finding.key, check.what)
        assert inside.reason != outside.reason, (finding.key, check.what)
        near = replace(base[i], coarse=_moved(check, False).value)
        assert replace(finding, checks=base[:i] + [near] + base[i + 1:]).verdict == UNCERTAIN, (finding.key, i)
    again = Finding.from_json(json.loads(json.dumps(finding.to_json())))
    assert (again.verdict, again.reason) == (finding.verdict, finding.reason), finding.key


def default_sigint() -> None:
    """preexec_fn for a child that must see Ctrl-C: a test run started in the background of a
    non-interactive shell ignores SIGINT, and a Python started with it ignored never raises
    KeyboardInterrupt."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


CHROMIUM, CHROMEDRIVER = Path("/usr/bin/chromium"), Path("/usr/bin/chromedriver")
"""Debian's packages chromium and chromium-driver (.ci/run installs them where missing)."""


def headless_chromium():
    """Debian's Chromium, headless, under Selenium (flags that keep it off the closed network)."""
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service
    opts = webdriver.ChromeOptions()
    opts.binary_location = str(CHROMIUM)
    for flag in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage", "--no-first-run",
                 "--disable-background-networking", "--disable-component-update", "--disable-sync",
                 "--window-size=1400,1000"):
        opts.add_argument(flag)
    return webdriver.Chrome(service=Service(str(CHROMEDRIVER)), options=opts)


def quarter_block(nu, fine_mm, size_mm, E_MPa=1.0):
    """(Model, held regions): a quarter of an elastic block (x, z >= 0 symmetry planes, y <= 0,
    the bottom held), P2, fine_mm under the origin, at least size_mm across and deep (graded
    grids that end on their first nodes beyond it)."""
    from fem.core.model import Model
    from fem.verify.closed_forms import box, fine_then_growing

    xs = fine_then_growing(fine_mm, 1.0, 1.6, size_mm)
    p, cells, r = box(xs, -fine_then_growing(fine_mm, 0.75, 1.5, size_mm)[::-1], xs)
    regions = {"top": r["ymax"], "bottom": r["ymin"], "symx": r["xmin"], "symz": r["zmin"]}
    return (Model(p, cells, np.ones(len(cells), int), regions, material=[E_MPa], nu=nu),
            {"bottom": 0.0, "symx": (0.0, None, None), "symz": (None, None, 0.0)})


def laplacian_3d(n: int):
    """(n^3, n^3) scipy CSR: the 7-point finite-difference Laplacian of an n x n x n grid
    (symmetric positive definite)."""
    import scipy.sparse as sp

    line = sp.diags([-np.ones(n - 1), 2 * np.ones(n), -np.ones(n - 1)], [-1, 0, 1])
    eye = sp.eye(n)
    return (sp.kron(sp.kron(line, eye), eye) + sp.kron(sp.kron(eye, line), eye)
            + sp.kron(sp.kron(eye, eye), line)).tocsr()
