"""Run a campaign into a results folder: skip what is done, execute the rest, commit parts as runs finish."""

from __future__ import annotations

import os
import time
from array import array
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

from swarm.base.errors import InvalidInput

from .executors import Executor, make_executor
from .spec import CampaignSpec, Run, parse_campaign
from swarm.results.schema import (COMM_ROBOT_SERIES, COMM_SERIES_COLUMNS, NONDETERMINISTIC_COLUMNS, TIMESERIES_COLUMNS,
                      comm_columns, summary_columns)
from swarm.util.source import version_label
from .store import QUARANTINE, ResultsStore
from .writers import Writer, live_writers


@dataclass
class Outcome:
    total: int
    skipped: int
    ran: int
    failed: int
    wall_s: float
    warmup_runs: int = 0
    """Runs executed in this process first, so numba compiled its kernels once (:mod:`.warmup`)."""
    warmup_s: float = 0.0
    compile_s: float = 0.0
    """Time the warm-up runs spent in numba's compiler (compiling or loading kernels)."""
    startup_s: float = 0.0
    """Time to start the executor (a Dask cluster; a process pool starts its workers lazily)."""
    executor_started: float | None = None
    """When the executor was started (``time.monotonic()``; None if every run was a warm-up run)."""

    def timing(self) -> str:
        """Where the time went, e.g. ``kernels compiled in 64 s, in 3 warm-up runs, executor started in 4 s``."""
        parts = []
        if self.warmup_runs and self.compile_s >= 1:
            parts.append(f"kernels compiled in {self.compile_s:.0f} s, in {self.warmup_runs} warm-up runs")
        if self.startup_s >= 1:
            parts.append(f"executor started in {self.startup_s:.0f} s")
        return ", ".join(parts)


SLURM_ARRAY = ("SLURM_ARRAY_TASK_ID", "SLURM_ARRAY_TASK_MIN", "SLURM_ARRAY_TASK_MAX", "SLURM_ARRAY_TASK_COUNT")


def parse_shard(text: str | None, env: Mapping[str, str] | None = None) -> tuple[int, int] | None:
    """``i/N`` (0 <= i < N: every N-th run from the i-th), or ``slurm``: this task's shard of a SLURM job
    array (:func:`slurm_shard`). None: every run."""
    if text is None:
        return None
    if text.strip().lower() == "slurm":
        return slurm_shard(os.environ if env is None else env)
    try:
        i, n = (int(v) for v in text.split("/"))
    except ValueError:
        raise InvalidInput("--shard", text, "i/N with 0 <= i < N, e.g. 3/10, or slurm (in a SLURM job array)") from None
    if not (n >= 1 and 0 <= i < n):
        raise InvalidInput("--shard", text, "i/N with 0 <= i < N, e.g. 3/10, or slurm (in a SLURM job array)")
    return i, n


def slurm_shard(env: Mapping[str, str]) -> tuple[int, int]:
    """``(i, N)`` of this task of a SLURM job array: N tasks, i counted from 0 whatever the array's first
    index and step, so ``--array=1-8``, ``--array=0-7`` and ``--array=0-14:2`` all make shards 0..7 of 8.
    An array whose indices are not evenly spaced (``--array=1,2,7``) is refused."""
    try:
        task, lo, hi, count = (int(env[name]) for name in SLURM_ARRAY)
    except KeyError as exc:
        raise InvalidInput("--shard", "slurm", f"a task of a SLURM job array ({exc.args[0]} is not set; "
                                               "submit with sbatch --array=1-N)") from None
    except ValueError:
        raise InvalidInput("--shard", "slurm", "a task of a SLURM job array (its SLURM_ARRAY_TASK_* variables "
                                               "are not integers)") from None
    step = (hi - lo) // (count - 1) if count > 1 else 1
    i, rest = divmod(task - lo, step) if step > 0 else (-1, 0)
    if count < 1 or rest or not 0 <= i < count or lo + step * (count - 1) != hi:
        raise InvalidInput("--shard", f"slurm (task {task} of {lo}-{hi}, {count} tasks)",
                           "a job array of evenly spaced indices, e.g. --array=1-8 or --array=0-14:2")
    return i, count


def select(runs: list[Run], shard: tuple[int, int] | None) -> list[Run]:
    if shard is None:
        return runs
    i, n = shard
    return [r for r in runs if r.index % n == i]


