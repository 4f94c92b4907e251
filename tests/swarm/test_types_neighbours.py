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
