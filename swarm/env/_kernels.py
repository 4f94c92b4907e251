"""Compiled pieces of the environments' observations: every learning robot's map crop, goal choices and
known-cell counts in one call each (a step must cost little more than a runtime tick)."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

UNSEEN, FREE, OUTSIDE = 0, 1, 3
"""Crop values: the knowledge map's UNSEEN / FREE / SOLID (0, 1, 2), and 3 for cells outside the map."""
NAV_IDLE, NAV_MOVING, NAV_FAILED = 0, 1, 2
"""A navigator's state as the pose vector needs it: idle or reached, driving to a goal, goal unreachable."""


TAN_22_5 = 0.41421356237309503
"""tan(22.5 degrees): sector boundaries, which no integer cell offset lies on."""


@njit(cache=True)
def _env_sector(dr: int, dc: int) -> int:  # pragma: no cover - compiled
    """The 45-degree sector of the offset (dr rows up, dc columns right): 0 centred on +x (east), counting
    counter-clockwise to 7 (south-east); ``floor((atan2(dr, dc) + pi / 8) / (pi / 4)) mod 8`` without the
    arc tangent."""
    adr = abs(dr)
    adc = abs(dc)
    if adr <= TAN_22_5 * adc:
        return 0 if dc > 0 else 4
    if adc <= TAN_22_5 * adr:
        return 2 if dr > 0 else 6
    if dr > 0:
        return 1 if dc > 0 else 3
    return 7 if dc > 0 else 5


@njit(cache=True)
def _env_observe(known: np.ndarray, poses: np.ndarray, learners: np.ndarray, half: int, min_goal2: float,
                 crop: np.ndarray, choices: np.ndarray, goals: np.ndarray) -> None:  # pragma: no cover - compiled
    """For learner ``l`` (robot ``learners[l]`` at (row, col) = its pose's 0.5 m cell): ``crop[l]`` its
    knowledge map over rows/cols ``cell - half .. cell + half - 1`` (OUTSIDE beyond the map), and per
    45-degree sector ``s`` (:func:`_env_sector`) the nearest frontier cell of the crop at least
    ``sqrt(min_goal2)`` cells away: ``goals[l, s]`` = (row, col), ``choices[l, s]`` = (1, dcol / half,
    drow / half), or zeros with ``goals = -1`` when the sector has none. A frontier cell is FREE with an
    UNSEEN 4-neighbour inside the map; ties go to the first in row-major order."""
    h = known.shape[1]
    w = known.shape[2]
    side = 2 * half
    best = np.empty(8)
    for l in range(learners.shape[0]):
        r = learners[l]
        kn = known[r]
        out = crop[l]
        row0 = min(max(int(poses[r, 1] * 2.0), 0), h - 1)
        col0 = min(max(int(poses[r, 0] * 2.0), 0), w - 1)
        for s in range(8):
            best[s] = np.inf
            goals[l, s, 0] = -1
            goals[l, s, 1] = -1
        for a in range(side):
            rr = row0 - half + a
            if rr < 0 or rr >= h:
                out[a, :] = OUTSIDE
                continue
            for b in range(side):
                cc = col0 - half + b
                if cc < 0 or cc >= w:
                    out[a, b] = OUTSIDE
                    continue
                v = kn[rr, cc]
                out[a, b] = v
                if v != FREE:
                    continue
                if not ((rr > 0 and kn[rr - 1, cc] == UNSEEN) or (rr < h - 1 and kn[rr + 1, cc] == UNSEEN)
                        or (cc > 0 and kn[rr, cc - 1] == UNSEEN) or (cc < w - 1 and kn[rr, cc + 1] == UNSEEN)):
                    continue
                dr = rr - row0
                dc = cc - col0
                d2 = float(dr * dr + dc * dc)
                if d2 < min_goal2:
                    continue
                s = _env_sector(dr, dc)
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
def _env_neighbours(poses: np.ndarray, link: np.ndarray, rssi: np.ndarray, sensitivity: np.ndarray,
                    learners: np.ndarray, scale: float, margin_db: float, observe_all: bool,
                    out: np.ndarray) -> None:  # pragma: no cover - compiled
    """``out[l, k]`` for learner ``l`` (robot ``i = learners[l]``) and the k-th other robot ``j`` (ids in order,
    ``i`` skipped): (linked, dx * scale, dy * scale, margin / margin_db) with ``linked = link[i, j]`` (j reaches
    i) and the margin ``rssi[i, j] - sensitivity[i]`` clipped to +-margin_db (NaN and -inf: -margin_db); zeros
    for an unlinked robot unless ``observe_all``."""
    n = poses.shape[0]
    for l in range(learners.shape[0]):
        i = learners[l]
        k = 0
        for j in range(n):
            if j == i:
                continue
            linked = link[i, j]
            if linked or observe_all:
                m = rssi[i, j] - sensitivity[i]
                if not (m > -margin_db):  # NaN, -inf, or below
                    m = -margin_db
                elif m > margin_db:
                    m = margin_db
                out[l, k, 0] = 1.0 if linked else 0.0
                out[l, k, 1] = (poses[j, 0] - poses[i, 0]) * scale
                out[l, k, 2] = (poses[j, 1] - poses[i, 1]) * scale
                out[l, k, 3] = m / margin_db
            else:
                out[l, k, 0] = 0.0
                out[l, k, 1] = 0.0
                out[l, k, 2] = 0.0
                out[l, k, 3] = 0.0
            k += 1


