"""The xBOA paper's exploration experiment (its sections 4-5; docs/boa.md sections 4 and 8.1).

One or more robots on the paper's 24 x 24 grid of 1 m cells, each starting at (x, y) = (1 + i, 1) facing
north, with a 180 degree / 4 m / 1 degree noisy lidar (``gridworld.scan``) and a battery counted in steps
(a 45 degree rotation or a move to one of the 8 neighbours is one step, each followed by a scan). When a
robot has no plan it decides (``decision.decide``: optimiser over goal cells on the shared belief) and
then executes the planned poses one step per tick. If the next cell of its path has become known-occupied
it replans the remaining goals on the current belief (a fresh decision if they are no longer reachable
within its battery). The mission ends when every robot's battery is spent or has no reachable gain, or
when more than 99 % of the 576 cells are known (section 4.3).

Multi-robot (section 5.4.4): robots share one belief in central memory and act round-robin, one step each
per tick (decision 17); "steps" in the results are these ticks. Each robot has its own optimiser and RNG
stream. With ``overlap_penalty`` a robot treats the cells the others' remaining plans will observe as
already known (the paper's future work).

Departures, all deliberate: a move the truth forbids (a wall the noisy belief missed, or a wall cutting a
diagonal) costs its step, fails, and marks the wall cells occupied (a bumper); robots may share a cell
(the paper does not model robot-robot collisions).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from swarm.api import InvalidInput, check_bool, check_float, check_int

from .beams import NORTH, Lidar
from .decision import DecisionParams, decide
from .fitness import Belief, predicted_observed
from .gridworld import L_MAX, known_fraction, scan
from .tree import StateTree


@dataclass(frozen=True)
class PaperSetup:
    """The experiment's fixed conditions (xBOA paper section 5.2; battery 300 as in docs/boa.md section 8.1)."""

    battery: int = 300
    n_robots: int = 1
    start_x: int = 1
    start_y: int = 1
    heading: int = NORTH
    fov_deg: float = 180.0
    range_m: float = 4.0
    resolution_deg: float = 1.0
    noise: float = 0.05
    stop_explored: float = 0.99
    overlap_penalty: bool = False
    max_ticks: int = 100_000

    def __post_init__(self) -> None:
        check_int("battery", self.battery, 0, 10_000_000)
        check_int("n_robots", self.n_robots, 1, 64)
        check_int("start_x", self.start_x, 0)
        check_int("start_y", self.start_y, 0)
        check_int("heading", self.heading, 0, 7)
        check_float("stop_explored", self.stop_explored, 0.0, 1.0)
        check_bool("overlap_penalty", self.overlap_penalty)
        check_int("max_ticks", self.max_ticks, 1)
        self.lidar()

    def lidar(self) -> Lidar:
        return Lidar(self.fov_deg, self.range_m, self.resolution_deg, self.noise)


@dataclass(frozen=True)
class DecisionRecord:
    robot: int
    tick: int
    goals: tuple[tuple[int, int], ...]      # (row, col); empty when no plan was found
    fitness: float
    nfev: int
    n_distinct: int
    attempts: int
    time_ms: float                          # wall time (not part of the deterministic result)


@dataclass
class MissionResult:
    explored: np.ndarray                    # known fraction after tick t (index 0: after the initial scans)
    ticks: int
    stop_reason: str                        # "explored" | "battery" | "no_gain" | "max_ticks"
    decisions: list[DecisionRecord] = field(default_factory=list)
    goal_log: list[tuple[tuple[int, int] | None, ...]] = field(default_factory=list)   # per tick, per robot
    steps_used: list[int] = field(default_factory=list)
    belief: np.ndarray | None = None

    def rate_at(self, step: int) -> float:
        """Explored fraction after ``step`` ticks (the final value if the mission ended before)."""
        return float(self.explored[min(step, len(self.explored) - 1)])


@dataclass
class _Robot:
    ident: int
    row: int
    col: int
    heading: int
    battery: int
    rng: np.random.Generator
    poses: list[tuple[int, int, int]] = field(default_factory=list)
    goals: list[tuple[int, int]] = field(default_factory=list)
    done: bool = False


def _route(belief: Belief, rob: _Robot, goals: list[tuple[int, int]]) -> list[tuple[int, int, int]] | None:
    """Minimum-energy poses visiting ``goals`` in order from the robot's pose, or None if over battery."""
    W = belief.shape[1]
    poses: list[tuple[int, int, int]] = []
    cell, heading, energy = (rob.row, rob.col), rob.heading, 0
    for g in goals:
        tree = StateTree.build(belief.blocked, cell, heading, rob.battery - energy)
        st = int(tree.cell_state[g[0] * W + g[1]])
        if st < 0:
            return None
        leg = tree.path(st)[1:]
        energy += len(leg)
        poses.extend(leg)
        if leg:
            cell, heading = leg[-1][:2], leg[-1][2]
    return poses


def _claimed(belief: Belief, robots: list[_Robot], me: int, lidar: Lidar) -> np.ndarray:
    """Cells the other robots' remaining plans are predicted to observe (overlap penalty)."""
    poses = [p for r in robots if r.ident != me and not r.done for p in r.poses]
    return predicted_observed(belief, poses, lidar)


