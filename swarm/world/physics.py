"""The physical world: pymunk rigid bodies for robots, static boxes for walls, differential drive.

One :meth:`World.step` is one logic tick (0.1 s) made of ``MotionParams.substeps`` physics steps. Walls
are ``truth.wall_rectangles`` as static boxes rounded outward by :func:`wall_margin`, in pymunk's default
BB-tree index (never the spatial hash: docs/measurements.md B1); robots are dynamic discs.
Everything has friction 0, so a robot driven into a wall slides along it instead of sticking, and
contacts never exert torque on a disc.

How the drive works, and why this way. Chipmunk integrates *positions* at the start of a step with the
velocity the body has then, and only afterwards detects contacts and solves velocities. Writing the
commanded velocity into the body before each step would throw away the solver's contact correction and
push the robot into the wall by a full sub-step every sub-step (measured: robots driven into a wall sink
17 cm at 1 m/s and 30 cm at 3 m/s that way). Instead the space has ``damping = 0`` (a
body's velocity is forgotten at every step) and the drive sets a *force* and *torque* of ``m * v / dt``
and ``I * omega / dt``: after velocity integration the body moves exactly at the commanded velocity, the
contact solver removes whatever would enter a wall or another robot, and the next step integrates that
contact-consistent velocity. The price is a delay of one sub-step between command and motion, which the
heading computation accounts for, so that free motion is an exact circular arc.

Speed. Chipmunk's own ``cpSpaceStep`` should dominate a tick, so everything else is kept below it: the
forces for all sub-steps are computed by one numba kernel, written with ``pymunk.batch``'s C iterator (no
per-body attribute access, which costs more than the physics: docs/measurements.md B1), and poses are
read back once per tick (figures: ``benchmarks/speed/bench_world.py``, docs/performance-history.md).

Acceleration limits apply to the *wheel* speed, the world's internal drive state: a robot pressing
against a wall keeps its wheel speed (it slips), and reversing still ramps.
"""

from __future__ import annotations

import math
from typing import Any

import numba
import numpy as np
import pymunk
import pymunk.batch as batch
from scipy.spatial import cKDTree

from maps import CELL_M, Map
from swarm.base.errors import InvalidInput

from .motion import MAX_SUBSTEP_MOVE_M, MOTION_PRESETS, TICK_S, MotionParams

ROBOT_MASS_KG: float = 10.0
"""Mass of a robot. It does not change free motion (the drive sets velocities); between robots of equal
mass it makes a pushed robot share the pusher's momentum half and half."""
COLLISION_SLOP_M: float = 0.001
"""Overlap pymunk tolerates before pushing shapes apart (its default, 0.1, would be 10 cm here)."""
WALL_TYPE: int = 1
ROBOT_TYPE: int = 2

_DRIVE_FIELDS = batch.BodyFields.FORCE | batch.BodyFields.TORQUE
_POSE_FIELDS = batch.BodyFields.POSITION | batch.BodyFields.ANGLE


def wall_margin(params: MotionParams) -> float:
    """How far (m) the wall boxes are rounded outward: one sub-step's travel at top speed plus twice the
    slop (2.2 cm by default, 3.95 cm for the MAES preset).

    Contacts are discrete: a robot at full speed can sink into a wall by up to one sub-step's travel
    before the contact exists and pushes back. With the margin that sinking happens in the rounded
    skin, so the robot's true disc never overlaps a wall cell, which is what sensing, coverage and the
    tests see. The cost is that a robot stops (and reports a collision) up to the margin short of the
    raster wall. Passages are whole cells, so the narrowest one a 0.6 m robot can use is 1.0 m wide and
    keeps at least 1.0 - 0.6 - 2 * 0.05 = 0.3 m of slack.
    """
    return params.max_speed * params.substep_s + 2.0 * COLLISION_SLOP_M


