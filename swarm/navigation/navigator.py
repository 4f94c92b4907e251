"""Drive a robot to its algorithm's goal on the robot's own knowledge map.

A :class:`Navigator` plans once per goal on the robot's configuration space (its knowledge map with the
robot radius plus a margin of clearance, :func:`swarm.grid.configuration_space`), shortcuts the grid path
into straight segments, and hands them to the waypoint follower. Each tick it checks, cheaply, whether a
cell in the path's corridor has turned SOLID (replan) and whether the robot is making progress (replan
after ``stuck_ticks`` without progress; report ``blocked`` after ``max_replans``). A goal that no path
reaches is reported ``unreachable``. What to do then is the algorithm's decision.

The runtime commands all its navigators at once (:class:`NavigationFleet`): their per-tick state lives in
arrays (:class:`NavigatorSlots`), so the step of every moving robot is one compiled call per tick; a lone
:class:`Navigator` keeps the same state in a table of one and behaves identically.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from swarm import grid
from swarm.base.types import CELL_M, SOLID, NavStatus, Pose, cell_of, frozen_builder
from swarm.grid import kept, memo
from swarm.grid.cspace import configuration_space_of, nearest_in_of
from swarm.grid.local import plan_local_first
from swarm.knowledge.tiles import TiledKnowledge, cells_below_tiled
from swarm.plugins.planners import AStar, get_planner
from swarm.util.arena import Arena
from swarm.world.motion import Follower, FollowerSlots, _follow_step, cells_below
from swarm.world.physics import MotionParams

from .spec import NavigationSpec

SNAP_RADIUS_CELLS = 4
"""A start or goal inside inflated space snaps to the nearest drivable cell within 2 m."""
PROGRESS_M = 0.05

_nav_status = frozen_builder(NavStatus)  # about half the runtime's status() calls build a new one


class NavigatorSlots:
    """The state a navigator's per-tick step reads and writes, a row per navigator, in arrays (its
    follower's :class:`~swarm.world.motion.FollowerSlots`, its corridor as an :class:`~swarm.util.arena.Arena` row, the
    best remaining length and the ticks since progress), so that :class:`NavigationFleet` steps all of them
    in one compiled call."""

    def __init__(self, n: int) -> None:
        self.followers = FollowerSlots(n)
        self.corridors = Arena(n, np.int64)
        self.best_remaining = np.full(n, math.inf)
        self.stalled = np.zeros(n, dtype=np.int64)


class Navigator:
    def __init__(self, spec: NavigationSpec, motion: MotionParams, rng: np.random.Generator | None = None, *,
                 slots: NavigatorSlots | None = None, row: int = 0) -> None:
        """``slots``/``row``: keep the per-tick state in row ``row`` of a fleet's table (default: its own)."""
        self.spec = spec
        self.motion = motion
        self.planner = get_planner(spec.planner)
        self.rng = rng if rng is not None else np.random.default_rng(0)
        self._slots = slots if slots is not None else NavigatorSlots(1)
        self._row = row
        self.follower = Follower(motion, slots=self._slots.followers, row=row)
        self.goal: tuple[float, float] | None = None
        self.state = "idle"
        self.path_length = 0.0
        self.corridor: np.ndarray | None = None  # flat cell indices (the slots' arena row while moving)
        self.replans = 0
        self.plans = 0
        self._status = NavStatus(goal=None, state="idle", path_length=0.0, ticks_since_progress=0)

    # ------------------------------------------------------------------------------------ control ----
    def set_goal(self, goal: tuple[float, float] | None, drive: str = "path") -> None:
        """A new goal (or None to stop). The same goal again changes nothing. ``drive`` (how MAES's motion
        model would drive there, :attr:`swarm.api.Action.drive`) does not matter here: every goal is
        planned and followed as a smooth path."""
        if goal is not None:
            goal = (float(goal[0]), float(goal[1]))
        if goal == self.goal:
            return
        self.goal = goal
        self.replans = 0
        self.corridor = None
        self.state = "idle" if goal is None else "planning"

    def command(self, pose: Pose, known: np.ndarray) -> tuple[float, float]:
        """The (v, omega) command for this tick. ``known`` is the robot's knowledge map as the runtime keeps
        it (uint8[H, W], values 0..2); it is not scanned for bad values again on every plan."""
        if self.goal is None or self.state in ("reached", "unreachable", "blocked", "idle"):
            return 0.0, 0.0
        # Moving (which comes with a corridor): the corridor check and the follower's step are one compiled
        # call; planning (or a blocked corridor) plans first.
        if self.state == "planning":
            return self._plan_and_step(pose, known)
        assert self.corridor is not None
        step = self.follower.command_unless(known, self.corridor, SOLID, pose)
        if step is None:
            return self._plan_and_step(pose, known)
        return self._after_step(step, pose, known)

    @property
    def best_remaining(self) -> float:
        """The shortest remaining path length seen since the last progress reset (m)."""
        return self._slots.best_remaining.item(self._row)

    @property
    def ticks_since_progress(self) -> int:
        return self._slots.stalled.item(self._row)

    def _plan_and_step(self, pose: Pose, known: np.ndarray) -> tuple[float, float]:
        """:meth:`command` from a plan: plan, then the follower's first step on it."""
        self._plan(pose, known)
        if self.state != "moving":
            return 0.0, 0.0
        return self._after_step(self.follower.command(pose), pose, known)

    def _after_step(self, step: tuple[float, float], pose: Pose, known: np.ndarray) -> tuple[float, float]:
        """:meth:`command` after the follower's step: arrival, then progress (which may replan)."""
        v, omega = step
        if self.follower.done:
            self.state = "reached"
            return 0.0, 0.0
        self._track_progress(pose, known)
        if self.state != "moving":
            return 0.0, 0.0
        return v, omega

    def status(self) -> NavStatus:
        """The current status; the same (immutable) object while nothing in it changed, since the runtime
        asks for every robot every tick and most ticks change nothing."""
        s = self._status
        stalled = self._slots.stalled.item(self._row)
        if (s.state != self.state or s.goal != self.goal or s.path_length != self.path_length
                or s.ticks_since_progress != stalled):
            s = self._status = _nav_status(goal=self.goal, state=self.state, path_length=self.path_length,
                                           ticks_since_progress=stalled)
        return s

    # ----------------------------------------------------------------------------------- planning ----
    def _plan(self, pose: Pose, known: np.ndarray) -> None:
        assert self.goal is not None
        self.plans += 1
        found = self._waypoints(pose, known)
        if found is None:
            self.state = "unreachable"
            self.corridor = None
            return
        waypoints, goal_fits = found
        if goal_fits:
            waypoints[-1] = self.goal  # end exactly on the goal when the robot fits there
        self.follower.set_path(waypoints)
        self.path_length = grid.path_length_m(waypoints)
        polyline = np.empty((waypoints.shape[0] + 1, 2), dtype=np.float64)
        polyline[0] = pose.x, pose.y
        polyline[1:] = waypoints
        slots, row = self._slots, self._row
        self.corridor = slots.corridors.put(row, _corridor(polyline, known))
        slots.best_remaining[row] = math.inf
        slots.stalled[row] = 0
        self.state = "moving"

    def _waypoints(self, pose: Pose, known: np.ndarray) -> tuple[np.ndarray, bool] | None:
        """Shortcut waypoints of the plan to the goal, and whether the goal's own cell is drivable; None
        when no path reaches the goal. The exact grid planner first tries the window around the robot
        (:func:`swarm.grid.local.plan_local_first`, the same answer when it gives one)."""
        assert self.goal is not None
        params = (self.motion.radius, self.spec.margin_m, self.spec.unseen == "traversable")
        start_cell = _clip(cell_of(pose.x, pose.y), known.shape)
        goal_cell = _clip(cell_of(*self.goal), known.shape)
        inside = _inside(self.goal, known.shape)
        exact = type(self.planner) is AStar  # the exact grid planner only (a subclass may plan differently)
        if exact:
            local = plan_local_first(known, start_cell, goal_cell, *params, SNAP_RADIUS_CELLS,
                                     boxed=kept.rebuilds(known))
            if local is not None:
                return local[0], inside and local[1]
        # The runtime's own map (uint8, values 0..2 by construction): no value scan per plan.
        searched = memo.recall(known, params, start_cell, goal_cell) if exact else None
        space = searched.space if searched is not None else configuration_space_of(known, *params)
        start = nearest_in_of(space, start_cell, SNAP_RADIUS_CELLS)
        goal = nearest_in_of(space, goal_cell, SNAP_RADIUS_CELLS)
        if searched is not None and (start, goal) == (searched.start, searched.goal):
            path = searched.path  # the far target's search already found this plan (swarm.grid.memo)
        else:
            path = None if start is None or goal is None else self.planner.plan(space, start, goal, self.rng)
        if path is None:
            return None
        return grid.simplify(space, path), inside and bool(space[goal_cell])

    def _track_progress(self, pose: Pose, known: np.ndarray) -> None:
        slots, row = self._slots, self._row
        remaining = self.follower.remaining_m
        if remaining < slots.best_remaining[row] - PROGRESS_M:
            slots.best_remaining[row] = remaining
            slots.stalled[row] = 0
            return
        slots.stalled[row] += 1
        if slots.stalled[row] >= self.spec.stuck_ticks:
            self._stuck(pose, known)

    def _stuck(self, pose: Pose, known: np.ndarray) -> None:
        """No progress for ``stuck_ticks``: replan, or report ``blocked`` after ``max_replans``."""
        if self.replans >= self.spec.max_replans:
            self.state = "blocked"
            return
        self.replans += 1
        self._plan(pose, known)


