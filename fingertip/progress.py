"""Progress reports on stderr for long steps; silent unless asked.

    progress = as_progress(progress)                  # None / False -> SILENT, True -> Progress()
    for exp in progress.bar(experiments, desc="experiments", unit="experiment"):
        ...                                           # a tqdm bar (known count)
    with progress.task("factorising 196644 DOFs", kind="factorise", size=196644):
        ...                                           # one long call: "<desc>: 12 s (about 40 s)"
    progress.note("mesh from cache")                  # one line

Science functions take `progress=None` and call `as_progress` on it; any object with the three
methods `bar`, `task` and `note` will do (duck typing). `Silent` does nothing, so the library
prints nothing when called from Python unless given `Progress()`.

A task line is refreshed about once a second by a background thread while the call runs (calls
that release the GIL: PARDISO, numpy, waiting for pytetwild's worker process). When `kind` and `size` are given, the seconds
it took are kept in a small per-machine timing history (`timings.json` in the cache folder,
written atomically), and later tasks of that kind show an estimate: a power law t = a size^b
fitted to the earlier (size, seconds) of this host. Without history only the elapsed time shows.
"""
from __future__ import annotations

import contextlib
import json
import math
import os
import platform
import sys
import threading
import time
from pathlib import Path

from tqdm import tqdm

HISTORY_KEEP = 30
"""Timings kept per kind and host (the most recent)."""
REFRESH_S = 1.0
"""Seconds between refreshes of a task line."""
BAR_DELAY_S = 0.5
"""Seconds before a bar shows (unless told otherwise): a loop that ends, or is refused, sooner
prints nothing, so an error found in its first half second is the only line."""

def cache_root() -> Path:
    """The toolkit's cache folder: $FINGERTIP_CACHE_DIR, else ~/.cache/fingertip-fem."""
    return Path(os.environ.get("FINGERTIP_CACHE_DIR", Path.home() / ".cache" / "fingertip-fem"))


class Silent:
    """Progress that reports nothing (the default of every science function)."""
    def bar(self, iterable, total=None, desc="", unit="it", delay=None):
        return iterable

    @contextlib.contextmanager
    def task(self, desc, kind=None, size=None):
        yield

    def note(self, text):
        pass


SILENT = Silent()


def as_progress(progress):
    """None or False -> SILENT; True -> Progress() on stderr; any other object is used as is."""
    if progress is None or progress is False:
        return SILENT
    if progress is True:
        return Progress()
    return progress


class TimingHistory:
    """(size, seconds) of earlier long calls per kind on this host, in a JSON file; `estimate`
    extrapolates them with a power law. A missing or unreadable file is an empty history."""
    def __init__(self, path=None):
        self.path = Path(path) if path is not None else cache_root() / "timings.json"
        self.host = platform.node() or "host"

    def _read(self) -> dict:
        try:
            data = json.loads(self.path.read_text())
            return data if isinstance(data, dict) else {}
        except (OSError, ValueError):
            return {}

    def records(self, kind) -> list[tuple[float, float]]:
        rows = self._read().get(kind, {}).get(self.host, [])
        try:
            return [(float(n), float(s)) for n, s in rows if float(n) > 0 and float(s) > 0]
        except (TypeError, ValueError):
            return []

    def estimate(self, kind, size) -> float | None:
        """Seconds a call of this kind and size should take, or None without history. One earlier
        size: proportional to size; several: least-squares power law in log-log (exponent
        limited to 0.5-3, the range of meshing and sparse factorisation)."""
        rows = self.records(kind)
        if not rows or not size or size <= 0:
            return None
        n = [math.log(r[0]) for r in rows]
        t = [math.log(r[1]) for r in rows]
        mean_n, mean_t = sum(n) / len(n), sum(t) / len(t)
        var = sum((x - mean_n) ** 2 for x in n)
        b = 1.0 if var < 1e-6 else sum((x - mean_n) * (y - mean_t) for x, y in zip(n, t)) / var
        b = min(max(b, 0.5), 3.0)
        return math.exp(mean_t + b * (math.log(size) - mean_n))

    def add(self, kind, size, seconds) -> None:
        """Record one timing (atomically replaces the file; concurrent writers may drop a record,
        never corrupt the file)."""
        data = self._read()
        rows = data.setdefault(kind, {}).setdefault(self.host, [])
        rows.append([float(size), round(float(seconds), 3)])
        del rows[:-HISTORY_KEEP]
        tmp = self.path.with_name(f".{self.path.name}.{os.getpid()}.{threading.get_ident()}.tmp")
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            tmp.write_text(json.dumps(data))
            os.replace(tmp, self.path)
        except OSError:
            pass                                   # a timing history is a convenience
        finally:
            with contextlib.suppress(OSError):
                tmp.unlink()


