"""SSB: spiral over 1 m tiles, reserving them so that no two robots cover one, then auction the backtracking
points (unexplored tiles left beside the covered ones) and spiral again from the one won.

A multi-robot version of the backtracking spiral algorithm (BSA: Gonzalez et al., "BSA: a complete coverage
algorithm", ICRA 2005), compared in the MAES paper (Andreasen, Holler, Jensen, Albano, ICAART 2022) under
the name SSB. Neither paper was at hand: the rules below are MAES's implementation,
``Assets/Scripts/ExplorationAlgorithm/SSB/SSBAlgorithm.cs``, ``TileReservationSystem.cs`` and
``BroadcastMessage.cs`` (DEIS-Tools/MAES commit 1bb0312; docs/maes.md section 13.4), whose comments name
"the spiral algorithm specified by the bsa paper" (578) and "the SSB paper" (604-606):

- **Spiralling** (``PerformSpiraling``, 332-361; ``DetermineNextSpiralTarget``, 559-590). The robot faces a
  compass direction and keeps a wall on its *reference lateral side*: next it takes that side's tile if it
  is free, else the tile ahead, else the opposite side's; a tile is *blocked* when it is solid, explored
  (covered) or reserved by another robot (``IsTileBlocked``, 495-501). Each tile reached is marked explored
  (433-438). With all three blocked the spiral ends and the robot backtracks.
- **Backtracking points** (``DetectBacktrackingPoints``, 607-617): a free, unexplored side tile with a solid
  or explored tile ahead, diagonally ahead or diagonally behind on that side; also the blocked-by-reservation
  tiles passed over (572-588).
- **Tile reservation** (``TileReservationSystem.cs``): before moving a robot reserves the tiles ahead (at
  least the next two of up to five straight on, ``EnsureFutureSpiralPathReserved``, 389-415; every tile of a
  backtracking path step, 279-300) and broadcasts them; a receiver keeps a tile's reservation unless a
  higher id's arrives (111-117); a robot counts its own only from the tick after it made it (83-89), so of
  two robots reserving one tile at the same tick only the higher id goes. Turning (369), starting a path
  step (263) and ending a spiral (341) clear the robot's reservations except the tile it stands on.
- **The auction** (``PerformBackTrack``, 195-227; the messages, 697-977). A robot without a target asks
  for backtracking points (at most every 10 ticks, 77-78, 202-205); the others answer with theirs, everyone
  merges them and bids, for each point, the Manhattan distance plus, when spiralling, the tiles left in its
  spiral (``GenerateBids``, 800-821; ``SimulateSpiraling``, 621-669); the asking robot gives each robot at
  most one point, cheapest first (860-925), and broadcasts the winners. Without a win it takes the nearest
  point it knows with a path (``FindBestBackTrackingTarget``, 511-539; a free tile at or next to it when it
  knows none, 542-555). It follows the path in straight steps, faces along a wall (441-482) and spirals.
- A collision ends whatever the robot does and sends it backtracking (130-136); a step whose tiles another
  robot holds is retried after 10 ticks, and after 100 the target is dropped (280-293).

Departures:

1. Explored tiles are shared by message (``ssb.explored``, every ``share_every`` ticks, the sender's whole
   layer as bits): MAES keeps them in the coarse map, which its distributed SLAM synchronises.
2. Headings are compass directions the robot keeps, not its body's (as :mod:`.wall_follower`, departure 6):
   a turn changes the direction at once; moves are goals with ``drive = "straight"`` (MAES's ``MoveTo``)
   to the next tile, or to the end of a backtracking step.
3. A move the navigator gives up (``unreachable``/``blocked``), ends off its tile or that stays within
   ``progress_m`` for ``deadlock_ticks`` counts as a collision (MAES has no such signal).
4. A tile reserved by another robot is skipped when reserving (``ReserveLocally`` throws, 56-57); a
   clearing removes a tile's reservation only if the sender holds it (``ClearReservations``, 140-143,
   removes whoever holds it); two answers with points in one tick keep both sets (``Combine``, 785-787,
   unions the higher requester's set with itself and drops the other); bids addressed to this robot are
   merged whatever came first (928-931 drop them behind a message for another); several auction results in
   one tick are applied in sender order (MAES throws, 973-974). Each tick's messages are handled in the
   order: explored tiles, reservations (clearings first), requests, points, bids, results (MAES: the order
   they arrived in), and also in the ticks of the first reservation (MAES skips them, 116-122).
5. ``SimulateSpiraling`` takes a tile for free when it is solid or explored and for blocked when it is
   free: its helper ``IsPotentiallyExplorable`` (672-675) negates the map's answer, so the simulated robot
   walks the walls and covered tiles, and usually runs straight for more than 20 tiles (no bids from a
   spiralling robot). swarm counts the free tiles left, the evident intent; ``variant = "maes"`` keeps
   MAES's test and, of departure 4, the clearing of a tile whoever holds it and the points of only the
   higher requester.
6. A robot with no backtracking point anywhere stays where it is and keeps asking (MAES's ``Terminated``
   state is never entered); ``_bpsFoundThisSpiralPhase`` (56, 337-339) is never filled in MAES and is left
   out.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from swarm.api import OMIT_DEFAULT, UNSEEN, Action, Observation, RobotInfo, check_choice, check_float, check_int
from swarm.api.messages import MessageError, message

from . import tiles
from .recovery import Watchdog

VARIANTS = ("swarm", "maes")
SPIRALING, BACKTRACKING = "spiraling", "backtracking"
LEFT, FRONT, RIGHT = -1, 0, 1
"""Turns relative to the robot's compass direction (tiles.STEP is clockwise: north, east, south, west)."""
REQUEST_EVERY = 10
"""``MinimumTicksBetweenBpRequests`` (78)."""
RESERVE_AHEAD, RESERVE_MIN = 5, 2
"""Straight tiles predicted and reserved at most, and reserved at least before a spiral move (392, 405, 410)."""
STEP_WAIT, DEADLOCK_GIVE_UP = 10, 100
"""A path step held by another robot: wait, and drop the target after this much waiting (285-292)."""
SPIRAL_MAX_COST, SPIRAL_MAX_STRAIGHT = 100, 20
"""``SimulateSpiraling``'s limits (621, 634)."""
MAX_TILES = 1 << 16

