"""Knowledge maps stored by tiles: memory in proportion to what each robot knows.

The dense stack ``uint8[R, H, W]`` is resident page by page, and a 4 KB page holds a row (or more) of one
robot's map: a robot that knows a few cells in each of 300 rows holds 300 pages. A swarm spawned together
knows a tall, narrow region, and its maps hold about ten times the cells they know (docs/performance.md,
"10,000 robots"). The tiled stack keeps each robot's map as ``TILE x TILE``-cell tiles, each one page,
``uint8[R, tiles_h * tiles_w * TILE * TILE]`` allocated lazily (:func:`swarm.util.memory.lazy_zeros`), so
a map costs a page for each 64 x 64 block in which it knows a cell.

Cell ``(row, col)`` of a robot's map sits at offset :func:`tile_offset` of that robot's flat row. Cells
keep their row-major index ``row * W + col`` everywhere outside the stack (messages, planes, journals,
metrics), and the kernels that read or write a map translate at the access.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from swarm.knowledge.packed import differing_words, sync_changes_packed, sync_chunk
from swarm.util.memory import lazy_zeros

TILE_SHIFT = 6
TILE = 1 << TILE_SHIFT
"""Cells per tile side: 64 x 64 one-byte cells fill one 4 KB page."""
TILE_CELLS = TILE * TILE
_MASK = TILE - 1


class TiledLayout:
    """Where each cell of an ``(H, W)`` map sits in a tiled map's flat array."""

    __slots__ = ("shape", "tiles", "size")

    def __init__(self, shape: tuple[int, int]) -> None:
        h, w = int(shape[0]), int(shape[1])
        self.shape = (h, w)
        self.tiles = (-(-h // TILE), -(-w // TILE))
        self.size = self.tiles[0] * self.tiles[1] * TILE_CELLS
        """Cells of one tiled map, padding included (the padding is never written)."""

    def stack(self, n_robots: int) -> np.ndarray:
        """An all-UNSEEN tiled stack ``uint8[n_robots, size]``, resident only where written."""
        return lazy_zeros((n_robots, self.size), np.uint8)

    def offsets(self, cells: np.ndarray) -> np.ndarray:
        """The tiled offsets of row-major ``cells`` (int64)."""
        return tile_offsets(np.ascontiguousarray(cells, dtype=np.int64), self.shape[1], self.tiles[1])

    def cells(self, offsets: np.ndarray) -> np.ndarray:
        """The row-major cells of tiled ``offsets`` (int64): the inverse of :meth:`offsets`."""
        return row_major_cells(np.ascontiguousarray(offsets, dtype=np.int64), self.shape[1], self.tiles[1])

    def untile(self, tiled: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        """One robot's tiled map (flat ``uint8[size]``) as a dense ``uint8[H, W]`` map (into ``out``)."""
        if out is None:
            out = np.empty(self.shape, dtype=np.uint8)
        _copy_tiles(tiled, out, 0, self.tiles[0] - 1, 0, self.tiles[1] - 1, self.tiles[1])  # every cell of out
        return out

    def tile(self, dense: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        """A dense ``uint8[H, W]`` map as a flat tiled map (into ``out``; padding left as it is)."""
        if out is None:
            out = np.zeros(self.size, dtype=np.uint8)
        tile_into(np.ascontiguousarray(dense, dtype=np.uint8), out, self.tiles[1])
        return out


@njit(cache=True, inline="always")
def tile_offset(row: int, col: int, tiles_w: int) -> int:  # pragma: no cover - compiled
    """The offset of cell ``(row, col)`` in a tiled map ``tiles_w`` tiles wide."""
    return ((((row >> TILE_SHIFT) * tiles_w + (col >> TILE_SHIFT)) << (2 * TILE_SHIFT))
            | ((row & _MASK) << TILE_SHIFT) | (col & _MASK))


@njit(cache=True)
def tile_offsets(cells: np.ndarray, width: int, tiles_w: int) -> np.ndarray:  # pragma: no cover - compiled
    out = np.empty(cells.shape[0], dtype=np.int64)
    for k in range(cells.shape[0]):
        row = cells[k] // width
        out[k] = tile_offset(row, cells[k] - row * width, tiles_w)
    return out


@njit(cache=True)
def row_major_cells(offsets: np.ndarray, width: int, tiles_w: int) -> np.ndarray:  # pragma: no cover - compiled
    out = np.empty(offsets.shape[0], dtype=np.int64)
    for k in range(offsets.shape[0]):
        t = offsets[k] >> (2 * TILE_SHIFT)
        within = offsets[k] & (TILE_CELLS - 1)
        tr = t // tiles_w
        row = (tr << TILE_SHIFT) | (within >> TILE_SHIFT)
        col = ((t - tr * tiles_w) << TILE_SHIFT) | (within & _MASK)
        out[k] = row * width + col
    return out


@njit(cache=True)
def tile_into(dense: np.ndarray, out: np.ndarray, tiles_w: int) -> None:  # pragma: no cover - compiled
    h, w = dense.shape
    for row in range(h):
        for col in range(w):
            out[tile_offset(row, col, tiles_w)] = dense[row, col]


def sync_tiles_packed(current: np.ndarray, prev: np.ndarray, layout: TiledLayout, box: np.ndarray | None,
                      dirty: np.ndarray | None, dirty_tile: int) -> np.ndarray:
    """The row-major cells (ascending) where the tiled map ``current`` (flat ``uint8[size]``) differs from its
    2-bit copy ``prev`` (packed in the same tiled order), written into ``prev``: the tiled form of
    :func:`swarm.knowledge.packed.sync_box_tiles_packed` (``box`` rows and columns ``[r0, r1, c0, c1)`` and
    the ``dirty_tile``-cell tiles marked in ``dirty``, each compared as the whole 64 x 64 tiles holding
    them; cells outside are unchanged by the same promise) or, with ``box`` None, of
    :func:`swarm.knowledge.packed.sync_changes_packed` (the whole map)."""
    if box is None:
        offsets = sync_changes_packed(current, prev)
    else:
        offsets = _sync_tiles_kernel(current, prev, box, dirty, dirty_tile, layout.shape[0], layout.shape[1],
                                     layout.tiles[1])
    cells = layout.cells(offsets)
    cells.sort()
    return cells


@njit(cache=True)
def _sync_tiles_kernel(cur: np.ndarray, prev: np.ndarray, box: np.ndarray, dirty: np.ndarray, dirty_tile: int,
                       h: int, w: int, tiles_w: int) -> np.ndarray:  # pragma: no cover - compiled
    tiles_h = cur.shape[0] // (TILE_CELLS * tiles_w)
    chosen = np.zeros(tiles_h * tiles_w, dtype=np.bool_)
    r0, r1, c0, c1 = max(box[0], 0), min(box[1], h), max(box[2], 0), min(box[3], w)
    if r1 > r0 and c1 > c0:
        for tr in range(r0 >> TILE_SHIFT, ((r1 - 1) >> TILE_SHIFT) + 1):
            for tc in range(c0 >> TILE_SHIFT, ((c1 - 1) >> TILE_SHIFT) + 1):
                chosen[tr * tiles_w + tc] = True
    for dr in range(dirty.shape[0]):
        for dc in range(dirty.shape[1]):
            if dirty[dr, dc]:
                chosen[((dr * dirty_tile) >> TILE_SHIFT) * tiles_w + ((dc * dirty_tile) >> TILE_SHIFT)] = True
    n_chosen = 0
    for t in range(chosen.shape[0]):
        n_chosen += chosen[t]
    out = np.empty(n_chosen * TILE_CELLS, dtype=np.int64)
    cur64, prev16 = cur.view(np.uint64), prev.view(np.uint16)
    words = TILE_CELLS // 8
    m = 0
    for t in range(chosen.shape[0]):
        if chosen[t]:
            k0 = t * words
            if differing_words(cur64, prev16, k0, k0 + words):
                m = sync_chunk(cur, prev, cur64, prev16, k0, k0 + words, out, m)
    return out[:m].copy()


class TiledKnowledge:
    """The runtime's maps as a tiled stack, with each robot's extent (the tiles it may have written, grown by
    every writer) so that a robot's dense map can be copied out in proportion to what it knows.

    ``stack``: ``uint8[R, size]``; ``extent``: ``int64[R, 4]`` first and last tile row, first and last tile
    column (empty while first > last). Writers report the boxes of cells they may have changed
    (:meth:`note_boxes`); :meth:`dense` gives robot i's map as a new read-only ``uint8[H, W]`` array."""

    def __init__(self, layout: TiledLayout, n_robots: int) -> None:
        self.layout = layout
        self.stack = layout.stack(n_robots)
        self.extent = np.empty((n_robots, 4), dtype=np.int64)
        self.extent[:, 0::2] = np.iinfo(np.int64).max
        self.extent[:, 1::2] = -1

    def note_boxes(self, robots: np.ndarray, boxes: np.ndarray) -> None:
        """Robots ``robots`` may have written cells in ``boxes`` (int64[k, 4]: rows [r0, r1), columns [c0, c1),
        clipped here to the map; one row per robot, or one row for all)."""
        h, w = self.layout.shape
        b = np.broadcast_to(boxes, (len(robots), 4))
        r0, r1 = np.clip(b[:, 0], 0, h), np.clip(b[:, 1], 0, h)
        c0, c1 = np.clip(b[:, 2], 0, w), np.clip(b[:, 3], 0, w)
        some = (r1 > r0) & (c1 > c0)
        if not some.all():
            robots, r0, r1, c0, c1 = robots[some], r0[some], r1[some], c0[some], c1[some]
        ext = self.extent
        np.minimum.at(ext[:, 0], robots, r0 >> TILE_SHIFT)
        np.maximum.at(ext[:, 1], robots, (r1 - 1) >> TILE_SHIFT)
        np.minimum.at(ext[:, 2], robots, c0 >> TILE_SHIFT)
        np.maximum.at(ext[:, 3], robots, (c1 - 1) >> TILE_SHIFT)

    def note_cells(self, robots: np.ndarray, cells: np.ndarray) -> None:
        """Robots ``robots`` may have written some of the row-major ``cells``."""
        if len(cells) and len(robots):
            w = self.layout.shape[1]
            rows = cells // w
            cols = cells - rows * w
            box = np.array([[rows.min(), rows.max() + 1, cols.min(), cols.max() + 1]], dtype=np.int64)
            self.note_boxes(np.asarray(robots, dtype=np.int64), box)

    def dense(self, i: int) -> np.ndarray:
        """Robot i's map, ``uint8[H, W]``, a new array (only the tiles of its extent are copied)."""
        out = np.zeros(self.layout.shape, dtype=np.uint8)
        tr0, tr1, tc0, tc1 = (int(v) for v in self.extent[i])
        if tr1 >= tr0 and tc1 >= tc0:
            _copy_tiles(self.stack[i], out, tr0, tr1, tc0, tc1, self.layout.tiles[1])
        return out


@njit(cache=True)
def _copy_tiles(tiled: np.ndarray, out: np.ndarray, tr0: int, tr1: int, tc0: int, tc1: int,
                tiles_w: int) -> None:  # pragma: no cover - compiled
    h, w = out.shape
    for tr in range(tr0, tr1 + 1):
        for tc in range(tc0, tc1 + 1):
            base = (tr * tiles_w + tc) * TILE_CELLS
            c0 = tc << TILE_SHIFT
            m = min(TILE, w - c0)
            for dr in range(TILE):
                row = (tr << TILE_SHIFT) + dr
                if row >= h:
                    break
                src = base + (dr << TILE_SHIFT)
                out[row, c0:c0 + m] = tiled[src:src + m]  # (a slice a tile row: 8x the cell-by-cell loop)


@njit(cache=True)
def cells_below_tiled(flat: np.ndarray, base: np.uint64, cells: np.ndarray, lo: int, hi: int, limit: int,
                      width: int, tiles_w: int) -> bool:  # pragma: no cover - compiled
    """:func:`swarm.world.motion.cells_below` on a tiled map (row-major ``cells``)."""
    for i in range(lo, hi):
        c = cells[i]
        if flat[base + np.uint64(tile_offset(c // width, c % width, tiles_w))] >= limit:
            return False
    return True
