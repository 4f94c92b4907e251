"""Wall crossings along straight segments: an exact grid walk over the map's 0.5 m cell raster (numba).

Why a raster walk: walls are solid cells, and the exact Amanatides-Woo traversal ("A fast voxel traversal
algorithm for ray tracing", Eurographics 1987) visits every cell a segment passes through, with the length
of the segment inside each, in O(cells crossed). A numba grid walk is the fast path for the radio, far
ahead of numpy segment tests and pymunk queries (docs/measurements.md section C2).

Leaping (our analogue of C2's "edge grid", which needs walls on tile boundaries; we must also serve
imported 0.5 m maps): every cell knows the uniform one-material rectangles that open from it into each
quadrant (:mod:`radio.blocks`), and the walk crosses a whole rectangle per loop iteration: a room in one or
two leaps, a wall in one or two. Each leap's length goes to the gap or to the run's material, exactly as
the cell-by-cell walk would add it up, so results do not change (tested against the plain walk and against
dense sampling).

**What counts as a wall crossing** (the issue's definition, made robust to the raster):

- Along the segment, every maximal run of solid cells is one wall crossing. A run through several
  materials is a crossing of each material whose share of the run is longer than the tolerance (or, if
  none is, of the longest one).
- Tolerance ``tol`` (default 0.05 m, :data:`DEFAULT_GRAZE_TOLERANCE_M`): a run whose solid length is at most
  ``tol`` is a corner graze and is ignored; a free sliver of at most ``tol`` inside a run (e.g. a segment
  running along a staircase-shaped diagonal wall, between the corners of its cells) does not split it.
  A straight wall at least one cell thick gives at least 0.5 m of solid path at any angle, and a free gap
  between two such walls at least 0.5 m, so for walls and gaps of whole cells the crossing count does not
  depend on the crossing angle or on where the segment cuts the raster. Only cuts through a wall's corner
  of at most ``tol`` are dropped (at 45 degrees: corners cut at most ``tol / 2`` = 2.5 cm deep).
- Known limit: a diagonal wall one cell thick whose cells touch only at corners is porous where a segment
  crosses it within ``tol / 2`` of a shared corner (the segment meets no cell, or only a sliver of one).
  Generated maps have no such walls; thicken them when importing plans drawn with 1-pixel diagonals.
- Walls are open sets: touching is not crossing. Exactly through a cell corner, the walk steps diagonally
  and visits no cell for a zero length. A segment lying exactly on a cell boundary (horizontal on a grid
  row line, or vertical on a grid column line) is inside a wall only where the cells on **both** sides
  are solid, so a segment running along a wall's face does not cross it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from typing import NamedTuple

import numpy as np
from numba import njit

from maps.model import CELL_M, Map
from maps.rects import merge_rectangles

from .blocks import single_cell_blocks, uniform_blocks

_NO_DB = np.zeros(2, dtype=np.float64)
"""The material prices :func:`_radio_walk_segment` passes to the shared walk, which does not read them."""
DEFAULT_GRAZE_TOLERANCE_M = 0.05
"""Solid runs and free gaps at most this long (metres along the segment) are ignored / bridged."""


# ------------------------------------------------------------------------------------- kernels ----
@njit(cache=True)
def _radio_close_run(n: int, solid_len: float, tol: float) -> int:
    """Keep the run just finished iff its solid length exceeds the graze tolerance."""
    return n + 1 if solid_len > tol else n


@njit(cache=True, inline="always")
def _radio_walk_segment(blocks, cell, x0, y0, x1, y1, tol, run_start, run_end, run_len):  # pragma: no cover
    """Walk the segment (x0, y0) -> (x1, y1) over the raster described by ``blocks`` (:mod:`radio.blocks`).

    Writes kept runs into ``run_start[k]``, ``run_end[k]`` (metres from the start) and ``run_len[k, m]``
    (metres of material ``m`` inside run ``k``); returns the number of kept runs.

    Each iteration crosses one uniform rectangle ahead of the current cell (one cell with
    :func:`radio.blocks.single_cell_blocks`: plain Amanatides-Woo) and moves to the cell the segment enters
    next. Boundaries are recomputed from integer indices every time, so no rounding accumulates.
    """
    return _radio_walk(blocks, cell, x0, y0, x1, y1, tol, run_start, run_end, run_len, _NO_DB, _NO_DB, False,
                       0.0, 0.0, 0.0, 0.0, False)[0]


@njit(cache=True, inline="always")
def _radio_price_run(acc, k, run_len, tol, cross_db, metre_db, per_metre):  # pragma: no cover
    """``acc`` plus the dB :func:`_radio_price_runs` charges run ``k``, added term by term in its order, so
    a running total over the runs is its sum bit for bit."""
    n_mat = run_len.shape[1]
    if per_metre:
        for m in range(1, n_mat):
            acc += run_len[k, m] * metre_db[m]
        return acc
    best = 1
    best_len = -1.0
    charged = False
    for m in range(1, n_mat):
        a = run_len[k, m]
        if a > best_len:
            best_len = a
            best = m
        if a > tol:
            charged = True
            acc += cross_db[m]
    if not charged:
        acc += cross_db[best]
    return acc


@njit(cache=True, inline="always")
def _radio_walk_until(blocks, cell, x0, y0, x1, y1, tol, run_start, run_end, run_len, cross_db, metre_db, per_metre,
                      a1, s1, a2, s2):  # pragma: no cover
    """:func:`_radio_walk_segment` for the link question alone: each kept run is priced as it closes (as
    :func:`_radio_price_runs` prices it, in the same order, so the running sum is a prefix of its sum), and
    the walk stops once neither direction can still link: ``a1 - dB < s1`` and ``a2 - dB < s2`` (``a`` a
    transmitter's power less the path loss, ``s`` the receiver's sensitivity). Wall dB only grow along
    the walk and these tests only fail more as they grow, so a stopped walk's links are the whole walk's.
    Returns (kept runs so far, dB so far, stopped early). A long segment through a building (most pairs of
    a spread-out swarm) stops after the few walls that exhaust its budget."""
    return _radio_walk(blocks, cell, x0, y0, x1, y1, tol, run_start, run_end, run_len, cross_db, metre_db, per_metre,
                       a1, s1, a2, s2, True)


@njit(cache=True, inline="always")
def _radio_walk(blocks, cell, x0, y0, x1, y1, tol, run_start, run_end, run_len, cross_db, metre_db, per_metre,
                a1, s1, a2, s2, price):  # pragma: no cover
    """The one traversal behind :func:`_radio_walk_segment` (``price`` False: every kept run, no pricing)
    and :func:`_radio_walk_until` (``price`` True: runs priced as they close, the walk stopped once neither
    direction can link). Returns (kept runs, dB priced, stopped early)."""
    rows = blocks.shape[1]
    cols = blocks.shape[2]
    dx = x1 - x0
    dy = y1 - y0
    length = math.sqrt(dx * dx + dy * dy)
    if length == 0.0:
        return 0, 0.0, False
    inv_cell = 1.0 / cell
    xs = x0 * inv_cell  # the walk runs in cell units
    ys = y0 * inv_cell
    dxs = dx * inv_cell
    dys = dy * inv_cell
    col = min(max(int(math.floor(xs)), 0), cols - 1)
    row = min(max(int(math.floor(ys)), 0), rows - 1)
    step_x = 1 if dx > 0.0 else (-1 if dx < 0.0 else 0)
    step_y = 1 if dy > 0.0 else (-1 if dy < 0.0 else 0)
    # the segment meets grid column line i at t = i * sx + cx (never, t = inf, if dx = 0); same for rows
    sx = 1.0 / dxs if dx != 0.0 else 0.0
    sy = 1.0 / dys if dy != 0.0 else 0.0
    cx = -xs * sx if dx != 0.0 else np.inf
    cy = -ys * sy if dy != 0.0 else np.inf
    off_x = 0 if step_x > 0 else 1  # the far side of a block w cells wide is grid line col + step_x * w + off_x
    off_y = 0 if step_y > 0 else 1
    # A segment lying on a grid line is inside a wall only where the cells on both sides are solid; such
    # segments walk cell by cell, comparing both neighbours.
    on_row_line = dy == 0.0 and ys == math.floor(ys) and row > 0
    on_col_line = dx == 0.0 and xs == math.floor(xs) and col > 0
    on_line = on_row_line or on_col_line
    q = (2 if step_x < 0 else 0) + (1 if step_y < 0 else 0)  # indexed, not sliced: views cost refcounting
    n_mat = run_len.shape[1]
    n = 0
    priced = 0
    db = 0.0
    in_run = False
    gap = 0.0
    solid_len = 0.0
    t = 0.0
    while True:
        m = int(blocks[q, row, col, 0])
        if on_line:
            k = 1
            wide = 1
            tall = 1
            if m != 0 and on_row_line and blocks[q, row - 1, col, 0] == 0:
                m = 0
            if m != 0 and on_col_line and blocks[q, row, col - 1, 0] == 0:
                m = 0
        else:
            k = int(blocks[q, row, col, 1])
            wide = int(blocks[q, row, col, 2])
            tall = int(blocks[q, row, col, 3])
        # where the segment leaves rectangle A (wide x k) and rectangle B (k x tall); leap through the one
        # it stays in longer
        ax = (col + step_x * wide + off_x) * sx + cx
        bx = (col + step_x * k + off_x) * sx + cx
        ay = (row + step_y * k + off_y) * sy + cy
        by = (row + step_y * tall + off_y) * sy + cy
        t_a = min(ax, ay)
        t_b = min(bx, by)
        if t_a >= t_b:
            w = wide
            h = k
            ex = ax
            ey = ay
            t_next = t_a
        else:
            w = k
            h = tall
            ex = bx
            ey = by
            t_next = t_b
        if t_next > 1.0:
            t_next = 1.0
        if t_next < t:
            t_next = t
        seg = (t_next - t) * length
        if m != 0:
            if not in_run:
                in_run = True
                run_start[n] = t * length
                for j in range(n_mat):
                    run_len[n, j] = 0.0
                solid_len = 0.0
            gap = 0.0
            run_len[n, m] += seg
            solid_len += seg
            run_end[n] = t_next * length
        elif in_run:
            gap += seg
            if gap > tol:
                n = _radio_close_run(n, solid_len, tol)
                in_run = False
                if price and n > priced:
                    db = _radio_price_run(db, priced, run_len, tol, cross_db, metre_db, per_metre)
                    priced = n
                    if a1 - db < s1 and a2 - db < s2:
                        return n, db, True
        if t_next >= 1.0:
            break
        # the next cell: across the rectangle's x side, its y side, or exactly its corner. Coordinates are
        # >= 0 inside the map, so int() truncation is floor() (and cheaper); the clamp keeps the cell on
        # the rectangle's side whatever the rounding.
        if ex < ey:
            if h > 1:
                lo_r = row - h + 1 if step_y < 0 else row
                row = min(max(int(ys + t_next * dys), lo_r), lo_r + h - 1)
            col += step_x * w
        elif ey < ex:
            if w > 1:
                lo_c = col - w + 1 if step_x < 0 else col
                col = min(max(int(xs + t_next * dxs), lo_c), lo_c + w - 1)
            row += step_y * h
        else:
            col += step_x * w
            row += step_y * h
        t = t_next
        if col < 0 or col >= cols or row < 0 or row >= rows:
            break
    if in_run:
        n = _radio_close_run(n, solid_len, tol)
        if price and n > priced:
            db = _radio_price_run(db, priced, run_len, tol, cross_db, metre_db, per_metre)
    return n, db, False


@njit(cache=True, inline="always")
def _radio_price_runs(n, run_len, tol, cross_db, metre_db, per_metre, counts, i, j):  # pragma: no cover
    """dB charged for ``n`` kept runs; adds one to ``counts[i, j, m]`` for every material crossing charged.

    Crossing mode: each material longer than ``tol`` in a run costs its crossing figure once (the longest
    material if none is). Per-metre mode: every metre of every material in a kept run costs ``metre_db``.
    """
    n_mat = run_len.shape[1]
    crossing = 0.0
    metres = 0.0
    for k in range(n):
        best = 1
        best_len = -1.0
        charged = False
        for m in range(1, n_mat):
            a = run_len[k, m]
            metres += a * metre_db[m]
            if a > best_len:
                best_len = a
                best = m
            if a > tol:
                charged = True
                counts[i, j, m] += 1
                crossing += cross_db[m]
        if not charged:
            counts[i, j, best] += 1
            crossing += cross_db[best]
    return metres if per_metre else crossing


@njit(cache=True, inline="always")
def _run_buffers(blocks, n_mat):  # pragma: no cover - compiled
    """Scratch for :func:`_radio_walk_segment`: run starts, ends and per-material lengths, enough for any
    segment on this raster (it crosses at most rows + cols + 2 runs)."""
    cap = blocks.shape[1] + blocks.shape[2] + 2
    return np.empty(cap), np.empty(cap), np.empty((cap, n_mat))


@njit(cache=True, inline="always")
def _distance(x0, y0, x1, y1):  # pragma: no cover - compiled
    """Euclidean distance; one definition, so every matrix and the in-range walk agree bit for bit."""
    ddx = x1 - x0
    ddy = y1 - y0
    return math.sqrt(ddx * ddx + ddy * ddy)


@njit(cache=True, inline="always")
def _radio_pair(blocks, cell, xy, a, b, tol, cross_db, metre_db, per_metre, run_start, run_end, run_len, counts, i,
                j):  # pragma: no cover - compiled
    """One robot pair as every matrix computes it: (distance, walls crossed, dB charged) of the walk from
    robot ``a`` to robot ``b`` (``a < b``), with ``counts[i, j]`` set to its material crossings."""
    n = _radio_walk_segment(blocks, cell, xy[a, 0], xy[a, 1], xy[b, 0], xy[b, 1], tol, run_start, run_end, run_len)
    for m in range(counts.shape[2]):
        counts[i, j, m] = 0
    db = _radio_price_runs(n, run_len, tol, cross_db, metre_db, per_metre, counts, i, j)
    return _distance(xy[a, 0], xy[a, 1], xy[b, 0], xy[b, 1]), n, db


@njit(cache=True)
def _radio_all_pairs(blocks, cell, xy, tol, cross_db, metre_db, per_metre,
                     distance, walls, wall_db, counts):  # pragma: no cover
    """Fill the symmetric all-pairs matrices (each unordered pair is walked once, from i to j > i)."""
    n_robots = xy.shape[0]
    n_mat = cross_db.shape[0]
    run_start, run_end, run_len = _run_buffers(blocks, n_mat)
    for i in range(n_robots):
        distance[i, i] = 0.0
        walls[i, i] = 0
        wall_db[i, i] = 0.0
        for m in range(n_mat):
            counts[i, i, m] = 0
        for j in range(i + 1, n_robots):
            d, n, db = _radio_pair(blocks, cell, xy, i, j, tol, cross_db, metre_db, per_metre, run_start, run_end,
                                   run_len, counts, i, j)
            for m in range(n_mat):
                counts[j, i, m] = counts[i, j, m]
            distance[i, j] = d
            distance[j, i] = d
            walls[i, j] = n
            walls[j, i] = n
            wall_db[i, j] = db
            wall_db[j, i] = db


@njit(cache=True)
def _radio_pairs_with(blocks, cell, xy, tol, cross_db, metre_db, per_metre, senders, distance, walls,
                      wall_db):  # pragma: no cover
    """Columns of :func:`_radio_all_pairs`' matrices for the robots ``senders`` only: ``distance[i, k]``,
    ``walls[i, k]`` and ``wall_db[i, k]`` for the pair (i, senders[k]), by the same :func:`_radio_pair`
    from the lower index to the higher, so the numbers are its numbers bit for bit."""
    n_robots = xy.shape[0]
    n_mat = cross_db.shape[0]
    run_start, run_end, run_len = _run_buffers(blocks, n_mat)
    counts = np.zeros((1, 1, n_mat), np.int32)
    for k in range(senders.shape[0]):
        j = senders[k]
        for i in range(n_robots):
            if i == j:
                distance[i, k] = 0.0
                walls[i, k] = 0
                wall_db[i, k] = 0.0
                continue
            d, n, db = _radio_pair(blocks, cell, xy, min(i, j), max(i, j), tol, cross_db, metre_db, per_metre,
                                   run_start, run_end, run_len, counts, 0, 0)
            distance[i, k] = d
            walls[i, k] = n
            wall_db[i, k] = db


@njit(cache=True)
def _radio_clear_within(blocks, cell, xy, tol, n_mat, max_distance, distance, clear):  # pragma: no cover
    """Fill ``distance`` (all pairs, as :func:`_radio_all_pairs` computes it) and ``clear[i, j]``: i != j, at
    most ``max_distance`` apart and no wall crossed. Only pairs within range are walked (the same walk from
    i to j > i), so a sensing-range question costs short walks instead of the all-pairs picture."""
    n_robots = xy.shape[0]
    run_start, run_end, run_len = _run_buffers(blocks, n_mat)
    for i in range(n_robots):
        distance[i, i] = 0.0
        clear[i, i] = False
        for j in range(i + 1, n_robots):
            d = _distance(xy[i, 0], xy[i, 1], xy[j, 0], xy[j, 1])
            seen = False
            if d <= max_distance:
                seen = _radio_walk_segment(blocks, cell, xy[i, 0], xy[i, 1], xy[j, 0], xy[j, 1], tol,
                                           run_start, run_end, run_len) == 0
            distance[i, j] = d
            distance[j, i] = d
            clear[i, j] = seen
            clear[j, i] = seen


@njit(cache=True)
def _radio_bucket_robots(xy, side, gx, gy, order, starts):  # pragma: no cover - compiled
    """Robots by square bucket of ``side`` metres (``gx`` x ``gy`` of them, positions clamped onto the grid),
    in robot order within one: bucket b holds ``order[starts[b]:starts[b + 1]]``. A counting sort, shared by
    the link matrix's reach buckets and :class:`radio.models.SightIndex`."""
    n = xy.shape[0]
    starts[:] = 0
    for i in range(n):
        b = _bucket_of(xy[i, 0], xy[i, 1], side, gx, gy)
        starts[b + 1] += 1
    for b in range(gx * gy):
        starts[b + 1] += starts[b]
    fill = starts[:-1].copy()
    for i in range(n):
        b = _bucket_of(xy[i, 0], xy[i, 1], side, gx, gy)
        order[fill[b]] = i
        fill[b] += 1


