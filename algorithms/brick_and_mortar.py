"""Brick & Mortar: mark each tile visited when that keeps the unvisited tiles connected, so the visited
region grows from the walls inwards ("bricks") while the rest stays one connected piece ("mortar").

Ferranti, Trigoni, Levene, "Brick&Mortar: an on-line multi-agent exploration algorithm", ICRA 2007: agents
on a grid tag the cells they stand on as *explored* (must be crossed again) or *visited* (never again, as
good as a wall), and tell each other only through those tags. The paper itself was not at hand; the rules
below are MAES's implementation, ``Assets/Scripts/ExplorationAlgorithm/BrickAndMortar/BrickAndMortar.cs``
and ``BrickAndMortarTag.cs`` (DEIS-Tools/MAES commit 1bb0312, where the whole class is commented out, lines
33-545: docs/maes.md section 13.3), which names the paper's phases:

- **Marking** (``UpdateTileStatus``, 218-279). In the regular state the tile the robot stands on becomes
  *visited* unless it is needed to get from one of its traversable (unexplored or explored) 8-neighbours
  to another, read off the ring of eight (``CenterBlocksPathBetweenNeighbours``, 335-375); so visited tiles
  never cut the traversable tiles in two. A tile kept *explored* that the robot left once by another side
  than the one it now comes from is on a loop: **loop control** (224-226).
- **Navigation** (``DetermineNextTarget``, 286-332): one of the four axial neighbours that is traversable,
  scored -100 for going straight back, +10 for unexplored, +1 for each non-traversable tile of the ring
  beside it; ties by a direction order turned by the robot's id (``SetController``, 527-532). With none,
  the robot is done (its tile and all around are visited).
- **Loops** (231-278). In loop control the robot writes its id as the tile's *loop controller* if the one
  there is lower, and keeps the tiles it took (``_controlledTiles``); back on a tile it controls, the loop
  is closed: **loop closing** walks the controlled tiles again from the first, marking each visited until
  one has a traversable neighbour outside the loop; then, or when it meets a higher id's loop or its own
  path backwards, **loop cleaning** walks back over its tiles erasing its id and its exit directions
  (``BrickAndMortarTag.Clean``, 56-59).
- A tile the robot enters becomes *explored* (``DepositNewTag``, 440-444, on first arrival, 204-205); the
  robot remembers the direction it left each tile by (``SetLastExitDirection``, 209-211; tags keep it per
  robot, and only the robot itself reads it).

Departures:

1. Tags are not in the environment: each robot keeps the tile states and loop controllers it knows,
   broadcasts what it writes (message ``brick_and_mortar.tags``, the tick it writes it) and every
   ``share_every`` ticks every state it knows (``brick_and_mortar.board``, so that what others wrote
   travels on from robot to robot); receivers keep the larger state (unexplored < explored < visited) and
   the latest controller. A robot that has not heard of a tile marked visited can take it for traversable
   and mark a tile next to it visited that the real tags would have kept: the visited tiles can then cut
   the rest in two (measured: never with every message delivered, ``radio.model = "global"``).
2. Tiles are MAES's fixed 1 m coarse tiles (:mod:`.tiles`) for every robot, blocked when the robot's map
   has a solid cell in them. MAES drops tags about 0.85 m apart where the robot stands and links them by
   sensing (``IdentifyNeighbour``, 502-525; ``UpdateTagNeighbours``, 474-499, "TODO: ... merge grid"), and
   calls a neighbour without a tag solid when a ray meets a wall within 1.27 m (1.8 m diagonally).
3. MAES's crashes are not reproduced: loop closing meant to reverse the stack of controlled tiles, but
   ``_controlledTiles.Reverse()`` (243) is LINQ's copy, discarded, so it pops the last tile instead of the
   first and the next target is not a neighbour (``First`` throws, 293); a ring with no traversable tile
   makes ``First`` throw too (354); with no traversable neighbour ``bestScore`` stays ``Int32.MinValue``
   where ``== -1`` is tested (328), so the robot drives east into a wall instead of stopping. Here the stack
   is reversed, a next loop tile that is not an axial neighbour ends the loop (the robot's ids are erased
   from the rest at once), and a robot with nowhere to go stops. Arriving, in loop control, on a tile it
   controls with no tile taken in this loop (MAES pops an empty stack, 244) it takes the tile again. A
   loop's end erases the robot's id from every tile, the loop's first one too (MAES pops it at 244 and
   leaves it controlled).
4. Loop closing stops at a neighbour outside the loop whether it is unexplored or explored; MAES looks
   only at tagged (explored) ones (``HasUncontrolledNeighbour``, 282-284), so closing can wall off an
   unexplored tile.
5. A move the navigator gives up (``unreachable``/``blocked``) or that stays within ``progress_m`` for
   ``deadlock_ticks`` (robots in each other's way; MAES pushes on) is abandoned: a loop under way ends as
   in 3, and the robot chooses again without that tile, or, with no other, waits a random 1 to
   ``deadlock_ticks`` ticks (robots that all want the last tile would otherwise push and give up in step).
6. Robots decide at the same tick and hear of each other's tags a tick later, where MAES's run one after
   the other on shared tags, and nothing stops one robot from following another. Two tiles less than three
   apart can each be safe to mark visited and not both (three robots spawned side by side in a corner wall
   a fourth tile in): so a robot with another within ``YIELD_TILES`` tiles marks only at the ticks of its
   own slot (``tick % n_robots == id``), waiting at its tile for it. A robot that followed another onto a
   tile marked visited meanwhile is cut off when the one ahead marks the next: so a robot does not mark
   its tile visited while another stands next to it on a visited tile; it stays explored, to be marked on
   a later pass (in loop closing, which must leave every tile behind it visited, the loop is cleaned
   instead), and a robot with nowhere to go is done only once its own tile is visited (else it waits and
   looks again).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from swarm.api import Action, Neighbours, Observation, RobotInfo, check_float, check_int
from swarm.api.messages import MessageError, message

from . import tiles
from .recovery import Watchdog

UNEXPLORED, EXPLORED, VISITED, SOLID = 0, 1, 2, 3
"""Tile states, MAES's ``TileStatus`` (BrickAndMortar.cs 78-84); SOLID is never stored, it is read off the map."""
NO_ROBOT = -1
KEPT = -2
"""In a tag message: the sender did not write the tile's loop controller."""
OFFSET = ((1, 0), (1, -1), (0, -1), (-1, -1), (-1, 0), (-1, 1), (0, 1), (1, 1))
"""(dx, dy) of MAES's eight directions, clockwise from east (138-148): even ones are axial."""
AXIAL = (0, 2, 4, 6)
REGULAR, LOOP_CONTROL, LOOP_CLOSING, LOOP_CLEANING = "regular", "loop_control", "loop_closing", "loop_cleaning"
MAX_TAGS = 100_000
MAX_BOARD = 1 << 22
"""Tiles in a board message at most: a 4 MiB message, the codec's limit."""
YIELD_TILES = 2
"""Robots whose tiles are this near (Chebyshev, in tiles) could mark tiles of one ring at the same tick
(departure 6)."""


