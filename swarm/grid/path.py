"""Turning a grid path into waypoints: line-of-sight shortcutting and path length.

A segment between two cell centres is accepted only when its supercover (every cell the segment touches,
including all four cells around a corner it passes exactly through) lies in the configuration space.
With the clearance rule of :mod:`swarm.grid.cspace` that keeps the robot's disc off every wall along the
whole segment, not only at its ends.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from swarm.base.errors import InvalidInput

from swarm.base.types import CELL_M
from ._kernels import PATH_GAP, PATH_OUTSIDE, grid_path_problem, grid_segment_clear, grid_shortcut
from ._validate import check_cell, check_space


def _check_path(path: Any, shape: tuple[int, int]) -> np.ndarray:
    arr = np.asarray(path)
    if arr.ndim != 2 or arr.shape[1] != 2 or arr.shape[0] == 0 or not (
            np.issubdtype(arr.dtype, np.integer) and arr.dtype != np.bool_):
        raise InvalidInput("path", f"array {arr.dtype}{list(arr.shape)}", "a non-empty int[N, 2] array of (row, col)")
    arr = np.ascontiguousarray(arr, dtype=np.int64)
    problem = grid_path_problem(arr, shape[0], shape[1])  # one compiled pass: every plan is checked here
    if problem == PATH_OUTSIDE:
        raise InvalidInput("path", arr.tolist(), f"cells with 0 <= row < {shape[0]} and 0 <= col < {shape[1]}")
    if problem == PATH_GAP:
        raise InvalidInput("path", arr.tolist(), "consecutive cells 8-adjacent (a path from swarm.grid.plan)")
    return arr


def cells_to_metres(cells: np.ndarray) -> np.ndarray:
    """Cell centres (x, y) in metres for int[N, 2] (row, col) cells: float64[N, 2] (note the swap: row is
    y). Not validated. Cost: O(N); ~3 us for 80 cells."""
    cells = np.asarray(cells)
    return ((cells[:, ::-1] + 0.5) * CELL_M).astype(np.float64, copy=False)


def segment_clear(space: np.ndarray, a: tuple[int, int], b: tuple[int, int]) -> bool:
    """True when the straight segment between the centres of cells ``a`` and ``b`` stays in ``space``.

    Every cell the segment touches (its supercover, corners included) must be True, which with
    :func:`configuration_space` keeps the robot's disc off every wall along the whole segment. False when
    either end is outside the space. Cost: O(segment length in cells), stopping at the first blocked cell;
    ~2 us on a 300 x 300 map."""
    sp = check_space(space)
    (r0, c0), (r1, c1) = check_cell(a, sp.shape, "a"), check_cell(b, sp.shape, "b")
    return bool(grid_segment_clear(sp, r0, c0, r1, c1))


def simplify(space: np.ndarray, path: np.ndarray) -> np.ndarray:
    """Waypoints (x, y) in metres, float64[M, 2]: ``path``'s start, corners it cannot see past, and goal.

    Greedy line-of-sight shortcutting: from each kept cell, the farthest path cell reachable by a clear
    straight segment before the first blocked one. Each kept segment replaces a stretch of the path
    between the same two cells, so the result is never longer (up to float rounding) and, if every step of
    ``path`` is in ``space`` (as :func:`swarm.grid.plan` returns), every segment of the result is clear.
    Raises :class:`InvalidInput` unless ``path`` is a non-empty int[N, 2] of 8-adjacent cells on the map.
    Cost: O(N * segment length); ~0.015 ms for an 80-cell path.
    """
    sp = check_space(space)
    cells = _check_path(path, sp.shape)
    keep = grid_shortcut(sp, cells)
    return cells_to_metres(cells[keep])


def path_length_m(waypoints: np.ndarray) -> float:
    """Total length (m) of the polyline through ``waypoints`` (float[M, 2] metres); 0.0 for one point or
    none. Raises :class:`InvalidInput` for another shape. Cost: O(M); ~5 us."""
    arr = np.asarray(waypoints, dtype=np.float64)
    if arr.ndim != 2 or arr.shape[1] != 2:
        raise InvalidInput("waypoints", f"array {arr.dtype}{list(arr.shape)}", "a float[M, 2] array of (x, y) metres")
    if arr.shape[0] < 2:
        return 0.0
    step = arr[1:] - arr[:-1]  # np.diff's values, without its per-call overhead (one call per plan)
    return float(np.hypot(step[:, 0], step[:, 1]).sum())
