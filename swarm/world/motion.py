"""Low-level motion: the drive limits of a robot (:class:`MotionParams`) and a waypoint follower that turns
a path into per-tick ``(v, omega)`` commands for :class:`swarm.world.physics.World`.

The follower is a pure function of the pose it is given and the path it holds, so it behaves the same
whether the pose comes from ground truth or from an estimate. It knows the drive limits, so it brakes
early enough for the world's acceleration limit to stop the robot where it should stop, and it never
asks for more than the world will deliver. The per-tick command is one compiled call on scalars (it
runs once per robot per tick; docs/performance-history.md has its cost) that performs the same float
operations in the same order as the Python formulas it replaced (bend speed, braking limit, turn rate,
:func:`wrap_angle`), with CPython's own ``hypot`` (:mod:`swarm.util.pymath`), so runs are bit for bit what they
were; ``tests/swarm/world/test_motion.py`` keeps those formulas in Python as the reference.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np
from numba import njit

from swarm.base.errors import InvalidInput
from swarm.base.params import OMIT_DEFAULT, check_choice, check_float, check_int

from swarm.util.arena import Arena
from swarm.util.pymath import py_hypot

TICK_S: float = 0.1
"""One logic tick of simulated time (docs/design.md section 3)."""
MAX_SUBSTEP_MOVE_M: float = 0.05
"""The most a robot may travel in one physics sub-step: a tenth of the thinnest wall (one 0.5 m cell).
Contacts are discrete, so a robot can overlap a wall by up to one sub-step's travel before the contact
pushes it back; keeping that far below the wall thickness is what makes tunnelling impossible."""
DEFAULT_SUBSTEPS: int = 5
"""Physics sub-steps per tick at the default speed (more only where ``max_speed`` needs them)."""


MOTION_MODELS: tuple[str, ...] = ("continuous", "maes")
"""How a robot drives to its goal (:attr:`MotionParams.model`)."""


@dataclass(frozen=True)
class MotionParams:
    """Drive limits of one differential-drive robot and the physics sub-stepping of the world.

    Defaults describe a real indoor robot of the 0.6 m diameter class rather than MAES's robot:

    - ``max_speed = 1.0`` m/s: between the TurtleBot 2 / Kobuki (0.7 m/s spec; its velocity smoother
      defaults to 0.8 m/s) and the Pioneer 3-DX (1.2 m/s), well below the outdoor Clearpath Jackal
      (2.0 m/s, ``jackal_control/config/control.yaml``). Indoors, with lidar SLAM on board, 1 m/s is a
      brisk but honest top speed.
    - ``max_turn_rate = 2.0`` rad/s (115 deg/s): turning in place at 2 rad/s needs 0.5 m/s at the wheels
      of a ~0.5 m track, half the driving top speed; Kobuki is specified at 180 deg/s, the Pioneer at
      300 deg/s, but scan matching smears above ~2 rad/s. It is also ``swarm.api.RobotInfo``'s default.
    - ``max_accel = 1.0`` m/s^2: Kobuki's smoother default (``accel_lim_v: 1.0``, "maximum is actually
      2.0, but we push it down to be smooth"); Jackal's controller allows 20 m/s^2, which a loaded
      robot on a smooth floor cannot transmit without wheel slip.
    - ``max_turn_accel = 4.0`` rad/s^2: the same 1 m/s^2 at the wheels of a ~0.5 m track
      (alpha = a / (track / 2)).
    - ``substeps = 5``: physics at 50 Hz moves a robot at most 2 cm per sub-step (see
      :data:`MAX_SUBSTEP_MOVE_M`). Free motion is integrated exactly whatever the sub-step (see
      :mod:`swarm.world.physics`), so sub-steps only refine contacts; each costs ~6 us per tick for 16 robots.
      Left out (None), it is the larger of 5 and the fewest that keep a sub-step's travel within
      :data:`MAX_SUBSTEP_MOVE_M` at ``max_speed`` (6 at 3 m/s), so ``max_speed = 3`` needs no
      ``substeps``; after construction it always holds the number used.

    MAES robots are much faster (about 3 tiles/s and 4 rad/s, reached within ~0.1 s); use
    :meth:`maes` for parity campaigns.

    ``model`` says how a goal is driven to. ``"continuous"`` (the default): the navigator plans on the
    robot's configuration space, shortcuts the path into straight segments and follows it without
    stopping at bends under 40 degrees (:class:`Follower`). ``"maes"``: MAES's controller
    (``Robot2DController.cs``, :mod:`swarm.navigation.maes_drive`): 1 m tiles one at a time, turning in
    place and stopping at each, or one straight move, as the algorithm's ``Action.drive`` asks.
    """

    max_speed: float = 1.0
    max_turn_rate: float = 2.0
    max_accel: float = 1.0
    max_turn_accel: float = 4.0
    radius: float = 0.3
    substeps: int | None = None
    model: str = field(default="continuous", metadata={OMIT_DEFAULT: True})

    def __post_init__(self) -> None:
        check_choice("model", self.model, MOTION_MODELS)
        check_float("max_speed", self.max_speed, 0.0, 10.0, lo_open=True)
        check_float("max_turn_rate", self.max_turn_rate, 0.0, 20.0, lo_open=True)
        check_float("max_accel", self.max_accel, 0.0, 1000.0, lo_open=True)
        check_float("max_turn_accel", self.max_turn_accel, 0.0, 1000.0, lo_open=True)
        check_float("radius", self.radius, 0.05, 1.0)
        needed = math.ceil(self.max_speed * TICK_S / MAX_SUBSTEP_MOVE_M - 1e-9)
        if self.substeps is None:
            object.__setattr__(self, "substeps", max(DEFAULT_SUBSTEPS, needed))
        check_int("substeps", self.substeps, 1, 1000)
        if self.substeps < needed:
            raise InvalidInput("substeps", self.substeps,
                               f"an integer >= {needed} (at max_speed {self.max_speed:g} m/s a physics "
                               f"sub-step may move at most {MAX_SUBSTEP_MOVE_M:g} m)")

    @property
    def substep_s(self) -> float:
        """Physics time step in seconds."""
        return TICK_S / self.substeps

    @classmethod
    def maes(cls) -> "MotionParams":
        """MAES-like drive for parity campaigns (docs/maes.md section 4.1): terminal speeds of
        3.0 tiles/s and 4.0 rad/s, and MAES's *initial* accelerations (force/mass = 60 m/s^2 with linear
        drag 20, i.e. 3.0 * 20; 4.0 * 30 = 120 rad/s^2 with angular drag 30). MAES approaches its
        terminal speed exponentially (63 % after ~55 ms); here the ramp is linear and done in 50 ms,
        so MAES robots cover a few centimetres less per start. Eight sub-steps (12.5 ms, close to MAES's
        10 ms physics step) keep a sub-step's travel at 3.75 cm; free motion is an exact arc whatever
        the sub-step, so more would only refine contacts, at ~6 us per sub-step."""
        return cls(max_speed=3.0, max_turn_rate=4.0, max_accel=60.0, max_turn_accel=120.0,
                   radius=0.3, substeps=8)


MOTION_PRESETS: dict[str, MotionParams] = {"default": MotionParams(), "maes": MotionParams.maes()}
"""Named drive parameter sets."""


@dataclass(frozen=True)
class FollowParams:
    """Tuning of :class:`Follower`. The defaults work for both :class:`MotionParams` presets.

    - ``rotate_above``: heading error (rad) above which the robot stops and turns in place; below it,
      it drives at ``cos(error)`` of its speed while correcting. 0.7 rad (40 deg) lets the robot take
      the 45-degree bends of grid paths without stopping.
    - ``switch_radius``: a waypoint counts as passed within this distance (m); the last one never does.
    - ``arrive_radius``: the path is done when the robot is this close (m) to the last waypoint. The
      residual speed then (``gain * arrive_radius``) stops within a few mm, inside the 0.05 m promise.
    - ``reverse_radius``: within this distance of the last waypoint the robot backs up instead of
      turning around when it has overshot.
    - ``heading_tolerance``: :meth:`Follower.turn_to` is satisfied within this error (rad).
    - ``gain``: proportional gain (1/s) of the final approach, linear and angular.
    """

    rotate_above: float = 0.7
    switch_radius: float = 0.2
    arrive_radius: float = 0.02
    reverse_radius: float = 0.15
    heading_tolerance: float = 0.002
    gain: float = 4.0

    def __post_init__(self) -> None:
        check_float("rotate_above", self.rotate_above, 0.05, math.pi / 2)
        check_float("switch_radius", self.switch_radius, 0.01, 2.0)
        check_float("arrive_radius", self.arrive_radius, 0.001, 0.05)
        check_float("reverse_radius", self.reverse_radius, 0.0, 1.0)
        check_float("heading_tolerance", self.heading_tolerance, 1e-5, 0.1)
        check_float("gain", self.gain, 0.1, 1.0 / TICK_S)


def wrap_angle(angle: float) -> float:
    """``angle`` mapped into (-pi, pi]."""
    return math.pi - (math.pi - angle) % (2.0 * math.pi)


class FollowerSlots:
    """The changing state of ``n`` followers, a row each: the waypoint each heads for, the path length still
    to drive, whether it is done, and its path table (an :class:`~swarm.util.arena.Arena` row). In arrays, so
    that one compiled call can step many followers (:class:`swarm.navigation.navigator.NavigationFleet`); a lone
    :class:`Follower` has a table of one."""

    def __init__(self, n: int) -> None:
        self.index = np.zeros(n, dtype=np.int64)
        self.remaining = np.zeros(n, dtype=np.float64)
        self.done = np.ones(n, dtype=np.bool_)
        self.paths = Arena(n, np.float64, (5,))


class Follower:
    """Follows a polyline of waypoints: rotate in place when the heading error is large, otherwise drive
    with heading correction; brake for sharp bends and for the last waypoint so that it ends within
    ``arrive_radius`` of it.

    Speeds are planned with half the drive's acceleration (``sqrt(2 * a/2 * d)``) so the world's
    acceleration limit can always honour them, and switch to a proportional law (``gain * d``) near the
    end so the robot converges without overshoot despite commands changing only once per tick.
    """

    def __init__(self, params: MotionParams, follow: FollowParams | None = None, *,
                 slots: FollowerSlots | None = None, row: int = 0) -> None:
        """``slots``/``row``: keep the state in row ``row`` of a fleet's :class:`FollowerSlots` (default: a
        table of one of its own)."""
        self.params = params
        self.follow = follow if follow is not None else FollowParams()
        self._slots = slots if slots is not None else FollowerSlots(1)
        self._row = row
        # Constants of the per-tick arithmetic, computed once with the same operations as in the formulas
        # (braking at half the acceleration); the parameters are frozen, so they hold for the follower's life.
        two_brake = 2.0 * (0.5 * params.max_accel)
        horizon = params.max_speed * params.max_speed / (2.0 * (0.5 * params.max_accel))
        f = self.follow
        self._consts = np.array([params.max_speed, params.max_turn_rate, params.max_turn_accel, two_brake, horizon,
                                 f.switch_radius, f.arrive_radius, f.reverse_radius, f.rotate_above, f.gain])

    # ------------------------------------------------------------------------------------------ path ----
    def set_path(self, waypoints: Any) -> None:
        """Follow ``waypoints`` (``float[M, 2]`` in metres, M >= 1) from the first one on."""
        try:
            pts = np.asarray(waypoints, dtype=np.float64)
        except (TypeError, ValueError):
            raise InvalidInput("waypoints", waypoints, "an array of shape (M, 2), M >= 1") from None
        if pts.ndim != 2 or pts.shape[0] < 1 or pts.shape[1] != 2:
            raise InvalidInput("waypoints", getattr(pts, "shape", waypoints), "an array of shape (M, 2), M >= 1")
        table = _path_table(np.ascontiguousarray(pts), self._consts)
        if table.shape[0] == 0:  # the table's kernel checks the coordinates (a numpy pass cost more)
            raise InvalidInput("waypoints", "non-finite values", "finite coordinates in metres")
        s, r = self._slots, self._row
        s.paths.put(r, table)
        s.index[r] = 0
        s.done[r] = False
        s.remaining[r] = table[0, 2]

    def clear(self) -> None:
        """Forget the path; :meth:`command` returns (0, 0) until the next :meth:`set_path`."""
        s, r = self._slots, self._row
        s.paths.put(r, _NO_PATH)
        s.done[r] = True
        s.remaining[r] = 0.0

    @property
    def done(self) -> bool:
        """True when there is no path or the last waypoint has been reached."""
        return bool(self._slots.done[self._row])

    @property
    def remaining_m(self) -> float:
        """Path length still to drive, measured from the pose of the last :meth:`command` (before the
        first command: from the first waypoint)."""
        s, r = self._slots, self._row
        return 0.0 if s.done[r] else float(s.remaining[r])

    @property
    def index(self) -> int:
        """Index of the waypoint the robot is heading for."""
        return int(self._slots.index[self._row])

    @property
    def path_table(self) -> np.ndarray:
        """Per waypoint: x, y, path length from it to the end, heading of the segment leaving it (NaN for
        the last and zero-length ones), corner speed (read-only use)."""
        return self._slots.paths.get(self._row)

    @property
    def waypoints(self) -> tuple[tuple[float, float], ...]:
        return tuple(map(tuple, self.path_table[:, :2].tolist()))

    # --------------------------------------------------------------------------------------- control ----
    def command(self, pose: Sequence[float]) -> tuple[float, float]:
        """The ``(v, omega)`` command for this tick from ``pose`` = (x, y, theta): advance past waypoints
        within ``switch_radius``, turn in place while the heading error exceeds ``rotate_above``, else
        drive at the braking limit of the bends ahead (:func:`_follow_step`, compiled;
        ``tests/swarm/world/test_motion.py`` checks it against the plain Python formulas bit for bit)."""
        s, r = self._slots, self._row
        if s.done[r]:
            return 0.0, 0.0
        v, omega, s.index[r], s.remaining[r], s.done[r] = _follow_step(
            s.paths.get(r), self._consts, int(s.index[r]), float(pose[0]), float(pose[1]), float(pose[2]))
        return v, omega

    def command_unless(self, grid: np.ndarray, cells: np.ndarray, limit: int,
                       pose: Sequence[float]) -> tuple[float, float] | None:
        """:meth:`command`, unless one of ``cells`` (flat indices into ``grid``, ``uint8[H, W]``) holds a
        value ``>= limit``: then None, and nothing changes. One compiled call for both, since a caller that
        must check its path's cells every tick before following the path (the navigator) would otherwise
        pay for two calls per robot per tick."""
        s, r = self._slots, self._row
        clear, v, omega, index, remaining, done = _follow_step_unless(
            grid, cells, limit, s.paths.get(r), self._consts, int(s.index[r]), float(s.remaining[r]), bool(s.done[r]),
            float(pose[0]), float(pose[1]), float(pose[2]))
        if not clear:
            return None
        s.index[r], s.remaining[r], s.done[r] = index, remaining, done
        return v, omega

    def turn_to(self, pose: Sequence[float], heading: float) -> tuple[float, float]:
        """A pure rotation toward ``heading`` (rad); (0, 0) once within ``heading_tolerance``."""
        err = wrap_angle(float(heading) - float(pose[2]))
        if abs(err) <= self.follow.heading_tolerance:
            return 0.0, 0.0
        return 0.0, _turn_rate(err, self._consts)


_TWO_PI = 2.0 * math.pi
_HALF_PI = math.pi / 2
_NO_PATH = np.zeros((0, 5), dtype=np.float64)


@njit(cache=True, inline="always")
def _wrap(angle: float) -> float:  # pragma: no cover - compiled
    """:func:`wrap_angle` in compiled code (the same operations)."""
    return math.pi - (math.pi - angle) % _TWO_PI


@njit(cache=True, inline="always")
def _turn_rate(err: float, consts: np.ndarray) -> float:  # pragma: no cover - compiled
    """Angular rate toward a heading error ``err`` that brakes at half the angular acceleration and lands
    on the target: the proportional term takes over near zero, with a floor of ``min(0.05 rad/s,
    err/tick)`` so the last fraction of a degree does not take seconds (and small enough that stopping
    from it turns less than the tolerance)."""
    max_turn_rate, max_turn_accel, gain = consts[1], consts[2], consts[9]
    mag = abs(err)
    rate = min(max_turn_rate, math.sqrt(max_turn_accel * mag), gain * mag)
    return math.copysign(min(max(rate, min(0.05, mag / TICK_S)), max_turn_rate), err)


@njit(cache=True, inline="always")
def _bend_speed(path: np.ndarray, i: int, px: float, py: float, consts: np.ndarray) -> float:  # pragma: no cover
    """Speed allowed when passing waypoint ``i`` (not the last) coming from (px, py): ``max_speed *
    cos(bend)``, zero for bends the robot must take by turning in place."""
    max_speed, rotate_above = consts[0], consts[8]
    ax = path[i, 0] - px
    ay = path[i, 1] - py
    out = path[i, 3]
    if (ax == 0.0 and ay == 0.0) or math.isnan(out):  # no bend at a zero-length segment
        return max_speed
    bend = abs(_wrap(out - math.atan2(ay, ax)))
    return 0.0 if bend > rotate_above else max_speed * math.cos(bend)


@njit(cache=True)
def _path_table(pts: np.ndarray, consts: np.ndarray) -> np.ndarray:  # pragma: no cover - compiled
    """The follower's table of ``pts`` (float64[M, 2], M >= 1): per waypoint x, y, the path length from it
    to the end (``math.dist`` summed from the end), the heading of the segment leaving it (NaN for the last
    and for zero-length segments) and its corner speed (the first: top speed, the last: 0). An empty table
    when a coordinate is not finite."""
    m = pts.shape[0]
    for i in range(m):
        if not (math.isfinite(pts[i, 0]) and math.isfinite(pts[i, 1])):
            return np.empty((0, 5), dtype=np.float64)
    path = np.empty((m, 5), dtype=np.float64)
    for i in range(m):  # not path[:, :2] = pts: a slice copy links numba's shape-error formatting
        path[i, 0] = pts[i, 0]
        path[i, 1] = pts[i, 1]
    path[m - 1, 2] = 0.0
    for i in range(m - 2, -1, -1):
        path[i, 2] = path[i + 1, 2] + py_hypot(pts[i, 0] - pts[i + 1, 0], pts[i, 1] - pts[i + 1, 1])
    for i in range(m):
        bx = pts[i + 1, 0] - pts[i, 0] if i < m - 1 else 0.0
        by = pts[i + 1, 1] - pts[i, 1] if i < m - 1 else 0.0
        path[i, 3] = math.nan if bx == 0.0 and by == 0.0 else math.atan2(by, bx)
    path[0, 4] = consts[0]
    for i in range(1, m - 1):
        path[i, 4] = _bend_speed(path, i, pts[i - 1, 0], pts[i - 1, 1], consts)
    path[m - 1, 4] = 0.0
    return path


@njit(cache=True)
def _follow_step(path: np.ndarray, consts: np.ndarray, index: int, x: float, y: float,
                 theta: float) -> tuple[float, float, int, float, bool]:  # pragma: no cover - compiled
    """One tick of :meth:`Follower.command`: ``(v, omega, index, remaining, done)``. ``path`` rows are
    (x, y, suffix length, heading of the segment leaving the waypoint or NaN, corner speed); ``consts``
    as built in :class:`Follower`. The braking limit looks ahead as far as braking from top speed takes,
    with the bend at the waypoint the robot heads for measured from the robot's position;
    ``math.dist`` / ``math.hypot`` are CPython's (:func:`swarm.util.pymath.py_hypot`)."""
    max_speed, two_brake, horizon, switch_radius, arrive_radius = consts[0], consts[3], consts[4], consts[5], consts[6]
    reverse_radius, rotate_above, gain = consts[7], consts[8], consts[9]
    last = path.shape[0] - 1
    while index < last and py_hypot(x - path[index, 0], y - path[index, 1]) < switch_radius:
        index += 1
    tx = path[index, 0]
    ty = path[index, 1]
    d = py_hypot(tx - x, ty - y)
    remaining = d + path[index, 2]
    if index == last and d <= arrive_radius:
        return 0.0, 0.0, index, 0.0, True
    err = _wrap(math.atan2(ty - y, tx - x) - theta)
    direction = 1.0
    if index == last and d < reverse_radius and abs(err) > _HALF_PI:
        direction = -1.0                      # small overshoot: back up rather than turn around
        err = _wrap(err - math.pi)
    omega = _turn_rate(err, consts)
    if abs(err) > rotate_above:
        return 0.0, omega, index, remaining, False
    limit = max_speed                         # braking limit for every bend within the horizon
    dist = d
    i = index
    while True:
        if i == last:
            limit = min(limit, math.sqrt(two_brake * dist), max(gain * dist, min(0.05, dist / TICK_S)))
            break
        vc = path[i, 4] if i != index else _bend_speed(path, i, x, y, consts)  # the next bend: from here
        limit = min(limit, math.sqrt(vc * vc + two_brake * dist))
        if dist > horizon:
            break
        dist += path[i, 2] - path[i + 1, 2]
        i += 1
    return direction * limit * math.cos(err), omega, index, remaining, False