def runs_row(campaign: CampaignSpec, run: Run, result: dict[str, Any]) -> dict[str, Any]:
    spec = run.spec
    row: dict[str, Any] = {
        "key": run.key, "campaign": campaign.name, "index": run.index, "replicate": run.replicate,
        "map": run.cell["map"], "size": run.cell["size"], "robots": spec.robots.count, "spawn": spec.robots.spawn,
        "algorithm": run.cell["algorithm"], "radio": run.cell["radio"], "comm": run.cell.get("comm", "default"),
        "transport": spec.transport, "map_kind": spec.map.kind, "algorithm_name": spec.algorithm.name,
        "radio_model": spec.radio.model, **run.seeds, "status": result["status"], "error": result["error"],
        "explored_target": spec.stop.explored, "max_ticks": spec.stop.max_ticks,
        **{axis: run.cell[axis] for axis in campaign.axes},
    }
    row.update(summary_columns(result["summary"]))
    row.update(comm_columns(result["summary"], result.get("comm")))
    dist = result.get("algorithm_dist") or (None, None)
    row.update(spec_json=spec.to_json(), wall_time_s=result["wall_time_s"], cpu_time_s=result.get("cpu_time_s"),
               jit_time_s=result.get("jit_time_s"), worker_pid=result["worker_pid"],
               worker_rss_mb=result["worker_rss_mb"], swarm_version=version_label(), algorithm_dist=dist[0],
               algorithm_version=dist[1])
    return row


def timeseries_rows(key: str, ts: dict[str, list[Any]] | None,
                    comm: dict[str, Any] | None = None) -> list[dict[str, Any]]:
    """The run's time-series rows, with its communication series (same ticks) as further columns."""
    if not ts:
        return []
    cols = [c for c in TIMESERIES_COLUMNS if c in ts]
    rows = [{"key": key, **dict(zip(cols, values))} for values in zip(*(ts[c] for c in cols))]
    series = (comm or {}).get("series")
    if series and series["tick"] == ts["tick"]:
        extra = [c for c in COMM_SERIES_COLUMNS if c != "tick" and c in series]
        for row, values in zip(rows, zip(*(series[c] for c in extra))):
            row.update(zip(extra, values))
    return rows


def robot_rows(key: str, comm: dict[str, Any] | None, every: int) -> list[dict[str, Any]]:
    """The long per-robot table of a run (key, tick, robot, :data:`swarm.results.schema.COMM_ROBOT_SERIES`): rows at
    ticks that are multiples of ``every`` and the run's last row; none when ``every`` is 0."""
    if not comm or not every or "robots" not in comm:
        return []
    ticks, robots = comm["series"]["tick"], comm["robots"]
    names = [c for c in COMM_ROBOT_SERIES if c in robots]
    out = []
    for k, tick in enumerate(ticks):
        if tick % every and k != len(ticks) - 1:
            continue
        columns = [robots[c][k] for c in names]
        for robot, values in enumerate(zip(*columns)):
            out.append({"key": key, "tick": tick, "robot": robot, **dict(zip(names, values))})
    return out


class Progress:
    """Campaign progress on stderr: a tqdm bar with a smoothed ETA on a terminal, else a plain line every
    ``every_s`` seconds (:class:`swarm.util.progress.Bar`). ``initial``: runs done before it started (the
    warm-up runs), counted but not in the rate, so compile time does not inflate the ETA."""

    def __init__(self, total: int, stream: Any = None, every_s: float = 30.0, initial: int = 0) -> None:
        from swarm.util.progress import Bar

        self.total = total
        self.failed = 0
        self.bar = Bar(total, "runs", unit="run", stream=stream, every_s=every_s, initial=initial, live=True)

    @property
    def done(self) -> int:
        return self.bar.n

    def update(self, ok: bool) -> None:
        self.failed += 0 if ok else 1
        self.bar.update(1, failed=self.failed)

    def close(self) -> None:
        self.bar.close()


ExecutorArg = Executor | Callable[[], Executor] | None