@njit(cache=True, inline="always")
def _bucket_of(x, y, side, gx, gy):  # pragma: no cover - compiled
    return min(max(int(x / side), 0), gx - 1) * gy + min(max(int(y / side), 0), gy - 1)


@njit(cache=True)
def _radio_clear_near(blocks, cell, xy, tol, n_mat, max_distance, row, range_m, side, gx, gy, order, starts,
                      cols, dist):  # pragma: no cover - compiled
    """:func:`_radio_clear_within`'s row ``row`` restricted to robots nearer than ``range_m``: the robots j
    with ``clear[row, j]`` and ``distance[row, j] < range_m``, ascending, into ``cols`` and their distances
    into ``dist``; returns how many. The same values bit for bit (the distance and the walk of the pair
    from its lower index), but only the robots of the buckets within ``range_m`` are looked at."""
    k = int(math.ceil(range_m / side)) + 1  # (a rounded distance below range_m cannot hide one more bucket)
    b = _bucket_of(xy[row, 0], xy[row, 1], side, gx, gy)
    bx, by = b // gy, b % gy
    count = 0
    run_start = np.empty(0)
    run_end = np.empty(0)
    run_len = np.empty((0, n_mat))
    for ix in range(max(bx - k, 0), min(bx + k + 1, gx)):
        for iy in range(max(by - k, 0), min(by + k + 1, gy)):
            q = ix * gy + iy
            for t in range(starts[q], starts[q + 1]):
                j = order[t]
                if j == row:
                    continue
                lo, hi = (row, j) if row < j else (j, row)
                d = _distance(xy[lo, 0], xy[lo, 1], xy[hi, 0], xy[hi, 1])
                if not (d < range_m and d <= max_distance):
                    continue
                if run_start.shape[0] == 0:
                    run_start, run_end, run_len = _run_buffers(blocks, n_mat)
                if _radio_walk_segment(blocks, cell, xy[lo, 0], xy[lo, 1], xy[hi, 0], xy[hi, 1], tol,
                                       run_start, run_end, run_len) != 0:
                    continue
                m = count  # insertion in robot order
                while m > 0 and cols[m - 1] > j:
                    cols[m] = cols[m - 1]
                    dist[m] = dist[m - 1]
                    m -= 1
                cols[m] = j
                dist[m] = d
                count += 1
    return count


