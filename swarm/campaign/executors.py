"""Where runs execute: inline, a local process pool (the default) or a Dask cluster, behind one interface.

Every executor calls :func:`execute` on ``(key, spec)`` pairs and yields results as they finish, keeping
only a bounded window of runs in flight so a 54,000-run campaign does not queue 54,000 futures. A run is
a pure function of its spec, so the executor never changes a result, only when it arrives.
"""

from __future__ import annotations

import multiprocessing
import os
import resource
import time
import traceback
from collections.abc import Iterable, Iterator
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from typing import Any, Protocol

Task = tuple[str, dict[str, Any]]


def execute(task: Task) -> dict[str, Any]:
    """Run one spec; never raises (a failure becomes a result with ``status = "failed"``)."""
    key, spec = task
    t0 = time.perf_counter()
    try:
        from ..simulation import Simulation

        result = Simulation(spec).run()
        out: dict[str, Any] = {"key": key, "status": "ok", "error": "", "summary": result.summary,
                               "timeseries": result.timeseries, "events": result.events}
        if result.key != key:
            out.update(status="failed", error=f"spec key changed in the worker ({result.key} != {key})")
    except BaseException as exc:  # a broken algorithm must not stop the campaign
        if isinstance(exc, KeyboardInterrupt):
            raise
        last = traceback.format_exception(exc)[-1].strip()
        out = {"key": key, "status": "failed", "error": last[:2000], "summary": None, "timeseries": None,
               "events": []}
    out["wall_time_s"] = time.perf_counter() - t0
    out["worker_pid"] = os.getpid()
    out["worker_rss_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    return out


class Executor(Protocol):
    name: str

    def run(self, tasks: Iterable[Task]) -> Iterator[dict[str, Any]]: ...

    def close(self) -> None: ...


class InlineExecutor:
    """In this process, one run after another (debugging, tests, profiling)."""

    name = "inline"

    def run(self, tasks: Iterable[Task]) -> Iterator[dict[str, Any]]:
        for task in tasks:
            yield execute(task)

    def close(self) -> None:
        pass


class PoolExecutor:
    """A local process pool (``spawn`` start method: no inherited zenoh/numba threads)."""

    def __init__(self, workers: int, max_runs_per_worker: int | None = None) -> None:
        self.name = f"pool:{workers}"
        self.workers = workers
        self.pool = ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn"),
                                        max_tasks_per_child=max_runs_per_worker)

    def run(self, tasks: Iterable[Task]) -> Iterator[dict[str, Any]]:
        pending: set = set()
        it = iter(tasks)
        window = 2 * self.workers
        for task in it:
            pending.add(self.pool.submit(execute, task))
            if len(pending) >= window:
                done, pending = wait(pending, return_when=FIRST_COMPLETED)
                for f in done:
                    yield f.result()
        while pending:
            done, pending = wait(pending, return_when=FIRST_COMPLETED)
            for f in done:
                yield f.result()

    def close(self) -> None:
        self.pool.shutdown(wait=True, cancel_futures=True)


class DaskExecutor:
    """Dask distributed: ``local`` starts a LocalCluster of ``workers`` single-threaded processes; anything
    else is a scheduler address (``tcp://host:8786``), e.g. a cluster started by dask-jobqueue on SLURM."""

    def __init__(self, address: str, workers: int) -> None:
        from distributed import Client, LocalCluster

        self.cluster = None
        if address == "local":
            self.cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                        dashboard_address=None, silence_logs=40)
            self.client = Client(self.cluster)
        else:
            self.client = Client(address, timeout="30s")
        self.name = f"dask:{address}"
        self.window = max(2 * workers, 2 * len(self.client.scheduler_info().get("workers", {})) or 2)

    def run(self, tasks: Iterable[Task]) -> Iterator[dict[str, Any]]:
        from distributed import as_completed

        it = iter(tasks)
        first = [self.client.submit(execute, t, pure=False) for _, t in zip(range(self.window), it)]
        ac = as_completed(first)
        for future in ac:
            yield future.result()
            future.release()
            nxt = next(it, None)
            if nxt is not None:
                ac.add(self.client.submit(execute, nxt, pure=False))

    def close(self) -> None:
        self.client.close()
        if self.cluster is not None:
            self.cluster.close()


def make_executor(workers: int | None = None, dask: str | None = None, inline: bool = False) -> Executor:
    if inline:
        return InlineExecutor()
    n = workers or os.cpu_count() or 1
    if dask:
        return DaskExecutor(dask, n)
    return PoolExecutor(n)
