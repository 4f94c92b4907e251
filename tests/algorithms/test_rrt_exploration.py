"""RRT exploration (Umari and Mukhopadhyay 2017, the authors' rrt_exploration package): the global tree
finds a frontier the local one misses; the filter's mean shift and its dropping of points that are no longer
frontiers; the assigner's revenue, hysteresis and discount; the checker; a 50-tile building with 4 robots."""

from __future__ import annotations

import numpy as np
import pytest

from algorithms.rrt_exploration import (Detector, RRTExploration, RRTExplorationParams, filter_points, mean_shift,
                                        obstacle_free, revenues, steer, unknown_area)
from swarm.api import CELL_M, FREE, SOLID, UNSEEN, InvalidInput, Observation, Pose, RobotInfo
from swarm.sim.loop import Simulation

ALGORITHM = "algorithms.rrt_exploration:RRTExploration"
P = RRTExplorationParams()


def hall() -> np.ndarray:
    """A 60 x 20 m hall, known free, with an unexplored gap in its west wall (x 0, y 2-18) next to the robot
    and one in its east wall (x 59.5, y 8-12) 58 m away."""
    known = np.full((40, 120), SOLID, dtype=np.uint8)
    known[1:39, 1:119] = FREE
    known[4:36, 0] = UNSEEN
    known[16:24, 119] = UNSEEN
    return known


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_the_global_tree_finds_the_far_frontier_the_local_one_misses(seed):
    rng, robot = np.random.default_rng(seed), (2.0, 10.0)
    local, glob = Detector(P.local_eta, True, P.max_vertices), Detector(P.global_eta, False, P.max_vertices)
    local.root(robot)
    glob.root(robot)
    near = local.step(hall(), robot, rng, 2000)
    far = glob.step(hall(), robot, rng, 2000)
    assert near and all(x < 1.0 for x, _ in near), "the local tree, reset at the robot, finds the west gap only"
    assert local.n < 1000, "it was reset"
    assert any(x > 59.0 for x, _ in far), "the global tree, never reset, reaches the east gap"
    assert glob.n > 1000


def _python_step(det: Detector, known: np.ndarray, robot_xy: tuple[float, float], rng: np.random.Generator,
                 iterations: int) -> list[tuple[float, float]]:
    """The detector's step as the authors' loop, in Python (sampling, nearest vertex, growth, re-rooting):
    the reference the compiled loop must equal. ``steer`` and ``obstacle_free`` run the same kernels as the
    compiled step; their own tests check them on hand-built cases."""
    h, w = known.shape
    found = []
    for _ in range(iterations):
        rand = np.array([rng.random() * w * CELL_M, rng.random() * h * CELL_M])
        v = det.vertices[:det.n]
        nearest = v[int(np.argmin(np.einsum("ij,ij->i", v - rand, v - rand)))]
        new = steer(nearest, rand, det.eta)
        state, point = obstacle_free(known, nearest, new)
        if state == -1:
            found.append((float(point[0]), float(point[1])))
            if det.reset_on_frontier:
                det.root(robot_xy)
        elif state == 1 and det.n < det.max_vertices:
            if det.n == det.vertices.shape[0]:
                det.vertices = np.concatenate([det.vertices, np.zeros_like(det.vertices)])
            det.vertices[det.n] = new
            det.n += 1
    return found


@pytest.mark.parametrize("eta, reset", [(1.0, True), (15.0, False), (3.0, False)])
def test_the_compiled_step_grows_the_python_tree_bit_for_bit(eta, reset):
    rng = np.random.default_rng(5)
    known = rng.choice(np.array([FREE, FREE, FREE, SOLID, UNSEEN], dtype=np.uint8), size=(60, 80))
    known[20:40, 20:60] = FREE
    compiled, python = Detector(eta, reset, 300), Detector(eta, reset, 300)
    for det in (compiled, python):
        det.root((20.0, 15.0))
    a, b = np.random.default_rng(9), np.random.default_rng(9)
    points = 0
    for tick in range(40):
        got = compiled.step(known, (20.0 + tick * 0.1, 15.0), a, 10)
        want = _python_step(python, known, (20.0 + tick * 0.1, 15.0), b, 10)
        assert got == want and compiled.n == python.n
        assert np.array_equal(compiled.vertices[:compiled.n], python.vertices[:python.n])
        points += len(got)
    assert a.random() == b.random()                       # the same draws consumed
    assert points > 0 and compiled.n > 1                  # frontier points found, the tree grew


