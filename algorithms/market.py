"""Market-based (cost-utility) frontier assignment: Burgard, Moors, Stachniss and Schneider,
"Coordinated multi-robot exploration", IEEE Transactions on Robotics 21(3), 2005 (docs/baselines.md).

What the paper does, and what this module follows (section numbers of the T-RO article, as recalled: the
article's text was not at hand when this was written, so check them against it):

- **Targets (section III).** Every frontier cell -- a known-free cell next to unexplored space -- is a
  candidate target point. Here the candidates are the drivable cells (configuration space) from which a
  frontier cell is within view reach (:func:`swarm.grid.view_cells`, the targets every frontier explorer
  of this project uses), so that every candidate can be driven to.
- **Cost (section III-A).** ``V^i_t``: the cost for robot ``i`` to reach ``t``, a shortest-path distance
  from the robot's position over the grid. Here the geodesic distance on the robot's configuration space
  (:func:`swarm.grid.field_at`, one bounded search per team member), in metres.
- **Utility (section III-B).** Every target starts with utility ``U_t = 1``; once a target ``t`` is
  assigned, the utility of every target ``t'`` is reduced by ``P(||t - t'||)``, the probability that
  ``t'`` is visible from ``t``. The paper estimates ``P`` from data and reports it falling roughly
  linearly to zero at the sensor's range; here ``P(d) = max(0, 1 - d / utility_range_m)`` (Euclidean
  ``d``; ``utility_range_m = 0``, the default, means the robot's lidar range).
- **Assignment (section III-C, the target point selection algorithm).** Repeat until every robot has a
  target: choose the robot-target pair ``(i, t)`` maximising ``U_t - beta * V^i_t`` among robots without
  a target, assign it, and reduce the utilities as above. Ties go to the lower robot id, then the
  candidate first in row-major order.
- **Limited communication (section IV).** The paper coordinates each sub-team of robots that can talk to
  each other. Here every robot broadcasts a ``market.pose`` message (its position) every
  ``announce_ticks``; a robot's team is itself plus every robot heard from within ``stale_ticks``. Each
  robot runs the whole assignment for its team on its own map (the runtime shares maps over the radio) and
  takes its own row of the result: *a robot decides for the robots it hears*. Robots that hear each other
  and hold the same map compute the same assignment; where maps or positions differ slightly they may
  disagree for a while. **Without connectivity** the team is the robot alone, the assignment reduces to
  ``argmax 1 - beta * V_t``, the nearest target (Yamauchi's nearest frontier), and robots out of range may
  head for the same frontier.

**Re-assignment.** The paper re-plans whenever a robot needs a new target. Here a robot re-runs the
assignment when it has no target, its target is reached, seen (no unseen cell left within view reach of
it), unreachable or blocked (then excluded for ``exclude_ticks``, a disc of ``exclude_radius_m``), when it
made no progress for ``deadlock_ticks``, and every ``recheck_ticks``.

**Departures**

1. Targets are drivable cells within view reach of a frontier (above), not the frontier cells themselves,
   which often lie inside the robot's inflated clearance from a wall.
2. Costs are geodesic path lengths on the configuration space of the robot's own (shared) map, not value
   iteration over occupancy probabilities; ``beta`` is per metre (the paper's ``beta`` weighs a cost in
   grid-cost units).
3. ``P(d)`` is the linear fall-off to the sensor range (above), not the paper's measured visibility table,
   and it ignores walls between the two targets.
4. Coordination is decentralised and asynchronous: each robot computes the team's assignment itself from
   positions heard over the radio one tick late, instead of one central assigner per sub-team; teammates'
   assignments are not sent, only positions.
5. Re-assignment triggers, target exclusions and the no-progress watchdog (above) are this project's, as
   in Greed; the paper leaves them open.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from swarm.api import CELL_M, Action, Observation, RobotInfo, cell_centre, cell_of, check_float, check_int, grid
from swarm.api.grid import DEFAULT_MARGIN_M, default_view_reach_cells
from swarm.api.messages import message, require_finite

from .recovery import Exclusions, Watchdog, gave_up, unseen_near

_STOP = Action(velocity=(0.0, 0.0), clear_goal=True)
SNAP_CELLS = 4   # a robot standing inside inflated space is costed from the drivable cell nearest it


@message("market.pose")
@dataclass(frozen=True)
class MarketPose:
    """"I am at (x, y)" (metres): what a teammate needs to cost targets for this robot."""

    sender: int
    x: float
    y: float

    def validate(self) -> None:
        require_finite("market.pose", x=self.x, y=self.y)


@dataclass(frozen=True)
class MarketParams:
    beta: float = 0.05              # cost weight per metre: utility 1 is worth 1 / beta metres of travel
    utility_range_m: float = 0.0    # P(d) falls linearly to 0 at this distance; 0 = the lidar range
    announce_ticks: int = 5         # broadcast the robot's position this often
    stale_ticks: int = 20           # a teammate not heard from for longer leaves the team
    recheck_ticks: int = 25         # re-run the assignment at least this often
    exclude_ticks: int = 300        # a target given up on stays excluded this long
    exclude_radius_m: float = 1.0   # the excluded disc around it
    deadlock_ticks: int = 50        # no progress beyond progress_m for this long gives a target up; 0 = off
    progress_m: float = 0.5

    def __post_init__(self) -> None:
        check_float("beta", self.beta, 0.0, 100.0)
        check_float("utility_range_m", self.utility_range_m, 0.0, 1000.0)
        check_int("announce_ticks", self.announce_ticks, 1, 100_000)
        check_int("stale_ticks", self.stale_ticks, 1, 1_000_000)
        check_int("recheck_ticks", self.recheck_ticks, 1, 1_000_000)
        check_int("exclude_ticks", self.exclude_ticks, 0, 1_000_000)
        check_float("exclude_radius_m", self.exclude_radius_m, 0.0, 100.0)
        check_int("deadlock_ticks", self.deadlock_ticks, 0, 1_000_000)
        check_float("progress_m", self.progress_m, 0.0, 100.0, lo_open=True)


def visibility(d: np.ndarray, range_m: float) -> np.ndarray:
    """``P(d)``: the utility a target loses when a target ``d`` metres away is assigned (section III-B)."""
    return np.clip(1.0 - d / range_m, 0.0, 1.0)


def assign(costs: np.ndarray, targets_xy: np.ndarray, beta: float, range_m: float) -> list[int]:
    """The paper's target point selection (section III-C): ``costs`` float[R, N] (metres, ``inf`` where
    robot ``i`` cannot reach target ``t``), ``targets_xy`` float[N, 2] metres. Returns, per robot, the index
    of its target, or -1 when it can reach none. Greedy: the pair with the largest ``U_t - beta * V^i_t``
    first, then the utilities near the assigned target are reduced by ``P``."""
    n_robots, n = costs.shape
    out = [-1] * n_robots
    if n == 0:
        return out
    utility = np.ones(n)
    score = np.full((n_robots, n), -np.inf)
    finite = np.isfinite(costs)
    free = list(range(n_robots))
    while free:
        score[free] = np.where(finite[free], utility[None, :] - beta * np.where(finite[free], costs[free], 0.0),
                               -np.inf)
        flat = int(np.argmax(score))
        i, t = divmod(flat, n)
        if not np.isfinite(score[i, t]):
            break
        out[i] = t
        free.remove(i)
        score[i] = -np.inf
        utility -= visibility(np.hypot(*(targets_xy - targets_xy[t]).T), range_m)
    return out


class Market:
    """Cost-utility frontier assignment of Burgard et al. 2005 (see the module docstring)."""

    name = "market"
    Params = MarketParams

    def reset(self, robot: RobotInfo, params: MarketParams, rng: np.random.Generator) -> None:
        self.robot = robot
        self.params = params
        self.range_m = params.utility_range_m or robot.lidar_range
        self.reach = default_view_reach_cells(robot.radius, DEFAULT_MARGIN_M)
        self.heard: dict[int, tuple[float, float, int]] = {}   # robot id -> (x, y, tick heard)
        self.target: tuple[int, int] | None = None
        self.goal: tuple[float, float] | None = None
        self.chosen_at = -1
        self.team_size = 1
        self.exclusions = Exclusions(params.exclude_radius_m, params.exclude_ticks)
        self.watchdog = Watchdog(params.deadlock_ticks, params.progress_m)

    def act(self, obs: Observation) -> Action:
        for msg in obs.inbox:
            if isinstance(msg, MarketPose) and msg.sender != self.robot.id:
                self.heard[msg.sender] = (float(msg.x), float(msg.y), obs.tick)
        if self._must_choose(obs):
            self._choose(obs)
        messages = ()
        if obs.tick % self.params.announce_ticks == 0:
            messages = (MarketPose(sender=self.robot.id, x=float(obs.pose.x), y=float(obs.pose.y)),)
        debug = {"team": self.team_size}
        if self.goal is None:
            return Action(velocity=(0.0, 0.0), clear_goal=True, messages=messages, debug=debug)
        return Action(goal=self.goal, messages=messages, debug=debug)

    # ------------------------------------------------------------------------------------- choosing ----
    def _must_choose(self, obs: Observation) -> bool:
        if self.target is None:
            return True
        nav = obs.nav if obs.nav.goal == self.goal else None
        if gave_up(obs, nav, self.target, self.exclusions, self.watchdog):
            return True
        if nav is not None and nav.state == "reached":   # seen what it can from there (a corner may hide
            self.exclusions.add(self.target, obs.tick)    # the rest): do not choose it again at once
            return True
        if not unseen_near(obs.known, self.target, self.reach + 1):
            return True
        return obs.tick - self.chosen_at >= self.params.recheck_ticks

    def team(self, obs: Observation) -> list[tuple[int, float, float]]:
        """(id, x, y) of this robot and every teammate heard within ``stale_ticks``, by id."""
        fresh = [(rid, x, y) for rid, (x, y, t) in self.heard.items() if obs.tick - t <= self.params.stale_ticks]
        return sorted(fresh + [(self.robot.id, float(obs.pose.x), float(obs.pose.y))])

    def _choose(self, obs: Observation) -> None:
        previous = self.target
        self.chosen_at = obs.tick
        self.target, self.goal = None, None
        known = obs.known
        space = grid.configuration_space(known, self.robot.radius)
        exclude = self.exclusions.mask(known.shape, obs.tick)
        candidates = np.argwhere(grid.view_cells(known, self.reach, exclude) & space)
        team = self.team(obs)
        self.team_size = len(team)
        if candidates.shape[0] == 0:
            return
        costs = np.full((len(team), candidates.shape[0]), np.inf)
        me = -1
        for k, (rid, x, y) in enumerate(team):
            if rid == self.robot.id:
                me = k
            start = grid.nearest_in(space, _clip(cell_of(x, y), known.shape), SNAP_CELLS)
            if start is not None:
                costs[k] = grid.field_at(space, start, candidates)
        xy = (candidates[:, ::-1] + 0.5) * CELL_M
        mine = assign(costs, xy, self.params.beta, self.range_m)[me]
        if mine < 0:
            return
        self.target = (int(candidates[mine, 0]), int(candidates[mine, 1]))
        self.goal = cell_centre(*self.target)
        if self.target != previous:
            self.watchdog.restart(obs)


def _clip(cell: tuple[int, int], shape: tuple[int, ...]) -> tuple[int, int]:
    return min(max(cell[0], 0), shape[0] - 1), min(max(cell[1], 0), shape[1] - 1)