class World:
    """Robots as pymunk discs in the walls of ``truth``.

    ``poses``: ``float64[R, 3]`` start poses (x, y in metres, heading in radians); every robot's disc must
    lie in free space and no two discs may overlap. After each :meth:`step`, :attr:`poses`,
    :attr:`collided`, :attr:`distance` and :attr:`rotation` describe the tick just simulated.
    """

    def __init__(self, truth: Map, poses: Any, params: MotionParams | None = None) -> None:
        self.truth = truth
        self.params = params if params is not None else MOTION_PRESETS["default"]
        start = _check_poses(truth, poses, self.params.radius)
        n = start.shape[0]
        self._n = n
        self._dt = self.params.substep_s
        self._space = space = pymunk.Space()
        space.gravity = (0.0, 0.0)
        space.damping = 0.0
        space.collision_slop = COLLISION_SLOP_M
        self.wall_margin = wall_margin(self.params)
        for k, rect in enumerate(truth.wall_rectangles):
            box = pymunk.Poly.create_box_bb(space.static_body, pymunk.BB(*rect.bounds_m),
                                            radius=self.wall_margin)
            box.friction = 0.0
            box.elasticity = 0.0
            box.collision_type = WALL_TYPE
            box.wall_index = k            # type: ignore[attr-defined]
            box.material = rect.material  # type: ignore[attr-defined]
            space.add(box)
        moment = pymunk.moment_for_circle(ROBOT_MASS_KG, 0.0, self.params.radius)
        self._bodies: list[pymunk.Body] = []
        for i in range(n):
            body = pymunk.Body(ROBOT_MASS_KG, moment)
            body.position = (float(start[i, 0]), float(start[i, 1]))
            body.angle = float(start[i, 2])
            disc = pymunk.Circle(body, self.params.radius)
            disc.friction = 0.0
            disc.elasticity = 0.0
            disc.collision_type = ROBOT_TYPE
            disc.robot_index = i          # type: ignore[attr-defined]
            space.add(body, disc)
            self._bodies.append(body)
        space.on_collision(ROBOT_TYPE, WALL_TYPE, begin=self._on_begin, separate=self._on_separate)
        space.on_collision(ROBOT_TYPE, ROBOT_TYPE, begin=self._on_begin, separate=self._on_separate)

        p = self.params
        self._limits = np.array([p.max_speed, p.max_turn_rate, p.max_accel * self._dt,
                                 p.max_turn_accel * self._dt, self._dt, ROBOT_MASS_KG / self._dt,
                                 moment / self._dt])
        self._contacts: set[tuple[int, int]] = set()   # (robot, other): other >= 0 robot, < 0 wall
        self._touching = np.zeros(n, dtype=np.int64)
        self._hit = np.zeros(n, dtype=bool)
        self._touching_kind = np.zeros((2, n), dtype=np.int64)   # open contacts: [0] with walls, [1] robots
        self._hit_kind = np.zeros((2, n), dtype=bool)
        self._disabled = np.zeros(n, dtype=bool)
        self._wheel_v = np.zeros(n)                    # drive state: last sub-step's commanded speeds
        self._wheel_w = np.zeros(n)
        self._angle = start[:, 2].copy()               # unwrapped body angles
        self._poses = start.copy()
        self._poses[:, 2] = _wrap(self._poses[:, 2])
        self._collided = np.zeros(n, dtype=bool)
        self._collided_kind = np.zeros((2, n), dtype=bool)
        self._distance = np.zeros(n)
        self._rotation = np.zeros(n)
        self._ticks = 0
        self._layout_rows()

    # ---------------------------------------------------------------------------------------- layout ----
    def _layout_rows(self) -> None:
        """Find where each robot sits in pymunk's body iteration order (the batch functions iterate every
        body, the static body included once it has shapes) and size the per-sub-step drive table."""
        order = _body_order(self._space)
        where = {body_id: row for row, body_id in enumerate(order)}
        self._rows = np.array([where[b.id] for b in self._bodies], dtype=np.intp)
        self._drive = np.zeros((self.params.substeps, len(order), 3), dtype=np.float64)
        self._io = _BatchIO(self._space, self._drive)

    # ------------------------------------------------------------------------------------ collisions ----
    def _pair(self, arbiter: pymunk.Arbiter) -> tuple[tuple[int, int], ...]:
        a, b = arbiter.shapes
        ia = getattr(a, "robot_index", None)
        ib = getattr(b, "robot_index", None)
        if ia is not None and ib is not None:
            return (ia, ib), (ib, ia)
        if ia is not None:
            return ((ia, -1 - b.wall_index),)
        return ((ib, -1 - a.wall_index),)

    def _on_begin(self, arbiter: pymunk.Arbiter, space: pymunk.Space, data: Any) -> None:
        for key in self._pair(arbiter):
            kind = int(key[1] >= 0)
            if key not in self._contacts:
                self._contacts.add(key)
                self._touching[key[0]] += 1
                self._touching_kind[kind, key[0]] += 1
            self._hit[key[0]] = True
            self._hit_kind[kind, key[0]] = True

    def _on_separate(self, arbiter: pymunk.Arbiter, space: pymunk.Space, data: Any) -> None:
        for key in self._pair(arbiter):
            if key in self._contacts:
                self._contacts.remove(key)
                self._touching[key[0]] -= 1
                self._touching_kind[int(key[1] >= 0), key[0]] -= 1

    # ------------------------------------------------------------------------------------------- step ----
    def step(self, commands: Any) -> None:
        """Advance one logic tick under ``commands``: ``float64[R, 2]`` of (v m/s forward, omega rad/s),
        clipped to the drive limits. Disabled robots ignore their command."""
        cmd = commands if type(commands) is np.ndarray and commands.dtype == np.float64 else \
            np.asarray(commands, dtype=np.float64)
        if cmd.shape != (self._n, 2):
            raise InvalidInput("commands", cmd.shape, f"an array of shape ({self._n}, 2): (v, omega) per robot")
        if not _drive_forces(cmd, self._disabled, self._wheel_v, self._wheel_w, self._angle, self._rows,
                             self._limits, self._drive, self._touching, self._hit):
            raise InvalidInput("commands", "non-finite values", "finite (v m/s, omega rad/s) per robot")
        np.greater(self._touching_kind, 0, out=self._hit_kind)
        self._io.drive(self._dt)
        state = self._io.read_poses()
        poses = np.empty_like(self._poses)
        distance = np.empty_like(self._distance)
        rotation = np.empty_like(self._rotation)
        _finish_tick(state, self._rows, self._angle, self._poses, self._distance, self._rotation,
                     poses, distance, rotation)
        self._poses, self._distance, self._rotation = poses, distance, rotation
        self._collided = self._hit.copy()
        self._collided_kind = self._hit_kind.copy()
        self._ticks += 1

    # ----------------------------------------------------------------------------------------- robots ----
    def disable(self, i: int) -> None:
        """Robot ``i``'s agent died: it stops at once and stays where it is as an immovable obstacle
        (a kinematic body at rest; other robots collide with it but cannot push it)."""
        if isinstance(i, bool) or not isinstance(i, (int, np.integer)) or not 0 <= i < self._n:
            raise InvalidInput("robot", i, f"a robot index in 0..{self._n - 1}")
        i = int(i)
        if self._disabled[i]:
            return
        body = self._bodies[i]
        body.body_type = pymunk.Body.KINEMATIC
        body.velocity = (0.0, 0.0)
        body.angular_velocity = 0.0
        self._disabled[i] = True
        self._wheel_v[i] = 0.0
        self._wheel_w[i] = 0.0
        self._layout_rows()

    # ------------------------------------------------------------------------------------------ state ----
    @property
    def n_robots(self) -> int:
        return self._n

    @property
    def ticks(self) -> int:
        """Number of :meth:`step` calls so far."""
        return self._ticks

    @property
    def poses(self) -> np.ndarray:
        """``float64[R, 3]`` (x, y, theta), theta in (-pi, pi]; read-only."""
        return _read_only(self._poses)

    @property
    def collided(self) -> np.ndarray:
        """``bool[R]``: touched a wall or another robot during the last tick (including a contact that
        lasted from the previous tick); read-only."""
        return _read_only(self._collided)

    @property
    def collided_with(self) -> np.ndarray:
        """``bool[2, R]``: :attr:`collided` split by what was touched, row 0 a wall, row 1 another robot
        (a robot touching both has both set); read-only."""
        return _read_only(self._collided_kind)

    @property
    def distance(self) -> np.ndarray:
        """``float64[R]`` metres each robot's centre has travelled since the start (being pushed counts);
        read-only."""
        return _read_only(self._distance)

    @property
    def rotation(self) -> np.ndarray:
        """``float64[R]`` radians turned (absolute) since the start; read-only."""
        return _read_only(self._rotation)

    @property
    def disabled(self) -> np.ndarray:
        """``bool[R]``: robots stopped by :meth:`disable`; read-only."""
        return _read_only(self._disabled)

    @property
    def space(self) -> pymunk.Space:
        """The pymunk space, for inspection and drawing. Do not step or edit it: :meth:`step` owns it."""
        return self._space

    @property
    def wall_count(self) -> int:
        """Number of static wall boxes in the space."""
        return len(self.truth.wall_rectangles)


