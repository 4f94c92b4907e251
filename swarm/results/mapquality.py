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

from swarm.base.types import FREE, SOLID


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
    """Per robot and over all robots: the known cells and the shares of them that are false free and false
    occupied (``known``: ``uint8[R, H, W]`` maps; ``truth_solid``: ``bool[H, W]``)."""
    out = np.zeros((known.shape[0], 3), dtype=np.int64)
    _counts(known, np.ascontiguousarray(truth_solid, dtype=np.bool_), out)
    known_cells = out[:, 0]
    total = max(int(known_cells.sum()), 1)
    per = np.maximum(known_cells, 1)
    return {"known_cells": [int(v) for v in known_cells],
            "false_free": [float(v) for v in out[:, 1] / per],
            "false_occupied": [float(v) for v in out[:, 2] / per],
            "false_free_share": float(out[:, 1].sum() / total),
            "false_occupied_share": float(out[:, 2].sum() / total)}


__all__ = ["map_quality"]
