"""Compiled pieces of the environments' observations: every learning robot's map crop, goal choices and
known-cell counts in one call each (a step must cost little more than a runtime tick)."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

UNSEEN, FREE, OUTSIDE = 0, 1, 3
"""Crop values: the knowledge map's UNSEEN / FREE / SOLID (0, 1, 2), and 3 for cells outside the map."""


@njit(cache=True)
def _env_observe(known: np.ndarray, cells: np.ndarray, learners: np.ndarray, half: int, min_goal2: float,
                 crop: np.ndarray, choices: np.ndarray, goals: np.ndarray) -> None:  # pragma: no cover - compiled
    """For learner ``l`` (robot ``learners[l]`` at cell ``cells[robot]`` = (row, col)): ``crop[l]`` its
    knowledge map over rows/cols ``cell - half .. cell + half - 1`` (OUTSIDE beyond the map), and per
    45-degree sector ``s`` (sector 0 centred on +x, counter-clockwise) the nearest frontier cell of the crop
    at least ``sqrt(min_goal2)`` cells away: ``goals[l, s]`` = (row, col), ``choices[l, s]`` = (1, dcol /
    half, drow / half), or zeros with ``goals = -1`` when the sector has none. A frontier cell is FREE with
    an UNSEEN 4-neighbour inside the map; ties go to the first in row-major order."""
    h = known.shape[1]
    w = known.shape[2]
    side = 2 * half
    sector_width = math.pi / 4.0
    for l in range(learners.shape[0]):
        r = learners[l]
        row0 = cells[r, 0]
        col0 = cells[r, 1]
        best = np.full(8, np.inf)
        for s in range(8):
            goals[l, s, 0] = -1
            goals[l, s, 1] = -1
        for a in range(side):
            rr = row0 - half + a
            for b in range(side):
                cc = col0 - half + b
                if rr < 0 or rr >= h or cc < 0 or cc >= w:
                    crop[l, a, b] = OUTSIDE
                    continue
                v = known[r, rr, cc]
                crop[l, a, b] = v
                if v != FREE:
                    continue
                if not ((rr > 0 and known[r, rr - 1, cc] == UNSEEN) or (rr < h - 1 and known[r, rr + 1, cc] == UNSEEN)
                        or (cc > 0 and known[r, rr, cc - 1] == UNSEEN) or (cc < w - 1 and known[r, rr, cc + 1] == UNSEEN)):
                    continue
                dr = rr - row0
                dc = cc - col0
                d2 = float(dr * dr + dc * dc)
                if d2 < min_goal2:
                    continue
                s = int(math.floor((math.atan2(dr, dc) + sector_width / 2.0) / sector_width)) % 8
                if s < 0:
                    s += 8
                if d2 < best[s]:
                    best[s] = d2
                    goals[l, s, 0] = rr
                    goals[l, s, 1] = cc
        for s in range(8):
            if goals[l, s, 0] >= 0:
                choices[l, s, 0] = 1.0
                choices[l, s, 1] = (goals[l, s, 1] - col0) / half
                choices[l, s, 2] = (goals[l, s, 0] - row0) / half
            else:
                choices[l, s, 0] = 0.0
                choices[l, s, 1] = 0.0
                choices[l, s, 2] = 0.0


@njit(cache=True)
def _env_window_counts(known: np.ndarray, learners: np.ndarray, cells: np.ndarray, radius: int,
                       out: np.ndarray) -> None:  # pragma: no cover - compiled
    """``out[l]``: known (not UNSEEN) cells of robot ``learners[l]``'s map within ``radius`` cells (a square)
    of ``cells[l]`` = (row, col)."""
    h = known.shape[1]
    w = known.shape[2]
    for l in range(learners.shape[0]):
        r = learners[l]
        r0 = max(cells[l, 0] - radius, 0)
        r1 = min(cells[l, 0] + radius + 1, h)
        c0 = max(cells[l, 1] - radius, 0)
        c1 = min(cells[l, 1] + radius + 1, w)
        n = 0
        for rr in range(r0, r1):
            for cc in range(c0, c1):
                if known[r, rr, cc] != UNSEEN:
                    n += 1
        out[l] = n