# ------------------------------------------------------------------------------------- pymunk I/O ----
def _body_order(space: pymunk.Space) -> list[int]:
    """Body ids in the order pymunk's batch functions visit them."""
    ids = batch.Buffer()
    batch.get_space_bodies(space, batch.BodyFields.BODY_ID, ids)
    return np.frombuffer(ids.int_buf(), dtype=np.uintp).tolist()


class _BatchIO:
    """``pymunk.batch`` without its per-call overhead.

    ``batch.set_space_bodies`` allocates a cffi struct and reads an enum on every call (~5 us, more than
    the physics step), and ``Space.step`` re-checks bodies and deferred additions (~1.5 us). Here the
    structs are built once and the Chipmunk functions are called directly: one write of the drive table
    row and one ``cpSpaceStep`` per sub-step, one read of positions and angles per tick. This is safe
    because nothing here adds or removes shapes while stepping (the collision callbacks only record),
    which is all ``Space.step``'s extra work is for.
    """

    def __init__(self, space: pymunk.Space, drive: np.ndarray) -> None:
        ffi, lib = batch.ffi, batch.lib
        self._space = space
        self._cp_space = space._space
        self._step = lib.cpSpaceStep
        self._each_body = lib.cpSpaceEachBody
        self._set_fn = ffi.addressof(lib, "pmSpaceBodySetIteratorFuncBatched")
        self._get_fn = ffi.addressof(lib, "pmSpaceBodyGetIteratorFuncBatched")
        self._drive_bufs = []
        self._drive_data = []
        for k in range(drive.shape[0]):
            buf = batch.Buffer()
            buf.set_float_buf(drive[k])
            data = ffi.new("pmBatchedData *")
            data.fields = _DRIVE_FIELDS.value
            data.floatArray = buf._float_arr
            data.intArray = buf._int_arr
            self._drive_bufs.append(buf)
            self._drive_data.append((buf._float_arr, data))
        self._read = batch.Buffer()
        self._read_data = ffi.new("pmBatchedData *")
        self._read_data.fields = _POSE_FIELDS.value
        self._read_data.floatArray = self._read._float_arr
        self._read_data.intArray = self._read._int_arr

    def drive(self, dt: float) -> None:
        """Write each sub-step's forces and torques, then step the space once per sub-step."""
        cp_space, each, set_fn, step = self._cp_space, self._each_body, self._set_fn, self._step
        for array, data in self._drive_data:
            array.num = 0                    # the setter reads the table from the start
            each(cp_space, set_fn, data)
            step(cp_space, dt)

    def read_poses(self) -> np.ndarray:
        """Flat ``float64[3 * bodies]`` of (x, y, angle) in body iteration order: a view of pymunk's
        buffer, valid until the next read."""
        self._read._float_arr.num = 0
        self._read._int_arr.num = 0
        self._each_body(self._cp_space, self._get_fn, self._read_data)
        return np.frombuffer(self._read.float_buf(), dtype=np.float64)


