"""MMPF, multi-robot potential fields: the baseline of SMMR-Explore (Yu et al., "SMMR-Explore: SubMap-based
Multi-Robot Exploration System with Multi-robot Multi-target Potential Field Exploration Method", ICRA
2021) and Explore-Bench (Xu et al., ICRA 2022), written from Explore-Bench's own implementation,
``exploration_benchmark/src/mmpf_node.cpp`` (github.com/efc-robot/Explore-Bench; line numbers below are
that file's). docs/baselines.md summarises it.

Each re-plan (Explore-Bench: once a second, ``rate`` 1 Hz, 159; here every ``replan_ticks``):

1. **Frontier targets and clusters** (284-329, 438-483). Explore-Bench takes the unknown cells that touch
   free space, drops those inside the costmap's inflation (331-357), and clusters them greedily (Manhattan
   distance < 3); a cluster's centre is its member nearest the mean and its *information gain* is its size.
   Here the clusters are :func:`swarm.grid.frontier_clusters` (8-connected frontier cells), a cluster's
   *target* is the set of drivable cells within view reach of it (clusters without one are dropped, as
   347-357 drop targets near obstacles), its gain its size.
2. **Distance maps** (``dismapConstruction_start_target``, 83-131, called 503-506): a BFS distance from each
   cluster centre over the free cells. Here :func:`swarm.grid.distance_field` from the cluster's target
   cells on the configuration space, in cells.
3. **Potential of a cell** (563-609): attraction ``-sum_j K_ATTRACT * gain_j / d_j`` over the clusters
   reached (``d_j >= 1``, 566-573; ``K_ATTRACT = 1``, 42), plus ``5 * river`` for each time the cell is on
   the path descended so far (586-590), plus, for every other robot within ``ROBOT_INTERFERE_RADIUS``
   Manhattan cells (50 cells of 0.05 m, 41 and 47), ``ROBOT_INTERFERE_RADIUS - distance`` (593-605). The
   repulsion is in Explore-Bench's 5 cm cells; here ``repulsion_per_m * (repulsion_radius_m - d)``, whose
   defaults (20 per metre, 2.5 m) are those numbers in metres. The attraction is resolution-free as it is
   (a cluster's cells and its distances scale alike).
4. **Descent** (535-659): from the robot's cell, step to the 4-neighbour of least potential (order +x, -y,
   -x, +y: 551-557, the first on ties) while that is below the current potential, else raise ``river`` by
   one (616-623); stop when the path's end is within one cell of a cluster's target (``minDis2Frontier``,
   635-644) or after 3000 steps (539). The path's end is the goal (660-661, 690-693).

Other robots' positions: Explore-Bench reads them from tf for every robot whose map is merged (509-532).
Here every robot broadcasts an ``mmpf.pose`` message every ``announce_ticks``; the robots heard within
``stale_ticks`` repel. **Without connectivity** nothing repels: each robot descends the attraction alone
and robots out of range may head for the same frontier (as Explore-Bench's robots without a merged map).

**Departures**

1. Frontier cells are the free side of the border (:func:`swarm.grid.frontier_mask`) and clusters are
   8-connected components, not Explore-Bench's unknown-side cells clustered at Manhattan distance < 3.
2. Distances are 8-connected path lengths on the configuration space (the navigator's), not a 4-connected
   BFS through every free cell; cells off the configuration space have infinite potential (Explore-Bench
   leaves them at zero attraction, which a descent among negative potentials avoids anyway).
3. A descent that cannot improve stops at once (Explore-Bench keeps raising ``river`` until step 3000,
   which changes nothing: only cells on the path get dearer). A descent that ends where it started (a local
   minimum at the robot) sends the robot to the nearest target cell of the most attractive cluster
   (largest ``gain / d``) instead of standing still.
6. A cluster's distance is measured to the nearest drivable cell within view reach of it (the targets of
   every frontier explorer here), not to one centre cell: a single centre cell snapped off a wall may lie
   in the next room.
4. No initial rotation goal (663-686): the lidar already sees all round. Explore-Bench stops a robot after
   four re-plans without targets (360-404); here it stops and looks again every re-plan.
5. Goals the navigator reports reached, unreachable or blocked are excluded for ``exclude_ticks`` (a disc of
   ``exclude_radius_m``) and the robot re-plans at once; Explore-Bench relies on move_base.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from swarm.api import CELL_M, Action, Observation, RobotInfo, cell_centre, cell_of, check_float, check_int, grid
from swarm.api.grid import DEFAULT_MARGIN_M, default_view_reach_cells
from swarm.api.messages import message, require_finite

from .recovery import Exclusions

NEIGHBOURS = ((0, 1), (-1, 0), (0, -1), (1, 0))   # mmpf_node.cpp 551-557: +x, -y, -x, +y (row = y)
START_POTENTIAL = 10000.0                          # 536
PATH_PENALTY = 5.0                                 # 588


@message("mmpf.pose")
@dataclass(frozen=True)
class MMPFPose:
    """"I am at (x, y)" (metres): the position the other robots' repulsion needs."""

    sender: int
    x: float
    y: float

    def validate(self) -> None:
        require_finite("mmpf.pose", x=self.x, y=self.y)


