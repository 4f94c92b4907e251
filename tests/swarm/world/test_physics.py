"""swarm.world.physics: walls stop robots at every angle, drive limits hold, collisions are reported, runs repeat
bit for bit."""

from __future__ import annotations

import hashlib
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from maps import Map, generate
from swarm.base.errors import InvalidInput
from swarm.base.params import from_mapping
from swarm.world.motion import MAX_SUBSTEP_MOVE_M, MOTION_PRESETS, TICK_S, MotionParams
from swarm.world.physics import World, disc_hits_solid, wall_margin

PRESETS = [pytest.param(MOTION_PRESETS["default"], id="default"), pytest.param(MOTION_PRESETS["maes"], id="maes")]


def make_map(solid: np.ndarray) -> Map:
    return Map(solid=solid, material=solid.astype(np.uint8), materials=("air", "concrete"))


def room(width_cells: int, height_cells: int) -> np.ndarray:
    """A solid raster with a one-cell (0.5 m) wall ring around free space."""
    solid = np.ones((height_cells, width_cells), dtype=bool)
    solid[1:-1, 1:-1] = False
    return solid


def run(world: World, command: tuple[float, float], ticks: int) -> list[np.ndarray]:
    """Step every robot under the same command; return the poses after each tick."""
    cmd = np.tile(np.asarray(command, dtype=np.float64), (world.n_robots, 1))
    out = []
    for _ in range(ticks):
        world.step(cmd)
        out.append(world.poses.copy())
    return out


# ------------------------------------------------------------------------------------------ params ----
def test_default_params_describe_a_small_indoor_robot() -> None:
    p = MotionParams()
    assert (p.max_speed, p.max_turn_rate, p.radius) == (1.0, 2.0, 0.3)
    assert p.max_speed * p.substep_s <= MAX_SUBSTEP_MOVE_M
    maes = MotionParams.maes()
    assert (maes.max_speed, maes.max_turn_rate) == (3.0, 4.0)
    assert maes.max_speed * maes.substep_s <= MAX_SUBSTEP_MOVE_M
    assert from_mapping(MotionParams, {"max_speed": 0.5}).max_speed == 0.5


@pytest.mark.parametrize("field,value", [
    ("max_speed", 0.0), ("max_speed", -1.0), ("max_speed", float("nan")), ("max_speed", True),
    ("max_turn_rate", 0.0), ("max_accel", float("inf")), ("max_turn_accel", -2.0), ("radius", 0.0),
    ("radius", "0.3"), ("substeps", 0), ("substeps", 2.5),
])
def test_bad_params_name_the_field(field: str, value: object) -> None:
    with pytest.raises(InvalidInput) as err:
        MotionParams(**{field: value})
    assert err.value.field == field


def test_too_few_substeps_for_the_speed_are_refused() -> None:
    with pytest.raises(InvalidInput) as err:
        MotionParams(max_speed=3.0, substeps=5)
    assert err.value.field == "substeps" and ">= 6" in err.value.allowed
    MotionParams(max_speed=3.0, substeps=6)


def test_substeps_left_out_follow_the_speed() -> None:
    """--set motion.max_speed=3 needs no --set motion.substeps: the fewest safe sub-steps, at least 5."""
    assert [MotionParams(max_speed=v).substeps for v in (0.5, 1.0, 2.5, 3.0, 10.0)] == [5, 5, 5, 6, 20]
    assert MotionParams.maes().substeps == 8, "an explicit count stays"
    from swarm.sim.spec import RunSpec

    spec = RunSpec.from_mapping({"motion": {"max_speed": 3.0}})
    assert spec.canonical()["motion"]["substeps"] == 6, "the spec records the count used"
    assert RunSpec.from_mapping({"motion": {"max_speed": 3.0, "substeps": 6}}).key == spec.key


def test_unknown_param_is_an_error() -> None:
    with pytest.raises(InvalidInput) as err:
        from_mapping(MotionParams, {"top_speed": 2.0})
    assert err.value.field == "top_speed"


