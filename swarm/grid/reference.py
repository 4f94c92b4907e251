"""Reference shortest-path lengths between two cells, to judge a planner's paths against.

* :func:`grid_length_m`: the optimal 8-connected path through a configuration space (octile steps, no
  corner cutting), the best any cell-to-cell planner can do. It is :func:`swarm.grid.plan`'s path, so the
  runtime's navigator, the reference and every planner built on :mod:`swarm.api.grid` share one search
  and one convention.
* :func:`any_angle_length_m`: the physical limit, the Euclidean shortest path of a point from cell centre
  to cell centre through free space, where free space is the closure of the passable cells (a path may
  touch a wall, may not pass between two walls that only touch at a corner). Computed exactly on the
  visibility graph of the convex obstacle corners (grid points with exactly one blocked cell around them;
  shortest paths among polygons bend only there) with A* and lazy line-of-sight tests.

Cells are (row, col) in ``space`` (bool, True = passable); lengths are metres (0.5 m cells); both are
``inf`` when the goal cannot be reached.
"""

from __future__ import annotations

import heapq
import math

import numpy as np
from numba import njit

from swarm.base.types import CELL_M
from ._validate import check_cell, check_space
from .search import plan

SQRT2 = math.sqrt(2.0)


def steps_length(path: np.ndarray) -> float:
    """Length in cells of an 8-connected cell path (int[N, 2]): 1 per orthogonal step, sqrt(2) per
    diagonal one, summed from the start; 0.0 for one cell. Not validated (a longer step counts as
    orthogonal). Cost: O(N), a Python loop; ~6 us for 80 cells."""
    p = np.asarray(path, dtype=np.int64)
    total = 0.0
    for d in (np.abs(p[1:] - p[:-1]).sum(axis=1) == 2).tolist():
        total += SQRT2 if d else 1.0
    return total


def grid_length_m(space: np.ndarray, start: tuple[int, int], goal: tuple[int, int]) -> float:
    """Length (m) of the optimal 8-connected path from ``start`` to ``goal`` through ``space``: the
    length of :func:`swarm.grid.plan`'s path, ``inf`` when there is none. Cost: a :func:`plan`."""
    path = plan(space, start, goal)
    return math.inf if path is None else steps_length(path) * CELL_M


def any_angle_length_m(space: np.ndarray, start: tuple[int, int], goal: tuple[int, int]) -> float:
    """Length (m) of the Euclidean shortest path between the centres of ``start`` and ``goal`` through
    ``space``'s True cells (see the module docstring), ``inf`` when either is outside the space or no path
    exists. For judging paths, not for per-tick use. Cost: A* on the visibility graph of the convex
    corners; ~4 ms for 38 m on a 300 x 300 building map (loaded 2-core machine)."""
    sp = check_space(space)
    s, g = check_cell(start, sp.shape, "start"), check_cell(goal, sp.shape, "goal")
    if not (sp[s] and sp[g]):
        return math.inf
    return _any_angle_cells(np.ascontiguousarray(~sp), s, g) * CELL_M


# ---------------------------------------------------------------- any-angle (visibility graph)
@njit(cache=True, inline="always")
def _free_cell(blocked: np.ndarray, r: int, c: int) -> bool:
    H, W = blocked.shape
    return 0 <= r < H and 0 <= c < W and not blocked[r, c]


@njit(cache=True, inline="always")
def _quad_ok(blocked: np.ndarray, vx: int, vy: int, qa: int, qb: int) -> bool:
    """At grid vertex (vx, vy) (cell units), are quadrants qa and qb (0 BL, 1 BR, 2 TR, 3 TL) connected
    through free quadrants around the vertex (a 4-cycle)?"""
    free = np.empty(4, np.bool_)
    free[0] = _free_cell(blocked, vy - 1, vx - 1)
    free[1] = _free_cell(blocked, vy - 1, vx)
    free[2] = _free_cell(blocked, vy, vx)
    free[3] = _free_cell(blocked, vy, vx - 1)
    if not free[qa] or not free[qb]:
        return False
    if qa == qb or (qa - qb) % 4 == 1 or (qb - qa) % 4 == 1:
        return True
    return free[(qa + 1) % 4] or free[(qa + 3) % 4]


@njit(cache=True)
def _quadrant(x: float, y: float, vx: int, vy: int) -> int:
    if y < vy:
        return 0 if x < vx else 1
    return 3 if x < vx else 2


@njit(cache=True, inline="always")
def _crossings(a0: int, a1: int, out: np.ndarray, m: int) -> int:
    """Append the parameters t in (0, 1) where coordinate a0 + t (a1 - a0) crosses an even value."""
    d = a1 - a0
    if d == 0:
        return m
    lo, hi = min(a0, a1), max(a0, a1)
    k = lo + 1 if lo % 2 != 0 else lo + 2
    while k < hi:
        out[m] = (k - a0) / d
        m += 1
        k += 2
    return m