@dataclass(frozen=True)
class MMPFParams:
    k_attract: float = 1.0             # K_ATTRACT (mmpf_node.cpp 42)
    repulsion_radius_m: float = 2.5    # ROBOT_INTERFERE_RADIUS, 50 cells of 0.05 m (41, 47)
    repulsion_per_m: float = 20.0      # one unit per 5 cm cell inside the radius (598-599)
    max_steps: int = 3000              # descent steps (539)
    replan_ticks: int = 10             # Explore-Bench re-plans at 1 Hz (159): 10 ticks of 0.1 s
    announce_ticks: int = 5            # broadcast the robot's position this often
    stale_ticks: int = 20              # a robot not heard from for longer no longer repels
    exclude_ticks: int = 300           # an unreachable or blocked goal stays excluded this long
    exclude_radius_m: float = 1.0

    def __post_init__(self) -> None:
        check_float("k_attract", self.k_attract, 0.0, 1e6, lo_open=True)
        check_float("repulsion_radius_m", self.repulsion_radius_m, 0.0, 1000.0)
        check_float("repulsion_per_m", self.repulsion_per_m, 0.0, 1e6)
        check_int("max_steps", self.max_steps, 1, 1_000_000)
        check_int("replan_ticks", self.replan_ticks, 1, 1_000_000)
        check_int("announce_ticks", self.announce_ticks, 1, 100_000)
        check_int("stale_ticks", self.stale_ticks, 1, 1_000_000)
        check_int("exclude_ticks", self.exclude_ticks, 0, 1_000_000)
        check_float("exclude_radius_m", self.exclude_radius_m, 0.0, 100.0)


@dataclass(frozen=True)
class Field:
    """One re-plan's potential: ``base`` float[H, W] (attraction + repulsion, ``inf`` off the configuration
    space), the clusters' distance maps ``dist`` float[K, H, W] in cells, their target cells ``seeds``
    bool[K, H, W] and gains float[K]."""

    base: np.ndarray
    dist: np.ndarray
    seeds: np.ndarray
    gains: np.ndarray


def potential_field(known: np.ndarray, space: np.ndarray, others: list[tuple[float, float]], params: MMPFParams,
                    reach: int, exclude: np.ndarray | None = None) -> Field | None:
    """Steps 1-3 of the module docstring (without the path term); None when there is no frontier."""
    view = grid.view_cells(known, reach) & space
    if exclude is not None:
        view &= ~exclude
    box = np.ones((2 * reach + 1, 2 * reach + 1), dtype=bool)
    seeds, gains = [], []
    for cluster in grid.frontier_clusters(known):
        mask = np.zeros(known.shape, dtype=bool)
        mask[cluster.cells[:, 0], cluster.cells[:, 1]] = True
        near = ndimage.binary_dilation(mask, structure=box) & view
        if near.any():
            seeds.append(near)
            gains.append(float(cluster.size))
    if not seeds:
        return None
    h, w = known.shape
    dist = np.stack([grid.distance_field(space, np.argwhere(m)) / CELL_M for m in seeds]).astype(np.float64)
    base = np.zeros((h, w))
    for d, gain in zip(dist, gains):
        ok = d >= 1.0          # 568: the target itself and unreached cells (inf) add nothing
        ok &= np.isfinite(d)
        base[ok] -= params.k_attract * gain / d[ok]
    if others and params.repulsion_per_m > 0:
        rows, cols = np.indices((h, w))
        for x, y in others:
            r, c = cell_of(x, y)
            manhattan_m = (np.abs(rows - r) + np.abs(cols - c)) * CELL_M
            near_robot = manhattan_m < params.repulsion_radius_m
            base[near_robot] += params.repulsion_per_m * (params.repulsion_radius_m - manhattan_m[near_robot])
    base[~space] = np.inf
    return Field(base, dist, np.stack(seeds), np.array(gains))


