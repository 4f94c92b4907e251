"""Who knows what, cell by cell: every robot's knowledge of a cell as two bits, for merging one update into
many maps at once.

A swarm shares maps in rounds: every robot broadcasts the cells it learned since its last update, and in
a swarm spawned together each update reaches nearly every other robot, which mostly knows those cells
already (it heard them from their first finder). Merging an update into each receiver's map reads every
cell once per receiver: 4 billion reads in the first 60 ticks of 1,000 robots. The planes answer "which
of these receivers lack this cell" for all of them at once: for each cell, one bit per robot in ``free``
(the robot's map holds at least FREE there) and one in ``solid`` (it holds SOLID), packed 64 robots to
a word. A cell then costs a few words for the whole team, and only the receivers it raises are written.

The planes mirror the knowledge maps exactly, so every write into the maps must go through them while
they are in use: the ternary lidar (:mod:`swarm.world.sensing`) and the map-sharing service
(:mod:`swarm.comm.sharing`) do. They need maps whose cells never decrease (a log-odds lidar may turn SOLID
back to FREE) and no writer that bypasses them (MAES's merges): :func:`wanted` says when a run uses them.
Memory: two bits per robot for every cell anyone knows (the arrays take memory where written, see
:func:`swarm.util.memory.lazy_zeros`).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from swarm.base.types import FREE, SOLID
from swarm.util.memory import lazy_zeros

MIN_ROBOTS = 64
"""Smaller teams merge map by map: their updates reach few robots, and a word per cell would mostly hold
empty bits."""

FEW_RECEIVERS = 2
"""Up to this many receivers a merge compares with each receiver's own map (a byte a cell, read in order)
instead of the planes (a cache line of words a cell): in a spread-out swarm most full maps reach one or two
robots that never heard their sender and take every one of its known cells (~700,000 at 1,000 robots on 600
tiles). The planes mirror the maps, so both ways raise the same cells."""

_NO_PLANE = np.zeros((0, 1), dtype=np.uint64)


def wanted(n_robots: int, monotone: bool, merged_through: bool) -> bool:
    """Whether a run of ``n_robots`` keeps planes: maps whose cells only ever rise (``monotone``, the ternary
    lidar), every merge going through them (``merged_through``: the runtime's map sharing on, not MAES's
    merges, which overwrite maps wholesale), and a team of at least ``MIN_ROBOTS``."""
    return monotone and merged_through and n_robots >= MIN_ROBOTS


class KnowledgePlanes:
    """The two planes of ``n_robots`` maps of ``cells`` cells each (see the module docstring)."""

    def __init__(self, n_robots: int, cells: int) -> None:
        self.n_robots = n_robots
        self.words = (n_robots + 63) // 64
        self.free = lazy_zeros((cells, self.words), np.uint64)
        self.solid = lazy_zeros((cells, self.words), np.uint64)
        self._mask = np.zeros(self.words, dtype=np.uint64)

    def mask(self, robots: np.ndarray) -> np.ndarray:
        """The bit mask of ``robots`` (int64 ids), for :func:`merge_into_many` (a scratch array: use it before
        the next call)."""
        set_mask(self._mask, robots)
        return self._mask


def no_planes() -> tuple[np.ndarray, np.ndarray]:
    """The empty planes compiled code takes when a run keeps none."""
    return _NO_PLANE, _NO_PLANE


@njit(cache=True)
def set_mask(mask: np.ndarray, robots: np.ndarray) -> None:  # pragma: no cover - compiled
    mask[:] = 0
    for k in range(robots.shape[0]):
        r = robots[k]
        mask[r >> 6] |= np.uint64(1) << np.uint64(r & 63)


@njit(cache=True, inline="always")
def note_raise(free: np.ndarray, solid: np.ndarray, cell: int, robot: int, value: int) -> None:  # pragma: no cover
    """Robot ``robot``'s map now holds ``value`` (FREE or SOLID) at flat ``cell``: its bits, for a writer that
    raised the cell itself (the lidar)."""
    bit = np.uint64(1) << np.uint64(robot & 63)
    free[cell, robot >> 6] |= bit
    if value == SOLID:
        solid[cell, robot >> 6] |= bit


@njit(cache=True)
def merge_into_many(stack: np.ndarray, free: np.ndarray, solid: np.ndarray, mask: np.ndarray, idx: np.ndarray,
                    values: np.ndarray, counts: np.ndarray, dirty: np.ndarray,
                    tile: int) -> None:  # pragma: no cover - compiled
    """Merge (cells ``idx``, ``values``) into the map ``stack[r]`` of every robot r in ``mask``: each cell
    keeps the maximum, as :func:`swarm.knowledge.maps.merge_cells_many` does, but the planes say at once
    which of them it raises, and only those maps are written. ``counts[r]`` (unless empty) changes by the
    FREE cells map r gained less those it lost; ``dirty[r]`` (unless empty) marks the tiles of ``tile`` x
    ``tile`` cells in which map r changed."""
    n, h, w = stack.shape
    _merge_into_many(stack.reshape(-1), h * w, w, idx, free, solid, mask, idx, values, counts, dirty, tile)


@njit(cache=True)
def merge_into_many_tiled(stack: np.ndarray, width: int, offsets: np.ndarray, free: np.ndarray, solid: np.ndarray,
                          mask: np.ndarray, idx: np.ndarray, values: np.ndarray, counts: np.ndarray,
                          dirty: np.ndarray, tile: int) -> None:  # pragma: no cover - compiled
    """:func:`merge_into_many` into a tiled stack ``uint8[R, size]`` (:mod:`swarm.knowledge.tiles`) of maps
    ``width`` cells wide: ``idx`` are row-major cells, as the planes and ``dirty`` use them, and ``offsets``
    where they sit in a tiled map (:meth:`swarm.knowledge.tiles.TiledLayout.offsets`)."""
    _merge_into_many(stack.reshape(-1), stack.shape[1], width, offsets, free, solid, mask, idx, values, counts,
                     dirty, tile)


@njit(cache=True, inline="always")
def _merge_into_many(flat: np.ndarray, size: int, w: int, offsets: np.ndarray, free: np.ndarray, solid: np.ndarray,
                     mask: np.ndarray, idx: np.ndarray, values: np.ndarray, counts: np.ndarray, dirty: np.ndarray,
                     tile: int) -> None:  # pragma: no cover - compiled
    """The body of :func:`merge_into_many` on a flat stack of maps of ``size`` cells, cell ``idx[j]`` written at
    ``offsets[j]`` of a map (``idx`` itself for dense maps)."""
    counting = counts.shape[0] > 0
    marking = dirty.shape[0] > 0
    active = np.empty(mask.shape[0], np.int64)  # the words with a receiver: a spread-out swarm's update reaches
    words = 0                                    # a few dozen robots, a few words of a thousand robots' mask
    for q in range(mask.shape[0]):
        if mask[q] != 0:
            active[words] = q
            words += 1
    one = np.uint64(1)
    receivers = 0
    for a in range(words):
        bits = mask[active[a]]
        while bits:
            bits &= bits - one
            receivers += 1
    if receivers <= FEW_RECEIVERS:
        _merge_map_by_map(flat, size, w, offsets, free, solid, mask, active, words, idx, values, counts, dirty,
                          tile)
        return
    for j in range(idx.shape[0]):
        c = idx[j]
        v = values[j]
        if v == 0:
            continue
        at = offsets[j]
        for a in range(words):
            q = active[a]
            m = mask[q]
            if v == FREE:
                new = m & ~free[c, q]
                was_free = np.uint64(0)
            else:
                new = m & ~solid[c, q]
                was_free = new & free[c, q]
            if new == 0:
                continue
            free[c, q] |= new
            if v == SOLID:
                solid[c, q] |= new
            bits = new
            while bits:
                low = bits & (~bits + one)
                b = _bit_index(low)
                r = q * 64 + b
                flat[r * size + at] = v
                if counting:
                    if v == FREE:
                        counts[r] += 1
                    elif was_free & low:
                        counts[r] -= 1
                if marking:
                    dirty[r, (c // w) // tile, (c % w) // tile] = 1
                bits ^= low


@njit(cache=True)
def _merge_map_by_map(flat: np.ndarray, size: int, w: int, offsets: np.ndarray, free: np.ndarray,
                      solid: np.ndarray, mask: np.ndarray, active: np.ndarray, words: int, idx: np.ndarray,
                      values: np.ndarray, counts: np.ndarray, dirty: np.ndarray,
                      tile: int) -> None:  # pragma: no cover - compiled
    """:func:`_merge_into_many` for a few receivers (:data:`FEW_RECEIVERS`): each receiver's map is read
    where the update has a cell, and the planes are written only where a cell rises."""
    counting = counts.shape[0] > 0
    marking = dirty.shape[0] > 0
    one = np.uint64(1)
    for a in range(words):
        q = active[a]
        bits = mask[q]
        while bits:
            low = bits & (~bits + one)
            r = q * 64 + _bit_index(low)
            base = r * size
            row, row_start, row_end = -1, 0, 0  # the row of the last raised cell (cells mostly ascend)
            for j in range(idx.shape[0]):
                v = values[j]
                at = base + offsets[j]
                cur = flat[at]
                if cur >= v:  # (an UNSEEN value never rises)
                    continue
                c = idx[j]
                flat[at] = v
                free[c, q] |= low
                if v == SOLID:
                    solid[c, q] |= low
                if counting:
                    if v == FREE:
                        counts[r] += 1
                    elif cur == FREE:
                        counts[r] -= 1
                if marking:
                    if c < row_start or c >= row_end:
                        row = c // w
                        row_start = row * w
                        row_end = row_start + w
                    dirty[r, row // tile, (c - row_start) // tile] = 1
            bits ^= low


@njit(cache=True, inline="always")
def _bit_index(low: np.uint64) -> int:  # pragma: no cover - compiled
    """The index of the single set bit of ``low`` (a binary search over the word)."""
    b = 0
    x = low
    if x >> np.uint64(32):
        b += 32
        x >>= np.uint64(32)
    if x >> np.uint64(16):
        b += 16
        x >>= np.uint64(16)
    if x >> np.uint64(8):
        b += 8
        x >>= np.uint64(8)
    if x >> np.uint64(4):
        b += 4
        x >>= np.uint64(4)
    if x >> np.uint64(2):
        b += 2
        x >>= np.uint64(2)
    if x >> np.uint64(1):
        b += 1
    return b


@njit(cache=True)
def book_receivers(robots: np.ndarray, seen_seq: np.ndarray, holds: np.ndarray, sender: int, seq: int,
                   rest: np.ndarray, held: np.ndarray) -> tuple[int, int]:  # pragma: no cover - compiled
    """Book delta ``seq`` of ``sender`` for each receiver in ``robots`` whose last merged update of the sender
    was ``seq - 1`` (:meth:`swarm.comm.sharing.MapSharing._take_delta`): returns how many positions were
    not booked (listed in ``rest``) and how many booked robots hold the sender's whole map (in ``held``)."""
    n_rest = 0
    n_held = 0
    for k in range(robots.shape[0]):
        r = robots[k]
        if seen_seq[r, sender] == seq - 1:
            seen_seq[r, sender] = seq
            if holds[r, sender]:
                held[n_held] = r
                n_held += 1
        else:
            rest[n_rest] = k
            n_rest += 1
    return n_rest, n_held


