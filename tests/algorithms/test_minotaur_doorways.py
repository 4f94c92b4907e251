"""Minotaur's doorway detection (paper section 3.3, Alg. 3, Fig. 1) on hand-made maps.

Each fixture is checked twice: the detector on the fully known map (exact, fast), and a whole
single-robot Minotaur run that must end with exactly the expected number of doorways, as MAES's
``MinotaurDoorwayTest`` does (docs/maes.md section 9, item 16).
"""

from __future__ import annotations

import numpy as np
import pytest

from algorithms.minotaur.detection import detect, pending_gaps
from algorithms.minotaur.doorways import Doorway, DoorwayBook
from maps import Map
from maps.materials import DEFAULT_TABLE
from swarm.api import FREE, SOLID, UNSEEN
from swarm.sim.loop import Simulation

CELL = 0.5


# ------------------------------------------------------------------------------------------ fixtures ----
def blank(width_m: float, height_m: float) -> np.ndarray:
    """A room with a 1 m wall all round: solid[row, col], row 0 at the bottom."""
    solid = np.zeros((int(height_m / CELL), int(width_m / CELL)), dtype=bool)
    solid[:2, :] = solid[-2:, :] = True
    solid[:, :2] = solid[:, -2:] = True
    return solid


def wall(solid: np.ndarray, x0: float, y0: float, x1: float, y1: float) -> np.ndarray:
    """Make [x0, x1) x [y0, y1) (metres) solid."""
    solid[int(y0 / CELL):int(y1 / CELL), int(x0 / CELL):int(x1 / CELL)] = True
    return solid


def gap(solid: np.ndarray, x0: float, y0: float, x1: float, y1: float) -> np.ndarray:
    solid[int(y0 / CELL):int(y1 / CELL), int(x0 / CELL):int(x1 / CELL)] = False
    return solid


def as_map(solid: np.ndarray) -> Map:
    return Map(solid=solid, material=np.where(solid, 1, 0).astype(np.uint8), materials=DEFAULT_TABLE)


def empty_room() -> Map:
    """Fig. 1 third case (corners, no door): a 14 x 10 m room."""
    return as_map(blank(14, 10))


def wall_with_door() -> Map:
    """Fig. 1 first case: a 1 m wall across a 24 x 12 m room with one 2 m gap in its middle."""
    solid = wall(blank(24, 12), 12, 0, 13, 12)
    return as_map(gap(solid, 12, 5, 13, 7))


def door_in_corner() -> Map:
    """Fig. 1 second case: the dividing wall stops 2 m short of the bottom wall."""
    solid = wall(blank(24, 12), 12, 3, 13, 12)
    return as_map(solid)


def corridor_into_room() -> Map:
    """A 2 m wide, 9 m long corridor (a dead end) opening into a 14 x 10 m room through its top wall."""
    solid = blank(14, 21)
    wall(solid, 0, 11, 14, 12)                  # the room's top wall (the room is y in [1, 11))
    wall(solid, 0, 12, 6, 21)                   # fill beside the corridor
    wall(solid, 8, 12, 14, 21)
    return as_map(gap(solid, 6, 11, 8, 12))     # the mouth: x in [6, 8)


def hallway() -> Map:
    """Fig. 1 fourth case: a 4 m gap (wider than the 3 m maximum door width) in a dividing wall."""
    solid = wall(blank(24, 12), 12, 0, 13, 12)
    return as_map(gap(solid, 12, 4, 13, 8))


FIXTURES = {
    "empty_room": (empty_room, 0, (4.0, 5.0)),
    "wall_with_door": (wall_with_door, 1, (5.0, 6.0)),
    "door_in_corner": (door_in_corner, 1, (5.0, 6.0)),
    "corridor_into_room": (corridor_into_room, 1, (4.0, 5.0)),
    "hallway": (hallway, 0, (5.0, 6.0)),
}


def known_of(m: Map) -> np.ndarray:
    return np.where(m.solid, SOLID, FREE).astype(np.uint8)


def find_doorways(m: Map) -> list[Doorway]:
    return detect(known_of(m), min_width_m=1.5, max_width_m=3.0, wall_continue_m=1.0)


# ------------------------------------------------------------------------------ detector, full map ----
@pytest.mark.parametrize("name", sorted(FIXTURES))
def test_detector_on_fully_known_fixture(name: str) -> None:
    build, expected, _ = FIXTURES[name]
    assert len(find_doorways(build())) == expected


