"""Knowledge maps (what each robot believes) and the ground-truth exploration/coverage tracker.

A knowledge map is a ``uint8[H, W]`` raster of 0.5 m cells with ``UNSEEN = 0 < FREE = 1 < SOLID = 2``
(:mod:`swarm.api`), so combining two maps is an elementwise maximum and SOLID is sticky, as in MAES's
SLAM map (docs/maes.md section 5.3). The runtime keeps one map per robot as ``uint8[R, H, W]``.

The optional log-odds mode (noisy lidar, xBOA paper section 4.1, Eqs. 5-8) keeps a ``float32`` log-odds
value per robot and cell (:class:`LogOddsGrid`); the sensor writes the derived ternary state into the
knowledge map, so algorithms and map merging see the same ``uint8`` rasters in both modes.

:class:`ExplorationTracker` is the referee: it knows the truth and measures how much of the free space
the swarm has seen (``explored``) and driven over (``coverage``, docs/maes.md section 5.2). It is incremental:
the sensor kernel reports the number of newly seen free cells, so reading the metrics is O(1) per tick.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np
from numba import njit

from maps import Map
from swarm.base.errors import InvalidInput

from swarm.base.types import CELL_M, FREE, SOLID, UNSEEN

__all__ = [
    "FREE", "SOLID", "UNSEEN", "ExplorationTracker", "LogOddsGrid", "active_flags", "check_writable_map",
    "classify_logodds", "count_cells", "count_known", "empty_knowledge", "merge", "merge_cells", "merge_cells_many",
    "merge_cells_many_counted", "sync_box", "sync_box_unchecked", "sync_changes", "sync_regions",
]


# --------------------------------------------------------------------------------------- ternary maps
def empty_knowledge(shape: tuple[int, int], n_robots: int | None = None) -> np.ndarray:
    """An all-UNSEEN map ``uint8[H, W]``, or a stack ``uint8[n_robots, H, W]`` (C-contiguous, as the
    sensor kernel wants it)."""
    full = tuple(shape) if n_robots is None else (n_robots, *shape)
    return np.zeros(full, dtype=np.uint8)


def _check_map(name: str, array: np.ndarray, *, writable: bool = False) -> None:
    if not isinstance(array, np.ndarray) or array.dtype != np.uint8 or array.ndim != 2:
        raise InvalidInput(name, getattr(array, "shape", type(array).__name__), "a uint8[H, W] knowledge map")
    if writable and not array.flags.writeable:
        raise InvalidInput(name, "a read-only array", "a writable uint8[H, W] knowledge map")


@njit(cache=True)
def _merge_max_kernel(into: np.ndarray, other: np.ndarray) -> int:
    changed = 0
    rows, cols = into.shape
    for r in range(rows):
        for c in range(cols):
            v = other[r, c]
            if v > into[r, c]:
                into[r, c] = v
                changed += 1
    return changed


def merge(into: np.ndarray, other: np.ndarray) -> int:
    """Merge ``other`` into ``into`` in place (elementwise maximum) and return how many cells changed.

    Maximum is the right merge because the states are ordered by certainty of the ternary sensor:
    anything beats UNSEEN and SOLID beats FREE (a wall seen by anyone stays a wall, MAES semantics).
    The count lets the caller tell whether a received map taught the robot anything.
    """
    _check_map("into", into, writable=True)
    _check_map("other", other)
    if other.shape != into.shape:
        raise InvalidInput("other", other.shape, f"the same shape as into {into.shape}")
    if not into.flags.c_contiguous:
        raise InvalidInput("into", "a non-contiguous view", "a C-contiguous uint8[H, W] array")
    return int(_merge_max_kernel(into, np.ascontiguousarray(other)))


@njit(cache=True, inline="always")  # also the body of _merge_cells_many_kernel
def _merge_cells_kernel(flat: np.ndarray, idx: np.ndarray, values: np.ndarray) -> None:  # pragma: no cover - compiled
    for k in range(idx.shape[0]):
        i = idx[k]
        if values[k] > flat[i]:
            flat[i] = values[k]


def check_writable_map(known: np.ndarray) -> None:
    """Refuse a map (or stack of maps) that cells cannot be merged into in place."""
    if not (known.flags.c_contiguous and known.flags.writeable):
        raise InvalidInput("known", "a read-only or non-contiguous map", "a writable C-contiguous uint8 map")


def merge_cells(known: np.ndarray, idx: np.ndarray, values: np.ndarray) -> None:
    """Raise cells ``idx`` (flat indices, repeats allowed) of ``known`` to at least ``values``, in place:
    ``numpy.maximum.at`` semantics at the cost of one pass (``ufunc.at`` is ~20x slower, and merging
    received map updates runs for every receiver every sharing tick). Indices must be in range."""
    check_writable_map(known)
    merge_cells_unchecked(known.reshape(-1), np.ascontiguousarray(idx, dtype=np.int64),
                          np.ascontiguousarray(values, dtype=np.uint8))


@njit(cache=True)
def _merge_cells_many_kernel(stack: np.ndarray, rows: np.ndarray, idx: np.ndarray,
                             values: np.ndarray) -> None:  # pragma: no cover - compiled
    """:func:`_merge_cells_kernel` into each map ``stack[rows[k]]``."""
    for k in range(rows.shape[0]):
        _merge_cells_kernel(stack[rows[k]].reshape(-1), idx, values)


@njit(cache=True, inline="always")
def _merge_counting(flat: np.ndarray, idx: np.ndarray, values: np.ndarray, out: np.ndarray,
                    m: int) -> tuple[int, int]:  # pragma: no cover - compiled
    """Merge ``values`` into the flat map ``flat`` at ``idx`` (each cell keeps the maximum), listing each
    cell it raises at ``out[m:]`` unless ``out`` is empty. Returns the FREE cells the map gained less those
    it lost, and the list's new end: the one loop of the counted and the listing merges."""
    record = out.shape[0] > 0
    change = 0
    for j in range(idx.shape[0]):
        i = idx[j]
        v = values[j]
        old = flat[i]
        if v > old:
            change += (v == FREE) - (old == FREE)
            flat[i] = v
            if record:
                out[m] = i
                m += 1
    return change, m