class NavigationFleet:
    """The runtime's navigators, a row each of one :class:`NavigatorSlots`, commanded together.

    On nearly every tick nearly every robot is moving: its corridor is checked, its follower steps and its
    progress is counted. For all of them that is one compiled call (:func:`_fleet_step`), instead of a
    call and a few Python frames per robot. What needs Python (plans, an arrival, no progress for
    ``stuck_ticks``) then goes through :class:`Navigator`'s own methods, robot by robot in robot order.
    The commands and states are those of :meth:`Navigator.command` robot by robot: a robot's step reads
    only its own map, pose and state, and plans (and the random numbers they draw) come in the same order.
    """

    def __init__(self, spec: NavigationSpec, motion: MotionParams, rngs: list[np.random.Generator]) -> None:
        n = len(rngs)
        self.slots = NavigatorSlots(n)
        self.navigators = [Navigator(spec, motion, rng, slots=self.slots, row=i) for i, rng in enumerate(rngs)]
        self._consts = self.navigators[0].follower._consts if n else np.zeros(0)
        self._stuck_ticks = spec.stuck_ticks
        self._flags = np.zeros(n, dtype=np.int8)

    def command(self, rows: list[int], poses: np.ndarray, pose_tuples: list[Pose], known: np.ndarray,
                out: np.ndarray, began: np.ndarray | None = None, maps: TiledKnowledge | None = None) -> None:
        """``out[i] = navigators[i].command(pose_tuples[i], known[i])`` for every robot ``i`` in ``rows``
        (ascending); ``poses`` (float64[R, 3]) holds the same poses, ``known`` (uint8[R, H, W], C-contiguous)
        is the robots' maps, ``out`` (float64[R, 2]) has zero rows for them. ``began`` (contacts begun this
        tick) is for MAES's controller (:class:`swarm.navigation.maes_drive.MaesDriveFleet`); not used here.
        ``maps``: the maps as a :class:`swarm.knowledge.tiles.TiledKnowledge` (``known`` its stack): the
        corridor checks read the tiles, and a robot that plans gets its map copied out."""
        navs = self.navigators
        moving: list[int] = []
        python: list[int] = []  # planning: all of it in Python (other states command (0, 0))
        for i in rows:
            state = navs[i].state
            if state == "moving":
                moving.append(i)
            elif state == "planning":
                python.append(i)
        flags = self._flags
        if moving:
            s, f = self.slots, self.slots.followers
            width, tiles_w = (0, 0) if maps is None else (maps.layout.shape[1], maps.layout.tiles[1])
            if _fleet_step(np.array(moving, dtype=np.int64), known, width, tiles_w, s.corridors.buffer,
                           s.corridors.start,
                           s.corridors.end, f.paths.buffer, f.paths.start, f.paths.end, self._consts, f.index,
                           f.remaining, f.done, s.best_remaining, s.stalled, self._stuck_ticks, PROGRESS_M, poses,
                           out, flags):
                python = sorted(python + [i for i in moving if flags[i] != _STEPPED])  # robot order
        for i in python:
            nav = navs[i]
            flag = flags[i]
            if nav.state == "moving" and flag == _ARRIVED:
                nav.state = "reached"
                continue
            mine = known[i] if maps is None else maps.dense(i)  # (tiled maps: copied out for this robot)
            if nav.state == "planning":
                out[i] = nav.command(pose_tuples[i], mine)
            elif flag == _BLOCKED:
                out[i] = nav._plan_and_step(pose_tuples[i], mine)
            else:  # _STUCK
                nav._stuck(pose_tuples[i], mine)
                if nav.state != "moving":
                    out[i] = 0.0