def descend(field: Field, start: tuple[int, int], max_steps: int) -> list[tuple[int, int]]:
    """Step 4: the steepest-descent path from ``start`` (mmpf_node.cpp 535-659)."""
    h, w = field.base.shape
    path = [start]
    visits = {start: 1}
    current = START_POTENTIAL
    river = 1
    for _ in range(max_steps):
        r, c = path[-1]
        d_here = field.dist[:, r, c]
        if float(np.min(d_here)) <= 1.0:        # minDis2Frontier (635-644): within a cell of a target
            break
        best, best_p = None, math.inf
        for dr, dc in NEIGHBOURS:
            n = (r + dr, c + dc)
            if not (0 <= n[0] < h and 0 <= n[1] < w):
                continue
            p = float(field.base[n]) + river * PATH_PENALTY * visits.get(n, 0)
            if p < best_p:
                best, best_p = n, p
        if best is None or not current > best_p:
            break   # 621-622 would raise river until step 3000; only path cells get dearer, so it stays here
        path.append(best)
        visits[best] = visits.get(best, 0) + 1
        current = best_p
    return path


class MMPF:
    """Multi-robot potential fields as Explore-Bench's ``mmpf_node.cpp`` (see the module docstring)."""

    name = "mmpf"
    Params = MMPFParams

    def reset(self, robot: RobotInfo, params: MMPFParams, rng: np.random.Generator) -> None:
        self.robot = robot
        self.params = params
        self.reach = default_view_reach_cells(robot.radius, DEFAULT_MARGIN_M)
        self.heard: dict[int, tuple[float, float, int]] = {}
        self.goal_cell: tuple[int, int] | None = None
        self.goal: tuple[float, float] | None = None
        self.planned_at = -(10 ** 9)
        self.exclusions = Exclusions(params.exclude_radius_m, params.exclude_ticks)
        self.steps = 0

    def act(self, obs: Observation) -> Action:
        for msg in obs.inbox:
            if isinstance(msg, MMPFPose) and msg.sender != self.robot.id:
                self.heard[msg.sender] = (float(msg.x), float(msg.y), obs.tick)
        nav = obs.nav if self.goal is not None and obs.nav.goal == self.goal else None
        replan = obs.tick - self.planned_at >= self.params.replan_ticks or self.goal is None
        if nav is not None and nav.state in ("unreachable", "blocked"):
            assert self.goal_cell is not None
            self.exclusions.add(self.goal_cell, obs.tick)
            replan = True
        elif nav is not None and nav.state == "reached":
            assert self.goal_cell is not None   # what is still unseen there is hidden from it (departure 5)
            self.exclusions.add(self.goal_cell, obs.tick)
            replan = True
        if replan:
            self._plan(obs)
        messages = ()
        if obs.tick % self.params.announce_ticks == 0:
            messages = (MMPFPose(sender=self.robot.id, x=float(obs.pose.x), y=float(obs.pose.y)),)
        debug = {"steps": self.steps, "repelled_by": len(self.others(obs))}
        if self.goal is None:
            return Action(velocity=(0.0, 0.0), clear_goal=True, messages=messages, debug=debug)
        return Action(goal=self.goal, messages=messages, debug=debug)

    def others(self, obs: Observation) -> list[tuple[float, float]]:
        """Positions of the robots heard within ``stale_ticks``, by id."""
        return [(x, y) for _, (x, y, t) in sorted(self.heard.items()) if obs.tick - t <= self.params.stale_ticks]

    def _plan(self, obs: Observation) -> None:
        self.planned_at = obs.tick
        self.goal_cell, self.goal = None, None
        known = obs.known
        space = grid.configuration_space(known, self.robot.radius)
        here = cell_of(obs.pose.x, obs.pose.y)
        here = (min(max(here[0], 0), known.shape[0] - 1), min(max(here[1], 0), known.shape[1] - 1))
        start = grid.nearest_in(space, here, self.reach)
        if start is None:
            return
        exclude = self.exclusions.mask(known.shape, obs.tick)
        field = potential_field(known, space, self.others(obs), self.params, self.reach, exclude)
        if field is None:
            return
        path = descend(field, start, self.params.max_steps)
        self.steps = len(path) - 1
        end = path[-1]
        if end == start:   # a local minimum at the robot (departure 3): the most attractive cluster
            d = field.dist[:, start[0], start[1]]
            score = np.where(np.isfinite(d) & (d >= 1.0), field.gains / np.maximum(d, 1.0), -np.inf)
            k = int(np.argmax(score))
            if not np.isfinite(score[k]):
                return
            found = grid.nearest_reachable(space, start, field.seeds[k])
            if found is None:
                return
            end = found[0]
        self.goal_cell = end
        self.goal = cell_centre(*end)
