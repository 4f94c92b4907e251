"""Wall Follower: MAES's ``WallFollower.cs`` rule tile by tile (west to a wall, then the left-hand rule;
a collision steps back), the wall kept on the chosen side round two hand-built rooms and through their
door, MAES's 1.8 m ray circling four tiles at that door (``variant = "maes"``), the checker, and a 50-tile
building explored with 4 robots."""

from __future__ import annotations

import math

import numpy as np
import pytest

from algorithms import tiles
from algorithms.wall_follower import WallFollower, WallFollowerParams
from maps import InvalidInput, Map
from swarm.api import FREE, SOLID, NavStatus, Observation, Pose, RobotInfo
from swarm.sim.loop import Simulation

ALGORITHM = "algorithms.wall_follower:WallFollower"


def room_tiles() -> np.ndarray:
    """bool[ty, tx] of blocked tiles: two rooms (tiles x 1-8 and 10-16, y 1-8) joined by a door at x 9,
    y 4-5, and above them a sealed one-tile pocket, so that a run never counts as fully explored."""
    t = np.zeros((13, 18), dtype=bool)
    t[0, :] = t[:, 0] = t[:, -1] = t[9:, :] = True
    t[:9, 9] = True
    t[4:6, 9] = False
    t[11, 2] = False
    return t


def rooms() -> Map:
    solid = np.kron(room_tiles(), np.ones((2, 2), dtype=bool))
    return Map(solid=solid, material=solid.astype(np.uint8), materials=("air", "concrete"))


def tile_path(variant: str = "swarm", side: str = "left", ticks: int = 2000) -> list[tuple[int, int]]:
    """The tiles one robot starting in the west room (4.75, 4.75) stands on, each change once."""
    path: list[tuple[int, int]] = []

    def watch(view):
        here = tiles.tile_of(*view.poses[0][:2])
        if not path or path[-1] != here:
            path.append(here)

    spec = {"seed": 0, "robots": {"count": 1}, "stop": {"max_ticks": ticks, "explored": 1.0},
            "algorithm": {"name": ALGORITHM, "params": {"variant": variant, "side": side}}}
    Simulation(spec, truth=rooms(), start_poses=np.array([[4.75, 4.75, 0.0]]), observers=(watch,)).run()
    return path


def blocked(tile: tuple[int, int]) -> bool:
    t = room_tiles()
    return bool(t[tile[1], tile[0]])


def side_of(a: tuple[int, int], b: tuple[int, int], turn: int) -> tuple[tuple[int, int], tuple[int, int]]:
    """The tiles beside ``a`` and ``b`` on the ``turn`` side (-1 left, +1 right) of the move a -> b."""
    d = tiles.STEP.index((b[0] - a[0], b[1] - a[1]))
    s = (d + turn) % 4
    return tiles.step(a, s), tiles.step(b, s)


@pytest.mark.parametrize("side, turn, sign", [("left", -1, -1.0), ("right", 1, 1.0)])
def test_keeps_the_wall_on_its_side_round_both_rooms_and_through_the_door(side, turn, sign):
    path = tile_path(side=side)
    wall = next(i for i, t in enumerate(path) if t[0] in (1, 16))   # the first wall reached: west (east)
    assert path[wall] == ((1, 4) if side == "left" else (16, 4)), "straight west (east) to the wall"
    loop = path[wall:]
    back = loop.index(loop[0], 1)                                    # round both rooms, back to it
    lap = loop[:back + 1]
    for a, b in zip(lap, lap[1:]):
        assert abs(a[0] - b[0]) + abs(a[1] - b[1]) == 1, f"one tile at a time: {a} -> {b}"
        assert any(blocked(t) for t in side_of(a, b, turn)), f"the wall on the {side} from {a} to {b}"
    ring = {(x, y) for x, y in np.ndindex(17, 9) if not blocked((x, y)) and (x in (1, 8, 10, 16) or y in (1, 8))}
    assert ring <= set(lap), f"missed {sorted(ring - set(lap))}"
    assert (9, 4) in lap and (9, 5) in lap, "through the door both ways"
    xs, ys = np.array(lap, dtype=float).T
    area = 0.5 * float(np.sum(xs[:-1] * ys[1:] - xs[1:] * ys[:-1]))
    assert math.copysign(1.0, area) == sign, "left hand clockwise, right hand counter-clockwise"


def test_maes_ray_follows_a_tile_off_the_wall_and_circles_four_tiles_at_the_door():
    path = tile_path(variant="maes")
    assert all(t[0] < 9 for t in path), "it never gets through the door"
    last = path[-40:]
    assert len(set(last)) == 4, f"round four tiles for ever: {sorted(set(last))}"
    xs, ys = zip(*set(last))
    assert max(xs) - min(xs) == 1 and max(ys) - min(ys) == 1 and max(xs) == 8, "a 2 x 2 block by the door"


