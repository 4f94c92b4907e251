"""swarm.base.types.Neighbours.within: the close neighbours, the same tuples as filtering them all."""

from __future__ import annotations

import numpy as np
import pytest

from swarm.base.types import Neighbours


def _neighbours(row: int, seed: int = 0) -> Neighbours:
    rng = np.random.default_rng(seed)
    n = 40
    xy = rng.uniform(0, 20, (n, 2))
    distance = np.hypot(*(xy[:, None, :] - xy[None, :, :]).transpose(2, 0, 1))
    bearing = rng.uniform(-np.pi, np.pi, (n, n))
    near = (distance < 8.0) & ~np.eye(n, dtype=bool)
    return Neighbours(row, near, distance, bearing, xy)


@pytest.mark.parametrize("row", [0, 7, 39])
@pytest.mark.parametrize("range_m", [0.0, 1.5, 4.0, 100.0])
def test_within_is_the_sensed_neighbours_closer_than_the_range(row: int, range_m: float) -> None:
    lazy, built = _neighbours(row), _neighbours(row)
    expected = tuple(n for n in built if n.distance < range_m)  # built: every neighbour, then filtered
    assert lazy.within(range_m) == expected
    assert built.within(range_m) == expected
    assert len(built) > 3 and (range_m < 100.0 or expected == tuple(built))


@pytest.mark.parametrize("row", [0, 7, 39])
def test_within_asks_the_runtimes_spatial_index_when_it_has_one(row: int) -> None:
    """The runtime's near mask can answer "who is within r of robot i" itself (a spatial index); within()
    then builds the same tuples from its answer and never reads the (R, R) matrices."""
    reference = _neighbours(row)
    source = reference._source
    assert source is not None
    _, near, distance, bearing, xy = source

    class IndexedNear:
        def __init__(self) -> None:
            self.asked: list[tuple[int, float]] = []

        def near(self, r: int, range_m: float) -> tuple[np.ndarray, np.ndarray]:
            self.asked.append((r, range_m))
            cols = np.flatnonzero(near[r])
            cols = cols[distance[r, cols] < range_m]
            return cols, distance[r, cols]

        def __getitem__(self, key):  # pragma: no cover - must not be read
            raise AssertionError("within() read the matrix")

    indexed = IndexedNear()
    lazy = Neighbours(row, indexed, None, bearing, xy)
    for range_m in (0.0, 1.5, 4.0):
        assert lazy.within(range_m) == reference.within(range_m)
    assert indexed.asked == [(row, 0.0), (row, 1.5), (row, 4.0)]


def test_a_ticks_near_robots_from_the_index_are_the_sight_matrices_rows() -> None:
    """In a run (a packed spawn, walls around), TickBatch.sight_near answers from the spatial index before
    the matrices exist and from the matrices after: the same robots and distances bit for bit."""
    from swarm.sim.loop import Simulation

    sim = Simulation({"seed": 3, "map": {"kind": "building", "size": 40}, "robots": {"count": 40, "spawn": "together"},
                      "algorithm": {"name": "greed"}, "stop": {"max_ticks": 5}})
    state = sim.start_state()
    sim.sense(state)
    batch = sim.observe(state)
    ranges = (0.8, 1.2, 3.0, 50.0)
    from_index = {(r, m): batch.sight_near(r, m) for r in range(40) for m in ranges}
    assert batch._near_value is not None and batch._sight_value is None, "answered by the index"
    distance, near = batch.sight()
    assert near.any()
    for (r, m), (cols, dist) in from_index.items():
        want = np.flatnonzero(near[r])
        want = want[distance[r, want] < m]
        assert cols.tolist() == want.tolist() and dist.tolist() == distance[r, want].tolist()
        got = batch.sight_near(r, m)  # now from the matrices
        assert got[0].tolist() == want.tolist()
