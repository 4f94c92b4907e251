"""Doorway detection on a knowledge map (paper section 3.3, Alg. 3, section 4.3), as gaps in wall faces.

The paper fits lines to the wall points the robot sees and distinguishes two cases:

- **single wall**: the wall stops; the robot moves on by the door width; if the wall continues in line,
  the gap is a doorway;
- **two walls**: the extended lines of two walls intersect; the robot moves until the intersection is
  seen; if it is open and the gap between the two wall ends (the jambs) is a valid door width, it is a
  doorway (a door in a room's corner).

On a 0.5 m occupancy grid both cases become one test on a straight line of cells, which we run along
every row and column of the map around the robot. A **doorway** is a run of FREE cells of width
``[min, max]`` cells on a line, closed by SOLID cells (the jambs) on both ends, seen from a side ``s`` (the
cells in front of the run on side ``s`` are FREE), leading through (the run's middle cells one and two
cells behind it are not SOLID: an opening, not a notch), and such that

- the wall face continues in line beyond one jamb for ``face`` cells (SOLID on the line, FREE in front),
  and beyond the other jamb either the same (**single-wall case**) or a wall runs from the other jamb
  into side ``s`` for ``face`` cells (**two-wall case**: the extended line of the first wall meets the
  second wall, and the gap between them is the door).

A corridor as wide as a door is not a doorway along its length (its cross-sections have walls running
across the line, not along it) but its mouth into a room is (the room's wall face continues on both
sides); a gap wider than ``max`` is a hallway. Because only SOLID and FREE cells count, a gap is accepted
only once it is seen: with a noise-free lidar a detection is a gap that exists in the true map.

Departures, on purpose:

- Walls are the rows and columns of the grid: the detector finds doors in axis-aligned walls only (all
  generated buildings and hand-made test maps), not in slanted walls. The paper fits lines at any angle
  but its evaluation is on axis-aligned buildings, and it reports the method useless in caves anyway.
- "Move forward by the door width" and "move towards the intersection until it is explored" are not
  separate motions: the detector is a pure function of the map, so a gap is accepted as soon as the
  map shows its far jamb, whoever saw it. :func:`pending_gaps` lists the gaps whose far end is still
  unseen so that the explorer can go and look (Minotaur's ``inspect`` targets).
"""

from __future__ import annotations

import numba
import numpy as np

from swarm.api import CELL_M, FREE, SOLID, UNSEEN

from .doorways import Doorway

_CAP = 4096
_MAX_DEPTH = 4


@numba.njit(cache=True, inline="always")
def _face(k: np.ndarray, r: int, c: int, step: int, s: int, n: int) -> bool:
    """A wall face continues in line from (r, c) for ``n`` cells in direction ``step``, FREE in front on s."""
    h, w = k.shape
    rr = r + s
    if rr < 0 or rr >= h:
        return False
    for i in range(n):
        col = c + step * i
        if col < 0 or col >= w or k[r, col] != SOLID or k[rr, col] != FREE:
            return False
    return True


@numba.njit(cache=True, inline="always")
def _perpendicular(k: np.ndarray, r: int, c: int, inner: int, s: int, n: int) -> bool:
    """A wall runs from the jamb (r, c) into side s for ``n`` cells, its face towards the gap (column
    ``inner``) FREE: the second wall of the two-wall case."""
    h = k.shape[0]
    for i in range(1, n + 1):
        row = r + s * i
        if row < 0 or row >= h or k[row, c] != SOLID or k[row, inner] != FREE:
            return False
    return True


