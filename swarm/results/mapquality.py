"""How right the robots' maps are, against the truth: what a localisation error costs (issue 50).

A cell a robot knows is *wrong* when its map says FREE where the truth is solid (false free: a planner may
send a robot through it) or SOLID where the truth is free (false occupied: a passage the robot believes
closed). Without a localisation error neither happens under the ternary lidar (it writes what the truth
says), so these are reported only for runs with one.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numba import njit

from swarm.base.types import CELL_M, FREE, SOLID
from .schema import THRESHOLDS, threshold_key


@njit(cache=True)
def _correct_free(known: np.ndarray, free: np.ndarray) -> int:  # pragma: no cover - compiled
    """Truly free cells (``free``) that some robot's map holds FREE."""
    n, h, w = known.shape
    total = 0
    for i in range(h):
        for j in range(w):
            if free[i, j]:
                for r in range(n):
                    if known[r, i, j] == FREE:
                        total += 1
                        break
    return total


class CorrectlyExplored:
    """The explored fraction counting only correctly known cells (the share of the truly free cells some
    robot's map holds FREE where they are), recorded with the time series of a run with a localisation model,
    and the first recorded tick it reaches each threshold. Recorded ticks only (``record_every``): one pass
    over every robot's map costs what the lidar's writes of a few ticks do."""

    def __init__(self, truth_solid: np.ndarray, thresholds: tuple[float, ...] = THRESHOLDS) -> None:
        self._free = np.ascontiguousarray(~np.asarray(truth_solid, dtype=np.bool_))
        self._total = max(int(self._free.sum()), 1)
        self._thresholds = tuple(sorted(thresholds))
        self._next = 0
        self.ticks_to: dict[str, int | None] = {threshold_key(t): None for t in self._thresholds}

    def record(self, tick: int, known: np.ndarray) -> float:
        """The fraction at ``tick`` from the robots' maps ``known`` (``uint8[R, H, W]``)."""
        value = _correct_free(known, self._free) / self._total
        while self._next < len(self._thresholds) and value >= self._thresholds[self._next]:
            self.ticks_to[threshold_key(self._thresholds[self._next])] = tick
            self._next += 1
        return value


@njit(cache=True)
def _counts(known: np.ndarray, solid: np.ndarray, out: np.ndarray) -> None:  # pragma: no cover - compiled
    """``out[r]`` = (known cells, false free, false occupied) of robot r's map."""
    n, h, w = known.shape
    for r in range(n):
        k = f_free = f_solid = 0
        for i in range(h):
            for j in range(w):
                v = known[r, i, j]
                if v == 0:
                    continue
                k += 1
                if v == FREE and solid[i, j]:
                    f_free += 1
                elif v == SOLID and not solid[i, j]:
                    f_solid += 1
        out[r, 0], out[r, 1], out[r, 2] = k, f_free, f_solid


def map_quality(known: np.ndarray, truth_solid: np.ndarray) -> dict[str, Any]:
    """Per robot and over all robots (``known``: ``uint8[R, H, W]`` maps; ``truth_solid``: ``bool[H, W]``):

    - the known cells and the shares of them that are false free and false occupied;
    - ``wall_offset_m``: the mean distance from a cell a map holds SOLID to the nearest truly solid cell, a
      map-alignment error (0 for a map whose walls are all where they are; a map shifted by d metres
      scores about d);
    - ``explored_correct``: the share of the truly free cells some robot's map holds FREE where they are,
      the explored fraction counting only correctly known cells."""
    from scipy import ndimage

    solid = np.ascontiguousarray(truth_solid, dtype=np.bool_)
    out = np.zeros((known.shape[0], 3), dtype=np.int64)
    _counts(known, solid, out)
    known_cells = out[:, 0]
    total = max(int(known_cells.sum()), 1)
    per = np.maximum(known_cells, 1)
    to_wall = ndimage.distance_transform_edt(~solid) * CELL_M          # metres to the nearest solid cell
    offsets = [float(to_wall[m == SOLID].mean()) if (m == SOLID).any() else 0.0 for m in known]
    return {"known_cells": [int(v) for v in known_cells],
            "false_free": [float(v) for v in out[:, 1] / per],
            "false_occupied": [float(v) for v in out[:, 2] / per],
            "false_free_share": float(out[:, 1].sum() / total),
            "false_occupied_share": float(out[:, 2].sum() / total),
            "wall_offset_m": offsets,
            "wall_offset_mean_m": float(np.mean(offsets)) if offsets else 0.0,
            "explored_correct": float(_correct_free(known, ~solid) / max(int((~solid).sum()), 1))}


__all__ = ["CorrectlyExplored", "map_quality"]
