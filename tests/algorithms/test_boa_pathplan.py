"""IBOA path planning (IBOA (Kent) grid planner, IBOA (Lévy) continuous planner) and the reference shortest paths."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.ndimage import label

from algorithms.boa.pathplan import (IBOAPlannerParams, plan_iboa, plan_path, simplify_los, simplify_rectangles,
                                     simplify_runs)
from algorithms.boa.pathplan_levy import (LevyPlannerParams, clearance, penalty, penalty_as_printed, plan_levy,
                                          polyline_lengths)
from algorithms.boa.shortest import (any_angle_length, astar, astar_length, path_free, path_length, segment_free)
from maps import generate
from swarm.base.errors import InvalidInput

SQ2 = math.sqrt(2.0)


def tile_grid(kind: str, seed: int, size: int = 40) -> np.ndarray:
    """A generated map at 1 m tiles: a tile is blocked if any of its four 0.5 m cells is solid."""
    s = generate(kind, size, seed=seed).solid
    return s.reshape(size, 2, size, 2).any(axis=(1, 3))


def random_pair(blocked: np.ndarray, rng: np.random.Generator) -> tuple[tuple[int, int], tuple[int, int]]:
    lab, _ = label(~blocked)                                  # 4-connected: always reachable without corner cuts
    big = np.argmax(np.bincount(lab.ravel())[1:]) + 1
    free = np.argwhere(lab == big)
    a, b = free[rng.choice(len(free), 2, replace=False)]
    return (int(a[0]), int(a[1])), (int(b[0]), int(b[1]))


# ---------------------------------------------------------------- reference shortest paths
def test_astar_and_any_angle_on_known_cases() -> None:
    g = np.zeros((10, 10), bool)
    assert astar_length(g, (0, 0), (9, 9)) == pytest.approx(9 * SQ2)
    assert astar_length(g, (0, 0), (9, 3)) == pytest.approx(6 + 3 * SQ2)
    assert any_angle_length(g, (0, 0), (9, 3)) == pytest.approx(math.hypot(9, 3))
    g[5, 0:8] = True                                          # a wall with a gap on the right
    assert any_angle_length(g, (0, 0), (9, 0)) == pytest.approx(math.hypot(7.5, 4.5) + 1 + math.hypot(7.5, 3.5))
    pinch = np.zeros((4, 4), bool)
    pinch[1, 1] = pinch[2, 2] = True                          # two walls touching at a corner
    assert any_angle_length(pinch, (2, 1), (1, 2)) == pytest.approx(2 + SQ2)   # around, not through the corner
    assert astar_length(pinch, (2, 1), (1, 2)) == pytest.approx(6.0)          # no corner cutting
    closed = np.zeros((5, 5), bool)
    closed[2, :] = True
    assert math.isinf(astar_length(closed, (0, 0), (4, 4))) and astar(closed, (0, 0), (4, 4)) is None
    assert math.isinf(any_angle_length(closed, (0, 0), (4, 4)))


def test_segment_free_matches_exact_geometry() -> None:
    """Supercover: blocked iff a blocked cell's closed square meets the segment between centres."""
    rng = np.random.default_rng(0)
    for _ in range(300):
        g = rng.random((9, 9)) < 0.15
        a, b = tuple(rng.integers(0, 9, 2)), tuple(rng.integers(0, 9, 2))
        g[a] = g[b] = False
        p0, p1 = np.array([a[1] + 0.5, a[0] + 0.5]), np.array([b[1] + 0.5, b[0] + 0.5])
        hit = False
        for r, c in np.argwhere(g):
            # Liang-Barsky clip of the segment against the closed square [c, c+1] x [r, r+1]
            t0, t1, d = 0.0, 1.0, p1 - p0
            ok = True
            for pk, qk in ((-d[0], p0[0] - c), (d[0], c + 1 - p0[0]), (-d[1], p0[1] - r), (d[1], r + 1 - p0[1])):
                if pk == 0:
                    ok &= qk >= 0
                elif pk < 0:
                    t0 = max(t0, qk / pk)
                else:
                    t1 = min(t1, qk / pk)
            if ok and t0 <= t1 + 1e-12:
                hit = True
                break
        assert segment_free(g, a, b) == (not hit)