def test_door_geometry_is_the_gap() -> None:
    (door,) = find_doorways(wall_with_door())
    assert door.axis == 1                                      # a vertical wall, crossed along x
    assert door.x == pytest.approx(12.5) and door.y == pytest.approx(6.0)
    assert door.width == pytest.approx(2.0) and door.depth == pytest.approx(1.0)
    assert door.side_of(10.0, 6.0) == -1 and door.side_of(15.0, 6.0) == 1 and door.side_of(12.5, 6.0) == 0


def test_corner_door_sits_between_wall_end_and_floor() -> None:
    (door,) = find_doorways(door_in_corner())
    assert door.axis == 1 and door.x == pytest.approx(12.5)
    assert door.y == pytest.approx(2.0) and door.width == pytest.approx(2.0)


def test_corridor_has_one_doorway_at_its_mouth() -> None:
    (door,) = find_doorways(corridor_into_room())
    assert door.axis == 0 and door.x == pytest.approx(7.0)
    assert 11.0 <= door.y <= 12.5                              # in the room's top wall, not along the corridor


def test_max_door_width_decides_door_or_hallway() -> None:
    wide = known_of(hallway())
    assert detect(wide, 1.5, 3.0, 1.0) == []
    assert len(detect(wide, 1.5, 4.0, 1.0)) == 1


def test_a_notch_is_not_a_doorway() -> None:
    solid = wall(blank(24, 12), 12, 0, 14, 12)                  # a 2 m thick wall
    gap(solid, 12, 5, 13, 7)                                   # cut half way through: a niche
    assert find_doorways(as_map(solid)) == []


def test_a_gap_is_accepted_only_once_its_far_jamb_is_seen() -> None:
    """Alg. 3 single-wall case: the wall must be seen to continue after the gap."""
    k = known_of(wall_with_door())
    k[14:, 24:26] = UNSEEN                                      # the wall beyond the gap not seen yet
    assert detect(k, 1.5, 3.0, 1.0) == []
    pending = pending_gaps(k, 1.5, 3.0, 1.0)
    assert any(r == 14 and c in (24, 25) for r, c, *_ in pending)   # go and look past the gap
    k[14:16, 24:26] = SOLID                                     # now the wall is seen to continue
    assert len(detect(k, 1.5, 3.0, 1.0)) == 1


def test_window_origin_maps_back_to_map_coordinates() -> None:
    k = known_of(wall_with_door())
    (whole,) = detect(k, 1.5, 3.0, 1.0)
    (part,) = detect(k[4:20, 16:40], 1.5, 3.0, 1.0, origin=(4, 16))
    assert (part.x, part.y, part.axis) == (whole.x, whole.y, whole.axis)


def test_doorway_book_merges_the_same_doorway() -> None:
    book = DoorwayBook()
    a, new_a = book.add(Doorway(12.5, 6.0, 1, 2.0, 1.0, sides=1))
    b, new_b = book.add(Doorway(12.75, 6.25, 1, 2.0, 0.5, sides=2))
    _, new_c = book.add(Doorway(12.5, 6.0, 0, 2.0, 1.0))            # other axis: another doorway
    assert new_a and not new_b and new_c and b is a and len(book) == 2
    assert a.sides == 3 and a.explored


# ---------------------------------------------------------------------------- exploration runs ----
def explore(m: Map, start: tuple[float, float], robots: int = 1, **spec: object) -> tuple[dict, list]:
    """Run Minotaur until 99 % explored; the final debug of every robot and the result summary."""
    last: dict[int, dict] = {}

    def watch(view) -> None:
        for i, a in enumerate(view.actions):
            if a is not None and a.debug:
                last[i] = dict(a.debug)

    poses = np.array([[start[0] + 0.8 * i, start[1], 0.0] for i in range(robots)])
    run_spec = {"robots": {"count": robots}, "algorithm": {"name": "minotaur"}, "seed": 3,
                "stop": {"max_ticks": 6000}, **spec}
    result = Simulation(run_spec, truth=m, observers=[watch], start_poses=poses).run()
    return result.summary, [last[i] for i in sorted(last)]


@pytest.mark.parametrize("name", sorted(FIXTURES))
def test_single_robot_run_finds_expected_doorways(name: str) -> None:
    build, expected, start = FIXTURES[name]
    summary, debug = explore(build(), start)
    assert summary["stop_reason"] == "explored"
    assert len(debug[0]["doorways"]) == expected


def test_doorway_explored_after_passing_through() -> None:
    """Alg. 3: a doorway is explored once passed through (here the robot must, to finish the map)."""
    summary, debug = explore(wall_with_door(), (5.0, 6.0))
    ((*_, explored),) = debug[0]["doorways"]
    assert summary["stop_reason"] == "explored" and explored
