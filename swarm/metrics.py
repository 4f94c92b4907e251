"""Per-run measurements: a time series every ``record_every`` ticks and exact threshold-crossing ticks."""

from __future__ import annotations

from typing import Any

from .schema import THRESHOLDS, TIMESERIES_COLUMNS, threshold_key


class Metrics:
    """Collects the time series (columns of equal length) and the first tick each explored threshold is met.

    Thresholds are checked every tick, so ``ticks_to`` is exact even though rows are only stored every
    ``record_every`` ticks; the final tick is always stored.
    """

    def __init__(self, record_every: int, thresholds: tuple[float, ...] = THRESHOLDS) -> None:
        self.record_every = record_every
        self.thresholds = tuple(sorted(thresholds))
        self.ticks_to: dict[str, int | None] = {threshold_key(t): None for t in self.thresholds}
        self.series: dict[str, list[Any]] = {}
        self._last_recorded: int | None = None
        self._next_threshold = 0

    def check_thresholds(self, tick: int, explored: float) -> None:
        while self._next_threshold < len(self.thresholds) and explored >= self.thresholds[self._next_threshold]:
            self.ticks_to[threshold_key(self.thresholds[self._next_threshold])] = tick
            self._next_threshold += 1

    def due(self, tick: int) -> bool:
        return tick % self.record_every == 0

    def record(self, tick: int, **values: Any) -> None:
        """Append one row of the schema's columns (:data:`swarm.schema.TIMESERIES`), in its order."""
        if self._last_recorded == tick:
            return
        row = {"tick": tick, **values}
        if not self.series:
            if tuple(row) != TIMESERIES_COLUMNS:
                raise ValueError(f"time-series columns {list(row)}, the schema has {list(TIMESERIES_COLUMNS)}")
            self.series = {k: [] for k in row}
        elif set(row) != set(self.series):
            raise ValueError(f"time-series columns changed: {sorted(row)} vs {sorted(self.series)}")
        for k, v in row.items():
            self.series[k].append(v)
        self._last_recorded = tick
