"""xBOA's windowed decision inputs equal the whole-map ones they replace (issue 47): reachability from a
window around the horizon, the coarsened window and the seen-from-claims window, on hand-built maps that
force the window to grow and on random maps with many separate components."""

from __future__ import annotations

import math

import numpy as np
import pytest

from algorithms.boa import Belief, predicted_observed
from algorithms.xboa import (
    REACH_MARGIN_CELLS,
    SNAP_CELLS,
    XBOA,
    XBOAParams,
    coarsen,
    coarsen_window,
    local_reach,
    local_tile_view,
    tile_view,
)
from swarm.api import FREE, SOLID, UNSEEN, RobotInfo, grid

RADIUS = 0.25


def whole_map(known: np.ndarray, here: tuple[int, int], f: int, horizon: int, range_tiles: float):
    """The decision's inputs as xBOA computed them before issue 47: every array over the whole map."""
    space = grid.configuration_space(known, RADIUS, grid.DEFAULT_MARGIN_M)
    start = grid.nearest_in(space, here, SNAP_CELLS)
    if start is None:
        return None, None
    reach = np.isfinite(grid.distance_field(space, start))
    return start, tile_view(known, reach, start, f, range_tiles, horizon)


def assert_same_view(known: np.ndarray, here: tuple[int, int], f: int = 2, horizon: int = 12,
                     range_tiles: float = 7.0) -> bool:
    """Windowed and whole-map views agree; returns whether a view exists."""
    start, want = whole_map(known, here, f, horizon, range_tiles)
    found = local_reach(known, RADIUS, here, f, horizon)
    if start is None:
        assert found is None
        return False
    assert found is not None and found[0] == start
    got = local_tile_view(known, found[1], found[0], f, range_tiles, horizon)
    if want is None:
        assert got is None
        return False
    assert got is not None
    assert got.origin == want.origin and got.start == want.start and got.box == want.box
    assert got.shape == want.shape
    for name in ("unknown", "occupied", "blocked"):
        a, b = getattr(got.belief, name), getattr(want.belief, name)
        assert (a is None) == (b is None) and (a is None or np.array_equal(a, b)), name
    tr, tc = start[0] // f, start[1] // f
    box = (slice(max(tr - horizon, 0) * f, (tr + horizon + 1) * f), slice(max(tc - horizon, 0) * f, (tc + horizon + 1) * f))
    assert np.array_equal(got.reach[box], want.reach[box]), "reach differs inside the horizon box"
    return True


def detour_map(n: int = 200) -> np.ndarray:
    """A room beside the robot whose only door is far away: reachable, but only through a corridor that
    leaves the first window, so the window must grow to prove it."""
    k = np.full((n, n), SOLID, np.uint8)
    k[95:105, 10:190] = FREE                      # the robot's corridor, west to east
    k[60:94, 20:40] = FREE                        # the room north of the robot, wall 94 in between
    k[20:30, 20:190] = FREE                       # a corridor far north
    k[30:60, 25:35] = FREE                        # the room's only door: to the far corridor
    k[30:95, 180:190] = FREE                      # the far corridor comes back to the robot's corridor
    return k


def test_a_room_reached_only_around_a_long_detour_is_reachable_as_on_the_whole_map():
    k = detour_map()
    here = (100, 30)
    _, want = whole_map(k, here, 2, 12, 7.0)
    assert want is not None and want.reach[80, 30], "the room is reachable on the whole map"
    assert assert_same_view(k, here)
    assert 100 - 30 > REACH_MARGIN_CELLS, "the detour leaves the first window"


def test_a_closed_room_beside_the_robot_is_not_reachable():
    k = detour_map()
    k[30:60, 25:35] = SOLID                       # wall the door up
    here = (100, 30)
    _, want = whole_map(k, here, 2, 12, 7.0)
    assert not want.reach[80, 30]
    assert assert_same_view(k, here)


@pytest.mark.parametrize("shape", [(97, 131), (120, 120), (61, 203)])
@pytest.mark.parametrize("f", [1, 2, 3])
def test_random_maps_with_many_components_give_the_whole_map_inputs(shape, f):
    rng = np.random.default_rng(shape[0] * 7 + f)
    views = 0
    for trial in range(12):
        k = np.where(rng.random(shape) < 0.72, FREE, SOLID).astype(np.uint8)
        k[rng.random(shape) < 0.08] = UNSEEN
        blob = rng.integers(0, shape[0] - 30), rng.integers(0, shape[1] - 30)
        k[blob[0]:blob[0] + 30, blob[1]:blob[1] + 30] = FREE     # open space, so starts exist
        for _ in range(6):
            here = (int(rng.integers(0, shape[0])), int(rng.integers(0, shape[1])))
            views += assert_same_view(k, here, f=f, horizon=int(rng.integers(0, 20)),
                                      range_tiles=float(rng.uniform(2.0, 9.0)))
    assert views > 10, "the cases must include decisions that have a view"


def test_coarsen_window_is_the_whole_maps_coarsening_at_every_window():
    rng = np.random.default_rng(5)
    k = rng.choice(np.array([FREE, SOLID, UNSEEN], np.uint8), size=(53, 47), p=[0.5, 0.2, 0.3])
    reach = rng.random(k.shape) < 0.3
    for f in (1, 2, 3, 4):
        whole = coarsen(k, reach, f)
        Ht, Wt = whole[0].shape
        for _ in range(40):
            t0, u0 = int(rng.integers(0, Ht)), int(rng.integers(0, Wt))
            t1, u1 = int(rng.integers(t0 + 1, Ht + 1)), int(rng.integers(u0 + 1, Wt + 1))
            got = coarsen_window(k, reach, f, (t0, t1, u0, u1))
            for g, w in zip(got, whole):
                assert np.array_equal(g, w[t0:t1, u0:u1])


def test_seen_from_claims_in_a_window_is_the_whole_maps_prediction():
    rng = np.random.default_rng(9)
    k = rng.choice(np.array([FREE, SOLID, UNSEEN], np.uint8), size=(120, 140), p=[0.6, 0.08, 0.32])
    x = XBOA()
    x.reset(RobotInfo(id=0, n_robots=2, map_shape=k.shape), XBOAParams(), np.random.default_rng(0))
    f = x.params.tile_cells
    unknown, occupied, _ = coarsen(k, np.zeros(k.shape, bool), f)
    whole = Belief(unknown, occupied, x.tile_m)
    for _ in range(30):
        poses = np.stack([rng.integers(0, 120, 8), rng.integers(0, 140, 8), rng.integers(0, 8, 8)], axis=1)
        tiles = poses.copy()
        tiles[:, :2] //= f
        tiles[:, 2] = 0
        want = predicted_observed(whole, np.unique(tiles, axis=0), x.lidar)
        t0, u0 = int(rng.integers(0, 55)), int(rng.integers(0, 65))
        box = (t0, t0 + int(rng.integers(1, 12)), u0, u0 + int(rng.integers(1, 12)))
        got = x._seen_from(k, box, poses)
        assert np.array_equal(got, want[box[0]:box[1], box[2]:box[3]])
    assert math.isfinite(x.lidar.range_m)
