"""Hand-made maps for the radio tests: an open floor with a concrete border and walls placed in metres."""

from __future__ import annotations

import numpy as np

from maps import Map
from maps.model import CELL_M

MATERIALS = ("air", "concrete", "wood", "brick")


class Plan:
    """An open floor ``width_m`` x ``height_m`` with a one-cell concrete border; add walls, then build."""

    def __init__(self, width_m: float, height_m: float, materials: tuple[str, ...] = MATERIALS) -> None:
        self.materials = materials
        self.material = np.zeros((int(round(height_m / CELL_M)), int(round(width_m / CELL_M))), dtype=np.uint8)
        border = materials.index("concrete") if "concrete" in materials else 1
        self.material[[0, -1], :] = border
        self.material[:, [0, -1]] = border

    def wall(self, x0: float, y0: float, x1: float, y1: float, material: str) -> "Plan":
        """Fill the rectangle [x0, x1) x [y0, y1) (metres, multiples of 0.5) with ``material``."""
        c0, c1 = int(round(x0 / CELL_M)), int(round(x1 / CELL_M))
        r0, r1 = int(round(y0 / CELL_M)), int(round(y1 / CELL_M))
        self.material[r0:r1, c0:c1] = self.materials.index(material)
        return self

    def build(self) -> Map:
        return Map(solid=self.material != 0, material=self.material, materials=self.materials)


def open_floor(width_m: float = 120.0, height_m: float = 20.0) -> Map:
    return Plan(width_m, height_m).build()


def vertical_wall(material: str = "concrete", thickness_m: float = 1.0, x0: float = 20.0, size_m: float = 40.0) -> Map:
    """A wall across the whole floor: x in [x0, x0 + thickness), every y."""
    return Plan(size_m, size_m).wall(x0, 0.5, x0 + thickness_m, size_m - 0.5, material).build()
