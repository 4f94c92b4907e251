"""The lidar: the exact seen-cell rule, occlusion, ray density, ranges, vectorisation and log-odds mode."""

from __future__ import annotations

import math

import numpy as np
import pytest

from maps import InvalidInput, Map, generate
from swarm.api import FREE, SOLID, UNSEEN
from swarm.base.params import from_mapping, to_mapping
from swarm.knowledge.maps import ExplorationTracker, empty_knowledge
from swarm.world.sensing import Lidar, LidarParams, auto_rays, ray_angles, warm_up

CELL = 0.5


def make_map(solid: np.ndarray) -> Map:
    return Map(solid=solid, material=solid.astype(np.uint8), materials=("air", "concrete"))


def room(rows: int, cols: int) -> np.ndarray:
    solid = np.ones((rows, cols), dtype=bool)
    solid[1:-1, 1:-1] = False
    return solid


def centre_disc(shape: tuple[int, int], x: float, y: float, r: float) -> np.ndarray:
    """Cells whose centre lies within r of (x, y), computed the way the kernel does."""
    rows, cols = np.indices(shape)
    cx = (cols + 0.5) * CELL - x
    cy = (rows + 0.5) * CELL - y
    return cx * cx + cy * cy <= r * r


def scan_one(truth: Map, pose: tuple[float, float, float], **params: object) -> tuple[np.ndarray, np.ndarray]:
    lidar = Lidar(truth, LidarParams(**params))  # type: ignore[arg-type]
    known = empty_knowledge(truth.shape, 1)
    ranges = lidar.scan(np.array([pose]), known)
    return known[0], ranges[0]


