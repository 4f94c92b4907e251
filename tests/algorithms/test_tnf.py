"""TNF: the utility terms on a hand-made frontier configuration, coordination through announced destinations,
garbage destinations and out-of-range parameters refused. The plugin contract (registration, typed
parameters, its message round-tripping the codec, determinism, in-process == zenoh) is
tests/algorithms/test_contract.py; whole runs on every radio are tests/algorithms/test_explorer_runs.py."""

from __future__ import annotations

import math

import numpy as np
import pytest

from algorithms.tnf import TNF, Destination, TNFParams
from algorithms.tnf_utility import G_KNOWN, G_UNSEEN, distance_term, frontiers, gaussian, score_frontiers
from maps import InvalidInput, Map
from swarm import grid
from swarm.api import FREE, SOLID, UNSEEN, NavStatus, Observation, Pose, RobotInfo, cell_centre
from swarm.comm.messages import MessageError, decode, encode
from swarm.sim.loop import Simulation

G0 = 5.0 * math.exp(-12.5)      # G(0): MAES's Gaussian far from its mean

IDLE = NavStatus()


# ------------------------------------------------------------------------------------ fixtures ----
def two_frontiers() -> np.ndarray:
    """20 x 40 cells, walled. West: an unseen strip (columns 1-3, rows 1-18), so frontier A is column 4,
    rows 1-18 (18 cells). East: columns 36-38 are solid except an unseen pocket in rows 8-11, so frontier B
    is column 35, rows 8-11 (4 cells)."""
    k = np.full((20, 40), FREE, dtype=np.uint8)
    k[0, :] = k[-1, :] = k[:, 0] = k[:, -1] = SOLID
    k[1:19, 1:4] = UNSEEN
    k[1:19, 36:39] = SOLID
    k[8:12, 36:39] = UNSEEN
    return k


ROBOT = (10, 25)
TARGET_A, TARGET_B = (9, 5), (9, 34)


def score(known, destinations=(), alpha=1.0, beta=10.0):
    dest = np.array(destinations, dtype=np.int64).reshape(-1, 2)
    out = score_frontiers(known, ROBOT, dest, alpha=alpha, beta=beta, robot_radius_m=0.3, penalty_radius_m=7.0,
                          reach=2)
    return {s.target: s for s in out}, out


# -------------------------------------------------------------------------------- the terms ----
def test_gaussian_has_maes_constants():
    assert gaussian(0.5) == pytest.approx(5.0)
    assert gaussian(0.0) == pytest.approx(G0) and G0 == pytest.approx(1.863e-5, rel=1e-3)
    assert gaussian(1.0) == pytest.approx(gaussian(0.0)), "occupied and free carry equally little information"
    assert (G_UNSEEN, G_KNOWN) == (pytest.approx(5.0), pytest.approx(G0))


def test_utility_terms_on_a_hand_made_frontier_configuration():
    by_target, ranked = score(two_frontiers())
    a, b = by_target[TARGET_A], by_target[TARGET_B]
    assert (a.size, b.size) == (18, 4)
    # Information: A's 16 inner cells see 3 unseen of 8 neighbours, its 2 end cells 2 (the border is solid):
    # 52 unseen slots -> 52 * 5, plus G(0) for the 18 cells themselves and their 92 known neighbours.
    assert a.raw_gain == pytest.approx(52 * 5.0 + 110 * G0)
    # B: 2 + 3 + 3 + 2 = 10 unseen slots; 4 cells + 22 known neighbours.
    assert b.raw_gain == pytest.approx(10 * 5.0 + 26 * G0)
    assert a.gain == 1.0 and b.gain == pytest.approx(0.192308, abs=1e-6)
    # Distance: octile paths from (10, 25): to (9, 5) 19 + sqrt 2 cells, to (9, 34) 8 + sqrt 2 cells (0.5 m each).
    assert a.distance_m == pytest.approx((19 + math.sqrt(2)) / 2, abs=1e-5)
    assert b.distance_m == pytest.approx((8 + math.sqrt(2)) / 2, abs=1e-5)
    w_b = (8 + math.sqrt(2)) / (19 + math.sqrt(2))          # 0.46116; A is the farthest, w = 1
    assert a.distance == 0.0
    assert b.distance == pytest.approx((1 - w_b) ** 9, rel=1e-5) == pytest.approx(0.0038295, rel=1e-4)
    assert a.penalty == b.penalty == 0.0, "nothing heard: no coordination penalty"
    assert a.utility == pytest.approx(1.0) and b.utility == pytest.approx(0.196138, abs=1e-6)
    assert ranked[0].target == TARGET_A, "alpha = 1, beta = 10: the information-rich frontier wins"