def test_obstacle_free_is_free_frontier_or_blocked():
    k = hall()
    assert obstacle_free(k, np.array([5.0, 10.0]), np.array([9.0, 10.0]))[0] == 1
    state, point = obstacle_free(k, np.array([3.0, 10.0]), np.array([-5.0, 10.0]))
    assert state == -1 and 0.0 <= point[0] < 0.5, "stops at the first unknown point"
    state, _ = obstacle_free(k, np.array([5.0, 1.0]), np.array([5.0, -5.0]))
    assert state == 0, "the south wall first"


def test_mean_shift_merges_points_within_the_bandwidth():
    pts = np.array([[1.0, 1.0], [1.1, 1.0], [1.0, 1.1], [5.0, 5.0]])
    centres = mean_shift(pts, 0.3)
    assert len(centres) == 2
    assert np.allclose(centres[0], [31 / 30, 31 / 30]) and np.allclose(centres[1], [5.0, 5.0]), "densest first"


def test_the_filter_drops_a_point_once_it_is_no_longer_a_frontier():
    k = hall()
    point = np.array([[0.6, 10.0]])      # beside the west gap
    middle = np.array([[30.0, 10.0]])    # known free all round: not a frontier
    assert filter_points(k, np.concatenate([point, middle]), P, 0.3).tolist() == point.tolist()
    seen = k.copy()
    seen[4:36, 0] = FREE                 # the gap seen (free, the map's edge beyond): no unknown left there
    assert len(filter_points(seen, point, P, 0.3)) == 0
    walled = k.copy()
    walled[4:36, 0] = SOLID              # seen to be wall: dropped, and inflated besides
    assert len(filter_points(walled, point, P, 0.3)) == 0
    assert len(filter_points(k, np.array([[0.6, 1.0]]), P, 0.3)) == 0, "in the corner: inflated obstacle space"


def test_revenue_is_gain_times_multiplier_minus_cost_with_hysteresis_and_discount():
    k = np.full((40, 40), FREE, dtype=np.uint8)
    k[10:14, 30:34] = UNSEEN
    c = np.array([[15.75, 5.75]])        # a centroid next to the unknown block
    gain = unknown_area(k, c[0], P.info_radius)
    assert gain > 0
    robot = np.array([5.75, 5.75])       # 10 m away: no hysteresis
    assert revenues(k, c, robot, None, [], P)[0] == pytest.approx(gain * 3.0 - 10.0)
    near = np.array([13.75, 5.75])       # 2 m away: gain doubled
    assert revenues(k, c, near, None, [], P)[0] == pytest.approx(gain * 2 * 3.0 - 2.0)
    other = [c[0] + [0.5, 0.0]]          # another robot's goal beside it takes the shared unknown area
    shared = unknown_area(k, c[0], P.info_radius, also=other[0])
    assert shared > 0
    assert revenues(k, c, robot, None, other, P)[0] == pytest.approx((gain - shared) * 3.0 - 10.0)
    busy = revenues(k, c, robot, c[0], other, P)[0]
    assert busy == pytest.approx(gain * 2 * 3.0 - 10.0), "near its own goal: undiscounted gain, doubled"


def test_randomness_comes_from_the_rng():
    def run(seed):
        x = RRTExploration()
        x.reset(RobotInfo(id=0, n_robots=1, map_shape=(40, 120)), P, np.random.default_rng(seed))
        known = hall()
        known.flags.writeable = False
        for t in range(3):
            x.act(Observation(tick=t, robot_id=0, pose=Pose(30.0, 10.0, 0.0), known=known))
        return x.global_.vertices[:x.global_.n].copy()
    assert np.array_equal(run(1), run(1)) and not np.array_equal(run(1), run(2))


@pytest.mark.parametrize("params, field", [
    ({"local_eta": 0.0}, "local_eta"), ({"global_eta": -1.0}, "global_eta"), ({"bandwidth": 0.0}, "bandwidth"),
    ({"info_radius": 0.0}, "info_radius"), ({"assign_ticks": 0}, "assign_ticks"),
    ({"iterations_per_tick": -1}, "iterations_per_tick"), ({"hysteresis_gain": -1.0}, "hysteresis_gain"),
])
def test_bad_parameters_are_one_line_errors_naming_the_field(params, field):
    with pytest.raises(InvalidInput) as err:
        RRTExplorationParams(**params)
    assert err.value.field == field and "\n" not in str(err.value)


def test_four_robots_explore_a_50_tile_building():
    """Measured (seeds 1-3, 1,500 ticks): 0.63, 0.61, 0.80 explored (nearest frontier: 0.61, 0.68, 0.78)."""
    r = Simulation({"seed": 1, "map": {"kind": "building", "size": 50}, "robots": {"count": 4},
                    "algorithm": {"name": ALGORITHM}, "stop": {"max_ticks": 1500}}).run()
    assert r.summary["explored"] > 0.55, r.one_line()
