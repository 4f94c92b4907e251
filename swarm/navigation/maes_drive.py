"""MAES's robot controller as a motion model (``motion.model = "maes"``): tile by tile, turning in place and
stopping, or one straight move.

MAES drives a robot with one task at a time (``Assets/Scripts/Robot/Robot2DController.cs``, commit 1bb0312):
a finite rotation (``Task/FiniteRotationTask.cs``: turn in place by an angle and brake to a stop) or a finite
move (``Task/FiniteMovementTask.cs``: drive forward a distance along the current heading, without steering,
and brake to a stop). A new task may start only when the robot is idle (``AssertRobotIsInIdleState``,
279-290), and a collision ends the current one (``NotifyCollided`` -> ``StopCurrentTask``, 118-123). The
algorithms reach goals in three ways, each asked for by :attr:`swarm.api.Action.drive`:

- ``"path"``, MAES's ``PathAndMoveTo`` (359-397): an A* path over 1 m coarse tiles (8-connected, no corner
  cutting, pessimistic: a tile is open only when its four 0.5 m cells are seen free; docs/maes.md 5.4),
  planned once per goal tile and followed one tile at a time: turn in place while the next tile's centre
  is more than 1.5 degrees off the heading, then one straight move to it, and stop. A tile of the path that
  has turned solid is skipped (372); a tile whose centre is within 0.5 m counts as passed (374-379).
- ``"runs"``, TNF's own following (``TnfExplorationAlgorithm.cs`` 347-389 with ``AStar.PathToSteps``,
  ``Map/PathFinding/AStar.cs`` 228-257): the same path cut into straight runs where its direction changes;
  per run, turn in place while its end is more than 0.5 degrees off (``AngleDelta``), then one straight
  move to the end tile's centre; runs ending within 0.3 m (``MinimumMoveDistance``) are skipped.
- ``"straight"``, MAES's ``MoveTo`` (403-409): turn in place while the goal tile's centre is more than
  0.5 degrees off, then one straight move there; no plan, so the move may end against a wall.

MAES's algorithms call these every tick and they act only while the robot is idle; here the drive does
the same for the goal the algorithm last set: the goal counts as ``reached`` once the robot is within
0.5 m of its goal tile's centre with nothing left to drive (``PathAndMoveTo`` returns, 376; ``MoveTo``,
406). A goal changed during a task takes effect when the task ends, as in MAES.

Departures (docs/maes.md section 4.1):

- The two tasks end where MAES's do (a move with less than 0.1 m left, a rotation within 0.1 degrees) but
  brake differently: MAES cuts its force at an over-estimated stop distance and coasts, acting every
  10 ms; this controller acts once per tick, so it commands the fastest rate after which stopping lands on
  the target, with the world's drive modelled as it is (:meth:`MaesDrive._rate`). Ticks per task are
  within one of MAES's own arithmetic (``benchmarks/experiments/maes_task_timing.py``). Speeds and
  accelerations are ``MotionParams``'s (``MotionParams.maes()`` holds MAES's).
- The next task starts at the first tick the robot is idle, slower than 1 m/s over the last tick, as MAES
  (``UpdateMotorPhysics`` 149-162, wheels under 0.01 tiles per physics step); MAES samples the wheels every
  10 ms, here the tick's displacement counts.
- Goals are points in metres; their tile is the 1 m tile holding them, or the nearest open tile within
  2 tiles when that one is not open (MAES's algorithms pick open coarse tiles themselves). The robot's
  own tile counts as open for planning.
- Safety nets MAES has not: a task that makes no progress for 1 s ends (MAES's pushes on against a wall
  until its algorithm's own deadlock rule reacts); without progress for ``navigation.stuck_ticks`` the
  task ends and the path is planned again, and after ``navigation.max_replans`` plans (for a straight
  move: at once) the goal is ``blocked``, as with swarm's navigator.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from swarm import grid
from swarm.base.types import CELL_M, FREE, SOLID, NavStatus, Pose, frozen_builder
from swarm.world.motion import TICK_S, MotionParams, wrap_angle
from .spec import NavigationSpec

TILE_M = 1.0
"""MAES's coarse tile: one map tile, 2 x 2 of swarm's 0.5 m cells (docs/maes.md 5.4)."""
CELLS_PER_TILE = int(round(TILE_M / CELL_M))
PATH_TURN_RAD = math.radians(1.5)
"""``PathAndMoveTo`` turns in place first while the next tile is more than 1.5 degrees off (line 395)."""
STRAIGHT_TURN_RAD = math.radians(0.5)
"""``MoveTo`` (line 407) and TNF's ``AngleDelta`` (``TnfExplorationAlgorithm.cs`` 75): 0.5 degrees."""
PASSED_M = 0.5
"""A tile's centre within 0.5 m counts as reached (``PathAndMoveTo`` 374, ``MoveTo`` 406)."""
RUN_SKIP_M = 0.3
"""TNF skips a path step whose end is nearer than 0.3 m (``MinimumMoveDistance``, line 76)."""
SNAP_TILES = 2
"""A goal in a tile that is not open moves to the nearest open tile within this many tiles."""
MOVE_END_M = 0.1
"""A straight move ends when less than 0.1 m is left (``FiniteMovementTask`` line 51); the robot then stops
within a few centimetres (MAES: coasts, ending 0.05-0.07 m short, benchmarks/experiments/maes_task_timing.py)."""
ROTATION_END_RAD = math.radians(0.1)
"""A rotation ends within 0.1 degrees (``FiniteRotationTask``: ``targetDelta < 0.1f``)."""
IDLE_BELOW_MPS = 1.0
"""MAES's robot is idle, and may start a task, once its wheels move less than 0.01 tiles per 10 ms physics
step (``UpdateMotorPhysics`` 154-162), i.e. 1 m/s; here the centre's speed over the last tick."""
PROGRESS_M = 0.05
TASK_STALL_TICKS = 10
"""A task that gains less than :data:`TASK_PROGRESS_M` (a move) or :data:`TASK_PROGRESS_RAD` (a rotation)
in this many ticks ends (a robot pushing against a wall or another robot)."""
TASK_PROGRESS_M = 0.01
TASK_PROGRESS_RAD = 0.01

