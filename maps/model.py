"""The ground-truth map: a solid/material raster at 0.5 m cells plus, for buildings, the true room graph.

Coordinates (see docs/design.md section 3): metres, origin at the lower-left corner, x right, y up.
``solid[row, col]`` covers ``y in [row*0.5, (row+1)*0.5)`` and ``x in [col*0.5, (col+1)*0.5)``; row 0 is
the bottom of the map. Pictures flip rows so north is up.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from typing import Any, Mapping

import networkx as nx
import numpy as np

from swarm.base.errors import InvalidInput
from swarm.base.types import CELL_M  # the edge of one raster cell (0.5 m), shared with knowledge maps

from .materials import AIR, check_table
from .rects import WallRect, merge_rectangles

CELLS_PER_TILE = 2
"""One tile (1 m, the unit of map sizes) is 2 x 2 cells."""
KINDS = ("cave", "building", "custom")


def _frozen(array: np.ndarray, dtype: Any) -> np.ndarray:
    out = np.array(array, dtype=dtype, copy=True, order="C")
    out.setflags(write=False)
    return out


@dataclass(frozen=True, eq=False)
class Map:
    """An immutable ground-truth map.

    ``material[r, c]`` is an index into ``materials``; it is 0 (``"air"``) exactly where the cell is free.
    ``rooms`` (buildings only) labels every free cell with its room id (doors get the id of the room the
    door leads out of, see :mod:`maps.building`), ``-1`` on solid cells. ``graph`` is a
    :class:`networkx.MultiGraph`: nodes are room ids with ``kind``, ``bounds`` (x0, y0, x1, y1 in metres)
    and ``cells``; edges are doors with ``x``, ``y`` (centre, m), ``width`` (m), ``axis`` and ``material``.
    """

    solid: np.ndarray
    material: np.ndarray
    materials: tuple[str, ...]
    kind: str = "custom"
    seed: int | None = None
    params: Mapping[str, Any] = field(default_factory=dict)
    rooms: np.ndarray | None = None
    graph: nx.MultiGraph | None = None

    def __post_init__(self) -> None:
        solid = np.asarray(self.solid)
        material = np.asarray(self.material)
        if solid.ndim != 2 or solid.shape[0] < 3 or solid.shape[1] < 3:
            raise InvalidInput("solid", solid.shape, "a 2-D raster of at least 3 x 3 cells")
        if material.shape != solid.shape:
            raise InvalidInput("material", material.shape, f"the same shape as solid {solid.shape}")
        if material.size and (material.min() < 0 or material.max() > 255):
            raise InvalidInput("material", (int(material.min()), int(material.max())), "ids in 0..255")
        object.__setattr__(self, "solid", _frozen(solid, np.bool_))
        object.__setattr__(self, "material", _frozen(material, np.uint8))
        object.__setattr__(self, "materials", check_table(tuple(self.materials)))
        if self.kind not in KINDS:
            raise InvalidInput("kind", self.kind, " | ".join(KINDS))
        if self.seed is not None and (not isinstance(self.seed, (int, np.integer)) or self.seed < 0):
            raise InvalidInput("seed", self.seed, "a non-negative integer or None")
        object.__setattr__(self, "params", dict(self.params))
        if self.rooms is not None:
            rooms = np.asarray(self.rooms)
            if rooms.shape != self.solid.shape:
                raise InvalidInput("rooms", rooms.shape, f"the same shape as solid {self.solid.shape}")
            object.__setattr__(self, "rooms", _frozen(rooms, np.int16))
        self._check_consistency()

    def _check_consistency(self) -> None:
        ids = self.material
        if int(ids.max()) >= len(self.materials):
            raise InvalidInput("material", int(ids.max()), f"ids below {len(self.materials)} (the material table)")
        if np.any((ids == 0) & self.solid):
            r, c = np.argwhere((ids == 0) & self.solid)[0]
            raise InvalidInput(f"material[{r},{c}]", AIR, "a wall material on every solid cell")
        if np.any((ids != 0) & ~self.solid):
            r, c = np.argwhere((ids != 0) & ~self.solid)[0]
            raise InvalidInput(f"material[{r},{c}]", self.materials[ids[r, c]], f"{AIR!r} on free cells")
        edge = np.concatenate([self.solid[0], self.solid[-1], self.solid[:, 0], self.solid[:, -1]])
        if not edge.all():
            raise InvalidInput("solid", "free cells on the outer edge", "a map whose outer edge is solid (add a border)")
        if not (~self.solid).any():
            raise InvalidInput("solid", "no free cell", "a map with free space")

    # ----------------------------------------------------------------------------------------- shape
    @property
    def shape(self) -> tuple[int, int]:
        """(rows, cols) of the cell raster."""
        return self.solid.shape  # type: ignore[return-value]

    @property
    def width_m(self) -> float:
        return self.solid.shape[1] * CELL_M

    @property
    def height_m(self) -> float:
        return self.solid.shape[0] * CELL_M

    @cached_property
    def free(self) -> np.ndarray:
        """Read-only ``~solid``."""
        return _frozen(~self.solid, np.bool_)

    @cached_property
    def free_cells(self) -> int:
        return int(self.free.sum())

    # ------------------------------------------------------------------------------------ geometry
    def cell_of(self, x: float, y: float) -> tuple[int, int]:
        """(row, col) of the cell containing the point (x, y) in metres."""
        return int(np.floor(y / CELL_M)), int(np.floor(x / CELL_M))

    @staticmethod
    def cell_centre(row: int, col: int) -> tuple[float, float]:
        """(x, y) in metres of a cell's centre."""
        return (col + 0.5) * CELL_M, (row + 0.5) * CELL_M

    def contains(self, x: float, y: float) -> bool:
        return 0.0 <= x < self.width_m and 0.0 <= y < self.height_m

    def is_free_at(self, x: float, y: float) -> bool:
        if not self.contains(x, y):
            return False
        r, c = self.cell_of(x, y)
        return bool(self.free[r, c])

    def material_id(self, name: str) -> int:
        try:
            return self.materials.index(name)
        except ValueError:
            raise InvalidInput("material", name, " | ".join(self.materials)) from None

    @cached_property
    def wall_rectangles(self) -> tuple[WallRect, ...]:
        """Solid cells merged into few disjoint axis-aligned rectangles, each of one material."""
        return merge_rectangles(self.material)

    # ---------------------------------------------------------------------------------- comparison
    def same_as(self, other: "Map") -> bool:
        """Exact equality of every array, the table, metadata and the room graph."""
        if not isinstance(other, Map):
            return False
        if (self.kind, self.seed, self.materials) != (other.kind, other.seed, other.materials):
            return False
        if dict(self.params) != dict(other.params):
            return False
        if not (np.array_equal(self.solid, other.solid) and np.array_equal(self.material, other.material)):
            return False
        if (self.rooms is None) != (other.rooms is None):
            return False
        if self.rooms is not None and not np.array_equal(self.rooms, other.rooms):
            return False
        return graph_to_json(self.graph) == graph_to_json(other.graph)

    def summary(self) -> str:
        """One line describing the map, for the CLI."""
        rows, cols = self.shape
        solid_share = 100.0 * float(self.solid.mean())
        counts = np.bincount(self.material.ravel(), minlength=len(self.materials))
        walls = ", ".join(f"{n} {100.0 * counts[i] / max(1, self.solid.sum()):.0f}%"
                          for i, n in enumerate(self.materials) if i and counts[i])
        extra = ""
        if self.graph is not None:
            extra = f", {self.graph.number_of_nodes()} rooms, {self.graph.number_of_edges()} doors"
        seed = f" seed {self.seed}" if self.seed is not None else ""
        return (f"{self.kind}{seed}: {self.width_m:g} x {self.height_m:g} m ({cols} x {rows} cells), "
                f"{solid_share:.1f}% solid [{walls}]{extra}")


