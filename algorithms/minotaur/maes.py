"""MAES's doorway candidates, their check on arrival, and its corner coverage (``variant = "maes"``).

MAES's Minotaur (``Assets/Scripts/ExplorationAlgorithm/Minotaur/MinotaurAlgorithm.cs``, docs/maes.md
section 7.2) does not accept a doorway from the map. ``DoorwayDetection`` (lines 786-849) turns a
*possible* doorway into a Door waypoint and drives there; only on reaching it does ``AttemptAddDoorway``
(lines 851-884) look at the walls again and accept the doorway or forget it. The paper describes the
same two steps (section 4.3, Figs. 5-6: "move forward doorway width", "move towards intersection point
until it is explored") and names their cost (section 5.2, Figs. 10-11). On swarm's 0.5 m grid (MAES's
SLAM cells are 0.5 m too, its coarse tiles 1 m):

- **Walls** are wall faces (SOLID cells with FREE in front, in a straight row or column, at least
  :data:`MIN_WALL_CELLS` long) that one of 360 one-degree rays from the robot hits, each ray
  2 (VisionRadius + 2) SLAM cells long and stopped by SOLID or UNSEEN: MAES's ``GetWallsNearRobot``
  (lines 769-784, rays ``EdgeDetector.GetTilesAroundPoint``/``GetFurthestTileAroundPoint``, lines 112-153).
  MAES fits line segments to the hit cells (``GetWalls``, lines 512-584); on a grid the faces are the
  segments. A wall's *line* is the row or column of FREE cells in front of it (MAES's "corrected" tiles,
  lines 519-540, move each wall cell to its open neighbour).
- **Gap candidates** (the one-wall case, lines 795-821): from a wall's end, walk its wall line away
  from the wall (through UNSEEN cells) within 2 VisionRadius SLAM cells of the robot; the first FREE
  cell is a gap (a SOLID one first: the wall turns, no gap). The Door waypoint is the wall's end moved on
  along the wall by ``doorWidth`` tiles, at the robot's distance from the wall (line 815-816).
- **Intersection candidates** (the several-walls case, lines 825-847): a row wall and a column wall whose
  lines cross within 2 VisionRadius SLAM cells of the robot at a cell on not both of them (on both is
  a real corner, line 826; a wall's line here runs in front of it, so "on" allows one cell beyond the
  wall's end, where MAES's line through the wall cells meets the other wall's at their shared corner
  cell: the outside corner of a wall's end is a corner, not a crossing) that is not SOLID (SOLID ones are remembered and skipped, line 834-836).
  The Door waypoint is the crossing pulled back VisionRadius SLAM cells towards the robot (lines
  838-840; literally, so a crossing nearer than that sends the robot *away* from it).
- **Which rule** (line 795, issue 49 row 1): the gap rule when exactly one wall is seen, the crossings
  otherwise (``candidates(..., by_wall_count=True)``). On the grid a door's jambs are short walls of their
  own, so a door in the middle of a wall seen head-on is a crossing of a jamb's face line with the other
  part of the wall.
- Each candidate cell is remembered (``_previousIntersections``, lines 809-813 and 830-834) and never
  tried again; the first candidate already remembered or inside a known doorway **ends the search**
  (``return``, lines 809-812 and 830-833, issue 49 row 1), so a robot that has tried the nearest
  crossing in view tries no other from there.
- **The check on arrival** (``AttemptAddDoorway``, lines 851-884): the jambs are the points of the two
  walls nearest to the crossing (``GetClosestPoints``, lines 886-889); the doorway is accepted if the
  crossing is seen (not UNSEEN) and the jamb distance ``d`` (SLAM cells) is ``2 doorWidth`` or in
  ``[3, 2 doorWidth]`` (line 863-864): 1.5-2 m for ``doorWidth = 2``. The crossing and jambs are measured
  where MAES's fitted lines lie (issue 49): ``GetWalls`` moves a wall cell onto its open neighbour to the
  east or north (lines 519-540), so a face towards +col/+row lies on its FREE line and a face towards
  -col/-row on its SOLID cells (MAES's asymmetry: of the two crossings of a head-on 2 m door one measures
  4 cells, accepted, the other 5, dropped). For a gap candidate the two walls
  are the wall before the gap and its continuation in line (the paper's single-wall case, Alg. 3 "if
  wall continues after doorway width"): the jamb distance is the gap's width, and a gap whose far side
  is not seen, or that ends in no wall of two cells or more in line, is dropped.
- **Corner coverage** (``MoveToCornerCoverage``, lines 607-630, ``IsAheadExploreable`` lines 752-761):
  unless the cells VisionRadius + 1 and + 2 tiles straight ahead (the heading rounded to one of eight
  directions, ``CardinalDirection.AngleToDirection``) are both UNSEEN, cast rays over the 30 degrees to
  the robot's right (heading - 30 ... heading - 1 degree, ``startAngle: 360 - 30``), VisionRadius + 2
  tiles long, stopped by UNSEEN or SOLID, and go to the first UNSEEN cell a ray stops at.
- **Dropping a direct waypoint** (lines 264-283): while the robot drives to a Door or Corner waypoint,
  a SOLID cell within VisionRadius - 2 tiles along the bearing to it ends the waypoint (a Door waypoint
  then is forgotten unchecked, as in MAES).

Departures (the explorer's module docstring lists them with the rest): candidates are walked nearest
first (MAES walks them in the order its line fitting gives, ``GetIntersectionPoints`` lines 586-605,
which the grid cannot reproduce), so "the first tried candidate" is the nearest one; the gap rule walks
from both ends of the wall, stopped by SOLID (MAES walks one way from the wall cell nearest the robot
and takes the first Open cell, lines 798-805); the check is made for the candidate the robot drove to
(MAES checks the first crossing of the walls it sees on arrival, line 859, which need not be the same
one); a candidate with no drivable cell near its Door waypoint is remembered and passed (MAES drives
towards it regardless).
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

import numba
import numpy as np

from swarm.api import CELL_M, FREE, SOLID, UNSEEN

from .doorways import Doorway

MIN_WALL_CELLS = 2
"""A wall face must be this long (MAES: a segment's start and end differ, line 792)."""
_CAP = 4096
_MAX_DEPTH = 4


@dataclass(frozen=True)
class Candidate:
    """A possible doorway the robot drives to before it checks it (map cells).

    ``kind`` ``gap``: ``line``/``side``/``end``/``step`` name the wall (axis 0: row ``line``, FREE on row
    ``line + side``, its end at column ``end``; axis 1 the same with rows and columns swapped) and the
    direction ``step`` (+1/-1) along it into the gap. ``kind`` ``cross``: ``line``/``side``/``span`` name the
    row wall (its columns), ``line2``/``side2``/``span2`` the column wall (its rows), ``key`` is the
    crossing (row, col). ``goal`` is the Door
    waypoint (m)."""

    kind: str
    key: tuple[int, int]
    goal: tuple[float, float]
    axis: int = 0
    line: int = 0
    side: int = 0
    end: int = 0
    step: int = 0
    line2: int = 0
    side2: int = 0
    span: tuple[int, int] = (0, 0)
    span2: tuple[int, int] = (0, 0)


# ------------------------------------------------------------------------------------ ray casting ----
@numba.njit(cache=True)
def _cast(k: np.ndarray, r0: int, c0: int, heading_deg: float, start: int, stop: int, sign: int, steps: int,
          unseen_only: bool, out: np.ndarray) -> int:
    """MAES's ``GetTilesAroundPoint``: for each whole degree ``a`` in [start, stop), the cell where a ray
    from (r0, c0) at ``heading_deg + sign * a`` stops: the first SOLID or UNSEEN cell of ``r`` = 0 .. steps - 1
    cells, ``floor(r * (cos, sin))`` from the start, or its last cell inside the map. Writes (row, col)
    rows into ``out``, each distinct cell once, in ray order; ``unseen_only`` keeps UNSEEN stops only."""
    h, w = k.shape
    n = 0
    for a in range(start, stop):
        th = math.radians(heading_deg + sign * a)
        ct, st = math.cos(th), math.sin(th)
        rr, cc = r0, c0
        hit = False
        for r in range(steps):
            pr = r0 + int(math.floor(r * st))
            pc = c0 + int(math.floor(r * ct))
            if pr < 0 or pr >= h or pc < 0 or pc >= w:
                continue
            rr, cc = pr, pc
            v = k[pr, pc]
            if v == SOLID or v == UNSEEN:
                hit = True
                break
        if unseen_only and not (hit and k[rr, cc] == UNSEEN):
            continue
        dup = False
        for i in range(n):
            if out[i, 0] == rr and out[i, 1] == cc:
                dup = True
                break
        if not dup and n < out.shape[0]:
            out[n, 0] = rr
            out[n, 1] = cc
            n += 1
    return n


def wall_hits(known: np.ndarray, cell: tuple[int, int], vision: int) -> np.ndarray:
    """Bool raster of the SOLID cells 360 one-degree rays of 2 (vision + 2) cells stop at (MAES lines
    769-784)."""
    k = np.ascontiguousarray(known, dtype=np.uint8)
    out = np.empty((360, 2), dtype=np.int64)
    n = _cast(k, cell[0], cell[1], 0.0, 0, 360, 1, 2 * (vision + 2), False, out)
    hits = np.zeros(k.shape, dtype=np.bool_)
    rows, cols = out[:n, 0], out[:n, 1]
    solid = k[rows, cols] == SOLID
    hits[rows[solid], cols[solid]] = True
    return hits


# ------------------------------------------------------------------------------------------ walls ----
@numba.njit(cache=True)
def _faces(g: np.ndarray, hits: np.ndarray, min_len: int, out: np.ndarray) -> int:
    """Wall faces along the rows of ``g`` that a ray hit: (row, side, first col, last col)."""
    h, w = g.shape
    n = 0
    for s in (-1, 1):
        for r in range(h):
            rr = r + s
            if rr < 0 or rr >= h:
                continue
            c = 0
            while c < w:
                if g[r, c] != SOLID or g[rr, c] != FREE:
                    c += 1
                    continue
                e = c
                seen = False
                while e < w and g[r, e] == SOLID and g[rr, e] == FREE:
                    if hits[r, e]:
                        seen = True
                    e += 1
                if seen and e - c >= min_len and n < out.shape[0]:
                    out[n, 0] = r
                    out[n, 1] = s
                    out[n, 2] = c
                    out[n, 3] = e - 1
                    n += 1
                c = e
    return n


def walls(known: np.ndarray, hits: np.ndarray) -> tuple[list[tuple[int, int, int, int]], list[tuple[int, int, int, int]]]:
    """The walls the robot sees: row walls (row, side, col0, col1) and column walls (col, side, row0, row1)."""
    out = np.empty((_CAP, 4), dtype=np.int64)
    k = np.ascontiguousarray(known, dtype=np.uint8)
    n = _faces(k, hits, MIN_WALL_CELLS, out)
    rows = [tuple(v) for v in out[:n].tolist()]
    n = _faces(np.ascontiguousarray(k.T), np.ascontiguousarray(hits.T), MIN_WALL_CELLS, out)
    cols = [tuple(v) for v in out[:n].tolist()]
    return rows, cols            # type: ignore[return-value]


# ------------------------------------------------------------------------------------- candidates ----
def candidates(known: np.ndarray, origin: tuple[int, int], xy: tuple[float, float], vision: int,
               door_width: int, by_wall_count: bool = False) -> list[Candidate]:
    """Gap and crossing candidates around the robot at ``xy`` (m) in ``known`` (a window whose cell
    (0, 0) is map cell ``origin``), nearest first, in map cells; SOLID crossings included (the caller
    remembers and skips them). ``by_wall_count``: MAES's choice of rule (line 795, issue 49 row 1): gap
    candidates only when exactly one wall is seen, crossings only otherwise (none with no wall, line
    788); False: both rules on every call."""
    return list(iter_candidates(known, origin, xy, vision, door_width, by_wall_count))


def iter_candidates(known: np.ndarray, origin: tuple[int, int], xy: tuple[float, float], vision: int,
                    door_width: int, by_wall_count: bool = False) -> Iterator[Candidate]:
    """:func:`candidates` one at a time, each built only when asked for: the MAES variant stops at the
    first tried one, and on caves a window holds hundreds of wall crossings."""
    h, w = known.shape
    pr, pc = xy[1] / CELL_M - origin[0], xy[0] / CELL_M - origin[1]          # the robot, window cells
    cell = (min(max(int(pr), 0), h - 1), min(max(int(pc), 0), w - 1))
    hits = wall_hits(known, cell, vision)
    row_walls, col_walls = walls(known, hits)
    radius = 2 * vision                                                   # SLAM cells (MAES line 803, 827)
    found: list[tuple[float, tuple[int, int], str, Any]] = []   # (distance, key, kind, what makes it)
    one_wall = len(row_walls) + len(col_walls) == 1
    for axis, faces in ((0, row_walls), (1, col_walls)):
        if by_wall_count and not one_wall:
            break
        g = known if axis == 0 else known.T
        p_line, p_along = (pr, pc) if axis == 0 else (pc, pr)
        lo_line, lo_along = (origin[0], origin[1]) if axis == 0 else (origin[1], origin[0])
        for line, side, a, b in faces:
            if side * (p_line - (line + 0.5)) <= 0:
                continue                                                  # the robot is behind this face
            for end, step in ((a, -1), (b, 1)):
                j = end + step
                while 0 <= j < g.shape[1] and math.hypot(line + 0.5 - p_line, j + 0.5 - p_along) <= radius:
                    v = g[line, j]
                    if v == SOLID:
                        break
                    if v == FREE:
                        along_m = (end + 0.5 + lo_along) * CELL_M + step * door_width
                        across_m = (p_line + lo_line) * CELL_M
                        goal = (along_m, across_m) if axis == 0 else (across_m, along_m)
                        key = (line + lo_line, j + lo_along) if axis == 0 else (j + lo_along, line + lo_line)
                        found.append((math.hypot(line + 0.5 - p_line, j + 0.5 - p_along), key, "gap",
                                      Candidate("gap", key, goal, axis, line + lo_line, side, end + lo_along, step)))
                        break
                    j += step
    for rl, rs, c0, c1 in (row_walls if not (by_wall_count and one_wall) else []):
        xr = rl + rs
        for cl, cs, r0, r1 in col_walls:
            xc = cl + cs
            if c0 - 1 <= xc <= c1 + 1 and r0 - 1 <= xr <= r1 + 1:
                continue                                                  # on both walls: a real corner
            if not (0 <= xr < h and 0 <= xc < w):
                continue
            d = math.hypot(xr + 0.5 - pr, xc + 0.5 - pc)
            if d > radius:
                continue
            found.append((d, (xr + origin[0], xc + origin[1]), "cross", (rl, rs, c0, c1, cl, cs, r0, r1)))
    found.sort(key=lambda t: (t[0], t[1], t[2]))
    for d, key, kind, made in found:
        if kind == "gap":
            yield made
            continue
        rl, rs, c0, c1, cl, cs, r0, r1 = made
        xr, xc = key[0] - origin[0], key[1] - origin[1]
        scale = (d - vision) / d if d > 0 else 0.0                        # pulled back `vision` cells (line 839-840)
        gr, gc = pr + (xr + 0.5 - pr) * scale, pc + (xc + 0.5 - pc) * scale
        goal = ((gc + origin[1]) * CELL_M, (gr + origin[0]) * CELL_M)
        yield Candidate("cross", key, goal, 0, rl + origin[0], rs, line2=cl + origin[1], side2=cs,
                        span=(c0 + origin[1], c1 + origin[1]), span2=(r0 + origin[0], r1 + origin[0]))


# ------------------------------------------------------------------------------------------ check ----
def _accept(distance: float, door_width: int) -> bool:
    """MAES line 864: ``d == 2 doorWidth`` or ``3 <= d <= 2 doorWidth`` (SLAM cells)."""
    top = 2 * door_width
    return math.isclose(distance, top) or 3 <= distance <= top


def _opening(g: np.ndarray, line: int, side: int, j1: int, j2: int, axis: int) -> Doorway:
    """The doorway between jamb cells ``j1`` and ``j2`` on row ``line`` of ``g`` (the map, transposed
    for axis 1) of a wall whose face is towards ``side``; its depth is the rows both jambs stay SOLID."""
    lo, hi = min(j1, j2) + 1, max(j1, j2) - 1
    depth = 0
    h = g.shape[0]
    while depth < _MAX_DEPTH:
        r = line - side * depth
        if not (0 <= r < h) or g[r, j1] != SOLID or g[r, j2] != SOLID:
            break
        depth += 1
    depth = max(depth, 1)
    first = min(line, line - side * (depth - 1))
    along = (lo + hi + 1) / 2 * CELL_M
    across = (first + depth / 2) * CELL_M
    x, y = (along, across) if axis == 0 else (across, along)
    return Doorway(x=x, y=y, axis=axis, width=(hi - lo + 1) * CELL_M, depth=depth * CELL_M)


def _jamb(g: np.ndarray, line: int, side: int, span: tuple[int, int], at: int) -> int | None:
    """The end of a wall nearest to ``at`` (``GetClosestPoints``, line 886-889): from the wall's cells
    ``span`` on row ``line`` of ``g`` (FREE on row ``line + side``), as far towards ``at`` as the face
    now goes (the robot may have seen more of it since)."""
    h, w = g.shape
    if not (0 <= line < h and 0 <= line + side < h):
        return None

    def face(c: int) -> bool:
        return 0 <= c < w and g[line, c] == SOLID and g[line + side, c] == FREE

    c = min(max(at, span[0]), span[1])
    if not face(c):
        return None
    step = 1 if at > c else -1
    while c != at and face(c + step):
        c += step
    return c


def check(known: np.ndarray, cand: Candidate, door_width: int) -> Doorway | None:
    """``AttemptAddDoorway`` for ``cand`` on the whole map ``known``: the doorway, or None (drop it)."""
    if cand.kind == "gap":
        g = known if cand.axis == 0 else known.T
        line, step = cand.line, cand.step
        n = g.shape[1]
        width = 0
        j = cand.end + step
        while 0 <= j < n and g[line, j] == FREE and width <= 4 * door_width:
            width += 1
            j += step
        far = j + step
        if width == 0 or not (0 <= far < n) or g[line, j] != SOLID or g[line, far] != SOLID:
            return None                                      # unseen beyond the gap, or no wall goes on
        if not _accept(width, door_width):
            return None
        return _opening(g, line, cand.side, cand.end, j, cand.axis)
    xr, xc = cand.key
    if known[xr, xc] == UNSEEN:
        return None
    # the jambs are measured in MAES's frame (issue 49): GetWalls moves a wall cell onto its open neighbour
    # to the east or north (lines 519-540), so a face towards +col/+row lies on its FREE line, a face
    # towards -col/-row on its own SOLID cells; a door in the middle of a wall seen head-on is then 2 doorWidth
    # cells from one jamb's face to the other wall's end on one side of it, as MAES measures it
    xr, xc = cand.line + max(cand.side, 0), cand.line2 + max(cand.side2, 0)
    ch = _jamb(known, cand.line, cand.side, cand.span, xc)                  # jamb on the row wall
    rv = _jamb(known.T, cand.line2, cand.side2, cand.span2, xr)             # jamb on the column wall
    if ch is None or rv is None:
        return None
    distance = math.hypot(xc - ch, rv - xr)
    if not _accept(distance, door_width):
        return None
    door = None
    if ch == xc:                       # the row wall runs on under the crossing: the column wall is broken
        door = _opening(known.T, cand.line2, cand.side2, rv, cand.line, 1)
    elif rv == xr:                     # the column wall runs on: the row wall is broken
        door = _opening(known, cand.line, cand.side, ch, cand.line2, 0)
    if door is not None and math.isclose(door.width, distance * CELL_M):
        return door
    # otherwise MAES's record as it is (lines 862-870): the opening from jamb to jamb, whatever lies
    # between them (MAES does not look: two walls in a T, or both ending short of the crossing), along
    # the cardinal direction between the jambs
    cx, cy = (ch + xc + 1) / 2 * CELL_M, (xr + rv + 1) / 2 * CELL_M
    axis = 0 if abs(xc - ch) >= abs(rv - xr) else 1
    return Doorway(x=cx, y=cy, axis=axis, width=distance * CELL_M, depth=CELL_M)


# -------------------------------------------------------------------------------- corner coverage ----
def _cardinal(theta: float) -> tuple[int, int]:
    """``CardinalDirection.AngleToDirection``: the heading rounded per axis, (dx, dy) in {-1, 0, 1}."""
    return round(math.cos(theta)), round(math.sin(theta))


def corner(known: np.ndarray, xy: tuple[float, float], theta: float, vision: int, spin: int
           ) -> list[tuple[int, int]]:
    """``MoveToCornerCoverage`` (lines 607-630): the UNSEEN cells rays over 30 degrees to the robot's
    right (spin +1; left for -1) stop at, in ray order, or [] when both cells vision + 1 and + 2 tiles
    straight ahead are UNSEEN (``IsAheadExploreable``, lines 752-761)."""
    h, w = known.shape
    dx, dy = _cardinal(theta)
    ahead = 0
    for extra in (1, 2):
        r, c = int((xy[1] + dy * (vision + extra)) / CELL_M), int((xy[0] + dx * (vision + extra)) / CELL_M)
        if 0 <= r < h and 0 <= c < w and known[r, c] == UNSEEN:
            ahead += 1
    if ahead == 2:
        return []
    k = np.ascontiguousarray(known, dtype=np.uint8)
    out = np.empty((32, 2), dtype=np.int64)
    r0, c0 = int(xy[1] / CELL_M), int(xy[0] / CELL_M)
    r0, c0 = min(max(r0, 0), h - 1), min(max(c0, 0), w - 1)
    heading = math.degrees(theta)
    steps = round((vision + 2) / CELL_M)
    n = _cast(k, r0, c0, heading, -30, 0, 1 if spin > 0 else -1, steps, True, out)   # clockwise: mirrored
    return [(int(r), int(c)) for r, c in out[:n].tolist()]


def wall_ahead(known: np.ndarray, xy: tuple[float, float], goal: tuple[float, float], vision: int) -> bool:
    """Lines 266-267: a SOLID cell within ``vision - 2`` tiles of the robot on the bearing to ``goal``
    (tiles 0 .. vision - 3 of the ray, sampled every cell)."""
    dx, dy = goal[0] - xy[0], goal[1] - xy[1]
    n = math.hypot(dx, dy)
    if n < 1e-9:
        return False
    ux, uy = dx / n, dy / n
    h, w = known.shape
    for i in range(1, round((vision - 3) / CELL_M) + 1):
        d = i * CELL_M
        r, c = int((xy[1] + uy * d) / CELL_M), int((xy[0] + ux * d) / CELL_M)
        if 0 <= r < h and 0 <= c < w and known[r, c] == SOLID:
            return True
    return False
