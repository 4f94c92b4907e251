"""Wall Follower: keep a wall on one side, moving one 1 m tile at a time.

MAES's ``WallFollowerAlgorithm`` (``Assets/Scripts/ExplorationAlgorithm/WallFollower/WallFollower.cs`` at
DEIS-Tools/MAES commit d9fd56c, "Wall follower Algorithm (#2)", on the branch of pull request 133, not
merged into MAES's main at 1bb0312; docs/maes.md section 13.2). It "implements the Wall Follower 1
pseudocode" of a left-hand grid-maze follower (line 130; the rule below), which is what swarm follows. As
MAES:

- The robot moves on MAES's 1 m coarse tiles (:mod:`.tiles`), facing north, east, south or west.
- It first heads west until a wall is ahead, then faces north, so that the wall is on its left (lines
  109-127); the first look ahead is along the start direction, north (MAES turns to north before it,
  101-107).
- Then one application of the rule per tile (130-155): if it has just turned left and nothing is ahead, go
  forward; else if nothing is on the left, turn left; else if nothing is ahead, go forward; else turn
  right. "Forward" moves the target one tile on (``GoForward``, 204-208, then ``MoveTo``, 95-99: a turn and
  one straight move); a turn only changes the direction.
- A collision steps the target back one tile and counts as a wall ahead at the next decision (75-80, 132,
  146); it is noticed once until that decision (``_collided``).
- It sends nothing.

Departures:

1. "A wall on a side" is the pseudocode's: the neighbouring tile on that side is blocked (a SOLID cell of
   the robot's map in it, or off the map). MAES casts a ray from the robot along that side and asks for a
   wall within 1.8 m (``_gridSpacing``, line 12; ``IsWallForward``/``Left``/``Right``, 210-235): so a wall
   1.5 m away, one free tile between, counts too, the robot turns at corners one tile early and then
   follows the wall one tile off it, and at an opening on its wall side (a door) the ray misses the jamb
   diagonally ahead: it turns into the opening, finds nothing on its left and turns again, round four
   tiles for ever. ``variant = "maes"`` casts MAES's ray, on the robot's map (and counts contacts as MAES,
   departure 5).
2. MAES's ray runs through the true map (``DetectWall`` -> ``CommunicationManager.DetectWall``); here the
   robot's own map (its lidar and what it was sent): unseen cells are not walls.
3. ``side = "right"`` mirrors the rule (east first, the wall kept on the right); the default ``"left"`` is
   MAES's.
4. Moves are goals with ``drive = "straight"`` (MAES's ``MoveTo``, exact under ``motion.model = "maes"``);
   under the continuous model the navigator drives there. A move the navigator reports ``unreachable`` or
   ``blocked``, or that stays within ``progress_m`` for ``deadlock_ticks`` (robots queueing along one wall
   push each other for ever), counts as a collision where the robot stands (MAES has neither; its move just
   ends against the obstacle). ``deadlock_ticks = 0`` turns the watchdog off.
5. A contact counts as a collision only once it lasts into a move's second tick: MAES counts any (75-80),
   so a robot that another one touches while it stands, or while it pulls away, steps back again at every
   decision. ``variant = "maes"`` counts any.
6. The rule is applied once the move to the target tile has ended, facing any way: MAES first turns in
   place to the direction (101-107), which changes nothing but time, since the walls are looked for along
   the direction, not along the robot's heading.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from swarm.api import CELL_M, OMIT_DEFAULT, SOLID, Action, Observation, RobotInfo, check_choice, check_float, check_int

from . import tiles
from .recovery import Watchdog

VARIANTS = ("swarm", "maes")
SIDES = ("left", "right")
MAES_WALL_RANGE_M = 1.8
"""``variant = "maes"``: a wall this near along a side's ray is on that side (``_gridSpacing``, line 12)."""
RAY_STEP_M = CELL_M / 10
NORTH = 0
_MOVING = ("planning", "moving")


@dataclass(frozen=True)
class WallFollowerParams:
    # "swarm": a wall on a side is the neighbouring tile (departures 1, 5); "maes": MAES's 1.8 m ray
    variant: str = field(default="swarm", metadata={OMIT_DEFAULT: True})
    side: str = "left"           # the wall's side: "left" (MAES) or "right"
    deadlock_ticks: int = 50     # a move that gets nowhere this long counts as a collision; 0 = never (MAES)
    progress_m: float = 0.3      # getting nowhere: staying within this of one spot

    def __post_init__(self) -> None:
        check_choice("variant", self.variant, VARIANTS)
        check_choice("side", self.side, SIDES)
        check_int("deadlock_ticks", self.deadlock_ticks, 0, 1_000_000)
        check_float("progress_m", self.progress_m, 0.0, 100.0, lo_open=True)


