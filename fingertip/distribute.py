"""Independent tasks run in this process or on Dask, results in task order.

    scheduler = parse_scheduler("local:2")          # "none", "local:N" or "tcp://host:port"
    with TaskRunner(scheduler) as runner:
        results = runner.map(run_subject, [(a,), (b,), (c,)])   # [f(a), f(b), f(c)]

Dask (`dask[distributed]`, the optional extra `pip install -e ".[dask]"`) is imported only when a
scheduler other than "none" is used (inside the functions: it is an optional extra most installs
do not have). A task is a module-level function and small arguments (paths,
option values): workers read large inputs from a folder they share with the caller, so what goes
over the network per task is a few hundred bytes. Results come back in the order of the tasks,
not of completion, so a run gives the same output whatever the scheduler. A task whose worker dies
is re-run by Dask on another worker (up to `distributed.scheduler.allowed-failures` deaths) and a
task that raises is re-run `retries` times; a task that still fails gives a `TaskFailed` in its
place of the result list, and the other tasks go on.

Worker processes of a local cluster are not daemonic, so a task may start processes of its own
(3D meshing runs pytetwild in one); workers of an existing cluster need the same setting
(DASK_DISTRIBUTED__WORKER__DAEMON=False in their environment).
"""
from __future__ import annotations

import pickle
import re
import time
from dataclasses import dataclass, field

from fingertip.errors import InputError

INSTALL_HINT = 'pip install -e ".[dask]"'
"""How to install the optional Dask extra (named in the one-line error without it)."""
RETRIES = 2
"""Re-runs of a task that raised on a worker (worker deaths are counted by Dask separately)."""


@dataclass(frozen=True)
class Scheduler:
    """Where tasks run: kind "none" (this process), "local" (a LocalCluster of `workers` worker
    processes, one thread each) or "address" (an existing cluster at `address`, tcp://host:port)."""
    kind: str = "none"
    workers: int = 1
    address: str | None = None

    def __str__(self):
        return {"none": "none", "local": f"local:{self.workers}"}.get(self.kind, self.address)


def parse_scheduler(text: str | None, option: str = "--scheduler") -> Scheduler:
    """`none` (or None), `local:N` (N >= 1 worker processes) or `tcp://HOST:PORT`; InputError else.
    Checks the form only; whether Dask is installed is `require_dask`'s question."""
    if text is None or text == "none":
        return Scheduler()
    m = re.fullmatch(r"local:(\d+)", text)
    if m:
        if int(m.group(1)) < 1:
            raise InputError(f"{option} {text}: give at least one worker, e.g. local:2")
        return Scheduler("local", int(m.group(1)))
    if re.fullmatch(r"(tcp|tls)://[^\s/:]+:\d+", text):
        return Scheduler("address", address=text)
    raise InputError(f"{option} '{text}': use none, local:N (N worker processes on this machine) or "
                     f"tcp://HOST:PORT (the scheduler address of a running Dask cluster)")


def require_dask(scheduler: Scheduler, option: str = "--scheduler") -> None:
    """InputError saying how to install the extra when the scheduler needs Dask and it is missing."""
    if scheduler.kind == "none":
        return
    try:
        import distributed  # noqa: F401
    except ImportError:
        raise InputError(f"{option} {scheduler} needs Dask, which is not installed: {INSTALL_HINT} "
                         f"(or use {option} none)") from None


@dataclass
class TaskFailed:
    """The place of a task that failed for good (its worker kept dying, or it raised every time)."""
    error: str

    def __str__(self):
        return self.error


@dataclass
class TaskStats:
    """What a map cost: seconds from submit to the last result, pickled bytes of each task's call
    (function reference and arguments) and of each result."""
    seconds: float = 0.0
    task_bytes: list = field(default_factory=list)
    result_bytes: list = field(default_factory=list)


def _one_line(exc: BaseException) -> str:
    return " ".join(f"{type(exc).__name__}: {exc}".split())


class TaskRunner:
    """Runs independent tasks on a `Scheduler` (a context manager: a local cluster is started on
    entry and closed on exit; an existing cluster is only connected to)."""

    def __init__(self, scheduler: Scheduler = Scheduler(), retries: int = RETRIES):
        self.scheduler, self.retries = scheduler, retries
        self.client = self.cluster = None
        self.stats = TaskStats()

    def __enter__(self):
        s = self.scheduler
        if s.kind == "none":
            return self
        require_dask(s)
        from distributed import Client, LocalCluster

        if s.kind == "local":
            import dask

            with dask.config.set({"distributed.worker.daemon": False}):      # tasks may start processes
                self.cluster = LocalCluster(n_workers=s.workers, threads_per_worker=1, processes=True,
                                            dashboard_address=None)
            self.client = Client(self.cluster)
        else:
            try:
                self.client = Client(s.address, timeout="10s")
            except OSError as exc:
                raise InputError(f"--scheduler {s.address}: no Dask scheduler answers there "
                                 f"({_one_line(exc)}); start one (dask scheduler) or check the address") from None
        return self

    def __exit__(self, *exc):
        if self.client is not None:
            self.client.close()
        if self.cluster is not None:
            self.cluster.close()
        self.client = self.cluster = None

    @property
    def workers(self) -> int:
        """Number of workers tasks can run on (1 in this process)."""
        if self.client is None:
            return 1
        return max(1, len(self.client.scheduler_info()["workers"]))

    def map(self, fn, calls: list[tuple], done=None) -> list:
        """[fn(*args) for args in calls], in the order of `calls`; a task that fails for good
        gives a TaskFailed in its place (in this process an exception propagates, as any call's
        would). done(index, result) is called as each task finishes (in completion order)."""
        start = time.perf_counter()
        self.stats = TaskStats(task_bytes=[len(pickle.dumps((fn, args))) for args in calls])
        if self.client is None:
            results = []
            for i, args in enumerate(calls):
                results.append(fn(*args))
                if done is not None:
                    done(i, results[-1])
        else:
            results = self._map_dask(fn, calls, done)
        self.stats.seconds = time.perf_counter() - start
        self.stats.result_bytes = [len(pickle.dumps(r)) for r in results]
        return results

    def _map_dask(self, fn, calls, done):
        from distributed import as_completed

        futures = [self.client.submit(fn, *args, key=f"{getattr(fn, '__name__', 'task')}-{i}-{time.time_ns()}",
                                      retries=self.retries, pure=False) for i, args in enumerate(calls)]
        index = {f.key: i for i, f in enumerate(futures)}
        results = [None] * len(calls)
        for future in as_completed(futures):
            i = index[future.key]
            try:
                results[i] = future.result()
            except Exception as exc:  # noqa: BLE001 - KilledWorker or the task's own error, after retries
                results[i] = TaskFailed(_one_line(exc))
            future.release()
            if done is not None:
                done(i, results[i])
        return results
