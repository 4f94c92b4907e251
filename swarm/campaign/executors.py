"""Where runs execute: inline, a local process pool (the default) or a Dask cluster, behind one interface.

Every executor calls :func:`execute` on ``(key, spec)`` pairs and yields results as they finish, keeping
only a bounded window of runs in flight so a 54,000-run campaign does not queue 54,000 futures. A run is
a pure function of its spec, so the executor never changes a result, only when it arrives.
"""

from __future__ import annotations

import multiprocessing
import os
import re
import resource
import socket
import sys
import threading
import time
import traceback
import types
from collections.abc import Iterable, Iterator
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from typing import Any, Protocol

from swarm.base.errors import InvalidInput

from .limits import DASK_CONNECT_TIMEOUT_S

Task = tuple[str, dict[str, Any]]


def execute(task: Task) -> dict[str, Any]:
    """Run one spec; never raises (a failure becomes a result with ``status = "failed"``).

    Besides the run's result: its wall and CPU time, the part of it spent in numba's compiler (compiling or
    loading cached kernels: a worker's first runs) and the functions it compiled, and its start and end on the machine's monotonic clock
    (``started``/``ended``: the gaps between a worker's runs are the pool's overhead, see :mod:`.estimate`)."""
    from swarm.util.jit import JitWatch

    key, spec = task
    started = time.monotonic()
    t0 = time.perf_counter()
    c0 = time.process_time()
    watch = JitWatch()
    try:
        from swarm.sim.loop import Simulation

        with watch:
            result = Simulation(spec).run()
        algorithm = result.provenance["algorithm"]
        out: dict[str, Any] = {"key": key, "status": "ok", "error": "", "summary": result.summary,
                               "timeseries": result.timeseries, "events": result.events, "comm": result.comm,
                               "algorithm_dist": (algorithm["distribution"], algorithm["version"])}
        if result.key != key:
            out.update(status="failed", error=f"spec key changed in the worker ({result.key} != {key})")
    except BaseException as exc:  # a broken algorithm must not stop the campaign
        if isinstance(exc, KeyboardInterrupt):
            raise
        last = traceback.format_exception(exc)[-1].strip()
        out = {"key": key, "status": "failed", "error": last[:2000], "summary": None, "timeseries": None,
               "events": [], "comm": None}
    out["wall_time_s"] = time.perf_counter() - t0
    out["cpu_time_s"] = time.process_time() - c0
    out["jit_time_s"] = watch.seconds
    out["jit_compiled"] = watch.compiled
    out["started"], out["ended"] = started, time.monotonic()
    out["worker_pid"] = os.getpid()
    out["worker_rss_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    return out


class Executor(Protocol):
    name: str
    shares_cache: bool
    """Its workers use this machine's numba cache (so kernels compiled here first serve them)."""

    def run(self, tasks: Iterable[Task]) -> Iterator[dict[str, Any]]: ...

    def close(self) -> None: ...


class InlineExecutor:
    """In this process, one run after another (debugging, tests, profiling)."""

    name = "inline"
    shares_cache = True

    def run(self, tasks: Iterable[Task]) -> Iterator[dict[str, Any]]:
        for task in tasks:
            yield execute(task)

    def close(self) -> None:
        pass


ORPHAN_CHECK_S = 1.0
"""How often a pool worker checks that the campaign process that started it is still alive."""


def _exit_when_orphaned(parent: int) -> None:
    """Exit this worker as soon as its parent is gone (killed, say, with no chance to stop its pool): an
    orphaned worker would otherwise finish its run, then wait on a queue nobody writes to, for ever."""
    while True:
        time.sleep(ORPHAN_CHECK_S)
        if os.getppid() != parent:
            os._exit(1)


def _worker_start(parent: int | None = None) -> None:
    """A pool worker's start: import the runtime before the first run, so that no run's time includes it;
    watch the campaign process (``parent``), and go when it goes."""
    if parent is not None:
        threading.Thread(target=_exit_when_orphaned, args=(parent,), name="swarm-orphan-watch", daemon=True).start()
    from swarm.sim import loop  # noqa: F401


_MAIN_SWAP = threading.Lock()


class _WorkerProcess(multiprocessing.context.SpawnProcess):
    """A spawned pool worker that does not run the caller's ``__main__`` script again.

    A spawned child normally re-imports the parent's main script (to find what it pickled there), so a
    script calling ``swarm.campaign.run`` without ``if __name__ == "__main__":`` started the campaign again
    in every worker and broke the pool. A worker only runs :func:`execute` on plain data, so it is started
    with a bare ``__main__`` in place of the script's: the swap lasts while the process is launched (its
    start data is built and pickled then) and holds a lock, so two launches never interleave."""

    @staticmethod
    def _Popen(process_obj: Any) -> Any:
        with _MAIN_SWAP:
            main = sys.modules["__main__"]
            sys.modules["__main__"] = types.ModuleType("__main__")  # no __file__, no __spec__: nothing to run
            try:
                return multiprocessing.context.SpawnProcess._Popen(process_obj)
            finally:
                sys.modules["__main__"] = main


def _check_outside_main(task: Task) -> None:
    """A pool worker does not run the caller's script (:class:`_WorkerProcess`), so it cannot load an
    algorithm defined there (``__main__:Class``): refused before the run, rather than every run failing."""
    name = task[1].get("algorithm", {}).get("name", "")
    if isinstance(name, str) and name.startswith("__main__:"):
        raise InvalidInput("algorithm.name", name, "a class in an importable module ('package.module:Class'): "
                                                   "pool workers do not run your script; move the class to a "
                                                   "module, or run the campaign inline")


class _WorkerContext(multiprocessing.context.SpawnContext):
    """The ``spawn`` context, with workers that leave the caller's script alone (:class:`_WorkerProcess`)."""

    Process = _WorkerProcess


class PoolExecutor:
    """A local process pool (``spawn`` start method: no inherited zenoh/numba threads; the caller's script is
    not run again in the workers, so it needs no ``__main__`` guard). Each worker imports
    the runtime when it starts, not in its first run, and exits when the campaign process is gone. Closing
    waits for the runs in flight; :meth:`abort` (Ctrl-C, SIGTERM) stops the workers at once instead (their
    runs are not written; a resumed campaign runs them again)."""

    shares_cache = True

    def __init__(self, workers: int, max_runs_per_worker: int | None = None) -> None:
        self.name = f"pool:{workers}"
        self.workers = workers
        self.pool = ProcessPoolExecutor(max_workers=workers, mp_context=_WorkerContext(),
                                        max_tasks_per_child=max_runs_per_worker, initializer=_worker_start,
                                        initargs=(os.getpid(),))

    def run(self, tasks: Iterable[Task]) -> Iterator[dict[str, Any]]:
        pending: set = set()
        it = iter(tasks)
        window = 2 * self.workers
        for task in it:
            _check_outside_main(task)
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

    def abort(self) -> None:
        """Stop now: cancel queued runs and terminate the workers (runs in flight are lost, not written)."""
        processes = list(getattr(self.pool, "_processes", {}).values())  # the stdlib has no public handle before 3.14
        self.pool.shutdown(wait=False, cancel_futures=True)
        for proc in processes:
            if proc.is_alive():
                proc.terminate()
        for proc in processes:
            proc.join(timeout=5)


DASK_SCHEMES = ("tcp", "tls", "ucx", "ws", "wss")
_ADDRESS = re.compile(r"^(?:(?P<scheme>[a-z]+)://)?(?P<host>\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9_.-]+):(?P<port>[0-9]{1,5})/?$")


def check_dask_address(address: str) -> tuple[str, str, int] | None:
    """None for ``local``; else ``(scheme, host, port)`` of a scheduler address, or :class:`InvalidInput`."""
    if address == "local":
        return None
    m = _ADDRESS.match(address)
    allowed = "local, or a Dask scheduler address [tcp|tls|ucx|ws|wss]://HOST:PORT, e.g. tcp://10.0.0.5:8786"
    if not m or (m.group("scheme") or "tcp") not in DASK_SCHEMES or not 0 < int(m.group("port")) < 65536:
        raise InvalidInput("--dask", address, allowed)
    return m.group("scheme") or "tcp", m.group("host").strip("[]"), int(m.group("port"))


def _reachable(address: str, host: str, port: int, timeout_s: float) -> None:
    """Fail at once when nothing listens at ``host:port`` (Dask itself retries until its timeout)."""
    try:
        with socket.create_connection((host, port), timeout=timeout_s):
            pass
    except OSError as exc:
        reason = exc.strerror or str(exc) or type(exc).__name__
        raise InvalidInput("--dask", address, f"the address of a running Dask scheduler (cannot connect to "
                                              f"{host}:{port}: {reason})") from None


def _connect(client_cls: Any, address: str, timeout_s: float) -> Any:
    """``Client(address)`` within ``timeout_s`` seconds, whatever answers there: Dask bounds its connect
    but not its handshake, so a port that accepts and stays silent would hang it; the attempt runs in a
    daemon thread and is abandoned at the deadline."""
    box: dict[str, Any] = {}

    def attempt() -> None:
        try:
            box["client"] = client_cls(address, timeout=f"{timeout_s}s")
        except BaseException as exc:  # refused, timed out, garbage handshake (e.g. a huge length prefix)
            box["error"] = exc

    thread = threading.Thread(target=attempt, name="dask-connect", daemon=True)
    thread.start()
    thread.join(timeout_s + 2)
    if "client" in box:
        return box["client"]
    exc = box.get("error")
    reason = (str(exc).splitlines()[0][:160] or type(exc).__name__) if exc is not None else "no handshake"
    raise InvalidInput("--dask", address, f"the address of a running Dask scheduler (no answer within "
                                          f"{timeout_s:g} s: {reason})")


class DaskExecutor:
    """Dask distributed: ``local`` starts a LocalCluster of ``workers`` single-threaded processes; anything
    else is a scheduler address (``tcp://host:8786``), e.g. a cluster started by dask-jobqueue on SLURM.

    A Dask scheduler runs whatever code a client sends it, so the local cluster listens on loopback with
    mutual TLS under a throw-away certificate held only by this process (``security=True``): another user
    of the machine cannot connect to it. A cluster given by address is secured by its own owner (Dask's
    ``distributed.comm.tls`` settings apply to the connection, e.g. ``--dask tls://host:8786``)."""

    def __init__(self, address: str, workers: int, timeout_s: float = DASK_CONNECT_TIMEOUT_S) -> None:
        where = check_dask_address(address)
        try:
            from distributed import Client, LocalCluster
        except ImportError:
            raise InvalidInput("--dask", address, "an installed Dask (pip install distributed)") from None

        self.cluster = None
        self.shares_cache = where is None
        if where is None:
            self.cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, host="127.0.0.1",
                                        dashboard_address=None, silence_logs=40, security=True)
            self.client = Client(self.cluster)
        else:
            _reachable(address, where[1], where[2], timeout_s)
            self.client = _connect(Client, address, timeout_s)
        self.name = f"dask:{address}"
        self.address = address
        self.window = max(2 * workers, 2 * len(self.client.scheduler_info().get("workers", {})) or 2)

    def describe(self) -> str:
        """How many workers, where (for the start-up message)."""
        workers = len(self.client.scheduler_info().get("workers", {}))
        where = "a local cluster" if self.cluster is not None else self.address
        return f"{workers} worker{'s' if workers != 1 else ''} on {where}"

    def run(self, tasks: Iterable[Task]) -> Iterator[dict[str, Any]]:
        from distributed import as_completed

        it = iter(tasks)
        first = [self.client.submit(execute, t, pure=False) for _, t in zip(range(self.window), it)]
        ac = as_completed(first, loop=self.client.loop)  # not the default client: another may be registered
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