def run_campaign(spec: CampaignSpec, folder: str | Path, executor: ExecutorArg = None,
                 shard: tuple[int, int] | None = None, retry_failed: bool = False, progress: bool = True,
                 flush_runs: int = 20, flush_seconds: float = 30.0,
                 on_result: Callable[[dict[str, Any]], None] | None = None,
                 log: Callable[[str], None] | None = None, warmup: bool | None = None,
                 indices: Iterable[int] | None = None) -> Outcome:
    """Execute the runs of ``spec`` not yet in ``folder`` (and failed ones if ``retry_failed``).

    ``executor``: an executor, a function making one (called only once the folder is registered and
    checked writable, and only if there is anything to run), or None for the default process pool. This
    process registers as a writer of ``folder`` first (:mod:`.writers`): a live writer of overlapping runs is
    an :class:`InvalidInput`. A part that cannot be written stops the campaign with :class:`CommitError`.

    ``warmup``: first execute a few runs in this process so numba compiles its kernels once, before the
    workers start (:mod:`.warmup`); None: unless ``executor`` is one whose workers do not share this
    machine's numba cache (a remote Dask cluster). ``indices``: only these runs (e.g. the sample of
    :mod:`.estimate`), within ``shard``.
    """
    t0 = time.monotonic()
    store = ResultsStore(folder)
    total = spec.run_count()
    selected = spec.indices(shard)
    wanted = None if indices is None else {int(i) for i in indices}
    if wanted is not None:
        selected = [i for i in selected if i in wanted]
    if warmup is None:
        warmup = getattr(executor, "shares_cache", True)
    with Writer(store, spec.source, shard=shard, retry_failed=retry_failed, total=total) as writer:
        damaged = store.damaged()
        if damaged:  # never merged: moved aside, and their runs are run again (docs/campaigns.md)
            moved = store.quarantine(damaged)
            if log:
                for check in damaged[:10]:
                    log(f"damaged part moved to {QUARANTINE}/, its runs will run again: {check.describe()}")
                if len(moved) > 10:
                    log(f"... and {len(moved) - 10} more damaged parts moved to {QUARANTINE}/")
        done = store.done_keys()
        todo = array("q", (i for i, key in spec.iter_keys(shard)
                           if (wanted is None or i in wanted)
                           and done.get(key) != "ok" and (retry_failed or done.get(key) != "failed")))
        outcome = Outcome(total=len(selected), skipped=len(selected) - len(todo), ran=len(todo), failed=0, wall_s=0.0)
        if log:
            log(f"{len(todo)} to run, {outcome.skipped} already done")
        if todo:
            _execute(spec, store, writer.id, todo, executor, progress, flush_runs, flush_seconds, on_result, log,
                     warmup, outcome)
    outcome.wall_s = time.monotonic() - t0
    return outcome


def _execute(spec: CampaignSpec, store: ResultsStore, writer: str, todo: array, executor: ExecutorArg,
             progress: bool, flush_runs: int, flush_seconds: float,
             on_result: Callable[[dict[str, Any]], None] | None, log: Callable[[str], None] | None,
             warmup: bool, outcome: Outcome) -> None:
    """Run ``todo`` (run indices), the warm-up runs first in this process, and commit their rows part by
    part; fills ``outcome`` (failed runs, compile and start-up times)."""
    from . import warmup as warm

    plan = warm.plan(spec, todo) if warmup else None
    first = plan.indices if plan is not None else []
    chosen = set(first)
    rest = array("q", (i for i in todo if i not in chosen))
    rows: list[dict[str, Any]] = []
    ts_rows: list[dict[str, Any]] = []
    per_robot: list[dict[str, Any]] = []
    last_flush = time.monotonic()
    in_flight: dict[str, Run] = {}
    bar: Progress | None = None

    def tasks(indices: Iterable[int]) -> Iterator[tuple[str, dict[str, Any]]]:
        for index in indices:
            run = spec.run_at(index)
            in_flight[run.key] = run
            yield run.key, run.canonical()

    def flush() -> None:
        nonlocal rows, ts_rows, per_robot, last_flush
        batch, ts_batch, robot_batch = rows, ts_rows, per_robot
        rows, ts_rows, per_robot, last_flush = [], [], [], time.monotonic()  # cleared first: no retry
        if batch:
            store.write_part(batch, ts_batch, writer=writer, robots=robot_batch)

    def take(result: dict[str, Any]) -> None:
        run = in_flight.pop(result["key"])
        rows.append(runs_row(spec, run, result))
        ts_rows.extend(timeseries_rows(run.key, result["timeseries"], result.get("comm")))
        per_robot.extend(robot_rows(run.key, result.get("comm"), spec.robot_series_every))
        outcome.failed += result["status"] != "ok"
        if bar:
            bar.update(result["status"] == "ok")
        if on_result:
            on_result(result)
        if len(rows) >= flush_runs or time.monotonic() - last_flush >= flush_seconds:
            flush()

    try:
        if first:
            _warm_up(spec, first, tasks, take, progress, log, outcome)
            warm.record(warm.stamp_path(), plan.needed)
        if rest:
            t_start = outcome.executor_started = time.monotonic()
            own = executor is None or not hasattr(executor, "run")
            runner: Executor = make_executor() if executor is None else executor() if own else executor  # type: ignore[operator]
            outcome.startup_s = time.monotonic() - t_start
            try:
                if log:
                    log(f"running on {runner.name}" + (f" (started in {outcome.startup_s:.1f} s)"
                                                       if outcome.startup_s >= 0.5 else ""))
                bar = Progress(len(todo), initial=len(first)) if progress else None
                for result in runner.run(tasks(rest)):
                    take(result)
            except BaseException:  # Ctrl-C, SIGTERM (swarm.cli turns it into SystemExit), a failed write
                if own and hasattr(runner, "abort"):
                    runner.abort()  # do not wait minutes for the runs in flight: a resume runs them again
                    own = False
                raise
            finally:
                if bar:
                    bar.close()
                if own:
                    runner.close()
    finally:
        flush()  # also on Ctrl-C: what finished is kept


