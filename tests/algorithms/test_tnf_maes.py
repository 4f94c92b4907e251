"""TNF with ``variant = "maes"``: MAES's utility with its three bugs (the unclamped ``w`` of the distance
term, the information term on its arbitrary scale, the coordination penalty's sign and its relative bearing
used as global), on hand-made maps where each bug decides; the default variant unchanged beside it; a
whole run deterministic and through the plugin checker. MAES's source: ``TnfExplorationAlgorithm.cs``
(DEIS-Tools/MAES), lines cited in :mod:`algorithms.tnf`."""

from __future__ import annotations

import math

import numpy as np
import pytest

from algorithms.tnf import TNF, Destination, TNFParams
from algorithms.tnf_utility import MAES_CELL_WEIGHT, frontiers, maes_distance_term, score_frontiers
from maps import InvalidInput
from swarm.api import FREE, SOLID, UNSEEN, NavStatus, Neighbour, Observation, Pose, RobotInfo, cell_centre
from swarm.sim.loop import Simulation
from swarm.testing import check_explorer

from .test_tnf import corridor

MAES_MOTION = {"max_speed": 3.0, "max_turn_rate": 4.0, "max_accel": 60.0, "max_turn_accel": 120.0, "substeps": 8}

G0 = 5.0 * math.exp(-12.5)      # G(0), a known cell's share of MAES's Gaussian
NONE = np.zeros((0, 2), dtype=np.int64)


# ------------------------------------------------------------------------------------ fixtures ----
def two_frontiers() -> np.ndarray:
    """tests/algorithms/test_tnf.py's map: 20 x 40 cells, frontier A = column 4, rows 1-18 (18 cells, far
    west), frontier B = column 35, rows 8-11 (4 cells, east)."""
    k = np.full((20, 40), FREE, dtype=np.uint8)
    k[0, :] = k[-1, :] = k[:, 0] = k[:, -1] = SOLID
    k[1:19, 1:4] = UNSEEN
    k[1:19, 36:39] = SOLID
    k[8:12, 36:39] = UNSEEN
    return k


def long_wall_and_pocket() -> np.ndarray:
    """40 x 40 cells: frontier A = column 4, rows 1-38 (38 cells along the west wall), frontier B = the
    2-cell mouth (rows 19-20, column 35) of an unseen pocket in the east wall."""
    k = np.full((40, 40), FREE, dtype=np.uint8)
    k[0, :] = k[-1, :] = k[:, 0] = k[:, -1] = SOLID
    k[1:39, 1:4] = UNSEEN
    k[1:39, 36:39] = SOLID
    k[19:21, 36:39] = UNSEEN
    return k


def mirror() -> np.ndarray:
    """20 x 40 cells, symmetric about x = 10 m: frontier W = column 4, E = column 35, rows 1-18 each."""
    k = np.full((20, 40), FREE, dtype=np.uint8)
    k[0, :] = k[-1, :] = k[:, 0] = k[:, -1] = SOLID
    k[1:19, 1:4] = UNSEEN
    k[1:19, 36:39] = UNSEEN
    return k


def score(known, start, variant, *, beta=10.0, position_m=None, sensed_m=None):
    out = score_frontiers(known, start, NONE, alpha=1.0, beta=beta, robot_radius_m=0.3, penalty_radius_m=7.0,
                          reach=2, variant=variant, position_m=position_m, sensed_m=sensed_m)
    return out


def by_column(out, col):
    """The candidate whose target lies left (col < 20) or right of the middle."""
    return next(s for s in out if (s.target[1] < 20) == (col < 20))


def centres(rows, col):
    return [cell_centre(r, col) for r in rows]


def maes_w(point, cells, all_cells):
    """MAES's w by hand: sqrt(sum_c |p - c| / Dmax) over 1 m tiles; each 0.5 m cell counts for half."""
    d_max = max(math.dist(point, c) for c in all_cells)
    return math.sqrt(MAES_CELL_WEIGHT * sum(math.dist(point, c) / d_max for c in cells))


