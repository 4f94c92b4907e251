"""Random Ballistic Walk: straight ahead until a collision, then a random turn in place as MAES's
``RandomExplorationAlgorithm.cs`` does (the ``maes`` variant clockwise only, in whole degrees), seeded and
reproducible; the checker; a 50-tile building explored with 4 robots."""

from __future__ import annotations

import math

import numpy as np
import pytest

from algorithms.random_ballistic_walk import (TURN_DONE_DEG, RandomBallisticWalk, RandomBallisticWalkParams,
                                              _wrap)
from maps import InvalidInput, Map
from swarm.api import FREE, Observation, Pose, RobotInfo
from swarm.sim.loop import Simulation

ALGORITHM = "algorithms.random_ballistic_walk:RandomBallisticWalk"
ROBOT = RobotInfo(id=0, n_robots=1, map_shape=(20, 20), max_speed=1.5, max_turn_rate=2.0)


def walker(seed: int = 0, **params) -> RandomBallisticWalk:
    w = RandomBallisticWalk()
    w.reset(ROBOT, RandomBallisticWalkParams(**params), np.random.default_rng(seed))
    return w


def observe(tick: int, theta: float = 0.0, collided: bool = False) -> Observation:
    known = np.full((20, 20), FREE, dtype=np.uint8)
    known.flags.writeable = False
    return Observation(tick=tick, robot_id=0, pose=Pose(5.0, 5.0, theta), known=known, collided=collided)


def drawn_turns(seed: int, n: int, **params) -> list[float]:
    """The turns (degrees, counter-clockwise) of ``n`` collisions, each turn completed at once."""
    w, out = walker(seed, **params), []
    for i in range(n):
        w.act(observe(3 * i, collided=True))
        out.append(w.last_turn_deg)
        heading = w.heading
        w.act(observe(3 * i + 1, theta=heading))      # facing the drawn heading, and
        w.act(observe(3 * i + 2, theta=heading))      # still: the turn is over
    return out


# ---------------------------------------------------------------------------------- the rule ----
def test_drives_straight_at_full_speed_until_a_collision_then_turns_in_place():
    w = walker()
    for tick in range(50):
        assert w.act(observe(tick)).velocity == (1.5, 0.0)
    turn = w.act(observe(50, collided=True)).velocity
    assert turn[0] == 0.0 and turn[1] != 0.0, "a collision ends the straight move: a turn in place"
    heading = w.heading
    assert math.copysign(1.0, turn[1]) == math.copysign(1.0, w.last_turn_deg)
    assert math.isclose(heading, _wrap(math.radians(w.last_turn_deg)))
    # Still turning while the heading is off, whatever it touches.
    assert w.act(observe(51, theta=heading / 2, collided=True)).velocity[0] == 0.0
    assert w.act(observe(52, theta=heading)).velocity == (0.0, 0.0), "there: it waits until it stops turning"
    assert w.act(observe(53, theta=heading)).velocity == (1.5, 0.0), "then straight on again"


def test_contact_on_the_first_tick_after_a_turn_is_the_old_one_but_a_second_starts_a_new_turn():
    w = walker()
    w.act(observe(0, collided=True))
    heading = w.heading
    w.act(observe(1, theta=heading))
    assert w.act(observe(2, theta=heading)).velocity == (1.5, 0.0)
    first = w.turns
    assert w.act(observe(3, theta=heading, collided=True)).velocity == (1.5, 0.0), \
        "the contact it turned away from (MAES re-declares a collision only after two physics updates)"
    assert w.act(observe(4, theta=heading, collided=True)).velocity[0] == 0.0
    assert w.turns == first + 1


def test_maes_variant_turns_clockwise_by_whole_degrees_from_50_to_179():
    turns = drawn_turns(3, 2000, variant="maes")
    assert all(t < 0 for t in turns), "Random.Next(0, 1) is always 0: direction -1, clockwise"
    assert all(float(t).is_integer() and 50 <= -t <= 179 for t in turns)
    assert {-t for t in turns} >= {50.0, 179.0}, "both ends of Random.Next(50, 180) are drawn"


def test_swarm_variant_turns_either_way_by_50_to_180_degrees():
    turns = drawn_turns(3, 400)
    left = sum(t > 0 for t in turns)
    assert 150 < left < 250, f"either side with probability 1/2: {left} of 400 to the left"
    assert all(50.0 <= abs(t) < 180.0 for t in turns)
    assert not all(float(t).is_integer() for t in turns)
    narrow = drawn_turns(3, 100, turn_min_deg=10.0, turn_max_deg=20.0)
    assert all(10.0 <= abs(t) < 20.0 for t in narrow)