# ------------------------------------------------------------------------------- the rule, unit ----
def known_of(t: np.ndarray) -> np.ndarray:
    k = np.where(np.kron(t, np.ones((2, 2), dtype=bool)), SOLID, FREE).astype(np.uint8)
    k.flags.writeable = False
    return k


def follower(side: str = "left", **params) -> WallFollower:
    w = WallFollower()
    w.reset(RobotInfo(id=0, n_robots=1, map_shape=(26, 36)), WallFollowerParams(side=side, **params),
            np.random.default_rng(0))
    return w


def at(tile: tuple[int, int], tick: int, **kw) -> Observation:
    x, y = tiles.tile_goal(tile)
    return Observation(tick=tick, robot_id=0, pose=Pose(x, y, 0.0), known=known_of(room_tiles()), **kw)


def arrive(w: WallFollower, tile: tuple[int, int], tick: int) -> tuple[int, int] | None:
    """The robot has driven to ``tile``: the tile of the next goal, or None if it stays."""
    goal = w.act(at(tile, tick, nav=NavStatus(goal=w.goal, state="reached"))).goal
    return None if goal is None else tiles.tile_of(*goal)


def test_heads_west_to_a_wall_then_north_with_the_wall_on_its_left():
    w = follower()
    assert tiles.tile_of(*w.act(at((4, 4), 0)).goal) == (3, 4), "north is open: one tile west"
    assert w.seeking and w.direction == 3
    assert arrive(w, (3, 4), 1) == (2, 4) and arrive(w, (2, 4), 2) == (1, 4)
    assert arrive(w, (1, 4), 3) is None, "at the wall: west is blocked, it turns north"
    assert not w.seeking and w.direction == 0
    assert tiles.tile_of(*w.act(at((1, 4), 4)).goal) == (1, 5), "wall on the left, nothing ahead: forward"


def test_left_hand_rule_turns_left_into_an_opening_and_right_at_a_corner():
    w = follower()
    w.seeking, w.direction, w.target = False, 2, (8, 5)       # going south along the east wall of room A
    stop = w.act(at((8, 5), 0))
    assert stop.goal is None and w.direction == 1 and w.turned, "the door on the left: turn left (east)"
    assert tiles.tile_of(*w.act(at((8, 5), 1)).goal) == (9, 5), "just turned, nothing ahead: forward"
    w.direction, w.target, w.turned = 0, (1, 8), False        # going north at the north-west corner
    w.act(at((1, 8), 2))
    assert w.direction == 1 and not w.turned, "wall left and ahead: turn right"


def test_a_collision_steps_back_and_counts_as_a_wall_ahead():
    w = follower()
    w.seeking, w.direction, w.target = False, 0, (1, 5)
    goal = w.act(at((1, 4), 0)).goal                            # on its way north to (1, 5)
    moving = NavStatus(goal=goal, state="moving")
    w.act(at((1, 4), 1, nav=moving))
    back = w.act(at((1, 4), 2, nav=moving, collided=True))
    assert w.target == (1, 4) and back.goal is None, "stepped back to where it stands"
    assert w.direction == 1 and not w.collided, "and decided: wall on the left, the collision ahead: turn right"


@pytest.mark.parametrize("params, field", [({"variant": "MAES"}, "variant"), ({"side": "up"}, "side"),
                                           ({"deadlock_ticks": -1}, "deadlock_ticks"),
                                           ({"progress_m": 0.0}, "progress_m")])
def test_bad_parameters_are_one_line_errors_naming_the_field(params, field):
    with pytest.raises(InvalidInput) as err:
        WallFollowerParams(**params)
    assert err.value.field == field and "\n" not in str(err.value)


# ----------------------------------------------------------------------------------- whole runs ----
def test_the_maes_variant_passes_the_explorer_checker():
    """The default variant is checked with every built-in (tests/algorithms/test_contract.py)."""
    from swarm.testing import CHECKS, check_explorer

    assert check_explorer(ALGORITHM, params={"variant": "maes"}).checks == CHECKS


def test_four_robots_explore_a_50_tile_building():
    """Measured (seeds 1-5, 5,000 ticks, swarm's 1 m/s robot stopping at every tile): 0.25, 0.46, 0.34,
    0.45, 0.31 explored (all four robots follow one wall); with MAES's motion preset 0.89, 0.85, 0.84, 0.90,
    0.92; the maes variant 0.15, 0.37, 0.09, 0.24, 0.12."""
    r = Simulation({"seed": 2, "map": {"kind": "building", "size": 50}, "robots": {"count": 4},
                    "algorithm": {"name": ALGORITHM}, "stop": {"max_ticks": 5000}}).run()
    assert r.summary["explored"] > 0.3, r.one_line()
