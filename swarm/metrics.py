"""Per-run measurements: a time series every ``record_every`` ticks, exact threshold-crossing ticks, and the
communication metrics (docs/comm-metrics.md): what the radio carried and lost, who could hear whom, and
how old and how complete each robot's knowledge of the team is."""

from __future__ import annotations

from typing import Any

import numpy as np
from numba import njit

from .api import FREE
from .schema import COMM_ROBOT_SERIES, COMM_SERIES_COLUMNS, DROP_CAUSES, THRESHOLDS, TIMESERIES_COLUMNS, threshold_key


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


# ---------------------------------------------------------------------------- age of information ----
class InfoAges:
    """When each robot last merged each other robot's map, directly or through a third robot's map.

    ``merged_at[i, s]`` (s != i) is the latest tick at which robot s's map was merged into a map that robot
    i has merged since (its own included), 0 (the start) if none: a merge of s's map by i at tick t sets
    it to t, and the merge of robot j's whole map also raises every ``merged_at[i, x]`` to what
    ``merged_at[j, x]`` was when j sent it (j's map held x's map as of then). The age of i's information
    about s is ``tick - merged_at[i, s]``. Only merges that leave i holding the sender's whole map count
    (:class:`swarm.comm.MapSharing` says which: a full map, or the delta that follows the last one i
    merged); MAES's merges (:mod:`swarm.maes_merge`) give every member of a merge the union.
    """

    KEEP_TICKS = 64
    """Snapshots of updates older than this are forgotten (deliveries take a tick, relayed ones a few)."""

    def __init__(self, n: int) -> None:
        self.n = n
        self.merged_at = np.zeros((n, n), dtype=np.int64)
        self.merges = 0
        self._sent: dict[tuple[int, int], tuple[int, np.ndarray]] = {}  # (sender, seq) -> (tick, merged_at row)

    def sent(self, sender: int, seq: int, tick: int) -> None:
        """Robot ``sender`` broadcasts its map (update ``seq``) at ``tick``: note what its map holds of the
        others, for whoever merges it."""
        row = self.merged_at[sender].copy()
        self._sent[(sender, seq)] = (tick, row)
        if len(self._sent) > 4 * self.n * self.KEEP_TICKS:
            self._forget(tick)

    def merged(self, receivers: list[int], sender: int, seq: int, tick: int) -> None:
        """``receivers`` merged update ``seq`` of ``sender`` at ``tick`` and now hold its whole map as of
        when it was sent."""
        if not receivers:
            return
        rows = np.array(receivers, dtype=np.int64)
        sent = self._sent.get((sender, seq))
        if sent is not None:
            self.merged_at[rows] = np.maximum(self.merged_at[rows], sent[1])
        self.merged_at[rows, sender] = tick
        self.merges += len(receivers)

    def group(self, members: list[int], tick: int) -> None:
        """``members`` all got the union of their maps at ``tick`` (a MAES synchronisation)."""
        rows = np.array(members, dtype=np.int64)
        union = self.merged_at[rows].max(axis=0)
        self.merged_at[rows] = union
        self.merged_at[np.ix_(rows, rows)] = tick
        self.merges += len(members) * (len(members) - 1)

    def ages(self, tick: int) -> np.ndarray:
        """Per robot: the mean over the other robots of ``tick - merged_at[i, s]`` (0 for a lone robot)."""
        n = self.n
        if n < 2:
            return np.zeros(n)
        off = self.merged_at.sum(axis=1) - np.diagonal(self.merged_at)
        return tick - off / (n - 1)

    def _forget(self, tick: int) -> None:
        self._sent = {k: v for k, v in self._sent.items() if v[0] >= tick - self.KEEP_TICKS}


