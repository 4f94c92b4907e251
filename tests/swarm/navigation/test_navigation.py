"""The navigator's path corridor: the cells whose turning SOLID forces a replan."""

from __future__ import annotations

import math

import numpy as np
import pytest

from swarm.api import FREE, SOLID, UNSEEN, Pose
from swarm.navigation.navigator import _corridor

CELL = 0.5


def corridor_reference(polyline: np.ndarray, known: np.ndarray) -> np.ndarray:
    """The rule in plain numpy: sample the polyline's first point, then ceil(length / 0.2) (at least 1)
    points per segment at fractions k / steps; take each sample's cell and its 4 neighbours, clipped to
    the map; keep the non-SOLID ones, distinct and ascending."""
    h, w = known.shape
    points = [polyline[0]]
    for a, b in zip(polyline[:-1], polyline[1:]):
        steps = max(1, int(np.ceil(np.hypot(*(b - a)) / 0.2)))
        points += [a + (b - a) * (k / steps) for k in range(1, steps + 1)]
    cells = set()
    for x, y in points:
        r0, c0 = int(math.floor(y / CELL)), int(math.floor(x / CELL))
        for dr, dc in ((0, 0), (-1, 0), (1, 0), (0, -1), (0, 1)):
            r, c = min(max(r0 + dr, 0), h - 1), min(max(c0 + dc, 0), w - 1)
            if known[r, c] < SOLID:
                cells.add(r * w + c)
    return np.array(sorted(cells), dtype=np.int64)


@pytest.mark.parametrize("seed", range(6))
def test_corridor_is_the_distinct_non_solid_footprint_cells_in_ascending_order(seed: int) -> None:
    rng = np.random.default_rng(seed)
    known = rng.choice(np.array([UNSEEN, FREE, SOLID], dtype=np.uint8), size=(30, 40), p=[0.2, 0.6, 0.2])
    polyline = np.column_stack([rng.uniform(-0.3, 20.3, 6), rng.uniform(-0.3, 15.3, 6)])  # some off the map
    polyline[3] = polyline[2]                                                             # a zero-length segment
    got = _corridor(polyline, known)
    assert got.dtype == np.int64
    assert np.array_equal(got, corridor_reference(polyline, known))
    assert np.all(np.diff(got) > 0)


# ------------------------------------------------ the fleet's one call against the navigators one by one ----
def _room_map(rng: np.random.Generator, h: int = 24, w: int = 32) -> np.ndarray:
    """A known map: free inside a solid border, a few solid blocks, a little unseen."""
    known = np.full((h, w), FREE, dtype=np.uint8)
    known[0, :] = known[-1, :] = known[:, 0] = known[:, -1] = SOLID
    for _ in range(5):
        r, c = int(rng.integers(3, h - 6)), int(rng.integers(3, w - 6))
        known[r:r + int(rng.integers(1, 4)), c:c + int(rng.integers(1, 4))] = SOLID
    known[rng.random((h, w)) < 0.02] = UNSEEN
    return known


@pytest.mark.parametrize("seed", range(4))
def test_the_fleet_commands_as_each_navigator_would_alone(seed: int) -> None:
    """NavigationFleet steps the moving navigators in one compiled call and hands plans, arrivals and
    stuck robots to Python. Against the same navigators driven one by one (Navigator.command): the same
    commands, bit for bit, and the same states, over goals set and cleared, corridors cut by new SOLID
    cells, robots that make no progress (replans, then ``blocked``) and robots that arrive."""
    from swarm.navigation.navigator import _ARRIVED, _BLOCKED, _STEPPED, _STUCK, NavigationFleet, Navigator
    from swarm.sim.spec import NavigationSpec
    from swarm.world.motion import MotionParams

    rng = np.random.default_rng(seed)
    n = 6
    spec = NavigationSpec(stuck_ticks=4, max_replans=2)
    motion = MotionParams()
    fleet = NavigationFleet(spec, motion, [np.random.default_rng([seed, i]) for i in range(n)])
    alone = [Navigator(spec, motion, np.random.default_rng([seed, i])) for i in range(n)]
    known = np.stack([_room_map(rng) for _ in range(n)])
    known_alone = known.copy()
    h, w = known.shape[1:]
    poses = np.column_stack([rng.uniform(2.0, 4.0, n), rng.uniform(2.0, 4.0, n), rng.uniform(-3.0, 3.0, n)])
    flags = {}  # what the compiled step left to Python: each case must occur
    for tick in range(400):
        rows = []
        for i in range(n):
            if rng.random() < 0.03 or fleet.navigators[i].state in ("idle", "reached", "blocked", "unreachable"):
                near = poses[i, :2] + rng.uniform(-3.0, 3.0, 2)  # near goals: many are reached
                goal = None if rng.random() < 0.1 else (float(np.clip(near[0], 0.0, w * CELL - 0.01)),
                                                        float(np.clip(near[1], 0.0, h * CELL - 0.01)))
                fleet.navigators[i].set_goal(goal)
                alone[i].set_goal(goal)
            if rng.random() < 0.9:
                rows.append(i)
        corridor = fleet.navigators[rows[0]].corridor if rows else None
        if corridor is not None and len(corridor) and rng.random() < 0.05:  # cut a path
            cell = int(rng.choice(corridor))
            known[rows[0]].reshape(-1)[cell] = known_alone[rows[0]].reshape(-1)[cell] = SOLID
        out = np.zeros((n, 2))
        tuples = [Pose(*row) for row in poses.tolist()]
        was_moving = [i for i in rows if fleet.navigators[i].state == "moving"]
        fleet.command(rows, poses, tuples, known, out)
        for i in was_moving:
            flags[int(fleet._flags[i])] = flags.get(int(fleet._flags[i]), 0) + 1
        want = np.zeros((n, 2))
        for i in rows:
            want[i] = alone[i].command(tuples[i], known_alone[i])
        assert np.array_equal(out, want), tick
        for mine, theirs in zip(fleet.navigators, alone):
            assert mine.status() == theirs.status() and mine.replans == theirs.replans
            assert mine.follower.index == theirs.follower.index
            assert mine.follower.remaining_m == theirs.follower.remaining_m
        stuck = rng.random(n) < 0.3  # these do not move this tick: progress stalls
        v, om = out[:, 0] * ~stuck, out[:, 1] * ~stuck
        poses[:, 2] += 0.1 * om
        poses[:, 0] = np.clip(poses[:, 0] + 0.1 * v * np.cos(poses[:, 2]), 0.0, w * CELL - 1e-6)
        poses[:, 1] = np.clip(poses[:, 1] + 0.1 * v * np.sin(poses[:, 2]), 0.0, h * CELL - 1e-6)
    assert sorted(flags) == [_STEPPED, _BLOCKED, _ARRIVED, _STUCK]