@njit(cache=True)
def _window_count(known: np.ndarray, r: int, row: int, col: int, radius: int) -> int:  # pragma: no cover - compiled
    """Known (not UNSEEN) cells of robot ``r``'s map within ``radius`` cells (a square) of (row, col)."""
    h = known.shape[1]
    w = known.shape[2]
    n = 0
    for rr in range(max(row - radius, 0), min(row + radius + 1, h)):
        for cc in range(max(col - radius, 0), min(col + radius + 1, w)):
            if known[r, rr, cc] != UNSEEN:
                n += 1
    return n


@njit(cache=True)
def _env_before(known: np.ndarray, learners: np.ndarray, poses: np.ndarray, cells: np.ndarray, valid: np.ndarray,
                radius: int, before: np.ndarray, after: np.ndarray) -> None:  # pragma: no cover - compiled
    """Before a tick's scan: ``before[l]``, the known cells of learner ``l``'s map in the window around its
    pose's cell, which becomes ``cells[l]``. When the robot is still in the cell of the last count and
    nothing was merged into its map since (``valid[l]``), that count (``after[l]``) is reused."""
    for l in range(learners.shape[0]):
        r = learners[l]
        row = int(poses[r, 1] * 2.0)
        col = int(poses[r, 0] * 2.0)
        if valid[l] and row == cells[l, 0] and col == cells[l, 1]:
            before[l] = after[l]
            continue
        cells[l, 0] = row
        cells[l, 1] = col
        before[l] = _window_count(known, r, row, col, radius)


@njit(cache=True)
def _env_after(known: np.ndarray, learners: np.ndarray, cells: np.ndarray, valid: np.ndarray, radius: int,
               cast: np.ndarray, before: np.ndarray, after: np.ndarray, began: np.ndarray, own_new: np.ndarray,
               known_count: np.ndarray, began_any: np.ndarray, rewards: np.ndarray, own_weight: float, shared: float,
               collision_penalty: float) -> None:  # pragma: no cover - compiled
    """After the scan: per learner the cells its lidar revealed (``after - before`` over the same window; 0
    without counting for a robot whose rays were not cast, ``cast[r]`` False: its scan wrote nothing),
    contacts begun, and the tick's reward: ``own_weight`` per revealed cell + ``shared`` (team area and
    time) - the collision penalty. The window count is then valid until a merge."""
    for l in range(learners.shape[0]):
        r = learners[l]
        after[l] = _window_count(known, r, cells[l, 0], cells[l, 1], radius) if cast[r] else before[l]
        valid[l] = True
        new = after[l] - before[l]
        own_new[l] += new
        known_count[l] += new
        hit = began[r]
        if hit:
            began_any[l] = True
        rewards[l] += own_weight * new + shared - (collision_penalty if hit else 0.0)