# ------------------------------------------------------------------------------------ construction ----
def test_one_static_box_per_wall_rectangle() -> None:
    truth = generate("building", 30, 2)
    world = World(truth, [[3.25, 3.25, 0.0]])
    walls = [s for s in world.space.shapes if s.body.body_type == s.body.STATIC]
    assert len(walls) == len(truth.wall_rectangles) == world.wall_count
    bounds = sorted((round(s.bb.left + world.wall_margin, 9), round(s.bb.bottom + world.wall_margin, 9))
                    for s in walls)
    assert bounds == sorted((r.bounds_m[0], r.bounds_m[1]) for r in truth.wall_rectangles)


@pytest.mark.parametrize("poses,field", [
    ([[0.2, 2.0, 0.0]], "poses[0]"),                      # centre in the outer wall
    ([[0.75, 2.0, 0.0]], "poses[0]"),                     # disc overlaps the wall cell
    ([[-3.0, 2.0, 0.0]], "poses[0]"),                     # outside the map
    ([[2.0, 2.0, 0.0], [2.5, 2.0, 0.0]], "poses[1]"),     # discs overlap
    ([[2.0, 2.0]], "poses"),
    ([], "poses"),
    ([[2.0, float("nan"), 0.0]], "poses"),
])
def test_bad_poses_are_refused(poses: list, field: str) -> None:
    with pytest.raises(InvalidInput) as err:
        World(make_map(room(10, 10)), poses)
    assert err.value.field == field


def test_touching_discs_and_walls_are_allowed() -> None:
    world = World(make_map(room(10, 10)), [[0.8, 1.0, 0.0], [1.4, 1.0, 0.0]])
    assert world.poses.shape == (2, 3)


def test_bad_commands_are_refused() -> None:
    world = World(make_map(room(10, 10)), [[2.0, 2.0, 0.0]])
    with pytest.raises(InvalidInput):
        world.step(np.zeros((2, 2)))
    with pytest.raises(InvalidInput):
        world.step([[float("nan"), 0.0]])
    with pytest.raises(InvalidInput):
        world.step([[1.0, float("inf")]])
    world.step([[0.0, 0.0]])
    assert world.ticks == 1


# ------------------------------------------------------------------------------------- free motion ----
def test_straight_drive_keeps_heading_and_line() -> None:
    world = World(make_map(room(60, 20)), [[2.0, 5.0, 0.0]])
    poses = run(world, (1.0, 0.0), 80)
    assert all(p[0, 1] == 5.0 and p[0, 2] == 0.0 for p in poses)
    xs = np.array([p[0, 0] for p in poses])
    assert np.all(np.diff(xs) > 0)
    assert not any(world.collided)


def test_speed_is_clipped_and_ramped_by_the_acceleration_limit() -> None:
    params = MotionParams()
    world = World(make_map(room(80, 20)), [[2.0, 5.0, 0.0]], params)
    poses = run(world, (50.0, 0.0), 40)
    steps = np.diff([2.0] + [p[0, 0] for p in poses])
    ramp_ticks = params.max_speed / params.max_accel / TICK_S
    assert steps[0] < 0.2 * params.max_speed * TICK_S           # starts slowly
    assert np.all(np.diff(steps[: int(ramp_ticks)]) > 0)        # speeds up tick by tick
    np.testing.assert_allclose(steps[int(ramp_ticks) + 2:], params.max_speed * TICK_S, rtol=1e-9)


def test_turn_rate_is_clipped() -> None:
    params = MotionParams()
    world = World(make_map(room(20, 20)), [[5.0, 5.0, 0.0]], params)
    run(world, (0.0, 100.0), 30)
    before = world.rotation[0]
    run(world, (0.0, 100.0), 10)
    assert world.rotation[0] - before == pytest.approx(10 * TICK_S * params.max_turn_rate, rel=1e-9)
    assert world.distance[0] == 0.0


