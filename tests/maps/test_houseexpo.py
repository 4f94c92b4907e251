"""HouseExpo JSON floor plans (issue 52): rasterised as HouseExpo's reader draws them, then onto 0.5 m cells
with walls that never leak and doors that stay open; one-line errors; a plan explored by a short run."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import swarm
from maps import InvalidInput
from maps.houseexpo import EXPLORABLE_SCALE, MAX_SIDE_M, MAX_VERTS
from maps.io import load_map
from swarm.cli import main
from .test_fuzz_inputs import EDITS, fuzz, load_or_refuse, mutate
from .test_input_errors import cli_error

PLANS = Path(__file__).resolve().parents[2] / "examples" / "plans"
T = 0.15  # wall thickness of the hand-made plans


def write(tmp_path: Path, plan: object, name: str = "plan.json") -> Path:
    path = tmp_path / name
    path.write_text(plan if isinstance(plan, str) else json.dumps(plan))
    return path


def two_rooms(door: tuple[float, float] = (1.15, 1.95)) -> dict:
    """Room A 4 x 3 m (x 0..4), a 0.15 m wall, room B 4 x 3 m (x 4.15..8.15), a door at y = door."""
    lo, hi = door
    verts = [[0, 0], [4, 0], [4, lo], [4 + T, lo], [4 + T, 0], [8 + T, 0], [8 + T, 3], [4 + T, 3], [4 + T, hi],
             [4, hi], [4, 3], [0, 3]]
    return {"id": "t", "room_num": 2, "bbox": {"min": [0, 0], "max": [8 + T, 3]}, "verts": verts,
            "room_category": {"bedroom": [[0, 0, 4, 3]], "kitchen": [[4 + T, 0, 8 + T, 3]]}}


def free_in(m, x0: float, x1: float, y0: float, y1: float) -> float:
    """Free area (m2) of the map's cells inside the plan rectangle (plan coordinates)."""
    ox, oy = m.params["origin"]
    c0, c1 = int(round((x0 - ox) / 0.5)), int(round((x1 - ox) / 0.5 + 0.49))
    r0, r1 = int(round((y0 - oy) / 0.5)), int(round((y1 - oy) / 0.5 + 0.49))
    return float((~m.solid[r0:r1, c0:c1]).sum()) * 0.25


def test_rooms_import_to_their_area_within_a_cell(tmp_path):
    m = load_map(write(tmp_path, two_rooms()))
    assert m.params["format"] == "houseexpo" and m.params["origin"] == [-0.5, -0.5]
    assert m.materials == ("air", "concrete") and m.params["room_categories"] == ["bedroom", "kitchen"]
    # room A lies on the cells: exactly 4 x 3 m; room B starts 0.15 m past a cell edge: one column short
    assert free_in(m, 0, 4, 0, 3) == 12.0
    assert 4 * 3 - 0.5 * 3 <= free_in(m, 4.5, 8.5, 0, 3) <= 4 * 3
    total = m.free_cells * 0.25
    polygon = 2 * 12 + T * 0.8
    assert polygon - (0.5 * 3 + 0.5 * 4) <= total <= polygon  # within one cell per side of each room


def test_the_wall_between_rooms_never_leaks_but_the_door_stays_open(tmp_path):
    from scipy import ndimage

    m = load_map(write(tmp_path, two_rooms()))
    wall_col = int((4.0 + 0.5) / 0.5)  # cell column x = 4.0..4.5 holds the wall
    opening = np.flatnonzero(~m.solid[:, wall_col])
    assert len(opening) == 1, "one door cell; the rest of the wall is solid"
    # the 0.8 m door (y 1.15..1.95) holds no whole cell: the all-pixels rule shut it, the door pass reopened it
    assert m.params["doors_opened"] == 1 and 1.0 <= (opening[0] - 1) * 0.5 <= 1.5
    assert ndimage.label(~m.solid)[1] == 1
    # a wall reaching in from the outline (x 3..3.15, y 2.5..6) is solid over its whole length, no door opened
    split = load_map(PLANS / "handmade_split_room.json")
    assert split.solid[6:13, 7].all() and not split.solid[1:6, 7].any() and split.params["doors_opened"] == 0


def test_a_door_aligned_with_the_cells_needs_no_reopening(tmp_path):
    m = load_map(write(tmp_path, two_rooms(door=(1.0, 2.0))))
    assert m.params["doors_opened"] == 0
    assert (~m.solid[:, 9]).sum() == 2


def test_shipped_hand_made_plans_are_connected_houses():
    from scipy import ndimage

    plans = sorted(PLANS.glob("*.json"))
    assert len(plans) == 3
    for path in plans:
        m = load_map(path)
        assert ndimage.label(~m.solid)[1] == 1, path.name
        assert m.free_cells * 0.25 <= m.params["polygon_area_m2"]


def test_closed_polygon_lists_material_and_border(tmp_path):
    plan = two_rooms()
    plan["verts"].append(plan["verts"][0])
    m = load_map(write(tmp_path, plan), material="brick", border=1)
    assert m.materials == ("air", "brick", "concrete") and m.params["origin"] == [-1.5, -1.5]  # border: 1 tile = 1 m
    assert m.free_cells == load_map(write(tmp_path, two_rooms(), "b.json")).free_cells


def test_cli_import(tmp_path, capsys):
    out = tmp_path / "plan.npz"
    assert main(["map", "import", str(PLANS / "handmade_two_rooms.json"), "-o", str(out), "--material", "brick"]) == 0
    m = load_map(out)
    assert m.params["material"] == "brick" and m.params["id"] == "handmade_two_rooms"


