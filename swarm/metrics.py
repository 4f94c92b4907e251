"""Per-run measurements: a time series every ``record_every`` ticks and exact threshold-crossing ticks."""

from __future__ import annotations

from typing import Any

THRESHOLDS: tuple[float, ...] = (0.5, 0.75, 0.9, 0.95, 0.98, 0.99)


class Metrics:
    """Collects the time series (columns of equal length) and the first tick each explored threshold is met.

    Thresholds are checked every tick, so ``ticks_to`` is exact even though rows are only stored every
    ``record_every`` ticks; the final tick is always stored.
    """

    def __init__(self, record_every: int, thresholds: tuple[float, ...] = THRESHOLDS) -> None:
        self.record_every = record_every
        self.thresholds = tuple(sorted(thresholds))
        self.ticks_to: dict[str, int | None] = {_key(t): None for t in self.thresholds}
        self.series: dict[str, list[Any]] = {}
        self._last_recorded: int | None = None
        self._next_threshold = 0

    def check_thresholds(self, tick: int, explored: float) -> None:
        while self._next_threshold < len(self.thresholds) and explored >= self.thresholds[self._next_threshold]:
            self.ticks_to[_key(self.thresholds[self._next_threshold])] = tick
            self._next_threshold += 1

    def due(self, tick: int) -> bool:
        return tick % self.record_every == 0

    def record(self, tick: int, **values: Any) -> None:
        """Append one row; the first call fixes the columns."""
        if self._last_recorded == tick:
            return
        row = {"tick": tick, **values}
        if not self.series:
            self.series = {k: [] for k in row}
        elif set(row) != set(self.series):
            raise ValueError(f"time-series columns changed: {sorted(row)} vs {sorted(self.series)}")
        for k, v in row.items():
            self.series[k].append(v)
        self._last_recorded = tick


def _key(threshold: float) -> str:
    return f"{threshold:g}"