def reference_scan(truth: Map, pose: tuple[float, float, float], angles: np.ndarray,
                   range_m: float) -> tuple[np.ndarray, np.ndarray]:
    """An independent implementation of the rule: for every ray, intersect it with every nearby cell box
    (slab method), sort the crossed cells by entry distance and apply the seen-cell rule. Only valid off
    exact ties (a ray through a cell corner), which random poses avoid."""
    x, y, theta = pose
    known = np.zeros(truth.shape, dtype=np.uint8)
    ranges = np.full(len(angles), np.inf)
    reach = int(math.ceil(range_m / CELL)) + 2
    r0, c0 = int(y // CELL), int(x // CELL)
    rows, cols = np.mgrid[max(r0 - reach, 0):min(r0 + reach + 1, truth.shape[0]),
                          max(c0 - reach, 0):min(c0 + reach + 1, truth.shape[1])]
    rows, cols = rows.ravel(), cols.ravel()
    x0, x1, y0, y1 = cols * CELL, (cols + 1) * CELL, rows * CELL, (rows + 1) * CELL
    disc = ((cols + 0.5) * CELL - x) ** 2 + ((rows + 0.5) * CELL - y) ** 2 <= range_m ** 2
    with np.errstate(divide="ignore", invalid="ignore"):
        for i, a in enumerate(angles):
            dx, dy = math.cos(theta + a), math.sin(theta + a)
            tx = np.sort(np.stack([(x0 - x) / dx, (x1 - x) / dx]), axis=0)
            ty = np.sort(np.stack([(y0 - y) / dy, (y1 - y) / dy]), axis=0)
            if dx == 0:
                tx = np.where((x0 <= x) & (x < x1), [[-np.inf], [np.inf]], [[np.inf], [-np.inf]])
            if dy == 0:
                ty = np.where((y0 <= y) & (y < y1), [[-np.inf], [np.inf]], [[np.inf], [-np.inf]])
            t_in = np.maximum(np.maximum(tx[0], ty[0]), 0.0)
            t_out = np.minimum(tx[1], ty[1])
            crossed = np.flatnonzero((t_out > t_in) & (t_in <= range_m))
            for k in crossed[np.argsort(t_in[crossed], kind="stable")]:
                r, c = rows[k], cols[k]
                if truth.solid[r, c]:
                    known[r, c] = SOLID
                    ranges[i] = t_in[k]
                    break
                if disc[k]:
                    known[r, c] = max(known[r, c], FREE)
    return known, ranges


def random_free_poses(truth: Map, n: int, rng: np.random.Generator) -> np.ndarray:
    cells = np.argwhere(truth.free)
    pick = cells[rng.choice(len(cells), size=n, replace=False)]
    xy = (pick[:, ::-1] + rng.uniform(0.01, 0.99, (n, 2))) * CELL
    return np.column_stack([xy, rng.uniform(-math.pi, math.pi, n)])


# ------------------------------------------------------------------------------------------ params
def test_defaults_follow_maes_and_resolve_the_ray_count() -> None:
    p = LidarParams()
    assert (p.range_m, p.fov_deg, p.rays, p.mode) == (7.0, 360.0, None, "ternary")
    assert p.n_rays == auto_rays(7.0) == 88
    assert LidarParams(rays=40).n_rays == 40


@pytest.mark.parametrize("r", [0.3, 1.0, 3.0, 7.0, 10.0, 20.0, 33.3])
def test_auto_rays_is_the_fewest_with_spacing_below_the_cell_angle(r: float) -> None:
    theta = 2 * math.asin(min(1.0, CELL / (2 * r)))
    n = auto_rays(r)
    assert 2 * math.pi / n < theta <= 2 * math.pi / (n - 1)
    m = auto_rays(r, 90.0)
    assert math.radians(90) / (m - 1) < theta
    assert m == 2 or theta <= math.radians(90) / (m - 2)      # with 2 rays, one fewer has no spacing


@pytest.mark.parametrize("field,value", [
    ("range_m", 0.0), ("range_m", -1.0), ("range_m", float("nan")), ("fov_deg", 0.0), ("fov_deg", 361.0),
    ("rays", 0), ("rays", 2.5), ("rays", True), ("noise_std", -0.1), ("mode", "fancy"),
    ("logodds_hit", 0.0), ("logodds_miss", 0.1), ("logodds_min", 1.0), ("logodds_max", -1.0),
    ("logodds_free_below", -6.0), ("logodds_occupied_above", 5.0),
])
def test_bad_parameters_name_the_field(field: str, value: object) -> None:
    with pytest.raises(InvalidInput) as err:
        LidarParams(**{"mode": "logodds", field: value})  # type: ignore[arg-type]
    assert err.value.field == field


def test_thresholds_must_be_ordered() -> None:
    with pytest.raises(InvalidInput) as err:
        LidarParams(logodds_free_below=1.0, logodds_occupied_above=0.5)
    assert err.value.field == "logodds_occupied_above"


def test_noise_requires_logodds_mode() -> None:
    with pytest.raises(InvalidInput) as err:
        LidarParams(noise_std=0.05)
    assert err.value.field == "noise_std"
    assert LidarParams(noise_std=0.05, mode="logodds").noisy


def test_params_from_a_mapping_normalise_numbers() -> None:
    p = from_mapping(LidarParams, {"range_m": 7, "noise_std": 0})
    assert to_mapping(p)["range_m"] == 7.0 and isinstance(to_mapping(p)["range_m"], float)
    with pytest.raises(InvalidInput):
        from_mapping(LidarParams, {"range": 7})


def test_angles_are_centred_on_the_heading() -> None:
    full = ray_angles(8)
    assert np.allclose(full, np.arange(8) * math.pi / 4)
    sector = ray_angles(5, 90.0)
    assert np.allclose(sector, np.radians([-45, -22.5, 0, 22.5, 45]))
    assert ray_angles(1, 30.0).tolist() == [0.0]


# --------------------------------------------------------------------------------- seen-cell rule
@pytest.mark.parametrize("range_m", [1.0, 3.0, 7.0, 10.0])
def test_in_an_empty_room_the_robot_sees_exactly_the_cells_within_range(range_m: float) -> None:
    truth = make_map(room(60, 60))
    rng = np.random.default_rng(int(range_m * 10))
    poses = [(15.25, 15.25, 0.0), (15.0, 15.0, 0.0)]            # a cell centre and a cell corner
    poses += [tuple(p) for p in rng.uniform([13, 13, -4], [17, 17, 4], (20, 3))]
    for pose in poses:
        known, ranges = scan_one(truth, pose, range_m=range_m)
        expected = centre_disc(truth.shape, pose[0], pose[1], range_m)
        assert np.array_equal(known == FREE, expected), pose
        assert not (known == SOLID).any()
        assert np.isinf(ranges).all()


def test_at_range_the_rays_leave_no_unseen_free_cell() -> None:
    """Auto rays never skip a cell in range, off-centre and at any heading, at long range too; with
    half as many rays cells are skipped, so this test can fail."""
    truth = make_map(room(100, 100))
    rng = np.random.default_rng(5)
    for range_m in (7.0, 20.0):
        for pose in rng.uniform([24, 24, -4], [26, 26, 4], (20, 3)):
            expected = centre_disc(truth.shape, pose[0], pose[1], range_m)
            known, _ = scan_one(truth, tuple(pose), range_m=range_m)
            assert not (expected & (known == UNSEEN)).any()
            sparse, _ = scan_one(truth, tuple(pose), range_m=range_m, rays=auto_rays(range_m) // 2)
            assert (expected & (sparse == UNSEEN)).any()


def test_a_wall_hides_what_is_behind_it() -> None:
    solid = room(40, 40)
    solid[1:-1, 20:22] = True           # a 1 m thick wall across the room, x in [10, 11)
    truth = make_map(solid)
    known, ranges = scan_one(truth, (8.3, 10.1, 0.0), range_m=7.0)
    assert not known[:, 21:].any()                               # the far half of the wall and beyond
    near = known[:, 20]
    assert (near[1:-1] == SOLID).sum() > 10 and set(np.unique(near)) <= {UNSEEN, SOLID}
    assert (known[:, :20] != SOLID).all() or (known[:, 0] == SOLID).any()
    assert ranges[0] == np.float32(10.0 - 8.3)                 # straight ahead to the wall face
    # Everything in range on the robot's side is seen, and only that.
    expected = centre_disc(truth.shape, 8.3, 10.1, 7.0) & truth.free
    expected[:, 20:] = False
    assert np.array_equal(known == FREE, expected)


def test_ranges_are_entry_distances_and_the_heading_turns_the_rays() -> None:
    truth = make_map(room(20, 20))                  # free x, y in [0.5, 9.5)
    x, y = 2.3, 3.1
    _, east = scan_one(truth, (x, y, 0.0), range_m=9.0)
    _, north = scan_one(truth, (x, y, math.pi / 2), range_m=9.0)
    assert east[0] == np.float32(9.5 - x)
    assert abs(north[0] - (9.5 - y)) < 1e-5          # cos(pi/2) is not exactly 0
    _, short = scan_one(truth, (x, y, 0.0), range_m=7.0)
    assert np.isinf(short[0])                       # 7.2 m to the east wall: no return
    assert short[44] == np.float32(x - 0.5)         # west wall (ray 44 of 88 points backwards)


def test_a_ray_hitting_within_range_marks_the_solid_cell_it_stops_in() -> None:
    truth = make_map(room(20, 20))
    x, y = 4.1, 4.2
    known, ranges = scan_one(truth, (x, y, 0.4), range_m=6.0)
    angles = 0.4 + ray_angles(auto_rays(6.0))
    for a, t in zip(angles, ranges):
        if np.isfinite(t):
            assert t <= 6.0
            px, py = x + (t + 1e-4) * math.cos(a), y + (t + 1e-4) * math.sin(a)
            r, c = int(py // CELL), int(px // CELL)
            assert truth.solid[r, c] and known[r, c] == SOLID


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_kernel_matches_an_independent_slab_reference_on_a_cave(seed: int) -> None:
    truth = generate("cave", 30, seed)
    rng = np.random.default_rng(seed)
    lidar = Lidar(truth, LidarParams(range_m=6.0))
    for pose in random_free_poses(truth, 8, rng):
        known = empty_knowledge(truth.shape, 1)
        ranges = lidar.scan(pose[None, :], known)[0]
        ref_known, ref_ranges = reference_scan(truth, tuple(pose), lidar.angles, 6.0)
        assert np.array_equal(known[0], ref_known)
        assert np.array_equal(np.isinf(ranges), np.isinf(ref_ranges))
        hit = np.isfinite(ref_ranges)
        assert np.allclose(ranges[hit], ref_ranges[hit], rtol=1e-6, atol=1e-6)


def test_solid_stays_solid_and_writes_are_maxima() -> None:
    truth = make_map(room(20, 20))
    known = empty_knowledge(truth.shape, 1)
    known[0, 8, 8] = SOLID                       # a (wrong) wall in free space, e.g. merged from a peer
    Lidar(truth).scan(np.array([[4.1, 4.1, 0.0]]), known)
    assert known[0, 8, 8] == SOLID
    assert known[0, 8, 9] == FREE


def test_a_sector_sees_only_ahead() -> None:
    truth = make_map(room(40, 40))
    known, _ = scan_one(truth, (10.1, 10.1, 0.0), range_m=5.0, fov_deg=90.0)
    assert not known[:, :19].any()                      # nothing behind (x < 9.5)
    rows, cols = np.indices(truth.shape)
    cx, cy = (cols + 0.5) * CELL - 10.1, (rows + 0.5) * CELL - 10.1
    cone = (np.abs(np.arctan2(cy, cx)) < math.radians(40)) & centre_disc(truth.shape, 10.1, 10.1, 5.0)
    assert (known[cone] == FREE).all()


def test_a_robot_inside_a_wall_sees_only_that_wall_cell() -> None:
    truth = make_map(room(20, 20))
    known, ranges = scan_one(truth, (0.2, 3.3, 1.0))
    assert (ranges == 0).all()
    assert known[6, 0] == SOLID and np.count_nonzero(known) == 1


# --------------------------------------------------------------------------------- vectorisation
def test_all_robots_in_one_call_equal_one_call_per_robot_and_inactive_robots_do_nothing() -> None:
    truth = generate("building", 30, 3)
    poses = random_free_poses(truth, 5, np.random.default_rng(3))
    active = np.array([True, False, True, True, False])
    lidar = Lidar(truth)
    known = empty_knowledge(truth.shape, 5)
    ranges = lidar.scan(poses, known, active=active)
    assert np.isnan(ranges[~active]).all() and not np.isnan(ranges[active]).any()
    assert not known[~active].any()
    for r in np.flatnonzero(active):
        alone = empty_knowledge(truth.shape, 1)
        single = Lidar(truth).scan(poses[r:r + 1], alone)
        assert np.array_equal(alone[0], known[r])
        assert np.array_equal(single[0], ranges[r])


def test_the_tracker_counts_free_cells_seen_by_anyone_exactly_once() -> None:
    truth = generate("cave", 40, 4)
    tracker = ExplorationTracker(truth)
    lidar = Lidar(truth, tracker=tracker)
    assert lidar.tracker is tracker and tracker.explored == 0.0
    known = empty_knowledge(truth.shape, 4)
    rng = np.random.default_rng(4)
    for _ in range(3):
        lidar.scan(random_free_poses(truth, 4, rng), known)
        seen_free = tracker.seen & truth.free
        assert tracker.seen_free_cells == seen_free.sum() > 0
        assert tracker.explored == seen_free.sum() / truth.free_cells
    union = known.max(axis=0)
    assert np.array_equal(union == FREE, tracker.seen & truth.free)
    assert np.array_equal(union == SOLID, tracker.seen & truth.solid)
    other = ExplorationTracker(truth)                # a tracker handed to one call gets that call's cells
    pose = random_free_poses(truth, 1, rng)
    lidar.scan(pose, empty_knowledge(truth.shape, 1), tracker=other)
    assert other.seen_free_cells == (other.seen & truth.free).sum() > 0
    assert tracker.seen_free_cells == (tracker.seen & truth.free).sum()


@pytest.mark.parametrize("pose", [(-0.1, 2.0, 0.0), (2.0, 10.0, 0.0), (2.0, 2.0, float("nan")),
                                  (float("inf"), 2.0, 0.0)])
def test_poses_outside_the_map_are_refused_before_anything_is_written(pose: tuple[float, ...]) -> None:
    truth = make_map(room(20, 20))
    known = empty_knowledge(truth.shape, 2)
    lidar = Lidar(truth)
    with pytest.raises(InvalidInput) as err:
        lidar.scan(np.array([(2.0, 2.0, 0.0), pose]), known)
    assert err.value.field == "poses[1]"
    assert not known.any() and lidar.tracker.seen_free_cells == 0


def test_bad_arrays_are_refused() -> None:
    truth = make_map(room(20, 20))
    lidar = Lidar(truth)
    pose = np.array([[2.0, 2.0, 0.0]])
    for known in (np.zeros((1, 20, 21), np.uint8), np.zeros((1, 20, 20), np.int32),
                  np.zeros((2, 20, 20), np.uint8), np.zeros((1, 20, 40), np.uint8)[:, :, ::2]):
        with pytest.raises(InvalidInput) as err:
            lidar.scan(pose, known)
        assert err.value.field == "known"
    with pytest.raises(InvalidInput) as err:
        lidar.scan(np.zeros((1, 2)), empty_knowledge(truth.shape, 1))
    assert err.value.field == "poses"
    with pytest.raises(InvalidInput) as err:
        lidar.scan(pose, empty_knowledge(truth.shape, 1), active=np.ones(2, bool))
    assert err.value.field == "active"
    with pytest.raises(InvalidInput):
        Lidar(truth, tracker=ExplorationTracker(make_map(room(10, 10))))
    with pytest.raises(InvalidInput) as err:
        lidar.scan(pose, empty_knowledge(truth.shape, 1), tracker=ExplorationTracker(make_map(room(10, 10))))
    assert err.value.field == "tracker"


# ------------------------------------------------------------------------------------------ log-odds
def test_noise_free_logodds_gives_the_ternary_map_and_the_eq7_increments() -> None:
    truth = generate("cave", 30, 7)
    poses = random_free_poses(truth, 3, np.random.default_rng(7))
    ternary = empty_knowledge(truth.shape, 3)
    t_ranges = Lidar(truth).scan(poses, ternary)
    params = LidarParams(mode="logodds")
    lidar = Lidar(truth, params)
    known = empty_knowledge(truth.shape, 3)
    ranges = lidar.scan(poses, known)
    assert np.array_equal(known, ternary) and np.array_equal(ranges, t_ranges)
    assert lidar.logodds is not None
    values = lidar.logodds.values
    assert np.all(values[known == SOLID] == np.float32(params.logodds_hit))
    assert np.all(values[known == FREE] == np.float32(params.logodds_miss))
    assert np.all(values[known == UNSEEN] == 0)
    assert np.array_equal(lidar.logodds.classify(), known)


def test_logodds_clamp_and_evidence_can_flip_a_cell() -> None:
    truth = make_map(room(20, 20))
    lidar = Lidar(truth, LidarParams(mode="logodds", range_m=3.0))
    known = empty_knowledge(truth.shape, 1)
    pose = np.array([[3.1, 3.1, 0.0]])
    lidar.scan(pose, known)
    assert lidar.logodds is not None
    lidar.logodds.values[0, 6, 8] = 0.85         # a false wall one scan of evidence strong
    known[0, 6, 8] = SOLID
    lidar.scan(pose, known)                       # 0.85 - 0.4 = 0.45: still SOLID
    assert known[0, 6, 8] == SOLID
    lidar.scan(pose, known)                       # 0.05
    lidar.scan(pose, known)                       # -0.35: FREE, overwritten (not a maximum)
    assert known[0, 6, 8] == FREE
    for _ in range(20):
        lidar.scan(pose, known)
    assert lidar.logodds.values[0, 6, 6] == np.float32(-5.0)
    assert lidar.logodds.values[0, 0, 6] == np.float32(5.0)    # the wall below the robot


def test_noise_is_drawn_from_the_rng_and_reproducible() -> None:
    truth = generate("cave", 30, 8)
    poses = random_free_poses(truth, 4, np.random.default_rng(8))
    params = LidarParams(mode="logodds", noise_std=0.05, noise_per_metre=0.01)
    out = []
    for seed in (1, 1, 2):
        lidar = Lidar(truth, params)
        known = empty_knowledge(truth.shape, 4)
        rng = np.random.default_rng(seed)
        ranges = np.stack([lidar.scan(poses, known, rng) for _ in range(3)])
        assert lidar.logodds is not None
        out.append((ranges, known, lidar.logodds.values.copy()))
    assert all(np.array_equal(a, b) for a, b in zip(out[0], out[1]))
    assert not np.array_equal(out[0][0], out[2][0])
    with pytest.raises(InvalidInput) as err:
        Lidar(truth, params).scan(poses, empty_knowledge(truth.shape, 4))
    assert err.value.field == "rng"


def test_noisy_ranges_scatter_around_the_truth_and_walls_stay_near_walls() -> None:
    truth = generate("building", 40, 9)
    poses = random_free_poses(truth, 16, np.random.default_rng(9))
    exact = Lidar(truth).scan(poses, empty_knowledge(truth.shape, 16))
    lidar = Lidar(truth, LidarParams(mode="logodds", noise_std=0.05))
    known = empty_knowledge(truth.shape, 16)
    rng = np.random.default_rng(10)
    errors = []
    for _ in range(10):
        noisy = lidar.scan(poses, known, rng)
        both = np.isfinite(exact) & np.isfinite(noisy) & (exact > 0.2)
        errors.append(noisy[both] - exact[both])
    err = np.concatenate(errors)
    assert abs(err.mean()) < 0.01 and 0.045 < err.std() < 0.055
    near_wall = np.zeros_like(truth.solid)
    padded = np.pad(truth.solid, 1)
    for dr in (-1, 0, 1):
        for dc in (-1, 0, 1):
            near_wall |= padded[1 + dr:1 + dr + truth.shape[0], 1 + dc:1 + dc + truth.shape[1]]
    assert near_wall[(known == SOLID).any(axis=0)].all()
    # The ground truth "seen" ignores noise: it equals what the exact scan sees.
    exact_tracker = Lidar(truth)
    exact_tracker.scan(poses, empty_knowledge(truth.shape, 16))
    assert np.array_equal(lidar.tracker.seen, exact_tracker.tracker.seen)


def test_range_noise_can_grow_with_distance() -> None:
    truth = generate("building", 40, 11)
    poses = random_free_poses(truth, 16, np.random.default_rng(11))
    exact = Lidar(truth).scan(poses, empty_knowledge(truth.shape, 16))
    lidar = Lidar(truth, LidarParams(mode="logodds", noise_per_metre=0.02))
    known = empty_knowledge(truth.shape, 16)
    rng = np.random.default_rng(12)
    rel = []
    for _ in range(10):
        noisy = lidar.scan(poses, known, rng)
        both = np.isfinite(exact) & np.isfinite(noisy) & (exact > 1.0)
        rel.append((noisy[both] - exact[both]) / exact[both])
    assert 0.018 < np.concatenate(rel).std() < 0.022


def test_noise_beyond_range_means_no_return() -> None:
    solid = room(20, 40)
    solid[:, 31] = True                          # wall face at x = 15.5, 6.99 m ahead of the robot
    truth = make_map(solid)
    lidar = Lidar(truth, LidarParams(mode="logodds", noise_std=0.05))
    known = empty_knowledge(truth.shape, 1)
    rng = np.random.default_rng(13)
    ahead = np.array([lidar.scan(np.array([[8.51, 5.1, 0.0]]), known, rng)[0, 0] for _ in range(60)])
    assert np.isinf(ahead).sum() > 10 and np.isfinite(ahead).sum() > 10
    assert (ahead[np.isfinite(ahead)] <= 7.0).all()


def test_the_robot_count_is_fixed_by_the_first_logodds_scan() -> None:
    truth = make_map(room(20, 20))
    lidar = Lidar(truth, LidarParams(mode="logodds"))
    lidar.scan(np.array([[2.0, 2.0, 0.0]] * 2), empty_knowledge(truth.shape, 2))
    with pytest.raises(InvalidInput):
        lidar.scan(np.array([[2.0, 2.0, 0.0]] * 3), empty_knowledge(truth.shape, 3))


def test_warm_up_compiles_the_kernels() -> None:
    from swarm.knowledge import maps as knowledge
    from swarm.world import sensing

    warm_up()
    for kernel in (sensing._lidar_ternary_kernel, sensing._lidar_logodds_kernel,
                   knowledge._cover_blocks_kernel, knowledge._merge_max_kernel):
        assert kernel.signatures


# A pose and ray with an exact tie: ray 1 of 8 at heading 0 (45 degrees) crosses x = 4 and y = 4 at the
# same float distance, i.e. passes exactly through the corner of cells (7, 7), (7, 8), (8, 7), (8, 8).
CORNER_POSE = (3.8999999999999826, 3.8999999999999826, 0.0)


def test_exact_corner_ties_step_in_x_first_so_rays_never_slip_between_diagonal_walls() -> None:
    dx, dy = math.cos(math.pi / 4), math.sin(math.pi / 4)
    assert dx != dy and (4.0 - CORNER_POSE[0]) / dx == (4.0 - CORNER_POSE[1]) / dy     # the tie is real
    solid = room(16, 16)
    solid[7, 8] = solid[8, 7] = True
    truth = make_map(solid)
    known, ranges = scan_one(truth, CORNER_POSE, rays=8)
    assert ranges[1] == np.float32((4.0 - CORNER_POSE[0]) / dx)
    assert known[7, 8] == SOLID and known[8, 8] == UNSEEN
    # The x-neighbour alone stops the ray (it is entered for zero length); the y-neighbour alone does not.
    solid[8, 7] = False
    _, ranges = scan_one(make_map(solid), CORNER_POSE, rays=8)
    assert ranges[1] == np.float32((4.0 - CORNER_POSE[0]) / dx)
    solid[8, 7], solid[7, 8] = True, False
    _, ranges = scan_one(make_map(solid), CORNER_POSE, rays=8)
    assert ranges[1] > 1.0


def test_noise_free_logodds_hits_the_corner_grazed_wall_like_the_ternary_scan() -> None:
    solid = room(16, 16)
    solid[7, 8] = True
    truth = make_map(solid)
    ternary, t_ranges = scan_one(truth, CORNER_POSE, rays=8)
    lidar = Lidar(truth, LidarParams(rays=8, mode="logodds"))
    known = empty_knowledge(truth.shape, 1)
    ranges = lidar.scan(np.array([CORNER_POSE]), known)
    assert t_ranges[1] == ranges[0, 1] and ternary[7, 8] == SOLID
    assert np.array_equal(known[0], ternary)


def sum_walk_ranges(truth: Map, pose: tuple[float, float, float], cos_a: np.ndarray, sin_a: np.ndarray,
                    range_m: float) -> np.ndarray:
    """The walk's entry distances in plain Python floats, by the textbook Amanatides-Woo sums ``t_x +=
    d_x * in_x`` with a 0/1 ``in_x``, as float32 ranges: the kernel picks its steps by selects instead
    and must give these bits, signed zeros included, for every ray."""
    x, y, theta = pose
    ch, sh = math.cos(theta), math.sin(theta)
    out = np.empty(len(cos_a), dtype=np.float32)
    for i, (ca, sa) in enumerate(zip(cos_a.tolist(), sin_a.tolist())):
        dx, dy = ch * ca - sh * sa, sh * ca + ch * sa
        col, row = math.floor(x / CELL), math.floor(y / CELL)
        step_c, t_x, d_x = 0, math.inf, 0.0
        if dx != 0.0:
            step_c = 1 if dx > 0.0 else -1
            t_x, d_x = ((col + (1 if dx > 0.0 else 0)) * CELL - x) / dx, CELL / abs(dx)
        step_r, t_y, d_y = 0, math.inf, 0.0
        if dy != 0.0:
            step_r = 1 if dy > 0.0 else -1
            t_y, d_y = ((row + (1 if dy > 0.0 else 0)) * CELL - y) / dy, CELL / abs(dy)
        t_entry = 0.0
        while not truth.solid[row, col]:
            in_x = int(t_x <= t_y)
            t_entry = min(t_x, t_y)
            col, row = col + step_c * in_x, row + step_r * (1 - in_x)
            t_x, t_y = t_x + d_x * in_x, t_y + d_y * (1 - in_x)
            if t_entry > range_m:
                t_entry = math.inf
                break
        out[i] = t_entry
    return out


def test_the_walk_gives_the_textbook_sums_bit_for_bit_also_from_cell_boundaries() -> None:
    truth = generate("building", 30, 2)
    rng = np.random.default_rng(5)
    poses = random_free_poses(truth, 12, rng)
    poses[:4, :2] = np.round(poses[:4, :2] / CELL) * CELL   # on cell corners: boundary distances of -0.0
    poses[4:8, 0] = np.round(poses[4:8, 0] / CELL) * CELL   # on a column boundary
    poses[::3, 2] = 0.0                                     # axis-parallel rays (dy == 0: t_y = inf)
    poses = poses[truth.solid[(poses[:, 1] // CELL).astype(int), (poses[:, 0] // CELL).astype(int)] == 0]
    # A robot on the corner of a wall cell: rays leaving down-left enter it at distance +0.0, after a
    # zero-length step past the corner (the sums turn the other boundary's -0.0 into +0.0 on the way).
    solid = room(12, 12)
    solid[3, 3] = True
    corner = make_map(solid)
    cases = [(truth, pose) for pose in poses] + [(corner, (2.0, 2.0, theta)) for theta in (0.0, 0.3, -2.0)]
    hits_at_zero = 0
    for mode in ("ternary", "logodds"):
        for world, pose in cases:
            lidar = Lidar(world, LidarParams(range_m=5.0, mode=mode))
            ranges = lidar.scan(np.array([pose]), empty_knowledge(world.shape, 1))[0]
            want = sum_walk_ranges(world, tuple(pose), lidar._cos, lidar._sin, 5.0)
            assert np.array_equal(ranges.view(np.uint32), want.view(np.uint32)), (mode, pose)
            hits_at_zero += int(np.count_nonzero(want == 0.0))
    assert hits_at_zero > 0


# ------------------------------------------------------------------------ settled robots (measure=False)
def _pair_of_lidars(truth: Map, n: int) -> tuple[tuple[Lidar, np.ndarray], tuple[Lidar, np.ndarray]]:
    """Two lidars with their own trackers and maps: one casts every robot, one skips settled robots."""
    return ((Lidar(truth, tracker=ExplorationTracker(truth)), empty_knowledge(truth.shape, n)),
            (Lidar(truth, tracker=ExplorationTracker(truth)), empty_knowledge(truth.shape, n)))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_skipping_settled_robots_leaves_maps_and_tracker_as_casting_every_robot(seed: int) -> None:
    truth = generate("building", 40, seed)
    rng = np.random.default_rng(seed)
    n = 6
    (full, full_known), (lazy, lazy_known) = _pair_of_lidars(truth, n)
    spots = random_free_poses(truth, 40, rng)  # the places robots come back to
    survey = random_free_poses(truth, 600, rng)  # both lidars first survey the map, so robots can be settled
    for lidar, known in ((full, full_known), (lazy, lazy_known)):
        for k in range(0, len(survey), n):
            lidar.scan(survey[k:k + n], known)
    skipped = cast = 0
    for step in range(60):
        poses = spots[rng.integers(0, len(spots), n)].copy()
        poses[:, 2] = rng.uniform(-math.pi, math.pi, n)
        poses[:, :2] += rng.uniform(-0.2, 0.2, (n, 2)) * (truth.free[(poses[:, 1] // CELL).astype(int),
                                                                    (poses[:, 0] // CELL).astype(int)])[:, None]
        poses = poses[truth.free[(poses[:, 1] // CELL).astype(int), (poses[:, 0] // CELL).astype(int)]]
        active = rng.random(len(poses)) > 0.1
        if len(poses) < n:
            continue
        if step % 4 == 3:   # map sharing: every robot takes the others' maps (maxima)
            for known in (full_known, lazy_known):
                known[:] = known.max(axis=0)
        if step % 2:        # damage: forget cells, and wrong walls in free space (merged from a peer)
            r = rng.integers(0, n, 2)
            cells = rng.integers(0, truth.shape[0], (20, 2))
            value = rng.integers(0, 3, 20).astype(np.uint8)
            for known in (full_known, lazy_known):
                known[r[:, None], cells[:, 0], cells[:, 1]] = value
        assert full.scan(poses, full_known, active=active) is not None
        assert lazy.scan(poses, lazy_known, active=active, measure=False) is None
        assert np.array_equal(full_known, lazy_known)
        assert np.array_equal(full.tracker.seen, lazy.tracker.seen)
        assert full.tracker.seen_free_cells == lazy.tracker.seen_free_cells
        assert np.array_equal(full.cast, active)
        assert not lazy.cast[~active].any()
        skipped += int(np.count_nonzero(active & ~lazy.cast))
        cast += int(np.count_nonzero(lazy.cast))
    assert skipped > 20 and cast > 20  # both paths were taken


def test_a_settled_robot_is_cast_again_when_any_cell_its_rays_reach_is_missing() -> None:
    truth = generate("building", 40, 5)
    pose = random_free_poses(truth, 1, np.random.default_rng(5))
    written = empty_knowledge(truth.shape, 1)
    Lidar(truth).scan(pose, written)                             # the cells one scan from here writes
    lidar = Lidar(truth)
    everything = np.where(truth.solid, SOLID, FREE).astype(np.uint8)[None]
    lidar.tracker.seen_buffer[:] = True                          # the map and the tracker hold everything
    known = everything.copy()
    lidar.scan(pose, known, measure=False)
    assert not lidar.cast[0] and np.array_equal(known, everything)   # settled: not cast, nothing written
    rows, cols = np.nonzero(written[0])
    x, y = pose[0, 0], pose[0, 1]
    far = np.argsort(np.hypot((cols + 0.5) * CELL - x, (rows + 0.5) * CELL - y))[-12:]
    for r, c in zip(rows[far], cols[far]):                       # the farthest cells the rays write
        known[0, r, c] = UNSEEN
        lidar.scan(pose, known, measure=False)
        assert lidar.cast[0] and np.array_equal(known, everything)
    r0, c0 = int(y // CELL), int(x // CELL)
    outside = everything.copy()
    outside[0, np.abs(np.arange(truth.shape[0]) - r0) > 16] = UNSEEN     # beyond the reach: still settled
    outside[0, :, np.abs(np.arange(truth.shape[1]) - c0) > 16] = UNSEEN
    lidar.scan(pose, outside, measure=False)
    assert not lidar.cast[0]


def test_a_wall_cell_the_tracker_has_not_seen_keeps_the_robot_cast() -> None:
    truth = make_map(room(30, 30))
    pose = np.array([[2.3, 2.4, 0.0]])                           # near the corner: the walls are in range
    lidar = Lidar(truth)
    known = np.where(truth.solid, SOLID, FREE).astype(np.uint8)[None]
    lidar.tracker.seen_buffer[:] = True
    lidar.scan(pose, known, measure=False)
    assert not lidar.cast[0]
    lidar.tracker.seen_buffer[0, 3] = False                      # a wall cell the rays hit
    lidar.scan(pose, known, measure=False)
    assert lidar.cast[0] and lidar.tracker.seen[0, 3]
    lidar.scan(pose, known, measure=False)
    assert not lidar.cast[0]
    lidar.tracker.seen_buffer[0, 0] = False                      # a corner no ray can enter: no matter
    lidar.scan(pose, known, measure=False)
    assert not lidar.cast[0]


def test_a_robot_inside_a_thick_wall_is_cast_although_no_ray_could_enter_its_cell() -> None:
    solid = np.ones((30, 30), dtype=bool)
    solid[3:-3, 3:-3] = False
    truth = make_map(solid)
    lidar = Lidar(truth)
    known = np.where(truth.solid, SOLID, FREE).astype(np.uint8)[None]
    lidar.tracker.seen_buffer[:] = True
    known[0, 1, 1] = UNSEEN                                      # enclosed by wall: only a robot in it sees it
    lidar.scan(np.array([[3.0, 3.0, 0.0]]), known, measure=False)
    assert not lidar.cast[0] and known[0, 1, 1] == UNSEEN
    lidar.scan(np.array([[0.7, 0.7, 0.0]]), known, measure=False)
    assert lidar.cast[0] and known[0, 1, 1] == SOLID


# ---------------------------------------------------------------- own sight: overlap and coverage spread ----
def two_rooms() -> Map:
    """Two 18 x 18-cell rooms side by side, parted by a wall two cells thick: no ray from one room reaches a cell
    a ray from the other reaches (rays stop at the first solid cell)."""
    solid = np.ones((20, 40), dtype=bool)
    solid[1:-1, 1:19] = False
    solid[1:-1, 21:39] = False
    return make_map(solid)


def tracked_scan(truth: Map, poses: list[tuple[float, float, float]], mode: str = "ternary",
                 measure: bool = True) -> tuple[Lidar, ExplorationTracker]:
    tracker = ExplorationTracker(truth)
    tracker.track_robots(len(poses))
    lidar = Lidar(truth, LidarParams(mode=mode), tracker=tracker)
    lidar.scan(np.array(poses), empty_knowledge(truth.shape, len(poses)), np.random.default_rng(0), measure=measure)
    return lidar, tracker


@pytest.mark.parametrize("mode", ["ternary", "logodds"])
def test_robots_that_see_disjoint_rooms_overlap_zero(mode: str) -> None:
    _, trk = tracked_scan(two_rooms(), [(5.0, 5.0, 0.0), (15.0, 5.0, 0.0)], mode)
    own = trk.own_seen_cells
    assert own[0] > 0 and own[1] > 0
    assert trk.overlap_rate() == 0.0
    assert own.sum() == np.count_nonzero(trk.seen) == np.count_nonzero(trk.seers)   # each cell seen by one
    shares = own / np.count_nonzero(trk.seen)
    assert trk.coverage_spread() == pytest.approx(abs(shares[0] - shares[1]) / 2)   # population std of two


@pytest.mark.parametrize("mode", ["ternary", "logodds"])
def test_robots_that_see_the_same_cells_overlap_one(mode: str) -> None:
    _, trk = tracked_scan(two_rooms(), [(5.0, 5.0, 0.0), (5.0, 5.0, 0.0)], mode)
    assert trk.overlap_rate() == 1.0 and trk.coverage_spread() == 0.0
    assert trk.own_seen_cells.tolist() == [np.count_nonzero(trk.seen)] * 2
    assert trk.seers.max() == 2


def test_overlap_counts_cells_seen_by_two_of_three_over_cells_seen() -> None:
    # robots 0 and 1 share the left room, robot 2 is alone in the right one
    _, trk = tracked_scan(two_rooms(), [(5.0, 5.0, 0.0), (5.0, 5.0, 0.0), (15.0, 5.0, 0.0)])
    left, right = trk.own_seen_cells[0], trk.own_seen_cells[2]
    assert trk.overlap_rate() == pytest.approx(left / (left + right))


def test_a_robot_in_cells_it_only_heard_of_is_cast_and_counted() -> None:
    """The ternary lidar skips robots whose scan would write nothing new (``measure=False``); a robot whose map
    holds its surroundings only through map sharing has not seen them itself, so tracking own sight casts it."""
    truth = make_map(room(12, 12))   # a convex room within range: the rays from its centre see every cell
    for tracking in (False, True):
        tracker = ExplorationTracker(truth)
        if tracking:
            tracker.track_robots(2)
        lidar = Lidar(truth, LidarParams(), tracker=tracker)
        known = empty_knowledge(truth.shape, 2)
        pose = np.array([[3.0, 3.0, 0.0], [3.0, 3.0, 0.0]])
        lidar.scan(pose, known, measure=False, active=np.array([True, False]))
        known[1] = known[0]   # robot 1 hears robot 0's map
        lidar.scan(pose, known, measure=False, active=np.array([False, True]))
        assert bool(lidar.cast[1]) is tracking
    assert tracker.overlap_rate() == 1.0
    lidar.scan(pose, known, measure=False)   # now both have seen everything in reach themselves: both settled
    assert not lidar.cast.any()


def test_measuring_scans_track_own_sight_too() -> None:
    """The localisation path measures (``write=False``) and writes from the believed pose: own sight is what the
    lidar saw from the true pose."""
    truth = two_rooms()
    tracker = ExplorationTracker(truth)
    tracker.track_robots(2)
    lidar = Lidar(truth, LidarParams(), tracker=tracker)
    lidar.scan(np.array([[5.0, 5.0, 0.0], [15.0, 5.0, 0.0]]), empty_knowledge(truth.shape, 2), write=False)
    assert tracker.overlap_rate() == 0.0 and tracker.own_seen_cells.sum() == np.count_nonzero(tracker.seen)


def test_a_tracker_of_other_robot_count_is_refused() -> None:
    truth = two_rooms()
    tracker = ExplorationTracker(truth)
    tracker.track_robots(3)
    with pytest.raises(InvalidInput):
        Lidar(truth, LidarParams(), tracker=tracker).scan(np.array([[5.0, 5.0, 0.0]] * 2),
                                                         empty_knowledge(truth.shape, 2))


def test_own_sight_takes_a_bit_per_robot_and_cell_and_keeps_robots_apart() -> None:
    """The own-sight mask holds a bit per robot and cell (a byte took 1 GB in a 10,000-robot swarm's first
    tick); a map whose cell count is no multiple of 64 still keeps each robot's bits apart: the same scan by
    robot 1 alone counts as its own first sight, not robot 0's."""
    truth = two_rooms()  # 800 cells: 12.5 words a robot
    tracker = ExplorationTracker(truth)
    tracker.track_robots(3)
    own = tracker.sight_buffers[0]
    assert own.dtype == np.uint64 and own.shape == (3, 13)
    lidar = Lidar(truth, LidarParams(), tracker=tracker)
    pose = np.array([[5.0, 5.0, 0.0]] * 3)
    lidar.scan(pose, empty_knowledge(truth.shape, 3), active=np.array([True, False, False]))
    first = int(tracker.own_seen_cells[0])
    lidar.scan(pose, empty_knowledge(truth.shape, 3), active=np.array([False, True, False]))
    assert tracker.own_seen_cells.tolist() == [first, first, 0]
    assert int(tracker.seers.max()) == 2