Tile = tuple[int, int]


def _tile_tuple(name: str, value: Any, width: int) -> None:
    ok = isinstance(value, tuple) and len(value) <= MAX_TILES and all(
        isinstance(t, tuple) and len(t) == width and all(isinstance(v, int) and not isinstance(v, bool) for v in t)
        for t in value)
    if not ok:
        raise MessageError(f"{name}: must be a tuple of {width}-int tuples")


@message("ssb.reservations")
@dataclass(frozen=True)
class Reservations:
    """Tiles ``sender`` reserved and cleared this tick (``ReservationMessage``, ``ReservationClearingMessage``)."""

    sender: int
    reserved: tuple[tuple[int, int], ...]
    cleared: tuple[tuple[int, int], ...]

    def validate(self) -> None:
        _tile_tuple("ssb.reservations.reserved", self.reserved, 2)
        _tile_tuple("ssb.reservations.cleared", self.cleared, 2)


@message("ssb.request")
@dataclass(frozen=True)
class Request:
    """``sender`` asks for every robot's backtracking points and opens an auction (``RequestMessage``)."""

    sender: int


@message("ssb.points")
@dataclass(frozen=True)
class Points:
    """Backtracking points, in answer to ``requester``'s request (``BackTrackingPointsMessage``)."""

    sender: int
    requester: int
    points: tuple[tuple[int, int], ...]

    def validate(self) -> None:
        _tile_tuple("ssb.points.points", self.points, 2)


@message("ssb.bids")
@dataclass(frozen=True)
class Bids:
    """``(tx, ty, cost)`` per point, ``sender``'s bids in ``requester``'s auction (``BiddingMessage``)."""

    sender: int
    requester: int
    bids: tuple[tuple[int, int, int], ...]

    def validate(self) -> None:
        _tile_tuple("ssb.bids.bids", self.bids, 3)


@message("ssb.results")
@dataclass(frozen=True)
class Results:
    """``(robot, tx, ty)``: the point each robot won (``AuctionResultsMessage``)."""

    sender: int
    winners: tuple[tuple[int, int, int], ...]

    def validate(self) -> None:
        _tile_tuple("ssb.results.winners", self.winners, 3)


@message("ssb.explored")
@dataclass(frozen=True)
class Explored:
    """Every tile ``sender`` knows explored, one bit each, row by row from the bottom (departure 1)."""

    sender: int
    bits: bytes

    def validate(self) -> None:
        if not isinstance(self.bits, bytes) or len(self.bits) > MAX_TILES * 64:
            raise MessageError("ssb.explored: bits must be bytes")