def opposite(direction: int) -> int:
    return (direction + 4) % 8


@message("brick_and_mortar.tags")
@dataclass(frozen=True)
class Tags:
    """What ``sender`` wrote this tick: ``(tx, ty, state, loop controller)`` per tile, the controller -1 for
    none and -2 when the sender did not write it."""

    sender: int
    tags: tuple[tuple[int, int, int, int], ...]

    def validate(self) -> None:
        ok = isinstance(self.tags, tuple) and len(self.tags) <= MAX_TAGS and all(
            isinstance(t, tuple) and len(t) == 4 and all(isinstance(v, int) and not isinstance(v, bool) for v in t)
            and UNEXPLORED <= t[2] <= VISITED and t[3] >= KEPT for t in self.tags)
        if not ok:
            raise MessageError("brick_and_mortar.tags: tags must be (tx, ty, state 0-2, controller >= -2) ints")


@message("brick_and_mortar.board")
@dataclass(frozen=True)
class Board:
    """Every tile state ``sender`` knows, one byte each, row by row from the bottom (departure 1)."""

    sender: int
    states: bytes

    def validate(self) -> None:
        if not isinstance(self.states, bytes) or len(self.states) > MAX_BOARD or max(self.states, default=0) > VISITED:
            raise MessageError("brick_and_mortar.board: states must be bytes of tile states 0-2")


