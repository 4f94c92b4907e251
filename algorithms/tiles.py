"""MAES's 1 m coarse tiles for the explorers that move tile by tile (Wall Follower, Brick & Mortar).

A tile ``(tx, ty)`` is the square ``[tx, tx + 1) x [ty, ty + 1)`` metres, 2 x 2 of the knowledge map's
0.5 m cells (MAES's ``CoarseGrainedMap``, docs/maes.md section 5.4). It is *blocked* when one of its cells
is SOLID or it leaves the map: a tile with none has its centre at least 0.5 m from every solid cell, so a
0.3 m robot stands there and drives straight between two such tiles side by side.
"""

from __future__ import annotations

import math

import numpy as np

from swarm.api import CELL_M, SOLID

TILE_M = 1.0
CELLS = int(round(TILE_M / CELL_M))
STEP = ((0, 1), (1, 0), (0, -1), (-1, 0))
"""(dx, dy) of one tile north, east, south, west: clockwise, as MAES's ``Direction`` enums."""


def tile_of(x: float, y: float) -> tuple[int, int]:
    """The tile holding the point (MAES's coarse position)."""
    return math.floor(x / TILE_M), math.floor(y / TILE_M)


def tile_goal(tile: tuple[int, int]) -> tuple[float, float]:
    """Where to send the robot for ``tile``: the centre of its upper right cell. The tile's own centre is a
    cell corner, from which the navigator would first drive to the centre of the cell it is in; the
    navigator moves a goal inside inflated space (a tile beside a wall) to the nearest cell it can reach."""
    return (tile[0] + 0.75) * TILE_M, (tile[1] + 0.75) * TILE_M


def blocked(known: np.ndarray, tile: tuple[int, int]) -> bool:
    """One of the tile's cells is SOLID, or the tile is not wholly on the map."""
    r, c = tile[1] * CELLS, tile[0] * CELLS
    h, w = known.shape
    if r < 0 or c < 0 or r + CELLS > h or c + CELLS > w:
        return True
    return bool((known[r:r + CELLS, c:c + CELLS] == SOLID).any())


def step(tile: tuple[int, int], direction: int, sign: int = 1) -> tuple[int, int]:
    """The tile ``sign`` steps from ``tile`` in compass ``direction`` (0 north, 1 east, 2 south, 3 west)."""
    dx, dy = STEP[direction]
    return tile[0] + sign * dx, tile[1] + sign * dy