def graph_to_json(graph: nx.MultiGraph | None) -> dict[str, Any] | None:
    """A canonical JSON-able form of the room graph (sorted, so equal graphs give equal dicts)."""
    if graph is None:
        return None
    rooms = [{"id": int(n), **_jsonable(graph.nodes[n])} for n in sorted(graph.nodes)]
    doors = []
    for u, v, key, data in graph.edges(keys=True, data=True):
        a, b = sorted((int(u), int(v)))
        doors.append({"rooms": [a, b], "key": int(key), **_jsonable(data)})
    doors.sort(key=lambda d: (d["rooms"], d["key"]))
    return {"rooms": rooms, "doors": doors}


def graph_from_json(data: Mapping[str, Any] | None) -> nx.MultiGraph | None:
    """Inverse of :func:`graph_to_json`."""
    if data is None:
        return None
    graph = nx.MultiGraph()
    for room in data["rooms"]:
        attrs = {k: _untuple(v) for k, v in room.items() if k != "id"}
        graph.add_node(int(room["id"]), **attrs)
    for door in data["doors"]:
        a, b = door["rooms"]
        attrs = {k: _untuple(v) for k, v in door.items() if k not in ("rooms", "key")}
        graph.add_edge(int(a), int(b), key=int(door["key"]), **attrs)
    return graph


def _jsonable(attrs: Mapping[str, Any]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for k, v in sorted(attrs.items()):
        if isinstance(v, tuple):
            v = [_scalar(x) for x in v]
        else:
            v = _scalar(v)
        out[k] = v
    return out


def _scalar(v: Any) -> Any:
    if isinstance(v, np.generic):
        return v.item()
    return v


def _untuple(v: Any) -> Any:
    return tuple(v) if isinstance(v, list) else v
