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
