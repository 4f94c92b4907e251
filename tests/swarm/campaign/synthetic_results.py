"""Hand-made campaign results with known numbers, written through the real row builders and store.

A test describes each run by its grid labels, replicate and outcome; the keys, seeds and columns come from
:func:`swarm.campaign.runner.runs_row` and :meth:`ResultsStore.write_part`, so the report reads exactly
what a real campaign writes.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from swarm.campaign import ResultsStore, parse_campaign
from swarm.campaign.runner import runs_row, timeseries_rows

SPEC = """
[campaign]
name = "synthetic"
seed = 5
replicates = {replicates}

[grid]
map = ["building"]
size = [20]
robots = [2]
spawn = ["together"]
algorithm = ["greed", "frontier"]
radio = ["global", "los"]

[stop]
explored = 0.98
max_ticks = 1000
"""


@dataclass
class FakeRun:
    """One run's outcome. ``series`` is [(tick, explored)]; ``t98`` None means the target was not reached."""

    algorithm: str
    radio: str
    replicate: int
    t98: int | None
    series: Sequence[tuple[int, float]] = ()
    stop_reason: str = "explored"
    failed: str = ""
    extra: dict[str, Any] = field(default_factory=dict)
    version: str | None = None
    """The row's ``swarm_version`` (the running code's when None)."""
    cell: dict[str, str] = field(default_factory=dict)
    """Labels of the other grid dimensions (``{"robots": "4"}``) when the spec has several values of them."""


def series_to(t98: int | None, end: int, every: int = 10) -> list[tuple[int, float]]:
    """A linear explored series reaching 0.98 at ``t98`` (or 0.9 at ``end``), rows every ``every`` ticks and
    at the final tick, as the simulator records them."""
    stop = t98 if t98 is not None else end
    ticks = list(range(0, stop + 1, every))
    if ticks[-1] != stop:
        ticks.append(stop)
    top = 0.98 if t98 is not None else 0.9
    return [(t, round(top * t / stop, 6) if stop else top) for t in ticks]


def write(folder: Path, runs: Sequence[FakeRun], replicates: int = 6, spec_text: str | None = None) -> Path:
    spec = parse_campaign(spec_text or SPEC.format(replicates=replicates))
    by_cell = {(frozenset(r.cell.items()), r.replicate): r for r in spec.runs()}
    defaults = {dim: opts[0].label for dim, opts in spec.grid.items()}
    store = ResultsStore(folder)
    store.open_for(spec.source)
    rows, ts_rows = [], []
    for fake in runs:
        labels = {**defaults, **fake.cell, "algorithm": fake.algorithm, "radio": fake.radio}
        run = by_cell[(frozenset(labels.items()), fake.replicate)]
        result = _result(fake, int(spec.stop.get("max_ticks", 1000)))
        rows.append(runs_row(spec, run, result))
        if fake.version is not None:
            rows[-1]["swarm_version"] = fake.version
        ts_rows.extend(timeseries_rows(run.key, result["timeseries"]))
    store.write_part(rows, ts_rows)
    return folder


def _result(fake: FakeRun, max_ticks: int) -> dict[str, Any]:
    base = {"wall_time_s": 0.1, "worker_pid": 1, "worker_rss_mb": 1.0, "events": []}
    if fake.failed:
        return {**base, "status": "failed", "error": fake.failed, "summary": None, "timeseries": None}
    series = list(fake.series) or series_to(fake.t98, max_ticks)
    ticks = [t for t, _ in series]
    explored = [e for _, e in series]
    n = len(series)
    summary = {"ticks": ticks[-1], "stop_reason": fake.stop_reason, "explored": explored[-1],
               "coverage": explored[-1] / 3,
               "ticks_to": {"0.5": None, "0.75": None, "0.9": None, "0.95": None, "0.98": fake.t98, "0.99": None},
               "distance_m": [1.0, 2.0], "collisions": 0,
               "messages": {"sent": 0, "bytes_sent": 0, "delivered": 0, "bytes_delivered": 0, "dropped_link": 0,
                            "dropped_loss": 0, "dropped_bandwidth": 0},
               "failed_robots": [], **fake.extra}
    timeseries = {"tick": ticks, "explored": explored, "coverage": [e / 3 for e in explored],
                  "distance_m": [0.0] * n, "collisions": [0] * n, "msgs_sent": [0] * n, "bytes_sent": [0] * n,
                  "msgs_delivered": [0] * n, "bytes_delivered": [0] * n, "msgs_dropped": [0] * n,
                  "comm_groups": [1 if t % 20 == 0 else 2 for t in ticks],
                  "biggest_group": [1.0 if t % 20 == 0 else 0.5 for t in ticks],
                  "all_connected": [t % 20 == 0 for t in ticks]}
    return {**base, "status": "ok", "error": "", "summary": summary, "timeseries": timeseries}
