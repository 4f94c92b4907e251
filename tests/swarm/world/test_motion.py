"""swarm.world.motion: the waypoint follower drives the world's robots where they should go (MAES's motion tests:
moves of 1-10 m within 0.1 m, rotations within 1 degree) and follows paths without touching walls."""

from __future__ import annotations

import math

import numpy as np
import pytest

from maps import Map
from swarm.base.errors import InvalidInput
from swarm.world.motion import MOTION_PRESETS, TICK_S, FollowParams, Follower, MotionParams, wrap_angle
from swarm.world.physics import World, disc_hits_solid

PRESETS = [pytest.param(MOTION_PRESETS["default"], id="default"), pytest.param(MOTION_PRESETS["maes"], id="maes")]
SETTLE_TICKS = 10


def open_room(width_cells: int = 60, height_cells: int = 60) -> Map:
    solid = np.ones((height_cells, width_cells), dtype=bool)
    solid[1:-1, 1:-1] = False
    return Map(solid=solid, material=solid.astype(np.uint8), materials=("air", "concrete"))


def follow(world: World, follower: Follower, max_ticks: int = 2000) -> int:
    """Drive robot 0 until the follower is done, then let it settle with zero commands."""
    ticks = 0
    while not follower.done:
        assert ticks < max_ticks, "follower never finished"
        v, w = follower.command(world.poses[0])
        world.step([[v, w]])
        ticks += 1
    for _ in range(SETTLE_TICKS):
        world.step([[0.0, 0.0]])
    return ticks


def angle_error(a: float, b: float) -> float:
    return abs(wrap_angle(a - b))


# ------------------------------------------------------------------------------ the MAES motion tests ----
@pytest.mark.parametrize("params", PRESETS)
@pytest.mark.parametrize("heading", [0.0, 2.3, -1.9])
@pytest.mark.parametrize("distance", [1.0, 2.0, 5.0, 10.0])
def test_straight_move_ends_within_a_tenth_of_a_metre(params: MotionParams, heading: float,
                                                      distance: float) -> None:
    start = np.array([15.0, 15.0])
    target = start + distance * np.array([math.cos(heading), math.sin(heading)])
    world = World(open_room(), [[*start, heading]], params)
    follower = Follower(params)
    follower.set_path([target])
    follow(world, follower)
    x, y, theta = world.poses[0]
    assert math.hypot(x - target[0], y - target[1]) <= 0.05        # the follower's promise (MAES: 0.1)
    assert angle_error(theta, heading) < math.radians(1.0)          # it drove straight
    assert world.distance[0] == pytest.approx(distance, abs=0.05)
    assert not world.collided[0]


@pytest.mark.parametrize("params", PRESETS)
@pytest.mark.parametrize("degrees", [1, -1, 2, 5, 10, 20, -20, 90, 180, -180])
def test_rotation_ends_within_one_degree(params: MotionParams, degrees: int) -> None:
    start_heading = 0.4
    target = start_heading + math.radians(degrees)
    world = World(open_room(20, 20), [[5.0, 5.0, start_heading]], params)
    follower = Follower(params)
    for _ in range(200):
        v, w = follower.turn_to(world.poses[0], target)
        assert v == 0.0
        if w == 0.0:
            break
        world.step([[v, w]])
    else:
        pytest.fail("turn_to never finished")
    for _ in range(SETTLE_TICKS):
        world.step([[0.0, 0.0]])
    assert angle_error(world.poses[0, 2], target) < math.radians(1.0)
    assert world.poses[0, 0] == 5.0 and world.poses[0, 1] == 5.0      # turned in place


# ---------------------------------------------------------------------------------------- paths ----
def l_corridor() -> Map:
    """A 1.5 m wide corridor: east along y = 2.75, then north along x = 14.25."""
    solid = np.ones((40, 40), dtype=bool)
    solid[4:7, 2:30] = False
    solid[4:30, 27:30] = False
    return Map(solid=solid, material=solid.astype(np.uint8), materials=("air", "concrete"))


