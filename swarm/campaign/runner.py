"""Run a campaign into a results folder: skip what is done, execute the rest, commit parts as runs finish."""

from __future__ import annotations

import sys
import time
from array import array
from collections.abc import Iterator
from dataclasses import dataclass
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path
from typing import Any, Callable

from maps.errors import InvalidInput

from .executors import Executor, make_executor
from .spec import CampaignSpec, Run, parse_campaign
from ..schema import (COMM_ROBOT_SERIES, COMM_SERIES_COLUMNS, NONDETERMINISTIC_COLUMNS, TIMESERIES_COLUMNS,
                      comm_columns, summary_columns)
from .store import ResultsStore
from .writers import Writer, live_writers




def swarm_version() -> str:
    try:
        return version("swarm-sim")
    except PackageNotFoundError:  # running from a source tree without installing
        return "unknown"


@dataclass
class Outcome:
    total: int
    skipped: int
    ran: int
    failed: int
    wall_s: float


def parse_shard(text: str | None) -> tuple[int, int] | None:
    if text is None:
        return None
    try:
        i, n = (int(v) for v in text.split("/"))
    except ValueError:
        raise InvalidInput("--shard", text, "i/N with 0 <= i < N, e.g. 3/10") from None
    if not (n >= 1 and 0 <= i < n):
        raise InvalidInput("--shard", text, "i/N with 0 <= i < N, e.g. 3/10")
    return i, n


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
    row.update(spec_json=spec.to_json(), wall_time_s=result["wall_time_s"], worker_pid=result["worker_pid"],
               worker_rss_mb=result["worker_rss_mb"], swarm_version=swarm_version(), algorithm_dist=dist[0],
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
    """The long per-robot table of a run (key, tick, robot, :data:`swarm.schema.COMM_ROBOT_SERIES`): rows at
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
    """A one-line bar on a terminal, a plain line every ``every_s`` seconds otherwise."""

    def __init__(self, total: int, stream: Any = None, every_s: float = 30.0) -> None:
        self.total = total
        self.stream = stream or sys.stderr
        self.tty = bool(getattr(self.stream, "isatty", lambda: False)())
        self.every_s = every_s
        self.t0 = time.monotonic()
        self.last = 0.0
        self.done = 0
        self.failed = 0

    def update(self, ok: bool) -> None:
        self.done += 1
        self.failed += 0 if ok else 1
        now = time.monotonic()
        if self.tty or now - self.last >= self.every_s or self.done == self.total:
            self.last = now
            self._print(now)

    def _print(self, now: float) -> None:
        elapsed = max(now - self.t0, 1e-9)
        rate = self.done / elapsed * 60
        left = (self.total - self.done) / (self.done / elapsed) if self.done else float("nan")
        eta = time.strftime("%H:%M:%S", time.gmtime(left)) if left == left else "?"
        width = 30
        filled = int(width * self.done / max(self.total, 1))
        bar = "#" * filled + "." * (width - filled)
        text = (f"[{bar}] {self.done}/{self.total} runs, {self.failed} failed, {rate:.1f} runs/min, ETA {eta}"
                if self.tty else
                f"{self.done}/{self.total} runs done, {self.failed} failed, {rate:.1f} runs/min, ETA {eta}")
        if self.tty:
            self.stream.write("\r" + text + ("\n" if self.done == self.total else ""))
        else:
            self.stream.write(text + "\n")
        self.stream.flush()


ExecutorArg = Executor | Callable[[], Executor] | None


def run_campaign(spec: CampaignSpec, folder: str | Path, executor: ExecutorArg = None,
                 shard: tuple[int, int] | None = None, retry_failed: bool = False, progress: bool = True,
                 flush_runs: int = 20, flush_seconds: float = 30.0,
                 on_result: Callable[[dict[str, Any]], None] | None = None,
                 log: Callable[[str], None] | None = None) -> Outcome:
    """Execute the runs of ``spec`` not yet in ``folder`` (and failed ones if ``retry_failed``).

    ``executor``: an executor, a function making one (called only once the folder is registered and
    checked writable, and only if there is anything to run), or None for the default process pool. This
    process registers as a writer of ``folder`` first (:mod:`.writers`): a live writer of overlapping runs is
    an :class:`InvalidInput`. A part that cannot be written stops the campaign with :class:`CommitError`.
    """
    t0 = time.monotonic()
    store = ResultsStore(folder)
    total = spec.run_count()
    selected = spec.indices(shard)
    with Writer(store, spec.source, shard=shard, retry_failed=retry_failed, total=total) as writer:
        done = store.done_keys()
        todo = array("q", (i for i, key in spec.iter_keys(shard)
                           if done.get(key) != "ok" and (retry_failed or done.get(key) != "failed")))
        outcome = Outcome(total=len(selected), skipped=len(selected) - len(todo), ran=len(todo), failed=0, wall_s=0.0)
        if log:
            log(f"{len(todo)} to run, {outcome.skipped} already done")
        if todo:
            outcome.failed = _execute(spec, store, writer.id, todo, executor, progress, flush_runs, flush_seconds,
                                      on_result, log)
    outcome.wall_s = time.monotonic() - t0
    return outcome


def _execute(spec: CampaignSpec, store: ResultsStore, writer: str, todo: array, executor: ExecutorArg,
             progress: bool, flush_runs: int, flush_seconds: float,
             on_result: Callable[[dict[str, Any]], None] | None, log: Callable[[str], None] | None) -> int:
    """Run ``todo`` (run indices) and commit their rows part by part; returns how many failed."""
    own = executor is None or not hasattr(executor, "run")
    if executor is None:
        runner: Executor = make_executor()
    elif own:
        runner = executor()  # type: ignore[operator]
    else:
        runner = executor  # type: ignore[assignment]
    if log:
        log(f"running on {runner.name}")
    bar = Progress(len(todo)) if progress else None
    rows: list[dict[str, Any]] = []
    ts_rows: list[dict[str, Any]] = []
    per_robot: list[dict[str, Any]] = []
    last_flush = time.monotonic()
    failed = 0
    in_flight: dict[str, Run] = {}

    def tasks() -> Iterator[tuple[str, dict[str, Any]]]:
        for index in todo:
            run = spec.run_at(index)
            in_flight[run.key] = run
            yield run.key, run.canonical()

    def flush() -> None:
        nonlocal rows, ts_rows, per_robot, last_flush
        batch, ts_batch, robot_batch = rows, ts_rows, per_robot
        rows, ts_rows, per_robot, last_flush = [], [], [], time.monotonic()  # cleared first: no retry
        if batch:
            store.write_part(batch, ts_batch, writer=writer, robots=robot_batch)

    try:
        try:
            for result in runner.run(tasks()):
                run = in_flight.pop(result["key"])
                rows.append(runs_row(spec, run, result))
                ts_rows.extend(timeseries_rows(run.key, result["timeseries"], result.get("comm")))
                per_robot.extend(robot_rows(run.key, result.get("comm"), spec.robot_series_every))
                failed += result["status"] != "ok"
                if bar:
                    bar.update(result["status"] == "ok")
                if on_result:
                    on_result(result)
                if len(rows) >= flush_runs or time.monotonic() - last_flush >= flush_seconds:
                    flush()
        finally:
            flush()  # also on Ctrl-C: what finished is kept
    finally:
        if own:
            runner.close()
    return failed


def status(folder: str | Path) -> dict[str, Any]:
    """done / failed / pending counts of a results folder against its spec, and its live writers."""
    store = ResultsStore(folder)
    spec = parse_campaign(store.spec_source(), str(Path(folder) / "campaign.toml"), max_runs=None)
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
            "writers": live_writers(folder)}


def deterministic_rows(folder: str | Path) -> list[dict[str, Any]]:
    """Runs rows without the fields that legitimately differ between executions (for comparisons)."""
    table = ResultsStore(folder).runs_table()
    if table is None:
        return []
    rows = [{k: v for k, v in row.items() if k not in NONDETERMINISTIC_COLUMNS} for row in table.to_pylist()]
    return sorted(rows, key=lambda r: r["key"])


__all__ = ["Outcome", "Progress", "deterministic_rows", "parse_shard", "run_campaign", "status"]