# ----------------------------------------------------------------------------------------- kernels ----
@numba.njit(cache=True)
def _sinc(x: float) -> float:
    return 1.0 if x == 0.0 else math.sin(x) / x


@numba.njit(cache=True)
def _drive_forces(cmd: np.ndarray, disabled: np.ndarray, wheel_v: np.ndarray, wheel_w: np.ndarray,
                  angle: np.ndarray, rows: np.ndarray, limits: np.ndarray, out: np.ndarray,
                  touching: np.ndarray, hit: np.ndarray) -> bool:
    """Fill ``out[k, row] = (fx, fy, torque)`` for every sub-step k, update the wheel speeds in place and
    start the tick's contact flags from the contacts still open. ``limits`` = (v_max, w_max, dv, dw, dt,
    force scale m/dt, torque scale I/dt).

    Wheel speeds move toward the clipped command by at most ``dv`` / ``dw`` per sub-step. The velocity
    written in sub-step k moves the body during sub-step k+1 (see the module docstring), while its angle
    advances by ``dt * w_k`` from where the previous command left it; driving along the chord of that arc
    (midpoint heading, length times sinc) makes free motion an exact circular arc. Returns False (and
    changes nothing) if a command is not finite.
    """
    v_max, w_max, dv, dw, dt, force_scale, torque_scale = (limits[0], limits[1], limits[2], limits[3],
                                                            limits[4], limits[5], limits[6])
    n = cmd.shape[0]
    for i in range(n):
        if not (math.isfinite(cmd[i, 0]) and math.isfinite(cmd[i, 1])):
            return False
    for i in range(n):
        hit[i] = touching[i] > 0
        vc = min(max(cmd[i, 0], -v_max), v_max)
        wc = min(max(cmd[i, 1], -w_max), w_max)
        if disabled[i]:
            vc = 0.0
            wc = 0.0
        v = wheel_v[i]
        w = wheel_w[i]
        theta = angle[i] + dt * w
        row = rows[i]
        for k in range(out.shape[0]):
            v += min(max(vc - v, -dv), dv)
            w += min(max(wc - w, -dw), dw)
            half = 0.5 * dt * w
            speed = force_scale * v * _sinc(half)
            out[k, row, 0] = speed * math.cos(theta + half)
            out[k, row, 1] = speed * math.sin(theta + half)
            out[k, row, 2] = torque_scale * w
            theta += dt * w
        wheel_v[i] = v
        wheel_w[i] = w
    return True


