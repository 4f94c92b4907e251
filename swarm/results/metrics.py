"""Per-run measurements: a time series every ``record_every`` ticks, exact threshold-crossing ticks, and the
communication metrics (docs/comm-metrics.md): what the radio carried and lost, who could hear whom, and
how old and how complete each robot's knowledge of the team is."""

from __future__ import annotations

from typing import Any

import numpy as np
from numba import njit

from swarm.base.types import FREE
from swarm.util.memory import lazy_zeros
from .schema import (COMM_ROBOT_SERIES, COMM_SERIES_COLUMNS, DROP_CAUSES, OPTIONAL_TIMESERIES, THRESHOLDS,
                     TIMESERIES_COLUMNS, threshold_key)


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
        """Append one row of the schema's columns (:data:`swarm.results.schema.TIMESERIES`), in its order; the
        optional columns (:data:`~swarm.results.schema.OPTIONAL_TIMESERIES`) in every row or in none."""
        if self._last_recorded == tick:
            return
        row = {"tick": tick, **values}
        if not self.series:
            want = tuple(c for c in TIMESERIES_COLUMNS if c in row or c not in OPTIONAL_TIMESERIES)
            if tuple(row) != want:
                raise ValueError(f"time-series columns {list(row)}, the schema has {list(want)}")
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
    (:class:`swarm.comm.sharing.MapSharing` says which: a full map, or the delta that follows the last one i
    merged); MAES's merges (:mod:`swarm.comm.maes_merge`) give every member of a merge the union.
    """

    KEEP_TICKS = 64
    """Snapshots kept for at most this many ticks (deliveries take a tick, relayed ones a few; older ones are
    forgotten)."""

    def __init__(self, n: int, keep_ticks: int | None = None) -> None:
        """``keep_ticks``: how long a snapshot may still be read, at most :data:`KEEP_TICKS`: one more than
        the longest a map update can take to arrive (``CommSpec.longest_delivery_ticks``), so a run keeps one
        or two snapshots, not one per sending tick of 64 (each n^2 int32: 400 MB at 10,000 robots). An update
        an algorithm builds carries a tick of its choosing: older than that, it counts only for its sender's
        own entry, as any update older than KEEP_TICKS did."""
        self.n = n
        self.keep = self.KEEP_TICKS if keep_ticks is None else max(1, min(int(keep_ticks), self.KEEP_TICKS))
        self.merged_at = np.zeros((n, n), dtype=np.int32)  # ticks (< 2^31: stop.max_ticks is at most 10^7)
        self.merges = 0
        # merged_at as of each tick within the last `keep` at which updates were sent: `keep` slots, resident
        # once written (one or two for a run without flooding; 4 MB each for 1,000 robots, 400 MB for 10,000).
        # Allocated up front: growing a stack of slots copied it (a 10,000-robot run held three for a moment)
        self._ring = lazy_zeros((self.keep, n, n), np.int32)
        self._ring_tick = np.full(self.keep, _NO_TICK, dtype=np.int64)

    def sent(self, tick: int) -> None:
        """Robots broadcast their maps at ``tick``: note what each map holds of the others, for whoever
        merges them (once per tick, whoever sends)."""
        if np.any(self._ring_tick == tick):
            return
        ticks = self._ring_tick
        stale = np.flatnonzero((ticks <= tick - self.keep) & (ticks != _NO_TICK))  # reused first: resident
        slot = int(stale[0]) if stale.size else int(np.argmin(ticks))  # else an unused slot (or the oldest)
        self._ring[slot] = self.merged_at
        self._ring_tick[slot] = tick

    def snapshots(self) -> int:
        """How many slots have held a snapshot (at most ``keep``; each n^2 int32 of resident memory)."""
        return int(np.count_nonzero(self._ring_tick != _NO_TICK))

    def merged(self, merges: list[tuple[np.ndarray, int, int]], tick: int) -> None:
        """A tick's merges, each ``(receivers, sender, sent)`` (``receivers``: int64 robot ids): they merged
        the update ``sender`` broadcast at tick ``sent`` and now hold its whole map as of then. Each merge
        reads the snapshot of when its update was sent (none older than ``keep`` ticks: then only the
        sender's own entry counts), so their order does not matter."""
        if not merges:
            return
        receivers = np.concatenate([m[0] for m in merges])
        ends = np.cumsum([len(m[0]) for m in merges])
        _merge_ages(self.merged_at, self._ring, self._ring_tick, receivers, ends,
                    np.array([m[1] for m in merges], dtype=np.int64), np.array([m[2] for m in merges], dtype=np.int64),
                    tick, self.keep)
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
        off = self.merged_at.sum(axis=1) - self.merged_at.diagonal()
        return tick - off / (n - 1)


_NO_TICK = np.iinfo(np.int64).min // 2
"""The tick of a ring slot that holds no snapshot (older than any)."""

TOP = 8
"""A merge round's snapshot rows are reduced column by column to their TOP largest values (with the rows
they come from) when a receiver merged all but fewer than TOP of the round's senders (see :func:`_merge_ages`)."""


ROW_BLOCK = 64
"""Receivers whose one-by-one snapshot rows :func:`_max_rows` applies together."""
COLUMN_BLOCK = 1024
"""...a block of this many columns at a time (64 receivers' rows of it: 256 KB, in cache)."""


@njit(cache=True)
def _merge_ages(merged_at: np.ndarray, ring: np.ndarray, ring_tick: np.ndarray, receivers: np.ndarray,
                ends: np.ndarray, senders: np.ndarray, sent: np.ndarray, tick: int, keep: int) -> None:  # pragma: no cover
    """:meth:`InfoAges.merged`: update j reached ``receivers[ends[j-1]:ends[j]]``; each receiver's row rises
    to the sender's row of the snapshot of tick ``sent[j]`` (if still kept) and its entry for the sender
    becomes ``tick``. Snapshots are of earlier ticks, so the order of the updates does not matter.

    Per receiver and snapshot, the row rises to the column maxima of the rows of the senders it merged.
    A swarm's sharing round has n senders reaching n - 1 receivers each: row by row that is n^3 work. So a
    receiver that merged all but a few (fewer than :data:`TOP`) of the senders of a snapshot reads, per
    column, the largest values of all its senders' rows and takes the first whose row it did not merge
    (the same maximum); one that merged few rows takes them one by one. Either way n^2 a round."""
    n = merged_at.shape[0]
    m = ends.shape[0]
    slots = ring_tick.shape[0]
    slot = np.full(m, -1, np.int64)
    for j in range(m):
        if sent[j] > tick - keep:  # an older update counts only for its sender's own entry
            for k in range(slots):
                if ring_tick[k] == sent[j]:
                    slot[j] = k
    # the merges of each receiver, and the senders of each snapshot (as sets)
    per = np.zeros(n + 1, np.int64)
    begin = 0
    for j in range(m):
        for k in range(begin, ends[j]):
            per[receivers[k] + 1] += 1
        begin = ends[j]
    for r in range(n):
        per[r + 1] += per[r]
    fill = per[:n].copy()
    merge_of = np.empty(per[n], np.int32)  # (a swarm's round: 32 million merges)
    begin = 0
    for j in range(m):
        for k in range(begin, ends[j]):
            r = receivers[k]
            merge_of[fill[r]] = j
            fill[r] += 1
        begin = ends[j]
    in_slot = np.zeros((slots, n), np.bool_)
    slot_senders = np.zeros(slots, np.int64)
    for j in range(m):
        if slot[j] >= 0 and not in_slot[slot[j], senders[j]]:
            in_slot[slot[j], senders[j]] = True
            slot_senders[slot[j]] += 1
    top_value = np.empty((slots, TOP, n), np.int32)
    top_row = np.empty((slots, TOP, n), np.int64)
    top_ready = np.zeros(slots, np.bool_)
    mine = np.zeros(n, np.bool_)
    excluded = np.zeros(n, np.bool_)
    done = np.zeros(slots, np.bool_)  # the snapshots the current receiver's row has taken
    row_max = np.empty(n, merged_at.dtype)
    # rows taken one by one are gathered for a block of receivers and applied together (_max_rows): nearby
    # robots merged mostly the same senders, so each sender's row is read once a block, not once a receiver
    most = 0
    for r0 in range(0, n, ROW_BLOCK):
        most = max(most, per[min(n, r0 + ROW_BLOCK)] - per[r0])
    pair_r = np.empty(most, np.int32)
    pair_row = np.empty(most, np.int64)  # sigma * n + sender
    unique_of = np.full(slots * n, -1, np.int64)
    pairs = 0
    for r in range(n):
        if r % ROW_BLOCK == 0 and pairs:
            _max_rows(merged_at, ring.reshape(slots * n, n), pair_r, pair_row, pairs, unique_of)
            pairs = 0
        a, b = per[r], per[r + 1]
        if a == b:
            continue
        row = merged_at[r]
        for q in range(a, b):  # each snapshot this receiver merged from, once
            j0 = merge_of[q]
            sigma = slot[j0]
            if sigma < 0:
                continue
            if done[sigma]:
                continue
            done[sigma] = True
            count = 0
            for q2 in range(q, b):
                j = merge_of[q2]
                if slot[j] == sigma and not mine[senders[j]]:
                    mine[senders[j]] = True
                    count += 1
            missing = slot_senders[sigma] - count
            if count <= TOP or missing >= TOP:  # few rows merged: take them one by one (in _max_rows)
                for q2 in range(q, b):
                    j = merge_of[q2]
                    if slot[j] == sigma and mine[senders[j]]:
                        pair_r[pairs] = r
                        pair_row[pairs] = sigma * n + senders[j]
                        pairs += 1
                        mine[senders[j]] = False  # each sender's row once
            else:  # nearly every row: the largest values of all of them, skipping the rows not merged
                if not top_ready[sigma]:
                    _column_tops(ring[sigma], in_slot[sigma], top_value[sigma], top_row[sigma])
                    top_ready[sigma] = True
                for s in range(n):
                    if in_slot[sigma, s] and not mine[s]:
                        excluded[s] = True
                tv, tr = top_value[sigma], top_row[sigma]
                for x in range(n):
                    best = row[x]
                    for t in range(TOP):
                        s = tr[t, x]
                        if s < 0:
                            break
                        if not excluded[s]:
                            best = max(best, tv[t, x])
                            break
                    row_max[x] = best
                for x in range(n):
                    row[x] = row_max[x]
                for s in range(n):
                    excluded[s] = False
            for q2 in range(q, b):
                mine[senders[merge_of[q2]]] = False
        for q in range(a, b):  # (before the block's rows are applied: a snapshot holds no tick after now)
            merged_at[r, senders[merge_of[q]]] = tick
            if slot[merge_of[q]] >= 0:
                done[slot[merge_of[q]]] = False
    if pairs:
        _max_rows(merged_at, ring.reshape(slots * n, n), pair_r, pair_row, pairs, unique_of)


@njit(cache=True)
def _max_rows(merged_at: np.ndarray, rows: np.ndarray, pair_r: np.ndarray, pair_row: np.ndarray, pairs: int,
              unique_of: np.ndarray) -> None:  # pragma: no cover - compiled
    """``merged_at[pair_r[k]]`` rises to ``rows[pair_row[k]]`` elementwise, for k < ``pairs``: grouped by
    source row (each read once, column block by column block, into every receiver that took it), the
    same maxima as pair by pair. ``unique_of``: scratch of -1s as long as ``rows``, left so."""
    n = merged_at.shape[1]
    unique = np.empty(pairs, np.int64)
    counts = np.zeros(pairs + 1, np.int64)
    k_unique = 0
    for k in range(pairs):
        u = unique_of[pair_row[k]]
        if u < 0:
            u = k_unique
            unique_of[pair_row[k]] = u
            unique[u] = pair_row[k]
            k_unique += 1
        counts[u + 1] += 1
    for u in range(k_unique):
        counts[u + 1] += counts[u]
    fill = counts[:k_unique].copy()
    takers = np.empty(pairs, np.int32)
    for k in range(pairs):
        u = unique_of[pair_row[k]]
        takers[fill[u]] = pair_r[k]
        fill[u] += 1
    for x0 in range(0, n, COLUMN_BLOCK):
        x1 = min(n, x0 + COLUMN_BLOCK)
        for u in range(k_unique):
            src = rows[unique[u], x0:x1]
            for t in range(counts[u], counts[u + 1]):
                dst = merged_at[takers[t], x0:x1]
                for x in range(dst.shape[0]):  # (on slices from 0: vectorised, 7x an offset range here)
                    dst[x] = max(dst[x], src[x])
    for u in range(k_unique):
        unique_of[unique[u]] = -1


@njit(cache=True)
def _column_tops(snap: np.ndarray, rows: np.ndarray, value: np.ndarray, which: np.ndarray) -> None:  # pragma: no cover
    """Per column x of ``snap`` (over the rows flagged in ``rows``): the TOP largest values, largest first, and
    their rows (-1 past the last row)."""
    n = snap.shape[1]
    depth = value.shape[0]
    for t in range(depth):
        for x in range(n):
            which[t, x] = -1
    for s in range(snap.shape[0]):
        if not rows[s]:
            continue
        line = snap[s]
        for x in range(n):
            v = line[x]
            if which[depth - 1, x] >= 0 and v <= value[depth - 1, x]:
                continue
            t = depth - 1
            while t > 0 and (which[t - 1, x] < 0 or value[t - 1, x] < v):
                value[t, x] = value[t - 1, x]
                which[t, x] = which[t - 1, x]
                t -= 1
            value[t, x] = v
            which[t, x] = s


# --------------------------------------------------------------------------------- free cells ----
class FreeCounts:
    """Each robot's count of FREE cells, kept without reading the maps (reading 16 maps of 300 x 300 cells
    at every recorded row costs the memory traffic of the whole stack): the ternary lidar adds the cells it
    turns FREE (:meth:`swarm.world.sensing.Lidar.scan`, ``freed``), delta merges add what they change
    (:func:`swarm.knowledge.maps.merge_cells_many_counted`), and a map overwritten wholesale (a full map or a
    MAES merge) is marked ``dirty`` and counted afresh when next read. ``exact=False`` (the log-odds lidar,
    whose scans may also unlearn cells) counts every map afresh at every read."""

    def __init__(self, n: int, exact: bool) -> None:
        self.exact = exact
        self.freed = np.zeros(n, dtype=np.int64)   # changes since the last read
        self.dirty = np.zeros(n, dtype=np.bool_)   # maps to count afresh at the next read
        self.counts = np.zeros(n, dtype=np.int64)  # the maps start UNSEEN

    def read(self, known: np.ndarray) -> np.ndarray:
        """The FREE cells of each map in ``known`` (``uint8[R, H, W]``), as of now."""
        self.counts += self.freed
        self.freed[:] = 0
        if not self.exact:
            self.dirty[:] = True
        if self.dirty.any():
            flat = known.reshape(-1)
            words = flat[: flat.shape[0] // 8 * 8].view(np.uint64)
            _free_counts(flat, words, flat.shape[0] // len(self.counts), self.dirty, self.counts)
            self.dirty[:] = False
        return self.counts


# -------------------------------------------------------------------------------- comm metrics ----
class CommMetrics:
    """The communication series of a run (:data:`swarm.results.schema.COMM_SERIES`), its per-robot series
    (:data:`swarm.results.schema.COMM_ROBOT_SERIES`) and summary (:class:`swarm.results.schema.CommSummary`), one row
    per row of the run's time series.

    The share of the team's known free cells a robot misses needs every robot's count of FREE cells
    (:class:`FreeCounts`). The team's count is the tracker's seen free cells when only the ternary lidar
    writes maps (every FREE cell of a map was seen by some lidar and every seen free cell was written FREE
    into its robot's map), else the union is counted at every row.
    """

    def __init__(self, n: int, free: FreeCounts) -> None:
        self.n = n
        self.free = free
        self.series: dict[str, list[Any]] = {c: [] for c in COMM_SERIES_COLUMNS}
        self.robots: dict[str, list[list[Any]]] = {c: [] for c in COMM_ROBOT_SERIES}
        self._union = np.zeros(0, dtype=np.uint8)
        self._groups: list[int] = []
        self._biggest: list[float] = []
        self._connected = 0

    def record(self, tick: int, stats: Any, known: np.ndarray, seen_free: int, groups: list[frozenset[int]],
               ages: InfoAges) -> None:
        """One row: ``stats`` is the medium's :class:`swarm.comm.medium.CommStats`, ``known`` the maps
        (``uint8[R, H, W]``), ``seen_free`` the tracker's seen free cells, ``groups`` the tick's
        communication groups."""
        if self.series["tick"] and self.series["tick"][-1] == tick:
            return
        n = self.n  # (16-robot rows are short: plain lists and builtins beat numpy calls here)
        missing = self._missing(known, seen_free)
        age = ages.ages(tick).tolist()
        contact = (tick - np.maximum(stats.contact, 0)).tolist() if n > 1 else [0] * n  # a lone robot hears no one
        group = [0] * n
        for k, members in enumerate(sorted(groups, key=min)):
            for robot in members:
                group[robot] = k
        s = self.series
        s["tick"].append(tick)
        for cause in DROP_CAUSES:
            s[f"msgs_{cause}"].append(int(getattr(stats, cause)))
        s["bytes_dropped"].append(int(stats.bytes_sent * (n - 1) - stats.bytes_delivered))
        s["map_merges"].append(ages.merges)
        s["since_contact_mean"].append(sum(contact) / n)
        s["since_contact_max"].append(max(contact))
        s["missing_free_mean"].append(sum(missing) / n)
        s["missing_free_max"].append(max(missing))
        s["aoi_age_mean"].append(sum(age) / n)
        s["aoi_age_max"].append(max(age))
        r = self.robots
        r["missing_free"].append(missing)
        r["aoi_age"].append(age)
        r["since_contact"].append(contact)
        r["group"].append(group)
        self._groups.append(len(groups))
        self._biggest.append(max(len(g) for g in groups) / n)
        self._connected += len(groups) == 1

    def team_free(self, known: np.ndarray, seen_free: int) -> int:
        """The team's known free cells, the missing share's denominator: ``seen_free`` (the tracker's count)
        when only the ternary lidar writes maps, else the cells FREE in some map of ``known``, counted."""
        if self.free.exact:
            return seen_free
        cells = known.size // self.n
        if self._union.shape[0] != cells:
            self._union = np.zeros(cells, dtype=np.uint8)
        return int(_free_union(known.reshape(self.n, cells), self._union))

    def _missing(self, known: np.ndarray, seen_free: int) -> list[float]:
        """Per robot: the share of the free cells some robot's map holds that its own map does not."""
        if self.n < 2:
            return [0.0] * self.n
        counts = self.free.read(known)
        team = self.team_free(known, seen_free)
        if team <= 0:
            return [0.0] * self.n
        # clipped: an algorithm's own map update may hold free cells no lidar saw
        return [min(max(1.0 - c / team, 0.0), 1.0) for c in counts.tolist()]

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


@njit(cache=True, inline="always")
def _free_in_words(words: np.ndarray) -> int:  # pragma: no cover (compiled)
    """FREE cells in ``words`` (cells 8 to a uint64): ``((w & 0x0101..01) * 0x0101..01) >> 56`` is the sum of
    the eight low bits (at most 8: no carry out of the top byte). Over a slice, so LLVM vectorises it."""
    mask = np.uint64(0x0101010101010101)
    acc = np.uint64(0)
    for k in range(words.shape[0]):
        acc += ((words[k] & mask) * mask) >> np.uint64(56)
    return acc


@njit(cache=True)
def _free_counts(flat: np.ndarray, words: np.ndarray, cells: int, which: np.ndarray,
                 out: np.ndarray) -> None:  # pragma: no cover (compiled)
    """``out[i]`` = FREE cells of map i for every ``which[i]``, the maps ``cells`` long one after another in
    ``flat`` (uint8, values 0..2, so FREE is bit 0 of a byte) and ``words`` (the same memory as uint64, as
    far as it goes): eight cells a step, ~5x faster than a loop over bytes."""
    for i in range(out.shape[0]):
        if not which[i]:
            continue
        start, end = i * cells, (i + 1) * cells
        lo, hi = (start + 7) // 8, end // 8  # the whole words inside [start, end), if lo < hi
        c = 0
        if lo >= hi:
            for k in range(start, end):
                c += flat[k] & 1
        else:
            for k in range(start, lo * 8):
                c += flat[k] & 1
            c += _free_in_words(words[lo:hi])
            for k in range(hi * 8, end):
                c += flat[k] & 1
        out[i] = c


@njit(cache=True)
def _free_union(known: np.ndarray, union: np.ndarray) -> int:  # pragma: no cover (compiled)
    """Cells FREE in some map of ``known`` (uint8[R, cells]; ``union``: a uint8[cells] buffer)."""
    union[:] = 0
    for i in range(known.shape[0]):
        row = known[i]
        for k in range(row.shape[0]):
            union[k] |= row[k] & 1
    total = 0
    for k in range(union.shape[0]):
        total += union[k]
    return total


assert FREE == 1  # the kernels count bit 0: UNSEEN 0, FREE 1, SOLID 2