@njit(cache=True)
def _merge_cells_many_counted_kernel(stack: np.ndarray, rows: np.ndarray, idx: np.ndarray, values: np.ndarray,
                                     robots: np.ndarray, freed: np.ndarray) -> None:  # pragma: no cover - compiled
    """:func:`_merge_cells_many_kernel`, adding to ``freed[robots[k]]`` how many FREE cells map
    ``stack[rows[k]]`` gained (UNSEEN -> FREE) less those it lost (FREE -> SOLID)."""
    no_list = np.empty(0, dtype=np.int64)
    for k in range(rows.shape[0]):
        change, _ = _merge_counting(stack[rows[k]].reshape(-1), idx, values, no_list, 0)
        freed[robots[k]] += change


def merge_cells_many_counted(stack: np.ndarray, rows: np.ndarray, idx: np.ndarray, values: np.ndarray,
                             robots: np.ndarray, freed: np.ndarray) -> None:
    """:func:`merge_cells_many` that also keeps count: ``freed[robots[k]]`` (int64) changes by the FREE cells
    map ``stack[rows[k]]`` gained or lost (age-of-information metrics, :class:`swarm.results.metrics.FreeCounts`)."""
    _merge_cells_many_counted_kernel(stack, rows, idx, values, robots, freed)


def merge_cells_many(stack: np.ndarray, rows: np.ndarray, idx: np.ndarray, values: np.ndarray) -> None:
    """:func:`merge_cells_unchecked` into each map ``stack[rows[k]]`` of a writable C-contiguous stack
    (``uint8[R, H, W]``, rows int64 in range): one call for all the receivers of a map update."""
    _merge_cells_many_kernel(stack, rows, idx, values)


def merge_cells_many_changed(stack: np.ndarray, rows: np.ndarray, idx: np.ndarray, values: np.ndarray,
                             out: np.ndarray, ends: np.ndarray, robots: np.ndarray | None = None,
                             freed: np.ndarray | None = None) -> None:
    """:func:`merge_cells_many` that also lists, per map, the cells the merge raised: map ``rows[k]``'s at
    ``out[ends[k-1]:ends[k]]``, ascending when ``idx`` is (``out``: int64 with room for every row's every
    cell; ``ends``: int64[len(rows)]). A receiver's next map update compares only these, not every cell it
    was sent: robots that share maps mostly know what they hear already. With ``freed`` it also keeps
    count as :func:`merge_cells_many_counted` does (``robots``: the robot of each row)."""
    if freed is None:
        robots, freed = rows, np.zeros(0, dtype=np.int64)
    _merge_cells_many_changed_kernel(stack, rows, idx, values, out, ends, robots, freed)