# ------------------------------------------------------------------- bug 1: the unclamped w ----
def test_sign_flip_drops_the_rich_far_frontier_for_the_small_near_one():
    known, start = two_frontiers(), (10, 25)
    swarm = score(known, start, "swarm")
    maes = score(known, start, "maes")
    assert swarm[0].size == 18, "swarm: the information-rich frontier wins"
    a, b = by_column(maes, 5), by_column(maes, 34)
    a_cells, b_cells = centres(range(1, 19), 4), centres(range(8, 12), 35)
    here = cell_centre(*start)
    w_a, w_b = maes_w(here, a_cells, a_cells + b_cells), maes_w(here, b_cells, a_cells + b_cells)
    assert w_a == pytest.approx(2.9190, abs=1e-4) and w_b == pytest.approx(0.9391, abs=1e-4)
    assert a.distance == pytest.approx((1 - w_a) ** 9, rel=1e-9) == pytest.approx(-352.88, abs=0.01)
    assert b.distance == pytest.approx((1 - w_b) ** 9, rel=1e-9)
    assert maes[0].size == 4, "maes: D(A) = (1 - 2.92)^9 = -353 buries A's information"
    # The parity of beta - 1 flips the sign: beta = 9 makes the same frontier +184 and the first choice.
    maes9 = score(known, start, "maes", beta=9.0)
    d9 = by_column(maes9, 5).distance
    assert d9 == pytest.approx((1 - w_a) ** 8, rel=1e-9) and d9 > 100
    assert maes9[0].size == 18


def test_sign_flip_gives_up_a_near_long_frontier_for_a_far_two_cell_pocket():
    known, start = long_wall_and_pocket(), (20, 10)     # 3 m from the west wall, 12.5 m from the pocket
    swarm = score(known, start, "swarm")
    maes = score(known, start, "maes")
    assert [s.size for s in swarm] == [38, 2]
    assert [s.size for s in maes] == [2, 38], "MAES heads for the far pocket"
    assert maes[1].distance < -400 and maes[1].gain > 100, "A: I = 140, D = (1 - w)^9 = -480"
    # Clamping w to [0, 1] would give A D = 0 and the first place back.
    assert maes[1].gain + maes_distance_term(np.array([1.0]), 1.0, 10.0)[0] > maes[0].utility


# ----------------------------------------------------------- bug 2: the information term's scale ----
def test_information_is_the_gaussian_sum_divided_by_the_number_of_frontiers():
    known = two_frontiers()
    # A third frontier nobody can reach: an unseen cell in a closed 5 x 5 box (rows 13-17, columns 20-24).
    known[13:18, 20:25] = SOLID
    known[14:17, 21:24] = FREE
    known[15, 22] = UNSEEN
    fr = frontiers(known)
    assert fr.count == 3
    out = score(known, (10, 25), "maes")
    assert len(out) == 2, "the boxed frontier is no candidate, but MAES counts it in F (lines 109, 296)"
    a, b = by_column(out, 5), by_column(out, 34)
    # A: 52 unseen neighbour slots (5 each), 18 known cells and 92 known neighbours; B: 10 slots, 4 + 22.
    assert a.raw_gain == pytest.approx(52 * 5.0 + 110 * G0)
    assert a.gain == pytest.approx(0.5 * (52 * 5.0 + 110 * G0) / 3, rel=1e-12) == pytest.approx(43.33, abs=0.01)
    assert b.gain == pytest.approx(0.5 * (10 * 5.0 + 26 * G0) / 3, rel=1e-12)
    swarm = score(known, (10, 25), "swarm")
    assert max(s.gain for s in swarm) == 1.0, "swarm: I in (0, 1]"


