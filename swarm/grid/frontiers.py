"""Frontiers: known-free cells on the border of the unseen, and their connected clusters.

A frontier cell is FREE with at least one UNSEEN **4-neighbour** (documented choice). Four, not eight,
because a cell that touches the unseen only at a corner is not a place from which the unseen cell is in
plain view past the corner, and because MAES's Greed uses 4-neighbours (docs/maes.md section 7.4).
Cells outside the map are not UNSEEN. Clusters join frontier cells that touch in any of the **8**
directions (as TNF's frontiers do, section 7.3): a diagonal staircase of frontier cells along a slanted
wall is one frontier, not many.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from swarm.base.types import CELL_M
from ._kernels import grid_frontier_mask
from ._validate import check_count, check_known

_EIGHT = np.ones((3, 3), dtype=bool)


def frontier_mask(known: np.ndarray) -> np.ndarray:
    """FREE cells with at least one UNSEEN 4-neighbour: bool[H, W]. The compiled pass the target search
    uses (:func:`swarm.grid.view_cells`), so both agree on what a frontier is."""
    k = np.ascontiguousarray(check_known(known), dtype=np.uint8)  # values checked: 0..2 fit any dtype
    out = np.zeros(k.shape, dtype=bool)
    grid_frontier_mask(k, _NO_EXCLUDE, out)
    return out


_NO_EXCLUDE = np.zeros((0, 0), dtype=bool)


@dataclass(frozen=True, eq=False)
class FrontierCluster:
    """One 8-connected group of frontier cells.

    ``cells`` int[K, 2] (row, col) in row-major order (read-only); ``centroid`` (x, y) metres is the mean
    of the cell centres; ``representative`` is the cluster cell whose centre is nearest the centroid
    (ties to the first in ``cells``) -- a goal that lies on the frontier even when the cluster is curved.
    """

    cells: np.ndarray
    size: int
    centroid: tuple[float, float]
    representative: tuple[int, int]


def frontier_clusters(known: np.ndarray, min_size: int = 1) -> list[FrontierCluster]:
    """8-connected components of :func:`frontier_mask` with at least ``min_size`` cells.

    Ordered by their first cell in row-major order (scipy's labelling order), so the list is deterministic.
    """
    size_min = check_count(min_size, "min_size", 1)
    assert size_min is not None
    labels, n = ndimage.label(frontier_mask(known), structure=_EIGHT)
    if n == 0:
        return []
    rows, cols = np.nonzero(labels)
    lab = labels[rows, cols]
    order = np.argsort(lab, kind="stable")  # groups by label, row-major within each group
    rows, cols, lab = rows[order], cols[order], lab[order]
    sizes = np.bincount(lab, minlength=n + 1)[1:]
    x = (cols + 0.5) * CELL_M
    y = (rows + 0.5) * CELL_M
    cx = np.bincount(lab, weights=x, minlength=n + 1)[1:] / sizes
    cy = np.bincount(lab, weights=y, minlength=n + 1)[1:] / sizes
    d2 = (x - cx[lab - 1]) ** 2 + (y - cy[lab - 1]) ** 2
    starts = np.concatenate(([0], np.cumsum(sizes)))
    out: list[FrontierCluster] = []
    for i in range(n):
        if sizes[i] < size_min:
            continue
        a, b = starts[i], starts[i + 1]
        j = a + int(np.argmin(d2[a:b]))
        cells = np.column_stack((rows[a:b], cols[a:b])).astype(np.int64)
        cells.setflags(write=False)
        out.append(FrontierCluster(cells=cells, size=int(sizes[i]), centroid=(float(cx[i]), float(cy[i])),
                                   representative=(int(rows[j]), int(cols[j]))))
    return out
