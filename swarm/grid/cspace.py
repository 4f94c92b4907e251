"""Where a robot may be: passable cells, the configuration space, snapping a cell into it.

Clearance rule (documented choice). Let ``need = radius_m + margin_m``. A passable cell is in the
configuration space when **its whole square** is at least ``need`` from the square of every non-passable
cell, except that a non-passable cell touching it only diagonally is allowed while ``need <= 0.354 m``
(the distance from a cell centre to a diagonal neighbour's square). Cells outside the map count as
non-passable: the robot may not leave the map. Distances are to the obstacle square's **nearest point**,
never its centre: with 0.5 m cells a centre-to-centre rule would let a 0.3 m robot sit 0.25 m from a
wall face.

This implies the rule "the cell centre is at least ``need`` from every non-passable cell" and is what
makes the guarantee hold **along straight segments**, not only at cell centres: if every cell a segment
between two cell centres touches (its supercover, corners included, see :mod:`swarm.grid.path`) is in
the configuration space, every point of the segment is at least ``need`` from every wall. Proof: a point
``p`` of the segment lies in some configuration-space cell ``c``; a blocked cell ``b`` is at least ``need``
from all of ``c``'s square, hence from ``p``, unless ``b`` is diagonal to ``c``. In that case the two
neighbours of ``c`` flanking ``b`` are 4-adjacent to ``b`` (0.25 m < need, excluded), so the segment
touches neither; it can only cross ``c`` between c's other two sides or end at c's centre, i.e. stay in
the half of ``c`` away from ``b``, at least 0.5 / sqrt(2) = 0.354 m >= need from ``b``'s square.
``tests/swarm/grid/test_grid.py`` checks the guarantee exactly on random maps for several radii.

For the default 0.3 m robot with 0.05 m margin the rule removes the passable cells 4-adjacent to a
blocked cell and keeps the ones that touch one only diagonally; along any valid segment the robot's
centre stays >= 0.354 m from every wall (>= 5 cm of slack). A corridor must be at least 3 cells (1.5 m)
wide to plan through: a 1 m (2-cell) gap has no cell centre 0.35 m from both walls. For ``need`` above
0.5 m the square rule is conservative (it asks for more room than the centres strictly need).
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from swarm.base.types import CELL_M, FREE, ROBOT_RADIUS_M, SOLID
from ._kernels import grid_configuration_space, grid_snap
from ._validate import check_cell, check_count, check_known, check_length, check_space

DEFAULT_MARGIN_M: float = 0.05
"""Extra clearance (m) on top of the robot radius, for tracking error and sensor noise: the navigator's
default, so ``configuration_space(known)`` is the space the navigator plans on."""


def passable(known: np.ndarray, unseen_traversable: bool = False) -> np.ndarray:
    """Cells the robot may enter, ignoring its size: bool[H, W], True where ``known`` is FREE (plus
    UNSEEN when ``unseen_traversable``, the navigator's optimistic mode).

    A new array. Cost: one pass over the map, O(H * W); ~0.01 ms on a 300 x 300 map.
    Raises :class:`InvalidInput` for a map that is not a 2-D array of 0/1/2."""
    k = check_known(known)
    return k != SOLID if unseen_traversable else k == FREE


def _point_square_distance(dr: int, dc: int) -> float:
    """Distance (m) from a cell's centre to the nearest point of the cell (dr, dc) away."""
    return CELL_M * math.hypot(max(abs(dr) - 0.5, 0.0), max(abs(dc) - 0.5, 0.0))


def _square_square_distance(dr: int, dc: int) -> float:
    """Distance (m) between the squares of two cells (dr, dc) apart."""
    return CELL_M * math.hypot(max(abs(dr) - 1, 0), max(abs(dc) - 1, 0))


@lru_cache(maxsize=64)
def inflation_offsets(radius_m: float, margin_m: float) -> tuple[tuple[int, int], ...]:
    """Offsets (dr, dc) such that a blocked cell at (row + dr, col + dc) removes (row, col) from the space.

    The rule of the module docstring: the two squares are nearer than ``radius + margin`` (metres); the
    diagonal neighbours are exempt while a cell centre is at least ``radius + margin`` from their square.
    A tuple of int pairs, ``()`` when ``radius + margin <= 0``. Cached per (radius, margin): a repeated
    call is a dictionary lookup; the first costs O(reach^2) with reach = ceil(need / 0.5) + 1 cells.
    """
    need = radius_m + margin_m
    if need <= 0.0:
        return ()
    reach = int(math.ceil(need / CELL_M)) + 1
    out = []
    for dr in range(-reach, reach + 1):
        for dc in range(-reach, reach + 1):
            if (abs(dr), abs(dc)) == (1, 1) and _point_square_distance(dr, dc) >= need:
                continue
            if _square_square_distance(dr, dc) < need:
                out.append((dr, dc))
    return tuple(out)


def configuration_space(known: np.ndarray, radius_m: float = ROBOT_RADIUS_M, margin_m: float = DEFAULT_MARGIN_M,
                        unseen_traversable: bool = False) -> np.ndarray:
    """Cells where the robot's centre may be: bool[H, W], the ``space`` every planning helper takes.

    A passable cell (:func:`passable`) is kept when no blocked cell (or the map's edge) is within
    ``radius_m + margin_m`` metres of its square (the clearance rule of :mod:`swarm.grid.cspace`). Frontier
    cells next to UNSEEN ones are therefore usually *not* in the space (pessimistic planning): pick goals
    with :func:`swarm.grid.nearest_reachable_unseen` or :func:`swarm.grid.view_cells`, or snap a cell
    with :func:`nearest_in`. Raises :class:`InvalidInput` for a bad map or a negative or non-finite length.

    Cost: O(H * W * radius cells); ~0.04 ms on a 300 x 300 map (0.3 m robot). Computed as an erosion of
    the passable cells by the offsets of :func:`inflation_offsets` (cells off the map count as blocked),
    decomposed into one centred row run per offset row
    (:func:`swarm.grid._kernels.grid_configuration_space`), so the cost is O(radius) passes over the map,
    not O(radius^2).
    """
    radius = check_length(radius_m, "radius_m")
    margin = check_length(margin_m, "margin_m")
    assert radius is not None and margin is not None
    return configuration_space_of(check_known(known), radius, margin, unseen_traversable)


def configuration_space_of(known: np.ndarray, radius_m: float, margin_m: float, unseen_traversable: bool
                           ) -> np.ndarray:
    """:func:`configuration_space` of an already checked map and lengths (for callers that validated)."""
    row_offsets, half_widths = _erosion_rows(radius_m, margin_m)
    out = np.empty(known.shape, dtype=np.uint8)
    grid_configuration_space(known, bool(unseen_traversable), row_offsets, half_widths, out)
    return out.view(np.bool_)


@lru_cache(maxsize=64)
def _erosion_rows(radius_m: float, margin_m: float) -> tuple[np.ndarray, np.ndarray]:
    """:func:`inflation_offsets` as one centred run per row offset: (row offsets, half widths). Each row of
    the offsets is a run [-j, j], since the distance to a square grows with the column offset. Without
    offsets (no clearance) it is the single run of the cell itself, the erosion that keeps every passable
    cell, so the compiled kernel serves that case too."""
    half_width: dict[int, int] = {0: 0}
    for dr, dc in inflation_offsets(radius_m, margin_m):
        half_width[dr] = max(half_width.get(dr, 0), abs(dc))
    rows = sorted(half_width)
    row_offsets = np.array(rows, dtype=np.int64)
    half_widths = np.array([half_width[r] for r in rows], dtype=np.int64)
    row_offsets.flags.writeable = half_widths.flags.writeable = False  # shared by every call (cached)
    return row_offsets, half_widths


def nearest_in(space: np.ndarray, cell: tuple[int, int], max_radius_cells: int | None = None
               ) -> tuple[int, int] | None:
    """The True cell of ``space`` whose centre is nearest (Euclidean) to ``cell``; ``cell`` itself if True.

    For snapping a start or goal that lies in inflated space (a frontier cell, a robot pushed against a
    wall). Returns ``(row, col)``, or None when no True cell is within ``max_radius_cells`` (in cells,
    inclusive; None searches the whole grid). Ties go to the lowest row, then the lowest column. The
    answer is nearest in a straight line, not necessarily reachable from the robot: a wall may separate
    them (use :func:`swarm.grid.nearest_reachable` when that matters).

    Cost: O(1) when ``cell`` is in the space; else O(s^2) for an answer ``s`` cells away (growing square
    windows; a window of half-size ``s`` is conclusive once its best cell is within ``s``): ~2 us one cell
    off, on a loaded 2-core machine; O(H * W) when nothing is found and the radius is None.
    """
    sp = check_space(space)
    r, c = check_cell(cell, sp.shape, "cell")
    limit = check_count(max_radius_cells, "max_radius_cells", 0, allow_none=True)
    return nearest_in_of(sp, (r, c), limit)


def nearest_in_of(space: np.ndarray, cell: tuple[int, int], limit: int | None) -> tuple[int, int] | None:
    """:func:`nearest_in` for checked inputs (a bool space, a cell inside it, a radius >= 0 or None)."""
    r, c = cell
    if space[r, c]:  # the usual case, without a call into compiled code
        return r, c
    h, w = space.shape
    found = grid_snap(space, r, c, h + w if limit is None else min(limit, h + w))  # h + w: beyond every cell
    return None if found[0] < 0 else (int(found[0]), int(found[1]))