def test_on_maes_scale_information_outweighs_a_negative_distance_term():
    known, start = long_wall_and_pocket(), (20, 6)      # 1 m from the west wall
    out = score(known, start, "maes")
    a, b = by_column(out, 5), by_column(out, 34)
    # 36 inner cells with 3 unseen neighbours and 2 end cells with 2: 112 slots; 38 x 9 - 112 = 230 known.
    assert a.gain == pytest.approx(0.5 * (112 * 5.0 + 230 * G0) / 2, rel=1e-12)   # 140
    assert -60 < a.distance < -40
    assert out[0] is a, "I(A) = 140 outweighs D(A) = -49"
    # On swarm's (0, 1] scale the same D would sink A below the 2-cell pocket.
    assert 1.0 + a.distance < b.gain / a.gain + b.distance


# --------------------------------------------------- bug 3: the coordination penalty's sign and frame ----
HERE = (10.0, 5.0)      # the middle of mirror(): both frontiers look the same from here
W_CELLS, E_CELLS = centres(range(1, 19), 4), centres(range(1, 19), 35)


def observe(heading, neighbours):
    known = mirror()
    known.flags.writeable = False
    return Observation(tick=1, robot_id=0, pose=Pose(HERE[0], HERE[1], heading), known=known,
                       neighbours=tuple(neighbours))


def robot(variant, n=2):
    t = TNF()
    t.reset(RobotInfo(id=0, n_robots=n, map_shape=(20, 40)), TNFParams(variant=variant), np.random.default_rng(0))
    return t


def test_coordination_penalises_frontiers_far_from_where_maes_misplaces_the_neighbour():
    # Robot 1 is 4 m west of robot 0, which faces west: its bearing is 0, which MAES reads as global east
    # and puts robot 1 at (14, 5), 4 m east; C grows with the distance from there, so W is penalised.
    west = Neighbour(id=1, distance=4.0, bearing=0.0, x=6.0, y=5.0)
    t = robot("maes")
    goal = t.act(observe(math.pi, [west])).goal
    assert goal[0] > 10.0, "MAES: heads east, towards where it wrongly thinks robot 1 is"
    choice = t.last_choice
    placed = (14.0, 5.0)
    c_e = maes_w(placed, E_CELLS, W_CELLS + E_CELLS)
    c_w = maes_w(placed, W_CELLS, W_CELLS + E_CELLS)
    assert choice.penalty == pytest.approx(c_e, rel=1e-9) and c_e < c_w
    assert choice.utility == pytest.approx(choice.gain + choice.distance - c_e, rel=1e-12)
    # The same neighbour, seen while facing east (bearing -pi): MAES now places it right, 4 m west, and
    # the robot heads west -- towards it. The choice depends on the heading only through the bug.
    west_again = Neighbour(id=1, distance=4.0, bearing=-math.pi, x=6.0, y=5.0)
    t = robot("maes")
    assert t.act(observe(0.0, [west_again])).goal[0] < 10.0
    assert t.last_choice.penalty == pytest.approx(maes_w((6.0, 5.0), W_CELLS, W_CELLS + E_CELLS), rel=1e-9)
    # No sensed robot: no penalty (line 146).
    t = robot("maes")
    t.act(observe(math.pi, []))
    assert t.last_choice.penalty == 0.0
    # swarm ignores sensed robots (its penalty comes from announced destinations): no penalty here.
    t = robot("swarm")
    t.act(observe(math.pi, [west]))
    assert t.last_choice.penalty == 0.0


def test_coordination_sums_over_every_sensed_robot():
    sensed = np.array([[14.0, 5.0], [10.0, 8.0]])
    out = score(mirror(), (10, 20), "maes", position_m=HERE, sensed_m=sensed)
    for s in out:
        cells = W_CELLS if s.target[1] < 20 else E_CELLS
        expected = sum(maes_w(tuple(p), cells, W_CELLS + E_CELLS) for p in sensed.tolist())
        assert s.penalty == pytest.approx(expected, rel=1e-9)


