"""Shortest paths on a configuration space: point-to-point plans, distance fields, nearest target.

All three are one exact search (:func:`swarm.grid._kernels.grid_bucket_search`): 8-connected, octile
costs (1 cell orthogonally, sqrt(2) diagonally, 0.5 m per cell), and no corner cutting: a diagonal step
needs both orthogonal neighbours in the space, since the robot's disc would otherwise clip the corner.

Everything happens inside ``space``: a start, goal or source outside it is not searched from (snap it
first with :func:`swarm.grid.nearest_in`). Cells are (row, col); distances are metres.
"""

from __future__ import annotations

import threading
from typing import Any

import numpy as np

from swarm.base.errors import InvalidInput
from swarm.base.types import CELL_M
from ._kernels import (NO_TOUCHED, grid_bucket_search, grid_bucket_settle, grid_descend_path, grid_field_metres,
                       grid_read_metres)
from ._validate import check_cell, check_cells, check_length, check_same_shape, check_space

_NO_TARGETS = np.zeros(0, dtype=np.uint8)


class _Workspace(threading.local):
    """Per-thread scratch arrays for the search, reused across calls.

    A 300 x 300 search needs ~2 MB of scratch. Allocating it per call lets the C allocator hand it back to
    the OS and fault it in again (with transparent huge pages that cost up to 5 ms a call, measured); one
    buffer per thread, grown when a larger grid comes, keeps every call at the cost of the search itself.
    The two padded grids (passable cells and targets) are reused too: their one-cell border stays 0, only
    the interior is rewritten per call.
    """

    def __init__(self) -> None:
        self.dist = np.empty(0, dtype=np.float64)
        self.ring = np.empty(0, dtype=np.int32)
        self.pads: dict[tuple[int, int, int], np.ndarray] = {}
        self.inf = np.zeros(0, dtype=np.float64)    # all inf between calls (field_at resets what it touched)
        self.touched = np.zeros(0, dtype=np.int32)
        self.marks = np.zeros(0, dtype=np.uint8)     # all 0 between calls

    def get(self, n: int) -> tuple[np.ndarray, np.ndarray]:
        """A distance array of ``n`` cells (filled by the search) and the bucket ring for it."""
        if self.dist.shape[0] < n:
            self.dist = np.empty(n, dtype=np.float64)
        return self.dist[:n], self.ring_for(n)

    def ring_for(self, n: int) -> np.ndarray:
        """The bucket ring for a search of ``n`` cells, for the searches on the all-inf array of
        :meth:`clean`, which need no distance array of their own."""
        if self.ring.shape[0] < 3 * n:
            self.ring = np.empty(3 * n, dtype=np.int32)
        return self.ring

    def clean(self, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """An all-inf distance array of ``n`` cells, room for the cells a search touches, and an all-0 mark
        array, for the searches that leave all three as they found them (:func:`plan`,
        :func:`nearest_reachable`, :func:`field_at` and the kept target search of :mod:`swarm.grid.kept`):
        one set per thread, 9 MB on a 300-tile map, grown for a larger one and sliced for a smaller one (the
        unused rest keeps the invariants too)."""
        if self.inf.shape[0] < n:
            self.inf = np.full(n, np.inf)
            self.touched = np.empty(4 * n, dtype=np.int32)
            self.marks = np.zeros(n, dtype=np.uint8)
        return self.inf[:n], self.touched[:4 * n], self.marks[:n]

    def padded(self, grid: np.ndarray, which: int = 0) -> tuple[np.ndarray, int]:
        """``grid`` (bool[H, W]) as a flat uint8 array with a one-cell blocked border, and the padded row
        length; ``which`` picks one of two buffers (a search needs the space and its targets at once).
        Valid until the next call with the same shape and ``which`` in this thread."""
        h, w = grid.shape
        key = (h, w, which)
        pad = self.pads.get(key)
        if pad is None:  # a few shapes recur (the whole map, the local windows): keep the last 8
            if len(self.pads) >= 8:
                del self.pads[next(iter(self.pads))]
            pad = self.pads[key] = np.zeros((h + 2, w + 2), dtype=np.uint8)
        pad[1:-1, 1:-1] = grid.view(np.uint8)  # a byte copy: bool and uint8 0/1 share their bytes
        return pad.reshape(-1), w + 2


_WORK = _Workspace()


def _flat(cells: np.ndarray, wp: int) -> np.ndarray:
    return (cells[:, 0] + 1) * wp + (cells[:, 1] + 1)


def _seed(cell: tuple[int, int], wp: int) -> np.ndarray:
    """One cell's padded flat index as the int64[1] seed array the search takes."""
    return np.array([(cell[0] + 1) * wp + cell[1] + 1], dtype=np.int64)


_NO_CELLS = np.zeros(0, dtype=np.int64)
_NO_METRES = np.zeros(0, dtype=np.float32)


def _reaches_cut(touched: np.ndarray, wp: int, h: int, w: int, cut: tuple[bool, bool, bool, bool]) -> bool:
    """Whether a search of a window (padded row length ``wp``, ``h`` x ``w`` cells) gave a distance to a cell
    on one of its cut sides (``cut``: top, bottom, left, right are inside the map): only then can its
    reachable space go on beyond the window. ``touched``: the search's touched padded flat indices."""
    rows = touched // wp - 1
    cols = touched % wp - 1
    top, bottom, left, right = cut
    return bool((top and (rows == 0).any()) or (bottom and (rows == h - 1).any())
                or (left and (cols == 0).any()) or (right and (cols == w - 1).any()))


def _forget(dist: np.ndarray, touched: np.ndarray, nt: int) -> None:
    """Set the ``touched[:nt]`` cells of the all-inf workspace ``dist`` back to inf (after a search that
    listed them): a search that stops near its start then costs what it touched, not a whole-map fill."""
    grid_read_metres(dist, _NO_CELLS, 0.0, touched, nt, _NO_METRES)


def plan(space: np.ndarray, start: tuple[int, int], goal: tuple[int, int]) -> np.ndarray | None:
    """Shortest 8-connected path from ``start`` to ``goal`` through ``space``: int64[N, 2] (row, col).

    The path includes both ends (N = 1 when they coincide). None when the goal is unreachable or either
    end is outside the space (snap them first with :func:`swarm.grid.nearest_in`). Raises
    :class:`InvalidInput` for a cell off the map. Cost: O(cells nearer the start than the goal, by path
    length): the search stops as soon as the goal's distance is final, so short plans are cheap; ~0.03 ms
    for a 38 m plan on a 300 x 300 map (loaded 2-core machine). Among equal-length paths the one walked
    back from the goal keeping its direction as long as possible is returned
    (:func:`swarm.grid._kernels.grid_descend_path`): deterministic, and straight runs simplify into few
    waypoints.
    """
    sp = check_space(space)
    s = check_cell(start, sp.shape, "start")
    g = check_cell(goal, sp.shape, "goal")
    if not (sp[s] and sp[g]):
        return None
    free, wp = _WORK.padded(sp)
    ring = _WORK.ring_for(free.shape[0])
    dist, touched, _ = _WORK.clean(free.shape[0])
    gi = (g[0] + 1) * wp + g[1] + 1
    best, _, nt = grid_bucket_search(free, wp, _seed(s, wp), gi, _NO_TARGETS, np.inf, dist, ring, touched)
    try:
        if best < 0:
            return None
        path = grid_descend_path(free, wp, dist, best)
    finally:
        _forget(dist, touched, nt)
    if (int(path[0, 0]), int(path[0, 1])) != s:  # the descent always ends at the seed on a settled field
        raise RuntimeError(f"swarm.grid.plan: path read-back stopped at {path[0].tolist()}, not at {s}")
    return path


def distance_field(space: np.ndarray, sources: Any, max_dist_m: float | None = None) -> np.ndarray:
    """Geodesic distance (m) from the nearest source to every cell of ``space``: float32[H, W].

    ``sources`` is one (row, col) or an int[K, 2] array; sources outside ``space`` are ignored (all of them:
    an all-``inf`` field). Cells not reached (outside the space, cut off, or farther than ``max_dist_m``)
    are ``inf`` -- test with ``numpy.isfinite``. Path lengths are octile (8-connected, no corner cutting),
    as :func:`plan`'s. A new array each call.

    Cost: O(cells reached) for the search plus O(H * W) to write the field; ~0.1 ms on a 300 x 300 map
    with 17 k free cells (loaded 2-core machine). Bounding the distance bounds the search, which is what a
    local coordination penalty wants; when only some cells matter, :func:`field_at` is cheaper.
    """
    sp = check_space(space)
    cells = check_cells(sources, sp.shape, "sources")
    limit = check_length(max_dist_m, "max_dist_m", allow_none=True)
    cells = cells[sp[cells[:, 0], cells[:, 1]]]
    out = np.empty(sp.shape, dtype=np.float32)
    if cells.shape[0] == 0:
        out.fill(np.inf)
        return out
    free, wp = _WORK.padded(sp)
    dist, ring = _WORK.get(free.shape[0])
    max_cells = np.inf if limit is None else limit / CELL_M
    grid_bucket_search(free, wp, _flat(cells, wp), -1, _NO_TARGETS, max_cells, dist, ring, NO_TOUCHED)
    grid_field_metres(dist, wp, max_cells, out)
    return out


def field_at(space: np.ndarray, sources: Any, cells: np.ndarray, max_dist_m: float | None = None) -> np.ndarray:
    """``distance_field(space, sources, max_dist_m)`` read at ``cells`` (int[N, 2], N may be 0): float32[N],
    bit for bit the same values.

    Cheaper when only some cells matter (a frontier's candidate targets, say): the search stops as soon as
    every one of ``cells`` has its final distance (a cell outside the space never gets one, so the search
    then runs to its end, as :func:`distance_field` does), and neither the whole distance array is reset
    nor the whole field converted to metres. The search is the same compiled one, run in the same order
    (:func:`swarm.grid._kernels.grid_bucket_settle`), which is what makes the values identical. Unreached
    cells are ``inf``. Cost: O(cells nearer the sources than the farthest of ``cells``); ~0.05 ms for a
    frontier cluster's cells on a 300 x 300 map.
    """
    sp = check_space(space)
    src = check_cells(sources, sp.shape, "sources")
    at = np.asarray(cells)
    if at.shape[0] == 0:
        return np.zeros(0, dtype=np.float32)
    at = check_cells(at, sp.shape, "cells")
    limit = check_length(max_dist_m, "max_dist_m", allow_none=True)
    src = src[sp[src[:, 0], src[:, 1]]]
    out = np.empty(at.shape[0], dtype=np.float32)
    if src.shape[0] == 0:
        out.fill(np.inf)
        return out
    free, wp = _WORK.padded(sp)
    ring = _WORK.ring_for(free.shape[0])
    dist, touched, marks = _WORK.clean(free.shape[0])
    flat = _flat(at, wp)
    marks[flat] = 1
    remaining = int(np.count_nonzero(marks))
    max_cells = np.inf if limit is None else limit / CELL_M
    try:
        nt = grid_bucket_settle(free, wp, _flat(src, wp), marks, remaining, max_cells, dist, ring, touched)
        grid_read_metres(dist, flat, max_cells, touched, nt, out)
    finally:
        marks[flat] = 0
    return out


NEAREST_WINDOW_CELLS = 48
"""Half-width (cells, 24 m) of the first window :func:`nearest_reachable` searches; each further window is
twice as wide, and once a window would cover a quarter of the map the whole map is searched."""


def nearest_reachable(space: np.ndarray, start: tuple[int, int], targets: np.ndarray
                      ) -> tuple[tuple[int, int], float] | None:
    """The ``targets`` cell with the shortest path from ``start`` through ``space``, and that length (m).

    Only targets inside the space can be reached. Ties (equal length within 1e-9 cells) go to the lowest
    row, then the lowest column. Returns ``((row, col), metres)``, or None when no target is reachable or
    ``start`` is outside the space. ``targets`` is bool[H, W], the shape of ``space``.

    Cost: O(cells nearer than the answer, by path length), plus byte copies of the window searched: a
    window around ``start`` first, which decides when its answer is nearer than the window's cut edge
    (no path through the rest of the map can be that short); ~0.03 ms on a 300 x 300 map (loaded 2-core
    machine), whatever the map's size when the answer is near.
    """
    sp = check_space(space)
    s = check_cell(start, sp.shape, "start")
    tg = check_space(targets, "targets")
    check_same_shape(tg, sp.shape, "targets")
    return nearest_reachable_in(sp, s, tg)


def nearest_reachable_in(space: np.ndarray, start: tuple[int, int], targets: np.ndarray
                         ) -> tuple[tuple[int, int], float] | None:
    """:func:`nearest_reachable` for checked inputs (``targets`` outside ``space`` are ignored).

    Exact window by window: a path that leaves the window is at least as long as the Chebyshev distance
    from ``start`` to the nearest cell beyond the window's cut edges (octile steps), and every cell nearer
    than that is settled in the same order, with the same distances, as on the whole map (a window's
    cells and their neighbours are the map's), so an answer nearer than that edge is the whole map's,
    tie-break included (flat indices keep the row-then-column order). Otherwise the next window is
    searched (issue 47: two whole-map copies per call made Minotaur's room searches cost the map's area).
    A search that runs out of cells without giving a distance to a cell on a cut edge has met everything
    reachable (a closed room): its answer, or None, is final too."""
    if not space[start]:
        return None
    h, w = space.shape
    half = NEAREST_WINDOW_CELLS
    while True:
        r0, r1 = max(start[0] - half, 0), min(start[0] + half + 1, h)
        c0, c1 = max(start[1] - half, 0), min(start[1] + half + 1, w)
        if (r1 - r0) * (c1 - c0) * 4 > h * w:
            r0, r1, c0, c1 = 0, h, 0, w
        window = (slice(r0, r1), slice(c0, c1))
        found, decided = _window_search(space[window], (start[0] - r0, start[1] - c0), targets[window],
                                        (r0 > 0, r1 < h, c0 > 0, c1 < w))
        if decided:
            return None if found is None else ((found[0][0] + r0, found[0][1] + c0), found[1])
        half *= 2


def nearest_reachable_window(space: np.ndarray, start: tuple[int, int], targets: np.ndarray,
                             cut: tuple[bool, bool, bool, bool]) -> tuple[tuple[tuple[int, int], float] | None, bool]:
    """:func:`nearest_reachable` on a window of a larger map, and whether the window decides it.

    ``space`` and ``targets`` are the window's cells (equal to the map's there), ``start`` a cell of the
    window, ``cut`` whether its top, bottom, left and right sides are cut out of the map (False: the map's
    own edge). Returns (answer, True) when the answer, or None, is the whole map's: the answer is nearer
    than every cut side, or the search met no cut side before it ran out; else (None, False), and the
    caller searches a larger window or the whole map. For callers that build the search's inputs
    (configuration space, targets) for a window only, so that a near answer costs the window's area.
    Cost: that of :func:`nearest_reachable` on the window."""
    sp = check_space(space)
    s = check_cell(start, sp.shape, "start")
    tg = check_space(targets, "targets")
    check_same_shape(tg, sp.shape, "targets")
    if not isinstance(cut, tuple) or len(cut) != 4 or not all(isinstance(v, bool) for v in cut):
        raise InvalidInput("cut", cut, "a tuple of 4 bools (top, bottom, left, right cut out of the map)")
    if not sp[s]:
        return None, True
    return _window_search(sp, s, tg, cut)


def _window_search(window: np.ndarray, start: tuple[int, int], targets: np.ndarray,
                   cut: tuple[bool, bool, bool, bool]) -> tuple[tuple[tuple[int, int], float] | None, bool]:
    """The search of :func:`nearest_reachable_window` for checked inputs, ``start`` in the space."""
    h, w = window.shape
    top, bottom, left, right = cut
    edges = [start[0] + 1] if top else []
    edges += [h - start[0]] if bottom else []
    edges += [start[1] + 1] if left else []
    edges += [w - start[1]] if right else []
    free, wp = _WORK.padded(window, 0)
    tflat, _ = _WORK.padded(targets & window, 1)
    ring = _WORK.ring_for(free.shape[0])
    dist, touched, _ = _WORK.clean(free.shape[0])
    best, best_d, nt = grid_bucket_search(free, wp, _seed(start, wp), -1, tflat, np.inf, dist, ring, touched)
    enclosed = best < 0 and bool(edges) and not _reaches_cut(touched[:nt], wp, h, w, cut)
    _forget(dist, touched, nt)
    found = None if best < 0 else ((int(best // wp - 1), int(best % wp - 1)), float(best_d * CELL_M))
    if not edges or enclosed:     # the whole map, or a search that ran out without meeting a cut side
        return found, True
    if best >= 0 and best_d < min(edges) - 1e-6:
        return found, True
    return None, False