def run_mission(truth: np.ndarray, setup: PaperSetup, params: DecisionParams, seed: int) -> MissionResult:
    """One mission on a truth grid (bool, True = wall, row index = y). Deterministic given ``seed`` (apart
    from the ``time_ms`` fields)."""
    truth = np.asarray(truth, dtype=bool)
    H, W = truth.shape
    lidar = setup.lidar()
    tables = lidar.tables(1.0)
    ss = np.random.SeedSequence(seed)
    world_ss, *robot_ss = ss.spawn(1 + setup.n_robots)
    world_rng = np.random.default_rng(world_ss)
    robots = []
    for i in range(setup.n_robots):
        row, col = setup.start_y, setup.start_x + i
        if not (0 <= row < H and 0 <= col < W) or truth[row, col]:
            raise InvalidInput("start", (col, row), "a free cell of the map for every robot")
        robots.append(_Robot(i, row, col, setup.heading, setup.battery, np.random.default_rng(robot_ss[i])))
    logodds = np.zeros((H, W))
    for r in robots:
        scan(truth, logodds, r.row, r.col, r.heading, tables, world_rng, lidar.noise)
    explored = [known_fraction(logodds)]
    decisions: list[DecisionRecord] = []
    goal_log: list[tuple[tuple[int, int] | None, ...]] = []
    stop = "max_ticks"
    for tick in range(1, setup.max_ticks + 1):
        for rob in robots:
            if rob.done:
                continue
            if rob.battery <= 0:
                rob.done = True
                continue
            belief = Belief.from_logodds(logodds, 1.0)
            if not rob.poses:
                _decide(rob, belief, robots, setup, params, lidar, tick, decisions)
                if rob.done:
                    continue
            _step(rob, truth, logodds, belief, tables, world_rng, lidar, robots, setup, params, tick, decisions)
        goal_log.append(tuple(r.goals[0] if r.goals and not r.done else None for r in robots))
        explored.append(known_fraction(logodds))
        if explored[-1] > setup.stop_explored:
            stop = "explored"
            break
        if all(r.done or r.battery <= 0 for r in robots):
            stop = "battery" if all(r.battery <= 0 for r in robots) else "no_gain"
            break
    return MissionResult(np.asarray(explored), len(explored) - 1, stop, decisions, goal_log,
                         [setup.battery - r.battery for r in robots], logodds)


def _decide(rob: _Robot, belief: Belief, robots: list[_Robot], setup: PaperSetup, params: DecisionParams,
            lidar: Lidar, tick: int, decisions: list[DecisionRecord]) -> None:
    claimed = _claimed(belief, robots, rob.ident, lidar) if setup.overlap_penalty and len(robots) > 1 else None
    t0 = time.perf_counter()
    d = decide(belief, (rob.row, rob.col), rob.heading, rob.battery, params, rob.rng, lidar=lidar, claimed=claimed)
    ms = (time.perf_counter() - t0) * 1000.0
    goals = d.plan.goals if d.plan is not None else ()
    decisions.append(DecisionRecord(rob.ident, tick, goals, d.fitness, d.nfev, d.n_distinct, d.attempts, ms))
    if d.plan is None or not d.plan.poses:
        rob.done = True
        return
    rob.goals = list(goals)
    rob.poses = list(d.plan.poses)
    _trim_goals(rob)


def _step(rob: _Robot, truth: np.ndarray, logodds: np.ndarray, belief: Belief, tables, world_rng, lidar: Lidar,
          robots: list[_Robot], setup: PaperSetup, params: DecisionParams, tick: int,
          decisions: list[DecisionRecord]) -> None:
    """One step (rotation or move, then a scan) of one robot, replanning first if its path is blocked."""
    if _path_blocked(belief.blocked, rob):
        poses = _route(belief, rob, rob.goals) if rob.goals else None
        if poses:
            rob.poses = poses
        else:
            rob.poses, rob.goals = [], []
            _decide(rob, belief, robots, setup, params, lidar, tick, decisions)
            if rob.done:
                return
    nxt = rob.poses[0]
    rob.battery -= 1
    if (nxt[0], nxt[1]) == (rob.row, rob.col):
        rob.heading = nxt[2]
    else:
        walls = _truth_walls(truth, rob, nxt)
        if walls:
            for (r, c) in walls:
                logodds[r, c] = L_MAX
            rob.poses, rob.goals = [], []          # decide again from here at the next tick
            return
        rob.row, rob.col, rob.heading = nxt
    rob.poses.pop(0)
    _trim_goals(rob)
    scan(truth, logodds, rob.row, rob.col, rob.heading, tables, world_rng, lidar.noise)


def _trim_goals(rob: _Robot) -> None:
    """Drop reached goals. A leg's path enters its goal cell only at its end (the goal's tree state is the
    first state of that cell the search reaches), so "standing on the next goal" means "leg finished"."""
    while rob.goals and (rob.row, rob.col) == rob.goals[0]:
        rob.goals.pop(0)
    if not rob.poses:
        rob.goals = []


def _path_blocked(blocked: np.ndarray, rob: _Robot) -> bool:
    """Whether a move anywhere on the remaining path now enters (or cuts the corner of) a known obstacle."""
    r0, c0 = rob.row, rob.col
    for (r, c, _) in rob.poses:
        if (r, c) != (r0, c0):
            if blocked[r, c] or (r != r0 and c != c0 and (blocked[r, c0] or blocked[r0, c])):
                return True
            r0, c0 = r, c
    return False


def _truth_walls(truth: np.ndarray, rob: _Robot, nxt: tuple[int, int, int]) -> list[tuple[int, int]]:
    r, c = nxt[0], nxt[1]
    cells = [(r, c)]
    if r != rob.row and c != rob.col:
        cells += [(r, rob.col), (rob.row, c)]
    return [cell for cell in cells if truth[cell]]


__all__ = ["DecisionRecord", "MissionResult", "PaperSetup", "run_mission"]