@njit(cache=True)
def _env_vectors(poses: np.ndarray, learners: np.ndarray, width: float, height: float, began: np.ndarray,
                 nav: np.ndarray, known_count: np.ndarray, map_cells: float, time: float,
                 msgs: np.ndarray, updates: np.ndarray, nbytes: np.ndarray, last_contact: np.ndarray, tick: int,
                 per: float, log_bytes: float, contact_ticks: float, pose: np.ndarray,
                 inbox: np.ndarray) -> None:  # pragma: no cover - compiled
    """The ``pose`` and ``inbox`` vectors of every learner (fields: swarm.env.core.POSE_FIELDS, INBOX_FIELDS)."""
    for l in range(learners.shape[0]):
        r = learners[l]
        pose[l, 0] = poses[r, 0] * (2.0 / width) - 1.0
        pose[l, 1] = poses[r, 1] * (2.0 / height) - 1.0
        pose[l, 2] = math.cos(poses[r, 2])
        pose[l, 3] = math.sin(poses[r, 2])
        pose[l, 4] = 1.0 if began[l] else 0.0
        pose[l, 5] = 1.0 if nav[l] == NAV_MOVING else 0.0
        pose[l, 6] = 1.0 if nav[l] == NAV_FAILED else 0.0
        pose[l, 7] = known_count[l] / map_cells
        pose[l, 8] = time
        inbox[l, 0] = min(msgs[l] * per, 1.0)
        inbox[l, 1] = min(updates[l] * per, 1.0)
        inbox[l, 2] = min(math.log1p(nbytes[l]) / log_bytes, 1.0)
        since = contact_ticks if last_contact[l] < 0 else tick - last_contact[l]
        inbox[l, 3] = min(since / contact_ticks, 1.0)


@njit(cache=True)
def _env_features(known: np.ndarray, poses: np.ndarray, learners: np.ndarray, half: int, min_goal2: float,
                  width: float, height: float, began: np.ndarray, nav: np.ndarray, known_count: np.ndarray,
                  map_cells: float, time: float, msgs: np.ndarray, updates: np.ndarray, nbytes: np.ndarray,
                  last_contact: np.ndarray, tick: int, per: float, log_bytes: float, contact_ticks: float,
                  has_links: bool, link: np.ndarray, rssi: np.ndarray, sensitivity: np.ndarray, scale: float,
                  margin_db: float, observe_all: bool, crop: np.ndarray, choices: np.ndarray, goals: np.ndarray,
                  pose: np.ndarray, inbox: np.ndarray, neighbours: np.ndarray,
                  masks: np.ndarray) -> None:  # pragma: no cover - compiled
    """Every learner's observation in one call: :func:`_env_observe`, :func:`_env_vectors`,
    :func:`_env_neighbours` (if ``has_links``) and, if ``masks`` has rows, the goal-mode action masks (keep and
    delegate always, a sector when it has a frontier)."""
    _env_observe(known, poses, learners, half, min_goal2, crop, choices, goals)
    _env_vectors(poses, learners, width, height, began, nav, known_count, map_cells, time, msgs, updates, nbytes,
                 last_contact, tick, per, log_bytes, contact_ticks, pose, inbox)
    if has_links:
        _env_neighbours(poses, link, rssi, sensitivity, learners, scale, margin_db, observe_all, neighbours)
    else:
        neighbours[:] = 0.0
    for l in range(masks.shape[0]):
        masks[l, :] = 1
        for s in range(8):
            masks[l, 1 + s] = 1 if choices[l, s, 0] > 0 else 0
