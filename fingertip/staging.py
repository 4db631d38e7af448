"""Atomic output: a failed run leaves no half-written file or folder behind.

    out = check_output_dir(args.out, marker="run.json", what="indent run")   # before any work
    with claimed(out):                                   # one command at a time per folder
        ...                                              # the work
        with staged_output(out, replace=True) as tmp:    # files into tmp; then tmp becomes out
            ...

An output folder that is entirely one command's (a run folder, an analysis, a layer study) is
replaced as a whole on a rerun (`replace=True`), so no file of an earlier run stays beside the new
ones; such a folder is recognised by its marker file, and one holding other files is refused
(nothing of the user's is deleted). Folders shared by several stages (a model folder, the `run`
chain's folder, a cohort) keep the files they hold.
"""
from __future__ import annotations

import contextlib
import errno
import functools
import inspect
import json
import os
import secrets
import shutil
import tempfile
from pathlib import Path

from fingertip.errors import InputError

LOCK_SUFFIX = ".lock"
"""A folder in use by a command has the lock file `.<name>.lock` beside it (`claimed`)."""


def _writable(folder: Path) -> bool:
    """Whether files can be made in `folder` (an existing directory): access bits, then a probe
    folder made and removed again (access bits do not see a read-only mount)."""
    try:
        if not os.access(folder, os.W_OK | os.X_OK):
            return False
        shutil.rmtree(tempfile.mkdtemp(prefix=".probe-", dir=folder))
    except OSError:
        return False
    return True


def check_output_dir(path: str | os.PathLike, option: str = "--out", marker: str | None = None,
                     what: str | None = None) -> Path:
    """Refuse an output folder that cannot be used, before any work; return it as a Path.

    An empty path, an existing file, or a missing folder whose nearest existing parent is not a
    writable directory raises InputError naming `option`. Probing writes nothing that stays: a
    temporary folder is created in that parent and removed again.
    marker: the file that marks an earlier output of the command (e.g. "run.json"), for an
    output folder the command replaces as a whole (`staged_output(replace=True)`): an existing
    folder that is neither empty nor holds the marker is refused (what: the command's output in
    words, e.g. "indent run"). Without a marker an existing folder is fine (files with other
    names in it are kept).
    """
    if not os.fspath(path).strip():
        raise InputError(f"{option} is empty: give a folder name (new or existing)")
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
    if not _writable(parent):
        raise InputError(f"{option} {path} cannot be created: {parent} is not writable; "
                         f"choose an output folder you can write to")
    if marker is not None and out.is_dir() and not (out / marker).is_file() and any(out.iterdir()):
        raise InputError(f"{option} {path} holds files that are not an earlier {what or 'output'} "
                         f"(no {marker}): give a new or empty folder")
    return out


def check_writable_folder(path: str | os.PathLike, what: str) -> Path:
    """Refuse an existing folder the command must write into (e.g. a model folder that keeps
    stored response models) when files cannot be made there; `what` names it for the message."""
    folder = Path(path)
    if folder.is_dir() and not _writable(folder):
        raise InputError(f"{what} {path} is not writable: make it writable (chmod u+w {path}) or copy "
                         f"it to a folder you can write to")
    return folder


# --------------------------------------------------------------------------- lock
def holding(param: str = "out_dir"):
    """Decorator: the function holds its output folder (its argument `param`) while it runs
    (`claimed`), refused like `check_output_dir` first."""
    def wrap(fn):
        signature = inspect.signature(fn)

        @functools.wraps(fn)
        def run(*args, **kwargs):
            out = signature.bind(*args, **kwargs).arguments.get(param)
            if out is None:
                return fn(*args, **kwargs)
            with claimed(out):
                return fn(*args, **kwargs)
        return run
    return wrap


# --------------------------------------------------------------------------- lock
def _lock_path(out: Path) -> Path:
    out = Path(os.path.abspath(out))
    return out.parent / f".{out.name}{LOCK_SUFFIX}"


def _holder(lock: Path) -> int | None:
    """The pid written in a lock file (None: unreadable or not a pid)."""
    try:
        return int(lock.read_text().split()[0])
    except (OSError, ValueError, IndexError):
        return None


def _alive(pid: int | None) -> bool:
    """Whether a process of this pid runs on this machine."""
    if pid is None or pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:                     # someone else's process: it exists
        return True
    except OSError:
        return False
    return True


def _make_parents(folder: Path) -> list[Path]:
    """mkdir -p folder; returns the folders made, deepest first (to remove them again)."""
    made = []
    while not folder.exists():
        made.append(folder)
        folder = folder.parent
    for f in reversed(made):
        f.mkdir(exist_ok=True)
    return made


