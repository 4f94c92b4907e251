"""Where each robot's knowledge map may have changed, so that a reader diffs only those places.

A run writes robots' maps in two ways: the lidar, within ``reach`` cells of where each robot it cast
believes it is, and merges of the map updates (or MAES's messages) it delivered. A
:class:`KnowledgeJournal` notes both as tiles of ``TILE x TILE`` cells per robot, plus a flag for "any
cell may have changed" (a full map merged, or no history yet), and :meth:`KnowledgeJournal.take` compares
only the noted tiles of each noted robot with the caller's mirror.

Why: the recorder used to compare every robot's whole map with its mirror every tick, R x H x W bytes
(1.4 GB a tick for 1,000 robots on a 600 m building), which held a swarm's recording to 1-2 ticks/s
(issue 47). The journal's cost is the cells it notes, not the map's area. Noting is an over-approximation
(a noted cell need not have changed), so what :meth:`take` returns is exactly what a whole-map diff
returns: the cells that differ from the mirror, in ascending order.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np
from numba import njit

from swarm.base.types import CELL_M
from swarm.util.memory import lazy_zeros

TILE = 16
"""Side of a journal tile in cells: a lidar window (~45 cells) spans 3-4 tiles a side, 1.2-1.6x its area."""


class KnowledgeJournal:
    """Per robot, the tiles of its map written since the last :meth:`take` (module docstring).

    ``n`` robots with maps ``shape`` (rows, columns); ``reach``: cells around a robot's believed position
    its lidar may write. It starts with every robot flagged whole: the caller's mirror has no history.
    """

    def __init__(self, n: int, shape: tuple[int, int], reach: int) -> None:
        self.n, self.shape, self.reach = n, (int(shape[0]), int(shape[1])), int(reach)
        self.tile_rows, self.tile_cols = -(-self.shape[0] // TILE), -(-self.shape[1] // TILE)
        self.tiles = lazy_zeros((n, self.tile_rows * self.tile_cols), np.uint8)
        self.whole = np.ones(n, dtype=np.bool_)
        self.noted = np.zeros(n, dtype=np.bool_)
        self.band = np.zeros((n, 2), dtype=np.int64)  # per robot: the tile rows [band0, band1) holding its notes
        self._scratch = np.zeros(self.tile_rows * self.tile_cols, dtype=np.uint8)
        self._found = np.empty(self.tile_rows * self.tile_cols, dtype=np.int64)

    def scanned(self, poses: np.ndarray, cast: np.ndarray) -> None:
        """The lidar wrote from ``poses`` (``float64[R, 3]``, where each robot believes it is) for the robots
        ``cast`` (``bool[R]``): note each one's window."""
        _note_windows(self.tiles, self.noted, self.band, np.ascontiguousarray(poses, dtype=np.float64),
                      np.ascontiguousarray(cast, dtype=np.bool_), self.reach, CELL_M, self.shape[0], self.shape[1],
                      self.tile_cols, TILE)

    def merged(self, receivers: Sequence[int] | np.ndarray, cells: np.ndarray | None) -> None:
        """A map update reached ``receivers`` and was merged: ``cells`` (flat indices it carried) are noted for
        each of them, or, for a full map (None), their whole maps are flagged."""
        rows = np.asarray(receivers, dtype=np.int64)
        if not len(rows):
            return
        if cells is None:
            self.whole[rows] = True
        elif len(cells):
            _note_cells(self.tiles, self.noted, self.band, rows, np.ascontiguousarray(cells, dtype=np.int64),
                        self.shape[1], self.tile_cols, TILE, self._scratch, self._found)

    def rewritten(self, robots: Sequence[int] | np.ndarray) -> None:
        """Any cell of these robots' maps may have changed (e.g. MAES's merges)."""
        self.whole[np.asarray(robots, dtype=np.int64)] = True

    def take(self, known: np.ndarray, mirror: np.ndarray) -> np.ndarray:
        """Sorted flat indices into ``known`` (``uint8[R, H, W]``) of the cells that differ from ``mirror``
        (same shape, C-contiguous), copied into it; the journal is emptied. Cells not noted are assumed
        equal: ``mirror`` must have followed ``known`` through every earlier take."""
        if known.shape != mirror.shape or known.shape[1:] != self.shape or known.shape[0] != self.n:
            raise ValueError(f"known {known.shape} and mirror {mirror.shape} must both be {(self.n, *self.shape)}")
        robots = np.flatnonzero(self.noted | self.whole)
        if not len(robots):
            return np.zeros(0, dtype=np.int64)
        out = _take_kernel(np.ascontiguousarray(known), mirror, self.tiles, self.band, self.whole, robots,
                           self.tile_cols, TILE)
        self.noted[robots] = False
        self.whole[robots] = False
        return out


@njit(cache=True, inline="always")
def _widen(noted: np.ndarray, band: np.ndarray, r: int, t0: int, t1: int) -> None:  # pragma: no cover
    """Robot r has notes in tile rows [t0, t1)."""
    if not noted[r]:
        noted[r] = True
        band[r, 0], band[r, 1] = t0, t1
    else:
        band[r, 0], band[r, 1] = min(band[r, 0], t0), max(band[r, 1], t1)


