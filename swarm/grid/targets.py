"""The Greed target: the nearest place, by path length, from which an unseen cell can be looked at.

MAES's Greed (docs/maes.md section 7.4) drives to the nearest free cell next to an unseen one. On a
planning grid with the robot's radius that cell is usually **not** in the configuration space: a frontier
cell has an unseen 4-neighbour, which is not passable when planning pessimistically, so the frontier cell
lies in inflated space.

Choice made here: the target is a configuration-space cell from which a frontier cell is at most
``view_reach_cells`` steps away through known-FREE cells, 4-connected (also when planning optimistically:
the robot should look at the unknown from ground it has seen). Such a view cell is where the robot's
centre can actually go, and the 4-connected chain of free cells between it and the frontier means the
sensor sees the unseen cell past the frontier. The default reach is the inflation depth plus one cell
(2 cells = 1 m for a 0.3 m robot), far below the lidar range, so the robot still drives right up to the
unknown as MAES does. Callers that check "is my target still next to the unknown" should look within
``view_reach_cells + 1`` cells of the target, not only its 8 neighbours.
"""

from __future__ import annotations

import math

import numpy as np

from swarm.base.types import CELL_M, ROBOT_RADIUS_M
from . import kept, memo
from ._kernels import grid_view_cells
from ._validate import check_cell, check_count, check_known, check_length, check_same_shape, check_space
from .cspace import DEFAULT_MARGIN_M, _erosion_rows
from .local import TARGET_FOUND, erosion_depth, known_box, window_bounds, window_target
from .search import _WORK

_NO_EXCLUDE = np.zeros((0, 0), dtype=bool)


def view_cells(known: np.ndarray, reach: int, exclude: np.ndarray | None = None) -> np.ndarray:
    """FREE cells from which a frontier cell (:func:`swarm.grid.frontier_mask`) not in ``exclude`` is at
    most ``reach`` 4-connected steps away through FREE cells (bool[H, W]); excluded frontier cells seed
    nothing but may be passed through. One compiled pass: the target search of every frontier-driven
    algorithm runs it on the whole map. ``view_cells(...) & configuration_space(...)`` are the cells a
    robot can stand on to look at the frontier: :func:`swarm.grid.nearest_reachable` on them picks a goal.
    Cost: O(H * W * reach); ~0.03 ms on a 300 x 300 map, reach 2."""
    k = np.ascontiguousarray(check_known(known), dtype=np.uint8)
    steps = check_count(reach, "reach", 0)
    assert steps is not None
    ex = _NO_EXCLUDE
    if exclude is not None:
        ex = np.ascontiguousarray(check_space(exclude, "exclude"))
        check_same_shape(ex, k.shape, "exclude")
    view = np.zeros(k.shape, dtype=bool)
    grid_view_cells(k, ex, steps, view)
    return view


def default_view_reach_cells(radius_m: float, margin_m: float) -> int:
    """Inflation depth in cells plus one: the usual gap between a frontier and the nearest drivable cell
    (2 for the default 0.3 m robot and 0.05 m margin), the ``reach`` to give :func:`view_cells`. O(1)."""
    return int(math.ceil((radius_m + margin_m) / CELL_M)) + 1


LOCAL_FIRST_M = 15.0
"""Search first on a window that decides every target up to this path length (metres; see
:func:`nearest_reachable_unseen`)."""
WINDOW_GROWTH = 2
"""Each further window decides searches this many times longer than the one before."""
BOXED = True
"""A search no window decides runs on the box no search leaves (:func:`swarm.grid.local.known_box`: the known
cells and the start, with the windows' margin), which decides it however far its answer, instead of the whole
map, when the map's kept inputs (:mod:`swarm.grid.kept`) would be built from scratch anyway (a swarm larger
than their cache: a crowd that knows a corner of a large map searches the corner). Off: the whole map, as
before; the tests compare both."""
WHOLE_MAP_SHARE = 0.25
"""A window larger than this share of the map is not tried: the whole-map search, on inputs kept from the
map's last search, costs about as much."""