def _take(lock: Path, shown: str) -> bool:
    """Create `lock` exclusively with this process's id (True), taking over a lock whose process is
    gone; False when no file can be made there (a read-only parent: the folder is not locked).
    InputError when a live process holds it (`shown`: the folder as the user gave it)."""
    for _ in range(3):
        try:
            fd = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
        except FileExistsError:
            pid = _holder(lock)
            if _alive(pid) or (pid is None and lock.exists()):
                who = f"another command (pid {pid})" if pid is not None else "another command"
                raise InputError(f"{shown} is in use by {who}: wait for it to finish or give another folder "
                                 f"(if no such command runs, remove {lock})") from None
            with contextlib.suppress(FileNotFoundError):         # its process is gone: take it over
                lock.unlink()
            continue
        except OSError as exc:
            if exc.errno in (errno.EACCES, errno.EROFS, errno.EPERM):
                return False
            raise
        with os.fdopen(fd, "w") as fh:
            fh.write(f"{os.getpid()}\n")
        return True
    raise InputError(f"{shown} is in use by another command: wait for it to finish or give another folder")


@contextlib.contextmanager
def claimed(out_dir: str | os.PathLike, option: str = "--out"):
    """Hold the output folder `out_dir` for this command while the block runs: a lock file
    `.<name>.lock` beside it, created exclusively with this process's id. Another command
    holding it is refused with InputError naming its pid; a lock left by a process that is gone
    is taken over. The lock (and any parent folder made for it) is removed at the end. The folder
    is checked first (`check_output_dir`: an empty path, a file, an uncreatable folder); an
    existing folder whose parent is read-only is used without a lock."""
    check_output_dir(out_dir, option)
    lock = _lock_path(Path(out_dir))
    made = _make_parents(lock.parent)
    try:
        taken = _take(lock, f"{option} {out_dir}")
        try:
            yield Path(out_dir)
        finally:
            if taken and _holder(lock) == os.getpid():
                with contextlib.suppress(OSError):
                    lock.unlink()
    finally:
        for f in made:
            with contextlib.suppress(OSError):
                f.rmdir()                       # only when empty: the output went elsewhere


@contextlib.contextmanager
def staged_output(out_dir: str | os.PathLike, replace: bool = False):
    """Yield a temporary folder next to `out_dir`; on success move its files into `out_dir`.

    On any exception the temporary folder is removed and `out_dir` is left as it was, so a
    failed run writes nothing. Files already in `out_dir` with other names are kept, unless
    replace: then the temporary folder replaces `out_dir` as a whole (no file of an earlier run
    stays; the old folder is removed only once the new one is in place). Check such a folder
    first with `check_output_dir(marker=...)`, so that nothing else is deleted.
    """
    out = Path(out_dir)
    out.parent.mkdir(parents=True, exist_ok=True)
    root = Path(tempfile.mkdtemp(prefix=f".{out.name}.partial-", dir=out.parent))
    tmp = root / out.name
    tmp.mkdir()                                 # the umask's mode, as a folder made by mkdir
    try:
        yield tmp
        if replace:
            _replace(tmp, out, root)
        else:
            _merge(tmp, out)
    finally:
        shutil.rmtree(root, ignore_errors=True)


def _merge(tmp: Path, out: Path) -> None:
    """Move the files of `tmp` into `out` (made when missing), each replacing its namesake."""
    if not out.exists():
        os.replace(tmp, out)                    # a new folder appears whole
        return
    for item in tmp.iterdir():
        target = out / item.name
        if target.is_dir() and not target.is_symlink():
            shutil.rmtree(target)
        os.replace(item, target)


def _replace(tmp: Path, out: Path, root: Path) -> None:
    """`tmp` becomes `out`: the old `out` (if any) is moved into `root` (removed with it)."""
    old = None
    if out.is_dir() and not out.is_symlink():
        old = root / ".old"
        os.replace(out, old)
    try:
        os.replace(tmp, out)
    except BaseException:
        if old is not None:
            os.replace(old, out)                # put the earlier output back
        raise


def atomic_write(path: str | os.PathLike, write) -> None:
    """Call write(tmp_path) on a temporary name beside `path`, then rename it to `path`.

    The temporary name is unique (an empty file made for it), so concurrent writers of one path
    never share it: readers see the old file or a whole new one. The file gets the mode a plain
    open() would give it (0666 less the umask: 0644 typically), not tempfile's 0600."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    while True:
        tmp = path.parent / f".{path.name}.{os.getpid()}.{secrets.token_hex(4)}.partial{path.suffix}"
        try:
            os.close(os.open(tmp, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o666))
            break
        except FileExistsError:
            continue
    try:
        write(tmp)
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)


def write_json(path: str | os.PathLike, data) -> None:
    """Write JSON atomically (`atomic_write`)."""
    atomic_write(path, lambda tmp: Path(tmp).write_text(json.dumps(data, indent=1)))