@pytest.mark.parametrize("params", PRESETS)
def test_constant_command_drives_an_exact_circle(params: MotionParams) -> None:
    v, w = 0.8 * params.max_speed, 0.5 * params.max_turn_rate
    world = World(make_map(room(60, 60)), [[15.0, 15.0, 0.3]], params)
    poses = run(world, (v, w), 40)
    x, y, th = poses[9][0]                                      # ramps are over by now
    cx, cy = x - v / w * math.sin(th), y + v / w * math.cos(th)
    radii = [math.hypot(p[0, 0] - cx, p[0, 1] - cy) for p in poses[10:]]
    np.testing.assert_allclose(radii, v / w, atol=1e-9)
    d0, r0 = world.distance[0], world.rotation[0]
    run(world, (v, w), 10)
    assert world.distance[0] - d0 == pytest.approx(v * 10 * TICK_S, rel=1e-9)
    assert world.rotation[0] - r0 == pytest.approx(w * 10 * TICK_S, rel=1e-9)


def test_headings_are_wrapped_into_minus_pi_pi() -> None:
    world = World(make_map(room(20, 20)), [[5.0, 5.0, 3.0]])
    for p in run(world, (0.0, 2.0), 100) + run(world, (0.0, -2.0), 200):
        assert -math.pi < p[0, 2] <= math.pi
    assert World(make_map(room(20, 20)), [[5.0, 5.0, -math.pi]]).poses[0, 2] == math.pi


def test_outputs_are_read_only_snapshots() -> None:
    world = World(make_map(room(20, 20)), [[5.0, 5.0, 0.0]])
    poses, distance = world.poses, world.distance
    with pytest.raises(ValueError):
        poses[0, 0] = 1.0
    with pytest.raises(ValueError):
        world.collided[0] = True
    run(world, (1.0, 0.0), 5)
    assert poses[0, 0] == 5.0 and distance[0] == 0.0


# ------------------------------------------------------------------------------------------- walls ----
def wall_across() -> np.ndarray:
    """9 x 7 m room split by a 0.5 m wall at y in [3.0, 3.5)."""
    solid = room(18, 14)
    solid[6, :] = True
    return solid


@pytest.mark.parametrize("params", PRESETS)
def test_robot_driven_into_walls_at_36_angles_never_enters_or_crosses_them(params: MotionParams) -> None:
    solid = wall_across()
    truth = make_map(solid)
    for k in range(36):
        heading = math.radians(10 * k)
        world = World(truth, [[4.5, 1.6, heading]], params)
        touched = False
        for _ in range(50):
            world.step([[params.max_speed, 0.0]])
            x, y, _ = world.poses[0]
            assert not disc_hits_solid(solid, x, y, params.radius), (k, x, y)
            assert y + params.radius <= 3.0, (k, x, y)          # never on or past the wall
            touched = touched or bool(world.collided[0])
        assert touched, k


@pytest.mark.parametrize("params", PRESETS)
def test_door_jambs_and_corners_are_never_entered(params: MotionParams) -> None:
    solid = wall_across()
    solid[6, 8:10] = False                                       # a 1 m door at x in [4, 5)
    truth = make_map(solid)
    for k in range(36):
        heading = math.radians(5 + 10 * k)
        world = World(truth, [[4.5, 2.2, heading]], params)
        for t in range(60):
            turn = params.max_turn_rate * 0.3 * math.sin(0.2 * t + k)
            world.step([[params.max_speed, turn]])
            x, y, _ = world.poses[0]
            assert not disc_hits_solid(solid, x, y, params.radius), (k, t, x, y)


def test_a_robot_pushing_into_a_wall_at_an_angle_slides_along_it() -> None:
    solid = wall_across()
    world = World(make_map(solid), [[1.5, 2.0, math.radians(45)]])
    poses = run(world, (1.0, 0.0), 40)
    last = [p[0] for p in poses[-10:]]
    assert all(world.collided)
    assert all(b[0] > a[0] + 0.05 for a, b in zip(last, last[1:]))          # still moving along x
    assert max(p[1] for p in last) - min(p[1] for p in last) < 1e-3         # pinned in y
    assert 3.0 - last[-1][1] - 0.3 <= wall_margin(MotionParams()) + 1e-6    # against the wall


def test_collided_tracks_contact() -> None:
    world = World(make_map(room(20, 12)), [[5.0, 3.0, math.pi / 2]])
    run(world, (0.5, 0.0), 5)
    assert not world.collided[0]
    flags = []
    for _ in range(60):
        world.step([[1.0, 0.0]])
        flags.append(bool(world.collided[0]))
    assert flags[-1] and all(flags[flags.index(True):])       # pressing against the wall: every tick
    run(world, (-1.0, 0.0), 30)                                 # wheels slip until reversed, then back off
    assert not world.collided[0]


