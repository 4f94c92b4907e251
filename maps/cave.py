"""Cave maps: the MAES cave pipeline (``CaveGenerator.cs`` at commit 1bb0312, docs/maes.md section 3.2).

Pipeline, on a 1 m tile grid, then upscaled to 0.5 m cells:

1. random fill (``fill_percent``), bitmap edge always wall;
2. ``smoothing_runs`` synchronous passes of the MAES-2023 rule: count walls among the 4 *diagonal*
   neighbours (outside counts as wall); wall iff the count >= ``smoothing_threshold``;
3. wall off corridors narrower than a robot (a free tile needs 2 free tiles of clearance on each axis and
   a free tile on each diagonal), iterated to a fixpoint (MAES uses a work queue; the fixpoint is the same
   because walling a tile only makes the test harder for its neighbours);
4. wall regions smaller than ``wall_threshold`` become free, free regions smaller than ``room_threshold``
   become wall;
5. connect every region to the main one: repeatedly carve a disc-brushed straight passage of radius
   ``passage_radius`` between the globally closest pair of edge tiles of an unconnected and the connected
   region;
6. a ``border`` of wall tiles around everything.

Departures from MAES, on purpose: materials are drawn per wall tile from ``materials`` (weights) and
majority-smoothed ``material_smoothing`` times so they come in patches (MAES: per cell, then a majority of
neighbours, border one material); after upscaling, free cells a 0.6 m robot cannot reach (pockets left by
step 5's discs meeting walls) are filled with the nearest wall's material, so every free cell can be seen
from where a robot can stand.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Mapping

import numpy as np
from scipy import ndimage

from swarm.base.errors import InvalidInput
from swarm.base.params import check_float, check_int
from .materials import DEFAULT_TABLE, DEFAULT_WALL_MATERIALS, check_weights
from .model import Map
from .raster import FOUR, nearest_wall_material, reachable_free, smooth_patches, tiles_to_cells


@dataclass(frozen=True)
class CaveParams:
    """MAES HEAD defaults (docs/maes.md section 3.2); lengths in tiles (1 m)."""

    fill_percent: float = 50.0
    smoothing_runs: int = 3
    smoothing_threshold: int = 3
    passage_radius: int = 4
    wall_threshold: int = 1
    room_threshold: int = 20
    border: int = 2
    materials: Mapping[str, float] = field(default_factory=lambda: {m: 1.0 for m in DEFAULT_WALL_MATERIALS})
    material_smoothing: int = 3

    def __post_init__(self) -> None:
        check_float("fill_percent", self.fill_percent, 0.0, 100.0, hi_open=True)
        check_int("smoothing_runs", self.smoothing_runs, 0, 50)
        check_int("smoothing_threshold", self.smoothing_threshold, 0, 4)
        check_int("passage_radius", self.passage_radius, 1, 20)
        check_int("wall_threshold", self.wall_threshold, 0)
        check_int("room_threshold", self.room_threshold, 0)
        check_int("border", self.border, 1, 10)
        object.__setattr__(self, "materials", dict(check_weights("materials", self.materials)))
        check_int("material_smoothing", self.material_smoothing, 0, 50)


def generate_cave(width: int, height: int, seed: int, params: CaveParams) -> Map:
    """A cave of ``width`` x ``height`` tiles; a pure function of its arguments."""
    layout_ss, material_ss = np.random.SeedSequence(seed).spawn(2)
    rng = np.random.default_rng(layout_ss)
    b = params.border
    inner_w, inner_h = width - 2 * b, height - 2 * b

    wall = rng.integers(0, 100, size=(inner_h, inner_w)) < params.fill_percent
    wall[0, :] = wall[-1, :] = wall[:, 0] = wall[:, -1] = True
    for _ in range(params.smoothing_runs):
        wall = _diagonal_count(wall) >= params.smoothing_threshold
    wall = _wall_off_narrow(wall)
    wall = _remove_small_regions(wall, params.wall_threshold, params.room_threshold)
    for _ in range(20):  # passages can leave slivers beside walls; walling them off may cut a link
        wall = _connect_regions(wall, params.passage_radius)
        wall = _remove_small_regions(_wall_off_narrow(wall), 0, params.room_threshold)
        if ndimage.label(~wall, structure=FOUR)[1] <= 1:
            break
    wall = np.pad(wall, b, constant_values=True)

    table = _table(params)
    tile_material = _materials(wall, params, table, np.random.default_rng(material_ss))
    solid = tiles_to_cells(wall)
    material = tiles_to_cells(tile_material)

    free = ~solid
    keep = reachable_free(free)
    if not keep.any():
        raise InvalidInput("seed", seed, f"a seed whose {width} x {height} cave leaves room for a robot (this one "
                                         "leaves none: try another seed, a bigger size or a lower fill_percent)")
    pockets = free & ~keep
    if pockets.any():
        fill = nearest_wall_material(material, solid)
        material = np.where(pockets, fill, material)
        solid = solid | pockets
    return Map(solid=solid, material=material, materials=table, kind="cave", seed=seed,
               params={"width": width, "height": height, **_params_dict(params)})


def _params_dict(params: CaveParams) -> dict[str, Any]:
    from swarm.base.params import to_mapping

    return to_mapping(params)


def _table(params: CaveParams) -> tuple[str, ...]:
    extra = sorted(set(params.materials) - set(DEFAULT_TABLE))
    return (*DEFAULT_TABLE, *extra)


def _materials(wall: np.ndarray, params: CaveParams, table: tuple[str, ...], rng: np.random.Generator) -> np.ndarray:
    names = [n for n, w in params.materials.items() if w > 0]
    ids = np.array([table.index(n) for n in names], dtype=np.uint8)
    weights = np.array([params.materials[n] for n in names])
    material = np.zeros(wall.shape, dtype=np.uint8)
    material[wall] = rng.choice(ids, size=int(wall.sum()), p=weights / weights.sum())
    return smooth_patches(material, wall, params.material_smoothing, len(table))


def _shift(a: np.ndarray, dy: int, dx: int, fill: bool) -> np.ndarray:
    """``out[y, x] = a[y + dy, x + dx]``, with ``fill`` outside the array."""
    h, w = a.shape
    out = np.full_like(a, fill)
    ys, yd = (slice(dy, h), slice(0, h - dy)) if dy >= 0 else (slice(0, h + dy), slice(-dy, h))
    xs, xd = (slice(dx, w), slice(0, w - dx)) if dx >= 0 else (slice(0, w + dx), slice(-dx, w))
    out[yd, xd] = a[ys, xs]
    return out


def _diagonal_count(wall: np.ndarray) -> np.ndarray:
    return sum(_shift(wall, dy, dx, True).astype(np.int8) for dy in (-1, 1) for dx in (-1, 1))


def _wall_off_narrow(wall: np.ndarray) -> np.ndarray:
    wall = wall.copy()
    while True:
        room = ~wall

        def r(dy: int, dx: int) -> np.ndarray:
            return _shift(room, dy, dx, False)

        horizontal = (r(0, -1) & r(0, 1)) | (r(0, 1) & r(0, 2)) | (r(0, -1) & r(0, -2))
        vertical = (r(-1, 0) & r(1, 0)) | (r(1, 0) & r(2, 0)) | (r(-1, 0) & r(-2, 0))
        diagonals = (r(-1, -1) | r(1, 1)) & (r(-1, 1) | r(1, -1))
        bad = room & ~(horizontal & vertical & diagonals)
        if not bad.any():
            return wall
        wall |= bad


def _remove_small_regions(wall: np.ndarray, wall_threshold: int, room_threshold: int) -> np.ndarray:
    wall = wall.copy()
    labels, n = ndimage.label(wall, structure=FOUR)
    if n:
        sizes = np.bincount(labels.ravel())
        small = sizes < wall_threshold
        small[0] = False
        wall[small[labels]] = False
    labels, n = ndimage.label(~wall, structure=FOUR)
    if n:
        sizes = np.bincount(labels.ravel())
        small = sizes < room_threshold
        small[0] = False
        wall[small[labels]] = True
    return wall


def _edges(region: np.ndarray) -> np.ndarray:
    """Tiles of ``region`` with a 4-neighbour outside it, as (y, x) rows."""
    inner = ndimage.binary_erosion(region, structure=FOUR, border_value=0)
    return np.argwhere(region & ~inner)


def _connect_regions(wall: np.ndarray, radius: int) -> np.ndarray:
    wall = wall.copy()
    yy, xx = np.mgrid[-radius:radius + 1, -radius:radius + 1]
    disc = (yy * yy + xx * xx) <= radius * radius
    while True:
        labels, n = ndimage.label(~wall, structure=FOUR)
        if n <= 1:
            return wall
        sizes = np.bincount(labels.ravel())
        sizes[0] = 0
        main = labels == int(sizes.argmax())
        others = (labels > 0) & ~main
        connected_edges = _edges(main)
        other_edges = _edges(others)
        from scipy.spatial import cKDTree  # here, not at import: scipy.spatial costs a building run ~13 MB

        tree = cKDTree(connected_edges)
        dist, idx = tree.query(other_edges)
        best = int(np.argmin(dist))
        start = other_edges[best]
        end = connected_edges[idx[best]]
        line = np.zeros_like(wall)
        steps = int(max(abs(end[0] - start[0]), abs(end[1] - start[1]))) + 1
        ys = np.rint(np.linspace(start[0], end[0], steps)).astype(int)
        xs = np.rint(np.linspace(start[1], end[1], steps)).astype(int)
        line[ys, xs] = True
        carved = ndimage.binary_dilation(line, structure=disc)
        carved[0, :] = carved[-1, :] = carved[:, 0] = carved[:, -1] = False
        wall &= ~carved
