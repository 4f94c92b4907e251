"""The navigator's path corridor: the cells whose turning SOLID forces a replan."""

from __future__ import annotations

import math

import numpy as np
import pytest

from swarm.api import FREE, SOLID, UNSEEN
from swarm.navigation import _corridor

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