# -------------------------------------------------------------------------------- comm metrics ----
class CommMetrics:
    """The communication series of a run (:data:`swarm.schema.COMM_SERIES`), its per-robot series
    (:data:`swarm.schema.COMM_ROBOT_SERIES`) and summary (:class:`swarm.schema.CommSummary`), one row
    per row of the run's time series.

    The share of the team's known free cells a robot misses needs every robot's count of FREE cells: one
    compiled pass over the maps per recorded row (:func:`_free_counts`). The team's count is the tracker's
    seen free cells when only the ternary lidar writes maps (every FREE cell of a map was seen by some
    lidar and every seen free cell was written FREE into its robot's map), else the union is counted too.
    """

    def __init__(self, n: int, exact_union: bool) -> None:
        self.n = n
        self.exact_union = exact_union
        self.series: dict[str, list[Any]] = {c: [] for c in COMM_SERIES_COLUMNS}
        self.robots: dict[str, list[list[Any]]] = {c: [] for c in COMM_ROBOT_SERIES}
        self._counts = np.zeros(n, dtype=np.int64)
        self._union = np.zeros(0, dtype=np.uint8)
        self._groups: list[int] = []
        self._biggest: list[float] = []
        self._connected = 0

    def record(self, tick: int, stats: Any, known: np.ndarray, seen_free: int, groups: list[frozenset[int]],
               ages: InfoAges) -> None:
        """One row: ``stats`` is the medium's :class:`swarm.comm.CommStats`, ``known`` the maps
        (``uint8[R, H, W]``), ``seen_free`` the tracker's seen free cells, ``groups`` the tick's
        communication groups."""
        if self.series["tick"] and self.series["tick"][-1] == tick:
            return
        n = self.n
        missing = self._missing(known, seen_free)
        age = ages.ages(tick)
        contact = tick - np.maximum(np.array(stats.last_contact, dtype=np.int64), 0)
        group = np.zeros(n, dtype=np.int64)
        for k, members in enumerate(sorted(groups, key=min)):
            group[list(members)] = k
        s = self.series
        s["tick"].append(tick)
        for cause in DROP_CAUSES:
            s[f"msgs_{cause}"].append(int(getattr(stats, cause)))
        s["bytes_dropped"].append(int(stats.bytes_sent * (n - 1) - stats.bytes_delivered))
        s["map_merges"].append(ages.merges)
        s["since_contact_mean"].append(float(contact.mean()))
        s["since_contact_max"].append(int(contact.max()))
        s["missing_free_mean"].append(float(missing.mean()))
        s["missing_free_max"].append(float(missing.max()))
        s["aoi_age_mean"].append(float(age.mean()))
        s["aoi_age_max"].append(float(age.max()))
        r = self.robots
        r["missing_free"].append(missing.tolist())
        r["aoi_age"].append(age.tolist())
        r["since_contact"].append(contact.tolist())
        r["group"].append(group.tolist())
        self._groups.append(len(groups))
        self._biggest.append(max(len(g) for g in groups) / n)
        self._connected += len(groups) == 1

    def _missing(self, known: np.ndarray, seen_free: int) -> np.ndarray:
        """Per robot: the share of the free cells some robot's map holds that its own map does not."""
        if self.n < 2:
            return np.zeros(self.n)
        flat = known.reshape(self.n, -1)
        if self.exact_union:
            _free_counts(flat, self._counts)
            team = seen_free
        else:
            if self._union.shape[0] != flat.shape[1]:
                self._union = np.zeros(flat.shape[1], dtype=np.uint8)
            team = _free_counts_union(flat, self._counts, self._union)
        if team <= 0:
            return np.zeros(self.n)
        return np.clip(1.0 - self._counts / team, 0.0, 1.0)  # (an algorithm's own map update may add cells no lidar saw)

    def result(self) -> dict[str, Any]:
        """``RunResult.comm``: ``{"summary", "series", "robots"}``."""
        rows = len(self.series["tick"])
        s, r = self.series, self.robots

        def mean(values: list[Any]) -> float:
            return float(np.mean(values)) if values else 0.0

        per_robot = {f"{name}_mean": (np.mean(np.array(r[name], dtype=np.float64), axis=0).tolist() if rows
                                      else [0.0] * self.n) for name in ("missing_free", "aoi_age", "since_contact")}
        summary = {
            "rows": rows,
            "bytes_dropped": s["bytes_dropped"][-1] if rows else 0,
            "map_merges": s["map_merges"][-1] if rows else 0,
            "comm_groups_mean": mean(self._groups),
            "biggest_group_mean": mean(self._biggest),
            "all_connected_share": self._connected / rows if rows else 0.0,
            "since_contact_mean": mean(s["since_contact_mean"]),
            "since_contact_max": max(s["since_contact_max"], default=0),
            "missing_free_mean": mean(s["missing_free_mean"]),
            "missing_free_max": max(s["missing_free_max"], default=0.0),
            "aoi_age_mean": mean(s["aoi_age_mean"]),
            "aoi_age_max": max(s["aoi_age_max"], default=0.0),
            "per_robot": per_robot,
        }
        return {"summary": summary, "series": self.series, "robots": self.robots}


@njit(cache=True)
def _free_counts(known: np.ndarray, out: np.ndarray) -> None:  # pragma: no cover (compiled)
    """``out[i]`` = FREE cells of map i (``known``: uint8[R, cells], values 0..2, so FREE is bit 0)."""
    for i in range(known.shape[0]):
        row = known[i]
        c = 0
        for k in range(row.shape[0]):
            c += row[k] & 1
        out[i] = c


@njit(cache=True)
def _free_counts_union(known: np.ndarray, out: np.ndarray, union: np.ndarray) -> int:  # pragma: no cover
    """:func:`_free_counts`, and the number of cells FREE in some map (``union``: a uint8[cells] buffer)."""
    union[:] = 0
    for i in range(known.shape[0]):
        row = known[i]
        c = 0
        for k in range(row.shape[0]):
            f = row[k] & 1
            c += f
            union[k] |= f
        out[i] = c
    total = 0
    for k in range(union.shape[0]):
        total += union[k]
    return total


assert FREE == 1  # the kernels count bit 0: UNSEEN 0, FREE 1, SOLID 2