@pytest.mark.parametrize("params", PRESETS)
def test_follows_a_corridor_around_a_corner_without_touching_walls(params: MotionParams) -> None:
    truth = l_corridor()
    path = [[3.0, 2.75], [6.0, 2.75], [10.0, 2.75], [14.25, 2.75], [14.25, 8.0], [14.25, 14.0]]
    world = World(truth, [[1.75, 2.75, 0.0]], params)
    follower = Follower(params)
    follower.set_path(path)
    remaining = [follower.remaining_m]
    while not follower.done:
        assert world.ticks < 1000
        v, w = follower.command(world.poses[0])
        assert abs(v) <= params.max_speed and abs(w) <= params.max_turn_rate
        remaining.append(follower.remaining_m)
        world.step([[v, w]])
        x, y, _ = world.poses[0]
        assert not world.collided[0]
        assert not disc_hits_solid(truth.solid, x, y, params.radius)
    assert remaining[0] == pytest.approx(11.25 + 11.25)
    assert remaining[-1] == 0.0 and follower.remaining_m == 0.0
    assert all(b <= a + 1e-9 for a, b in zip(remaining[1:], remaining[2:]))   # never moves away
    assert math.hypot(*(world.poses[0, :2] - path[-1])) <= 0.05
    # it does not crawl: the ideal time at top speed plus a few seconds for ramps and the corner
    assert world.ticks < (22.5 / params.max_speed) * 10 + 60


def test_waypoint_behind_the_robot_turns_it_around() -> None:
    params = MotionParams()
    world = World(open_room(), [[10.0, 10.0, 0.0]], params)
    follower = Follower(params)
    follower.set_path([[7.0, 10.0], [7.0, 13.0]])
    v, w = follower.command(world.poses[0])
    assert v == 0.0 and w > 0.0                                     # turns in place first
    follow(world, follower)
    assert math.hypot(world.poses[0, 0] - 7.0, world.poses[0, 1] - 13.0) <= 0.05


def test_small_overshoot_is_corrected_by_backing_up() -> None:
    params = MotionParams()
    follower = Follower(params)
    follower.set_path([[5.0, 5.0]])
    v, w = follower.command((5.1, 5.0, 0.0))                        # 10 cm past, facing away
    assert v < 0.0
    world = World(open_room(20, 20), [[5.1, 5.0, 0.0]], params)
    follow(world, follower)
    assert math.hypot(world.poses[0, 0] - 5.0, world.poses[0, 1] - 5.0) <= 0.05
    assert angle_error(world.poses[0, 2], 0.0) < 0.01              # it did not turn around


def test_waypoints_switch_when_close() -> None:
    follower = Follower(MotionParams())
    follower.set_path([[1.0, 0.0], [2.0, 0.0], [2.0, 1.0]])
    follower.command((0.0, 0.0, 0.0))
    assert follower.index == 0
    follower.command((0.85, 0.0, 0.0))
    assert follower.index == 1
    assert follower.remaining_m == pytest.approx(1.15 + 1.0)
    follower.command((1.9, 0.1, math.pi / 2))
    assert follower.index == 2 and not follower.done
    assert follower.remaining_m == pytest.approx(math.hypot(0.1, 0.9))


def test_brakes_before_a_sharp_bend_but_not_before_a_gentle_one() -> None:
    params = MotionParams()
    sharp, gentle = Follower(params), Follower(params)
    sharp.set_path([[0.0, 0.0], [2.0, 0.0], [2.0, 2.0]])            # 90 degrees
    gentle.set_path([[0.0, 0.0], [2.0, 0.0], [4.0, 0.2]])           # ~6 degrees
    pose = (1.7, 0.0, 0.0)
    sharp.command((0.1, 0.0, 0.0))
    gentle.command((0.1, 0.0, 0.0))
    v_sharp, _ = sharp.command(pose)
    v_gentle, _ = gentle.command(pose)
    assert v_sharp < 0.6 < v_gentle


def test_idle_follower_and_clear() -> None:
    follower = Follower(MotionParams())
    assert follower.done and follower.remaining_m == 0.0
    assert follower.command((1.0, 2.0, 0.3)) == (0.0, 0.0)
    follower.set_path(np.array([[3.0, 4.0], [3.0, 6.0]]))
    assert not follower.done and follower.remaining_m == pytest.approx(2.0)
    follower.clear()
    assert follower.done and follower.command((1.0, 2.0, 0.3)) == (0.0, 0.0)


def test_turn_to_is_done_within_tolerance() -> None:
    follower = Follower(MotionParams())
    assert follower.turn_to((0.0, 0.0, 1.0), 1.0 + 0.001) == (0.0, 0.0)
    v, w = follower.turn_to((0.0, 0.0, 1.0), 1.0 - 0.5)
    assert v == 0.0 and w < 0.0
    _, w = follower.turn_to((0.0, 0.0, 3.0), -3.0)                  # the short way round, across pi
    assert w > 0.0