@numba.njit(cache=True)
def _finish_tick(state: np.ndarray, rows: np.ndarray, angle: np.ndarray, old_poses: np.ndarray,
                 old_distance: np.ndarray, old_rotation: np.ndarray, poses: np.ndarray, distance: np.ndarray,
                 rotation: np.ndarray) -> None:
    """New poses (heading wrapped into (-pi, pi]), odometry, and the unwrapped angles (in place).

    Each tick's displacement counts as a constant-curvature arc with the tick's rotation: exact for free
    motion, the chord (within 0.7 %) for ticks with contacts."""
    two_pi = 2.0 * math.pi
    for i in range(rows.shape[0]):
        row = 3 * rows[i]
        x, y, a = state[row], state[row + 1], state[row + 2]
        turned = a - angle[i]
        moved = math.hypot(x - old_poses[i, 0], y - old_poses[i, 1])
        distance[i] = old_distance[i] + moved / _sinc(0.5 * turned)
        rotation[i] = old_rotation[i] + abs(turned)
        angle[i] = a
        poses[i, 0] = x
        poses[i, 1] = y
        poses[i, 2] = math.pi - (math.pi - a) % two_pi


# ------------------------------------------------------------------------------------------ helpers ----
def disc_hits_solid(solid: np.ndarray, x: float, y: float, radius: float) -> bool:
    """True when the open disc of ``radius`` around (x, y) overlaps a solid cell (or leaves the raster).
    Touching a cell's edge is not overlapping."""
    rows, cols = solid.shape
    c0, c1 = math.floor((x - radius) / CELL_M), math.floor((x + radius) / CELL_M)
    r0, r1 = math.floor((y - radius) / CELL_M), math.floor((y + radius) / CELL_M)
    if c0 < 0 or r0 < 0 or c1 >= cols or r1 >= rows:
        return True
    block = solid[r0:r1 + 1, c0:c1 + 1]
    if not block.any():
        return False
    cx = np.arange(c0, c1 + 1) * CELL_M
    cy = np.arange(r0, r1 + 1) * CELL_M
    dx = np.maximum(np.maximum(cx - x, 0.0), x - (cx + CELL_M))      # distance from x to each column
    dy = np.maximum(np.maximum(cy - y, 0.0), y - (cy + CELL_M))
    d2 = dy[:, None] ** 2 + dx[None, :] ** 2
    return bool((block & (d2 < radius * radius)).any())


