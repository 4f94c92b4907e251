"""Small helpers on map cells shared by Minotaur's modules: clipping, masks of cell sets, line of sight."""

from __future__ import annotations

import math
from collections.abc import Iterable

import numpy as np

from swarm.api import CELL_M, SOLID, cell_of


def clip(cell: tuple[int, int], shape: tuple[int, int]) -> tuple[int, int]:
    """The cell moved into a raster of ``shape``."""
    return min(max(cell[0], 0), shape[0] - 1), min(max(cell[1], 0), shape[1] - 1)


def local(cell: tuple[int, int], origin: tuple[int, int], shape: tuple[int, int]) -> tuple[int, int]:
    """A map cell in the coordinates of a window whose cell (0, 0) is map cell ``origin`` (clipped)."""
    return clip((cell[0] - origin[0], cell[1] - origin[1]), shape)


def mask(cells: Iterable[tuple[int, int]], shape: tuple[int, int], origin: tuple[int, int] = (0, 0)
         ) -> np.ndarray | None:
    """A bool raster of ``shape`` (a window whose cell (0, 0) is map cell ``origin``) with the given map
    cells set, or None when there are none."""
    cells = list(cells)
    if not cells:
        return None
    arr = np.array(cells, dtype=np.int64).reshape(-1, 2) - np.array(origin)
    ok = (arr[:, 0] >= 0) & (arr[:, 0] < shape[0]) & (arr[:, 1] >= 0) & (arr[:, 1] < shape[1])
    out = np.zeros(shape, dtype=bool)
    out[arr[ok, 0], arr[ok, 1]] = True
    return out


def line_of_sight(known: np.ndarray, a: tuple[float, float], b: tuple[float, float]) -> bool:
    """No SOLID cell on the straight line from a to b (metres; sampled every quarter cell)."""
    n = max(1, int(math.hypot(b[0] - a[0], b[1] - a[1]) / (CELL_M / 4)))
    h, w = known.shape
    for i in range(1, n):
        t = i / n
        r, c = cell_of(a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t)
        if 0 <= r < h and 0 <= c < w and known[r, c] == SOLID:
            return False
    return True
