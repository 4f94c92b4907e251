"""Raster helpers shared by the generators: tile -> cell upscaling, material patches, traversability."""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from .model import CELLS_PER_TILE

FOUR = ndimage.generate_binary_structure(2, 1)
"""4-connectivity (a cross)."""

ROBOT_FOOTPRINT = FOUR
"""Cells a 0.6 m robot centred in a 0.5 m cell overlaps: its own and its 4 neighbours.

The robot's radius (0.3 m) exceeds the 0.25 m from a cell centre to its edges but not the 0.354 m to
its corners, so the footprint is exactly the cross."""


def tiles_to_cells(tiles: np.ndarray) -> np.ndarray:
    """Upscale a per-tile raster (1 m) to cells (0.5 m)."""
    return np.repeat(np.repeat(tiles, CELLS_PER_TILE, axis=0), CELLS_PER_TILE, axis=1)


def pick_weighted(rng: np.random.Generator, ids: np.ndarray, weights: np.ndarray, size: int) -> np.ndarray:
    """Draw ``size`` ids with probability proportional to ``weights``."""
    p = np.asarray(weights, dtype=float)
    return rng.choice(np.asarray(ids), size=size, p=p / p.sum())


def smooth_patches(material: np.ndarray, solid: np.ndarray, iterations: int, n_materials: int) -> np.ndarray:
    """Majority-filter wall materials over 3x3 windows so they form patches rather than salt-and-pepper.

    Only solid cells change; each takes the most common material among the solid cells around it (ties go
    to the lowest id, so the result is deterministic).
    """
    kernel = np.ones((3, 3), dtype=np.int32)
    out = material.copy()
    for _ in range(iterations):
        counts = np.stack([
            ndimage.convolve(((out == m) & solid).astype(np.int32), kernel, mode="constant")
            for m in range(1, n_materials)
        ])
        best = counts.argmax(axis=0).astype(np.uint8) + 1
        new = np.where(solid, best, 0).astype(np.uint8)
        if np.array_equal(new, out):
            break
        out = new
    return out


def robot_space(free: np.ndarray) -> np.ndarray:
    """Cells where a robot's centre may sit: free cells whose whole footprint is free."""
    return ndimage.binary_erosion(free, structure=ROBOT_FOOTPRINT, border_value=0)


NEAR = np.ones((3, 3), dtype=bool)
"""A cell and its 8 neighbours: cells within 0.71 m of a cell centre."""


def reachable_free(free: np.ndarray, start_mask: np.ndarray | None = None) -> np.ndarray:
    """Free cells next to (8-neighbourhood) the largest (or the given) 4-connected component of robot space:
    the free space a robot can get within arm's reach of (room corners included)."""
    space = robot_space(free)
    labels, n = ndimage.label(space, structure=FOUR)
    if n == 0:
        return np.zeros_like(free)
    if start_mask is not None:
        keep = np.unique(labels[start_mask & space])
        keep = keep[keep > 0]
        main = np.isin(labels, keep)
    else:
        sizes = np.bincount(labels.ravel())
        sizes[0] = 0
        main = labels == int(sizes.argmax())
    return ndimage.binary_dilation(main, structure=NEAR) & free


def nearest_wall_material(material: np.ndarray, solid: np.ndarray) -> np.ndarray:
    """For every cell, the material of the nearest solid cell (used to fill cells turned into wall)."""
    _, (ri, ci) = ndimage.distance_transform_edt(~solid, return_indices=True)
    return material[ri, ci]
