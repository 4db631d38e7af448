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
    """Thesis findings by their key."""
    return {f.key: f for f in findings}


def default_sigint() -> None:
    """preexec_fn for a child that must see Ctrl-C: a test run started in the background of a
    non-interactive shell ignores SIGINT, and a Python started with it ignored never raises
    KeyboardInterrupt."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)
