"""What the jobs hand to `fingertip.distribute` workers: calls with BLAS and PARDISO on
TASK_THREADS threads, and the `map(fn, items)` hook the science layer takes (`fem.experiments.
runner.run_scene`, `fem.biomech.deflection.DeflectionExperiment`).

    with task_map(parse_scheduler("local:2"), "trial material", progress) as map_:
        exp = DeflectionExperiment("out/msec", map=map_)      # materials on the workers

A task runs on TASK_THREADS threads wherever it runs, and so does the caller once it uses
workers, so every sum is done in one order and a parallel run writes the bytes of a serial one.
The workers start at the first call of the map, so a scene that runs in this process after all
(`fem.experiments.runner.distribution_blocker`) starts no cluster.
"""
from __future__ import annotations

import contextlib

from fem.core.linalg import blas_threads, load_mkl
from fingertip.distribute import TaskFailed, TaskRunner
from fingertip.errors import InputError

TASK_THREADS = 1
"""BLAS and PARDISO threads of a task (and of the caller of a parallel run): the work runs in
parallel over tasks (`--scheduler local:N`)."""


def task_threads():
    """Context manager: BLAS and PARDISO limited to TASK_THREADS threads (MKL is loaded first,
    so that the limit finds it)."""
    load_mkl()
    return blas_threads(TASK_THREADS)


def call_in_task_threads(fn, *args):
    """fn(*args) on TASK_THREADS threads: the task a worker runs."""
    with task_threads():
        return fn(*args)


class _LazyMap:
    """map(fn, items) -> [fn(item) ...] in item order, one task per item on the scheduler's
    workers, started at the first call (and this process on TASK_THREADS threads from then on)."""

    def __init__(self, scheduler, what: str, progress, stack: contextlib.ExitStack):
        self.scheduler, self.what, self.progress, self.stack = scheduler, what, progress, stack
        self.runner = None

    def __call__(self, fn, items):
        items = list(items)
        if self.runner is None:
            self.runner = self.stack.enter_context(TaskRunner(self.scheduler))
            self.stack.enter_context(task_threads())
            self.progress.note(f"scheduler {self.scheduler}: {len(items)} {self.what} task(s) on "
                               f"{self.runner.workers} worker(s)")
        results = self.runner.map(call_in_task_threads, [(fn, item) for item in items])
        failed = [r for r in results if isinstance(r, TaskFailed)]
        if failed:
            raise InputError(f"{len(failed)} of {len(items)} {self.what} task(s) failed on the Dask workers, "
                             f"the first: {failed[0]}")
        return results


@contextlib.contextmanager
def task_map(scheduler, what: str, progress):
    """The map hook for a scheduler (fingertip.distribute.Scheduler): None for "none" (this
    process, as ever), else a map whose workers start at its first call and stop at exit. A task
    that fails for good raises InputError naming how many failed and the first error (`what`:
    the task's noun). progress: a `fingertip.progress` object (notes the workers)."""
    if scheduler.kind == "none":
        yield None
        return
    with contextlib.ExitStack() as stack:
        yield _LazyMap(scheduler, what, progress, stack)