@numba.njit(cache=True, inline="always")
def _accept(k: np.ndarray, r: int, c0: int, c1: int, s: int, face: int) -> bool:
    h = k.shape[0]
    if r + s < 0 or r + s >= h or r - 2 * s < 0 or r - 2 * s >= h:
        return False
    for c in range(c0, c1 + 1):
        if k[r + s, c] != FREE:
            return False
    width = c1 - c0 + 1
    for c in range(c0 + (width - 1) // 2, c0 + width // 2 + 1):
        if k[r - s, c] == SOLID or k[r - 2 * s, c] == SOLID:
            return False
    face_left = _face(k, r, c0 - 1, -1, s, face)
    face_right = _face(k, r, c1 + 1, 1, s, face)
    if face_left and face_right:
        return True
    if face_left and _perpendicular(k, r, c1 + 1, c1, s, face):
        return True
    return face_right and _perpendicular(k, r, c0 - 1, c0, s, face)


@numba.njit(cache=True, inline="always")
def _depth(k: np.ndarray, r: int, c0: int, c1: int, s: int, cap: int) -> int:
    """Rows of wall the gap runs through, from the face row r away from side s (at most ``cap``)."""
    h, w = k.shape
    mid = (c0 + c1) // 2
    d = 0
    row = r
    while d < cap and 0 <= row < h:
        left = c0 - 1 >= 0 and k[row, c0 - 1] == SOLID
        right = c1 + 1 < w and k[row, c1 + 1] == SOLID
        if not (left and right) or k[row, mid] == SOLID:
            break
        d += 1
        row -= s
    return max(d, 1)


@numba.njit(cache=True)
def _scan(k: np.ndarray, wmin: int, wmax: int, face: int, max_depth: int, found: np.ndarray,
          pending: np.ndarray) -> tuple[int, int]:
    """Scan every row of ``k``. ``found`` rows: (r, c0, c1, s * depth) accepted gaps seen from side s
    through a wall ``depth`` lines thick; ``pending`` rows:
    (r, c, s, j): an UNSEEN cell at (r, c) that ends a FREE run starting at the end (r, j) of a wall face."""
    h, w = k.shape
    n = 0
    m = 0
    cap_f = found.shape[0]
    cap_p = pending.shape[0]
    for r in range(1, h - 1):
        c = 1
        while c < w - 1:
            if k[r, c] != FREE:
                c += 1
                continue
            e = c
            while e < w and k[r, e] == FREE:
                e += 1
            width = e - c
            left = k[r, c - 1]
            right = k[r, e] if e < w else UNSEEN
            if left == SOLID and right == SOLID and wmin <= width <= wmax:
                for s in range(-1, 2, 2):
                    if n < cap_f and _accept(k, r, c, e - 1, s, face):
                        found[n, 0] = r
                        found[n, 1] = c
                        found[n, 2] = e - 1
                        found[n, 3] = s * _depth(k, r, c, e - 1, s, max_depth)  # sign: side; size: depth
                        n += 1
            elif width < wmax and ((left == SOLID and right == UNSEEN and e < w)
                                   or (left == UNSEEN and right == SOLID)):
                for s in range(-1, 2, 2):
                    rr = r + s
                    if rr < 0 or rr >= h:
                        continue
                    front = True
                    for cc in range(c, e):
                        if k[rr, cc] != FREE:
                            front = False
                            break
                    if not front:
                        continue
                    if left == SOLID and _face(k, r, c - 1, -1, s, face) and m < cap_p:
                        pending[m, 0] = r
                        pending[m, 1] = e
                        pending[m, 2] = s
                        pending[m, 3] = c - 1
                        m += 1
                    elif right == SOLID and _face(k, r, e, 1, s, face) and m < cap_p:
                        pending[m, 0] = r
                        pending[m, 1] = c - 1
                        pending[m, 2] = s
                        pending[m, 3] = e
                        m += 1
            c = e
    return n, m


def cells(width_m: float) -> int:
    """Whole cells in a length (rounded, so 2 m is 4 cells and 1.5 m is 3)."""
    return max(1, round(width_m / CELL_M))


def _scan_axis(k: np.ndarray, wmin: int, wmax: int, face: int) -> tuple[np.ndarray, np.ndarray]:
    found = np.empty((_CAP, 4), dtype=np.int64)
    pending = np.empty((_CAP, 4), dtype=np.int64)
    n, m = _scan(k, wmin, wmax, face, _MAX_DEPTH, found, pending)
    return found[:n], pending[:m]


Pending = tuple[int, int, int, int, tuple[int, int]]


def scan(known: np.ndarray, min_width_m: float, max_width_m: float, wall_continue_m: float,
         origin: tuple[int, int] = (0, 0)) -> tuple[list[Doorway], list[Pending]]:
    """Doorways visible in ``known`` (a knowledge map, or a window of one whose cell (0, 0) is map cell
    ``origin``), each gap once, and pending gaps (see :func:`pending_gaps`), in map coordinates.
    ``sides`` is left 0: who saw a doorway from where is the caller's fact."""
    wmin, wmax, face = cells(min_width_m), cells(max_width_m), cells(wall_continue_m)
    k = np.ascontiguousarray(known, dtype=np.uint8)
    doors: list[Doorway] = []
    pending: list[Pending] = []
    r0, c0 = origin
    for axis, grid in ((0, k), (1, np.ascontiguousarray(k.T))):
        found, pend = _scan_axis(grid, wmin, wmax, face)
        keys: set[tuple[int, int, int, int]] = set()
        for line, a, b, sd in found.tolist():
            s = 1 if sd > 0 else -1
            depth = abs(sd)
            lo = min(line, line - s * (depth - 1))      # the wall spans lines [lo, lo + depth)
            if (a, b, lo, depth) in keys:              # the same gap found from the wall's other face
                continue
            keys.add((a, b, lo, depth))
            along = (a + b + 1) / 2 * CELL_M
            across = (lo + depth / 2) * CELL_M
            if axis == 0:
                door = Doorway(x=along + c0 * CELL_M, y=across + r0 * CELL_M, axis=0,
                               width=(b - a + 1) * CELL_M, depth=depth * CELL_M)
            else:
                door = Doorway(x=across + c0 * CELL_M, y=along + r0 * CELL_M, axis=1,
                               width=(b - a + 1) * CELL_M, depth=depth * CELL_M)
            doors.append(door)
        for line, pos, s, jamb in pend.tolist():
            if axis == 0:
                pending.append((line + r0, pos + c0, s, 0, (line + r0, jamb + c0)))
            else:
                pending.append((pos + r0, line + c0, 0, s, (jamb + r0, line + c0)))
    return doors, pending


def detect(known: np.ndarray, min_width_m: float, max_width_m: float, wall_continue_m: float,
           origin: tuple[int, int] = (0, 0)) -> list[Doorway]:
    """Every doorway visible in ``known`` (see :func:`scan`)."""
    return scan(known, min_width_m, max_width_m, wall_continue_m, origin)[0]


def pending_gaps(known: np.ndarray, min_width_m: float, max_width_m: float, wall_continue_m: float,
                 origin: tuple[int, int] = (0, 0)) -> list[Pending]:
    """Gaps that may be doorways once their far end is seen, in map cells: (row, col) of the UNSEEN cell
    that ends a short FREE run after a wall face's end, the side (drow, dcol) the gap is seen from, and the
    wall face's end cell (the jamb; it names the gap while the run grows)."""
    return scan(known, min_width_m, max_width_m, wall_continue_m, origin)[1]
