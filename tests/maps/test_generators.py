"""Generators: determinism, connectivity a robot can use, materials, and the building room graph."""

from __future__ import annotations

import networkx as nx
import numpy as np
import pytest
from scipy import ndimage

from maps import InvalidInput, generate
from maps.building import DOOR_LABEL
from maps.io import map_to_bytes
from maps.raster import FOUR, NEAR, robot_space
from maps.rects import rasterise

KINDS = ("cave", "building")


def components(mask: np.ndarray) -> int:
    return ndimage.label(mask, structure=FOUR)[1]


def check_traversable(m) -> None:
    free = ~m.solid
    assert components(free) == 1, "free space must be one 4-connected region"
    space = robot_space(free)
    assert components(space) == 1, "the space a 0.6 m robot's centre can occupy must be one region"
    reach = ndimage.binary_dilation(space, structure=NEAR) & free
    assert np.array_equal(reach, free), "every free cell must be next to a place a robot's centre can be"


def check_common(m) -> None:
    s = m.solid
    assert s[0].all() and s[-1].all() and s[:, 0].all() and s[:, -1].all(), "outer border must be solid"
    assert (m.material[s] != 0).all(), "every solid cell has a wall material"
    assert (m.material[~s] == 0).all(), "free cells are air"
    assert set(np.unique(m.material[s]).tolist()) <= set(range(1, len(m.materials)))


def check_building_graph(m) -> None:
    g, labels = m.graph, m.rooms
    p = m.params
    assert nx.is_connected(g), "every room must be reachable in the room graph"
    assert np.array_equal(labels == -1, m.solid), "rooms raster labels exactly the solid cells -1"
    for rid, data in g.nodes(data=True):
        mask = labels == rid
        assert data["cells"] == int(mask.sum()) > 0
        assert components(mask) == 1, f"room {rid} must be one region"
        assert data["kind"] in ("hall", "room")
    halls = sorted(r for r, d in g.nodes(data=True) if d["kind"] == "hall")
    assert halls == list(range(len(halls))), "halls come first"
    # Without its doors, no free region spans two rooms: rooms are separated exactly by walls and doors.
    no_doors = (labels >= 0)
    lab, n = ndimage.label(no_doors, structure=FOUR)
    for comp in range(1, n + 1):
        assert len(np.unique(labels[lab == comp])) == 1
    door_cells = np.zeros_like(m.solid)
    for u, v, d in g.edges(data=True):
        r0, c0, r1, c1 = d["cells"]
        door_cells[r0:r1, c0:c1] = True
        assert (labels[r0:r1, c0:c1] == DOOR_LABEL).all()
        width, depth = ((c1 - c0), (r1 - r0)) if d["axis"] == "x" else ((r1 - r0), (c1 - c0))
        assert width == 2 * p["door_width"], "door opening has the configured width"
        assert depth == 2 * p["wall_thickness"]
        assert d["width"] == p["door_width"]
        # the cells just beyond the opening on either side belong to the two rooms the edge joins
        if d["axis"] == "x":
            sides = {int(labels[r0 - 1, c0]), int(labels[r1, c0])}
        else:
            sides = {int(labels[r0, c0 - 1]), int(labels[r0, c1])}
        assert sides == {u, v}
        assert d["material"] in m.materials[1:]
        x, y = d["x"], d["y"]
        assert (c0 * 0.5 <= x <= c1 * 0.5) and (r0 * 0.5 <= y <= r1 * 0.5)
    assert np.array_equal(door_cells, labels == DOOR_LABEL), "every door cell belongs to a graph door"


@pytest.mark.parametrize("kind", KINDS)
def test_same_inputs_give_identical_maps(kind):
    a = generate(kind, 60, 11)
    b = generate(kind, 60, 11)
    assert np.array_equal(a.solid, b.solid) and np.array_equal(a.material, b.material)
    assert map_to_bytes(a) == map_to_bytes(b)
    c = generate(kind, 60, 12)
    assert not np.array_equal(a.solid, c.solid)


