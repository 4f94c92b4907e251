"""Exploration fitness: docs/boa.md section 12 test 10, and the issue's "gain table equals per-candidate
evaluation for every goal of a fixed belief on the house map" (plus the same on a synthetic map, so CI
tests it without the paper's files)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.ndimage import gaussian_filter

from algorithms.boa import minimize
from algorithms.boa.beams import NORTH, Lidar, heading_index, visible_cells
from algorithms.boa.fitness import Belief, ExplorationProblem
from algorithms.boa.gridworld import load_xboa_csv, paper_map_path, synthetic_house
from swarm.base.errors import InvalidInput

HOUSE = paper_map_path("house")
needs_house = pytest.mark.skipif(HOUSE is None, reason="the paper's map-house.csv is not available "
                                 "(set XBOA_MAPS or place ../shared/data/xboa-maps beside the repository)")


def belief_after_scans(truth: np.ndarray, poses: list[tuple[int, int, int]], cell_m: float = 1.0) -> Belief:
    """A fixed belief: noise-free scans at ``poses`` on the truth grid."""
    tables = Lidar().tables(cell_m)
    known = np.zeros(truth.size, bool)
    for (r, c, h) in poses:
        known[visible_cells(truth, r, c, h, tables)] = True
    known = known.reshape(truth.shape)
    return Belief(~known, known & truth, cell_m)


def reference_gains(problem: ExplorationProblem) -> np.ndarray:
    """Per-candidate evaluation: for every goal, the union of the (separately walked) beams of every pose
    on the same tree path, intersected with the unknown cells. Plain numpy, no trie, no tree pass."""
    H, W = problem.shape
    occ = problem.belief.occupied
    unknown = problem.belief.unknown.ravel()
    cache: dict[tuple[int, int, int], np.ndarray] = {}
    out = np.zeros((H, W), np.int64)
    for r in range(H):
        for c in range(W):
            st = int(problem.tree.cell_state[r * W + c])
            if st < 0:
                continue
            seen: set[int] = set()
            for pose in problem.tree.path(st)[1:]:
                if pose not in cache:
                    cache[pose] = visible_cells(occ, *pose, problem.tables)
                seen.update(cache[pose].tolist())
            out[r, c] = sum(1 for k in seen if unknown[k])
    return out


def check_table_equals_per_candidate(truth: np.ndarray, poses, start, heading) -> None:
    belief = belief_after_scans(truth, poses)
    table = ExplorationProblem(belief, start, heading, 300, mode="table")
    lazy = ExplorationProblem(belief, start, heading, 300, mode="lazy")
    ref = reference_gains(table)
    H, W = truth.shape
    ys, xs = np.mgrid[0:H, 0:W]
    lazy_gain = -lazy(np.c_[xs.ravel(), ys.ravel()].astype(float)).reshape(H, W)
    assert (ref > 0).sum() > 0.8 * (~truth).sum()         # non-trivial: most goals see something
    assert np.array_equal(table.gain_table(), ref)
    assert np.array_equal(lazy_gain, ref)
    # and the plan of the best goal reproduces the table value along the same poses
    best = np.unravel_index(np.argmax(ref), ref.shape)
    plan = table.plan(np.array([best[1], best[0]], float))
    assert plan.gain == ref[best] and plan.poses[-1][:2] == best


@needs_house
def test_gain_table_equals_per_candidate_evaluation_on_the_house_map() -> None:
    truth = load_xboa_csv(HOUSE)
    # a mid-mission belief: the robot went from (1,1) up the left room and into the corridor
    poses = [(1, 1, NORTH), (3, 2, 1), (5, 4, NORTH), (8, 5, 0), (12, 6, 1), (12, 10, 0), (13, 13, 2)]
    check_table_equals_per_candidate(truth, poses, (13, 13), 0)
    check_table_equals_per_candidate(truth, [(1, 1, NORTH)], (1, 1), NORTH)


def test_gain_table_equals_per_candidate_evaluation_on_a_synthetic_map() -> None:
    truth = synthetic_house()
    poses = [(1, 1, NORTH), (4, 3, 1), (8, 8, 2), (11, 4, 2), (14, 5, 0)]
    check_table_equals_per_candidate(truth, poses, (14, 5), 0)


def test_lazy_equals_table_on_a_large_fine_belief() -> None:
    rng = np.random.default_rng(0)
    truth = rng.random((70, 90)) < 0.12
    truth[0, :] = truth[-1, :] = truth[:, 0] = truth[:, -1] = True
    truth[30:33, 40:45] = False
    belief = belief_after_scans(truth, [(31, 42, h) for h in range(8)], cell_m=0.5)
    a = ExplorationProblem(belief, (31, 42), 2, 400, mode="table").gain_table()
    lazy = ExplorationProblem(belief, (31, 42), 2, 400, mode="lazy")
    ys, xs = np.mgrid[0:70, 0:90]
    b = -lazy(np.c_[xs.ravel(), ys.ravel()].astype(float)).reshape(70, 90)
    assert np.array_equal(a, b) and a.max() > 100


def test_infeasible_goals_give_zero() -> None:
    truth = synthetic_house()
    belief = belief_after_scans(truth, [(1, 1, NORTH)])
    pr = ExplorationProblem(belief, (1, 1), NORTH, 300)
    f = lambda x, y: float(pr(np.array([[x, y]], float))[0])   # noqa: E731
    assert belief.occupied[1, 0] and f(0, 1) == 0.0             # a known wall (x = 0, y = 1)
    assert f(1, 1) == 0.0                                        # the robot's own cell
    assert f(20, 20) < 0.0
    short = ExplorationProblem(belief, (1, 1), NORTH, 10)
    energy = pr.energy_table()
    far = np.argwhere((energy > 10) & (pr.gain_table() > 0))
    r, c = far[0]
    assert float(short(np.array([[c, r]], float))[0]) == 0.0    # over the battery
    assert short.gain_table()[energy > 10].max() == 0


def test_energy_counts_rotations_and_moves() -> None:
    free = np.zeros((24, 24), bool)
    free[0, :] = free[-1, :] = free[:, 0] = free[:, -1] = True
    pr = ExplorationProblem(Belief(np.zeros_like(free), free, 1.0), (1, 1), NORTH, 300)
    assert pr.energy_table()[5, 5] == 5              # one 45 degree turn (north -> north-east) + 4 diagonal moves
    assert pr.energy_table()[5, 1] == 4              # straight north: no turn
    assert pr.energy_table()[1, 5] == 6              # two turns to face east + 4 moves
    assert pr.energy_table()[0, 0] == -1             # a wall


def test_gain_is_monotone_along_a_path_and_bounded() -> None:
    truth = synthetic_house()
    belief = belief_after_scans(truth, [(1, 1, NORTH), (5, 5, 1)])
    pr = ExplorationProblem(belief, (5, 5), 1, 300)
    table = pr.gain_table()
    W = truth.shape[1]
    for goal in [(20, 20), (20, 2), (2, 20), (10, 13)]:
        path = pr.tree.path_to_cell(*goal)
        gains = [table[r, c] for (r, c, h) in path if pr.tree.cell_state[r * W + c] == (r * W + c) * 8 + h]
        assert gains == sorted(gains)
    assert table.max() <= belief.unknown.sum()


def test_long_term_plans_chain_legs_and_count_the_union_once() -> None:
    truth = synthetic_house()
    belief = belief_after_scans(truth, [(1, 1, NORTH)])
    one = ExplorationProblem(belief, (1, 1), NORTH, 300)
    two = ExplorationProblem(belief, (1, 1), NORTH, 300, n_goals=2)
    g1, g2 = (8, 3), (8, 8)                       # (x, y)
    f1 = float(one(np.array([g1], float))[0])
    f12 = float(two(np.array([g1 + g2], float))[0])
    f11 = float(two(np.array([g1 + g1], float))[0])
    assert f11 == f1                              # revisiting a goal adds nothing
    assert f12 <= f1                              # more cells seen on the longer plan (fitness is negative)
    plan = two.plan(np.array(g1 + g2, float))
    assert plan.goals == ((3, 8), (8, 8)) and plan.poses[-1][:2] == (8, 8)
    assert plan.energy == len(plan.poses) and -plan.gain == f12
    tiny = ExplorationProblem(belief, (1, 1), NORTH, plan.energy - 1, n_goals=2)
    assert float(tiny(np.array([g1 + g2], float))[0]) == 0.0   # chained energy over the battery


def test_claimed_cells_count_as_known() -> None:
    truth = synthetic_house()
    belief = belief_after_scans(truth, [(1, 1, NORTH)])
    claimed = np.zeros_like(truth)
    claimed[12:, :] = True
    a = ExplorationProblem(belief, (1, 1), NORTH, 300).gain_table()
    b = ExplorationProblem(belief, (1, 1), NORTH, 300, claimed=claimed).gain_table()
    assert (b <= a).all() and b[20, 5] < a[20, 5] and b[5, 5] == a[5, 5]


def test_fan_geometry() -> None:
    tables = Lidar().tables(1.0)
    assert tables.fan.shape == (8, 181)
    open_grid = np.zeros((21, 21), bool)
    vis = visible_cells(open_grid, 10, 10, NORTH, tables)
    rows, cols = np.divmod(vis, 21)
    assert rows.min() == 10 and rows.max() == 14 and cols.min() == 6 and cols.max() == 14   # 4 m ahead, 4 m aside
    assert heading_index(np.pi / 2) == NORTH and heading_index(-np.pi / 4) == 7
    with pytest.raises(InvalidInput):
        Lidar(resolution_deg=0.7)


def test_belief_validation_and_knowledge_map() -> None:
    with pytest.raises(InvalidInput):
        Belief(np.zeros((3, 3), bool), np.zeros((3, 4), bool))
    known = np.array([[0, 1, 2]], np.uint8)
    b = Belief.from_knowledge(known)
    assert b.unknown.tolist() == [[True, False, False]] and b.occupied.tolist() == [[False, False, True]]
    assert b.cell_m == 0.5


def smooth_gain_table(seed: int) -> np.ndarray:
    """A seeded 24 x 24 smooth random gain field (periodic Gaussian-filtered noise, 0..250), as fitness."""
    z = gaussian_filter(np.random.default_rng(seed).standard_normal((24, 24)), 4.0, mode="wrap")
    return -np.round(250.0 * (z - z.min()) / (z.max() - z.min()))


def search_hits(pop: int, **kw) -> float:
    hits = []
    for seed in range(50):
        T = smooth_gain_table(seed)

        def f(X: np.ndarray) -> np.ndarray:
            cell = np.clip(np.floor(X + 0.5), 0, 23).astype(int)
            return T[cell[:, 1], cell[:, 0]]

        r = minimize(f, [(0, 23)] * 2, rng=np.random.default_rng(1000 + seed), variant="xBOA", pop_size=pop,
                     max_gen=30, early_stop=10, **kw)
        hits.append(r.f <= 0.95 * T.min())
    return float(np.mean(hits))


def test_xboa_grid_search_gets_near_the_exhaustive_optimum() -> None:
    """Measured (50 seeds, c = 0.01, a = 0.1, p = 0.8, code switch): pop 20 96 %, pop 5 58 % within 5 % of
    the exhaustive optimum (indicative values in docs/boa.md section 12 test 10, on an unspecified table: 100 % / 82 %).

    Documented, not asserted: the Table-2 presets reach 70 % (pop 20) and 24 % (pop 5) here, because the
    fragrance c|F|^a on raw fitness makes moves jump to the border (section 1 item 3); plain random
    sampling with the same number of evaluations reaches 100 % / 98 % - on a 576-cell problem a
    population of 20 over 30 generations nearly enumerates the grid.
    """
    kw = dict(c=0.01, a=0.1, p=0.8, switch="code")
    pop20 = search_hits(20, **kw)
    pop5 = search_hits(5, **kw)
    assert pop20 >= 0.90
    assert pop5 >= 0.45
    assert pop20 > pop5


def test_unlimited_battery() -> None:
    truth = synthetic_house()
    belief = belief_after_scans(truth, [(1, 1, NORTH)])
    a = ExplorationProblem(belief, (1, 1), NORTH, None).gain_table()
    b = ExplorationProblem(belief, (1, 1), NORTH, 10**6).gain_table()
    assert np.array_equal(a, b)
    two = ExplorationProblem(belief, (1, 1), NORTH, None, n_goals=2)
    assert float(two(np.array([[8.0, 3.0, 20.0, 20.0]]))[0]) < 0


@settings(max_examples=150, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), fov=st.sampled_from([90.0, 180.0, 360.0]),
       range_m=st.sampled_from([2.0, 4.0, 7.0]))
def test_predicted_observed_is_the_union_of_the_reference_scans(seed: int, fov: float, range_m: float):
    """The compiled trie walk (issue 35) marks exactly the cells the per-beam reference sees from each pose,
    poses off the grid and headings outside 0..7 included."""
    from algorithms.boa.fitness import predicted_observed

    rng = np.random.default_rng(seed)
    h, w = (int(v) for v in rng.integers(1, 50, size=2))
    belief = Belief(rng.random((h, w)) < 0.5, rng.random((h, w)) < rng.uniform(0, 0.4), float(rng.choice([0.5, 1.0])))
    lidar = Lidar(fov_deg=fov, range_m=range_m)
    poses = [(int(rng.integers(-3, h + 3)), int(rng.integers(-3, w + 3)), int(rng.integers(-1, 8)))
             for _ in range(int(rng.integers(0, 20)))]
    tables = lidar.tables(belief.cell_m)
    want = np.zeros(h * w, bool)
    for r, c, hd in poses:
        want[visible_cells(belief.occupied, r, c, hd, tables)] = True
    assert np.array_equal(predicted_observed(belief, poses, lidar), want.reshape(h, w))
