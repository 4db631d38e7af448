"""What produced an output: the project's version and commit, the date, Python and the libraries
the numbers depend on, and the machine; for reports and run records.

The date honours SOURCE_DATE_EPOCH (the reproducible-builds convention) so that a rerun can be made
byte-identical on purpose.
"""
from __future__ import annotations

import datetime as _dt
import os
import platform
import subprocess
from importlib import metadata
from pathlib import Path

PACKAGE = "fingertip-fem"
#: Distributions whose versions change the numbers (solver, meshing, forms) or the figures.
LIBRARIES = ("numpy", "scipy", "scikit-fem", "pypardiso", "mkl", "pytetwild", "trimesh", "meshio", "opencv-python",
             "opencv-python-headless", "matplotlib")


def version(dist: str) -> str | None:
    """Installed version of distribution `dist`, None when it is not installed."""
    try:
        return metadata.version(dist)
    except metadata.PackageNotFoundError:
        return None


def source_commit(folder: Path | None = None) -> str | None:
    """The git commit of the source tree holding this package ('<sha>+dirty' with uncommitted
    changes), None when it is not a git checkout (an installed wheel) or git is absent."""
    folder = Path(__file__).resolve().parents[1] if folder is None else Path(folder)
    if not (folder / ".git").exists():
        return None
    try:
        sha = subprocess.run(["git", "-C", str(folder), "rev-parse", "HEAD"], capture_output=True,
                             text=True, timeout=10, check=True).stdout.strip()
        dirty = subprocess.run(["git", "-C", str(folder), "status", "--porcelain", "--untracked-files=no"],
                               capture_output=True, text=True, timeout=10, check=True).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return None
    return sha + ("+dirty" if dirty else "")


def today() -> str:
    """UTC date and time (ISO 8601, seconds), from SOURCE_DATE_EPOCH when it is set."""
    epoch = os.environ.get("SOURCE_DATE_EPOCH")
    now = (_dt.datetime.fromtimestamp(int(epoch), _dt.UTC) if epoch and epoch.isdigit()
           else _dt.datetime.now(_dt.UTC))
    return now.replace(microsecond=0).isoformat()


def provenance() -> dict:
    """{"package", "version", "commit", "date", "python", "libraries", "machine"}."""
    return {"package": PACKAGE, "version": version(PACKAGE), "commit": source_commit(), "date": today(),
            "python": platform.python_version(),
            "libraries": {d: v for d in LIBRARIES if (v := version(d)) is not None},
            "machine": {"system": f"{platform.system()} {platform.release()}", "cpu": platform.machine(),
                        "cores": os.cpu_count()}}
