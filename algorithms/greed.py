"""Greed: always head for the nearest reachable unexplored cell.

Follows the Minotaur paper (Schmidt et al., docs/papers.md), section 3.5: Minotaur's
fallback "move to the nearest unexplored tile anywhere on the map", extracted into an algorithm of its
own that "always moves to the nearest unexplored tile, and still communicates and shares its map with
other robots"; and MAES's ``Greed.cs`` (docs/maes.md section 7.4) for the behaviour the paper leaves
open: re-targeting, collisions and deadlocks.

**Target.** The configuration-space cell nearest the robot **by path length on its own knowledge map**
from which an unseen cell is in view (:func:`swarm.grid.nearest_reachable_unseen`): a frontier behind a
wall is as far as the way around the wall, never as near as the straight line. It is chosen again when

- there is none yet, or the navigator reports it ``reached``;
- it is *seen*: no unseen cell is left within view reach of it (its own lidar or a merged map did it;
  not with ``variant = "maes"``, which drives on until within 0.5 m, below);
- the navigator reports it ``unreachable`` or ``blocked`` -- it is then excluded (below);
- **deadlock**: the robot stayed within ``progress_m`` of one spot for ``deadlock_ticks`` while heading
  for it (MAES: the same coarse tile at 5 position checks 10 ticks apart) -- it is then excluded;
- after a **collision** (MAES clears its waypoint): the robot first backs off (``backoff_ticks`` at
  ``backoff_speed``, only if its map shows free space behind it and no sensed robot is there).

An excluded target is a disc of ``exclude_radius_m`` around it that no target or frontier may use for
``exclude_ticks``. With nothing left to explore (or everything excluded) the robot stops and looks again
every ``idle_recheck_ticks``: shared maps and expiring exclusions can open new targets.

**Map sharing.** Greed sends no messages of its own: the runtime's map-sharing service (``comm``
section of the run spec) broadcasts each robot's map changes every ``share_every`` ticks over the radio
and merges what a robot receives into its own map before it decides. That replaces MAES's heartbeat
merge (docs/maes.md section 2 item 4), which merges only when two heartbeats arrive in the same tick
and then merges the two *senders'* maps with each other, not with the receiver's: two MAES Greed robots
never share anything. Here every received update reaches the receiver's map.

**Departures** (from the paper, which specifies only the target rule, and from MAES):

1. Nearest is measured on the robot's configuration space (its radius plus the navigator's margin),
   not by MAES's flood fill through every non-solid coarse tile, which may pass through gaps the robot
   cannot fit and through unseen space it then cannot plan through (MAES plans pessimistically).
2. The target is re-chosen as soon as it is seen; MAES keeps driving to a waypoint until within 0.5 m of
   it, even when a merged map or its own lidar has already revealed everything there.
3. Exclusions are discs that last ``exclude_ticks``; MAES excludes the one failed cell for the single
   re-targeting call after a deadlock, so the next choice is often the cell next to it.
4. Deadlock is "no displacement beyond ``progress_m``", not "same coarse tile", so a robot oscillating
   across a tile boundary is caught too. Collisions back off a fixed short time at a safe speed instead of
   MAES's 1 m reverse, and only into known free space.
5. ``recheck_ticks`` (default 0 = off, as MAES) optionally re-chooses the nearest target periodically
   while travelling.
6. Map sharing is the runtime's service (above), fixing MAES's heartbeat-merge bug.

**``variant = "maes"``** puts back MAES's target persistence and first move (issue 49 rows 4 and 5; line
numbers are ``Assets/Scripts/ExplorationAlgorithm/Greed/Greed.cs`` in DEIS-Tools/MAES, commit 1bb0312):

- *Drive on until within 0.5 m* (departure 2 undone). MAES keeps its waypoint while it is not reached:
  ``PathAndMoveTo`` every tick (157), cleared only when ``IsDestinationReached`` (159-162), the tile centre
  closer than 0.5 m (237), after a collision (121-136), on a deadlock (138-147) or when there is no path to
  it (152-156). Seeing the target does not end it. Here the target is kept until the robot is within
  ``MAES_REACHED_M`` of it or the navigator reports it reached; unreachable, blocked, deadlock and collision
  still re-choose as above. A target that is still the nearest once reached is given up (excluded), as in
  the default variant; MAES would choose it again on every tick.
- *First move straight ahead until a collision.* In state Idle MAES calls ``StartMoving()`` (181-183), an
  endless ``MovementTask`` at full speed (``Robot2DController.cs`` 272-276) that only a collision ends
  (``NotifyCollided`` stops the task, 118-123; re-declared while pushing on, 164-171); ExploreRoom chooses
  only once the robot is idle (186-190). Here the robot commands (``max_speed``, 0) until its first
  ``collided`` observation, then backs off and chooses as usual. With ``robots.heading = "maes"`` it
  starts facing +y as in MAES (``swarm/world/spawn.py``).

Not reproduced (issue 49 row 3, MAES's motion): ``PathAndMoveTo`` moves one 1 m coarse tile at a time,
turning in place (> 1.5 degrees off) and stopping after each step (``Robot2DController.cs`` 359-397); here
the runtime's navigator drives the path continuously. The other departures (1, 3-6) stay.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from swarm.api import OMIT_DEFAULT, Action, Observation, RobotInfo, cell_centre, cell_of, check_choice, check_int, grid
from swarm.api.grid import DEFAULT_MARGIN_M, default_view_reach_cells

from .recovery import Backoff, Exclusions, Watchdog, check_recovery_params, gave_up, unseen_near


VARIANTS = ("swarm", "maes")
MAES_REACHED_M = 0.5
"""MAES's waypoint is reached when its tile centre is nearer than this (``Greed.cs`` 237)."""


