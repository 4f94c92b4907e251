"""The result of one run, in the shape docs/design.md section 5 gives (also what ``swarm run --json`` writes)."""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from .schema import Summary

NONDETERMINISTIC_SUFFIX = "_time_s"
"""Fields ending like this (wall-clock times) are the only ones allowed to differ between identical runs."""


@dataclass
class RunResult:
    spec: dict[str, Any]
    key: str
    summary: Summary  # swarm.results.schema: what a run computed
    timeseries: dict[str, list[Any]]
    events: list[dict[str, Any]] = field(default_factory=list)
    provenance: dict[str, Any] = field(default_factory=dict)
    """What computed it: ``{"swarm": version, "algorithm": {"name", "distribution", "version"}}`` (the
    plugin's installed distribution; None for one loaded from a path outside any)."""
    comm: dict[str, Any] = field(default_factory=dict)
    """Communication metrics (docs/comm-metrics.md): ``{"summary": CommSummary, "series": {column: [...]},
    "robots": {name: [[per robot] per row]}}``, rows at the time series' ticks. Kept apart from ``summary``
    and ``timeseries`` so those stay what they were (benchmarks/result_digests.py hashes them)."""

    def __repr__(self) -> str:
        """One short line: the key, the summary and how much the result holds (the default repr printed the
        whole time series, 83 KB for 2,000 ticks). Never raises, whatever a hand-built result holds."""
        try:
            rows = len(next(iter(self.timeseries.values()), ()))
            what = f"{self.one_line()}; {rows} time-series rows, {len(self.events)} events"
        except (KeyError, TypeError, ValueError, AttributeError, IndexError):  # a hand-built, partial result
            what = "incomplete"
        return f"RunResult(key={self.key!r}, {what})"

    def to_dict(self) -> dict[str, Any]:
        return {"key": self.key, "spec": self.spec, "summary": self.summary, "timeseries": self.timeseries,
                "events": self.events, "provenance": self.provenance, "comm": self.comm}

    def to_json(self, indent: int | None = None) -> str:
        return json.dumps(self.to_dict(), indent=indent, sort_keys=True)

    def write_json(self, path: str | Path) -> Path:
        from maps.io import atomic_write_bytes

        return atomic_write_bytes(Path(path), self.to_json(indent=1).encode())

    def deterministic_view(self) -> dict[str, Any]:
        """Everything except wall-clock fields and the source commit (which depends on where the code runs
        from, not on the run): equal for two runs of the same spec."""
        view = _strip_times(self.to_dict())
        view["provenance"] = {k: v for k, v in view["provenance"].items() if k != "source"}
        return view

    def one_line(self) -> str:
        s = self.summary
        t99 = s["ticks_to"].get("0.99")
        done = f"99% at tick {t99}" if t99 is not None else f"{100 * s['explored']:.1f}% explored"
        return (f"{self.spec['algorithm']['name']} x{self.spec['robots']['count']} on {self.spec['map']['kind']} "
                f"{self.spec['map'].get('size', '')}: {done}, stopped at tick {s['ticks']} ({s['stop_reason']}), "
                f"coverage {100 * s['coverage']:.1f}%, {sum(s['distance_m']):.0f} m driven, "
                f"{s['collisions']} collisions, {s['ticks'] / max(s['wall_time_s'], 1e-9):.0f} ticks/s")


def _strip_times(obj: Any) -> Any:
    if isinstance(obj, dict):
        return {k: _strip_times(v) for k, v in obj.items() if not str(k).endswith(NONDETERMINISTIC_SUFFIX)}
    if isinstance(obj, list):
        return [_strip_times(v) for v in obj]
    return obj