@njit(cache=True)
def _merge_cells_many_changed_kernel(stack: np.ndarray, rows: np.ndarray, idx: np.ndarray, values: np.ndarray,
                                     out: np.ndarray, ends: np.ndarray, robots: np.ndarray,
                                     freed: np.ndarray) -> None:  # pragma: no cover - compiled
    """``freed`` empty: no count kept."""
    m = 0
    for k in range(rows.shape[0]):
        change, m = _merge_counting(stack[rows[k]].reshape(-1), idx, values, out, m)
        ends[k] = m
        if freed.shape[0]:
            freed[robots[k]] += change


def merge_cells_unchecked(flat: np.ndarray, idx: np.ndarray, values: np.ndarray) -> None:
    """:func:`merge_cells` on a flat writable map with int64 indices (in range) and uint8 values, for callers
    whose cells already are (decoded map updates); :func:`merge_cells_many` merges into several maps."""
    _merge_cells_kernel(flat, idx, values)


@njit(cache=True, inline="always")
def _copy_if_changed(current: np.ndarray, last: np.ndarray, i: int) -> bool:  # pragma: no cover - compiled
    """Copy flat cell ``i`` into ``last`` if it differs; True if it did. The callers record ``i`` themselves:
    threading the output count through this helper made the window scan 8x slower (12 us against 1.4 us
    for a 33 x 33 window, measured), as LLVM then keeps the loop from being optimised."""
    v = current[i]
    if v != last[i]:
        last[i] = v
        return True
    return False


@njit(cache=True)
def _sync_changes_kernel(current: np.ndarray, last: np.ndarray, cur64: np.ndarray, last64: np.ndarray,
                         out: np.ndarray) -> int:  # pragma: no cover - compiled
    """Compare 8 cells at a time (uint64 views of the same memory), bytes only inside differing words."""
    m = 0
    for k in range(cur64.shape[0]):
        if cur64[k] != last64[k]:
            for i in range(8 * k, 8 * k + 8):
                if _copy_if_changed(current, last, i):
                    out[m] = i
                    m += 1
    for i in range(8 * cur64.shape[0], current.shape[0]):
        if _copy_if_changed(current, last, i):
            out[m] = i
            m += 1
    return m


def sync_changes(current: np.ndarray, last: np.ndarray) -> np.ndarray:
    """Flat indices (ascending) where ``current`` differs from ``last``, copying them into ``last``: after
    the call ``last == current``. One pass instead of compare + nonzero + copy (the map-sharing service
    does this for every robot every sharing tick)."""
    cur, prev = current.reshape(-1), last.reshape(-1)
    if cur.shape != prev.shape or not last.flags.c_contiguous:
        raise InvalidInput("last", getattr(last, "shape", None), f"a C-contiguous map shaped like current {current.shape}")
    cur = np.ascontiguousarray(cur)
    words = cur.shape[0] // 8
    out = np.empty(cur.shape[0], dtype=np.int64)
    m = _sync_changes_kernel(cur, prev, cur[:8 * words].view(np.uint64), prev[:8 * words].view(np.uint64), out)
    return out[:m].copy()


@njit(cache=True, inline="always")
def _same_words(cur64: np.ndarray, prev64: np.ndarray, a: int, b: int) -> bool:  # pragma: no cover - compiled
    """True if the 8-byte words covering flat cells ``a..b-1`` are equal in both maps (so those cells are);
    False if one differs or the span reaches the bytes after the last whole word. Most window rows have no
    change: comparing 5 words instead of 33 bytes made the windows' scan 3x faster."""
    last = (b - 1) >> 3
    if last >= cur64.shape[0]:
        return False
    for w in range(a >> 3, last + 1):
        if cur64[w] != prev64[w]:
            return False
    return True


@njit(cache=True, inline="always")
def _sync_rect(cur: np.ndarray, prev: np.ndarray, cols: int, r0: int, r1: int, c0: int, c1: int, extra: np.ndarray,
               e0: int, e1: int, out: np.ndarray, m: int) -> int:  # pragma: no cover - compiled
    """Copy into ``prev`` the cells of the flat map ``cur`` (rows ``cols`` wide) that differ in rows ``r0:r1``
    x columns ``c0:c1`` (clipped by the caller) and at ``extra[e0:e1]``, listing them in ``out`` from ``m``
    (sorted when there were extra cells: the rectangle's scan alone is ascending); returns the new end.
    The per-map body of the window and box scans (:func:`sync_regions`, :func:`sync_box`)."""
    words = cur.shape[0] // 8
    cur64, prev64 = cur[:8 * words].view(np.uint64), prev[:8 * words].view(np.uint64)
    start = m
    if c1 > c0:
        for r in range(r0, r1):
            a, b = r * cols + c0, r * cols + c1
            if _same_words(cur64, prev64, a, b):
                continue
            for i in range(a, b):
                if _copy_if_changed(cur, prev, i):
                    out[m] = i
                    m += 1
    for j in range(e0, e1):
        if _copy_if_changed(cur, prev, extra[j]):
            out[m] = extra[j]
            m += 1
    if e1 > e0:
        out[start:m].sort()
    return m


