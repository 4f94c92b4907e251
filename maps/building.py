"""Building maps: halls splitting the area, rooms between halls split recursively, doors connecting all.

Follows the working 2022 MAES ``BuildingGenerator`` (docs/maes.md section 3.3), not the 2023
regression whose swapped min/max means rooms are never split. Because halls always cut a block across its
full extent and rooms are cut by guillotine walls, every region is an axis-aligned rectangle; we build the
map from those rectangles directly, which makes the true room graph exact by construction.

1. **Halls.** Starting from the area inside the ``border``, while halls cover less than
   ``max_hall_percent`` of it: take the biggest block and cut a ``hall_width`` strip across it at a random
   position leaving both sides room for a room and its walls; axes alternate, x first. Stop when no block
   can be cut.
2. **Blocks.** Each block gets a ``wall_thickness`` wall on every side that faces a hall (sides on the
   border use the exterior wall).
3. **Rooms.** The block's inside is split recursively by ``wall_thickness`` walls: each part splits with
   probability ``room_split_percent``, starting on its longer axis and alternating; if the axis has no room
   for two parts of ``min_room_side``, one forced try on the other axis (as MAES).
4. **Doors.** Breadth-first from the biggest hall: every room gets a door of
   ``door_width`` to the first already-connected neighbour (halls first), placed uniformly at least
   ``door_padding`` from the ends of the shared wall; every other adjacent pair gets a door with
   probability ``extra_door_percent`` (loops; MAES adds 1-3 doors per pair).
   Hall strips that touch form one hall node; parallel halls that do not touch are separate nodes, ids
   0.. biggest first, then rooms.
5. **Materials.** The border is ``exterior_material``; each interior wall segment (a block side, a split
   wall) draws one material from ``interior_materials`` (MAES: one material for the whole map).

``Map.rooms`` labels free cells with their room id, door openings with -2 and solid cells with -1.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field
from typing import Mapping, NamedTuple

import networkx as nx
import numpy as np
from scipy import ndimage

from swarm.base.errors import InvalidInput
from swarm.base.params import check_float, check_int, to_mapping
from .materials import DEFAULT_TABLE, DEFAULT_WALL_MATERIALS, check_known_material, check_weights
from .model import CELL_M, CELLS_PER_TILE, Map
from .raster import FOUR, tiles_to_cells

DOOR_LABEL = -2
DEFAULT_DOOR_PADDING = 2
"""MAES's door padding, used whenever the door fits with it (see :class:`BuildingParams`)."""
SOLID_LABEL = -1