_nav_status = frozen_builder(NavStatus)


def coarse_open(known: np.ndarray) -> np.ndarray:
    """MAES's pessimistic coarse map of a knowledge map (uint8[H, W] of 0.5 m cells): bool[ceil(H/2),
    ceil(W/2)], True where all of a 1 m tile's cells are FREE (cells beyond the map count as solid)."""
    h, w = known.shape
    k = CELLS_PER_TILE
    th, tw = -(-h // k), -(-w // k)
    free = np.zeros((th * k, tw * k), dtype=bool)
    free[:h, :w] = known == FREE
    return free.reshape(th, k, tw, k).all(axis=(1, 3))


def tile_of(x: float, y: float) -> tuple[int, int]:
    """The (row, col) of the 1 m tile holding point (x, y) in metres."""
    return int(math.floor(y / TILE_M)), int(math.floor(x / TILE_M))


def tile_centre(tile: tuple[int, int]) -> tuple[float, float]:
    """(x, y) in metres of a tile's centre."""
    return (tile[1] + 0.5) * TILE_M, (tile[0] + 0.5) * TILE_M


def path_runs(tiles: np.ndarray) -> np.ndarray:
    """``AStar.PathToSteps`` (AStar.cs 228-257): the end tile of each straight run of a tile path
    (int[N, 2], both ends included), a run ending where the step direction changes."""
    if len(tiles) <= 1:
        return tiles[:1].copy()
    steps = np.diff(tiles, axis=0)
    turns = np.nonzero(np.any(steps[1:] != steps[:-1], axis=1))[0] + 1  # the tile where a new run starts
    return np.concatenate([tiles[turns], tiles[-1:]])


def _solid_tile(known: np.ndarray, tile: tuple[int, int]) -> bool:
    """Whether a tile holds a SOLID cell (MAES's coarse ``Solid`` status, any sub-cell solid)."""
    k = CELLS_PER_TILE
    block = known[tile[0] * k:(tile[0] + 1) * k, tile[1] * k:(tile[1] + 1) * k]
    return bool(block.size) and bool((block == SOLID).any())


def _snap(space: np.ndarray, tile: tuple[int, int]) -> tuple[int, int]:
    """``tile`` if open, else the nearest open tile within :data:`SNAP_TILES` (the first in row order among
    equally near ones), else ``tile``."""
    h, w = space.shape
    r0, c0 = tile
    if 0 <= r0 < h and 0 <= c0 < w and space[r0, c0]:
        return tile
    best, best_d = tile, math.inf
    for r in range(max(r0 - SNAP_TILES, 0), min(r0 + SNAP_TILES + 1, h)):
        for c in range(max(c0 - SNAP_TILES, 0), min(c0 + SNAP_TILES + 1, w)):
            d = (r - r0) ** 2 + (c - c0) ** 2
            if space[r, c] and d < best_d:
                best, best_d = (r, c), d
    return best


@njit(cache=True)
def _ramp(w: float, command: float, substeps: int, dw: float) -> float:  # pragma: no cover - compiled
    """The drive's rate after ``substeps`` sub-steps toward ``command`` from ``w``, at most ``dw`` per
    sub-step (:mod:`swarm.world.physics`)."""
    for _ in range(substeps):
        w = min(w + dw, command) if command > w else max(w - dw, command)
    return w


@njit(cache=True)
def _coast(w: float, command: float, substeps: int, dw: float) -> float:  # pragma: no cover - compiled
    """The travel, in sub-steps times rate, of ``substeps`` sub-steps toward ``command`` from ``w`` (each
    sub-step moves at the rate before it); ``substeps = 0``: until the rate reaches ``command``."""
    total = 0.0
    k = 0
    while (k < substeps) if substeps else (w != command and k < 100_000):
        total += w
        w = min(w + dw, command) if command > w else max(w - dw, command)
        k += 1
    return total


@njit(cache=True)
def _travel(w0: float, command: float, substeps: int, dw: float, dsub: float) -> float:  # pragma: no cover
    """How far (m or rad) the drive goes from rate ``w0`` under ``command`` for a tick, then commanded 0
    until it stops."""
    return (_coast(w0, command, substeps, dw) + _coast(_ramp(w0, command, substeps, dw), 0.0, 0, dw)) * dsub


@njit(cache=True)
def _fastest(left: float, w0: float, top: float, dw: float, substeps: int,
             dsub: float) -> float:  # pragma: no cover - compiled
    """:meth:`MaesDrive._rate`: the largest command in [0, top] (bisection) after which stopping travels no
    further than ``left``; 0 when even stopping now overshoots."""
    if w0 > 0 and _travel(w0, w0, substeps, dw, dsub) > left:
        return 0.0
    lo, hi = 0.0, top
    for _ in range(24):
        mid = 0.5 * (lo + hi)
        if _travel(w0, mid, substeps, dw, dsub) <= left:
            lo = mid
        else:
            hi = mid
    return lo


def _snap_near(known: np.ndarray, tile: tuple[int, int]) -> tuple[int, int]:
    """:func:`_snap` on the coarse map of the tiles within :data:`SNAP_TILES` of ``tile`` only (a straight
    move needs no more of the map)."""
    k = CELLS_PER_TILE
    r0, c0 = max(tile[0] - SNAP_TILES, 0), max(tile[1] - SNAP_TILES, 0)
    window = known[r0 * k:(tile[0] + SNAP_TILES + 1) * k, c0 * k:(tile[1] + SNAP_TILES + 1) * k]
    if window.size == 0:
        return tile
    r, c = _snap(coarse_open(window), (tile[0] - r0, tile[1] - c0))
    return r + r0, c + c0


class MaesDrive:
    """One robot's MAES controller: the goal and drive its algorithm set, the path (tiles, or the ends of
    its straight runs) and the task under way. Has :class:`~swarm.navigation.navigator.Navigator`'s
    interface (``set_goal``, ``command``, ``status``, ``state``, ``goal``, ``plans``)."""

    def __init__(self, spec: NavigationSpec, motion: MotionParams) -> None:
        self.spec = spec
        self.motion = motion
        self._max_speed, self._max_turn_rate = motion.max_speed, motion.max_turn_rate
        self._last_xy: tuple[float, float, float] | None = None   # the pose of the last tick
        self._speed = 0.0                 # m/s over the last tick, for MAES's idle rule
        self._wheel_w = 0.0               # the world's drive turn rate as the last command left it (rad/s)
        self._wheel_known = False         # whether the last tick's command was this controller's
        self._substeps = motion.substeps or 1
        self._dsub = TICK_S / self._substeps
        self._dw = motion.max_turn_accel * self._dsub   # the most the turn rate changes per sub-step
        self._wheel_v = 0.0               # and its forward speed (m/s)
        self._dv = motion.max_accel * self._dsub
        self.goal: tuple[float, float] | None = None
        self.drive = "path"
        self.state = "idle"
        self.path_length = 0.0
        self.plans = 0
        self.replans = 0
        self.tasks = 0                    # tasks started (rotations and moves)
        self.stalled_tasks = 0            # tasks ended for want of progress (pushing against a wall)
        self.last_task = ""               # "rotate" or "move": the last task started
        self._task_best = math.inf
        self._task_stalled = 0
        self._goal_tile: tuple[int, int] | None = None
        self._path: np.ndarray | None = None      # tile centres still to reach (float[M, 2], metres)
        self._suffix: np.ndarray | None = None    # path length after each of them
        self._next = 0                            # index of the tile (or run end) heading for
        self._moved = False                       # "runs": the current run's move was made
        self._task: tuple[float, ...] | None = None  # (0, heading) or (1, x0, y0, cos, sin, distance)
        self._best = math.inf
        self._stalled = 0
        self._status = NavStatus(goal=None, state="idle", path_length=0.0, ticks_since_progress=0)

    # ------------------------------------------------------------------------------------ control ----
    def set_goal(self, goal: tuple[float, float] | None, drive: str = "path") -> None:
        """A new goal (None: stop now, ending the task under way) and how to drive there. The same goal and
        drive again change nothing; a new one is taken up when the task under way ends."""
        if goal is not None:
            goal = (float(goal[0]), float(goal[1]))
        if goal == self.goal and drive == self.drive:
            return
        self.goal, self.drive = goal, drive
        self.replans = 0
        self._best, self._stalled = math.inf, 0
        self._path = None
        if goal is None:
            self._task = None
            self.state = "idle"
        else:
            self.state = "moving"

    def interrupt(self) -> None:
        """End the task under way (a collision, or the algorithm driving by velocity this tick)."""
        self._task = None

    def skipped(self) -> None:
        """This tick's command was not this controller's (the algorithm drove by velocity, or did not act)."""
        self._task = None
        self._wheel_known = False

    def command(self, pose: Pose, known: np.ndarray) -> tuple[float, float]:
        """This tick's (v, omega): the task under way, or, when the robot is idle, the next task toward the
        goal (and its first command)."""
        last, self._last_xy = self._last_xy, (pose.x, pose.y, pose.theta)
        self._speed = 0.0 if last is None else math.hypot(pose.x - last[0], pose.y - last[1]) / TICK_S
        if not self._wheel_known:   # the robot was driven by velocity (or not at all): its rates then
            self._wheel_w = 0.0 if last is None else wrap_angle(pose.theta - last[2]) / TICK_S
            self._wheel_v = 0.0 if last is None else ((pose.x - last[0]) * math.cos(pose.theta)
                                                      + (pose.y - last[1]) * math.sin(pose.theta)) / TICK_S
        v, omega = self._command(pose, known)
        self._wheel_w = _ramp(self._wheel_w, omega, self._substeps, self._dw)
        self._wheel_v = _ramp(self._wheel_v, v, self._substeps, self._dv)
        self._wheel_known = True
        return v, omega

    def _command(self, pose: Pose, known: np.ndarray) -> tuple[float, float]:
        if self._task is not None:
            step = self._step_task(pose)
            if step is not None:
                self._track(pose, known)
                return step
        if self.goal is None or self.state != "moving" or self._speed >= IDLE_BELOW_MPS:
            return 0.0, 0.0   # (still stopping: not idle yet)
        self._decide(pose, known)
        if self._task is None:
            return 0.0, 0.0
        step = self._step_task(pose)
        if self.state == "moving":
            self._track(pose, known)
        return step if step is not None else (0.0, 0.0)

    @property
    def ticks_since_progress(self) -> int:
        return self._stalled

    def status(self) -> NavStatus:
        s = self._status
        if (s.state != self.state or s.goal != self.goal or s.path_length != self.path_length
                or s.ticks_since_progress != self._stalled):
            s = self._status = _nav_status(goal=self.goal, state=self.state, path_length=self.path_length,
                                           ticks_since_progress=self._stalled)
        return s

    # -------------------------------------------------------------------------------------- tasks ----
    def _step_task(self, pose: Pose) -> tuple[float, float] | None:
        """The task's command for this tick, or None when it has ended (then no task is under way)."""
        task = self._task
        assert task is not None
        if task[0] == 0.0:   # rotation in place onto a heading
            err = wrap_angle(task[1] - pose.theta)
            if abs(err) <= ROTATION_END_RAD:
                self._task = None
                return None
            if self._task_stalled_on(abs(err), TASK_PROGRESS_RAD):
                return None
            sign = 1.0 if err > 0 else -1.0
            return 0.0, sign * self._rate(abs(err), sign * self._wheel_w, self._max_turn_rate, self._dw)
        _, x0, y0, cos, sin, distance = task   # straight move along the heading it started on
        along = (pose.x - x0) * cos + (pose.y - y0) * sin
        rem = distance - along
        if rem <= MOVE_END_M:
            self._task = None
            return None
        if self._task_stalled_on(rem, TASK_PROGRESS_M):
            return None
        return self._rate(rem, self._wheel_v, self._max_speed, self._dv), 0.0

    def _rate(self, left: float, w0: float, top: float, dw: float) -> float:
        """The fastest rate (turn or forward) for this tick, toward a target ``left`` away, after which
        commanding 0 stops the robot no further than the target; ``w0``: the drive's rate now (signed toward
        the target), ``dw`` the most it changes per sub-step. MAES's controller acts every 10 ms physics
        step, this one once per tick, so it must brake a tick ahead. The drive is modelled as the world has
        it (:mod:`swarm.world.physics`): per sub-step the rate moves toward the command by at most ``dw``,
        and the body moves at the rate of the sub-step before."""
        return _fastest(left, w0, top, dw, self._substeps, self._dsub)

    def _task_stalled_on(self, left: float, step: float) -> bool:
        """Count a tick of the task with ``left`` still to go; True (and the task ended) after
        :data:`TASK_STALL_TICKS` ticks without ``step`` of progress."""
        if left < self._task_best - step:
            self._task_best, self._task_stalled = left, 0
            return False
        self._task_stalled += 1
        if self._task_stalled < TASK_STALL_TICKS:
            return False
        self._task = None
        self.stalled_tasks += 1
        return True

    def _rotate(self, pose: Pose, bearing: float) -> None:
        self._task = (0.0, bearing)
        self.tasks += 1
        self.last_task = "rotate"
        self._task_best, self._task_stalled = math.inf, 0

    def _move(self, pose: Pose, distance: float) -> None:
        self._task = (1.0, pose.x, pose.y, math.cos(pose.theta), math.sin(pose.theta), distance)
        self.tasks += 1
        self.last_task = "move"
        self._task_best, self._task_stalled = math.inf, 0

    # --------------------------------------------------------------------------------- decisions ----
    def _decide(self, pose: Pose, known: np.ndarray) -> None:
        """The robot is idle: the next task toward the goal, as the drive's MAES routine chooses it (or the
        goal reached, unreachable)."""
        if self.drive == "straight":
            self._decide_straight(pose, known)
        else:
            self._decide_path(pose, known, runs=self.drive == "runs")

    def _decide_straight(self, pose: Pose, known: np.ndarray) -> None:
        """``MoveTo`` (Robot2DController.cs 403-409)."""
        if self._goal_tile is None or self._path is None:
            self._goal_tile = _snap_near(known, tile_of(*self.goal))  # type: ignore[misc]
            self._path = np.array([tile_centre(self._goal_tile)])
            self._suffix = np.zeros(1)
            self.path_length = math.hypot(self._path[0, 0] - pose.x, self._path[0, 1] - pose.y)
        tx, ty = self._path[0]
        dist = math.hypot(tx - pose.x, ty - pose.y)
        if dist < PASSED_M:
            self.state = "reached"
            return
        err = wrap_angle(math.atan2(ty - pose.y, tx - pose.x) - pose.theta)
        if abs(err) > STRAIGHT_TURN_RAD:
            self._rotate(pose, pose.theta + err)
        else:
            self._move(pose, dist)

    def _decide_path(self, pose: Pose, known: np.ndarray, runs: bool) -> None:
        """``PathAndMoveTo`` (Robot2DController.cs 359-397), or TNF's run by run (``runs``)."""
        if self._path is None:
            if not self._plan(pose, known, runs):
                return
        path = self._path
        assert path is not None
        if runs:
            while True:
                tx, ty = path[self._next]
                dist = math.hypot(tx - pose.x, ty - pose.y)
                if not self._moved and dist >= RUN_SKIP_M:
                    break
                self._next += 1   # the run was driven (or needs no move): the next one
                self._moved = False
                if self._next >= len(path):
                    self.state = "reached"
                    return
            err = wrap_angle(math.atan2(ty - pose.y, tx - pose.x) - pose.theta)
            if abs(err) <= STRAIGHT_TURN_RAD:
                self._move(pose, dist)
                self._moved = True
            else:
                self._rotate(pose, pose.theta + err)
            return
        if self._next < len(path) - 1 and _solid_tile(known, tile_of(*path[self._next])):
            self._next += 1   # the tile turned solid: on to the next (line 372)
        tx, ty = path[self._next]
        dist = math.hypot(tx - pose.x, ty - pose.y)
        if dist < PASSED_M:
            if self._next >= len(path) - 1:
                self.state = "reached"
                return
            self._next += 1
            tx, ty = path[self._next]
            dist = math.hypot(tx - pose.x, ty - pose.y)
        err = wrap_angle(math.atan2(ty - pose.y, tx - pose.x) - pose.theta)
        if abs(err) > PATH_TURN_RAD:
            self._rotate(pose, pose.theta + err)
        elif dist > PASSED_M:
            self._move(pose, dist)

    def _plan(self, pose: Pose, known: np.ndarray, runs: bool) -> bool:
        """A* over the coarse tiles from the robot's tile to the goal's; False (and ``reached`` or
        ``unreachable``) when there is nothing to drive."""
        assert self.goal is not None
        self.plans += 1
        space = coarse_open(known)
        goal = _snap(space, tile_of(*self.goal))
        self._goal_tile = goal
        start = tile_of(pose.x, pose.y)
        h, w = space.shape
        if not (0 <= start[0] < h and 0 <= start[1] < w and 0 <= goal[0] < h and 0 <= goal[1] < w):
            self.state = "unreachable"
            return False
        if start == goal and not runs:
            self.state = "reached"   # PathAndMoveTo: already on the goal tile (line 366)
            return False
        space[start] = True          # the robot's own tile, whatever it holds
        tiles = grid.plan(space, start, goal)
        if tiles is None:
            self.state = "unreachable"   # PathAndMoveTo returns without a path (368)
            return False
        if runs:
            tiles = path_runs(tiles)
        centres = (tiles[:, ::-1].astype(np.float64) + 0.5) * TILE_M
        seg = np.hypot(*np.diff(centres, axis=0).T) if len(centres) > 1 else np.zeros(0)
        suffix = np.zeros(len(centres))
        if len(seg):
            suffix[:-1] = np.cumsum(seg[::-1])[::-1]
        self._path, self._suffix, self._next, self._moved = centres, suffix, 0, False
        self.path_length = float(math.hypot(centres[0, 0] - pose.x, centres[0, 1] - pose.y) + suffix[0])
        return True

    # ---------------------------------------------------------------------------------- progress ----
    def _track(self, pose: Pose, known: np.ndarray) -> None:
        """No progress toward the goal for ``stuck_ticks``: plan again; ``blocked`` after ``max_replans``."""
        path, suffix = self._path, self._suffix
        if path is None or suffix is None:
            return
        i = min(self._next, len(path) - 1)
        remaining = math.hypot(path[i, 0] - pose.x, path[i, 1] - pose.y) + suffix[i]
        if remaining < self._best - PROGRESS_M:
            self._best, self._stalled = remaining, 0
            return
        self._stalled += 1
        if self._stalled < self.spec.stuck_ticks:
            return
        self._stalled, self._best = 0, math.inf
        self._task = None
        if self.replans >= self.spec.max_replans or self.drive == "straight":
            self.state = "blocked"   # a straight move has no plan to change
            return
        self.replans += 1
        self._path = None   # plan again
        self._goal_tile = None


class MaesDriveFleet:
    """The runtime's MAES controllers, one per robot, with :class:`~swarm.navigation.navigator.NavigationFleet`'s
    interface. Robot by robot in Python: MAES-parity runs have a few robots."""

    def __init__(self, spec: NavigationSpec, motion: MotionParams, rngs: list[np.random.Generator]) -> None:
        self.navigators = [MaesDrive(spec, motion) for _ in rngs]  # MAES's planner draws no random numbers

    def command(self, rows: list[int], poses: np.ndarray, pose_tuples: list[Pose], known: np.ndarray,
                out: np.ndarray, began: np.ndarray | None = None) -> None:
        """``out[i]`` for every robot ``i`` in ``rows`` (those that steer by goal this tick). A collision that
        began this tick (``began[i]``) ends the robot's task, as does driving by velocity (a robot not in
        ``rows``)."""
        steered = set(rows)
        for i, nav in enumerate(self.navigators):
            if i not in steered:
                nav.skipped()
            elif nav._task is not None and began is not None and began[i]:
                nav.interrupt()
        for i in rows:
            out[i] = self.navigators[i].command(pose_tuples[i], known[i])


__all__ = ["MaesDrive", "MaesDriveFleet", "coarse_open", "path_runs", "tile_centre", "tile_of"]
