"""Rooms as Minotaur sees them: the free space the robot reaches **without passing a doorway**.

Alg. 1-2 loop "while unexplored area is reachable without passing doorways", and the auction (Alg. 4)
asks who "can reach the doorway on the same side without passing any doorway". Both are searches on
the configuration space with every known doorway's opening closed (:meth:`Doorway.cut`): a room is a
connected component of that space. MAES does the same with a flood fill that treats doorway tiles as
blocked (docs/maes.md section 7.2).

Everything here is a search on the whole map (the costly kind; docs/performance-history.md), so the explorer calls it
only when the local follow step has nothing in range, when a room is finished, or to bid.
"""

from __future__ import annotations

import math
from collections.abc import Iterable

import numpy as np

from swarm.api import cell_of, grid

from .doorways import Doorway

SNAP_CELLS = 4
"""A point in inflated space (a robot against a wall, a door's centre) snaps this far into the space."""


def cut_doors(space: np.ndarray, doors: Iterable[Doorway], origin: tuple[int, int] = (0, 0)) -> np.ndarray:
    """A copy of ``space`` (a map or a window whose cell (0, 0) is map cell ``origin``) with every
    doorway's opening closed."""
    out = space.copy()
    h, w = out.shape
    for d in doors:
        r0, c0, r1, c1 = d.cut()
        r0, r1, c0, c1 = r0 - origin[0], r1 - origin[0], c0 - origin[1], c1 - origin[1]
        if r1 < 0 or c1 < 0 or r0 >= h or c0 >= w:
            continue
        out[max(r0, 0):r1 + 1, max(c0, 0):c1 + 1] = False
    return out


def view_cells(known: np.ndarray, space: np.ndarray, reach: int) -> np.ndarray:
    """Configuration-space cells from which a frontier is in view (the Greed target set of
    :func:`swarm.grid.nearest_reachable_unseen`: within ``reach`` 4-steps of a frontier through FREE)."""
    return grid.view_cells(known, reach) & space


def snap(space: np.ndarray, xy: tuple[float, float]) -> tuple[int, int] | None:
    h, w = space.shape
    r, c = cell_of(*xy)
    r, c = min(max(r, 0), h - 1), min(max(c, 0), w - 1)
    return grid.nearest_in(space, (r, c), SNAP_CELLS)


def nearest_in_room(cut: np.ndarray, start: tuple[int, int], targets: np.ndarray
                    ) -> tuple[tuple[int, int], float] | None:
    """The nearest target reachable without passing a doorway, and its path length (m)."""
    return grid.nearest_reachable(cut, start, targets & cut)


def door_distance(cut: np.ndarray, start: tuple[int, int], door: Doorway, side: int) -> float:
    """Path length (m) from ``start`` to the doorway's approach point on ``side`` without passing any
    doorway (``cut`` has every known doorway closed); inf when there is no such path."""
    goal = snap(cut, door.point(side, 1.0))
    if goal is None:
        return math.inf
    path = grid.plan(cut, start, goal)
    return math.inf if path is None else grid.path_length_m(grid.cells_to_metres(path))


def choose_door(space: np.ndarray, cut: np.ndarray, start: tuple[int, int], doors: list[Doorway],
                views: np.ndarray) -> tuple[Doorway, int, bool, float] | None:
    """Alg. 1's tail: the nearest unexplored doorway in the robot's room, else the nearest anywhere.

    Returns (door, side to enter from, whether it is in the room, path length to its approach point in m).
    A doorway is worth passing only when
    unseen space is reachable behind it without passing another doorway; one that is not is marked
    ``resolved`` (everything behind it is known) and skipped from then on."""
    if not doors:
        return None
    in_room = grid.distance_field(cut, [start])
    anywhere = grid.distance_field(space, [start])
    options: list[tuple[int, float, int, Doorway, int]] = []
    for k, d in enumerate(doors):
        best: tuple[int, float, int] | None = None
        for side in (-1, 1):
            cell = snap(space, d.point(side, 1.0))
            if cell is None:
                continue
            room_d = float(in_room[cell]) if cut[cell] else math.inf
            if math.isfinite(room_d):
                cand = (0, room_d, side)
            elif math.isfinite(float(anywhere[cell])):
                cand = (1, float(anywhere[cell]), side)
            else:
                continue
            if best is None or cand[:2] < best[:2]:
                best = cand
        if best is not None:
            options.append((best[0], best[1], k, d, best[2]))
    options.sort(key=lambda o: o[:3])
    for rank, dist, _, d, side in options:
        far = snap(cut, d.point(-side, 1.0))
        if far is not None and nearest_in_room(cut, far, views) is None:
            d.resolved = True
            continue
        return d, side, rank == 0, dist
    return None


def nearest_door(space: np.ndarray, start: tuple[int, int], doors: list[Doorway]) -> tuple[Doorway, int, float] | None:
    """MAES's ``GetNearestUnexploredDoorway`` (MinotaurAlgorithm.cs lines 916-931): the unexplored doorway
    nearest by path length anywhere, in or out of the robot's room, whatever lies behind it; with the side
    to enter from (the nearer approach point) and the path length (m)."""
    if not doors:
        return None
    field = grid.distance_field(space, [start])
    best: tuple[float, int, int] | None = None
    for k, d in enumerate(doors):
        for side in (-1, 1):
            cell = snap(space, d.point(side, 1.0))
            if cell is None or not math.isfinite(float(field[cell])):
                continue
            cand = (float(field[cell]), k, side)
            if best is None or cand < best:
                best = cand
    if best is None:
        return None
    return doors[best[1]], best[2], best[0]
