"""Spawning: reproducible, spaced, inside drivable space; together is packed, random is spread."""

from __future__ import annotations

import numpy as np
import pytest

from maps import InvalidInput, generate
from swarm.world.spawn import SPACING_M, drivable_region, spawn


@pytest.mark.parametrize("mode", ["together", "random"])
def test_spawn_is_reproducible_spaced_and_drivable(mode):
    truth = generate("building", 60, 4)
    a = spawn(truth, mode, 12, np.random.default_rng(7))
    b = spawn(truth, mode, 12, np.random.default_rng(7))
    assert np.array_equal(a, b)
    region = drivable_region(truth)
    rows, cols = np.floor(a[:, 1] / 0.5).astype(int), np.floor(a[:, 0] / 0.5).astype(int)
    assert region[rows, cols].all()
    d = np.hypot(*(a[:, None, :2] - a[None, :, :2]).transpose(2, 0, 1))
    assert d[~np.eye(12, dtype=bool)].min() >= SPACING_M - 1e-9


def test_together_is_packed_and_random_is_spread():
    truth = generate("building", 100, 1)
    together = spawn(truth, "together", 8, np.random.default_rng(3))
    spread = spawn(truth, "random", 8, np.random.default_rng(3))
    radius = lambda p: np.hypot(*(p[:, :2] - p[:, :2].mean(0)).T).max()  # noqa: E731
    assert radius(together) < 3.0
    assert radius(spread) > 15.0


def test_too_many_robots_is_a_clear_error():
    with pytest.raises(InvalidInput, match="robots.count"):
        spawn(generate("building", 20, 0), "random", 5000, np.random.default_rng(0))


def _spaced_all_pairs(order, count):
    """The greedy spacing rule as first written: each candidate against every cell taken so far."""
    taken = []
    for r, c in order:
        if taken and min((r - a) ** 2 + (c - b) ** 2 for a, b in taken) < (SPACING_M / 0.5) ** 2:
            continue
        taken.append((int(r), int(c)))
        if len(taken) == count:
            break
    return taken


@pytest.mark.parametrize("seed", range(4))
def test_spacing_by_neighbour_lookup_takes_the_cells_the_all_pairs_rule_takes(seed):
    from swarm.world.spawn import _spaced

    rng = np.random.default_rng(seed)
    order = rng.integers(0, 25, size=(600, 2))  # repeats and clusters, as a together spawn's BFS gives
    assert _spaced(order, 80) == _spaced_all_pairs(order, 80)
    assert _spaced(order, 10_000) == _spaced_all_pairs(order, 10_000)  # fewer fit: both stop at the same place