# -------------------------------------------------------------------------------- messages ----
def test_maes_sends_no_destinations_and_does_not_yield():
    known = two_frontiers()
    known.flags.writeable = False
    x, y = cell_centre(10, 25)
    t = TNF()
    t.reset(RobotInfo(id=1, n_robots=2, map_shape=(20, 40)), TNFParams(variant="maes"), np.random.default_rng(0))
    first = t.act(Observation(tick=1, robot_id=1, pose=Pose(x, y, 0.0), known=known))  # 0: MAES's comm tick
    assert first.messages == (), "MAES's plain TNF never reads destinations: nothing to announce"
    # A lower-id robot announcing this very destination changes nothing (swarm would yield).
    heard = Destination(sender=0, x=first.goal[0], y=first.goal[1])
    later = t.act(Observation(tick=2, robot_id=1, pose=Pose(x, y, 0.0), known=known, inbox=(heard,),
                              nav=NavStatus(goal=first.goal, state="moving")))
    assert later.goal == first.goal and later.messages == ()


# ------------------------------------------------ row 11: when MAES's TNF decides, when it stops ----
START = cell_centre(10, 25)
MATE = Neighbour(id=1, distance=2.0, bearing=0.0, x=START[0] + 2.0, y=START[1])


IDLE = NavStatus()


def at(known, tick, nav=IDLE, neighbours=(), collided=False, xy=START):
    known = known.copy()
    known.flags.writeable = False
    return Observation(tick=tick, robot_id=0, pose=Pose(xy[0], xy[1], math.pi), known=known, nav=nav,
                       neighbours=tuple(neighbours), collided=collided)


def decisions(t: TNF) -> list:
    """Count ``t``'s decisions (each one scores the frontiers afresh)."""
    calls = []
    inner = t._decide
    t._decide = lambda obs: (calls.append(obs.tick), inner(obs))[1]
    return calls


def test_maes_does_not_decide_again_when_its_destination_is_seen_but_at_its_paths_end():
    t, known = robot("maes", n=1), two_frontiers()
    first = t.act(at(known, 1)).goal
    assert first is not None
    seen = known.copy()
    seen[seen == UNSEEN] = FREE                       # a merged map revealed everything: nothing left to see
    moving = NavStatus(goal=first, state="moving")
    calls = decisions(t)
    for tick in range(2, 19):
        assert t.act(at(seen, tick, moving)).goal == first, "MAES follows its path to the end"
    assert calls == []
    t.act(at(known, 19, NavStatus(goal=first, state="reached")))
    assert calls == [19], "at the end of its path it decides"
    # swarm's TNF decides as soon as its destination is seen (the control)
    s = robot("swarm", n=1)
    s_first = s.act(at(known, 1)).goal
    s_calls = decisions(s)
    s.act(at(seen, 2, NavStatus(goal=s_first, state="moving")))
    assert s_calls == [2]


def test_maes_decides_again_after_a_collision():
    t, known = robot("maes", n=1), two_frontiers()
    first = t.act(at(known, 1)).goal
    calls = decisions(t)
    moving = NavStatus(goal=first, state="moving")
    backing = t.act(at(known, 2, moving, collided=True))
    assert backing.velocity is not None and backing.velocity[0] < 0, "it backs off (MAES: 0.1 m, line 242)"
    tick, action = 3, backing
    while action.velocity is not None:                  # the back-off, then the random step (246-265)
        action = t.act(at(known, tick, moving))
        tick += 1
    step = action.goal
    assert step != first and math.dist(step, START) < 1.5
    assert calls == []
    t.act(at(known, tick, NavStatus(goal=step, state="reached")))
    assert calls == [tick], "the random step done, it picks a frontier again"