def _warm_up(spec: CampaignSpec, indices: list[int], tasks: Callable[[Iterable[int]], Iterator[Any]],
             take: Callable[[dict[str, Any]], None], progress: bool, log: Callable[[str], None] | None,
             outcome: Outcome) -> None:
    """Execute the warm-up runs here, showing numba compiling (see :mod:`.warmup`)."""
    from swarm.util.jit import JitWatch
    from swarm.util.progress import CompileProgress
    from .executors import execute

    n = len(indices)
    if log:
        log(f"{n} warm-up run{'s' if n > 1 else ''} in this process first, so that numba compiles the kernels "
            "this campaign needs once, before the workers start")
    text = ("compiling numba kernels (after an install or an update: about a minute on one core; then cached "
            "for every worker and later campaigns)")
    display = CompileProgress(note_text=text, desc=f"warm-up run 1/{n}") if progress else None
    watch = display.watch if display is not None else JitWatch()
    t0, c0 = time.monotonic(), time.process_time()
    with display if display is not None else watch:
        for k, task in enumerate(tasks(indices)):
            if display is not None:
                display.step(f"warm-up run {k + 1}/{n}")
            take(execute(task))
    outcome.warmup_runs, outcome.compile_s, outcome.warmup_s = n, watch.seconds, time.monotonic() - t0
    if log and watch.compiled:
        log(f"kernels ready: {watch.compiled} functions compiled in {watch.compile_seconds:.0f} s "
            f"({n} warm-up run{'s' if n > 1 else ''}: {outcome.warmup_s:.0f} s, {time.process_time() - c0:.0f} s "
            "of CPU; kept as campaign runs)")


def status(folder: str | Path) -> dict[str, Any]:
    """done / failed / pending counts of a results folder against its spec, and its live writers."""
    store = ResultsStore(folder)
    spec = parse_campaign(store.spec_source(), str(Path(folder) / "campaign.toml"), max_runs=None)
    damaged = store.damaged()
    done = store.done_keys()
    ok = failed = total = 0
    for _, key in spec.iter_keys():
        total += 1
        st = done.get(key)
        ok += st == "ok"
        failed += st == "failed"
    errors: dict[str, int] = {}
    table = store.runs_table(columns=("key", "status", "error")) if failed else None
    if table is not None:
        for st, err in zip(table.column("status").to_pylist(), table.column("error").to_pylist()):
            if st == "failed":
                errors[err] = errors.get(err, 0) + 1
    return {"campaign": spec.name, "total": total, "done": ok, "failed": failed,
            "pending": total - ok - failed, "errors": errors, "parts": len(store.run_files()),
            "damaged": [c.describe() for c in damaged], "writers": live_writers(folder)}


def deterministic_rows(folder: str | Path) -> list[dict[str, Any]]:
    """Runs rows without the fields that legitimately differ between executions (for comparisons)."""
    table = ResultsStore(folder).runs_table()
    if table is None:
        return []
    rows = [{k: v for k, v in row.items() if k not in NONDETERMINISTIC_COLUMNS} for row in table.to_pylist()]
    return sorted(rows, key=lambda r: r["key"])


__all__ = ["Outcome", "Progress", "deterministic_rows", "parse_shard", "run_campaign", "status"]
