"""Long library calls that Ctrl-C can interrupt: `interruptible(call, *args)` runs call on one
thread kept for the life of the process while the main thread waits in short steps. A process
that stops on Ctrl-C ends through `end_interrupted`, which does not wait for a call it abandoned."""
from __future__ import annotations

import functools
import os
import queue
import sys
import threading

WAIT_S = 0.1
"""Seconds between checks for Ctrl-C while a long library call runs in the long-call thread."""


@functools.lru_cache(maxsize=1)
def _long_calls() -> queue.SimpleQueue:
    """The queue of the one daemon thread that runs every `interruptible` call, started on first
    use. One thread for the life of the process, not one per call: MKL's OpenMP runtime keeps a
    team of threads for every thread that calls it in parallel, so a new thread per factorisation
    left one more OS thread behind each time (measured: 103 threads after 100 two-thread
    factorisations of a 29,791-unknown matrix, and 300 of them took 25.7 s and 416 MB; with this
    thread, 5 threads, 16.1 s and 135 MB)."""
    calls = queue.SimpleQueue()

    def serve():
        while True:
            call, args, box, done = calls.get()
            try:
                box["value"] = call(*args)
            except BaseException as exc:  # noqa: BLE001 - handed to the waiting thread
                box["error"] = exc
            finally:
                done.set()

    threading.Thread(target=serve, name="long calls", daemon=True).start()
    return calls


os.register_at_fork(after_in_child=_long_calls.cache_clear)    # a forked child has no such thread


def interruptible(call, *args):
    """call(*args) in the long-call thread (`_long_calls`) while this thread waits in WAIT_S
    steps, so that Ctrl-C (KeyboardInterrupt, which Python delivers to the main thread between
    bytecodes) acts within a fraction of a second during a long call that releases Python's lock
    (a PARDISO factorisation, a dense LAPACK factorisation), instead of when it returns. The
    abandoned call finishes in its thread (the next long call waits for it) or is ended with the
    process; its result is dropped. Off the main thread, where no KeyboardInterrupt arrives, call
    runs here."""
    if threading.current_thread() is not threading.main_thread():
        return call(*args)
    box, done = {}, threading.Event()
    _long_calls().put((call, args, box, done))
    try:
        while not done.wait(WAIT_S):
            pass
    except KeyboardInterrupt:
        _abandoned.append(done)
        raise
    if "error" in box:
        raise box["error"]
    return box.get("value")


_abandoned: list[threading.Event] = []
"""The completion events of the calls `interruptible` gave up waiting for."""


def end_interrupted(status: int) -> int:
    """The exit status of a process that Ctrl-C stopped, returned as is when no abandoned call
    still runs; otherwise the process ends here, its output flushed (os._exit): a normal exit runs
    the libraries' destructors, and OpenBLAS's joins the threads of the call that still runs in
    them (measured with MUMPS: the process hung until killed)."""
    if any(not done.is_set() for done in _abandoned):
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(status)
    return status