@dataclass(frozen=True)
class SSBParams:
    # "swarm": the spiral left is counted in bids (departure 5); "maes": MAES's inverted test, clearings, points
    variant: str = field(default="swarm", metadata={OMIT_DEFAULT: True})
    share_every: int = 10        # broadcast the explored tiles this often, in ticks (departure 1); 0 = never
    deadlock_ticks: int = 50     # a move that gets nowhere this long counts as a collision (departure 3); 0 = never
    progress_m: float = 0.3      # getting nowhere: staying within this of one spot

    def __post_init__(self) -> None:
        check_choice("variant", self.variant, VARIANTS)
        check_int("share_every", self.share_every, 0, 1_000_000)
        check_int("deadlock_ticks", self.deadlock_ticks, 0, 1_000_000)
        check_float("progress_m", self.progress_m, 0.0, 100.0, lo_open=True)


class SSB:
    """SSB as MAES implements it (see the module docstring)."""

    name = "ssb"
    Params = SSBParams

    def reset(self, robot: RobotInfo, params: SSBParams, rng: np.random.Generator) -> None:
        self.me = robot.id
        self.params = params
        self.maes = params.variant == "maes"
        shape = (-(-robot.map_shape[0] // tiles.CELLS), -(-robot.map_shape[1] // tiles.CELLS))
        self.explored = np.zeros(shape, dtype=bool)                 # [ty, tx]
        self.reservations: dict[Tile, tuple[int, int]] = {}         # tile -> (robot, tick reserved)
        self.reserved_out: set[Tile] = set()
        self.cleared_out: set[Tile] = set()
        self.outbox: list[Any] = []
        self.state = BACKTRACKING
        self.points: set[Tile] = set()
        self.target: Tile | None = None                             # the backtracking point
        self.path: list[tuple[tuple[Tile, ...], Tile]] | None = None   # steps: (crossed tiles, end)
        self.step: tuple[tuple[Tile, ...], Tile] | None = None
        self.spiral_target: Tile | None = None
        self.facing = 0
        self.side = RIGHT                                           # the reference lateral side
        self.tick = 0
        self.wait_until = 0
        self.deadlock_waited = 0
        self.last_request = -1
        self.request_sent = -(1 << 30)
        self.initial_reserved = False
        self.here: Tile = (0, 0)
        self.known = np.zeros(robot.map_shape, dtype=np.uint8)
        self.obs: Observation | None = None
        self.goal: tuple[float, float] | None = None
        self.watchdog = Watchdog(params.deadlock_ticks, params.progress_m)

    # ------------------------------------------------------------------------------------------ act ----
    def act(self, obs: Observation) -> Action:
        self.tick = obs.tick + 1                                    # MAES's _currentTick counts from 1
        self.obs = obs
        self.known = obs.known
        self.here = tiles.tile_of(obs.pose.x, obs.pose.y)
        self.outbox = []
        self._read(obs.inbox)
        if not self.initial_reserved:                               # 116-123
            if self._mine_confirmed(self.here):
                self.initial_reserved = True
            else:
                self._reserve((self.here,))
                return self._action(obs)
        if self.goal is not None and obs.nav.goal == self.goal:
            if obs.nav.state == "reached" and self.here == self._goal_tile():
                self.goal = None
            elif obs.nav.state in ("unreachable", "blocked", "reached") or self.watchdog.stuck(obs):
                self._collide()                                     # departure 3
            else:
                return self._action(obs)
        if obs.collided:
            self._collide()
        for _ in range(50):                                         # 139-150
            if self.tick < self.wait_until or self.goal is not None:
                break
            if self.state == BACKTRACKING:
                self._backtrack()
            if self.state == SPIRALING and self.tick >= self.wait_until and self.goal is None:
                self._spiral()
        return self._action(obs)

    def _action(self, obs: Observation) -> Action:
        messages = list(self.outbox)
        if self.reserved_out or self.cleared_out:
            messages.append(Reservations(sender=self.me, reserved=tuple(sorted(self.reserved_out)),
                                         cleared=tuple(sorted(self.cleared_out))))
            self.reserved_out, self.cleared_out = set(), set()
        every = self.params.share_every
        if every and obs.tick % every == self.me % every:
            messages.append(Explored(sender=self.me, bits=np.packbits(self.explored).tobytes()))
        debug = {"state": self.state, "target": list(self.target or ()), "points": len(self.points),
                 "facing": "NESW"[self.facing]}
        if self.goal is None:
            return Action(velocity=(0.0, 0.0), clear_goal=True, messages=tuple(messages), debug=debug)
        return Action(goal=self.goal, drive="straight", messages=tuple(messages), debug=debug)

    def _goal_tile(self) -> Tile | None:
        if self.state == SPIRALING:
            return self.spiral_target
        return None if self.step is None else self.step[1]

    def _move(self, tile: Tile) -> None:
        assert self.obs is not None
        self.goal = tiles.tile_goal(tile)
        self.watchdog.restart(self.obs)

    def _collide(self) -> None:
        """130-136: a collision sends the robot backtracking (its target kept, its path planned again)."""
        self.state = BACKTRACKING
        self.path = None
        self.step = None
        self.spiral_target = None
        self.goal = None

    # ---------------------------------------------------------------------------------- backtracking ----
    def _backtrack(self) -> None:
        """``PerformBackTrack`` (195-313)."""
        if self.target is None:
            self._clear_except(self.here)
            if self.tick - self.last_request >= REQUEST_EVERY:
                self.last_request = self.request_sent = self.tick
                self.outbox.append(Request(sender=self.me))
            if self.request_sent == self.tick - 3:
                self.target = self._best_point()
            elif self.request_sent == self.tick - 1:
                self.outbox.append(Points(sender=self.me, requester=self.me, points=tuple(sorted(self.points))))
            self.wait_until = self.tick + 1
            return
        if self._explored(self.target):
            self.target = None
            return
        if self.path is None:
            path = self._path_steps(self.target)
            if path is None:
                self.wait_until = self.tick + STEP_WAIT
                self.target = None
                return
            self.path = path
        if self.step is None and not self.path:
            if self._orient():
                self._start_spiral()
            return
        if self.step is None:
            self.step = self.path.pop(0)
            self._clear_except(self.here)
            self.wait_until = self.tick + 1
            if any(tiles.blocked(self.known, t) for t in self.step[0][1:]):
                self.step = None
                self.path = None
            return
        crossed = self.step[0]
        if not all(self._holder(t) == self.me for t in crossed):
            if any(self._other(t) for t in crossed):
                self.path = None
                self.step = None
                if self.deadlock_waited > DEADLOCK_GIVE_UP:
                    self.deadlock_waited = 0
                    self.target = None
                    return
                self.wait_until = self.tick + STEP_WAIT
                self.deadlock_waited += STEP_WAIT
            else:
                self._reserve(crossed)
                self.wait_until = self.tick + 1
            return
        self.deadlock_waited = 0
        if self.here != self.step[1]:
            self._move(self.step[1])
        else:
            self.step = None

    def _start_spiral(self) -> None:
        """315-322."""
        self.state = SPIRALING
        self.step = None
        self.path = None
        self.target = None
        self._mark(self.here)
        self._detect_points()

    def _orient(self) -> bool:
        """``EnsureCorrectOrientationForSpiraling`` (441-482): face the first free direction of east, south,
        west, north with a blocked tile on its left (then the reference side is left) or right; else north,
        reference side right. The turn is immediate (departure 2)."""
        for d in (1, 2, 3, 0):
            if self._blocked(tiles.step(self.here, d)):
                continue
            for side in (LEFT, RIGHT):
                if self._blocked(tiles.step(self.here, (d + side) % 4)):
                    self.facing, self.side = d, side
                    return True
        self.facing, self.side = 0, RIGHT
        return True

    def _best_point(self) -> Tile | None:
        """``FindBestBackTrackingTarget`` (511-539), ``FindNearbyBP`` (542-555)."""
        self.points = {p for p in self.points if not self._blocked(p)}
        if not self.points:
            near = next((t for t in [self.here] + [(self.here[0] + dx, self.here[1] + dy) for dx, dy in NEARBY]
                         if not self._blocked(t)), None)
            if near is None:
                return None
            self.points.add(near)
        for p in sorted(self.points, key=lambda p: (math.dist(p, self.here), p)):
            if self._path_steps(p) is not None:
                return p
        return None

    def _path_steps(self, goal: Tile) -> list[tuple[tuple[Tile, ...], Tile]] | None:
        """``GetPathSteps``: a shortest 4-connected tile path to ``goal`` over tiles not blocked and not
        wholly unseen, cut into straight steps ``(tiles crossed, end)``; [] when already there."""
        if goal == self.here:
            return []
        came: dict[Tile, Tile] = {self.here: self.here}
        queue = deque([self.here])
        while queue and goal not in came:
            t = queue.popleft()
            for d in range(4):
                n = tiles.step(t, d)
                if n not in came and self._passable(n):
                    came[n] = t
                    queue.append(n)
        if goal not in came:
            return None
        path = [goal]
        while path[-1] != self.here:
            path.append(came[path[-1]])
        path.reverse()
        steps: list[tuple[tuple[Tile, ...], Tile]] = []
        start = 0
        for i in range(1, len(path)):
            if i == len(path) - 1 or _delta(path[i], path[i + 1]) != _delta(path[i - 1], path[i]):
                steps.append((tuple(path[start:i + 1]), path[i]))
                start = i
        return steps

    def _passable(self, tile: Tile) -> bool:
        if tiles.blocked(self.known, tile):
            return False
        r, c = tile[1] * tiles.CELLS, tile[0] * tiles.CELLS
        return bool((self.known[r:r + tiles.CELLS, c:c + tiles.CELLS] != UNSEEN).any())

    # ------------------------------------------------------------------------------------ spiralling ----
    def _spiral(self) -> None:
        """``PerformSpiraling`` (332-361) and ``MoveToSpiralTarget`` (363-387)."""
        if self.spiral_target is None:
            self.spiral_target = self._next_spiral_target()
        if self.spiral_target is None:                              # 335-345
            self.points = {p for p in self.points if not self._explored(p)}
            self._clear_except(self.here)
            self.state = BACKTRACKING
            return
        if self._other(self.spiral_target):
            self.spiral_target = None
            return
        if self.here == self.spiral_target:
            self._mark(self.spiral_target)
            self.spiral_target = None
            return
        direction = next((d for d in range(4) if tiles.step(self.here, d) == self.spiral_target), None)
        if direction is None:                                       # pushed off the spiral: backtrack
            self._collide()
            return
        if direction != self.facing:                                # 364-370: a turn
            self._detect_points()
            self._clear_except(self.here)
            self.facing = direction
            return
        if not self._reserve_ahead():                               # 373-379
            self.wait_until = self.tick + 1
            return
        self._detect_points()
        self._move(self.spiral_target)

    def _next_spiral_target(self) -> Tile | None:
        """``DetermineNextSpiralTarget`` (559-590): the reference side, else ahead, else the other side."""
        front = tiles.step(self.here, self.facing)
        rls = tiles.step(self.here, (self.facing + self.side) % 4)
        ols = tiles.step(self.here, (self.facing - self.side) % 4)
        blocked = {t: self._blocked(t) for t in (front, rls, ols)}
        if all(blocked.values()):
            self.points.update(t for t in (front, rls, ols) if not self._solid_or_explored(t))
            return None
        if not blocked[rls]:
            return rls
        self._point_if_open(rls)
        if blocked[front]:
            self._point_if_open(front)
            return ols
        self._point_if_open(ols)
        return front

    def _point_if_open(self, tile: Tile) -> None:
        if not self._solid_or_explored(tile):
            self.points.add(tile)

    def _reserve_ahead(self) -> bool:
        """``EnsureFutureSpiralPathReserved`` (389-415), ``EstimateSpiralPathBeforeTurning`` (417-431)."""
        assert self.spiral_target is not None
        tile, ahead = self.spiral_target, [self.spiral_target]
        side = (self.facing + self.side) % 4
        while (len(ahead) < RESERVE_AHEAD and not self._blocked(tiles.step(tile, self.facing))
               and self._blocked(tiles.step(tile, side))):
            tile = tiles.step(tile, self.facing)
            ahead.append(tile)
        held = 0
        for t in ahead:
            if not self._mine_confirmed(t):
                break
            held += 1
        if held >= min(RESERVE_MIN, len(ahead)):
            return True
        self._reserve(tuple(ahead))
        return self._mine_confirmed(ahead[0])

    def _detect_points(self) -> None:
        """``DetectBacktrackingPoints`` (607-617): a free side tile with the tile ahead, diagonally ahead or
        diagonally behind on that side solid or explored."""
        front = tiles.step(self.here, self.facing)
        back = tiles.step(self.here, self.facing, -1)
        for turn in (RIGHT, LEFT):
            d = (self.facing + turn) % 4
            side = tiles.step(self.here, d)
            if not self._solid_or_explored(side) and (
                    self._solid_or_explored(front) or self._solid_or_explored(tiles.step(front, d))
                    or self._solid_or_explored(tiles.step(back, d))):
                self.points.add(side)

    def _simulate_spiral(self) -> int | None:
        """``SimulateSpiraling`` (621-669): the tiles left in this spiral if unknown tiles are free; None if
        it does not end within 100 tiles or runs straight for more than 20."""
        cost, straight = 1, 0
        seen: set[Tile] = set()
        tile, facing = self.spiral_target or self.here, self.facing
        while cost < SPIRAL_MAX_COST:
            seen.add(tile)
            front = tiles.step(tile, facing)
            rls = tiles.step(tile, (facing + self.side) % 4)
            ols = tiles.step(tile, (facing - self.side) % 4)
            blocked = [self._sim_blocked(t) or t in seen for t in (front, rls, ols)]
            if all(blocked):
                return cost
            turn = self.side if not blocked[1] else (-self.side if blocked[0] else FRONT)
            straight = straight + 1 if turn == FRONT else 0
            if straight > SPIRAL_MAX_STRAIGHT:
                return None
            facing = (facing + turn) % 4
            tile = tiles.step(tile, facing)
            cost += 1
        return None

    def _sim_blocked(self, tile: Tile) -> bool:
        """Departure 5: solid, explored or reserved by another; MAES (672-675) negates the first two."""
        potentially = not tiles.blocked(self.known, tile) and not self._explored(tile)
        if self.maes:
            potentially = not potentially
        return not potentially or self._other(tile)

    # --------------------------------------------------------------------------------- tile layers ----
    def _solid_or_explored(self, tile: Tile) -> bool:
        return tiles.blocked(self.known, tile) or self._explored(tile)

    def _blocked(self, tile: Tile) -> bool:
        """``IsTileBlocked`` (495-501): solid, explored or reserved by another robot."""
        return self._solid_or_explored(tile) or self._other(tile)

    def _explored(self, tile: Tile) -> bool:
        h, w = self.explored.shape
        return 0 <= tile[0] < w and 0 <= tile[1] < h and bool(self.explored[tile[1], tile[0]])

    def _mark(self, tile: Tile) -> None:
        """``MarkTileExplored`` (433-438)."""
        h, w = self.explored.shape
        if 0 <= tile[0] < w and 0 <= tile[1] < h:
            self.explored[tile[1], tile[0]] = True
        self.points.discard(tile)

    # ---------------------------------------------------------------------------------- reservations ----
    def _holder(self, tile: Tile) -> int | None:
        entry = self.reservations.get(tile)
        return None if entry is None else entry[0]

    def _other(self, tile: Tile) -> bool:
        """``IsTileReservedByOtherRobot`` (92-95)."""
        holder = self._holder(tile)
        return holder is not None and holder != self.me

    def _mine_confirmed(self, tile: Tile) -> bool:
        """``IsTileReservedByThisRobot`` (83-89): held, and not reserved this very tick."""
        entry = self.reservations.get(tile)
        return entry is not None and entry[0] == self.me and entry[1] != self.tick

    def _reserve(self, wanted: tuple[Tile, ...]) -> None:
        """``Reserve`` (66-80); a tile another robot holds is skipped (departure 4)."""
        new = [t for t in wanted if t not in self.reservations]
        for t in new:
            self.reservations[t] = (self.me, self.tick)
        if new:
            mine = [t for t in wanted if self._holder(t) == self.me]
            self.reserved_out.update(mine)
            self.cleared_out.difference_update(mine)

    def _clear_except(self, keep: Tile) -> None:
        """``ClearThisRobotsReservationsExcept`` (119-134)."""
        gone = [t for t, (robot, _) in self.reservations.items() if robot == self.me and t != keep]
        for t in gone:
            del self.reservations[t]
        self.cleared_out.update(gone)
        self.reserved_out.difference_update(gone)

    # -------------------------------------------------------------------------------------- messages ----
    def _read(self, inbox: tuple[Any, ...]) -> None:
        """``ProcessIncomingCommunication`` (153-192), in departure 4's order."""
        msgs = [m for m in inbox if getattr(m, "sender", self.me) != self.me]
        for m in msgs:
            if isinstance(m, Explored) and len(m.bits) == -(-self.explored.size // 8):
                bits = np.unpackbits(np.frombuffer(m.bits, dtype=np.uint8), count=self.explored.size)
                self.explored |= bits.reshape(self.explored.shape).astype(bool)
        for m in msgs:
            if isinstance(m, Reservations):
                for t in m.cleared:                                 # ReservationClearingMessage
                    if self.maes or self._holder(t) == m.sender:
                        self.reservations.pop(t, None)
                for t in m.reserved:                                # RegisterReservationFromOtherRobot
                    holder = self._holder(t)
                    if holder is None or holder < m.sender:
                        self.reservations[t] = (m.sender, self.tick)
        requests = [m for m in msgs if isinstance(m, Request)]
        if requests:
            self._on_request(max(r.sender for r in requests))
        points = [m for m in msgs if isinstance(m, Points)]
        if points:
            requester = max(p.requester for p in points)
            merged = {t for p in points if not self.maes or p.requester == requester for t in p.points}
            self._on_points(requester, merged)
        mine = [m for m in msgs if isinstance(m, Bids) and m.requester == self.me]
        if mine:
            self._auction([(m.sender, b) for m in mine for b in m.bids])
        for m in msgs:
            if isinstance(m, Results):
                won = [(tx, ty) for robot, tx, ty in m.winners if robot == self.me]
                self.target = won[0] if won else None               # 956-969

    def _on_request(self, requester: int) -> None:
        """``RequestMessage.Process`` (707-730)."""
        self.last_request = self.tick
        if self.request_sent == self.tick - 1 and requester < self.me:
            return
        self.points = {p for p in self.points if not self._explored(p)}
        if self.points:
            self.outbox.append(Points(sender=self.me, requester=requester, points=tuple(sorted(self.points))))

    def _on_points(self, requester: int, points: set[Tile]) -> None:
        """``BackTrackingPointsMessage.Process`` (756-780)."""
        self.points = {p for p in self.points | points if not self._explored(p)}
        if self.request_sent == self.tick - 2 and requester < self.me:
            return
        if requester == self.me:
            return
        self.outbox.append(Bids(sender=self.me, requester=requester, bids=self._bids()))

    def _bids(self) -> tuple[tuple[int, int, int], ...]:
        """``GenerateBids`` (800-821): Manhattan distance plus the spiral left (when spiralling)."""
        left = self._simulate_spiral() if self.state == SPIRALING else 0
        if left is None:
            return ()
        return tuple((p[0], p[1], left + abs(p[0] - self.here[0]) + abs(p[1] - self.here[1]))
                     for p in sorted(self.points))

    def _auction(self, received: list[tuple[int, tuple[int, int, int]]]) -> None:
        """``BiddingMessage.Process`` (860-925): each robot wins at most one point, the cheapest bids first."""
        offers: dict[Tile, list[tuple[int, int]]] = {}              # point -> [(cost, robot)]
        for robot, (tx, ty, cost) in received + [(self.me, b) for b in self._bids()]:
            offers.setdefault((tx, ty), []).append((cost, robot))
        queues = {p: deque(sorted(o, key=lambda b: b[0])) for p, o in offers.items()}
        best: dict[int, tuple[Tile, int]] = {}                      # robot -> (point, cost)
        settled = False
        while not settled:
            settled = True
            for point, queue in queues.items():
                if not queue:
                    continue
                cost, robot = queue[0]
                if robot in best:
                    if best[robot][0] == point:
                        continue
                    settled = False
                    if cost < best[robot][1]:
                        queues[best[robot][0]].popleft()
                        best[robot] = (point, cost)
                    else:
                        queue.popleft()
                else:
                    best[robot] = (point, cost)
                    settled = False
        winners = tuple((robot, p[0], p[1]) for robot, (p, _) in sorted(best.items()))
        self.target = best[self.me][0] if self.me in best else None
        self.outbox.append(Results(sender=self.me, winners=winners))


NEARBY = ((1, 0), (1, -1), (0, -1), (-1, -1), (-1, 0), (-1, 1), (0, 1), (1, 1))
"""``GetCardinalAndOrdinalDirections`` (548; ``CardinalDirection.cs`` 33-41, 108), clockwise from east."""


def _delta(a: Tile, b: Tile) -> Tile:
    return b[0] - a[0], b[1] - a[1]