class WallFollower:
    """The left-hand (or right-hand) wall follower of MAES (see the module docstring)."""

    name = "wall_follower"
    Params = WallFollowerParams

    def reset(self, robot: RobotInfo, params: WallFollowerParams, rng: np.random.Generator) -> None:
        self.maes = params.variant == "maes"
        self.turn = -1 if params.side == "left" else 1   # the wall's side as a turn: MAES's TurnLeft is -1
        self.direction = NORTH
        self.seeking = True                    # MAES's _initial: heading for the first wall
        self.turned = False                    # MAES's _hasTurnedLeft (towards the wall's side)
        self.collided = False
        self.target: tuple[int, int] | None = None
        self.goal: tuple[float, float] | None = None
        self.watchdog = Watchdog(params.deadlock_ticks, params.progress_m)
        self.moved_at = 0                      # the tick the current target was set

    def act(self, obs: Observation) -> Action:
        here = tiles.tile_of(obs.pose.x, obs.pose.y)
        if self.target is None:
            self.target = here
        if self._ours(obs) and (obs.nav.state in ("unreachable", "blocked") or self.watchdog.stuck(obs)):
            self.collided = True               # the move cannot be finished: decide here, a wall ahead
            self._set_target(here, obs)
        elif obs.collided and not self.collided and self._collision_counts(obs):
            self.collided = True               # WallFollower.cs 75-80: step back, a wall ahead next time
            self._set_target(tiles.step(self.target, self.direction, -1), obs)
        if here != self.target:
            if not (self._ours(obs) and obs.nav.state == "reached"):
                return self._move()
            self.target = here                 # the navigator ended the move as near as it could
        elif self._ours(obs) and obs.nav.state in _MOVING:
            return Action(goal=self.goal, drive="straight", debug=self._debug())   # not idle yet
        self._decide(obs, here)
        if here != self.target:
            self._set_target(self.target, obs)
            return self._move()
        return Action(velocity=(0.0, 0.0), clear_goal=True, debug=self._debug())

    def _ours(self, obs: Observation) -> bool:
        """The navigator's status is about the current move."""
        return self.goal is not None and obs.nav.goal == self.goal

    def _collision_counts(self, obs: Observation) -> bool:
        """MAES counts any contact (75-80); swarm only one that lasts into a move's second tick, so that a
        robot standing, or pulling away, while another touches it does not step back for ever."""
        return self.maes or (self._ours(obs) and obs.nav.state in _MOVING and obs.tick > self.moved_at + 1)

    def _set_target(self, tile: tuple[int, int], obs: Observation) -> None:
        self.target = tile
        self.goal = None
        self.moved_at = obs.tick
        self.watchdog.restart(obs)

    def _move(self) -> Action:
        assert self.target is not None
        self.goal = tiles.tile_goal(self.target)
        return Action(goal=self.goal, drive="straight", debug=self._debug())

    def _decide(self, obs: Observation, here: tuple[int, int]) -> None:
        """One application of the rule at the target tile (WallFollower.cs 109-155)."""
        if self.seeking:                       # 109-127: west (east) to a wall, then face north
            ahead = self._wall(obs, here, self.direction)
            self.direction = (NORTH + self.turn) % 4
            if ahead:
                self.direction = NORTH
                self.seeking = False
            else:
                self._forward()
            return
        ahead = self._wall(obs, here, self.direction) or self.collided
        if self.turned and not ahead:          # 132-137
            self._forward()
        elif not self._wall(obs, here, (self.direction + self.turn) % 4):   # 139-144
            self.direction = (self.direction + self.turn) % 4
            self.turned = True
            self.collided = False
            return
        elif not ahead:                        # 146-151
            self._forward()
        else:                                  # 153-155
            self.direction = (self.direction - self.turn) % 4
        self.turned = False
        self.collided = False

    def _forward(self) -> None:
        assert self.target is not None
        self.target = tiles.step(self.target, self.direction)

    def _wall(self, obs: Observation, here: tuple[int, int], direction: int) -> bool:
        """A wall on the ``direction`` side: the neighbouring tile blocked, or (MAES) a solid cell within
        1.8 m along the ray from the robot."""
        if self.maes:
            return wall_within(obs.known, obs.pose.x, obs.pose.y, direction, MAES_WALL_RANGE_M)
        return tiles.blocked(obs.known, tiles.step(here, direction))

    def _debug(self) -> dict[str, object]:
        return {"direction": "NESW"[self.direction], "seeking": self.seeking, "turned": self.turned,
                "collided": self.collided, "target": list(self.target or ())}


def wall_within(known: np.ndarray, x: float, y: float, direction: int, reach_m: float) -> bool:
    """A SOLID cell, or the map's edge, within ``reach_m`` of (x, y) along the compass ``direction``."""
    dx, dy = tiles.STEP[direction]
    h, w = known.shape
    for i in range(1, int(round(reach_m / RAY_STEP_M)) + 1):
        d = i * RAY_STEP_M
        r, c = math.floor((y + dy * d) / CELL_M), math.floor((x + dx * d) / CELL_M)
        if not (0 <= r < h and 0 <= c < w) or known[r, c] == SOLID:
            return True
    return False