@njit(cache=True)
def _sync_windows_kernel(current: np.ndarray, last: np.ndarray, centres: np.ndarray, reach: int, active: np.ndarray,
                         extra: np.ndarray, ends: np.ndarray, out: np.ndarray) -> None:  # pragma: no cover - compiled
    """The window scan plus listed cells of :func:`sync_regions` for every active map of a stack. On entry
    ``ends[k]`` is where map k's extra cells end in ``extra``; on return, where its changed cells end in
    ``out``. Fewer arguments: numba's dispatch costs ~0.5 us per array."""
    rows, cols = current.shape[1], current.shape[2]
    m = 0
    e0 = 0
    for k in range(current.shape[0]):
        e1 = ends[k]
        if active[k]:
            r, c = centres[k, 0], centres[k, 1]
            m = _sync_rect(current[k].reshape(-1), last[k].reshape(-1), cols, max(r - reach, 0),
                           min(r + reach + 1, rows), max(c - reach, 0), min(c + reach + 1, cols), extra, e0, e1,
                           out, m)
        e0 = e1
        ends[k] = m


def sync_regions(current: np.ndarray, last: np.ndarray, centres: np.ndarray, reach: int,
                 cells: Sequence[Sequence[np.ndarray]], active: np.ndarray) -> list[np.ndarray | None]:
    """:func:`sync_changes` restricted, for every map of a stack (``uint8[R, H, W]``) in one compiled call, to
    a window and a list: map k's window is rows ``centres[k, 0] +- reach`` and cols ``centres[k, 1] +- reach``
    (clipped to the map), its list the flat ``cells[k]`` (arrays; repeats allowed; read for active maps only).
    Per map: the changed cells among them, ascending, copied into ``last``. None for maps with ``active[k]``
    False, which are left alone. The zenoh transport ships each robot only what changed where its lidar
    looked or a merge wrote, every robot every tick: per-robot calls cost several times the scan itself in
    Python (bounds, concatenation, allocation)."""
    out, ends = sync_regions_flat(current, last, centres, reach, cells, active)
    bounds = ends.tolist()
    return [out[start:end] if a else None
            for start, end, a in zip([0, *bounds[:-1]], bounds, active_flags(len(bounds), active).tolist())]


def sync_regions_flat(current: np.ndarray, last: np.ndarray, centres: np.ndarray, reach: int,
                      cells: Sequence[Sequence[np.ndarray]], active: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`sync_regions` as one array: map k's changed cells are ``out[ends[k-1]:ends[k]]`` (empty for
    inactive maps), the layout the zenoh transport's packet writer reads without cutting it per robot."""
    if current.shape != last.shape or current.ndim != 3 or not (current.flags.c_contiguous and last.flags.c_contiguous):
        raise InvalidInput("last", getattr(last, "shape", None), f"a C-contiguous stack shaped like current {current.shape}")
    n = current.shape[0]
    act = active_flags(n, active)
    extra, bounds = _listed_cells(cells, act)
    side = 2 * reach + 1
    out = np.empty(n * side * side + len(extra), dtype=np.int64)
    _sync_windows_kernel(current, last, np.ascontiguousarray(centres, dtype=np.int64), reach, act, extra, bounds, out)
    return out, bounds