def test_alpha_beta_8_8_prefers_the_middle_distance():
    by_target, ranked = score(two_frontiers(), alpha=8.0, beta=8.0)
    w_b = (8 + math.sqrt(2)) / (19 + math.sqrt(2))
    assert by_target[TARGET_B].distance == pytest.approx((w_b * (1 - w_b) / 0.25) ** 7, rel=1e-5)   # 0.9585
    assert ranked[0].target == TARGET_B


def test_an_announced_destination_lowers_the_frontiers_near_it():
    by_target, ranked = score(two_frontiers(), destinations=[TARGET_A])
    assert by_target[TARGET_A].penalty == 1.0 and by_target[TARGET_A].utility == pytest.approx(0.0)
    assert by_target[TARGET_B].penalty == 0.0, "B is 14.5 m from A's target, beyond the 7 m wavefront"
    assert ranked[0].target == TARGET_B
    # Halfway out of the wavefront (3.5 m = 7 cells east of A's target), half the penalty.
    by_target, _ = score(two_frontiers(), destinations=[(9, 12)])
    assert by_target[TARGET_A].penalty == pytest.approx(0.5)


def test_flat_frontier_clusters_are_the_runtimes_clusters():
    sim = Simulation({"seed": 2, "map": {"kind": "cave", "size": 50}, "robots": {"count": 1}, "stop": {"max_ticks": 150}})
    sim.run()
    known = sim.known[0]
    ours, theirs = frontiers(known), grid.frontier_clusters(known)
    assert ours.count == len(theirs) > 3
    for i, cluster in enumerate(theirs):
        assert np.array_equal(ours.cells[ours.owner == i], cluster.cells)
        assert tuple(ours.representative[i]) == cluster.representative
    big = frontiers(known, min_size=5)
    assert big.count == sum(c.size >= 5 for c in theirs) and (big.sizes >= 5).all()


def test_distance_term_stays_in_0_1():
    w = np.linspace(0.0, 1.0, 101)
    for alpha, beta in [(1, 10), (8, 8), (5, 9), (1, 1), (2, 1)]:
        d = distance_term(w, alpha, beta)
        mode = (alpha - 1) / (alpha + beta - 2) if alpha + beta > 2 else 0.5
        assert d.min() >= 0.0 and d.max() <= 1.0 + 1e-12, (alpha, beta)
        assert distance_term(np.array([mode]), alpha, beta)[0] == pytest.approx(1.0), (alpha, beta)
    # MAES's w = sqrt(sum_c |robot - c| / Dmax) is ~4 for frontier A above, and (1 - 4)^9 = -19683; here w
    # cannot leave [0, 1] (it is clipped if a caller passes more).
    assert distance_term(np.array([4.0]), 1, 10)[0] == 0.0


# -------------------------------------------------------------------------------- the robot ----
def observe(known, robot_id=0, tick=0, cell=ROBOT, inbox=(), nav=IDLE):
    x, y = cell_centre(*cell)
    known = known.copy()
    known.flags.writeable = False
    return Observation(tick=tick, robot_id=robot_id, pose=Pose(x, y, 0.0), known=known, inbox=tuple(inbox), nav=nav)


def robot(robot_id, n=2, **params):
    t = TNF()
    t.reset(RobotInfo(id=robot_id, n_robots=n, map_shape=(20, 40)), TNFParams(**params), np.random.default_rng(0))
    return t


def test_robot_announces_its_destination_and_a_later_robot_yields():
    known = two_frontiers()
    first, second = robot(0), robot(1)
    a0 = first.act(observe(known, 0))
    a1 = second.act(observe(known, 1))
    assert a0.goal == a1.goal == cell_centre(*TARGET_A), "nobody heard anybody yet: both choose A"
    assert a0.messages == (Destination(sender=0, x=a0.goal[0], y=a0.goal[1]),)
    b1 = second.act(observe(known, 1, tick=1, inbox=a0.messages, nav=NavStatus(goal=a1.goal, state="moving")))
    assert b1.goal == cell_centre(*TARGET_B), "robot 1 heard robot 0 head for A and took B"
    b0 = first.act(observe(known, 0, tick=1, inbox=a1.messages, nav=NavStatus(goal=a0.goal, state="moving")))
    assert b0.goal == a0.goal, "the lower id keeps its destination"