@dataclass(frozen=True)
class GreedParams:
    # "swarm" (the module docstring's departures) | "maes" (MAES's target persistence and straight first
    # move); left out of the canonical spec at its default, so Greed runs specified before it keep their keys
    variant: str = field(default="swarm", metadata={OMIT_DEFAULT: True})
    deadlock_ticks: int = 50         # MAES: 5 position checks, 10 ticks apart; 0 disables
    progress_m: float = 0.5          # moving less than this during deadlock_ticks is no progress
    exclude_ticks: int = 300         # how long a given-up target stays excluded
    exclude_radius_m: float = 1.0    # the excluded disc around it
    backoff_ticks: int = 15          # reverse this long after a collision; 0 disables
    backoff_speed: float = 0.3       # m/s
    recheck_ticks: int = 0           # also re-choose every N ticks while travelling; 0 = only on events
    idle_recheck_ticks: int = 20     # with no target, look again this often

    def __post_init__(self) -> None:
        check_choice("variant", self.variant, VARIANTS)
        check_recovery_params(self)
        check_int("recheck_ticks", self.recheck_ticks, 0, 1_000_000)
        check_int("idle_recheck_ticks", self.idle_recheck_ticks, 1, 1_000_000)


class Greed:
    """The nearest-unexplored-cell explorer of the Minotaur paper, section 3.5 (see the module docstring)."""

    name = "greed"
    Params = GreedParams

    def reset(self, robot: RobotInfo, params: GreedParams, rng: np.random.Generator) -> None:
        self.robot = robot
        self.params = params
        self.reach = default_view_reach_cells(robot.radius, DEFAULT_MARGIN_M)
        self.target: tuple[int, int] | None = None
        self.goal: tuple[float, float] | None = None
        self.chosen_at = -1
        self.next_look = 0
        self.rechoose = False
        self.backoff = Backoff(params.backoff_ticks, params.backoff_speed)
        self.watchdog = Watchdog(params.deadlock_ticks, params.progress_m)
        self.exclusions = Exclusions(params.exclude_radius_m, params.exclude_ticks)
        self.maes = params.variant == "maes"
        self.straight = self.maes   # MAES's first move: straight ahead until a collision (Greed.cs 181-183)

    # ------------------------------------------------------------------------------------------ act ----
    def act(self, obs: Observation) -> Action:
        if self.straight:
            if not obs.collided:
                return Action(velocity=(self.robot.max_speed, 0.0))
            self.straight = False   # the collision ends MAES's MovementTask (Robot2DController.cs 118-123)
            self.watchdog.restart(obs)
        if self.backoff.active(obs.tick) or self.backoff.start_if_collided(obs):
            self.rechoose = True  # MAES clears its waypoint on a collision; choose afresh once backed off
            return Action(velocity=self.backoff.command())
        if self._must_choose(obs):
            self._choose(obs)
        if self.target is None:
            self.goal = None
            return Action(velocity=(0.0, 0.0), clear_goal=True)
        return Action(goal=self.goal)

    def _must_choose(self, obs: Observation) -> bool:
        if self.target is None:
            return obs.tick >= self.next_look
        nav = obs.nav if obs.nav.goal == self.goal else None  # a status about an older goal says nothing
        if gave_up(obs, nav, self.target, self.exclusions, self.watchdog):
            return True
        if self.rechoose:
            return True
        if nav is not None and nav.state == "reached":
            return True
        if self.maes:   # MAES drives on until within 0.5 m, seen or not (Greed.cs 159-162, 237)
            if self._within_maes_reach(obs):
                return True
        elif not unseen_near(obs.known, self.target, self.reach + 1):
            return True
        return self.params.recheck_ticks > 0 and obs.tick - self.chosen_at >= self.params.recheck_ticks

    def _choose(self, obs: Observation) -> None:
        self.rechoose = False
        previous = self.target
        here = _clip(cell_of(obs.pose.x, obs.pose.y), obs.known.shape)
        found = self._nearest(obs, here)
        reached = obs.nav.state == "reached" and obs.nav.goal == self.goal
        if found is not None and found == previous and (reached or (self.maes and self._within_maes_reach(obs))):
            # Standing on the target and it still has unseen cells in view reach that the lidar cannot
            # see (e.g. behind a corner): give it up, or the robot would choose it forever.
            self.exclusions.add(found, obs.tick)
            found = self._nearest(obs, here)
        self.chosen_at = obs.tick
        self.target = found
        if found is None:
            self.goal = None
            self.next_look = obs.tick + self.params.idle_recheck_ticks
            return
        self.goal = cell_centre(*found)
        if found != previous:
            self.watchdog.restart(obs)

    def _within_maes_reach(self, obs: Observation) -> bool:
        """MAES's ``IsDestinationReached``: the target's centre nearer than 0.5 m (``Greed.cs`` 235-238)."""
        return self.goal is not None and math.dist((obs.pose.x, obs.pose.y), self.goal) < MAES_REACHED_M

    def _nearest(self, obs: Observation, here: tuple[int, int]) -> tuple[int, int] | None:
        exclude = self.exclusions.mask(obs.known.shape, obs.tick)
        found = grid.nearest_reachable_unseen(obs.known, here, radius_m=self.robot.radius, exclude=exclude)
        return None if found is None else (int(found[0][0]), int(found[0][1]))


def _clip(cell: tuple[int, int], shape: tuple[int, ...]) -> tuple[int, int]:
    return min(max(cell[0], 0), shape[0] - 1), min(max(cell[1], 0), shape[1] - 1)