@njit(cache=True, inline="always")
def _los_touch(blocked: np.ndarray, X0: int, Y0: int, X1: int, Y1: int) -> bool:
    """Line of sight between two points in doubled coordinates (cell centres odd, grid vertices even):
    the segment stays in the closure of the free cells and never squeezes between blocked cells that
    only touch at a corner, nor runs along a grid line with blocked cells on both sides."""
    dX = X1 - X0
    dY = Y1 - Y0
    raw = np.empty(abs(dX) // 2 + abs(dY) // 2 + 4)
    raw[0] = 0.0
    raw[1] = 1.0
    m = _crossings(X0, X1, raw, 2)
    m = _crossings(Y0, Y1, raw, m)
    srt = np.sort(raw[:m])
    t = np.empty(m)
    n = 0
    for i in range(m):
        if n == 0 or srt[i] - t[n - 1] > 1e-12:
            t[n] = srt[i]
            n += 1
    vertical = dX == 0 and X0 % 2 == 0
    horizontal = dY == 0 and Y0 % 2 == 0
    xb = 0.0
    yb = 0.0
    for i in range(n - 1):
        tm = 0.5 * (t[i] + t[i + 1])
        x = (X0 + tm * dX) / 2.0
        y = (Y0 + tm * dY) / 2.0
        if vertical:
            vx = X0 // 2
            r = int(math.floor(y))
            if not (_free_cell(blocked, r, vx - 1) or _free_cell(blocked, r, vx)):
                return False
        elif horizontal:
            vy = Y0 // 2
            c = int(math.floor(x))
            if not (_free_cell(blocked, vy - 1, c) or _free_cell(blocked, vy, c)):
                return False
        elif not _free_cell(blocked, int(math.floor(y)), int(math.floor(x))):
            return False
        if i > 0:
            # the segment passes t[i]; if that point is a grid vertex, check the passage around it
            px = X0 + t[i] * dX
            py = Y0 + t[i] * dY
            ix = int(round(px))
            iy = int(round(py))
            if abs(px - ix) < 1e-9 and abs(py - iy) < 1e-9 and ix % 2 == 0 and iy % 2 == 0:
                vx, vy = ix // 2, iy // 2
                if vertical or horizontal:
                    ok = False
                    for qa in range(4):
                        for qb in range(4):
                            if (_quad_side(qa, xb, yb, vx, vy, vertical) and _quad_side(qb, x, y, vx, vy, vertical)
                                    and _quad_ok(blocked, vx, vy, qa, qb)):
                                ok = True
                    if not ok:
                        return False
                elif not _quad_ok(blocked, vx, vy, _quadrant(xb, yb, vx, vy), _quadrant(x, y, vx, vy)):
                    return False
        xb = x
        yb = y
    return True


@njit(cache=True)
def _quad_side(q: int, x: float, y: float, vx: int, vy: int, vertical: bool) -> bool:
    """Is quadrant q adjacent to a point on the grid line through vertex (vx, vy)?"""
    if vertical:
        below = y < vy
        return (q in (0, 1)) if below else (q in (2, 3))
    left = x < vx
    return (q in (0, 3)) if left else (q in (1, 2))


@njit(cache=True)
def _visibility_astar(blocked: np.ndarray, NX: np.ndarray, NY: np.ndarray, s: int, g: int) -> float:
    n = NX.shape[0]
    dist = np.full(n, np.inf)
    closed = np.zeros(n, np.bool_)
    dist[s] = 0.0
    heap = [(0.0, s)]
    while len(heap) > 0:
        f, u = heapq.heappop(heap)
        if closed[u]:
            continue
        if u == g:
            return dist[u] / 2.0
        closed[u] = True
        for v in range(n):
            if closed[v]:
                continue
            d = math.hypot(NX[v] - NX[u], NY[v] - NY[u])
            nd = dist[u] + d
            if nd < dist[v] - 1e-9 and _los_touch(blocked, NX[u], NY[u], NX[v], NY[v]):
                dist[v] = nd
                heapq.heappush(heap, (nd + math.hypot(NX[g] - NX[v], NY[g] - NY[v]), v))
    return np.inf


def convex_corners(blocked: np.ndarray) -> np.ndarray:
    """Grid vertices (x, y) in cell units with exactly one blocked cell among the four around them (cells
    outside the map count as blocked)."""
    pad = np.pad(np.asarray(blocked, bool), 1, constant_values=True)
    # vertex (x, y) touches cells (y-1, x-1), (y-1, x), (y, x-1), (y, x) -> padded +1
    s = pad[:-1, :-1].astype(int) + pad[:-1, 1:] + pad[1:, :-1] + pad[1:, 1:]
    ys, xs = np.nonzero(s == 1)
    return np.c_[xs, ys]


def _any_angle_cells(blocked: np.ndarray, start: tuple[int, int], goal: tuple[int, int]) -> float:
    corners = convex_corners(blocked)
    NX = np.concatenate([[2 * start[1] + 1, 2 * goal[1] + 1], 2 * corners[:, 0]]).astype(np.int64)
    NY = np.concatenate([[2 * start[0] + 1, 2 * goal[0] + 1], 2 * corners[:, 1]]).astype(np.int64)
    return float(_visibility_astar(blocked, NX, NY, 0, 1))