# ------------------------------------------------------------------------------------------ robots ----
def test_robot_robot_collisions_are_reported_to_both_and_nobody_else() -> None:
    params = MotionParams()
    world = World(make_map(room(40, 20)), [[3.0, 5.0, 0.0], [6.0, 5.0, math.pi], [15.0, 5.0, 0.0]], params)
    hits = np.zeros(3, dtype=bool)
    closest = math.inf
    for _ in range(30):
        world.step([[1.0, 0.0], [1.0, 0.0], [0.0, 0.0]])
        hits |= world.collided
        p = world.poses
        closest = min(closest, math.hypot(*(p[0, :2] - p[1, :2])))
    assert hits.tolist() == [True, True, False]
    assert closest >= 2 * params.radius - 2 * params.max_speed * params.substep_s - 0.002


def test_collided_with_says_whether_a_wall_or_a_robot_was_touched() -> None:
    # robots 0 and 1 drive head-on into each other; robot 2 drives up into the top wall; robot 3 stays put
    world = World(make_map(room(40, 20)), [[3.0, 5.0, 0.0], [6.0, 5.0, math.pi], [15.0, 7.0, math.pi / 2],
                                           [15.0, 3.0, 0.0]])
    seen = np.zeros((2, 4), dtype=bool)
    for _ in range(40):
        world.step([[1.0, 0.0], [1.0, 0.0], [1.0, 0.0], [0.0, 0.0]])
        assert (world.collided_with.any(axis=0) == world.collided).all()
        seen |= world.collided_with
    assert seen[0].tolist() == [False, False, True, False]      # walls
    assert seen[1].tolist() == [True, True, False, False]       # robots


def test_a_robot_pushes_a_stopped_robot() -> None:
    world = World(make_map(room(40, 20)), [[3.0, 5.0, 0.0], [4.0, 5.0, 0.0]])
    run_cmd = np.array([[1.0, 0.0], [0.0, 0.0]])
    for _ in range(40):
        world.step(run_cmd)
    assert world.poses[1, 0] > 4.5
    assert world.collided.all()


def test_disabled_robot_stops_and_stays_put_as_an_obstacle() -> None:
    params = MotionParams()
    world = World(make_map(room(40, 20)), [[3.0, 5.0, 0.0], [8.0, 5.0, math.pi]], params)
    run(world, (1.0, 0.0), 5)                                   # both moving when robot 1 dies
    world.disable(1)
    world.disable(1)                                            # twice is fine
    assert world.disabled.tolist() == [False, True]
    frozen = [v.hex() for v in world.poses[1]]
    pushed_at = None
    for t in range(80):
        world.step([[1.0, 0.0], [1.0, 1.0]])                    # the dead robot's command is ignored
        assert [v.hex() for v in world.poses[1]] == frozen
        if world.collided[0] and pushed_at is None:
            pushed_at = t
        gap = math.hypot(*(world.poses[0, :2] - world.poses[1, :2]))
        assert gap >= 2 * params.radius - params.max_speed * params.substep_s - 0.002
    assert pushed_at is not None and world.collided[0]


@pytest.mark.parametrize("bad", [-1, 2, 1.0, True, "0"])
def test_disable_refuses_bad_indices(bad: object) -> None:
    world = World(make_map(room(20, 20)), [[3.0, 3.0, 0.0], [6.0, 3.0, 0.0]])
    with pytest.raises(InvalidInput):
        world.disable(bad)  # type: ignore[arg-type]


