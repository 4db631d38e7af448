"""Atomic output: a failed run leaves no half-written file or folder behind."""
from __future__ import annotations

import contextlib
import json
import os
import shutil
import tempfile
from pathlib import Path

from fingertip.errors import InputError


def check_output_dir(path: str | os.PathLike, option: str = "--out") -> Path:
    """Refuse an output folder that cannot be used, before any work; return it as a Path.

    An existing directory is fine (files with other names in it are kept). An existing file,
    or a missing folder whose nearest existing parent is not a writable directory, raises
    InputError naming `option`. Probing writes nothing that stays: a temporary folder is
    created in that parent and removed again.
    """
    out = Path(path)
    if out.exists() and not out.is_dir():
        raise InputError(f"{option} {path} is an existing file, not a folder; "
                         f"give a folder name (new or existing)")
    parent = out if out.exists() else out.parent
    parent = Path(os.path.abspath(parent))
    while not parent.exists():
        parent = parent.parent
    if not parent.is_dir():
        raise InputError(f"{option} {path} cannot be created: {parent} is a file, not a folder; "
                         f"choose another output folder")
    try:
        if not os.access(parent, os.W_OK | os.X_OK):
            raise OSError("not writable")
        shutil.rmtree(tempfile.mkdtemp(prefix=".probe-", dir=parent))
    except OSError:
        raise InputError(f"{option} {path} cannot be created: {parent} is not writable; "
                         f"choose an output folder you can write to") from None
    return out


@contextlib.contextmanager
def staged_output(out_dir: str | os.PathLike):
    """Yield a temporary folder next to `out_dir`; on success move its files into `out_dir`.

    On any exception the temporary folder is removed and `out_dir` is left as it was, so a
    failed run writes nothing. Files already in `out_dir` with other names are kept.
    """
    out = Path(out_dir)
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.partial-", dir=out.parent))
    try:
        yield tmp
        created = not out.exists()
        out.mkdir(parents=True, exist_ok=True)
        for item in tmp.iterdir():
            target = out / item.name
            if target.is_dir() and not target.is_symlink():
                shutil.rmtree(target)
            os.replace(item, target)
        if created:
            os.utime(out)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def atomic_write(path: str | os.PathLike, write) -> None:
    """Call write(tmp_path) on a temporary name beside `path`, then rename it to `path`.

    The temporary name is unique (an empty file made for it), so concurrent writers of one path
    never share it: readers see the old file or a whole new one."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, name = tempfile.mkstemp(prefix=f".{path.name}.", suffix=f".partial{path.suffix}", dir=path.parent)
    os.close(fd)
    tmp = Path(name)
    try:
        write(tmp)
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)


def write_json(path: str | os.PathLike, data) -> None:
    """Write JSON atomically (temporary name, then rename)."""
    path = Path(path)
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(json.dumps(data, indent=1))
    os.replace(tmp, path)