@pytest.mark.parametrize("text, needles", [
    ("not json", ["plan.json", "a HouseExpo plan: a UTF-8 JSON object with 'verts'"]),
    ("[1, 2]", ["plan.json", "not a list"]),
    ('{"id": "x"}', ["verts: got None", "a list of [x, y] vertices in metres (missing in"]),
    ('{"verts": "abc"}', ["verts: got 'abc'", "a list of 3..20000 [x, y] vertices"]),
    ('{"verts": [[0, 0], [1, 1]]}', ["verts: got '2 vertices'", "3..20000"]),
    ('{"verts": [[0, 0], [4, 0], [4, "a"], [0, 4]]}', ["verts[2]: got [4, 'a']", "two finite numbers"]),
    ('{"verts": [[0, 0], [4, 0], [4, 1e400], [0, 4]]}', ["verts[2]", "two finite numbers"]),
    ('{"verts": [[0, 0], [4, 0], [8, 0]]}', ["verts: got '3 vertices, 8.00 m x 0.00 m, area 0.000 m2'",
                                            "a polygon enclosing at least one 0.5 m cell"]),
    ('{"verts": [[0, 0], [0.9, 0], [0, 0.9]]}', ["verts", "room for at least one whole 0.5 m cell"]),
    ('{"verts": [[0, 0], [900, 0], [900, 10], [0, 10]]}', ["verts: got '900.0 m x 10.0 m'",
                                                          f"at most {MAX_SIDE_M:g} m per side"]),
    ('{"verts": [[0, 0], [4, 0], [4, 4]], "room_num": -1}', ["room_num: got -1", "a non-negative integer"]),
    ('{"verts": [[0, 0], [4, 0], [4, 4]], "room_category": [1]}', ["room_category: got [1]"]),
])
def test_bad_plans_are_one_line_naming_the_field(tmp_path, capfd, text, needles):
    err = cli_error(capfd, "map", "import", write(tmp_path, text), "-o", tmp_path / "out.npz")
    assert all(n in err for n in needles), err
    assert not (tmp_path / "out.npz").exists()


def test_too_many_vertices_and_a_legend_are_refused(tmp_path):
    verts = [[float(i % 7), float(i // 7)] for i in range(MAX_VERTS + 1)]
    with pytest.raises(InvalidInput, match="verts: got '20001 vertices'"):
        load_map(write(tmp_path, {"verts": verts}))
    with pytest.raises(InvalidInput, match="no legend for a HouseExpo"):
        load_map(write(tmp_path, two_rooms()), legend=tmp_path / "legend.toml")


def test_scale_multiplies_the_plan(tmp_path, capfd):
    m = load_map(write(tmp_path, two_rooms()), scale=2.0)
    assert m.params["scale"] == 2.0 and free_in(m, 0, 8, 0, 6) == 48.0  # room A, 8 x 6 m, on the cells
    assert "--plan-scale: got 0.1" in cli_error(capfd, "map", "import", write(tmp_path, two_rooms()), "-o",
                                                tmp_path / "o.npz", "--plan-scale", "0.1")
    (tmp_path / "o.csv").write_text("1,1,1\n1,0,1\n1,1,1\n")
    assert "--plan-scale: got 2.0" in cli_error(capfd, "map", "import", tmp_path / "o.csv", "-o",
                                                tmp_path / "p.npz", "--plan-scale", "2")
    with pytest.raises(InvalidInput, match="map.params.scale: got 'big'"):
        swarm.run({"map": {"kind": "file", "path": "a.json", "params": {"scale": "big"}}})
    with pytest.raises(InvalidInput, match="map.params.scale: got 2"):
        swarm.run({"map": {"kind": "file", "path": "a.npz", "params": {"scale": 2}}})


def test_at_scale_one_the_default_robot_cannot_leave_the_hallway_at_explorable_scale_it_can():
    """swarm's planner needs 1.5 m openings: the plan's 0.9 m doors and 1.2 m hallway hold no path at scale 1."""
    path = PLANS / "handmade_hall_three_rooms.json"
    explored = {}
    for scale in (1.0, EXPLORABLE_SCALE):
        spec = (f'seed = 1\nrecord_every = 10\n[map]\nkind = "file"\npath = "{path}"\nparams = {{scale = {scale}}}\n'
                '[robots]\ncount = 2\n[stop]\nmax_ticks = 400\nexplored = 0.95\n')
        explored[scale] = swarm.run(spec).timeseries["explored"]
    assert explored[1.0][-1] == explored[1.0][0], "stuck at scale 1"
    assert explored[EXPLORABLE_SCALE][-1] > explored[EXPLORABLE_SCALE][0] + 0.3, explored[EXPLORABLE_SCALE]


COORD = st.one_of(st.floats(-60, 60, allow_nan=False), st.integers(-60, 60),
                  st.sampled_from([float("nan"), float("inf"), 1e300, -0.0, True, None, "1", [1]]))


@fuzz(200)
@given(verts=st.lists(st.lists(COORD, min_size=0, max_size=3), min_size=0, max_size=40),
       extra=st.dictionaries(st.sampled_from(["id", "room_num", "room_category", "bbox"]),
                             st.one_of(st.none(), st.integers(-5, 5), st.text(max_size=4), st.lists(st.integers()))))
def test_random_plans_import_or_are_refused_in_one_line(tmp_path_factory, verts, extra):
    path = tmp_path_factory.getbasetemp() / "fuzz_plan.json"
    path.write_text(json.dumps({"verts": verts, **extra}))
    load_or_refuse("houseexpo plan", load_map, path)


@fuzz(150)
@given(edits=EDITS)
def test_mutated_plans(tmp_path_factory, edits):
    path = tmp_path_factory.getbasetemp() / "mutated_plan.json"
    path.write_bytes(mutate((PLANS / "handmade_hall_three_rooms.json").read_bytes(), edits))
    load_or_refuse("houseexpo mutated", load_map, path)