@njit(cache=True)
def _radio_one_to_many(blocks, cell, x0, y0, targets, tol, cross_db, metre_db, per_metre,
                       distance, walls, wall_db):  # pragma: no cover
    """Walk from one point to each target (the heatmap's inner loop)."""
    n_mat = cross_db.shape[0]
    run_start, run_end, run_len = _run_buffers(blocks, n_mat)
    counts = np.zeros((1, 1, n_mat), dtype=np.int32)  # not reported: the heatmap needs dB only
    for i in range(targets.shape[0]):
        distance[i] = _distance(x0, y0, targets[i, 0], targets[i, 1])
        n = _radio_walk_segment(blocks, cell, x0, y0, targets[i, 0], targets[i, 1], tol,
                                run_start, run_end, run_len)
        walls[i] = n
        wall_db[i] = _radio_price_runs(n, run_len, tol, cross_db, metre_db, per_metre, counts, 0, 0)


# ------------------------------------------------------------------------------------- Python ----
class WallCrossing(NamedTuple):
    """One wall crossed by a segment, in order along it.

    ``start_m`` / ``end_m``: where the wall's solid run begins and ends, metres from the segment's start;
    ``materials``: (name, metres of path) for each material in the run; ``charged``: the materials the
    model charged a crossing for; ``db``: the attenuation charged for this wall.
    """

    start_m: float
    end_m: float
    materials: tuple[tuple[str, float], ...]
    charged: tuple[str, ...]
    db: float


