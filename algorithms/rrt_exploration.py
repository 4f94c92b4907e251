"""RRT exploration: Umari and Mukhopadhyay, "Autonomous robotic exploration based on multiple
rapidly-exploring randomized trees", IROS 2017, written from the authors' ROS package
(github.com/hasauino/rrt_exploration; file:line below are its files). docs/baselines.md summarises it.

The paper's four modules (section III), each robot running all four on its own map (the runtime shares maps
over the radio):

- **Local RRT detector** (section III-A; ``src/local_rrt_detector.cpp``). An RRT rooted at the robot: each
  iteration samples a point uniformly over the map, steers from the nearest vertex by at most ``eta``
  (``Steer``, ``src/functions.cpp``), and walks the new edge (``ObstacleFree``): through known free cells
  only, the new vertex is added; if the walk meets an unknown cell before any obstacle, that point is a
  frontier point, it is published, and the tree is **reset to the robot's current position**; an obstacle
  first, nothing. ``eta`` 1.0 m (``launch/single.launch``).
- **Global RRT detector** (section III-B; ``src/global_rrt_detector.cpp``). The same, rooted at the robot's
  start and **never reset**: a frontier point is published and the tree grows on, so it keeps reaching
  frontiers far from the robot that the local tree, reset near the robot, rarely gets to. ``eta`` 15 m.
  Both detectors run 100 iterations a second (``ros::Rate rate(100)``): ``iterations_per_tick`` (10 at
  0.1 s a tick).
- **Filter** (section III-C; ``scripts/filter.py``). The frontier points received so far and the previous
  centroids are clustered by **mean shift** (scikit-learn's flat kernel, ``bandwidth`` 0.3 m); the cluster
  centres replace them, and a centre is **dropped** when it lies in the robot's inflated obstacle space
  (the costmap above ``costmap_clearing_threshold``) or when it is **no longer a frontier**: less than
  0.2 m\\ :sup:`2` unknown within ``info_radius / 2`` of it (``informationGain``).
- **Assigner** (section III-D; ``scripts/assigner.py``). Every ``assign_ticks`` (``delay_after_assignement``
  0.5 s): for each centroid, the information gain ``I`` (unknown area within ``info_radius`` 1 m,
  ``scripts/functions.py`` ``informationGain``), discounted by the unknown area it shares with other robots'
  assigned points (``discount``); cost ``N`` the Euclidean distance from the robot; **revenue
  R = I * info_multiplier - N** (``info_multiplier`` 3). **Hysteresis**: ``I`` is multiplied by
  ``hysteresis_gain`` (2) for centroids within ``hysteresis_radius`` (3 m) of the robot, and, while the robot
  is busy with a goal, for centroids within ``hysteresis_radius`` of that goal (with the undiscounted gain).
  The centroid of largest revenue becomes the goal.

**Randomness** comes only from the ``rng`` given to ``reset`` (the authors seed a Mersenne twister with
constants and the wall clock).

**Radio.** The authors' assigner is one central node that knows every robot's goal. Here each robot
assigns itself and broadcasts its assigned point (``rrt.goal``, when it changes and every
``announce_ticks``); the points heard within ``stale_ticks`` are discounted. **Without connectivity** nothing
is discounted and robots out of range may choose the same centroid.

**Departures**

1. Decentralised assignment (above): each robot re-assigns only itself, every ``assign_ticks``, busy or not;
   the central assigner serves the idle robots first and re-assigns a busy one only when none is idle.
2. ``ObstacleFree`` walks edges in steps of ``CELL_M / 2`` on 0.5 m cells (the authors step one 5 cm cell);
   cells off the map count as obstacles. The sample square is the whole map (the authors click its corners).
3. The "costmap" of the filter is the robot's configuration space with unknown cells passable (a point
   within ``radius + margin`` of a known obstacle is dropped), not ROS's inflated costmap.
4. Information gain counts cells whose centres lie within the radius of the point's cell centre (the
   authors use the point itself), in m\\ :sup:`2`; the discount subtracts areas too (the authors subtract 1
   per cell from an area, their own comment says it is wrong).
5. A goal the navigator reports unreachable or blocked, or reached with unknown space still around it, is
   excluded (centroids within ``exclude_radius_m``) for ``exclude_ticks``; move_base's recovery is not here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit
from scipy import ndimage

from swarm.api import CELL_M, SOLID, UNSEEN, Action, Observation, RobotInfo, check_float, check_int, grid
from swarm.api.messages import message, require_finite

MEAN_SHIFT_MAX_ITER = 300          # scikit-learn's MeanShift default
MIN_FRONTIER_GAIN_M2 = 0.2         # filter.py: informationGain(..., info_radius * 0.5) < 0.2 drops a centroid


@message("rrt.goal")
@dataclass(frozen=True)
class RRTGoal:
    """"My assigned point is (x, y)" (metres): the others discount the information gain around it."""

    sender: int
    x: float
    y: float

    def validate(self) -> None:
        require_finite("rrt.goal", x=self.x, y=self.y)


@dataclass(frozen=True)
class RRTExplorationParams:
    local_eta: float = 1.0            # launch/single.launch "eta"
    global_eta: float = 15.0          # launch/single.launch "Geta"
    iterations_per_tick: int = 10     # each detector: 100 Hz (ros::Rate rate(100)) at 0.1 s a tick
    bandwidth: float = 0.3            # filter.py: MeanShift(bandwidth=0.3)
    info_radius: float = 1.0          # filter.py / assigner.py
    info_multiplier: float = 3.0      # assigner.py
    hysteresis_radius: float = 3.0    # assigner.py
    hysteresis_gain: float = 2.0      # assigner.py
    assign_ticks: int = 5             # assigner.py delay_after_assignement 0.5 s
    announce_ticks: int = 20          # re-broadcast the assigned point this often
    stale_ticks: int = 50             # another robot's assigned point is forgotten after this long
    exclude_ticks: int = 300
    exclude_radius_m: float = 1.0
    max_vertices: int = 20_000        # the global tree stops growing here (memory and time bound)

    def __post_init__(self) -> None:
        check_float("local_eta", self.local_eta, 0.0, 1000.0, lo_open=True)
        check_float("global_eta", self.global_eta, 0.0, 1000.0, lo_open=True)
        check_int("iterations_per_tick", self.iterations_per_tick, 0, 10_000)
        check_float("bandwidth", self.bandwidth, 0.0, 100.0, lo_open=True)
        check_float("info_radius", self.info_radius, 0.0, 100.0, lo_open=True)
        check_float("info_multiplier", self.info_multiplier, 0.0, 1e6)
        check_float("hysteresis_radius", self.hysteresis_radius, 0.0, 1000.0)
        check_float("hysteresis_gain", self.hysteresis_gain, 0.0, 1e6)
        check_int("assign_ticks", self.assign_ticks, 1, 100_000)
        check_int("announce_ticks", self.announce_ticks, 1, 100_000)
        check_int("stale_ticks", self.stale_ticks, 1, 1_000_000)
        check_int("exclude_ticks", self.exclude_ticks, 0, 1_000_000)
        check_float("exclude_radius_m", self.exclude_radius_m, 0.0, 100.0)
        check_int("max_vertices", self.max_vertices, 1, 10_000_000)


# --------------------------------------------------------------------------------------- geometry ----
def steer(nearest: np.ndarray, rand: np.ndarray, eta: float) -> np.ndarray:
    """``Steer`` (src/functions.cpp): ``rand`` if within ``eta`` of ``nearest``, else the point ``eta``
    from ``nearest`` towards it."""
    return np.array(_steer(float(nearest[0]), float(nearest[1]), float(rand[0]), float(rand[1]), float(eta)))


def obstacle_free(known: np.ndarray, near: np.ndarray, new: np.ndarray) -> tuple[int, np.ndarray]:
    """``ObstacleFree`` (src/functions.cpp): walk from ``near`` to ``new`` in steps of ``CELL_M / 2``; 1 and
    ``new`` if every cell is known free, -1 and the first unknown point if one comes before any obstacle, 0
    if an obstacle does (cells off the map are obstacles). The walk's points are those of repeated ``steer``
    calls."""
    state, x, y = _walk(np.ascontiguousarray(known), float(near[0]), float(near[1]), float(new[0]), float(new[1]))
    return state, np.array([x, y])


@njit(cache=True, inline="always")
def _steer(nx: float, ny: float, rx: float, ry: float, eta: float) -> tuple[float, float]:  # pragma: no cover
    """:func:`steer` on coordinates (shared with the compiled detector step)."""
    d = np.hypot(rx - nx, ry - ny)
    if d <= eta:
        return rx, ry
    return nx + (rx - nx) * (eta / d), ny + (ry - ny) * (eta / d)


@njit(cache=True, inline="always")
def _walk(known: np.ndarray, nx: float, ny: float, newx: float, newy: float) -> tuple[int, float, float]:  # pragma: no cover
    """:func:`obstacle_free` on coordinates: (state, point) as it returns them (shared with the detector)."""
    h, w = known.shape
    step = CELL_M / 2
    dist = np.hypot(newx - nx, newy - ny)
    m = int(np.ceil(dist / step))
    solid = False
    for k in range(1, m + 1):
        t = min(k * step, dist) / dist
        qx, qy = nx + (newx - nx) * t, ny + (newy - ny) * t
        if k == m:
            qx, qy = newx, newy
        row, col = int(np.floor(qy / CELL_M)), int(np.floor(qx / CELL_M))
        value = known[row, col] if 0 <= row < h and 0 <= col < w else SOLID
        if value == UNSEEN:
            return (0 if solid else -1), qx, qy
        if value == SOLID:
            solid = True
    return (0 if solid else 1), newx, newy


class Detector:
    """An RRT frontier detector: local (``reset_on_frontier``, re-rooted at the robot after each frontier
    point) or global (never reset). Vertices are float[N, 2] metres."""

    def __init__(self, eta: float, reset_on_frontier: bool, max_vertices: int) -> None:
        self.eta = eta
        self.reset_on_frontier = reset_on_frontier
        self.max_vertices = max_vertices
        self.vertices = np.zeros((0, 2))
        self.n = 0

    def root(self, xy: tuple[float, float]) -> None:
        self.vertices = np.zeros((64, 2))
        self.vertices[0] = xy
        self.n = 1

    def step(self, known: np.ndarray, robot_xy: tuple[float, float], rng: np.random.Generator,
             iterations: int) -> list[tuple[float, float]]:
        """``iterations`` RRT iterations; the frontier points found. Compiled (:func:`_rrt_steps`, with
        :func:`steer` and :func:`obstacle_free`'s kernels): the samples are drawn x then y per iteration from
        ``rng``, as the authors' loop draws them."""
        samples = rng.random(2 * iterations)
        if self.vertices.shape[0] < self.n + iterations:  # room for every vertex this step may add
            grown = np.zeros((max(2 * self.vertices.shape[0], self.n + iterations), 2))
            grown[:self.n] = self.vertices[:self.n]
            self.vertices = grown
        found = np.empty((iterations, 2))
        self.n, count = _rrt_steps(self.vertices, self.n, np.ascontiguousarray(known), samples, self.eta,
                                   self.reset_on_frontier, float(robot_xy[0]), float(robot_xy[1]), self.max_vertices,
                                   found)
        return [(float(x), float(y)) for x, y in found[:count]]


@njit(cache=True)
def _rrt_steps(vertices: np.ndarray, n: int, known: np.ndarray, samples: np.ndarray, eta: float, reset: bool,
               rx: float, ry: float, max_vertices: int, found: np.ndarray) -> tuple[int, int]:  # pragma: no cover - compiled
    """The detector's iterations (``samples``: two uniforms each): nearest vertex, :func:`_steer`,
    :func:`_walk`, the tree grown in ``vertices[:n]`` (room for every new vertex) or
    re-rooted at (rx, ry) after a frontier point when ``reset``; returns (n, frontier points in ``found``)."""
    h, w = known.shape
    count = 0
    for it in range(samples.shape[0] // 2):
        randx = samples[2 * it] * w * CELL_M
        randy = samples[2 * it + 1] * h * CELL_M
        best, best_d = 0, np.inf
        for k in range(n):
            dx, dy = vertices[k, 0] - randx, vertices[k, 1] - randy
            d2 = dx * dx + dy * dy
            if d2 < best_d:
                best, best_d = k, d2
        nx, ny = vertices[best, 0], vertices[best, 1]
        newx, newy = _steer(nx, ny, randx, randy, eta)
        state, px, py = _walk(known, nx, ny, newx, newy)
        if state == -1:
            found[count, 0], found[count, 1] = px, py
            count += 1
            if reset:
                vertices[0, 0], vertices[0, 1] = rx, ry
                n = 1
        elif state == 1 and n < max_vertices:
            vertices[n, 0], vertices[n, 1] = newx, newy
            n += 1
    return n, count


# ----------------------------------------------------------------------------------------- filter ----
def mean_shift(points: np.ndarray, bandwidth: float) -> np.ndarray:
    """Flat-kernel mean shift as scikit-learn's ``MeanShift(bandwidth)`` (every point a seed, shifted to the
    mean of the points within ``bandwidth`` until it moves less than ``1e-3 * bandwidth``; centres within
    ``bandwidth`` of a more intense one merged): the cluster centres, float[K, 2]. All seeds at once."""
    if len(points) <= 1:
        return points.copy()
    means = points.copy()
    counts = np.zeros(len(points), dtype=np.int64)
    running = np.ones(len(points), dtype=bool)
    for i in range(MEAN_SHIFT_MAX_ITER):
        idx = np.flatnonzero(running)
        if idx.size == 0:
            break
        m = means[idx]
        within = np.hypot(m[:, None, 0] - points[None, :, 0], m[:, None, 1] - points[None, :, 1]) <= bandwidth
        n = within.sum(axis=1)
        new = (within.astype(np.float64) @ points) / n[:, None]   # a seed always has itself within reach
        means[idx] = new
        counts[idx] = n
        done = np.hypot(*(new - m).T) <= 1e-3 * bandwidth
        if i == MEAN_SHIFT_MAX_ITER - 1:
            done[:] = True
        running[idx[done]] = False
    found: dict[tuple[float, float], int] = {}
    for mean, count in zip(means, counts):
        found[(float(mean[0]), float(mean[1]))] = int(count)
    ranked = sorted(found.items(), key=lambda kv: (kv[1], kv[0]), reverse=True)
    kept = np.zeros((len(ranked), 2))
    n = 0
    for centre, _ in ranked:
        c = np.array(centre)
        if n == 0 or bool((np.hypot(*(kept[:n] - c).T) > bandwidth).all()):
            kept[n] = c
            n += 1
    return kept[:n]


def unknown_area(known: np.ndarray, xy: np.ndarray, r: float, also: np.ndarray | None = None) -> float:
    """``informationGain`` (scripts/functions.py): the area (m^2) of unknown cells within ``r`` of the point's
    cell centre (and, with ``also``, within ``r`` of that point's too: ``discount``'s overlap)."""
    h, w = known.shape
    row, col = int(math.floor(xy[1] / CELL_M)), int(math.floor(xy[0] / CELL_M))
    k = int(r / CELL_M)
    r0, r1, c0, c1 = max(row - k, 0), min(row + k + 1, h), max(col - k, 0), min(col + k + 1, w)
    if r0 >= r1 or c0 >= c1:
        return 0.0
    rows, cols = np.mgrid[r0:r1, c0:c1]
    cy, cx = (rows + 0.5) * CELL_M, (cols + 0.5) * CELL_M
    inside = (cx - (col + 0.5) * CELL_M) ** 2 + (cy - (row + 0.5) * CELL_M) ** 2 <= r * r
    if also is not None:
        inside &= (cx - also[0]) ** 2 + (cy - also[1]) ** 2 <= r * r
    return float(np.count_nonzero(inside & (known[r0:r1, c0:c1] == UNSEEN))) * CELL_M * CELL_M


def area_map(known: np.ndarray, r: float) -> np.ndarray:
    """:func:`unknown_area` (without ``also``) of every cell at once: float[H, W] m^2."""
    k = int(r / CELL_M)
    dr, dc = np.mgrid[-k:k + 1, -k:k + 1]
    disc = ((dr * CELL_M) ** 2 + (dc * CELL_M) ** 2 <= r * r).astype(np.float64)
    unseen = (known == UNSEEN).astype(np.float64)
    return ndimage.correlate(unseen, disc, mode="constant", cval=0.0) * CELL_M * CELL_M


def _cells(xy: np.ndarray, shape: tuple[int, ...]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rows, cols = np.floor(xy[:, 1] / CELL_M).astype(np.int64), np.floor(xy[:, 0] / CELL_M).astype(np.int64)
    inside = (rows >= 0) & (rows < shape[0]) & (cols >= 0) & (cols < shape[1])
    return np.clip(rows, 0, shape[0] - 1), np.clip(cols, 0, shape[1] - 1), inside


def filter_points(known: np.ndarray, points: np.ndarray, params: RRTExplorationParams, radius_m: float
                  ) -> np.ndarray:
    """The filter (scripts/filter.py): mean-shift centres, without those in inflated obstacle space or no
    longer frontiers."""
    centres = mean_shift(points, params.bandwidth)
    if len(centres) == 0:
        return centres
    clear = grid.configuration_space(known, radius_m, unseen_traversable=True)
    rows, cols, inside = _cells(centres, known.shape)
    gain = area_map(known, params.info_radius * 0.5)[rows, cols]
    return centres[inside & clear[rows, cols] & (gain >= MIN_FRONTIER_GAIN_M2)]


# --------------------------------------------------------------------------------------- assigner ----
def revenues(known: np.ndarray, centroids: np.ndarray, robot_xy: np.ndarray, assigned: np.ndarray | None,
             others: list[np.ndarray], params: RRTExplorationParams) -> np.ndarray:
    """assigner.py's revenue of every centroid for this robot: ``I * info_multiplier - N`` with the discount
    and both hysteresis rules (module docstring)."""
    out = np.empty(len(centroids))
    rows, cols, _ = _cells(centroids, known.shape)
    plains = area_map(known, params.info_radius)[rows, cols]
    for i, c in enumerate(centroids):
        plain = float(plains[i])
        gain = plain - sum(unknown_area(known, c, params.info_radius, also=o) for o in others
                           if float(np.hypot(*(c - o))) <= 2 * params.info_radius)   # discs that overlap
        cost = float(np.hypot(*(robot_xy - c)))
        if cost <= params.hysteresis_radius:
            gain *= params.hysteresis_gain
        if assigned is not None and float(np.hypot(*(c - assigned))) < params.hysteresis_radius:
            gain = plain * params.hysteresis_gain
        out[i] = gain * params.info_multiplier - cost
    return out


class RRTExploration:
    """Multiple-RRT exploration of Umari and Mukhopadhyay 2017 (see the module docstring)."""

    name = "rrt_exploration"
    Params = RRTExplorationParams

    def reset(self, robot: RobotInfo, params: RRTExplorationParams, rng: np.random.Generator) -> None:
        self.robot = robot
        self.params = params
        self.rng = rng
        self.local = Detector(params.local_eta, True, params.max_vertices)
        self.global_ = Detector(params.global_eta, False, params.max_vertices)
        self.points = np.zeros((0, 2))                 # filtered centroids plus the points found since
        self.goal: tuple[float, float] | None = None
        self.excluded: dict[tuple[float, float], int] = {}
        self.others: dict[int, tuple[float, float, int]] = {}
        self.announced_at = -(10 ** 9)
        self.assigned_at = -(10 ** 9)

    def act(self, obs: Observation) -> Action:
        here = (float(obs.pose.x), float(obs.pose.y))
        if self.local.n == 0:
            self.local.root(here)
            self.global_.root(here)
        for msg in obs.inbox:
            if isinstance(msg, RRTGoal) and msg.sender != self.robot.id:
                self.others[msg.sender] = (float(msg.x), float(msg.y), obs.tick)
        known = obs.known
        n = self.params.iterations_per_tick
        found = self.local.step(known, here, self.rng, n) + self.global_.step(known, here, self.rng, n)
        if found:
            self.points = np.concatenate([self.points, np.array(found)])
        self.points = filter_points(known, self.points, self.params, self.robot.radius)
        previous = self.goal
        self._assign(obs, here)
        messages = ()
        if self.goal is not None and (self.goal != previous or obs.tick - self.announced_at >= self.params.announce_ticks):
            messages = (RRTGoal(sender=self.robot.id, x=self.goal[0], y=self.goal[1]),)
            self.announced_at = obs.tick
        debug = {"centroids": len(self.points), "local_tree": self.local.n, "global_tree": self.global_.n}
        if self.goal is None:
            return Action(velocity=(0.0, 0.0), clear_goal=True, messages=messages, debug=debug)
        return Action(goal=self.goal, messages=messages, debug=debug)

    def _assign(self, obs: Observation, here: tuple[float, float]) -> None:
        nav = obs.nav if self.goal is not None and obs.nav.goal == self.goal else None
        idle = self.goal is None or (nav is not None and nav.state in ("reached", "unreachable", "blocked"))
        if nav is not None and nav.state in ("unreachable", "blocked", "reached"):
            assert self.goal is not None
            self.excluded[self.goal] = obs.tick + self.params.exclude_ticks
        if not idle and obs.tick - self.assigned_at < self.params.assign_ticks:
            return
        self.assigned_at = obs.tick
        self.excluded = {g: until for g, until in self.excluded.items() if until > obs.tick}
        centroids = self.points
        if self.excluded and len(centroids):
            ex = np.array(list(self.excluded))
            far = np.all(np.hypot(centroids[:, None, 0] - ex[None, :, 0], centroids[:, None, 1] - ex[None, :, 1])
                         > self.params.exclude_radius_m, axis=1)
            centroids = centroids[far]
        if len(centroids) == 0:
            if idle:
                self.goal = None
            return
        others = [np.array((x, y)) for x, y, t in (self.others[k] for k in sorted(self.others))
                  if obs.tick - t <= self.params.stale_ticks]
        assigned = None if idle or self.goal is None else np.array(self.goal)
        rev = revenues(obs.known, centroids, np.array(here), assigned, others, self.params)
        best = centroids[int(np.argmax(rev))]
        self.goal = (float(best[0]), float(best[1]))
