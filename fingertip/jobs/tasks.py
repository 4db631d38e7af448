"""What the command back ends hand to `fingertip.distribute` workers: calls with BLAS and PARDISO
on TASK_THREADS threads, and the `map(fn, items)` hook of the science layer on a TaskRunner.

    with TaskRunner(parse_scheduler("local:2")) as runner, task_threads():
        exp = DeflectionExperiment("out/msec", map=task_map(runner))     # materials on the workers

A task runs on TASK_THREADS threads wherever it runs, and so does the caller while it uses
workers, so every sum is done in one order and a parallel run writes the bytes of a serial one.
"""
from __future__ import annotations

import contextlib

from fingertip.distribute import TaskFailed
from fingertip.errors import InputError

TASK_THREADS = 1
"""BLAS and PARDISO threads of a task (and of the caller of a parallel run): the work runs in
parallel over tasks (`--scheduler local:N`)."""


def task_threads():
    """Context manager: BLAS and PARDISO limited to TASK_THREADS threads (MKL is loaded first,
    so that the limit finds it)."""
    from fem.core.linalg import blas_threads

    with contextlib.suppress(ImportError):
        import pypardiso  # noqa: F401
    return blas_threads(TASK_THREADS)


def call_in_task_threads(fn, *args):
    """fn(*args) on TASK_THREADS threads: the task a worker runs."""
    with task_threads():
        return fn(*args)


def task_map(runner, what: str = "task"):
    """map(fn, items) -> [fn(item) ...] in item order, one task per item on `runner` (a
    fingertip.distribute.TaskRunner), each on TASK_THREADS threads. A task that fails for good
    raises InputError naming how many failed and the first error (`what`: the task's noun)."""
    def map_(fn, items):
        items = list(items)
        results = runner.map(call_in_task_threads, [(fn, item) for item in items])
        failed = [r for r in results if isinstance(r, TaskFailed)]
        if failed:
            raise InputError(f"{len(failed)} of {len(items)} {what} task(s) failed on the Dask workers, "
                             f"the first: {failed[0]}")
        return results
    return map_
