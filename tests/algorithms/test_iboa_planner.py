"""The IBOA navigation planner plug-in: collision-free cell paths the navigator accepts, its fallbacks, and a
run that explores with ``navigation.planner = "iboa"``."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.ndimage import label

from maps import generate
from swarm import grid
from swarm.api import FREE, SOLID
from swarm.plugins.planners import get_planner
from swarm.sim.loop import Simulation

from algorithms.boa.planner_plugin import IBOAPlanner, IBOAPlannerSettings, supercover_walk


def true_space(kind: str, size: int, seed: int) -> np.ndarray:
    m = generate(kind, size, seed=seed)
    return grid.configuration_space(np.where(m.solid, SOLID, FREE).astype(np.uint8))


def pairs(space: np.ndarray, n: int, rng: np.random.Generator) -> list[tuple[tuple[int, int], tuple[int, int]]]:
    lab, _ = label(space, structure=np.ones((3, 3)))
    big = np.argmax(np.bincount(lab.ravel())[1:]) + 1
    cells = np.argwhere(lab == big)
    out = []
    for _ in range(n):
        a, b = cells[rng.choice(len(cells), 2, replace=False)]
        out.append(((int(a[0]), int(a[1])), (int(b[0]), int(b[1]))))
    return out


def test_registered_for_the_navigator():
    assert isinstance(get_planner("iboa"), IBOAPlanner)


@pytest.mark.parametrize("a, b", [((0, 0), (3, 3)), ((0, 0), (2, 5)), ((5, 5), (5, 1)), ((4, 0), (0, 1)),
                                  ((2, 7), (9, 3))])
def test_supercover_walk_is_adjacent_and_covers_the_segment(a, b):
    walk = supercover_walk(a, b)
    assert walk[0] == a and walk[-1] == b
    steps = np.abs(np.diff(np.array(walk), axis=0))
    assert steps.max() <= 1 and (steps.sum(axis=1) >= 1).all()
    # the walk's cells are exactly the cells the runtime's segment test needs: block any one and it fails
    space = np.ones((12, 12), bool)
    for cell in set(walk):
        space[cell] = False
        assert not grid.segment_clear(space, a, b), f"{cell} is on the segment"
        space[cell] = True
    assert grid.segment_clear(space, a, b)


@pytest.mark.parametrize("kind, seed", [("building", 1), ("building", 2), ("cave", 3)])
def test_paths_are_collision_free_cell_chains_from_start_to_goal(kind, seed):
    space = true_space(kind, 25, seed)
    planner = IBOAPlanner()
    rng = np.random.default_rng(seed)
    for start, goal in pairs(space, 6, np.random.default_rng(seed)):
        path = planner.plan(space, start, goal, rng)
        assert path is not None and tuple(path[0]) == start and tuple(path[-1]) == goal
        assert space[path[:, 0], path[:, 1]].all(), "every cell of the path is in the configuration space"
        assert np.abs(np.diff(path, axis=0)).max() <= 1, "consecutive cells are 8-adjacent"
        for p, q in zip(path[:-1], path[1:]):    # diagonal steps cut no corner
            assert space[p[0], q[1]] or space[q[0], p[1]]
        way = grid.simplify(space, path)          # what the navigator does next
        cells = np.floor(way[:, ::-1] / 0.5).astype(int)
        assert all(grid.segment_clear(space, tuple(a), tuple(b)) for a, b in zip(cells[:-1], cells[1:]))
    assert planner.stats.iboa >= 5, planner.stats           # IBOA planned (not the A* fallback)


def test_same_rng_state_gives_the_same_path():
    space = true_space("building", 25, 1)
    (start, goal), = pairs(space, 1, np.random.default_rng(5))
    a = IBOAPlanner().plan(space, start, goal, np.random.default_rng(9))
    b = IBOAPlanner().plan(space, start, goal, np.random.default_rng(9))
    assert np.array_equal(a, b)


def test_unreachable_goal_is_none_and_oversized_windows_fall_back_to_astar():
    space = np.zeros((30, 30), bool)
    space[2:28, 2:12] = True
    space[2:28, 18:28] = True                      # two rooms, no door
    planner = IBOAPlanner()
    assert planner.plan(space, (5, 5), (5, 20), np.random.default_rng(0)) is None
    small = IBOAPlanner(IBOAPlannerSettings(max_window_cells=10))
    path = small.plan(space, (3, 3), (25, 10), np.random.default_rng(0))
    assert small.stats.fallback_size == 1 and small.stats.iboa == 0
    assert np.array_equal(path, grid.plan(space, (3, 3), (25, 10)))


def test_a_run_navigating_with_iboa_explores():
    sim = Simulation({"seed": 2, "map": {"kind": "building", "size": 20}, "robots": {"count": 1},
                      "navigation": {"planner": "iboa"}, "stop": {"max_ticks": 1500}})
    r = sim.run()
    assert r.summary["explored"] > 0.9
    assert sim.navigators[0].planner.stats.iboa > 5
    assert r.spec["navigation"]["planner"] == "iboa"
