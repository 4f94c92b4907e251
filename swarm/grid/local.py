"""Local-first planning: the navigator's plan computed on a window around the robot, when that is exact.

Most plans are short (the share on the runtime benchmark: docs/performance-history.md), yet a whole-map plan pays
for the whole map: the configuration space of all 90 000 cells, a padded copy and a distance array of the
same size. :func:`plan_local_first` first plans on the window of half-width ``half_cells`` around the
robot's cell and accepts the answer only when it is provably the whole-map answer, bit for bit:

* Let ``e`` be the erosion depth of the configuration space (:func:`erosion_depth`). The window's space
  equals the whole map's space on every cell at Chebyshev distance ``<= half - e`` from the robot's cell
  (the window treats cells beyond its edge as blocked, which erodes only its outer ``e`` rings; an edge
  on the map border is the same in both).
* Snapping start and goal looks at most ``snap`` cells around them, so both snap the same way when the
  goal's cell is within ``half - e - snap`` of the robot's cell.
* The search (:func:`swarm.grid._kernels.grid_bucket_search`) stops at the goal's distance bucket
  ``k = floor(D)``; before that it expands only cells nearer than ``D``, which lie within ``D + snap`` of
  the robot's cell, and relaxes their neighbours. The path read-back and the shortcutting only look at
  path cells, their neighbours and the segments between path cells. So if ``D <= half - e - snap - 1``
  cells, every cell any of these steps reads is in the equal region: the same cells are expanded in the
  same order with the same float sums, and the path and waypoints are identical. A shorter whole-map
  path would lie in that region too, so it would have been found in the window.

Otherwise (goal too far, no path in the window, or a longer one) the caller plans on the whole map, or,
for a swarm whose maps find nothing kept (:data:`BOXED`), this module plans on the box of the map's known
cells, start and goal (:func:`known_box`): planning through known space, no plan leaves it, so with the
same margin the box is a window that decides every plan.
Only the exact grid planner (:func:`swarm.grid.plan`) may be windowed; other planners see the whole map.

The same module holds the compiled window stage of the target search used by
:func:`swarm.grid.nearest_reachable_unseen` (whose docstring gives the window's exactness condition),
:func:`window_target`: one call for what would otherwise be five numpy and kernel calls with padded
copies. Its snapping and search, :func:`search_targets`, also end the whole-map stage
(:func:`swarm.grid.kept.map_target`), whose inputs are kept between searches.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np
from numba import njit

from swarm.base.types import CELL_M
from ._kernels import (grid_bucket_search, grid_configuration_space, grid_descend_path, grid_shortcut, grid_snap,
                       grid_view_cells)
from .cspace import _erosion_rows
from .search import _WORK

PLAN_WINDOW_CELLS = 40
"""Half-width of the first local planning window (20 m): plans up to 34 cells (17 m) stay local for the
default robot. Each further window is twice as wide."""
BOXED = True
"""A plan no window decides runs on the box no plan leaves (:func:`known_box`: the known cells, start and goal,
with the windows' margin) instead of the whole map, when the map's inputs would be built from scratch anyway
(``plan_local_first(boxed=...)``: a swarm larger than the kept searches' cache, :func:`swarm.grid.kept.rebuilds`;
a team keeps the plan its far target search remembered, :mod:`swarm.grid.memo`). Off: the whole map, as before;
the tests compare both."""
LARGER_WINDOW_SHARE = 0.25
"""Windows after the first are tried while they cover at most this share of the map (beyond, the whole-map
plan costs about as much)."""

_NO_TARGETS = np.zeros(0, dtype=np.uint8)


@lru_cache(maxsize=64)
def erosion_depth(radius_m: float, margin_m: float) -> int:
    """How many rings of cells beside a blocked one can leave the configuration space: the largest
    Chebyshev offset of :func:`swarm.grid.inflation_offsets` (the erosion's rows and their half widths), 0
    without clearance. A window's configuration space equals the map's at least this far inside the
    window's cut edges, so a decision that reads a window computes the space on that much more. Cost:
    O(1) (cached per radius and margin)."""
    rows, widths = _erosion_rows(radius_m, margin_m)
    return int(max(np.abs(rows).max(), widths.max()))


def window_bounds(cell: tuple[int, int], half: int, shape: tuple[int, int]) -> tuple[int, int, int, int]:
    """Rows ``r0:r1`` and columns ``c0:c1`` of the square of half-width ``half`` around ``cell``, clipped
    to the map."""
    return (max(cell[0] - half, 0), min(cell[0] + half + 1, shape[0]),
            max(cell[1] - half, 0), min(cell[1] + half + 1, shape[1]))


def known_box(known: np.ndarray, cells: tuple[tuple[int, int], ...], margin: int) -> tuple[int, int, int, int]:
    """Rows ``r0:r1`` and columns ``c0:c1`` of the smallest box holding every known (non-zero) cell of the
    checked uint8 map ``known`` and every one of ``cells``, widened by ``margin`` and clipped to the map.

    Planning through known space only (unknown cells are not traversable), no search can leave this box,
    and with ``margin`` at least the erosion depth plus the snap radius plus one, a window that covers it
    computes the whole map's configuration space, view cells and targets on every cell a search reads: it
    decides every search, however long (a crowd that has explored a corner of a large map searches that
    corner, not the map). Cost: the known rows' bytes outside the box, read once."""
    r0, r1, c0, c1 = _box_of(np.ascontiguousarray(known, dtype=np.uint8))
    for r, c in cells:
        r0, r1, c0, c1 = min(r0, r), max(r1, r + 1), min(c0, c), max(c1, c + 1)
    h, w = known.shape
    return max(r0 - margin, 0), min(r1 + margin, h), max(c0 - margin, 0), min(c1 + margin, w)


@njit(cache=True)
def _box_of(known):  # pragma: no cover - compiled
    """(r0, r1, c0, c1) of the non-zero cells of a C-contiguous uint8 map; an empty box (r0 = H, r1 = 0,
    c0 = W, c1 = 0) when there are none. The first and last non-zero bytes give the rows (read 8 at a time);
    each row between them is read only outside the columns found so far."""
    h, w = known.shape
    flat = known.reshape(-1)
    n = flat.shape[0]
    words = n // 8
    wide = flat[:8 * words].view(np.uint64)
    first = -1
    for i in range(words):
        if wide[i] != 0:
            for j in range(8 * i, 8 * i + 8):
                if flat[j] != 0:
                    first = j
                    break
            break
    if first < 0:
        for j in range(8 * words, n):
            if flat[j] != 0:
                first = j
                break
    if first < 0:
        return h, 0, w, 0
    last = -1
    for j in range(n - 1, 8 * words - 1, -1):
        if flat[j] != 0:
            last = j
            break
    if last < 0:  # none in the tail: the last non-zero word, at or after the first's
        for i in range(words - 1, first // 8 - 1, -1):
            if wide[i] != 0:
                for j in range(8 * i + 7, 8 * i - 1, -1):
                    if flat[j] != 0:
                        last = j
                        break
                break
    r0, r1 = first // w, last // w + 1
    c0, c1 = w, 0
    if w % 8 == 0:  # rows start on words: OR the band's rows together, 8 cells at a time
        acc = np.zeros(w // 8, np.uint64)
        rows = flat[r0 * w:r1 * w].view(np.uint64).reshape(r1 - r0, w // 8)
        for r in range(r1 - r0):
            for j in range(w // 8):
                acc[j] |= rows[r, j]
        seen = acc.view(np.uint8)
        for c in range(w):
            if seen[c] != 0:
                c0 = c
                break
        for c in range(w - 1, -1, -1):
            if seen[c] != 0:
                c1 = c + 1
                break
        return r0, r1, c0, c1
    for r in range(r0, r1):
        row = known[r]
        for c in range(c0):
            if row[c] != 0:
                c0 = c
                break
        for c in range(w - 1, c1 - 1, -1):
            if row[c] != 0:
                c1 = c + 1
                break
    return r0, r1, c0, c1


def plan_local_first(known: np.ndarray, start: tuple[int, int], goal: tuple[int, int], radius_m: float,
                     margin_m: float, unseen_traversable: bool, snap: int,
                     half_cells: int = PLAN_WINDOW_CELLS, boxed: bool = False) -> tuple[np.ndarray, bool] | None:
    """The whole-map plan from cell ``start`` to cell ``goal`` if a window decides it exactly (see the
    module docstring), else None. The window of half-width ``half_cells`` is tried first, then windows
    twice as wide while they cover at most ``LARGER_WINDOW_SHARE`` of the map, so a plan costs about the
    area within its length, not the map's.

    ``known`` is a checked uint8 map; ``start`` and ``goal`` are cells in it, snapped into the
    configuration space within ``snap`` cells as the navigator does (:func:`swarm.grid.nearest_in`).
    Returns the shortcut waypoints (float64[M, 2] metres, as :func:`swarm.grid.simplify` gives for
    :func:`swarm.grid.plan`'s path on the whole map) and whether the goal cell itself is in the
    configuration space. ``boxed``: the whole map's inputs would be built from scratch anyway (the caller
    asked :func:`swarm.grid.kept.rebuilds`): a plan no window decides then runs on the box of the known
    cells (:data:`BOXED`).
    """
    depth = erosion_depth(radius_m, margin_m)
    rows, widths = _erosion_rows(radius_m, margin_m)
    reach = max(abs(goal[0] - start[0]), abs(goal[1] - start[1]))
    half = half_cells
    unseen_ok = bool(unseen_traversable)
    while True:
        budget = half - depth - snap - 1  # the longest path (cells) whose search stays in the equal region
        r0, r1, c0, c1 = window_bounds(start, half, known.shape)
        area = (r1 - r0) * (c1 - c0)
        if area >= known.size or (half > half_cells and area > LARGER_WINDOW_SHARE * known.size):
            break  # the whole map is searched next: nothing to save
        if budget >= 0 and reach <= budget + 1:
            dist, ring = _WORK.get((r1 - r0 + 2) * (c1 - c0 + 2))
            waypoints, goal_fits = _window_plan(known, r0, r1, c0, c1, unseen_ok, rows, widths,
                                                start[0], start[1], goal[0], goal[1], snap, float(budget), dist,
                                                ring)
            if waypoints.shape[0] > 0:
                return waypoints, goal_fits
        half *= 2
    if not (BOXED and boxed and not unseen_ok):
        return None
    r0, r1, c0, c1 = known_box(known, (start, goal), depth + snap + 1)
    if (r1 - r0) * (c1 - c0) >= known.size:
        return None
    # The box holds every cell a plan can reach (a swarm that knows a corner of a large map plans there):
    # it decides, however long the plan
    dist, ring = _WORK.get((r1 - r0 + 2) * (c1 - c0 + 2))
    waypoints, goal_fits = _window_plan(known, r0, r1, c0, c1, unseen_ok, rows, widths, start[0], start[1],
                                        goal[0], goal[1], snap, math.inf, dist, ring)
    return (waypoints, goal_fits) if waypoints.shape[0] > 0 else None


@njit(cache=True)
def _window_plan(known, r0, r1, c0, c1, unseen_ok, row_offsets, half_widths, sr, sc, gr, gc, snap, budget,
                 dist, ring):  # pragma: no cover - compiled
    """Configuration space of ``known[r0:r1, c0:c1]``, snapping, search, read-back and shortcut in one
    call. Returns (waypoints float64[M, 2] metres in map coordinates, goal cell in the space); no
    waypoints when the window does not decide the plan."""
    w = c1 - c0
    space, pad = _space_and_pad(np.ascontiguousarray(known[r0:r1, c0:c1]), unseen_ok, row_offsets, half_widths)
    none = np.empty((0, 2), np.float64)
    s = grid_snap(space, sr - r0, sc - c0, snap)
    g = grid_snap(space, gr - r0, gc - c0, snap)
    if s[0] < 0 or g[0] < 0:
        return none, False
    wp = w + 2
    seeds = np.empty(1, np.int64)
    seeds[0] = (s[0] + 1) * wp + s[1] + 1
    free = pad.reshape(-1)
    best, best_d, _ = grid_bucket_search(free, wp, seeds, (g[0] + 1) * wp + g[1] + 1, _NO_TARGETS, budget,
                                         dist[:free.shape[0]], ring, np.empty(0, np.int32))
    if best < 0 or not best_d <= budget:
        return none, False
    path = grid_descend_path(free, wp, dist, best)
    keep = grid_shortcut(space, path)
    out = np.empty((keep.shape[0], 2), np.float64)
    for i in range(keep.shape[0]):
        out[i, 0] = (float(path[keep[i], 1] + c0) + 0.5) * CELL_M
        out[i, 1] = (float(path[keep[i], 0] + r0) + 0.5) * CELL_M
    return out, space[gr - r0, gc - c0] != 0


NO_TARGET, TARGET_FOUND = 0, 1
_NO_PATH = np.empty((0, 2), np.int64)


@njit(cache=True)
def window_target(known, r0, r1, c0, c1, exclude, reach, unseen_ok, row_offsets, half_widths, sr, sc, snap,
                  dist, ring):  # pragma: no cover - compiled
    """The target search of :func:`swarm.grid.nearest_reachable_unseen` on ``known[r0:r1, c0:c1]`` in one
    call: view cells, configuration space, snapping ``(sr, sc)`` (map coordinates), nearest view cell.
    ``exclude`` is the window of the exclusion mask or an empty array. Returns (TARGET_FOUND, row, col,
    distance in cells, snapped row, snapped col) in window coordinates, or NO_TARGET first."""
    window = np.ascontiguousarray(known[r0:r1, c0:c1])
    status, row, col, best_d, s_r, s_c, _ = _target_search(window, exclude, reach, unseen_ok, row_offsets,
                                                              half_widths, sr - r0, sc - c0, snap, dist, ring)
    return status, row, col, best_d, s_r, s_c


@njit(cache=True)
def _target_search(window, exclude, reach, unseen_ok, row_offsets, half_widths, sr, sc, snap, dist,
                   ring):  # pragma: no cover - compiled
    """The body of :func:`window_target` on a contiguous ``window`` (coordinates relative to it): view
    cells, configuration space, targets, then :func:`search_targets`."""
    h, w = window.shape
    view = np.zeros((h, w), np.bool_)
    if grid_view_cells(window, exclude, reach, view) == 0:
        return NO_TARGET, -1, -1, np.inf, -1, -1, _NO_PATH
    space, pad = _space_and_pad(window, unseen_ok, row_offsets, half_widths)
    targets = np.zeros((h + 2, w + 2), np.uint8)
    if mark_targets(view, pad, exclude, targets) == 0:
        return NO_TARGET, -1, -1, np.inf, -1, -1, _NO_PATH
    return search_targets(space, pad, targets, sr, sc, snap, False, dist, ring, np.empty(0, np.int32))


@njit(cache=True)
def search_targets(space, pad, targets, sr, sc, snap, with_path, dist, ring,
                   touched):  # pragma: no cover - compiled
    """Snap ``(sr, sc)`` into ``space`` and find the nearest cell of ``targets`` (padded like ``pad``, the
    space with a blocked border; a byte or a bit per cell, see :func:`swarm.grid._kernels.grid_bucket_search`):
    (status, row, col, distance in cells, snapped row, snapped col, path), the path read off the search's
    distances only ``with_path``. Shared by the window
    stage and the whole-map stage (:func:`swarm.grid.kept.map_target`). ``touched``: empty, or (with an
    all-inf ``dist``) where the search lists the cells it gave a distance, which are set back to inf
    before returning (see :func:`swarm.grid._kernels.grid_bucket_search`)."""
    w = space.shape[1]
    s = grid_snap(space, sr, sc, snap)
    if s[0] < 0:
        return NO_TARGET, -1, -1, np.inf, -1, -1, _NO_PATH
    wp = w + 2
    seeds = np.empty(1, np.int64)
    seeds[0] = (s[0] + 1) * wp + s[1] + 1
    free = pad.reshape(-1)
    field = dist[:free.shape[0]]
    best, best_d, nt = grid_bucket_search(free, wp, seeds, -1, targets.reshape(-1), np.inf, field, ring, touched)
    path = _NO_PATH
    if best >= 0 and with_path:
        path = grid_descend_path(free, wp, field, best)
    for i in range(nt):
        field[touched[i]] = np.inf
    if best < 0:
        return NO_TARGET, -1, -1, np.inf, -1, -1, _NO_PATH
    return TARGET_FOUND, best // wp - 1, best % wp - 1, best_d, s[0], s[1], path


@njit(cache=True)
def mark_targets(view, pad, exclude, targets):  # pragma: no cover - compiled
    """``targets`` (padded like ``pad``, zero border) = view cells in the space (``pad``'s interior) and not
    in ``exclude`` (same shape as ``view``, or empty for none); returns how many. Branch-free rows, so the
    compiler vectorises them (a short-circuit test per cell cost more than the whole-map search's numpy
    passes)."""
    h, w = view.shape
    excluded = exclude.shape[0] == h
    count = 0
    for r in range(h):
        v = view[r].view(np.uint8)
        sp = pad[r + 1]
        t = targets[r + 1]
        for c in range(w):
            t[c + 1] = v[c] & sp[c + 1]
        if excluded:
            ex = exclude[r].view(np.uint8)
            for c in range(w):
                t[c + 1] = t[c + 1] > ex[c]  # a and not b
        for c in range(w):
            count += t[c + 1]
    return count


@njit(cache=True)
def _space_and_pad(window, unseen_ok, row_offsets, half_widths):  # pragma: no cover - compiled
    """The configuration space of a contiguous map window (uint8[h, w], 0/1,
    :func:`swarm.grid.cspace.configuration_space_of`) and its copy padded with one blocked cell on every
    side (uint8[h + 2, w + 2]), laid out for the search."""
    h, w = window.shape
    pad = np.zeros((h + 2, w + 2), np.uint8)
    space = np.empty((h, w), np.uint8)
    grid_configuration_space(window, unseen_ok, row_offsets, half_widths, space)
    for r in range(h):  # not a slice copy, which links numba's shape-error formatting (docs/performance-history.md)
        for c in range(w):
            pad[r + 1, c + 1] = space[r, c]
    return space, pad
