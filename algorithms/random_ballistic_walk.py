"""Random Ballistic Walk (RBW): straight ahead until something is hit, then turn in place by a random angle.

The baseline of the MAES paper (Andreasen, Holler, Jensen, Albano, "Comparison of Online Exploration and
Coverage Algorithms in Continuous Space", ICAART 2022, section 2.2.1, after Kegeleirs et al. 2019: "the
straight movement continues until the agent collides with either an obstacle or another agent"), as MAES
implements it in ``Assets/Scripts/ExplorationAlgorithm/RandomBallisticWalk/RandomExplorationAlgorithm.cs``
(DEIS-Tools/MAES, commit 1bb0312; docs/maes.md section 13.1):

- The first move is straight ahead (``_hasJustRotated`` starts true, line 29, so the idle robot calls
  ``StartMoving()``, lines 51-53): an endless forward ``MovementTask`` that only a collision ends
  (``Robot2DController.cs`` 118-123, 272-276). Here: (``max_speed``, 0) every tick until ``obs.collided``.
- Once idle after a collision it turns in place by ``degrees * direction`` (lines 45-49) and then moves
  straight again (51-53). ``degrees`` is ``Random.Next(50, 180)``, an integer in [50, 179]. A wall or a
  robot counts alike: MAES's collision flag does not say what was touched.
- A move that starts while the robot still touches something is ended again after two physics updates
  (``Robot2DController.cs`` 164-171, "re-declaring" a collision the contact has not left): here the
  ``collided`` of the first tick after a turn is ignored (the contact it reports may be the one the robot
  is turning away from) and a contact on the next tick ends the move.

Departures:

1. The turn's side: MAES draws ``direction`` with ``Random.Next(0, 1)`` (line 46), whose upper bound is
   exclusive, so it is always 0 and every turn is clockwise (``Rotate`` takes counter-clockwise degrees:
   ``FiniteRotationTask.cs`` 72 and ``CoarseGrainedMap.GetTileCenterRelativePosition``'s signed angle).
   The code's evident intent, and a random walk's, is either side with probability 1/2; here it is.
   ``variant = "maes"`` keeps MAES's clockwise-only turns.
2. The angle is uniform in [``turn_min_deg``, ``turn_max_deg``) (default MAES's 50 and 180) as a real
   number; ``variant = "maes"`` draws MAES's whole degrees.
3. The turn is a velocity command towards the drawn heading that slows in proportion to what is left,
   ending within ``TURN_DONE_DEG`` once the robot has stopped turning (MAES's ``FiniteRotationTask`` brakes
   on its own physics model and ends within 0.1 degrees): the algorithm does not know the run's angular
   acceleration.
4. Random numbers come from the robot's own ``rng`` (MAES seeds ``System.Random`` with the robot's seed).

RBW sends nothing; the runtime's map sharing still merges the robots' maps, which RBW does not read.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from swarm.api import OMIT_DEFAULT, Action, InvalidInput, Observation, RobotInfo, check_choice, check_float

VARIANTS = ("swarm", "maes")
TURN_GAIN = 1.5
"""The turn rate commanded per rad of heading error left, in units of ``max_turn_rate``: 3 /s for swarm's
default robot (2 rad/s, 4 rad/s^2: the turns of a run in an open box take 16 ticks on average), 6 /s for
MAES's (4 rad/s, 120 rad/s^2: 7 ticks). The algorithm does not know the run's angular acceleration."""
TURN_DONE_DEG = 1.0
"""The turn ends once the heading is this close to the drawn one."""
MIN_TURN_RATE = 0.05
"""rad/s: the slowest turn commanded, so the last degree does not take seconds."""
STILL_RAD = 1e-4
"""The turn is over once the heading changed less than this (rad) in a tick: the robot has stopped."""


@dataclass(frozen=True)
class RandomBallisticWalkParams:
    # "swarm": turns to either side at random (departure 1); "maes": clockwise only, whole degrees
    variant: str = field(default="swarm", metadata={OMIT_DEFAULT: True})
    turn_min_deg: float = 50.0   # MAES: Random.Next(50, 180), RandomExplorationAlgorithm.cs line 47
    turn_max_deg: float = 180.0  # exclusive

    def __post_init__(self) -> None:
        check_choice("variant", self.variant, VARIANTS)
        check_float("turn_min_deg", self.turn_min_deg, 0.0, 180.0)
        check_float("turn_max_deg", self.turn_max_deg, 0.0, 180.0)
        if self.turn_max_deg <= self.turn_min_deg:
            raise InvalidInput("turn_max_deg", self.turn_max_deg, f"a number > turn_min_deg ({self.turn_min_deg:g})")
        if self.variant == "maes" and math.ceil(self.turn_min_deg) >= self.turn_max_deg:
            raise InvalidInput("turn_max_deg", self.turn_max_deg,
                               "a number with a whole degree in [turn_min_deg, turn_max_deg) for variant 'maes'")


class RandomBallisticWalk:
    """Straight until a collision, then a random turn in place (see the module docstring)."""

    name = "rbw"
    Params = RandomBallisticWalkParams

    def reset(self, robot: RobotInfo, params: RandomBallisticWalkParams, rng: np.random.Generator) -> None:
        self.robot = robot
        self.params = params
        self.rng = rng
        self.maes = params.variant == "maes"
        self.heading: float | None = None   # the heading being turned to; None while moving straight
        self.fresh = False                  # the first tick of a move after a turn: its contact is old
        self.theta: float | None = None     # the heading seen at the previous tick of a turn
        self.turns = 0
        self.last_turn_deg = 0.0

    def act(self, obs: Observation) -> Action:
        if self.heading is not None:
            return self._turn(obs)
        if obs.collided and not self.fresh:
            self.heading = self._draw_heading(obs.pose.theta)
            return self._turn(obs)
        self.fresh = False
        return Action(velocity=(self.robot.max_speed, 0.0), debug=self._debug())

    def _draw_heading(self, theta: float) -> float:
        """The heading after MAES's random turn: ``degrees * direction`` counter-clockwise (lines 46-48)."""
        p = self.params
        if self.maes:
            degrees = float(self.rng.integers(math.ceil(p.turn_min_deg), math.ceil(p.turn_max_deg)))
            side = -1.0                       # Random.Next(0, 1) is always 0: direction -1, clockwise
        else:
            degrees = float(self.rng.uniform(p.turn_min_deg, p.turn_max_deg))
            side = 1.0 if self.rng.random() < 0.5 else -1.0
        self.turns += 1
        self.last_turn_deg = side * degrees
        return _wrap(theta + math.radians(self.last_turn_deg))

    def _turn(self, obs: Observation) -> Action:
        """Turn towards the drawn heading; once there and still (MAES starts the next task only when the
        robot is idle, ``Robot2DController.cs`` 149-162), move straight again."""
        assert self.heading is not None
        err = _wrap(self.heading - obs.pose.theta)
        turning = self.theta is not None and abs(_wrap(obs.pose.theta - self.theta)) > STILL_RAD
        self.theta = obs.pose.theta
        if abs(err) <= math.radians(TURN_DONE_DEG):
            if turning:
                return Action(velocity=(0.0, 0.0), debug=self._debug())
            self.heading = None
            self.theta = None
            self.fresh = True
            return Action(velocity=(self.robot.max_speed, 0.0), debug=self._debug())
        top = self.robot.max_turn_rate
        rate = max(min(top, TURN_GAIN * top * abs(err)), min(MIN_TURN_RATE, abs(err) / self.robot.tick_seconds))
        return Action(velocity=(0.0, math.copysign(rate, err)), debug=self._debug())

    def _debug(self) -> dict[str, float | int | str]:
        return {"state": "move" if self.heading is None else "turn", "turns": self.turns,
                "last_turn_deg": self.last_turn_deg}


def _wrap(angle: float) -> float:
    """``angle`` in (-pi, pi]."""
    return math.pi - (math.pi - angle) % (2.0 * math.pi)
