"""Voronoi: each robot explores the part of what it sees that is nearer to it than to any robot it senses,
taking the farthest unexplored tile in a compass direction given by its id; with none, it looks behind
occlusions, then pushes out to the edge of its region.

The "local Voronoi decomposition" (LVD) of the MAES paper (Andreasen, Holler, Jensen, Albano, ICAART 2022),
which was not at hand: the rules are MAES's ``VoronoiExplorationAlgorithm``
(``Assets/Scripts/ExplorationAlgorithm/Voronoi/VoronoiExplorationAlgorithm.cs``, DEIS-Tools/MAES commit
1bb0312; docs/maes.md section 13.5), on MAES's 1 m coarse tiles (:mod:`.tiles`):

- **Explored tiles** (``UpdateExploredStatusOfTiles``, 251-268): every tile the robot sees this tick within
  the marking range is explored; MAES's campaign sets the range to the lidar's minus one tile
  (``ExperimentBase.cs`` 101; ``ScenarioGenerator.cs`` uses 1).
- **When to decide** (``ShouldRecalculate``, 295-323): after a collision, when the current target is
  reached, and, while another robot is sensed, every 50 ticks exploring, 40 searching or expanding.
- **The region** (``RecalculateVoronoiRegions``, 627-690): each tile the robot sees goes to the nearest of
  it and the robots it senses (ties to itself); its own tiles are its region.
- **Explore** (140-156): the region's unexplored, not solid tiles, ordered by the heuristic of the robot's id
  modulo 4 (``GetSortingFunction``, 205-240): north then east, east then south, south then west, west then
  north; the first is the target.
- **Search** (``EnterSearchMode``, 325-380; ``FindClosestOcclusionPoints``, 473-525): with none, the
  *occlusion points*, the nearest tile of each 4-connected group of free tiles on the edge of what it sees
  that lie at least 2 tiles short of the farthest one, are visited nearest first, skipping those within 1
  tile of a tile passed in this search; with all visited, the least recently passed one again.
- **Expand** (``FindClosestVoronoiBoundary``, 409-471): with no occlusion point left, a random tile among
  the region's edge tiles (not wholly solid when there are such) within 2 tiles of the nearest one's
  distance, away from those passed in the search.

Departures:

1. Explored tiles are each robot's own, shared by message (``voronoi.explored``, every ``share_every``
   ticks, the sender's whole layer as bits): MAES's ``_isExploredMap`` is ``static`` (45), one layer for
   every robot of the process at once.
2. "The tiles it sees" are the tiles within the lidar's range whose centre the robot sees across free
   cells of its own map (a tile with no cell seen is not seen); MAES reads the cells its rays hit this tick
   (``GetCurrentlyVisibleTiles``).
3. A target is a goal with ``drive = "path"`` (MAES's tile-by-tile path, exact under
   ``motion.model = "maes"``): the navigator plans on the robot's map, where MAES runs A* on the coarse map
   of visible tiles with partial paths (392). Reaching the goal is reaching the target; the tiles passed
   while searching are the tiles the robot enters (288). A target the navigator gives up on
   (``unreachable``/``blocked``, or within ``progress_m`` for ``deadlock_ticks``) is left out for
   ``exclude_ticks`` (MAES would pick it again at once and stand still).
4. MAES's two filters against tiles passed in the search are inverted: an occlusion point is kept once per
   passed tile more than 1 tile from it (333-341), so with none passed none is kept and MAES goes from
   explore straight to expand (search mode is never entered); a boundary candidate is kept only if it is
   within 1 tile of every passed tile (453-462). swarm keeps what is more than 1 tile from all of them, the
   evident intent; ``variant = "maes"`` keeps MAES's filters.
5. A robot whose region is empty (it sees no tile) waits for the next decision (MAES dereferences a
   missing list, 413, 589).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numba import njit

from swarm.api import (CELL_M, FREE, OMIT_DEFAULT, SOLID, UNSEEN, Action, Neighbours, Observation, RobotInfo,
                       check_choice, check_float, check_int)
from swarm.api.messages import MessageError, message

from . import tiles
from .recovery import Watchdog

VARIANTS = ("swarm", "maes")
EXPLORE, SEARCH, EXPAND = "explore", "search", "expand"
RECALC_EVERY = {EXPLORE: 50, SEARCH: 40, EXPAND: 40}
"""``EXPLORE_MODE_RECALC_INTERVAL`` and the others (51-53), in ticks, while another robot is sensed."""
SAME_POINT = 1.0
"""``DISTANCE_BETWEEN_SAME_OCC_POINT`` (58), tiles."""
BOUNDARY_DELTA = 2.0
"""``VORONOI_BOUNDARY_EQUAL_DISTANCE_DELTA`` (59), tiles."""
OCCLUDED_BELOW = 2.0
"""An edge tile this much nearer than the farthest one may be occluded (502)."""
RAY_STEP_M = CELL_M / 2
SORT_KEYS = (lambda t: (-t[1], -t[0]), lambda t: (-t[0], t[1]), lambda t: (t[1], t[0]), lambda t: (t[0], -t[1]))
"""``GetSortingFunction`` (205-240) by id modulo 4: north-east, east-south, south-west, west-north."""
FOUR = ((1, 0), (0, -1), (-1, 0), (0, 1))

Tile = tuple[int, int]


@message("voronoi.explored")
@dataclass(frozen=True)
class Explored:
    """Every tile ``sender`` knows explored, one bit each, row by row from the bottom (departure 1)."""

    sender: int
    bits: bytes

    def validate(self) -> None:
        if not isinstance(self.bits, bytes) or len(self.bits) > 1 << 22:
            raise MessageError("voronoi.explored: bits must be bytes")


@dataclass(frozen=True)
class VoronoiParams:
    # "swarm": passed tiles filter search and expand targets (departure 4); "maes": MAES's inverted filters
    variant: str = field(default="swarm", metadata={OMIT_DEFAULT: True})
    mark_margin_tiles: float = 1.0   # tiles seen within the lidar's range minus this are explored (ExperimentBase.cs 101)
    share_every: int = 10            # broadcast the explored tiles this often, in ticks (departure 1); 0 = never
    deadlock_ticks: int = 50         # a move that gets nowhere this long is given up (departure 3); 0 = never
    progress_m: float = 0.3          # getting nowhere: staying within this of one spot
    exclude_ticks: int = 300         # a target given up is left out this long (departure 3)

    def __post_init__(self) -> None:
        check_choice("variant", self.variant, VARIANTS)
        check_float("mark_margin_tiles", self.mark_margin_tiles, 0.0, 1000.0)
        check_int("share_every", self.share_every, 0, 1_000_000)
        check_int("deadlock_ticks", self.deadlock_ticks, 0, 1_000_000)
        check_float("progress_m", self.progress_m, 0.0, 100.0, lo_open=True)
        check_int("exclude_ticks", self.exclude_ticks, 0, 1_000_000)


class Voronoi:
    """MAES's Voronoi explorer (see the module docstring)."""

    name = "voronoi"
    Params = VoronoiParams

    def reset(self, robot: RobotInfo, params: VoronoiParams, rng: np.random.Generator) -> None:
        self.me = robot.id
        self.params = params
        self.rng = rng
        self.maes = params.variant == "maes"
        self.reach = robot.lidar_range / tiles.TILE_M
        self.mark_range = self.reach - params.mark_margin_tiles
        shape = (-(-robot.map_shape[0] // tiles.CELLS), -(-robot.map_shape[1] // tiles.CELLS))
        self.explored = np.zeros(shape, dtype=bool)                # [ty, tx]
        self.sort_key = SORT_KEYS[robot.id % 4]
        self.phase = EXPLORE
        self.target: Tile | None = None
        self.goal: tuple[float, float] | None = None
        self.region: list[Tile] = []
        self.passed: list[tuple[Tile, int]] = []                   # tiles entered while searching, with the tick
        self.last_tile: Tile | None = None
        self.excluded: dict[Tile, int] = {}                        # target -> tick it may be chosen again
        self.watchdog = Watchdog(params.deadlock_ticks, params.progress_m)

    def act(self, obs: Observation) -> Action:
        self._read(obs.inbox)
        here = tiles.tile_of(obs.pose.x, obs.pose.y)
        position = (obs.pose.x / tiles.TILE_M, obs.pose.y / tiles.TILE_M)
        seen = visible_array(obs.known, obs.pose.x, obs.pose.y, self.reach)
        near = np.hypot(seen[:, 0] - position[0], seen[:, 1] - position[1]) <= self.mark_range   # 258-268
        self.explored[seen[near, 1], seen[near, 0]] = True
        if self.phase == SEARCH and here != self.last_tile:        # 286-289
            self.passed.append((here, obs.tick))
        self.last_tile = here
        if self._should_decide(obs):
            self.goal = None
            self._decide(obs, here, position, [(tx, ty) for tx, ty in seen.tolist()])
        messages: tuple[Any, ...] = ()
        every = self.params.share_every
        if every and obs.tick % every == self.me % every:
            messages = (Explored(sender=self.me, bits=np.packbits(self.explored).tobytes()),)
        debug = {"phase": self.phase, "target": list(self.target or ()), "region": len(self.region)}
        if self.target is None:
            return Action(velocity=(0.0, 0.0), clear_goal=True, messages=messages, debug=debug)
        if self.goal is None:
            self.goal = tiles.tile_goal(self.target)
            self.watchdog.restart(obs)
        return Action(goal=self.goal, drive="path", messages=messages, debug=debug)

    def _should_decide(self, obs: Observation) -> bool:
        """``ShouldRecalculate`` (295-323), with departure 3's end of a move."""
        if obs.collided:
            return True
        if self.target is None:
            return True
        if self.goal is not None and obs.nav.goal == self.goal:
            if obs.nav.state == "reached":
                self.target = None
                return True
            if obs.nav.state in ("unreachable", "blocked") or self.watchdog.stuck(obs):
                self.excluded[self.target] = obs.tick + self.params.exclude_ticks
                self.target = None
                return True
        return bool(obs.neighbours) and obs.tick % RECALC_EVERY[self.phase] == 0

    def _decide(self, obs: Observation, here: Tile, position: tuple[float, float], seen: list[Tile]) -> None:
        """``UpdateLogic`` 135-161: the region, then explore, search or expand."""
        self.excluded = {t: until for t, until in self.excluded.items() if until > obs.tick}
        others = obs.neighbours
        if isinstance(others, Neighbours):
            others = others.within(2 * self.reach * tiles.TILE_M)
        self.region = region_of(here, [(n.x / tiles.TILE_M, n.y / tiles.TILE_M) for n in others], seen)
        unexplored = [t for t in self.region if not self.explored[t[1], t[0]] and not tiles.blocked(obs.known, t)
                      and t not in self.excluded]
        if unexplored:
            self.phase = EXPLORE
            self.passed.clear()
            self.target = min(unexplored, key=self.sort_key)
            return
        self.target = self._search(obs.known, position, seen)

    def _search(self, known: np.ndarray, position: tuple[float, float], seen: list[Tile]) -> Tile | None:
        """``EnterSearchMode`` (325-380)."""
        points = [p for p in occlusion_points(known, position, seen) if p not in self.excluded]
        if self.maes:                                              # 333-341, departure 4
            fresh = [p for p in points for v, _ in self.passed if math.dist(p, v) > SAME_POINT]
        else:
            fresh = [p for p in points if all(math.dist(p, v) > SAME_POINT for v, _ in self.passed)]
        if fresh:
            self.phase = SEARCH
            return min(fresh, key=lambda p: math.dist(position, p))
        if len(self.passed) > 1:
            self.phase = SEARCH
            return min(self.passed, key=lambda e: e[1])[0]
        self.phase = EXPAND
        return self._boundary(known, position)

    def _boundary(self, known: np.ndarray, position: tuple[float, float]) -> Tile | None:
        """``FindClosestVoronoiBoundary`` (409-471)."""
        edges = [t for t in edge_tiles(self.region) if t not in self.excluded]
        if not edges:
            return None
        open_edges = [t for t in edges if not wholly_solid(known, t)]
        edges = open_edges or edges
        nearest = min(math.dist(position, t) for t in edges)
        candidates = [t for t in edges if abs(math.dist(position, t) - nearest) < BOUNDARY_DELTA]
        if self.maes:                                              # 453-462, departure 4
            kept = [t for t in candidates if all(math.dist(t, v) <= SAME_POINT for v, _ in self.passed)]
        else:
            kept = [t for t in candidates if all(math.dist(t, v) > SAME_POINT for v, _ in self.passed)]
        candidates = kept or candidates
        candidates.sort(key=lambda t: (math.dist(position, t), t))
        return candidates[int(self.rng.integers(len(candidates)))]

    def _read(self, inbox: tuple[Any, ...]) -> None:
        """Departure 1: merge the explored tiles others send."""
        for m in inbox:
            if isinstance(m, Explored) and m.sender != self.me and len(m.bits) == -(-self.explored.size // 8):
                bits = np.unpackbits(np.frombuffer(m.bits, dtype=np.uint8), count=self.explored.size)
                self.explored |= bits.reshape(self.explored.shape).astype(bool)


def visible_array(known: np.ndarray, x: float, y: float, reach: float) -> np.ndarray:
    """int64[N, 2] (tx, ty) of the tiles within ``reach`` tiles whose centre is seen from (x, y) across FREE
    cells, and with a cell seen (departure 2), in (tx, ty) order. Cost: O(reach^3) ray steps, compiled."""
    return _visible(np.ascontiguousarray(known), x, y, reach, tiles.TILE_M, tiles.CELLS, CELL_M, RAY_STEP_M)


@njit(cache=True)
def _visible(known: np.ndarray, x: float, y: float, reach: float, tile_m: float, cells: int, cell_m: float,
             ray_step_m: float) -> np.ndarray:
    h, w = known.shape
    tw, th = (w + cells - 1) // cells, (h + cells - 1) // cells
    cx, cy = x / tile_m, y / tile_m
    r = math.ceil(reach)
    out = np.empty(((2 * r + 1) ** 2, 2), dtype=np.int64)
    n = 0
    for tx in range(max(0, math.floor(cx) - r), min(tw, math.floor(cx) + r + 1)):
        for ty in range(max(0, math.floor(cy) - r), min(th, math.floor(cy) + r + 1)):
            gx, gy = (tx + 0.5) * tile_m, (ty + 0.5) * tile_m
            length = math.hypot(gx - x, gy - y)
            if length > reach * tile_m:
                continue
            seen = False
            for rr in range(ty * cells, min(h, (ty + 1) * cells)):
                for cc in range(tx * cells, min(w, (tx + 1) * cells)):
                    if known[rr, cc] != UNSEEN:
                        seen = True
            if not seen:
                continue
            steps = math.ceil(length / ray_step_m)
            clear = True
            for i in range(steps + 1):
                f = i / steps if steps > 0 else 1.0
                px, py = x + f * (gx - x), y + f * (gy - y)
                if math.floor(px / tile_m) == tx and math.floor(py / tile_m) == ty:
                    continue
                rr, cc = min(max(int(py / cell_m), 0), h - 1), min(max(int(px / cell_m), 0), w - 1)
                if known[rr, cc] != FREE:
                    clear = False
                    break
            if clear:
                out[n, 0], out[n, 1] = tx, ty
                n += 1
    return out[:n]


def region_of(here: Tile, others: list[tuple[float, float]], seen: list[Tile]) -> list[Tile]:
    """``RecalculateVoronoiRegions`` (627-690): the seen tiles strictly nearer to no sensed robot than to
    ``here`` (other robots' positions in tiles)."""
    return [t for t in seen if all(math.dist(o, t) >= math.dist(here, t) for o in others)]


def edge_tiles(region: list[Tile]) -> list[Tile]:
    """``FindEdgeTiles`` (584-608): tiles with a 4-neighbour outside ``region``."""
    inside = set(region)
    return [t for t in region if any((t[0] + dx, t[1] + dy) not in inside for dx, dy in FOUR)]


def occlusion_points(known: np.ndarray, position: tuple[float, float], seen: list[Tile]) -> list[Tile]:
    """``FindClosestOcclusionPoints`` (473-525): of the not solid edge tiles of what is seen, those at
    least 2 tiles nearer than the farthest; the nearest of each 4-connected group."""
    edges = [t for t in edge_tiles(seen) if not tiles.blocked(known, t)]
    if not edges:
        return []
    far = max(math.dist(position, t) for t in edges)
    rest = {t for t in edges if math.dist(position, t) < far - OCCLUDED_BELOW}
    points = []
    while rest:                                                    # FindGroupedTiles (527-582)
        start = min(rest)
        group, todo = [], [start]
        rest.discard(start)
        while todo:
            t = todo.pop()
            group.append(t)
            for dx, dy in FOUR:
                n = (t[0] + dx, t[1] + dy)
                if n in rest:
                    rest.discard(n)
                    todo.append(n)
        points.append(min(group, key=lambda t: (math.dist(position, t), t)))
    return points


def wholly_solid(known: np.ndarray, tile: Tile) -> bool:
    """``IsOptimisticSolid``: every cell of the tile SOLID, or the tile off the map."""
    h, w = known.shape
    r, c = tile[1] * tiles.CELLS, tile[0] * tiles.CELLS
    if r < 0 or c < 0 or r + tiles.CELLS > h or c + tiles.CELLS > w:
        return True
    return bool((known[r:r + tiles.CELLS, c:c + tiles.CELLS] == SOLID).all())