def test_without_yielding_the_destination_counts_at_the_next_decision():
    known = two_frontiers()
    first, second = robot(0), robot(1, yield_on_conflict=False)
    a0 = first.act(observe(known, 0))
    a1 = second.act(observe(known, 1))
    b1 = second.act(observe(known, 1, tick=1, inbox=a0.messages, nav=NavStatus(goal=a1.goal, state="moving")))
    assert b1.goal == a1.goal
    c1 = second.act(observe(known, 1, tick=2, nav=NavStatus(goal=a1.goal, state="unreachable")))
    assert c1.goal == cell_centre(*TARGET_B)


def test_reached_destination_whose_unseen_cells_stay_hidden_is_given_up():
    known = two_frontiers()
    t = robot(0)
    first = t.act(observe(known)).goal
    again = t.act(observe(known, tick=1, nav=NavStatus(goal=first, state="reached"))).goal
    assert first == cell_centre(*TARGET_A) and math.dist(first, again) > 1.0, "outside the excluded 1 m disc"


def test_destination_is_reannounced_every_announce_every_ticks():
    known = two_frontiers()
    t = robot(0, announce_every=20, deadlock_ticks=0)
    goal = t.act(observe(known)).goal
    sent = [tick for tick in range(1, 61)
            if t.act(observe(known, tick=tick, nav=NavStatus(goal=goal, state="moving"))).messages]
    assert sent == [20, 40, 60]


def test_destination_message_rejects_garbage():
    with pytest.raises(MessageError):
        decode(encode(Destination(sender=3, x=float("nan"), y=0.0)))


def corridor() -> Map:
    """60 x 24 m, a 3 m wide corridor (y 10-13 m) from x = 2 to 58 m: seen from its middle it has two
    frontiers, one each way."""
    solid = np.ones((48, 120), dtype=bool)
    solid[20:26, 4:116] = False
    return Map(solid=solid, material=solid.astype(np.uint8), materials=("air", "concrete"))


def goals_at_tick_5(comm: dict) -> list:
    seen = {}

    def watch(view):
        if view.tick == 5:
            seen["goals"] = [a.goal for a in view.actions]

    spec = {"seed": 0, "robots": {"count": 2}, "algorithm": {"name": "tnf"}, "stop": {"max_ticks": 6}, **comm}
    Simulation(spec, truth=corridor(), start_poses=np.array([[30.0, 10.9, 0.0], [30.0, 12.1, 0.0]]),
               observers=(watch,)).run()
    return seen["goals"]


def test_second_robot_avoids_the_first_ones_destination_with_global_comm():
    g0, g1 = goals_at_tick_5({"radio": {"model": "global"}})
    assert (g0[0] - 30.0) * (g1[0] - 30.0) < 0, f"the robots head opposite ways: {g0}, {g1}"
    n0, n1 = goals_at_tick_5({"radio": {"model": "los", "max_range_m": 0.001}, "comm": {"map_sharing": "off"}})
    assert (n0[0] - 30.0) * (n1[0] - 30.0) > 0, "without comm both chose the same frontier (the control)"


@pytest.mark.parametrize("bad", [{"alpha": 0.5}, {"beta": -1}, {"announce_every": 0},
                                 {"penalty_radius_m": float("inf")}, {"min_frontier_cells": 0}])
def test_bad_parameters_are_rejected(bad):
    with pytest.raises(InvalidInput):
        TNFParams(**bad)


def test_a_destination_read_by_many_robots_gives_each_the_cell_it_would_compute():
    """One announcement object reaches every robot in range (in-process); its cell is computed once and
    reused, clamped onto the map, and recomputed for a map of another shape."""
    from algorithms.tnf import _destination_cell
    from swarm.api import cell_of

    for x, y in [(3.2, 7.9), (-4.0, 2.0), (500.0, 500.0), (0.0, 0.24)]:
        msg = Destination(sender=1, x=x, y=y)
        for h, w in [(40, 60), (40, 60), (20, 10), (40, 60)]:
            r, c = cell_of(x, y)
            assert _destination_cell(msg, h, w) == (min(max(r, 0), h - 1), min(max(c, 0), w - 1))
        assert decode(encode(msg)) == msg, "the memo is not part of the message"
