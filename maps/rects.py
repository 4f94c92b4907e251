"""Merge solid cells into few axis-aligned rectangles for the physics world.

Row runs of one material are found per row, then runs with the same columns and material in consecutive
rows are stacked into one rectangle. The rectangles are disjoint and cover exactly the solid cells, so
physics sees walls exactly where the raster has them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from swarm.base.types import CELL_M


@dataclass(frozen=True)
class WallRect:
    """A solid rectangle in cell units: rows ``[row0, row1)``, cols ``[col0, col1)``, one material id."""

    row0: int
    col0: int
    row1: int
    col1: int
    material: int

    @property
    def bounds_m(self) -> tuple[float, float, float, float]:
        """(x0, y0, x1, y1) in metres."""
        return self.col0 * CELL_M, self.row0 * CELL_M, self.col1 * CELL_M, self.row1 * CELL_M


def merge_rectangles(material: np.ndarray) -> tuple[WallRect, ...]:
    """Rectangles covering every cell with ``material != 0`` exactly once, one material each."""
    rows, cols = material.shape
    open_runs: dict[tuple[int, int, int], int] = {}
    done: list[WallRect] = []
    for r in range(rows + 1):
        current: set[tuple[int, int, int]] = set()
        if r < rows:
            row = material[r].astype(np.int16)
            change = np.flatnonzero(np.diff(row)) + 1
            starts = np.concatenate(([0], change))
            ends = np.concatenate((change, [cols]))
            values = row[starts]
            keep = values != 0
            current = set(zip(starts[keep].tolist(), ends[keep].tolist(), values[keep].tolist()))
        for key in [k for k in open_runs if k not in current]:
            c0, c1, m = key
            done.append(WallRect(open_runs.pop(key), c0, r, c1, m))
        for key in current:
            open_runs.setdefault(key, r)
    done.sort(key=lambda w: (w.row0, w.col0))
    return tuple(done)


def rasterise(rects: tuple[WallRect, ...], shape: tuple[int, int]) -> np.ndarray:
    """Inverse of :func:`merge_rectangles`: a uint8 material raster (0 where no rectangle)."""
    out = np.zeros(shape, dtype=np.uint8)
    for w in rects:
        out[w.row0:w.row1, w.col0:w.col1] = w.material
    return out