@pytest.mark.parametrize("kind", ["building", "cave"])
def test_reference_lengths_are_ordered(kind: str) -> None:
    rng = np.random.default_rng(1)
    for seed in range(3):
        g = tile_grid(kind, seed)
        a, b = random_pair(g, rng)
        path = astar(g, a, b)
        assert path[0] == a and path[-1] == b and path_free(g, path)
        assert path_length(path) == pytest.approx(astar_length(g, a, b))
        assert any_angle_length(g, a, b) <= astar_length(g, a, b) + 1e-9
        assert any_angle_length(g, a, b) >= math.dist(a, b) - 1e-9


# ---------------------------------------------------------------- IBOA grid planner
def check_grid_path(g: np.ndarray, p, a, b) -> None:
    cells = list(p.cells)
    assert cells[0] == a and cells[-1] == b
    steps = np.abs(np.diff(np.array(cells), axis=0))
    assert (steps.max(axis=1) == 1).all()                       # 8-connected, one cell per step
    assert path_free(g, cells)                                  # no blocked cell, no corner cutting
    assert path_free(g, list(p.waypoints))                      # simplified segments touch only free cells
    assert p.waypoints[0] == a and p.waypoints[-1] == b
    assert p.length <= p.grid_length + 1e-9
    assert p.grid_length >= astar_length(g, a, b) - 1e-9
    assert p.length >= any_angle_length(g, a, b) - 1e-9


@pytest.mark.parametrize("kind", ["building", "cave"])
def test_iboa_paths_are_collision_free_and_simplification_never_longer(kind: str) -> None:
    rng = np.random.default_rng(2)
    for seed in range(3):
        g = tile_grid(kind, seed)
        a, b = random_pair(g, rng)
        p = plan_iboa(g, a, b, np.random.default_rng(seed), IBOAPlannerParams(pop_size=30, max_gen=30))
        check_grid_path(g, p, a, b)
        cells = list(p.cells)
        s1 = simplify_rectangles(g, cells)
        s2 = simplify_runs(g, s1)
        s3 = simplify_los(g, s2)
        for before, after in ((cells, s1), (s1, s2), (s2, s3)):
            assert path_length(after) <= path_length(before) + 1e-9
            assert path_free(g, after) and set(after) <= set(before)
        assert p.waypoints == tuple(s2)


def test_iboa_planner_is_deterministic_and_handles_orientation() -> None:
    g = tile_grid("building", 4)
    a, b = random_pair(g, np.random.default_rng(5))
    prm = IBOAPlannerParams(pop_size=20, max_gen=20)
    p1 = plan_iboa(g, a, b, np.random.default_rng(9), prm)
    p2 = plan_iboa(g, a, b, np.random.default_rng(9), prm)
    assert p1 == p2
    for s, t in ((b, a), ((a[0], a[1]), (a[0], min(a[1] + 1, g.shape[1] - 1)))):
        if g[t]:
            continue
        check_grid_path(g, plan_iboa(g, s, t, np.random.default_rng(0), prm), s, t)