@njit(cache=True, inline="always")
def cells_below(flat: np.ndarray, base: np.uint64, cells: np.ndarray, lo: int, hi: int,
                limit: int) -> bool:  # pragma: no cover - compiled
    """Whether ``flat[base + cells[i]] < limit`` for every i in ``lo:hi`` (the corridor check of
    :meth:`Follower.command_unless` and of the navigation fleet's step, on unsigned indices)."""
    for i in range(lo, hi):
        if flat[base + np.uint64(cells[i])] >= limit:
            return False
    return True


@njit(cache=True)
def _follow_step_unless(grid: np.ndarray, cells: np.ndarray, limit: int, path: np.ndarray, consts: np.ndarray,
                        index: int, remaining: float, done: bool, x: float, y: float,
                        theta: float) -> tuple[bool, float, float, int, float, bool]:  # pragma: no cover - compiled
    """:func:`_follow_step` behind the check of :meth:`Follower.command_unless`: ``(clear, v, omega, index,
    remaining, done)``, the follower's state unchanged when not clear or already ``done`` (then (0, 0))."""
    if not cells_below(grid.ravel(), np.uint64(0), cells, 0, cells.shape[0], limit):  # ravel: a view if C-contiguous
        return False, 0.0, 0.0, index, remaining, done
    if done:
        return True, 0.0, 0.0, index, remaining, done
    v, omega, index, remaining, done = _follow_step(path, consts, index, x, y, theta)
    return True, v, omega, index, remaining, done


__all__ = ["FollowParams", "Follower", "FollowerSlots", "MAX_SUBSTEP_MOVE_M", "MOTION_MODELS", "MOTION_PRESETS", "MotionParams",
           "TICK_S", "wrap_angle"]