def test_turns_are_seeded_by_the_robots_rng_and_reproducible():
    assert drawn_turns(7, 20) == drawn_turns(7, 20)
    assert drawn_turns(7, 20) != drawn_turns(8, 20)
    assert drawn_turns(7, 20, variant="maes") == drawn_turns(7, 20, variant="maes")


@pytest.mark.parametrize("params, field", [
    ({"variant": "MAES"}, "variant"), ({"turn_min_deg": -1.0}, "turn_min_deg"),
    ({"turn_max_deg": 200.0}, "turn_max_deg"), ({"turn_min_deg": 90.0, "turn_max_deg": 90.0}, "turn_max_deg"),
    ({"variant": "maes", "turn_min_deg": 50.5, "turn_max_deg": 50.9}, "turn_max_deg"),
])
def test_bad_parameters_are_one_line_errors_naming_the_field(params, field):
    with pytest.raises(InvalidInput) as err:
        RandomBallisticWalkParams(**params)
    assert err.value.field == field and "\n" not in str(err.value)


# ----------------------------------------------------------------------------------- in a run ----
def box() -> Map:
    """20 x 20 m, walls 0.5 m thick, open inside."""
    solid = np.zeros((40, 40), dtype=bool)
    solid[0, :] = solid[-1, :] = solid[:, 0] = solid[:, -1] = True
    return Map(solid=solid, material=solid.astype(np.uint8), materials=("air", "concrete"))


def run_in_box(variant: str, seed: int = 0) -> list[tuple[np.ndarray, dict]]:
    rows: list[tuple[np.ndarray, dict]] = []
    spec = {"seed": seed, "robots": {"count": 1}, "algorithm": {"name": ALGORITHM, "params": {"variant": variant}},
            "stop": {"max_ticks": 2000, "explored": 1.0}}
    Simulation(spec, truth=box(), start_poses=np.array([[10.0, 10.0, 0.3]]),
               observers=(lambda view: rows.append((view.poses[0].copy(), dict(view.actions[0].debug))),)).run()
    return rows


@pytest.mark.parametrize("variant", ["swarm", "maes"])
def test_in_a_box_heading_holds_between_collisions_and_each_turn_is_the_drawn_angle(variant):
    rows = run_in_box(variant)
    turns = rows[-1][1]["turns"]
    assert turns >= 8, f"it bounced round the box: {turns} turns"
    t, checked = 1, 0
    while t < len(rows):
        if rows[t][1]["state"] == "turn" and rows[t - 1][1]["state"] == "move":
            before, drawn = rows[t - 1][0][2], rows[t][1]["last_turn_deg"]
            end = next((u for u in range(t, len(rows)) if rows[u][1]["state"] == "move"), None)
            if end is None:
                break
            turned = math.degrees(_wrap(rows[end][0][2] - before))
            assert abs(turned - drawn) <= TURN_DONE_DEG + 0.5, f"turned {turned:.1f}, drew {drawn:.1f}"
            if variant == "maes":
                assert turned < 0
            checked += 1
            t = end
        else:
            t += 1
    assert checked >= 8
    straight = [r[0][2] for r, nxt in zip(rows, rows[1:]) if r[1]["state"] == nxt[1]["state"] == "move"
                and r[1]["turns"] == nxt[1]["turns"]]
    assert straight, "there were straight stretches"
    for (pose, dbg), (nxt, ndbg) in zip(rows, rows[1:]):
        if dbg["state"] == ndbg["state"] == "move" and dbg["turns"] == ndbg["turns"]:
            assert abs(_wrap(nxt[2] - pose[2])) < 1e-6, "no turning while moving straight"


def test_same_seed_same_walk_other_seed_other_walk():
    a, b, c = run_in_box("swarm", 4), run_in_box("swarm", 4), run_in_box("swarm", 5)
    assert all(np.array_equal(x[0], y[0]) for x, y in zip(a, b)) and len(a) == len(b)
    assert not all(np.array_equal(x[0], y[0]) for x, y in zip(a, c))


def test_the_maes_variant_passes_the_explorer_checker():
    """The default variant is checked with every built-in (tests/algorithms/test_contract.py)."""
    from swarm.testing import CHECKS, check_explorer

    report = check_explorer(ALGORITHM, params={"variant": "maes"})
    assert report.checks == CHECKS, str(report)


def test_four_robots_explore_a_50_tile_building():
    """Measured (seeds 1-3, 3,000 ticks): 0.58, 0.36, 0.39 explored (the maes variant 0.42, 0.28, 0.39).
    RBW is weak in buildings (the MAES paper's finding too), so the bar is low: out of the spawn room and on."""
    r = Simulation({"seed": 1, "map": {"kind": "building", "size": 50}, "robots": {"count": 4},
                    "algorithm": {"name": ALGORITHM}, "stop": {"max_ticks": 3000}}).run()
    assert r.summary["explored"] > 0.3, r.one_line()