def test_simplification_cases_of_paper_001() -> None:
    open_ = np.zeros((6, 8), bool)
    # case 1: P(i), P(i+2) are corners of a free 3 x 2 frame -> P(i+1) removed
    assert simplify_rectangles(open_, [(1, 1), (1, 2), (2, 3)]) == [(1, 1), (2, 3)]
    # case 2: same row, free 3 x 3 frame -> removed; a blocked cell in the frame keeps it
    assert simplify_rectangles(open_, [(2, 1), (2, 2), (2, 3)]) == [(2, 1), (2, 3)]
    g = open_.copy()
    g[3, 2] = True
    assert simplify_rectangles(g, [(2, 1), (2, 2), (2, 3)]) == [(2, 1), (2, 2), (2, 3)]
    # strategy 2: points in adjacent rows with long free runs from both ends, one blocked cell in the frame
    g = np.zeros((4, 10), bool)
    g[2, 1] = True
    pts = [(1, 0), (1, 1), (1, 2), (1, 3), (1, 4), (1, 5), (2, 6), (2, 7), (2, 8)]
    s1 = simplify_rectangles(g, pts)
    s2 = simplify_runs(g, s1)
    assert len(s2) < len(s1) and path_free(g, s2) and path_length(s2) <= path_length(s1)


def test_plan_path_hook() -> None:
    g = tile_grid("cave", 2)
    a, b = random_pair(g, np.random.default_rng(3))
    assert plan_path(g, a, b, np.random.default_rng(0), planner="astar") == astar(g, a, b)
    way = plan_path(g, a, b, np.random.default_rng(0), planner="iboa", params=IBOAPlannerParams(pop_size=20, max_gen=20))
    assert way[0] == a and way[-1] == b and path_free(g, way)
    with pytest.raises(InvalidInput):
        plan_path(g, a, b, np.random.default_rng(0), planner="rrt")
    with pytest.raises(InvalidInput):
        plan_iboa(g, (0, 0), b, np.random.default_rng(0))                 # a wall cell


# ---------------------------------------------------------------- IBOA-Levy continuous planner
OBSTACLES = np.array([(50, 40, 12), (90, 70, 15), (140, 50, 18), (170, 100, 14), (110, 20, 10)], float)


def test_penalty_sign_is_fixed() -> None:
    through = np.array([[[40.0, 40.0], [60.0, 40.0]]])        # straight through obstacle 0's centre
    around = np.array([[[40.0, 60.0], [60.0, 60.0]]])         # same length, clear of it
    assert penalty(through, OBSTACLES, 25)[0] > 0 and penalty(around, OBSTACLES, 25)[0] == 0
    assert penalty_as_printed(through, OBSTACLES, 25)[0] < 0  # the printed Eq. 13 would reward the collision
    assert polyline_lengths(through)[0] == polyline_lengths(around)[0] == 20.0
    grazing = np.array([[[30.0, 40.0], [70.0, 40.0 + 11.5]]])  # clips the circle between sample points
    assert penalty(grazing, OBSTACLES, 2)[0] > 0


def test_levy_planner_finds_collision_free_paths_with_a_strong_penalty() -> None:
    # measured (10 seeds): w = 1000 -> all paths clear (min clearance 0.04); the paper's w = 10 -> 6 of 10
    # clear, the others clip an obstacle by up to 3 units (the penalty is an average over path points)
    lengths = []
    for seed in range(4):
        p = plan_levy(OBSTACLES, (10, 10), (220, 140), ((0, 230), (0, 150)), np.random.default_rng(seed),
                      LevyPlannerParams(penalty_weight=1000.0))
        assert p.clearance >= 0.0 and p.penalty == 0.0
        assert tuple(p.points[0]) == (10, 10) and tuple(p.points[-1]) == (220, 140)
        assert clearance(p.points, OBSTACLES) == p.clearance
        lengths.append(p.length)
    assert max(lengths) < 1.15 * math.hypot(210, 130)          # measured mean 263 vs straight 247


def test_plan_report_for_the_cli() -> None:
    from algorithms.boa import plan_report

    g = tile_grid("building", 1)
    a, b = random_pair(g, np.random.default_rng(4))
    rep = plan_report(g, a, b, np.random.default_rng(0), IBOAPlannerParams(pop_size=20, max_gen=20))
    assert rep.any_angle_length <= rep.astar_length <= rep.path.grid_length + 1e-9
    assert rep.any_angle_length <= rep.path.length + 1e-9