@njit(cache=True)
def _note_windows(tiles: np.ndarray, noted: np.ndarray, band: np.ndarray, poses: np.ndarray, cast: np.ndarray,
                  reach: int, cell_m: float, h: int, w: int, tile_cols: int, tile: int) -> None:  # pragma: no cover
    for r in range(poses.shape[0]):
        if not cast[r]:
            continue
        row, col = int(poses[r, 1] / cell_m), int(poses[r, 0] / cell_m)  # truncation, as the runtime's boxes
        r0, r1 = max(row - reach, 0), min(row + reach + 1, h)
        c0, c1 = max(col - reach, 0), min(col + reach + 1, w)
        if r0 >= r1 or c0 >= c1:
            continue
        _widen(noted, band, r, r0 // tile, (r1 - 1) // tile + 1)
        for tr in range(r0 // tile, (r1 - 1) // tile + 1):
            for tc in range(c0 // tile, (c1 - 1) // tile + 1):
                tiles[r, tr * tile_cols + tc] = 1


@njit(cache=True)
def _note_cells(tiles: np.ndarray, noted: np.ndarray, band: np.ndarray, receivers: np.ndarray, idx: np.ndarray,
                w: int, tile_cols: int, tile: int, scratch: np.ndarray, found: np.ndarray) -> None:  # pragma: no cover
    """The tiles of cells ``idx`` (each found once), noted for every receiver: O(cells + receivers x tiles)."""
    m = 0
    t0, t1 = 1 << 62, 0
    for k in range(idx.shape[0]):
        cell = idx[k]
        tr = cell // w // tile
        t = tr * tile_cols + (cell % w) // tile
        if scratch[t] == 0:
            scratch[t] = 1
            found[m] = t
            m += 1
            t0, t1 = min(t0, tr), max(t1, tr + 1)
    for j in range(receivers.shape[0]):
        r = receivers[j]
        _widen(noted, band, r, t0, t1)
        for q in range(m):
            tiles[r, found[q]] = 1
    for q in range(m):
        scratch[found[q]] = 0


@njit(cache=True)
def _take_kernel(known: np.ndarray, mirror: np.ndarray, tiles: np.ndarray, band: np.ndarray, whole: np.ndarray,
                 robots: np.ndarray, tile_cols: int, tile: int) -> np.ndarray:  # pragma: no cover - compiled
    """Row by row over each listed robot's noted tiles (all, if whole): the differing cells in ascending
    flat order, the mirror updated; the robots' tiles cleared. Runs of adjacent noted tiles are one span
    per row, compared 8 cells at a time where the words are equal."""
    _, h, w = known.shape
    cur = known.reshape(-1)
    mir = mirror.reshape(-1)
    words = cur.shape[0] // 8
    cur64 = cur[:8 * words].view(np.uint64)
    mir64 = mir[:8 * words].view(np.uint64)
    out = np.empty(1024, dtype=np.int64)
    k = 0
    tile_rows = -(-h // tile)
    spans = np.empty((tile_cols + 1, 2), dtype=np.int64)
    for j in range(robots.shape[0]):
        r = robots[j]
        every = whole[r]
        base = r * h * w
        t0, t1 = (0, tile_rows) if every else (band[r, 0], band[r, 1])
        for tr in range(t0, t1):
            m = 0  # this tile row's runs of noted tiles, as cell columns [c0, c1)
            tc = 0
            while tc < tile_cols:
                if every or tiles[r, tr * tile_cols + tc]:
                    start = tc
                    while tc < tile_cols and (every or tiles[r, tr * tile_cols + tc]):
                        if tiles[r, tr * tile_cols + tc]:
                            tiles[r, tr * tile_cols + tc] = 0  # (a page never written stays unallocated)
                        tc += 1
                    spans[m, 0], spans[m, 1] = start * tile, min(w, tc * tile)
                    m += 1
                else:
                    tc += 1
            for row in range(tr * tile, min(h, (tr + 1) * tile)):
                for s in range(m):
                    i = base + row * w + spans[s, 0]
                    b = base + row * w + spans[s, 1]
                    head = min(b, (i + 7) & ~7)  # bytes up to the first whole word, then word by word
                    out, k = _diff_bytes(cur, mir, i, head, out, k)
                    i = head
                    while i < b:
                        if i + 8 <= b and cur64[i >> 3] == mir64[i >> 3]:
                            i += 8
                            continue
                        out, k = _diff_bytes(cur, mir, i, min(b, i + 8), out, k)
                        i = min(b, i + 8)
    return out[:k].copy()


@njit(cache=True, inline="always")
def _diff_bytes(cur: np.ndarray, mir: np.ndarray, a: int, b: int, out: np.ndarray,
                k: int) -> tuple[np.ndarray, int]:  # pragma: no cover - compiled
    """Cells ``a..b-1`` that differ: appended to ``out[k:]`` (grown when full), copied into the mirror."""
    for i in range(a, b):
        if cur[i] != mir[i]:
            mir[i] = cur[i]
            if k == out.shape[0]:
                grown = np.empty(2 * k, dtype=np.int64)
                grown[:k] = out
                out = grown
            out[k] = i
            k += 1
    return out, k
