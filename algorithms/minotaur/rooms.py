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
from numba import njit

from swarm.api import cell_of, grid

from .doorways import Doorway, DoorwayBook

SNAP_CELLS = 4
"""A point in inflated space (a robot against a wall, a door's centre) snaps this far into the space."""


def cut_doors(space: np.ndarray, doors: Iterable[Doorway], origin: tuple[int, int] = (0, 0)) -> np.ndarray:
    """A copy of ``space`` (a map or a window whose cell (0, 0) is map cell ``origin``) with every
    doorway's opening closed. A :class:`DoorwayBook` gives its boxes at once (kept per book)."""
    boxes = doors.cut_boxes() if isinstance(doors, DoorwayBook) else np.array(
        [d.cut() for d in doors], dtype=np.int64).reshape(-1, 4)
    out = space.copy()
    _close(out, boxes, origin[0], origin[1])
    return out


@njit(cache=True)
def _close(out, boxes, r_origin, c_origin):  # pragma: no cover - compiled
    """``out[r0:r1 + 1, c0:c1 + 1] = False`` for each box (r0, c0, r1, c1) shifted by the origin, clipped
    to ``out``; boxes wholly outside are skipped."""
    h, w = out.shape
    for i in range(boxes.shape[0]):
        r0, c0 = boxes[i, 0] - r_origin, boxes[i, 1] - c_origin
        r1, c1 = boxes[i, 2] - r_origin, boxes[i, 3] - c_origin
        if r1 < 0 or c1 < 0 or r0 >= h or c0 >= w:
            continue
        for r in range(max(r0, 0), min(r1 + 1, h)):
            for c in range(max(c0, 0), min(c1 + 1, w)):
                out[r, c] = False


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
    cells = [(k, side, snap(space, d.point(side, 1.0))) for k, d in enumerate(doors) for side in (-1, 1)]
    cells = [(k, side, cell) for k, side, cell in cells if cell is not None]
    # the door-cut and the plain distance from start, read only at the approach cells (grid.field_at: the
    # distance fields' values there), the plain one only where the door-cut one is inf
    room = _field_at(cut, start, [cell for _, _, cell in cells if cut[cell]])
    room_d = [room.get(cell, math.inf) if cut[cell] else math.inf for _, _, cell in cells]
    plain = _field_at(space, start, [cell for (_, _, cell), d in zip(cells, room_d) if not math.isfinite(d)])
    best_of: dict[int, tuple[int, float, int]] = {}
    for (k, side, cell), in_d in zip(cells, room_d):
        if math.isfinite(in_d):
            cand = (0, in_d, side)
        elif math.isfinite(plain.get(cell, math.inf)):
            cand = (1, plain[cell], side)
        else:
            continue
        best = best_of.get(k)
        if best is None or cand[:2] < best[:2]:
            best_of[k] = cand
    options: list[tuple[int, float, int, Doorway, int]] = [
        (best[0], best[1], k, doors[k], best[2]) for k, best in sorted(best_of.items())]
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
    cells = [(k, side, snap(space, d.point(side, 1.0))) for k, d in enumerate(doors) for side in (-1, 1)]
    field = _field_at(space, start, [cell for _, _, cell in cells if cell is not None])
    best: tuple[float, int, int] | None = None
    for k, side, cell in cells:
        if cell is None or not math.isfinite(field[cell]):
            continue
        cand = (field[cell], k, side)
        if best is None or cand < best:
            best = cand
    if best is None:
        return None
    return doors[best[1]], best[2], best[0]


def _field_at(space: np.ndarray, start: tuple[int, int], cells: list[tuple[int, int]]
              ) -> dict[tuple[int, int], float]:
    """``float(grid.distance_field(space, [start])[cell])`` for each of ``cells``, as a dict."""
    if not cells:
        return {}
    values = grid.field_at(space, [start], np.array(cells, dtype=np.int64).reshape(-1, 2))
    return dict(zip(cells, values.tolist()))