@pytest.mark.parametrize("waypoints", [[], [1.0, 2.0], [[1.0, 2.0, 3.0]], [[1.0, float("nan")]], "ab"])
def test_bad_paths_are_refused(waypoints: object) -> None:
    with pytest.raises(InvalidInput) as err:
        Follower(MotionParams()).set_path(waypoints)
    assert err.value.field == "waypoints"


@pytest.mark.parametrize("field,value", [("rotate_above", 0.0), ("switch_radius", -1.0), ("arrive_radius", 0.2),
                                         ("gain", 100.0), ("heading_tolerance", float("nan"))])
def test_bad_follow_params_name_the_field(field: str, value: float) -> None:
    with pytest.raises(InvalidInput) as err:
        FollowParams(**{field: value})
    assert err.value.field == field


def test_wrap_angle() -> None:
    assert wrap_angle(math.pi) == math.pi
    assert wrap_angle(-math.pi) == math.pi
    assert wrap_angle(3 * math.pi / 2) == pytest.approx(-math.pi / 2)
    for a in np.linspace(-20, 20, 401):
        w = wrap_angle(float(a))
        assert -math.pi < w <= math.pi and math.isclose(math.cos(w), math.cos(a), abs_tol=1e-12)


# ------------------------------------------------------- the inlined command against its plain formulas ----
class _PlainFollower(Follower):
    """The follower as it was written in Python before it was compiled: the path table built with
    ``math.dist`` and the bend speeds, and one call per formula each tick (bend speed at the robot's
    position, braking limit, turn rate, ``wrap_angle``). The compiled follower must give the same floats
    bit for bit, or every run would change."""

    def set_path(self, waypoints):  # type: ignore[override]
        super().set_path(waypoints)  # validation
        self._index, self._done = 0, False  # its own state, in Python (the base class keeps it in arrays)
        self._points = list(map(tuple, np.asarray(waypoints, dtype=np.float64).tolist()))
        m = len(self._points)
        seg = [math.dist(self._points[i], self._points[i + 1]) for i in range(m - 1)]
        self._suffix = [0.0] * m
        for i in range(m - 2, -1, -1):
            self._suffix[i] = self._suffix[i + 1] + seg[i]
        self._corner_speed = [self._plain_bend_speed(i, self._points[i - 1]) if i > 0 else
                              (0.0 if m == 1 else self.params.max_speed) for i in range(m)]
        self._remaining = self._suffix[0]

    @property
    def index(self) -> int:
        return self._index

    @property
    def done(self) -> bool:
        return self._done

    @property
    def remaining_m(self) -> float:
        return 0.0 if self._done else self._remaining

    def command(self, pose):  # type: ignore[override]
        if self._done:
            return 0.0, 0.0
        x, y, theta = float(pose[0]), float(pose[1]), float(pose[2])
        fp = self.follow
        last = len(self._points) - 1
        while self._index < last and math.dist((x, y), self._points[self._index]) < fp.switch_radius:
            self._index += 1
        tx, ty = self._points[self._index]
        d = math.hypot(tx - x, ty - y)
        self._remaining = d + self._suffix[self._index]
        if self._index == last and d <= fp.arrive_radius:
            self._done = True
            self._remaining = 0.0
            return 0.0, 0.0
        err = wrap_angle(math.atan2(ty - y, tx - x) - theta)
        speed = self._plain_speed_limit(x, y, d)
        direction = 1.0
        if self._index == last and d < fp.reverse_radius and abs(err) > math.pi / 2:
            direction = -1.0
            err = wrap_angle(err - math.pi)
        omega = self._plain_turn_rate(err)
        if abs(err) > fp.rotate_above:
            return 0.0, omega
        return direction * speed * math.cos(err), omega

    def _plain_speed_limit(self, x: float, y: float, d: float) -> float:
        p = self.params
        brake = 0.5 * p.max_accel
        horizon = p.max_speed * p.max_speed / (2.0 * brake)
        last = len(self._points) - 1
        limit = p.max_speed
        dist = d
        i = self._index
        while True:
            vc = self._corner_speed[i] if i != self._index else self._plain_bend_speed(i, (x, y))
            if i == last:
                limit = min(limit, math.sqrt(2.0 * brake * dist),
                            max(self.follow.gain * dist, min(0.05, dist / 0.1)))
                break
            limit = min(limit, math.sqrt(vc * vc + 2.0 * brake * dist))
            if dist > horizon:
                break
            dist += self._suffix[i] - self._suffix[i + 1]
            i += 1
        return limit

    def _plain_turn_rate(self, err: float) -> float:
        p = self.params
        mag = abs(err)
        rate = min(p.max_turn_rate, math.sqrt(p.max_turn_accel * mag), self.follow.gain * mag)
        rate = min(max(rate, min(0.05, mag / TICK_S)), p.max_turn_rate)
        return math.copysign(rate, err)

    def _plain_bend_speed(self, i: int, prev: tuple[float, float]) -> float:
        pts = self._points
        if i == len(pts) - 1:
            return 0.0
        ax, ay = pts[i][0] - prev[0], pts[i][1] - prev[1]
        bx, by = pts[i + 1][0] - pts[i][0], pts[i + 1][1] - pts[i][1]
        if (ax == 0.0 and ay == 0.0) or (bx == 0.0 and by == 0.0):
            return self.params.max_speed
        bend = abs(wrap_angle(math.atan2(by, bx) - math.atan2(ay, ax)))
        if bend > self.follow.rotate_above:
            return 0.0
        return self.params.max_speed * math.cos(bend)