_STEPPED, _BLOCKED, _ARRIVED, _STUCK = 0, 1, 2, 3


@njit(cache=True)
def _fleet_step(rows: np.ndarray, known: np.ndarray, width: int, tiles_w: int, cells: np.ndarray,
                cell_start: np.ndarray, cell_end: np.ndarray,
                paths: np.ndarray, path_start: np.ndarray, path_end: np.ndarray, consts: np.ndarray,
                index: np.ndarray, remaining: np.ndarray, done: np.ndarray, best: np.ndarray, stalled: np.ndarray,
                stuck_ticks: int, progress_m: float, poses: np.ndarray, out: np.ndarray,
                flags: np.ndarray) -> bool:  # pragma: no cover - compiled
    """For each moving robot ``k`` in ``rows``, what :meth:`Navigator.command` does up to the point where
    Python is needed, with the same operations: ``flags[k]`` = _BLOCKED when a corridor cell (robot k's
    ``cells[cell_start[k]:cell_end[k]]``) is SOLID (nothing changes); else the follower's step
    (the corridor check and :func:`swarm.world.motion._follow_step` as :meth:`~swarm.world.motion.Follower.command_unless`
    makes them, on its path table, state in ``index``/``remaining``/``done``) into
    ``out[k]``, then _ARRIVED (and (0, 0)) when the path is done, else the progress count (``best``,
    ``stalled``): _STUCK when it reaches ``stuck_ticks``, otherwise _STEPPED. Returns whether any robot
    was left to Python (not _STEPPED). ``tiles_w`` above 0: ``known`` is a tiled stack of maps ``width``
    cells wide (:mod:`swarm.knowledge.tiles`)."""
    size = np.uint64(known.size // known.shape[0])
    flat = known.ravel()  # a view of the C-contiguous maps
    left = False
    for t in range(rows.shape[0]):
        k = rows[t]
        base = np.uint64(k) * size
        if not (cells_below(flat, base, cells, cell_start[k], cell_end[k], SOLID) if tiles_w == 0 else
                cells_below_tiled(flat, base, cells, cell_start[k], cell_end[k], SOLID, width, tiles_w)):
            flags[k] = _BLOCKED
            left = True
            continue
        if done[k]:
            flags[k] = _ARRIVED
            left = True
            out[k, 0] = 0.0
            out[k, 1] = 0.0
            continue
        v, omega, idx, rem, finished = _follow_step(paths[path_start[k]:path_end[k]], consts, index[k], poses[k, 0],
                                                    poses[k, 1], poses[k, 2])
        index[k] = idx
        remaining[k] = rem
        done[k] = finished
        if finished:
            flags[k] = _ARRIVED
            left = True
            out[k, 0] = 0.0
            out[k, 1] = 0.0
            continue
        flags[k] = _STEPPED
        if rem < best[k] - progress_m:
            best[k] = rem
            stalled[k] = 0
        else:
            stalled[k] += 1
            if stalled[k] >= stuck_ticks:
                flags[k] = _STUCK
                left = True
        out[k, 0] = v
        out[k, 1] = omega
    return left


def _clip(cell: tuple[int, int], shape: tuple[int, int]) -> tuple[int, int]:
    return min(max(cell[0], 0), shape[0] - 1), min(max(cell[1], 0), shape[1] - 1)


def _inside(point: tuple[float, float], shape: tuple[int, int]) -> bool:
    return 0 <= point[0] < shape[1] * CELL_M and 0 <= point[1] < shape[0] * CELL_M


def _corridor(polyline: np.ndarray, known: np.ndarray) -> np.ndarray:
    """Cells the robot's disc sweeps along the polyline (sampled every 0.2 m, each sample's cell and its 4
    neighbours, the footprint :func:`swarm.grid.configuration_space` keeps clear) that are not SOLID now,
    as ascending flat indices: if one of them turns SOLID, the path must change."""
    poly = np.ascontiguousarray(polyline, dtype=np.float64)
    return _corridor_kernel(poly, known, CELL_M, 0.2)


_FOOTPRINT_DR = np.array([0, -1, 1, 0, 0])
_FOOTPRINT_DC = np.array([0, 0, 0, -1, 1])


@njit(cache=True, inline="always")
def _mark_footprint(x: float, y: float, known: np.ndarray, cell: float, mask: np.ndarray, r_lo: int,
                    c_lo: int) -> None:  # pragma: no cover - compiled
    """Mark in ``mask`` (the box of map cells from (r_lo, c_lo)) the non-SOLID cells of the footprint of
    point (x, y), clipped to the map."""
    h, w = known.shape
    r0 = int(np.floor(y / cell))
    c0 = int(np.floor(x / cell))
    for t in range(_FOOTPRINT_DR.shape[0]):
        r = min(max(r0 + _FOOTPRINT_DR[t], 0), h - 1)
        c = min(max(c0 + _FOOTPRINT_DC[t], 0), w - 1)
        if known[r, c] < SOLID:
            mask[r - r_lo, c - c_lo] = 1


@njit(cache=True)
def _corridor_kernel(poly: np.ndarray, known: np.ndarray, cell: float, spacing: float) -> np.ndarray:  # pragma: no cover
    """Distinct non-SOLID flat cells, ascending, of the footprints of the samples: the polyline's first
    point, then for each segment ``ceil(length / spacing)`` (at least 1) points at fractions k / steps,
    k = 1..steps. The cells are marked in a mask over the polyline's bounding box (two cells wider on
    every side than its vertices' cells: the footprint, and rounding of the samples), which is read
    row by row: ascending without a sort, and no map-sized mask to clear per plan."""
    h, w = known.shape
    n_seg = poly.shape[0] - 1
    x_lo, x_hi, y_lo, y_hi = poly[0, 0], poly[0, 0], poly[0, 1], poly[0, 1]
    for s in range(1, poly.shape[0]):
        x_lo, x_hi = min(x_lo, poly[s, 0]), max(x_hi, poly[s, 0])
        y_lo, y_hi = min(y_lo, poly[s, 1]), max(y_hi, poly[s, 1])
    r_lo = min(max(int(np.floor(y_lo / cell)) - 2, 0), h - 1)
    r_hi = min(max(int(np.floor(y_hi / cell)) + 2, 0), h - 1)
    c_lo = min(max(int(np.floor(x_lo / cell)) - 2, 0), w - 1)
    c_hi = min(max(int(np.floor(x_hi / cell)) + 2, 0), w - 1)
    mask = np.zeros((r_hi - r_lo + 1, c_hi - c_lo + 1), dtype=np.uint8)
    _mark_footprint(poly[0, 0], poly[0, 1], known, cell, mask, r_lo, c_lo)
    for s in range(n_seg):
        dx = poly[s + 1, 0] - poly[s, 0]
        dy = poly[s + 1, 1] - poly[s, 1]
        steps = max(1, int(np.ceil(np.hypot(dx, dy) / spacing)))
        for k in range(1, steps + 1):
            frac = k / steps
            _mark_footprint(poly[s, 0] + dx * frac, poly[s, 1] + dy * frac, known, cell, mask, r_lo, c_lo)
    out = np.empty(int(mask.sum()), dtype=np.int64)
    m = 0
    for r in range(mask.shape[0]):
        for c in range(mask.shape[1]):
            if mask[r, c]:
                out[m] = (r + r_lo) * w + c + c_lo
                m += 1
    return out
