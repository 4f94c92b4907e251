"""Nearest-frontier exploration (Yamauchi, "A frontier-based approach for autonomous exploration", 1997).

The simplest useful explorer and the runtime's reference algorithm: head for the free cell next to
unseen space that is nearest by path length on the robot's own map; no messages (robots share nothing
unless the run's map-sharing service is on). Targets the navigator reports unreachable or blocked are
excluded for ``exclude_ticks``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from swarm.api import Action, Observation, RobotInfo, cell_centre, cell_of, check_int, grid

from .recovery import unseen_near


TARGET_REACH_CELLS = 3
_STOP = Action(velocity=(0.0, 0.0), clear_goal=True)


@dataclass(frozen=True)
class FrontierParams:
    recheck_ticks: int = 20     # re-choose the target at least this often (the map may offer a nearer one)
    exclude_ticks: int = 300    # how long a target the robot failed to reach stays excluded

    def __post_init__(self) -> None:
        check_int("recheck_ticks", self.recheck_ticks, 1, 100_000)
        check_int("exclude_ticks", self.exclude_ticks, 0, 1_000_000)


class FrontierExplorer:
    name = "frontier"
    Params = FrontierParams

    def reset(self, robot: RobotInfo, params: FrontierParams, rng: np.random.Generator) -> None:
        self.robot = robot
        self.params = params
        self.target: tuple[int, int] | None = None
        self.chosen_at = -1
        self.excluded: dict[tuple[int, int], int] = {}
        self._goal_action: tuple[tuple[int, int] | None, Action] = (None, _STOP)

    def act(self, obs: Observation) -> Action:
        if obs.nav.state in ("unreachable", "blocked") and self.target is not None:
            self.excluded[self.target] = obs.tick + self.params.exclude_ticks
            self.target = None
        if (self.target is None or obs.nav.state == "reached" or obs.tick - self.chosen_at >= self.params.recheck_ticks
                or not self._still_frontier(obs.known)):
            self._choose(obs)
        if self.target is None:
            return _STOP
        if self._goal_action[0] != self.target:  # the same immutable Action while the target stands
            self._goal_action = (self.target, Action(goal=cell_centre(*self.target)))
        return self._goal_action[1]

    def _still_frontier(self, known: np.ndarray) -> bool:
        """Unseen space still within reach of the target (targets sit up to 3 cells from it, see
        :func:`swarm.grid.nearest_reachable_unseen`)."""
        assert self.target is not None
        return unseen_near(known, self.target, TARGET_REACH_CELLS)

    def _choose(self, obs: Observation) -> None:
        self.excluded = {cell: until for cell, until in self.excluded.items() if until > obs.tick}
        exclude = None
        if self.excluded:
            exclude = np.zeros(obs.known.shape, dtype=bool)
            cells = np.array(list(self.excluded))
            exclude[cells[:, 0], cells[:, 1]] = True
        found = grid.nearest_reachable_unseen(obs.known, cell_of(obs.pose.x, obs.pose.y), exclude=exclude)
        self.target = None if found is None else (int(found[0][0]), int(found[0][1]))
        self.chosen_at = obs.tick