@pytest.mark.parametrize("seed", range(6))
def test_command_equals_the_plain_formulas_bit_for_bit(seed: int) -> None:
    rng = np.random.default_rng(seed)
    params = [MOTION_PRESETS["default"], MOTION_PRESETS["maes"]][seed % 2]
    follow = FollowParams() if seed < 3 else FollowParams(rotate_above=float(rng.uniform(0.3, 1.5)),
                                                          switch_radius=float(rng.uniform(0.05, 1.0)),
                                                          gain=float(rng.uniform(0.5, 9.0)))
    for _ in range(60):
        m = int(rng.integers(1, 8))
        pts = np.cumsum(rng.choice([0.0, 0.5, -0.5, 1.0, 3.0], size=(m, 2)), axis=0)  # repeats and sharp bends
        fast, plain = Follower(params, follow), _PlainFollower(params, follow)
        fast.set_path(pts)
        plain.set_path(pts)
        # the compiled path table: lengths to the end and corner speeds as the Python formulas give them
        assert fast.path_table[:, 2].tolist() == plain._suffix and fast.path_table[:, 4].tolist() == plain._corner_speed
        here = pts[0] + rng.normal(0.0, 0.3, 2)
        for _ in range(40):
            pose = (float(here[0]), float(here[1]), float(rng.uniform(-4.0, 4.0)))
            assert fast.command(pose) == plain.command(pose)
            assert (fast.index, fast.done, fast.remaining_m) == (plain.index, plain.done, plain.remaining_m)
            target = pts[min(fast.index, m - 1)]
            here = here + (target - here) * rng.uniform(0.0, 0.7) + rng.normal(0.0, 0.05, 2)


def test_command_unless_follows_like_command_and_stops_before_a_marked_cell() -> None:
    grid = np.zeros((6, 8), dtype=np.uint8)
    cells = np.array([3, 17, 40], dtype=np.int64)
    plain, fused = Follower(MotionParams()), Follower(MotionParams())
    for f in (plain, fused):
        f.set_path([(0.0, 0.0), (2.0, 0.5), (3.0, 2.0)])
    pose = (0.1, -0.05, 0.3)
    for _ in range(5):
        want = plain.command(pose)
        assert fused.command_unless(grid, cells, 2, pose) == want
        assert (fused.index, fused.remaining_m, fused.done) == (plain.index, plain.remaining_m, plain.done)
        pose = (pose[0] + 0.1, pose[1] + 0.02, pose[2])
    grid.reshape(-1)[17] = 1                      # below the limit: still clear
    assert fused.command_unless(grid, cells, 2, pose) == plain.command(pose)
    grid.reshape(-1)[40] = 2                      # a marked cell: no command, nothing advances
    before = (fused.index, fused.remaining_m, fused.done)
    assert fused.command_unless(grid, cells, 2, (2.0, 0.5, 0.0)) is None
    assert (fused.index, fused.remaining_m, fused.done) == before
    assert fused.command_unless(grid[:, ::-1], np.zeros(0, np.int64), 2, pose) == plain.command(pose)  # any layout
    idle = Follower(MotionParams())
    assert idle.command_unless(grid, cells, 2, pose) is None
    assert idle.command_unless(grid, cells[:2], 2, pose) == (0.0, 0.0)