@njit(cache=True)
def note_cells(free: np.ndarray, solid: np.ndarray, known: np.ndarray, robot: int,
               cells: np.ndarray) -> None:  # pragma: no cover - compiled
    """Set robot ``robot``'s bits of flat ``cells`` from its map ``known`` (flat), after a merge that listed
    the cells it raised without going through the planes."""
    bit = np.uint64(1) << np.uint64(robot & 63)
    q = robot >> 6
    for j in range(cells.shape[0]):
        c = cells[j]
        v = known[c]
        if v >= FREE:
            free[c, q] |= bit
            if v == SOLID:
                solid[c, q] |= bit


@njit(cache=True)
def note_map(free: np.ndarray, solid: np.ndarray, known: np.ndarray, robot: int) -> None:  # pragma: no cover
    """Set robot ``robot``'s bits from its whole map ``known`` (flat): after a write that did not go through
    the planes (a full map merged into it)."""
    bit = np.uint64(1) << np.uint64(robot & 63)
    q = robot >> 6
    for c in range(known.shape[0]):
        v = known[c]
        if v >= FREE:
            free[c, q] |= bit
            if v == SOLID:
                solid[c, q] |= bit


def check_planes(planes: KnowledgePlanes, known: np.ndarray) -> bool:
    """Whether ``planes`` mirror the maps ``known`` (``uint8[R, H, W]``) exactly: for tests."""
    n = known.shape[0]
    flat = known.reshape(n, -1)
    for r in range(n):
        q, bit = r >> 6, np.uint64(1) << np.uint64(r & 63)
        has_free = (planes.free[:, q] & bit) != 0
        has_solid = (planes.solid[:, q] & bit) != 0
        if not (np.array_equal(has_free, flat[r] >= FREE) and np.array_equal(has_solid, flat[r] == SOLID)):
            return False
    return True