@dataclass(frozen=True, eq=False)
class WallRaster:
    """The map's raster prepared for walking: per quadrant, each cell's material and uniform blocks."""

    blocks: np.ndarray
    names: tuple[str, ...]
    cell_m: float = CELL_M

    @classmethod
    def from_map(cls, m: Map, skip_empty_space: bool = True) -> "WallRaster":
        """Prepare ``m`` (a few ms for 300 x 300 cells). ``skip_empty_space=False`` walks cell by cell."""
        build = uniform_blocks if skip_empty_space else single_cell_blocks
        return cls(build(m.material), tuple(m.materials))

    @property
    def n_materials(self) -> int:
        return len(self.names)

    @cached_property
    def free_ids(self) -> np.ndarray:
        """int32[H, W]: the free cells cut into rectangles (:func:`maps.rects.merge_rectangles`), each cell
        labelled with its rectangle (1, 2, ...; 0 for solid). A segment between two points of one rectangle
        crosses no wall (a rectangle is convex), so the link kernels need not walk it: most pairs of a swarm
        gathered in a hall."""
        free = (self.blocks[0, :, :, 0] == 0).astype(np.uint8)
        ids = np.zeros(free.shape, dtype=np.int32)
        for k, rect in enumerate(merge_rectangles(free), start=1):
            ids[rect.row0:rect.row1, rect.col0:rect.col1] = k
        return ids

    def _capacity(self) -> int:
        return self.blocks.shape[1] + self.blocks.shape[2] + 2  # more than the runs any segment can have

    def trace(self, p: tuple[float, float], q: tuple[float, float],
              tol: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Runs kept from ``p`` to ``q``: (start_m[n], end_m[n], metres per material float64[n, M])."""
        cap = self._capacity()
        start = np.empty(cap)
        end = np.empty(cap)
        lengths = np.empty((cap, self.n_materials))
        n = _radio_walk_segment(self.blocks, self.cell_m, float(p[0]), float(p[1]), float(q[0]), float(q[1]),
                                float(tol), start, end, lengths)
        return start[:n].copy(), end[:n].copy(), lengths[:n].copy()

    def all_pairs(self, xy: np.ndarray, tol: float, cross_db: np.ndarray, metre_db: np.ndarray,
                  per_metre: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(distance, walls, wall_db, material_walls) for all pairs of the points ``xy`` (float64[R, 2])."""
        r = xy.shape[0]
        distance = np.empty((r, r))
        walls = np.empty((r, r), dtype=np.int32)
        wall_db = np.empty((r, r))
        counts = np.empty((r, r, self.n_materials), dtype=np.int32)
        _radio_all_pairs(self.blocks, self.cell_m, xy, tol, cross_db, metre_db, per_metre, distance, walls,
                         wall_db, counts)
        return distance, walls, wall_db, counts

    def one_to_many(self, p: tuple[float, float], targets: np.ndarray, tol: float, cross_db: np.ndarray,
                    metre_db: np.ndarray, per_metre: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(distance, walls, wall_db) from ``p`` to every row of ``targets`` (float64[N, 2])."""
        n = targets.shape[0]
        distance = np.empty(n)
        walls = np.empty(n, dtype=np.int32)
        wall_db = np.empty(n)
        _radio_one_to_many(self.blocks, self.cell_m, float(p[0]), float(p[1]), targets, tol, cross_db, metre_db,
                           per_metre, distance, walls, wall_db)
        return distance, walls, wall_db
