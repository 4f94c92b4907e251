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


@pytest.fixture
def empty_room() -> Map:
    return box_map()
