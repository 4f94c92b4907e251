"""Shortest paths and collision tests on a bool occupancy grid (True = blocked), for IBOA and its evaluation.

* ``astar`` / ``astar_length``: the optimal 8-connected grid path (octile lengths 1 and sqrt 2, no corner
  cutting): :func:`swarm.api.grid.plan` on the free cells, the runtime's own search.
* ``any_angle_length``: the physical limit (:func:`swarm.api.grid.any_angle_length_m`), in cells.
* ``segment_free``: the strict collision test for a segment between two cell centres: every cell the
  segment touches, corners included (supercover, Dedu's integer algorithm), is free. Simplified paths
  are checked with it, so they keep a margin where ``any_angle_length`` may touch.

Coordinates are (row, col) cells; lengths are in cells.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from swarm.api import CELL_M, grid

SQRT2 = math.sqrt(2.0)


def astar(blocked: np.ndarray, start: tuple[int, int], goal: tuple[int, int]) -> list[tuple[int, int]] | None:
    """Optimal 8-connected cell path (octile, no corner cutting) or None if the goal is unreachable."""
    path = grid.plan(~np.asarray(blocked, dtype=np.bool_), start, goal)
    return None if path is None else [(int(r), int(c)) for r, c in path.tolist()]


def astar_length(blocked: np.ndarray, start: tuple[int, int], goal: tuple[int, int]) -> float:
    """Length of the optimal 8-connected path in cells (inf if unreachable)."""
    return grid.grid_length_m(~np.asarray(blocked, dtype=np.bool_), start, goal) / CELL_M


def any_angle_length(blocked: np.ndarray, start: tuple[int, int], goal: tuple[int, int]) -> float:
    """Euclidean shortest path length between two cell centres in cells (inf if disconnected)."""
    return grid.any_angle_length_m(~np.asarray(blocked, dtype=np.bool_), start, goal) / CELL_M


def path_length(points: list[tuple[float, float]] | np.ndarray) -> float:
    """Euclidean length of a polyline of (row, col) points."""
    p = np.asarray(points, dtype=float)
    return float(np.hypot(*np.diff(p, axis=0).T).sum()) if len(p) > 1 else 0.0


@njit(cache=True)
def _segment_free(blocked: np.ndarray, r0: int, c0: int, r1: int, c1: int) -> bool:
    """Supercover of the segment between two cell centres (Dedu): every touched cell must be free."""
    H, W = blocked.shape
    x, y = c0, r0
    dx, dy = c1 - c0, r1 - r0
    xstep = 1 if dx >= 0 else -1
    ystep = 1 if dy >= 0 else -1
    dx, dy = abs(dx), abs(dy)
    if blocked[y, x]:
        return False
    ddx, ddy = 2 * dx, 2 * dy
    if ddx >= ddy:
        errorprev = error = dx
        for _ in range(dx):
            x += xstep
            error += ddy
            if error > ddx:
                y += ystep
                error -= ddx
                if error + errorprev < ddx:
                    if blocked[y - ystep, x]:
                        return False
                elif error + errorprev > ddx:
                    if blocked[y, x - xstep]:
                        return False
                else:
                    if blocked[y - ystep, x] or blocked[y, x - xstep]:
                        return False
            if blocked[y, x]:
                return False
            errorprev = error
    else:
        errorprev = error = dy
        for _ in range(dy):
            y += ystep
            error += ddx
            if error > ddy:
                x += xstep
                error -= ddy
                if error + errorprev < ddy:
                    if blocked[y, x - xstep]:
                        return False
                elif error + errorprev > ddy:
                    if blocked[y - ystep, x]:
                        return False
                else:
                    if blocked[y, x - xstep] or blocked[y - ystep, x]:
                        return False
            if blocked[y, x]:
                return False
            errorprev = error
    return True


def segment_free(blocked: np.ndarray, a: tuple[int, int], b: tuple[int, int]) -> bool:
    """Whether the straight segment between the centres of cells ``a`` and ``b`` touches only free cells."""
    return bool(_segment_free(np.ascontiguousarray(blocked, dtype=np.bool_), a[0], a[1], b[0], b[1]))


def path_free(blocked: np.ndarray, points: list[tuple[int, int]]) -> bool:
    """Every segment of a polyline through cell centres is collision-free (``segment_free``)."""
    blocked = np.ascontiguousarray(blocked, dtype=np.bool_)
    return all(_segment_free(blocked, a[0], a[1], b[0], b[1]) for a, b in zip(points, points[1:]))