@dataclass(frozen=True)
class BrickAndMortarParams:
    share_every: int = 10        # broadcast every tile state known this often, in ticks (departure 1); 0 = never
    deadlock_ticks: int = 50     # a move that gets nowhere this long is abandoned (departure 5); 0 = never
    progress_m: float = 0.3      # getting nowhere: staying within this of one spot

    def __post_init__(self) -> None:
        check_int("share_every", self.share_every, 0, 1_000_000)
        check_int("deadlock_ticks", self.deadlock_ticks, 0, 1_000_000)
        check_float("progress_m", self.progress_m, 0.0, 100.0, lo_open=True)


class BrickAndMortar:
    """Brick & Mortar as MAES implements it (see the module docstring)."""

    name = "brick_and_mortar"
    Params = BrickAndMortarParams

    def reset(self, robot: RobotInfo, params: BrickAndMortarParams, rng: np.random.Generator) -> None:
        self.me = robot.id
        self.robots = robot.n_robots
        self.params = params
        self.rng = rng
        shape = (-(-robot.map_shape[0] // tiles.CELLS), -(-robot.map_shape[1] // tiles.CELLS))
        self.state_of = np.zeros(shape, dtype=np.int8)             # [ty, tx]: UNEXPLORED..VISITED
        self.controller = np.full(shape, NO_ROBOT, dtype=np.int32)
        self.exits: dict[tuple[int, int], int] = {}                # this robot's last exit direction per tile
        self.priority = tuple((d + 2 * robot.id) % 8 for d in AXIAL)
        self.phase = REGULAR
        self.controlled: list[tuple[int, int]] = []
        self.current: tuple[int, int] | None = None
        self.target: tuple[tuple[int, int], int] | None = None     # (tile, direction from current)
        self.previous = 0                                          # the direction of the last step (MAES: 0)
        self.done = False
        self.goal: tuple[float, float] | None = None
        self.wait_until = -1
        self.watchdog = Watchdog(params.deadlock_ticks, params.progress_m)
        self.written: dict[tuple[int, int], tuple[int, int]] = {}

    # ------------------------------------------------------------------------------------------ act ----
    def act(self, obs: Observation) -> Action:
        self._read(obs.inbox)
        if self.current is None:
            self.current = tiles.tile_of(obs.pose.x, obs.pose.y)
            self._deposit(self.current)
        if self.target is not None and self._ours(obs):
            if obs.nav.state == "reached" and tiles.tile_of(obs.pose.x, obs.pose.y) == self.target[0]:
                self._arrive()
            elif obs.nav.state in ("unreachable", "blocked", "reached") or self.watchdog.stuck(obs):
                self._give_up(obs)
        if self.target is None and not self.done and obs.tick >= self.wait_until:
            self._choose(obs, avoid=None)
        messages = (self._tags(),) if self.written else ()
        if self.params.share_every and obs.tick % self.params.share_every == self.me % self.params.share_every:
            messages += (Board(sender=self.me, states=self.state_of.tobytes()),)
        debug = {"phase": self.phase, "done": self.done, "controlled": len(self.controlled),
                 "current": list(self.current)}
        if self.target is None:
            self.goal = None
            return Action(velocity=(0.0, 0.0), clear_goal=True, messages=messages, debug=debug)
        if self.goal is None:
            self.goal = tiles.tile_goal(self.target[0])
            self.watchdog.restart(obs)
        return Action(goal=self.goal, drive="straight", messages=messages, debug=debug)

    def _ours(self, obs: Observation) -> bool:
        return self.goal is not None and obs.nav.goal == self.goal

    # ----------------------------------------------------------------------------------- the steps ----
    def _choose(self, obs: Observation, avoid: tuple[int, int] | None) -> None:
        """MAES's UpdateLogic without a target (181-194): mark the current tile, pick the next."""
        assert self.current is not None
        ring = self._ring(obs.known, self.current)
        if avoid is None:
            others = self._others(obs)
            if others and obs.tick % self.robots != self.me % self.robots:
                return                         # departure 6: near others, mark only in this robot's slot
            self._mark(self.current, ring, may_visit=not self._leads(others))
        step = self._next(ring, avoid)
        if step is None:
            if avoid is None and self._state(self.current) == VISITED:
                self.done = True
            else:                              # robots after one tile, or its own not marked: retry later
                self.wait_until = obs.tick + int(self.rng.integers(1, max(self.params.deadlock_ticks, 1) + 1))
            return
        self.target = step

    def _arrive(self) -> None:
        """MAES 204-215: tag the tile, remember how the last one was left, stand on the new one."""
        assert self.target is not None and self.current is not None
        tile, direction = self.target
        self._deposit(tile)
        self.previous = direction
        self.exits[self.current] = direction
        self.current = tile
        self.target = None
        self.goal = None

    def _give_up(self, obs: Observation) -> None:
        """Departure 5: the move cannot be finished. End a loop, choose again without that tile."""
        assert self.target is not None
        avoid = self.target[0]
        self.target = None
        self.goal = None
        if self.phase != REGULAR:
            self._clean(avoid)
            self._end_loop()
        self._choose(obs, avoid=avoid)

    def _others(self, obs: Observation) -> list[tuple[int, int]]:
        """The tiles of the robots sensed within ``YIELD_TILES`` tiles (Chebyshev) of this one's."""
        assert self.current is not None
        near = obs.neighbours
        if isinstance(near, Neighbours):   # the runtime's lazy neighbours: build only the close ones
            near = near.within((YIELD_TILES + 2) * tiles.TILE_M)
        out = []
        for other in near:
            t = tiles.tile_of(other.x, other.y)
            if max(abs(t[0] - self.current[0]), abs(t[1] - self.current[1])) <= YIELD_TILES:
                out.append(t)
        return out

    def _leads(self, others: list[tuple[int, int]]) -> bool:
        """Departure 6: a robot stands next to this tile on a tile marked visited, which this one may be its
        only way out of."""
        assert self.current is not None
        return any(max(abs(t[0] - self.current[0]), abs(t[1] - self.current[1])) == 1 and self._state(t) == VISITED
                   for t in others)

    def _mark(self, tile: tuple[int, int], ring: list[int], may_visit: bool) -> None:
        """``UpdateTileStatus`` (218-279); ``may_visit`` False keeps the tile explored (departure 6)."""
        enter = self.previous
        if self.phase == REGULAR:
            if not blocks_path(ring):
                if may_visit:
                    self._write(tile, state=VISITED)
            elif self.exits.get(tile) is not None and opposite(enter) != self.exits[tile]:
                self.phase = LOOP_CONTROL
            return
        if self.phase == LOOP_CONTROL:
            last = self.exits.get(tile)
            if last is None or opposite(enter) == last:
                self.phase = LOOP_CLEANING
            else:
                owner = int(self.controller[tile[1], tile[0]])
                if owner == self.me and self.controlled:   # back on its own loop: close it from the first
                    self.phase = LOOP_CLOSING
                    self.controlled.reverse()
                    self.controlled.pop()
                    return
                if owner <= self.me:
                    self._write(tile, controller=self.me)
                    self.controlled.append(tile)
                elif self.controlled:          # a higher id controls this loop
                    self.phase = LOOP_CLEANING
        if self.phase == LOOP_CLOSING:
            if self._outside_loop(tile, ring) or not may_visit:   # a tile left explored ends the closing
                self.phase = LOOP_CLEANING
            else:
                self._write(tile, state=VISITED)
        if self.phase == LOOP_CLEANING:
            self._clean(tile)

    def _next(self, ring: list[int], avoid: tuple[int, int] | None) -> tuple[tuple[int, int], int] | None:
        """``DetermineNextTarget`` (286-332): the loop's next tile, or the best-scored axial neighbour."""
        assert self.current is not None
        if self.phase in (LOOP_CLEANING, LOOP_CLOSING):
            if not self.controlled:
                self._end_loop()
            else:
                tile = self.controlled.pop()
                for d in AXIAL:
                    if _at(self.current, d) == tile:
                        return tile, d
                self.controlled.append(tile)   # not a neighbour (MAES throws here): end the loop
                self._end_loop()
        best: tuple[int, int, int] | None = None   # (score, -priority, direction)
        for d in AXIAL:
            if not traversable(ring[d]) or _at(self.current, d) == avoid:
                continue
            score = -100 if opposite(d) == self.previous else 0
            score += 10 if ring[d] == UNEXPLORED else 0
            score += (not traversable(ring[(d + 7) % 8])) + (not traversable(ring[(d + 1) % 8]))
            key = (score, -self.priority.index(d), d)
            if best is None or key > best:
                best = key
        return None if best is None else (_at(self.current, best[2]), best[2])

    def _outside_loop(self, tile: tuple[int, int], ring: list[int]) -> bool:
        """A traversable 8-neighbour this robot does not control (``HasUncontrolledNeighbour``, departure 4)."""
        return any(traversable(ring[d]) and int(self.controller[n[1], n[0]]) != self.me
                   for d, n in enumerate(_at(tile, d) for d in range(8)))

    def _end_loop(self) -> None:
        """Back to the regular state, erasing this robot's control from every tile that still has it (the
        rest of a loop given up, and the first tile of a closed one, which MAES leaves controlled)."""
        for tx, ty in np.argwhere(self.controller.T == self.me).tolist():
            self._clean((tx, ty))
        self.controlled.clear()
        self.phase = REGULAR

    def _clean(self, tile: tuple[int, int]) -> None:
        """``BrickAndMortarTag.Clean`` (56-59): forget this robot's exit and its control of the tile."""
        self.exits.pop(tile, None)
        if int(self.controller[tile[1], tile[0]]) == self.me:
            self._write(tile, controller=NO_ROBOT)

    # ------------------------------------------------------------------------------------ the tags ----
    def _ring(self, known: np.ndarray, tile: tuple[int, int]) -> list[int]:
        """The eight neighbours' states, MAES's direction order; SOLID where the map blocks the tile."""
        ring = []
        for dx, dy in OFFSET:
            n = (tile[0] + dx, tile[1] + dy)
            ring.append(SOLID if tiles.blocked(known, n) else self._state(n))
        return ring

    def _state(self, tile: tuple[int, int]) -> int:
        h, w = self.state_of.shape
        if not (0 <= tile[0] < w and 0 <= tile[1] < h):
            return SOLID
        return int(self.state_of[tile[1], tile[0]])

    def _deposit(self, tile: tuple[int, int]) -> None:
        """``DepositNewTag`` (440-444): a tile entered is at least explored."""
        if self._state(tile) == UNEXPLORED:
            self._write(tile, state=EXPLORED)

    def _write(self, tile: tuple[int, int], state: int | None = None, controller: int | None = None) -> None:
        tx, ty = tile
        if not (0 <= ty < self.state_of.shape[0] and 0 <= tx < self.state_of.shape[1]):
            return
        old_state, old_controller = self.written.get(tile, (UNEXPLORED, KEPT))
        if state is not None:
            self.state_of[ty, tx] = max(int(self.state_of[ty, tx]), state)
        if controller is not None:
            self.controller[ty, tx] = controller
        self.written[tile] = (max(old_state, int(self.state_of[ty, tx])),
                              old_controller if controller is None else controller)

    def _tags(self) -> Tags:
        out = Tags(sender=self.me, tags=tuple((tx, ty, s, c) for (tx, ty), (s, c) in sorted(self.written.items())))
        self.written = {}
        return out

    def _read(self, inbox: tuple[Any, ...]) -> None:
        """Departure 1: merge what the others wrote (larger state, latest controller)."""
        h, w = self.state_of.shape
        for msg in inbox:
            if isinstance(msg, Board) and msg.sender != self.me and len(msg.states) == self.state_of.size:
                np.maximum(self.state_of, np.frombuffer(msg.states, dtype=np.int8).reshape(h, w), out=self.state_of)
            if not isinstance(msg, Tags) or msg.sender == self.me:
                continue
            for tx, ty, s, c in msg.tags:
                if 0 <= ty < h and 0 <= tx < w:
                    self.state_of[ty, tx] = max(int(self.state_of[ty, tx]), s)
                    if c != KEPT:
                        self.controller[ty, tx] = c


def traversable(state: int) -> bool:
    return state in (UNEXPLORED, EXPLORED)


def blocks_path(ring: list[int]) -> bool:
    """``CenterBlocksPathBetweenNeighbours`` (335-375): the traversable ring tiles reachable through the
    centre (the axial ones and the diagonals beside a traversable axial one) do not all lie on one run of
    consecutive traversable ring tiles, so without the centre some would be cut off from the others."""
    via = set()
    for d in AXIAL:
        if traversable(ring[d]):
            via.add(d)
            for side in ((d + 7) % 8, (d + 1) % 8):
                if traversable(ring[side]):
                    via.add(side)
    if len(via) >= 7 or not via:
        return False
    first = next(d for d in AXIAL if d in via)
    run = {first}
    for step in (7, 1):                 # counter-clockwise, then clockwise, while traversable
        d = (first + step) % 8
        while traversable(ring[d]) and d != first:
            run.add(d)
            d = (d + step) % 8
    return len(run) != len(via)


def _at(tile: tuple[int, int], direction: int) -> tuple[int, int]:
    dx, dy = OFFSET[direction]
    return tile[0] + dx, tile[1] + dy