def _seconds(s: float) -> str:
    if s < 10:
        return f"{s:.1f} s"
    return f"{s:.0f} s" if s < 100 else f"{int(s // 60)} min {int(s % 60):02d} s"


class Progress:
    """Progress on a stream (stderr): tqdm bars, task lines with elapsed time and estimate, notes.

    history: a TimingHistory (default: the cache folder's), or None to neither read nor record."""
    def __init__(self, stream=None, history="default"):
        self.stream = stream if stream is not None else sys.stderr
        self.history = TimingHistory() if history == "default" else history
        self._bars = []                              # open bars, innermost last

    def bar(self, iterable, total=None, desc="", unit="it", delay=None):
        """Iterate with a bar (total: the count when `iterable` has no length; delay: seconds before
        the bar shows, default BAR_DELAY_S, so a loop that ends early, or fails on its first items,
        prints nothing)."""
        delay = BAR_DELAY_S if delay is None else delay
        if total is None and hasattr(iterable, "__len__"):
            total = len(iterable)
        bar = tqdm(iterable, total=total, desc=desc, unit=unit, file=self.stream, dynamic_ncols=True,
                   leave=not self._bars, position=len(self._bars) if self._bars else None, delay=delay)
        self._bars.append(bar)
        try:
            yield from bar
        finally:
            self._bars.remove(bar)
            bar.close()

    @contextlib.contextmanager
    def task(self, desc, kind=None, size=None):
        """Report one long call: inside a bar its status (postfix) shows the task, else a line of
        its own ("desc: elapsed (about N s expected)", then "desc: done in N s"), shown from the
        first refresh on (calls shorter than REFRESH_S print nothing). The call must release
        Python's lock for the refreshes to run (PARDISO, numpy, a worker process do)."""
        guess = self.history.estimate(kind, size) if self.history is not None and kind else None
        start = time.perf_counter()
        outer = self._bars[-1] if self._bars else None
        shown = {}                                   # the line, made on the first refresh

        def status(done=False):
            elapsed = time.perf_counter() - start
            text = f"done in {elapsed:.1f} s" if done else _seconds(elapsed)
            if guess is not None and not done:
                text += (f" (about {_seconds(guess)} expected)" if elapsed < guess
                         else f" (longer than the {_seconds(guess)} expected)")
            if outer is not None:
                outer.set_postfix_str("" if done else f"{desc}: {text}", refresh=True)
                return
            if "line" not in shown:
                shown["line"] = tqdm(total=None, file=self.stream, leave=True, bar_format="{desc}",
                                     dynamic_ncols=True)
            shown["line"].set_description_str(f"{desc}: {text}", refresh=True)

        stop = threading.Event()

        def refresh():
            while not stop.wait(REFRESH_S):
                status()

        thread = threading.Thread(target=refresh, daemon=True)
        thread.start()
        ok = False
        try:
            yield
            ok = True
        finally:
            stop.set()
            thread.join()
            if ok and (shown or outer is not None):
                status(done=True)
            if "line" in shown:
                shown["line"].close()
            if ok:
                self._record(kind, size, start)

    def _record(self, kind, size, start):
        if kind and size and self.history is not None:
            self.history.add(kind, size, time.perf_counter() - start)

    def note(self, text):
        """One line of text (printed above any open bar)."""
        tqdm.write(str(text), file=self.stream)