def test_maes_stops_every_20_ticks_when_it_senses_a_neighbour():
    t, known = robot("maes"), two_frontiers()
    assert t.act(at(known, 0, neighbours=[MATE])).velocity == (0.0, 0.0), "tick 0 is a communication tick"
    goal = t.act(at(known, 1, neighbours=[MATE])).goal
    moving = NavStatus(goal=goal, state="moving")
    stops = [tick for tick in range(2, 61)
             if t.act(at(known, tick, moving, neighbours=[MATE])).velocity == (0.0, 0.0)]
    assert stops == [20, 40, 60]
    # Alone it carries on through the communication ticks (still its goal, no stop).
    alone = robot("maes")
    goal = alone.act(at(known, 1)).goal
    for tick in (20, 40):
        a = alone.act(at(known, tick, NavStatus(goal=goal, state="moving")))
        assert a.goal == goal and a.velocity is None
    # swarm's TNF never stops to communicate (the control).
    s = robot("swarm")
    goal = s.act(at(known, 1, neighbours=[MATE])).goal
    assert all(s.act(at(known, tick, NavStatus(goal=goal, state="moving"), neighbours=[MATE])).velocity is None
               for tick in (20, 40))


def test_maes_communication_tick_does_nothing_else():
    t, known = robot("maes", n=1), two_frontiers()
    first = t.act(at(known, 1)).goal
    calls = decisions(t)
    reached = NavStatus(goal=first, state="reached")
    assert t.act(at(known, 20, reached)).goal == first and calls == [], "no decision on tick 20 (line 181)"
    assert t.act(at(known, 40, NavStatus(goal=first, state="moving"), collided=True)).velocity is None, \
        "a collision reported on a communication tick is not handled"
    t.act(at(known, 21, reached))
    assert calls == [21]


def test_maes_stop_shows_in_a_run():
    """Under MAES's motion preset (3 m/s, 60 m/s^2) the tick's (0, 0) brings a cruising robot to rest."""
    poses: dict[int, np.ndarray] = {}

    def watch(view):
        poses[view.tick] = view.poses[:, :2].copy()

    spec = {"seed": 0, "robots": {"count": 2}, "algorithm": {"name": "tnf", "params": {"variant": "maes"}},
            "motion": MAES_MOTION, "stop": {"max_ticks": 43}}
    Simulation(spec, truth=corridor(), start_poses=np.array([[30.0, 10.9, 0.0], [30.0, 12.1, 0.0]]),
               observers=(watch,)).run()

    def moved(tick: int) -> float:   # during tick ``tick``: the command of view ``tick`` moves it to ``tick + 1``
        return float(np.linalg.norm(poses[tick + 1] - poses[tick], axis=1).max())

    assert moved(39) > 0.2, "cruising at up to 3 m/s before the communication tick"
    assert moved(40) < 0.4 * moved(39), "braking to rest for the communication tick (0.3 m a tick at 3 m/s)"
    assert moved(41) > moved(40), "and on its way again"


# ------------------------------------------------------------------------------ parameters ----
def test_variant_is_validated():
    assert TNFParams().variant == "swarm"
    with pytest.raises(InvalidInput):
        TNFParams(variant="MAES")
    with pytest.raises(InvalidInput):
        TNFParams(variant="maes", beta=9.5)     # MAES's alpha and beta are int
    TNFParams(variant="swarm", beta=9.5)
    TNFParams(variant="maes", alpha=8, beta=8.0)


# ---------------------------------------------------------------------------------- whole runs ----
def test_maes_run_is_deterministic_and_explores():
    spec = {"seed": 4, "map": {"kind": "cave", "size": 30}, "robots": {"count": 2},
            "algorithm": {"name": "tnf", "params": {"variant": "maes"}}, "stop": {"max_ticks": 300}}
    one, two = Simulation(spec).run(), Simulation(spec).run()
    assert one.deterministic_view() == two.deterministic_view()
    assert one.summary["explored"] > 0.3


def test_maes_variant_passes_the_explorer_checker():
    report = check_explorer("tnf", params={"variant": "maes"})
    messages = next(r.detail for r in report.results if r.check == "messages")
    assert messages.startswith("sends no messages of its own"), messages