def nearest_reachable_unseen(known: np.ndarray, start: tuple[int, int], radius_m: float = ROBOT_RADIUS_M,
                             unseen_traversable: bool = False, exclude: np.ndarray | None = None, *,
                             margin_m: float = DEFAULT_MARGIN_M, view_reach_cells: int | None = None,
                             snap_radius_cells: int | None = None,
                             local_first_m: float | None = LOCAL_FIRST_M) -> tuple[tuple[int, int], float] | None:
    """The configuration-space cell nearest ``start`` by path length from which a frontier is in view.

    Returns ``((row, col), distance_m)`` or None when no frontier is reachable (exploration is over, or the
    rest is cut off). The cell is in the configuration space of ``radius_m`` and ``margin_m`` (a goal the
    navigator can reach), up to ``view_reach_cells`` free cells from the frontier it looks at; drive to
    ``cell_centre(*cell)``. Cost: O(cells nearer than the answer) (see Speed below); ~0.05 ms on a
    300 x 300 map for a target 38 m away (loaded 2-core machine).

    ``exclude`` (bool[H, W]) removes cells both as targets and as frontiers, for deadlock handling: pass
    the current target to give up that spot, or a disc around it to give up that frontier.

    ``start`` is the robot's cell; when it lies in inflated space (a robot pushed against a wall) it snaps
    to the nearest configuration-space cell within ``snap_radius_cells`` (default: view reach + 1), and
    the straight snapping distance is added to the returned distance.

    Speed: the search first runs on a window around ``start`` that decides every search no longer than
    ``local_first_m`` (from the snapped start): its half-width adds :func:`window_margin` and the snap
    radius, so every cell such a search reads, and every target it could find, is what the whole map
    holds there (the window's edge erodes the space and hides frontiers whose unknown neighbour lies
    past it). A target found there within that length is the global answer, bit for bit. Otherwise the
    next window decides searches ``WINDOW_GROWTH`` times longer, and so on while a window covers at most
    ``WHOLE_MAP_SHARE`` of the map; only then does the whole-map search run. A search therefore costs
    about the area within its answer's distance, not the map's (a swarm on a large map searches mostly
    within tens of metres). Each map remembers the window that decided its last search and starts one
    below it, or at the whole map when that is where the last one ended (97 % of the time the next one
    does too on the 16-robot benchmark). Either way the answer is the whole-map answer.
    ``local_first_m=None`` searches the whole map at once.
    """
    k = np.ascontiguousarray(check_known(known), dtype=np.uint8)  # values checked: 0..2 fit any dtype
    s = check_cell(start, k.shape, "start")
    radius = check_length(radius_m, "radius_m")
    margin = check_length(margin_m, "margin_m")
    assert radius is not None and margin is not None
    reach = check_count(view_reach_cells, "view_reach_cells", 0, allow_none=True)
    if reach is None:
        reach = default_view_reach_cells(radius, margin)
    snap = check_count(snap_radius_cells, "snap_radius_cells", 0, allow_none=True)
    if snap is None:
        snap = reach + 1
    ex = None
    if exclude is not None:
        ex = check_space(exclude, "exclude")
        check_same_shape(ex, k.shape, "exclude")
    local = check_length(local_first_m, "local_first_m", allow_none=True)
    search = _TargetSearch(radius, margin, bool(unseen_traversable), reach, snap)
    keep = k is known
    key = None  # the kept map whose hint this search reads and updates
    if local is not None:
        budget = int(local / CELL_M)  # the longest search (cells) the first window decides
        grow = window_margin(radius, margin, reach) + snap + 1
        key = kept.key_of(k, radius, margin, search.unseen_traversable, reach) if keep else None
        last = kept.last_budget(key) if key is not None else None
        if last == kept.WHOLE_MAP:
            budget = -1  # the last search went to the whole map: the next most likely does too
        elif last is not None:
            budget = max(budget, last // WINDOW_GROWTH)  # one window below the last one that decided
        first = budget
        while budget >= 0:
            r0, r1, c0, c1 = window_bounds(s, budget + grow, k.shape)
            if not _worth_trying((r1 - r0) * (c1 - c0), k.size, budget == first):
                break
            found = search.run_window(k, (r0, r1, c0, c1), s, _NO_EXCLUDE if ex is None else ex[r0:r1, c0:c1],
                                      budget)
            if found is not None:
                if key is not None:
                    kept.note_budget(key, budget)
                return found
            budget *= WINDOW_GROWTH
        if BOXED and not search.unseen_traversable and (key is None or kept.would_evict(key)):
            r0, r1, c0, c1 = known_box(k, (s,), grow)
            if (r1 - r0) * (c1 - c0) < k.size:  # a swarm in a corner of a large map searches the corner
                found = search.run_window(k, (r0, r1, c0, c1), s, _NO_EXCLUDE if ex is None else ex[r0:r1, c0:c1],
                                          math.inf)
                if key is not None:  # (as after a whole-map search: where the next one starts)
                    kept.note_budget(key, _deciding_budget(found, int(local / CELL_M), grow, s, k.shape))
                return found
    found = search.run(k, s, ex, keep=keep, key=key)
    if key is not None and local is not None:
        kept.note_budget(key, _deciding_budget(found, int(local / CELL_M), grow, s, k.shape))
    return found


def _deciding_budget(found: tuple[tuple[int, int], float] | None, budget: int, grow: int, start: tuple[int, int],
                     shape: tuple[int, int]) -> int:
    """The budget of the first window that would have decided a whole-map search's answer ``found`` (its
    distance bounds the search's), or ``kept.WHOLE_MAP`` when no window small enough to try would have."""
    if found is None:
        return kept.WHOLE_MAP
    cells = found[1] / CELL_M
    first = budget
    while budget < cells:
        budget *= WINDOW_GROWTH
    r0, r1, c0, c1 = window_bounds(start, budget + grow, shape)
    return budget if _worth_trying((r1 - r0) * (c1 - c0), shape[0] * shape[1], budget == first) else kept.WHOLE_MAP


def _worth_trying(area: int, size: int, first: bool) -> bool:
    """Whether a window of ``area`` cells is searched before the whole map of ``size``: the first window
    whenever it is smaller, a larger one up to ``WHOLE_MAP_SHARE`` of the map."""
    return area < size if first else area <= WHOLE_MAP_SHARE * size


def window_margin(radius_m: float, margin_m: float, reach: int) -> int:
    """How many rings at a window's edge (not on the map's border) may differ from the whole map in a
    target search: the configuration space erodes ``erosion_depth`` of them, and a view cell depends on
    cells up to ``reach`` steps plus the frontier test's neighbour away. For the same reason it is how
    far past a changed row the kept inputs are recomputed (:func:`swarm.grid.kept.refresh`)."""
    return max(erosion_depth(radius_m, margin_m), reach + 1)


class _TargetSearch:
    """One :func:`nearest_reachable_unseen` search on checked inputs: on the local window (one compiled
    call), then possibly on the whole map, without validating the same map again each time."""

    def __init__(self, radius_m: float, margin_m: float, unseen_traversable: bool, reach: int, snap: int) -> None:
        self.radius_m, self.margin_m, self.unseen_traversable = radius_m, margin_m, unseen_traversable
        self.reach, self.snap = reach, snap

    def run_window(self, known: np.ndarray, bounds: tuple[int, int, int, int], start: tuple[int, int],
                   exclude: np.ndarray, budget: float) -> tuple[tuple[int, int], float] | None:
        """:meth:`run` on the window ``known[r0:r1, c0:c1]`` (``exclude`` is that window of the mask, or
        empty), compiled as one call (:func:`swarm.grid.local.window_target`), in map coordinates; None
        unless it found a target at most ``budget`` cells from the snapped start."""
        r0, r1, c0, c1 = bounds
        rows, widths = _erosion_rows(self.radius_m, self.margin_m)
        dist, ring = _WORK.get((r1 - r0 + 2) * (c1 - c0 + 2))
        status, row, col, cells, sr, sc = window_target(known, r0, r1, c0, c1, exclude, self.reach,
                                                        self.unseen_traversable, rows, widths,
                                                        start[0], start[1], self.snap, dist, ring)
        if status != TARGET_FOUND or not cells <= budget:
            return None
        return (int(row) + r0, int(col) + c0), _distance_m(cells, (int(sr) + r0, int(sc) + c0), start)

    def run(self, known: np.ndarray, start: tuple[int, int], exclude: np.ndarray | None, keep: bool = True,
            key: kept.Key | None = None) -> tuple[tuple[int, int], float] | None:
        """The search on the whole map ``known``, one compiled call (:func:`swarm.grid.kept.map_target`) on
        inputs kept from this map's previous search and brought up to date (``keep=False``: a map converted
        for this call, whose inputs are not worth keeping; ``key``: the map's :func:`swarm.grid.kept.key_of`
        when the caller already has it). The path to the target is kept for the navigator's plan
        (:mod:`swarm.grid.memo`)."""
        rows, widths = _erosion_rows(self.radius_m, self.margin_m)
        h, w = known.shape
        ring = _WORK.ring_for((h + 2) * (w + 2))
        dist, touched, _ = _WORK.clean((h + 2) * (w + 2))
        pad = kept.unpack_buffer((h + 2) * (w + 2))
        ex = _NO_EXCLUDE if exclude is None else np.ascontiguousarray(exclude)
        inputs = kept.inputs_for(known, self.radius_m, self.margin_m, self.unseen_traversable, self.reach,
                                 keep=keep, key=key)
        margin = window_margin(self.radius_m, self.margin_m, self.reach)
        status, row, col, cells, sr, sc, path = kept.map_target(known, ex, self.reach, self.unseen_traversable,
                                                                rows, widths, start[0], start[1], self.snap,
                                                                dist, ring, touched, pad, *inputs, margin)
        if status != TARGET_FOUND:
            return None
        cell, snapped = (int(row), int(col)), (int(sr), int(sc))
        memo.remember(inputs.copy, inputs.space, (h, w), inputs.version,
                      (self.radius_m, self.margin_m, self.unseen_traversable), start, snapped, cell, path)
        return cell, _distance_m(cells, snapped, start)


def _distance_m(cells: float, snapped: tuple[int, int], start: tuple[int, int]) -> float:
    """The returned distance: the search's path length (cells) from the snapped start, in metres, plus the
    straight snapping distance from the robot's cell."""
    return float(cells * CELL_M) + CELL_M * math.hypot(snapped[0] - start[0], snapped[1] - start[1])