@dataclass(frozen=True)
class BuildingParams:
    """MAES defaults (docs/maes.md section 3.3); lengths in tiles (1 m).

    ``door_padding`` left out (None) is chosen to fit the door: MAES's 2 where ``2 * 2 + door_width <=
    min_room_side``, else the most that fits (``(min_room_side - door_width) // 2``), so ``door_width = 3``
    works without also lowering the padding. After construction it always holds the number used."""

    hall_width: int = 4
    max_hall_percent: float = 20.0
    min_room_side: int = 6
    wall_thickness: int = 1
    door_width: int = 2
    door_padding: int | None = None
    room_split_percent: float = 85.0
    extra_door_percent: float = 0.0
    border: int = 1
    exterior_material: str = "concrete"
    interior_materials: Mapping[str, float] = field(
        default_factory=lambda: {m: 1.0 for m in DEFAULT_WALL_MATERIALS})

    def __post_init__(self) -> None:
        check_int("wall_thickness", self.wall_thickness, 1, 10)
        check_int("hall_width", self.hall_width, 2, 50)
        check_float("max_hall_percent", self.max_hall_percent, 0.0, 90.0)
        check_int("min_room_side", self.min_room_side, 2, 100)
        check_int("door_width", self.door_width, 1, 20)
        auto = self.door_padding is None
        if auto:
            object.__setattr__(self, "door_padding",
                               min(DEFAULT_DOOR_PADDING, max(0, (self.min_room_side - self.door_width) // 2)))
        check_int("door_padding", self.door_padding, 0, 20)
        check_float("room_split_percent", self.room_split_percent, 0.0, 100.0)
        check_float("extra_door_percent", self.extra_door_percent, 0.0, 100.0)
        check_int("border", self.border, 1, 10)
        check_known_material(self.exterior_material, "exterior_material")
        object.__setattr__(self, "interior_materials",
                           dict(check_weights("interior_materials", self.interior_materials)))
        if 2 * self.door_padding + self.door_width > self.min_room_side:
            raise InvalidInput("door_width", self.door_width,
                               f"door_width <= min_room_side ({self.min_room_side})" if auto else
                               f"2*door_padding + door_width <= min_room_side ({self.min_room_side}) with "
                               f"door_padding {self.door_padding}")


class _RoomsWithoutDoor(Exception):
    """Door placement could not connect every room (see :func:`generate_building` for what that means)."""


class Rect(NamedTuple):
    """Half-open tile rectangle ``[x0, x1) x [y0, y1)``."""

    x0: int
    y0: int
    x1: int
    y1: int

    @property
    def area(self) -> int:
        return (self.x1 - self.x0) * (self.y1 - self.y0)

    def paint(self, grid: np.ndarray, value: int) -> None:
        grid[self.y0:self.y1, self.x0:self.x1] = value


class _Adjacency(NamedTuple):
    a: int            # room id on the low side
    b: int            # room id on the high side
    axis: str         # "x": the door opening runs along x (wall is horizontal), "y": along y
    lo: int           # shared extent along the wall, [lo, hi)
    hi: int
    wall0: int        # wall position across, [wall0, wall1)
    wall1: int


def generate_building(width: int, height: int, seed: int, params: BuildingParams) -> Map:
    """A building of ``width`` x ``height`` tiles; a pure function of its arguments."""
    layout_rng, material_rng = (np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(2))
    table = _table(params)
    interior = Rect(params.border, params.border, width - params.border, height - params.border)
    if interior.x1 <= interior.x0 or interior.y1 <= interior.y0:
        raise InvalidInput("border", params.border, f"at most {max((min(width, height) - 1) // 2, 0)} for a "
                           f"{width} x {height} map (the border leaves no inside)")
    halls, blocks = _cut_halls(interior, params, layout_rng)

    material = np.full((height, width), table.index(params.exterior_material), dtype=np.uint8)
    labels = np.full((height, width), SOLID_LABEL, dtype=np.int16)
    free_rects = _label_halls(halls, labels)
    for hall in halls:
        hall.paint(material, 0)

    interior_ids = np.array([table.index(n) for n in params.interior_materials])
    interior_w = np.array(list(params.interior_materials.values()))

    def draw_material() -> int:
        return int(material_rng.choice(interior_ids, p=interior_w / interior_w.sum()))

    n_halls = 1 + max((rid for rid, _ in free_rects), default=-1)
    next_id = n_halls
    t = params.wall_thickness
    for block in blocks:
        inside = _block_inside(block, interior, t)
        for side in _hall_sides(block, inside):
            side.paint(material, draw_material())
        rooms, walls = _split_rooms(inside, params, layout_rng)
        for wall in walls:
            wall.paint(material, draw_material())
        for room in rooms:
            room.paint(material, 0)
            room.paint(labels, next_id)
            free_rects.append((next_id, room))
            next_id += 1

    graph = nx.MultiGraph()
    for rid, rect in free_rects:
        if rid not in graph:
            graph.add_node(rid, kind="hall" if rid < n_halls else "room")
    adjacencies = _adjacencies(free_rects, material, params)
    try:
        _place_doors(graph, adjacencies, material, labels, table, params, layout_rng)
    except _RoomsWithoutDoor:
        side = 2 * params.border + params.min_room_side
        if min(interior.x1 - interior.x0, interior.y1 - interior.y0) >= params.min_room_side:
            raise RuntimeError(f"building generator left rooms without a door (seed {seed}, {width} x {height}); "
                               "please report the seed") from None
        # Inside the border there is less than a room side: rooms that thin can share walls too short for a door.
        raise InvalidInput("size", f"{width}x{height}",
                           f"at least {side} tiles per side with border {params.border} and min_room_side "
                           f"{params.min_room_side} (this one leaves rooms without a door)") from None

    solid = tiles_to_cells(material != 0)
    cell_material = tiles_to_cells(material)
    cell_labels = tiles_to_cells(labels)
    _annotate_rooms(graph, cell_labels)
    return Map(solid=solid, material=cell_material, materials=table, kind="building", seed=seed,
               params={"width": width, "height": height, **to_mapping(params)},
               rooms=cell_labels, graph=graph)


def _table(params: BuildingParams) -> tuple[str, ...]:
    names = {params.exterior_material, *params.interior_materials}
    return (*DEFAULT_TABLE, *sorted(names - set(DEFAULT_TABLE)))


# --------------------------------------------------------------------------------------- halls ----
def _cut_halls(interior: Rect, p: BuildingParams, rng: np.random.Generator) -> tuple[list[Rect], list[Rect]]:
    blocks = [interior]
    halls: list[Rect] = []
    hall_area = 0
    axis = "x"
    t = p.wall_thickness
    while 100.0 * hall_area / interior.area < p.max_hall_percent:
        block = max(blocks, key=lambda r: (r.area, -r.y0, -r.x0))
        cut = None
        for ax in (axis, "y" if axis == "x" else "x"):
            lo_edge = (block.x0 if ax == "x" else block.y0) > (interior.x0 if ax == "x" else interior.y0)
            hi_edge = (block.x1 if ax == "x" else block.y1) < (interior.x1 if ax == "x" else interior.y1)
            start, end = (block.x0, block.x1) if ax == "x" else (block.y0, block.y1)
            lo = start + p.min_room_side + t + (t if lo_edge else 0)
            hi = end - p.min_room_side - t - (t if hi_edge else 0) - p.hall_width
            if lo <= hi:
                c = int(rng.integers(lo, hi + 1))
                cut = (ax, c)
                break
        if cut is None:
            break
        ax, c = cut
        blocks.remove(block)
        if ax == "x":
            hall = Rect(c, block.y0, c + p.hall_width, block.y1)
            blocks += [Rect(block.x0, block.y0, c, block.y1), Rect(c + p.hall_width, block.y0, block.x1, block.y1)]
        else:
            hall = Rect(block.x0, c, block.x1, c + p.hall_width)
            blocks += [Rect(block.x0, block.y0, block.x1, c), Rect(block.x0, c + p.hall_width, block.x1, block.y1)]
        halls.append(hall)
        hall_area += hall.area
        axis = "y" if ax == "x" else "x"
    blocks.sort(key=lambda r: (r.y0, r.x0))
    return halls, blocks


def _label_halls(halls: list[Rect], labels: np.ndarray) -> list[tuple[int, Rect]]:
    """Hall strips that touch form one hall; halls get ids 0, 1, ... biggest first, painted into ``labels``."""
    mask = np.zeros(labels.shape, dtype=bool)
    for hall in halls:
        hall.paint(mask, True)
    comp, n = ndimage.label(mask, structure=FOUR)
    sizes = np.bincount(comp.ravel())[1:]
    order = sorted(range(1, n + 1), key=lambda c: (-sizes[c - 1], c))
    hall_id = {c: i for i, c in enumerate(order)}
    if n:
        ids = np.zeros(n + 1, dtype=labels.dtype)
        for c, i in hall_id.items():
            ids[c] = i
        labels[mask] = ids[comp[mask]]  # every hall cell at once (a pass per hall grew with halls x area)
    return [(hall_id[int(comp[h.y0, h.x0])], h) for h in halls]


def _block_inside(block: Rect, interior: Rect, t: int) -> Rect:
    """The block minus a wall on every side that faces a hall (every side not on the border)."""
    return Rect(block.x0 + (t if block.x0 > interior.x0 else 0), block.y0 + (t if block.y0 > interior.y0 else 0),
                block.x1 - (t if block.x1 < interior.x1 else 0), block.y1 - (t if block.y1 < interior.y1 else 0))


def _hall_sides(block: Rect, inside: Rect) -> list[Rect]:
    sides = []
    if inside.x0 > block.x0:
        sides.append(Rect(block.x0, block.y0, inside.x0, block.y1))
    if inside.x1 < block.x1:
        sides.append(Rect(inside.x1, block.y0, block.x1, block.y1))
    if inside.y0 > block.y0:
        sides.append(Rect(block.x0, block.y0, block.x1, inside.y0))
    if inside.y1 < block.y1:
        sides.append(Rect(block.x0, inside.y1, block.x1, block.y1))
    return sides


# --------------------------------------------------------------------------------------- rooms ----
def _split_rooms(inside: Rect, p: BuildingParams, rng: np.random.Generator) -> tuple[list[Rect], list[Rect]]:
    rooms: list[Rect] = []
    walls: list[Rect] = []
    t, m = p.wall_thickness, p.min_room_side

    def split(rect: Rect, axis: str) -> None:
        if rng.random() * 100.0 >= p.room_split_percent:
            rooms.append(rect)
            return
        for ax in (axis, "y" if axis == "x" else "x"):
            start, end = (rect.x0, rect.x1) if ax == "x" else (rect.y0, rect.y1)
            lo, hi = start + m, end - m - t
            if lo > hi:
                continue
            c = int(rng.integers(lo, hi + 1))
            nxt = "y" if ax == "x" else "x"
            if ax == "x":
                walls.append(Rect(c, rect.y0, c + t, rect.y1))
                split(Rect(rect.x0, rect.y0, c, rect.y1), nxt)
                split(Rect(c + t, rect.y0, rect.x1, rect.y1), nxt)
            else:
                walls.append(Rect(rect.x0, c, rect.x1, c + t))
                split(Rect(rect.x0, rect.y0, rect.x1, c), nxt)
                split(Rect(rect.x0, c + t, rect.x1, rect.y1), nxt)
            return
        rooms.append(rect)

    longer = "x" if inside.x1 - inside.x0 >= inside.y1 - inside.y0 else "y"
    split(inside, longer)
    return rooms, walls


# --------------------------------------------------------------------------------------- doors ----
def _adjacencies(free_rects: list[tuple[int, Rect]], material: np.ndarray, p: BuildingParams) -> list[_Adjacency]:
    """Pairs of free rectangles separated by exactly one wall thickness of solid tiles, sorted.

    Rectangles are indexed by their left and bottom edges, so each one meets only the rectangles a wall
    thickness to its right or above (a test of every pair grew with the square of the rooms: 22 s on a
    1,200-tile building). Candidates are taken in the order the pairwise test took them, so equal sort
    keys keep their order and the doors are the same."""
    t = p.wall_thickness
    by_x0: dict[int, list[int]] = {}
    by_y0: dict[int, list[int]] = {}
    for k, (_, r) in enumerate(free_rects):
        by_x0.setdefault(r.x0, []).append(k)
        by_y0.setdefault(r.y0, []).append(k)
    candidates = []  # (first, second, which of them is lower, axis test order, lower, higher)
    for k, (_, low) in enumerate(free_rects):
        for j in by_x0.get(low.x1 + t, ()):  # low left of free_rects[j]: door opening runs along y
            candidates.append((min(k, j), max(k, j), 0 if k < j else 1, 0, k, j))
        for j in by_y0.get(low.y1 + t, ()):  # low below free_rects[j]: door opening runs along x
            candidates.append((min(k, j), max(k, j), 0 if k < j else 1, 1, k, j))
    candidates.sort()
    found = []
    for _, _, _, test, k, j in candidates:
        (idl, lowr), (idh, highr) = free_rects[k], free_rects[j]
        if idl == idh:
            continue
        if test == 0:
            lo, hi = max(lowr.y0, highr.y0), min(lowr.y1, highr.y1)
            if hi > lo and (material[lo:hi, lowr.x1:highr.x0] != 0).all():
                found.append(_Adjacency(idl, idh, "y", lo, hi, lowr.x1, highr.x0))
        else:
            lo, hi = max(lowr.x0, highr.x0), min(lowr.x1, highr.x1)
            if hi > lo and (material[lowr.y1:highr.y0, lo:hi] != 0).all():
                found.append(_Adjacency(idl, idh, "x", lo, hi, lowr.y1, highr.y0))
    found.sort(key=lambda e: (min(e.a, e.b), max(e.a, e.b), e.axis, e.lo, e.wall0))
    return found


def _place_doors(graph: nx.MultiGraph, adjacencies: list[_Adjacency], material: np.ndarray, labels: np.ndarray,
                 table: tuple[str, ...], p: BuildingParams, rng: np.random.Generator) -> None:
    usable = [e for e in adjacencies if e.hi - e.lo >= p.door_width + 2 * p.door_padding]
    if not graph.number_of_nodes():
        return
    root = min(graph.nodes)  # the biggest hall, or the first room when there is no hall
    incident: dict[int, list[int]] = {}  # each room's usable adjacencies, in list order
    for k, e in enumerate(usable):
        incident.setdefault(e.a, []).append(k)
        if e.b != e.a:
            incident.setdefault(e.b, []).append(k)
    connected = {root}
    queue = deque([root])
    used: set[int] = set()
    while queue:
        u = queue.popleft()
        for k in incident.get(u, ()):
            e = usable[k]
            v = e.b if e.a == u else e.a
            if v in connected:
                continue
            _carve(graph, e, material, labels, table, p, rng)
            used.add(k)
            connected.add(v)
            queue.append(v)
    missing = set(graph.nodes) - connected
    if missing:
        raise _RoomsWithoutDoor(sorted(missing))
    if p.extra_door_percent > 0:
        for k, e in enumerate(usable):
            if k not in used and rng.random() * 100.0 < p.extra_door_percent:
                _carve(graph, e, material, labels, table, p, rng)


def _carve(graph: nx.MultiGraph, e: _Adjacency, material: np.ndarray, labels: np.ndarray,
           table: tuple[str, ...], p: BuildingParams, rng: np.random.Generator) -> None:
    start = int(rng.integers(e.lo + p.door_padding, e.hi - p.door_padding - p.door_width + 1))
    end = start + p.door_width
    if e.axis == "x":
        ys, xs = slice(e.wall0, e.wall1), slice(start, end)
        cx, cy = (start + end) / 2, (e.wall0 + e.wall1) / 2
    else:
        ys, xs = slice(start, end), slice(e.wall0, e.wall1)
        cx, cy = (e.wall0 + e.wall1) / 2, (start + end) / 2
    wall_ids = material[ys, xs]
    wall_material = table[int(np.bincount(wall_ids.ravel()).argmax())]
    material[ys, xs] = 0
    labels[ys, xs] = DOOR_LABEL
    k = CELLS_PER_TILE
    graph.add_edge(e.a, e.b, x=cx * k * CELL_M, y=cy * k * CELL_M, width=float(p.door_width), axis=e.axis,
                   thickness=float(p.wall_thickness), material=wall_material,
                   cells=(ys.start * k, xs.start * k, ys.stop * k, xs.stop * k))


def _annotate_rooms(graph: nx.MultiGraph, labels: np.ndarray) -> None:
    """Each room's cell count and bounding box (metres), in one pass over the raster for all rooms."""
    shifted = np.where(labels >= 0, labels.astype(np.int64) + 1, 0)  # room r -> r + 1; walls and doors -> 0
    counts = np.bincount(shifted.ravel())
    boxes = ndimage.find_objects(shifted)
    for rid in graph.nodes:
        rows, cols = boxes[rid]
        graph.nodes[rid]["cells"] = int(counts[rid + 1])
        graph.nodes[rid]["bounds"] = (float(cols.start * CELL_M), float(rows.start * CELL_M),
                                      float(cols.stop * CELL_M), float(rows.stop * CELL_M))