@pytest.mark.parametrize("kind", KINDS)
def test_params_change_the_map(kind):
    key = {"cave": ("fill_percent", 45.0), "building": ("hall_width", 5)}[kind]
    a = generate(kind, 60, 3)
    b = generate(kind, 60, 3, {key[0]: key[1]})
    assert not np.array_equal(a.solid, b.solid)
    assert b.params[key[0]] == key[1]


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("size", [50, 100])
def test_hundred_seeds_are_valid(kind, size):
    for seed in range(100):
        m = generate(kind, size, seed)
        assert m.shape == (2 * size, 2 * size)
        check_common(m)
        check_traversable(m)
        if kind == "building":
            check_building_graph(m)


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("size", [150, (60, 20), (20, 90), 20])
def test_large_and_rectangular_sizes(kind, size):
    for seed in range(3):
        m = generate(kind, size, seed)
        w, h = (size, size) if isinstance(size, int) else size
        assert m.shape == (2 * h, 2 * w)
        check_common(m)
        check_traversable(m)
        if kind == "building":
            check_building_graph(m)


def test_building_materials_exterior_and_interior():
    m = generate("building", 80, 5, {"exterior_material": "brick", "interior_materials": {"wood": 1, "glass": 1}})
    assert "glass" in m.materials
    border = np.concatenate([m.material[0], m.material[-1], m.material[:, 0], m.material[:, -1]])
    assert set(border.tolist()) == {m.material_id("brick")}
    inner = m.material[4:-4, 4:-4]
    present = {m.materials[i] for i in np.unique(inner[inner > 0])}
    assert present <= {"wood", "glass"} and present == {"wood", "glass"}


def test_building_door_width_is_configurable():
    m = generate("building", 100, 2, {"door_width": 3, "door_padding": 1})
    for _, _, d in m.graph.edges(data=True):
        r0, c0, r1, c1 = d["cells"]
        assert max(r1 - r0, c1 - c0) == 6
    check_building_graph(m)
    check_traversable(m)


def test_a_wider_door_gets_a_padding_that_fits_unless_one_is_given():
    """door_width = 3 works as the README writes it: the padding left out shrinks to fit the room side."""
    from maps.building import BuildingParams

    assert BuildingParams().door_padding == 2, "MAES's padding where the door fits with it"
    assert [BuildingParams(door_width=w).door_padding for w in (3, 4, 5, 6)] == [1, 1, 0, 0]
    assert BuildingParams(door_width=3, min_room_side=8).door_padding == 2
    m = generate("building", 100, 2, {"door_width": 3})
    same = generate("building", 100, 2, {"door_width": 3, "door_padding": 1})
    assert np.array_equal(m.solid, same.solid) and np.array_equal(m.material, same.material), "as padding 1"
    with pytest.raises(InvalidInput) as err:
        BuildingParams(door_width=3, door_padding=2)
    assert err.value.field == "door_width" and "door_padding 2" in err.value.allowed
    with pytest.raises(InvalidInput) as err:
        BuildingParams(door_width=7)
    assert err.value.allowed == "door_width <= min_room_side (6)"


def test_building_extra_doors_make_loops():
    m = generate("building", 100, 4, {"extra_door_percent": 100})
    assert m.graph.number_of_edges() > m.graph.number_of_nodes() - 1
    check_building_graph(m)


def test_cave_materials_come_in_patches():
    m = generate("cave", 100, 1)
    solid, mat = m.solid, m.material
    right = solid[:, :-1] & solid[:, 1:]
    same = (mat[:, :-1] == mat[:, 1:])[right].mean()
    assert same > 0.8, f"neighbouring wall cells should mostly share a material, got {same:.2f}"
    counts = np.bincount(mat[solid], minlength=4)[1:]
    assert (counts > 0).all(), "all three default materials appear"


def test_cave_material_mix_is_respected():
    m = generate("cave", 60, 1, {"materials": {"concrete": 1, "wood": 0, "brick": 0}})
    assert set(np.unique(m.material[m.solid]).tolist()) == {m.material_id("concrete")}


@pytest.mark.parametrize("kind", KINDS)
def test_wall_rectangles_cover_exactly_the_solid_cells(kind):
    for seed in range(5):
        m = generate(kind, 70, seed)
        rects = m.wall_rectangles
        assert np.array_equal(rasterise(rects, m.shape), m.material)
        assert sum((w.row1 - w.row0) * (w.col1 - w.col0) for w in rects) == int(m.solid.sum())
        assert len(rects) < m.solid.sum() / 4, "rectangles should merge cells"


def test_map_arrays_are_read_only():
    m = generate("building", 30, 0)
    for arr in (m.solid, m.material, m.rooms, m.free):
        with pytest.raises(ValueError):
            arr[1, 1] = 0
