"""Shared fixtures: small hand-made maps and helpers used across the test packages."""

from __future__ import annotations

import numpy as np
import pytest

from maps import Map


def box_map(width_cells: int = 20, height_cells: int = 20, material: str = "concrete") -> Map:
    """An empty room: a one-cell wall ring around free space."""
    solid = np.ones((height_cells, width_cells), dtype=bool)
    solid[1:-1, 1:-1] = False
    return Map(solid=solid, material=solid.astype(np.uint8), materials=("air", material))


@pytest.fixture(autouse=True, scope="session")
def _warmup_stamps_stay_in_the_test_session(tmp_path_factory):
    """Campaigns record their numba warm-up (swarm.campaign.warmup) in a folder of this session, not in the
    user's cache folder."""
    mp = pytest.MonkeyPatch()
    mp.setenv("SWARM_CACHE_DIR", str(tmp_path_factory.mktemp("swarm-cache")))
    yield
    mp.undo()


@pytest.fixture
def empty_room() -> Map:
    return box_map()