def sync_boxes_flat(current: np.ndarray, last: np.ndarray, boxes: np.ndarray,
                    cells: Sequence[Sequence[np.ndarray]], active: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`sync_regions_flat` with a box per map instead of a window: map k is compared in rows
    ``boxes[k, 0]:boxes[k, 1]`` x columns ``boxes[k, 2]:boxes[k, 3]`` (clipped; empty when r0 >= r1) and at
    its listed ``cells[k]``. For a caller that knows where each map was written: the runtime gives each
    robot the window its lidar may have written, empty for a robot it did not cast."""
    if current.shape != last.shape or current.ndim != 3 or not (current.flags.c_contiguous and last.flags.c_contiguous):
        raise InvalidInput("last", getattr(last, "shape", None), f"a C-contiguous stack shaped like current {current.shape}")
    n, rows, cols = current.shape
    box = np.ascontiguousarray(boxes, dtype=np.int64)
    if box.shape != (n, 4):
        raise InvalidInput("boxes", box.shape, f"an int64 array of shape ({n}, 4): r0, r1, c0, c1 per map")
    act = active_flags(n, active)
    extra, bounds = _listed_cells(cells, act)
    return _sync_boxes_kernel(current, last, box, act, extra, bounds), bounds


def _listed_cells(cells: Sequence[Sequence[np.ndarray]], act: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The listed cells of the active maps as one int64 array and where each map's end (int64[n])."""
    flags = act.tolist()
    pieces: list[np.ndarray] = []
    ends = [0] * len(flags)
    total = 0
    for k in range(len(flags)) if any(cells) else ():  # most ticks nothing merged at all
        if flags[k] and cells[k]:
            pieces.extend(cells[k])
            total += sum(len(a) for a in cells[k])
        ends[k] = total
    extra = np.concatenate(pieces).astype(np.int64, copy=False) if pieces else _NO_CELLS
    return extra, np.array(ends, dtype=np.int64)


@njit(cache=True)
def _sync_boxes_kernel(current: np.ndarray, last: np.ndarray, boxes: np.ndarray, active: np.ndarray, extra: np.ndarray,
                       ends: np.ndarray) -> np.ndarray:  # pragma: no cover - compiled
    """:func:`_sync_windows_kernel` with a box per map; returns ``out`` (room for every active box's cells
    and every listed cell)."""
    rows, cols = current.shape[1], current.shape[2]
    room = extra.shape[0]
    for k in range(current.shape[0]):
        if active[k]:
            tall = max(min(boxes[k, 1], rows) - max(boxes[k, 0], 0), 0)
            room += tall * max(min(boxes[k, 3], cols) - max(boxes[k, 2], 0), 0)
    out = np.empty(room, dtype=np.int64)
    m = 0
    e0 = 0
    for k in range(current.shape[0]):
        e1 = ends[k]
        if active[k]:
            m = _sync_rect(current[k].reshape(-1), last[k].reshape(-1), cols, max(boxes[k, 0], 0),
                           min(boxes[k, 1], rows), max(boxes[k, 2], 0), min(boxes[k, 3], cols), extra, e0, e1, out, m)
        e0 = e1
        ends[k] = m
    return out


_NO_CELLS = np.zeros(0, dtype=np.int64)


@njit(cache=True)
def _sync_box_kernel(current: np.ndarray, last: np.ndarray, box: np.ndarray,
                     extra: np.ndarray) -> np.ndarray:  # pragma: no cover - compiled
    """:func:`sync_box` without the checks; ``box`` = int64 (r0, r1, c0, c1), clipped here."""
    h, w = current.shape
    r0, r1, c0, c1 = max(box[0], 0), min(box[1], h), max(box[2], 0), min(box[3], w)
    out = np.empty(max(r1 - r0, 0) * max(c1 - c0, 0) + extra.shape[0], dtype=np.int64)
    m = _sync_rect(current.reshape(-1), last.reshape(-1), w, r0, r1, c0, c1, extra, 0, extra.shape[0], out, 0)
    return out[:m].copy()


def sync_box(current: np.ndarray, last: np.ndarray, box: tuple[int, int, int, int], extra: np.ndarray) -> np.ndarray:
    """:func:`sync_changes` where the caller knows the maps can differ only inside the box of rows
    ``r0:r1`` and columns ``c0:c1`` (clipped to the map) and at the flat cells ``extra`` (in range, repeats
    allowed): the changed cells among them, ascending, copied into ``last``. Equal to :func:`sync_changes`
    when that promise holds, without reading both whole maps (the map-sharing service's deltas,
    :class:`swarm.comm.sharing.MapSharing`, where ~80 of 90 000 cells change between two updates)."""
    contiguous = current.flags.c_contiguous and last.flags.c_contiguous
    if current.shape != last.shape or current.ndim != 2 or not contiguous:
        raise InvalidInput("last", getattr(last, "shape", None),
                           f"a C-contiguous map shaped like current {current.shape}")
    cells = np.ascontiguousarray(extra, dtype=np.int64)
    if cells.size and not (0 <= cells.min() and cells.max() < current.size):
        raise InvalidInput("extra", f"cells {cells.min()}..{cells.max()}", f"flat indices in 0..{current.size - 1}")
    return sync_box_unchecked(current, last, np.array(box, dtype=np.int64), cells)


def sync_box_unchecked(current: np.ndarray, last: np.ndarray, box: np.ndarray, extra: np.ndarray) -> np.ndarray:
    """:func:`sync_box` for the map-sharing service, whose maps, box (int64[4]) and cells already are what
    it needs: it runs for every robot every sharing tick."""
    return _sync_box_kernel(current, last, box, extra)


def count_known(known: np.ndarray) -> int:
    """Cells that are not UNSEEN (FREE or SOLID), over the whole array (one map or a stack)."""
    return int(np.count_nonzero(known))


def count_cells(known: np.ndarray, state: int) -> int:
    """Cells in exactly ``state`` (UNSEEN, FREE or SOLID)."""
    if state not in (UNSEEN, FREE, SOLID):
        raise InvalidInput("state", state, f"{UNSEEN} (UNSEEN) | {FREE} (FREE) | {SOLID} (SOLID)")
    return int(np.count_nonzero(known == state))


# ------------------------------------------------------------------------------------- log-odds maps
def classify_logodds(values: np.ndarray, occupied_above: float = 0.0, free_below: float = 0.0) -> np.ndarray:
    """Ternary state of log-odds values, xBOA paper Eq. 8: SOLID if ``L > occupied_above``, FREE if
    ``L < free_below``, UNSEEN otherwise (the paper uses 0 for both: log-odds 0 is the prior p = 0.5).

    Thresholds are compared in float32, exactly as the sensor kernel does, so both agree on every cell.
    """
    v = np.asarray(values, dtype=np.float32)
    out = np.full(v.shape, UNSEEN, dtype=np.uint8)
    out[v < np.float32(free_below)] = FREE
    out[v > np.float32(occupied_above)] = SOLID
    return out


class LogOddsGrid:
    """Per-robot occupancy log-odds ``float32[R, H, W]`` (xBOA paper Eq. 7), all 0 (p = 0.5) at start.

    The lidar adds the inverse-sensor-model increments (see :class:`swarm.world.sensing.LidarParams`) and
    writes the classified state into the robot's knowledge map; this object only stores the numbers and
    knows how to classify them, so an algorithm or a viewer can inspect the belief behind a map.
    """

    def __init__(self, n_robots: int, shape: tuple[int, int], occupied_above: float = 0.0,
                 free_below: float = 0.0) -> None:
        if free_below > occupied_above:
            raise InvalidInput("free_below", free_below, f"a value <= occupied_above ({occupied_above:g})")
        self.values = np.zeros((n_robots, *shape), dtype=np.float32)
        self.occupied_above = float(occupied_above)
        self.free_below = float(free_below)

    @property
    def n_robots(self) -> int:
        return int(self.values.shape[0])

    def classify(self, robot: int | None = None) -> np.ndarray:
        """Ternary map of one robot (``uint8[H, W]``) or of all (``uint8[R, H, W]``)."""
        values = self.values if robot is None else self.values[robot]
        return classify_logodds(values, self.occupied_above, self.free_below)


# ----------------------------------------------------------------------------- ground-truth tracker
def active_flags(n_robots: int, active: np.ndarray | None) -> np.ndarray:
    """``active`` as a C-contiguous ``bool[n_robots]`` (None = every robot active)."""
    if active is None:
        return np.ones(n_robots, dtype=np.bool_)
    act = np.ascontiguousarray(active, dtype=np.bool_)
    if act.shape != (n_robots,):
        raise InvalidInput("active", act.shape, f"a bool array of shape ({n_robots},), one flag per robot")
    return act


@njit(cache=True)
def _cover_blocks_kernel(free: np.ndarray, positions: np.ndarray, active: np.ndarray, cell: float,
                         covered: np.ndarray) -> int:
    """Mark the free cells of the 3x3 block around each active robot's cell; return the number newly
    covered, or ``-(r + 1)`` (nothing written) if robot r is outside the map."""
    rows, cols = covered.shape
    n = positions.shape[0]
    for r in range(n):
        if active[r]:
            x = positions[r, 0]
            y = positions[r, 1]
            if not (x >= 0.0 and x < cols * cell and y >= 0.0 and y < rows * cell):
                return -(r + 1)
    new = 0
    for r in range(n):
        if not active[r]:
            continue
        row = int(np.floor(positions[r, 1] / cell))
        col = int(np.floor(positions[r, 0] / cell))
        for rr in range(max(row - 1, 0), min(row + 2, rows)):
            for cc in range(max(col - 1, 0), min(col + 2, cols)):
                if free[rr, cc] and not covered[rr, cc]:
                    covered[rr, cc] = True
                    new += 1
    return new


_NO_OWN = np.zeros((0, 1), dtype=np.uint64)
"""The own-sight mask of a tracker that does not track robots (:meth:`ExplorationTracker.track_robots`)."""


class ExplorationTracker:
    """Ground-truth exploration and coverage of one run.

    - ``seen[r, c]``: some robot's lidar observed the cell (free or solid, see :mod:`swarm.world.sensing` for
      the exact rule). It is written by the lidar kernel, which also reports how many *free* cells it saw
      for the first time, so ``explored = seen free cells / free cells`` costs O(1) per tick. MAES counts
      explored triangles; on our raster the cell is the unit.
    - ``covered[r, c]``: a free cell in the 3x3 block of 0.5 m cells around a robot's cell at some tick
      (docs/maes.md section 5.2; a cell is coverable iff it is free). ``coverage = covered / free cells``.
    - With :meth:`track_robots`, who saw what by its own lidar (not through shared maps): an own-sight mask
      of a bit per robot and cell (memory only where written: a byte a cell took 1 GB in a 10,000-robot
      swarm's first tick), ``seers[r, c]`` the number of distinct robots whose own
      lidar saw the cell (``uint16``), and each robot's own-seen cell count. The lidar kernels
      update them where they mark ``seen``, so the cost is linear in the cells the rays touch. They give
      :attr:`overlap_rate` and :attr:`coverage_spread` (docs/benchmark-metrics.md).
    """

    def __init__(self, truth: Map) -> None:
        self.truth = truth
        self.shape: tuple[int, int] = truth.shape
        self.free_cells: int = truth.free_cells
        self._free = np.ascontiguousarray(truth.free, dtype=np.bool_).copy()  # writable: one numba type
        self._seen = np.zeros(self.shape, dtype=np.bool_)
        self._covered = np.zeros(self.shape, dtype=np.bool_)
        self.seen_free_cells: int = 0
        self.covered_cells: int = 0
        self._own = _NO_OWN
        self._seers = np.zeros((0, 0), dtype=np.uint16)
        self._own_cells = np.zeros(0, dtype=np.int64)

    def track_robots(self, n_robots: int) -> None:
        """Keep, from now on, which of ``n_robots`` robots saw each cell by its own lidar (see the class
        docstring); the lidar kernels then mark a robot's own sight wherever they mark ``seen``."""
        from swarm.util.memory import lazy_zeros

        if not 0 < n_robots <= 65535:
            raise InvalidInput("n_robots", n_robots, "1 ... 65535 (the per-cell robot count is a uint16)")
        self._own = lazy_zeros((n_robots, -(-self.shape[0] * self.shape[1] // 64)), np.uint64)
        self._seers = np.zeros(self.shape, dtype=np.uint16)
        self._own_cells = np.zeros(n_robots, dtype=np.int64)

    @property
    def sight_buffers(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The writable own-sight mask (``uint64[R, ceil(H * W / 64)]``: bit ``k`` of robot r's row for flat cell
        ``k``, memory only where written), ``seers`` (``uint16[H, W]``) and own-seen counts
        (``int64[R]``), for the sensor kernels only; empty arrays unless :meth:`track_robots` was called."""
        return self._own, self._seers, self._own_cells

    @property
    def tracks_robots(self) -> bool:
        """Whether :meth:`track_robots` is on."""
        return self._own_cells.shape[0] > 0

    @property
    def own_seen_cells(self) -> np.ndarray:
        """Per robot, the cells (free or solid) its own lidar has seen (read-only ``int64[R]``)."""
        view = self._own_cells.view()
        view.setflags(write=False)
        return view

    @property
    def seers(self) -> np.ndarray:
        """Read-only ``uint16[H, W]``: how many distinct robots' own lidars saw each cell."""
        view = self._seers.view()
        view.setflags(write=False)
        return view

    def overlap_rate(self) -> float:
        """Cells seen by the own lidars of two or more robots over the cells seen (free or solid); 0 when
        nothing was seen. One pass over the ``seers`` raster: call it once, at the end of a run."""
        seen = int(np.count_nonzero(self._seers))
        return int(np.count_nonzero(self._seers >= 2)) / seen if seen else 0.0

    def coverage_spread(self) -> float:
        """The population standard deviation over robots of each robot's own-seen share, the cells its own
        lidar saw over the cells the team saw (Explore-Bench's coverage std); 0 when nothing was seen."""
        seen = int(np.count_nonzero(self._seers))
        return float(np.std(self._own_cells / seen)) if seen and self._own_cells.shape[0] else 0.0

    # The lidar kernel writes into this raster directly and reports its count through ``add_seen``.
    @property
    def seen_buffer(self) -> np.ndarray:
        """The writable ``seen`` raster, for the sensor kernel only."""
        return self._seen

    def add_seen(self, newly_seen_free: int) -> None:
        """Account for free cells the sensor saw for the first time (it has already set them in
        ``seen_buffer``)."""
        self.seen_free_cells += int(newly_seen_free)

    @property
    def seen(self) -> np.ndarray:
        """Read-only ``bool[H, W]``: cells observed by any robot so far."""
        view = self._seen.view()
        view.setflags(write=False)
        return view

    @property
    def covered(self) -> np.ndarray:
        """Read-only ``bool[H, W]``: free cells covered by any robot so far."""
        view = self._covered.view()
        view.setflags(write=False)
        return view

    @property
    def explored(self) -> float:
        """Fraction of the free cells seen by any robot, in [0, 1]."""
        return self.seen_free_cells / self.free_cells

    @property
    def coverage(self) -> float:
        """Fraction of the free (coverable) cells covered by any robot, in [0, 1]."""
        return self.covered_cells / self.free_cells

    def update_coverage(self, positions: np.ndarray, active: np.ndarray | None = None) -> int:
        """Cover the 3x3 block around each robot's cell (``positions``: ``float64[R, 2]`` x, y in metres);
        returns the number of newly covered cells. Inactive robots (``active[r]`` False) cover nothing."""
        pos = np.ascontiguousarray(positions, dtype=np.float64)
        if pos.ndim != 2 or pos.shape[1] != 2:
            raise InvalidInput("positions", pos.shape, "an array of shape (R, 2): x, y in metres")
        act = active_flags(pos.shape[0], active)
        new = int(_cover_blocks_kernel(self._free, pos, act, CELL_M, self._covered))
        if new < 0:
            r = -new - 1
            raise InvalidInput(f"positions[{r}]", tuple(float(v) for v in pos[r]),
                               f"a point inside the map (0 <= x < {self.truth.width_m:g}, "
                               f"0 <= y < {self.truth.height_m:g} m)")
        self.covered_cells += new
        return new


# ------------------------------------------------------------------------- map sharing's merge ----
@njit(cache=True)
def mark_tiles(dirty: np.ndarray, cells: np.ndarray, width: int, tile: int) -> None:  # pragma: no cover
    """Mark in ``dirty`` (uint8[ceil(H / tile), ceil(W / tile)]) the tiles of ``tile`` x ``tile`` cells that hold
    the flat ``cells`` of a map ``width`` cells wide."""
    for j in range(cells.shape[0]):
        i = cells[j]
        dirty[(i // width) // tile, (i % width) // tile] = 1


@njit(cache=True)
def merge_delta_booked_kernel(stack: np.ndarray, rows: np.ndarray, robots: np.ndarray, idx: np.ndarray,
                              values: np.ndarray, freed: np.ndarray, seen_seq: np.ndarray, holds: np.ndarray,
                              sender: int, seq: int, dirty: np.ndarray, tile: int, rest: np.ndarray,
                              held: np.ndarray) -> tuple[int, int]:  # pragma: no cover - compiled
    """A map-sharing delta (cells ``idx``, ``values``) from ``sender`` merged into each map ``stack[rows[k]]``
    of robot ``robots[k]``, with the books of :meth:`swarm.comm.sharing.MapSharing._take_delta` kept in the
    same pass: ``freed[robot]`` counts the FREE cells gained less those lost (unless ``freed`` is empty),
    ``dirty[robot]`` marks the tiles in which the merge raised cells, and a robot whose last merged update
    of the sender (``seen_seq[robot, sender]``) was ``seq - 1`` is booked at ``seq``. Returns how many
    positions ``k`` were not booked (listed in ``rest``) and how many booked robots hold the sender's whole
    map (``holds[robot, sender]``, listed in ``held``)."""
    width = stack.shape[2]
    counting = freed.shape[0] > 0
    n_rest = 0
    n_held = 0
    for k in range(rows.shape[0]):
        r = robots[k]
        flat = stack[rows[k]].reshape(-1)
        marks = dirty[r]
        change = 0
        for j in range(idx.shape[0]):
            i = idx[j]
            v = values[j]
            old = flat[i]
            if v > old:
                change += (v == FREE) - (old == FREE)
                flat[i] = v
                marks[(i // width) // tile, (i % width) // tile] = 1
        if counting:
            freed[r] += change
        if seen_seq[r, sender] == seq - 1:
            seen_seq[r, sender] = seq
            if holds[r, sender]:
                held[n_held] = r
                n_held += 1
        else:
            rest[n_rest] = k
            n_rest += 1
    return n_rest, n_held
