"""Wall following and spiralling (paper section 3.1, Alg. 1-2, section 4.2) as a choice of the next
waypoint around the robot.

Section 4.2: the robot looks at the walls it sees, keeps following one while "there are unseen tiles in
front of it", prefers to keep moving the way it is moving, stays "a little less than max vision range"
from the wall, follows a wall around a bend, and after a lap "spirals around the edge of the previously
explored area". MAES (docs/maes.md section 7.2) does this with wall segments fitted to lidar hits, targets
offset by VisionRadius - 2 tiles perpendicular to the wall, and an edge ring at VisionRadius + 1..2
swept counter-clockwise from the robot's right.

Here, on the robot's own grid, around the robot (within ``radius`` cells):

- a **wall end** is a SOLID cell with FREE in front (a wall face) whose neighbour along the wall is
  UNSEEN, with no SOLID in front of that neighbour: the wall continues into the unknown (an unseen cell
  with a wall in front of it is the corner cell of two walls, which the lidar cannot hit). Its target
  is in front of it at the follow distance, or half way across when the free space in front is
  narrower than twice that (a 4 m hall is followed in its middle);
- an **edge** cell is a FREE cell next to UNSEEN: the edge of explored space. Its target is
  ``edge`` cells back into explored space;
- candidates are taken in **spin order**: by the angle from the robot's right (counter-clockwise spin,
  the wall on the right) or left (clockwise), turning towards the front, relative to the direction the
  robot last chose to travel, so it keeps going the way it goes and turns with the wall. The first
  candidate whose target is in the same room (finite door-cut distance) wins.

A lap and the spiral are not separate states: once the room's walls are seen no wall end is left, and
the same sweep follows the edge of the explored area inwards, lap after lap (section 4.2). When no
candidate is in range the caller falls back to the nearest unseen cell in the room (Alg. 1's "else").

Departure: MAES drives straight to its targets with no planning and sweeps edges from behind the robot
(an operator-precedence bug, docs/maes.md section 7.2); we hand targets to the runtime's planner and start the sweep at
the robot's side as the paper describes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from swarm.api import FREE, SOLID

_DIRS = ((1, 0), (-1, 0), (0, 1), (0, -1))   # (drow, dcol)
MAX_TRIES = 16


@dataclass(frozen=True)
class FollowTarget:
    """A chosen waypoint (window cells), what kind of boundary it follows, and the UNSEEN cell that makes
    it worth going (when that cell is seen, the target has done its job)."""

    cell: tuple[int, int]
    kind: str                     # "wall" | "edge" | "inspect" | "corner" (variant maes)
    anchor: tuple[int, int]


def candidates(known: np.ndarray) -> tuple[np.ndarray, ...]:
    """Wall ends and edge cells of a window: rows, cols, normal (drow, dcol) pointing into free space,
    anchor (row, col) of the UNSEEN cell, and kind (0 wall end, 1 edge), all int64.

    For each normal in the order of ``_DIRS``: the wall ends along the wall one way, then the other (a
    face cell found one way is not looked at the other way), then the edge cells whose UNSEEN neighbour
    lies behind the normal (an edge cell found for one normal is FREE no longer for the next ones, so it
    has one normal and is no wall's free front for later normals); each group in row-major order. One
    compiled pass per group (``tests/algorithms/test_minotaur_fast.py`` checks it against the numpy
    form it replaced)."""
    k = np.ascontiguousarray(known, dtype=np.uint8)
    return _candidates(k)


@njit(cache=True)
def _candidates(known):  # pragma: no cover - compiled
    """:func:`candidates`. Every candidate is a known cell with an UNSEEN 4-neighbour (the wall end's cell
    along the wall, the edge cell's behind it), so the groups are read off the row-major list of such
    cells; ``cleared``
    marks the edge cells taken (FREE no longer for later normals)."""
    h, w = known.shape
    near = np.empty(h * w, np.int64)
    m = 0
    for r in range(h):
        for c in range(w):
            if known[r, c] != 0 and ((r > 0 and known[r - 1, c] == 0) or (r + 1 < h and known[r + 1, c] == 0)
                                     or (c > 0 and known[r, c - 1] == 0) or (c + 1 < w and known[r, c + 1] == 0)):
                near[m] = r * w + c
                m += 1
    cleared = np.zeros((h, w), np.bool_)
    ended = np.zeros(m, np.bool_)
    out = np.empty((7, 64), np.int64)
    n = 0
    for d in range(4):
        dr, dc = _DIRS[d]
        ended[:] = False
        for t in range(2):
            tr, tc = (dc, dr) if t == 0 else (-dc, -dr)
            for i in range(m):
                r, c = near[i] // w, near[i] % w
                fr, fc = r + dr, c + dc
                if ended[i] or known[r, c] != 2 or not (0 <= fr < h and 0 <= fc < w):
                    continue
                if known[fr, fc] != 1 or cleared[fr, fc]:
                    continue          # not a wall face towards (dr, dc)
                ar, ac = r + tr, c + tc
                if not (0 <= ar < h and 0 <= ac < w) or known[ar, ac] != 0:
                    continue
                br, bc = ar + dr, ac + dc
                if not (0 <= br < h and 0 <= bc < w) or known[br, bc] == 2:
                    continue          # a wall in front of the unseen cell (or the map's edge)
                out = _push(out, n, r, c, dr, dc, ar, ac, 0)
                n += 1
                ended[i] = True
        for i in range(m):
            r, c = near[i] // w, near[i] % w
            ar, ac = r - dr, c - dc
            if known[r, c] == 1 and not cleared[r, c] and 0 <= ar < h and 0 <= ac < w and known[ar, ac] == 0:
                out = _push(out, n, r, c, dr, dc, ar, ac, 1)
                n += 1
                cleared[r, c] = True
    return (out[0, :n].copy(), out[1, :n].copy(), out[2, :n].copy(), out[3, :n].copy(), out[4, :n].copy(),
            out[5, :n].copy(), out[6, :n].copy())


@njit(cache=True, inline="always")
def _push(out, n, r, c, dr, dc, ar, ac, kind):  # pragma: no cover - compiled
    """Column ``n`` of ``out`` (7 rows, grown when full) set to one candidate; returns ``out``."""
    if n == out.shape[1]:
        bigger = np.empty((7, 2 * n), np.int64)
        for j in range(7):       # element loops: a slice copy would link numba's shape-error formatting
            for i in range(n):
                bigger[j, i] = out[j, i]
        out = bigger
    out[0, n], out[1, n], out[2, n], out[3, n] = r, c, dr, dc
    out[4, n], out[5, n], out[6, n] = ar, ac, kind
    return out


def spin_keys(rows: np.ndarray, cols: np.ndarray, at: tuple[float, float], travel: tuple[float, float],
              spin: int) -> np.ndarray:
    """Sweep order in [0, 2 pi): 0 at the robot's right (spin +1, counter-clockwise) or left (-1), growing
    towards the front. ``at`` is the robot's (row, col), ``travel`` its (dx, dy) direction."""
    heading = math.atan2(travel[1], travel[0])
    ang = np.arctan2(rows + 0.5 - at[0], cols + 0.5 - at[1]) - heading
    ang = (ang + np.pi) % (2 * np.pi) - np.pi             # relative bearing in [-pi, pi)
    return (spin * ang + np.pi / 2) % (2 * np.pi)


def _march(known: np.ndarray, r: int, c: int, dr: int, dc: int, far: int) -> tuple[int, bool]:
    """FREE cells in front of (r, c) along (dr, dc), up to ``far``, and whether a SOLID cell ends them."""
    h, w = known.shape
    for i in range(1, far + 1):
        rr, cc = r + dr * i, c + dc * i
        if not (0 <= rr < h and 0 <= cc < w):
            return i - 1, False
        v = known[rr, cc]
        if v != FREE:
            return i - 1, v == SOLID
    return far, False


def offset_cell(known: np.ndarray, r: int, c: int, dr: int, dc: int, want: int) -> tuple[int, int]:
    """The cell ``want`` cells in front of (r, c), or half way across when a wall closes the free space in
    front sooner than ``2 * want`` (follow the middle of a narrow room or hall), or the last free cell."""
    n, closed = _march(known, r, c, dr, dc, 2 * want)
    k = min(want, n // 2) if closed and n < 2 * want else min(want, n)
    return r + dr * k, c + dc * k


def choose(known: np.ndarray, space: np.ndarray, room_dist: np.ndarray, at: tuple[int, int],
           travel: tuple[float, float], spin: int, radius: int, follow: int, edge: int,
           inspect: list[tuple[int, int, int, int]], blocked: np.ndarray | None,
           futile: np.ndarray | None = None, kind: int | None = None) -> FollowTarget | None:
    """The next wall-following / spiralling waypoint in a window, or None (nothing in visual range).

    ``space`` is the window's configuration space, ``room_dist`` the door-cut distance from the robot
    (inf outside its room), ``at`` the robot's cell, ``inspect`` pending doorway gaps (row, col, drow,
    dcol) to look at first, ``blocked`` cells not to aim at (targets that failed), ``futile`` anchors that
    stayed unseen when the robot went to look at them (occluded corners: never again), ``kind`` 0 or 1
    only wall ends or only edges (MAES tries its wall following, its corner coverage and its edges in
    turn, MinotaurAlgorithm.cs lines 341-343; None: both, in one sweep)."""
    h, w = known.shape
    r2 = radius * radius

    def usable(cell: tuple[int, int]) -> tuple[int, int] | None:
        r, c = cell
        if not (0 <= r < h and 0 <= c < w):
            return None
        if space[r, c] and np.isfinite(room_dist[r, c]) and (blocked is None or not blocked[r, c]):
            return cell
        r0, r1, c0, c1 = max(r - 2, 0), min(r + 3, h), max(c - 2, 0), min(c + 3, w)
        ok = space[r0:r1, c0:c1] & np.isfinite(room_dist[r0:r1, c0:c1])
        if blocked is not None:
            ok &= ~blocked[r0:r1, c0:c1]
        rr, cc = np.nonzero(ok)
        if not rr.size:
            return None
        i = int(np.argmin((rr + r0 - r) ** 2 + (cc + c0 - c) ** 2))
        return int(rr[i] + r0), int(cc[i] + c0)

    for r, c, dr, dc in inspect:
        if (r - at[0]) ** 2 + (c - at[1]) ** 2 > r2 or not (0 <= r < h and 0 <= c < w):
            continue
        goal = usable(offset_cell(known, r, c, dr, dc, follow))
        if goal is not None:
            return FollowTarget(goal, "inspect", (r, c))

    rows, cols, nrs, ncs, ars, acs, kinds = candidates(known)
    if not rows.size:
        return None
    near = (rows - at[0]) ** 2 + (cols - at[1]) ** 2 <= r2
    if kind is not None:
        near &= kinds == kind
    if futile is not None:
        inside = (ars >= 0) & (ars < h) & (acs >= 0) & (acs < w)
        near &= ~(inside & futile[np.clip(ars, 0, h - 1), np.clip(acs, 0, w - 1)])
    if not near.any():
        return None
    rows, cols, nrs, ncs, ars, acs, kinds = (a[near] for a in (rows, cols, nrs, ncs, ars, acs, kinds))
    keys = spin_keys(rows, cols, (float(at[0]), float(at[1])), travel, spin)
    order = np.lexsort((kinds, keys))
    for i in order.tolist()[:MAX_TRIES]:
        r, c, dr, dc = int(rows[i]), int(cols[i]), int(nrs[i]), int(ncs[i])
        if kinds[i] == 0:
            cell = offset_cell(known, r, c, dr, dc, follow)
        else:
            cell = offset_cell(known, r, c, dr, dc, edge)
        goal = usable(cell)
        if goal is not None and goal != tuple(at):
            return FollowTarget(goal, "wall" if kinds[i] == 0 else "edge", (int(ars[i]), int(acs[i])))
    return None