def _check_poses(truth: Map, poses: Any, radius: float) -> np.ndarray:
    arr = np.array(poses, dtype=np.float64, copy=True)
    if arr.ndim != 2 or arr.shape[1] != 3 or arr.shape[0] < 1:
        raise InvalidInput("poses", getattr(arr, "shape", poses), "an array of shape (R, 3), R >= 1: x, y, theta")
    if not np.isfinite(arr).all():
        raise InvalidInput("poses", "non-finite values", "finite (x m, y m, theta rad) per robot")
    for i, (x, y, _) in enumerate(arr):
        if disc_hits_solid(truth.solid, x, y, radius):
            raise InvalidInput(f"poses[{i}]", (float(x), float(y)),
                               f"a position whose {radius:g} m disc lies in free space")
    close = _closest_overlap(arr[:, :2], 2.0 * radius * (1.0 - 1e-9))
    if close is not None:
        i, j, d = close
        raise InvalidInput(f"poses[{j}]", tuple(float(v) for v in arr[j, :2]),
                           f"a position at least {2 * radius:g} m from every other robot "
                           f"(robot {i} is {d:.3f} m away)")
    return arr


def _closest_overlap(xy: np.ndarray, limit: float) -> tuple[int, int, float] | None:
    """The closest pair of points ``(i, j, distance)``, ``i < j``, if it is closer than ``limit`` (ties: the
    smallest ``i``, then ``j``), else None. Candidates come from a k-d tree (a 10,000-robot swarm's all-pairs
    matrix would take 800 MB); their distances are ``numpy.hypot``'s, as the all-pairs check computed them."""
    if len(xy) < 2:
        return None
    pairs = cKDTree(xy).query_pairs(limit * (1.0 + 1e-6) + 1e-12, output_type="ndarray")
    if not len(pairs):
        return None
    pairs = np.sort(pairs, axis=1)
    d = np.hypot(xy[pairs[:, 0], 0] - xy[pairs[:, 1], 0], xy[pairs[:, 0], 1] - xy[pairs[:, 1], 1])
    best = np.flatnonzero(d == d.min())
    i, j = min((int(pairs[k, 0]), int(pairs[k, 1])) for k in best)
    dist = float(d[best[0]])
    return (i, j, dist) if dist < limit else None


def _wrap(angle: np.ndarray) -> np.ndarray:
    """Angles mapped into (-pi, pi]."""
    return np.pi - np.mod(np.pi - angle, 2.0 * np.pi)


def _read_only(a: np.ndarray) -> np.ndarray:
    view = a.view()
    view.flags.writeable = False
    return view


__all__ = ["COLLISION_SLOP_M", "MAX_SUBSTEP_MOVE_M", "MotionParams", "ROBOT_MASS_KG", "TICK_S", "World",
           "disc_hits_solid", "wall_margin"]