@pytest.mark.parametrize("params", PRESETS)
def test_a_crowd_never_enters_walls(params: MotionParams) -> None:
    solid = room(14, 14)                                        # 6 x 6 m of free space
    truth = make_map(solid)
    start = [[1.25 + 1.1 * (i % 4), 1.25 + 1.1 * (i // 4), 0.4 * i] for i in range(16)]
    world = World(truth, start, params)
    rng = np.random.default_rng(5)
    cmd = np.zeros((16, 2))
    for t in range(300):
        if t % 10 == 0:
            cmd[:, 0] = params.max_speed * rng.uniform(-0.3, 1.0, 16)
            cmd[:, 1] = params.max_turn_rate * rng.uniform(-1.0, 1.0, 16)
        world.step(cmd)
        for x, y, _ in world.poses:
            assert not disc_hits_solid(solid, x, y, params.radius), (t, x, y)
    assert world.collided.any()


# ------------------------------------------------------------------------------------- determinism ----
def scenario_digest(ticks: int = 300) -> str:
    """Eight robots in a generated building under seeded random commands; a digest of every output."""
    truth = generate("building", 30, 3)
    from maps.raster import robot_space

    cells = np.argwhere(robot_space(truth.free))
    rng = np.random.default_rng(11)
    chosen: list[tuple[float, float, float]] = []
    for r, c in cells[rng.permutation(len(cells))]:
        x, y = (c + 0.5) * 0.5, (r + 0.5) * 0.5
        if all(math.hypot(x - a, y - b) >= 0.7 for a, b, _ in chosen):
            chosen.append((x, y, float(rng.uniform(-math.pi, math.pi))))
        if len(chosen) == 8:
            break
    world = World(truth, chosen, MotionParams())
    digest = hashlib.sha256()
    cmd = np.zeros((8, 2))
    for t in range(ticks):
        if t % 7 == 0:
            cmd = np.column_stack([rng.uniform(-0.3, 1.2, 8), rng.uniform(-2.5, 2.5, 8)])
        if t == 150:
            world.disable(3)
        world.step(cmd)
        for array in (world.poses, world.distance, world.rotation):
            digest.update(" ".join(float(v).hex() for v in array.ravel()).encode())
        digest.update(world.collided.tobytes())
    return digest.hexdigest()


def test_same_commands_give_bit_identical_results() -> None:
    assert scenario_digest() == scenario_digest()


def test_results_do_not_depend_on_the_process() -> None:
    root = Path(__file__).resolve().parents[3]
    code = "from tests.swarm.world.test_physics import scenario_digest; print(scenario_digest())"
    env = dict(os.environ, PYTHONHASHSEED="12345", PYTHONPATH=str(root))
    child = subprocess.run([sys.executable, "-c", code], cwd=root, env=env, capture_output=True, text=True,
                           check=True)
    assert child.stdout.strip() == scenario_digest()


# ------------------------------------------------------------------------------------------ helper ----
def test_disc_hits_solid() -> None:
    solid = room(10, 10)
    assert not disc_hits_solid(solid, 2.5, 2.5, 0.3)
    assert not disc_hits_solid(solid, 0.8, 2.5, 0.3)            # touching the wall cell's edge
    assert disc_hits_solid(solid, 0.79, 2.5, 0.3)
    assert disc_hits_solid(solid, 0.7, 0.7, 0.3)                # the corner cell (0.5, 0.5)-(1.0, 1.0)
    assert not disc_hits_solid(solid, 0.5 + 0.3 / math.sqrt(2) + 0.5, 0.5 + 0.3 / math.sqrt(2) + 0.5, 0.3)
    assert disc_hits_solid(solid, 4.9, 2.5, 0.3)                # off the raster


@pytest.mark.parametrize("seed", range(6))
def test_the_overlap_check_finds_the_pair_the_all_pairs_matrix_finds(seed: int) -> None:
    from swarm.world.physics import _closest_overlap

    rng = np.random.default_rng(seed)
    limit = 0.6 * (1.0 - 1e-9)
    for _ in range(200):
        n = int(rng.integers(2, 40))
        xy = rng.uniform(0, 6, (n, 2))
        if seed % 2:  # on a 0.3 m grid: exact ties and pairs exactly at the limit
            xy = np.round(xy / 0.3) * 0.3
        d = np.hypot(xy[:, None, 0] - xy[None, :, 0], xy[:, None, 1] - xy[None, :, 1])
        d[np.diag_indices_from(d)] = np.inf
        i, j = np.unravel_index(int(np.argmin(d)), d.shape)
        expected = (min(i, j), max(i, j), float(d[i, j])) if d[i, j] < limit else None
        assert _closest_overlap(xy, limit) == expected
