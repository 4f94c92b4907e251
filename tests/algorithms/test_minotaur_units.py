"""Minotaur's pieces on their own: parameters, messages, the spin sweep, wall/edge candidates, rooms
bounded by doorways, and the explorer's contract (deterministic, documented debug, spin split)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from algorithms.minotaur import Minotaur, MinotaurParams, rooms, walls
from algorithms.minotaur.doorways import Doorway, valid_wire
from algorithms.minotaur.messages import (
    AuctionResult,
    Bid,
    DoorwayFound,
    DoorwayList,
    Tried,
    Heading,
)
from swarm import grid
from swarm.api import FREE, SOLID, UNSEEN
from swarm.base.errors import InvalidInput
from swarm.comm.messages import decode, encode
from swarm.sim.loop import Simulation
from tests.algorithms.test_minotaur_doorways import (
    blank,
    wall_with_door,
)


# ------------------------------------------------------------------------------------- parameters ----
@pytest.mark.parametrize("bad", [
    {"max_door_width_m": 0.1}, {"min_door_width_m": 3.5}, {"spin": "left"}, {"auction_ticks": 1},
    {"inspect_doorways": 1}, {"follow_margin_m": -1.0}, {"scan_every": 0}, {"reach_m": math.nan},
])
def test_bad_parameters_are_refused(bad: dict) -> None:
    with pytest.raises(InvalidInput):
        MinotaurParams(**bad)


def test_unknown_parameter_is_an_error_naming_it() -> None:
    with pytest.raises(InvalidInput, match="door_widht"):
        Simulation({"algorithm": {"name": "minotaur", "params": {"door_widht": 2.0}}})


# --------------------------------------------------------------------------------------- messages ----
WIRE = (16.5, 6.0, 1, 2.0, 1.0, 1, 0)


@pytest.mark.parametrize("msg", [
    DoorwayList(1, (WIRE, (3.0, 4.0, 0, 2.0, 0.5, 3, 1)), (2.0, 3.0), WIRE),
    DoorwayList(1, (), (math.inf, 0.0), ()),
    Heading(2, (1.5, 2.5), ()),
    DoorwayFound(0, 7, WIRE, -1),
    Bid(3, 0, 7, 12.5),
    AuctionResult(0, 7, WIRE, -1, (3, 1)),
    Tried(4, ((10, 23), (13, 23))),
    Tried(4, ()),
])
def test_messages_survive_the_wire(msg: object) -> None:
    assert decode(encode(msg)) == msg


@pytest.mark.parametrize("wire,ok", [
    (WIRE, True), ((16.5, 6.0, 2, 2.0, 1.0, 1, 0), False), ((math.nan, 6.0, 1, 2.0, 1.0, 1, 0), False),
    ((16.5, 6.0, 1, -2.0, 1.0, 1, 0), False), ((16.5, 6.0, 1), False), ("door", False), ((True,) * 7, False),
])
def test_received_doorways_are_validated(wire: object, ok: bool) -> None:
    assert valid_wire(wire) is ok


# ------------------------------------------------------------------------------------ spin sweep ----
def test_spin_sweep_starts_at_the_robot_side_and_turns_to_the_front() -> None:
    at, east = (10.0, 10.0), (1.0, 0.0)
    # right (south), front (east), left (north), behind (west) of a robot travelling east
    rows, cols = np.array([5, 10, 15, 10]), np.array([10, 15, 10, 5])
    ccw = walls.spin_keys(rows - 0.5, cols - 0.5, at, east, 1)
    cw = walls.spin_keys(rows - 0.5, cols - 0.5, at, east, -1)
    assert list(np.argsort(ccw)) == [0, 1, 2, 3]        # counter-clockwise: wall on the right
    assert list(np.argsort(cw)) == [2, 1, 0, 3]         # clockwise: wall on the left


def partially_seen_room() -> np.ndarray:
    """A 30 x 20 m room known only within 7 m of a robot at (10, 5): 4 m from its south wall."""
    solid = blank(30, 20)
    yy, xx = np.mgrid[0:40, 0:60]
    seen = (xx + 0.5 - 20) ** 2 + (yy + 0.5 - 10) ** 2 <= 14 ** 2
    known = np.where(solid, SOLID, FREE).astype(np.uint8)
    known[~seen] = UNSEEN
    return known


def test_candidates_are_wall_ends_and_edges() -> None:
    known = partially_seen_room()
    rows, cols, nr, nc, ar, ac, kind = walls.candidates(known)
    ends = kind == 0
    assert ends.any() and (~ends).any()
    assert (known[rows[ends], cols[ends]] == SOLID).all() and (known[ar[ends], ac[ends]] == UNSEEN).all()
    assert (known[rows[~ends], cols[~ends]] == FREE).all() and (known[ar[~ends], ac[~ends]] == UNSEEN).all()
    # every wall end continues into the unknown along the wall and its normal points into free space
    assert (known[rows[ends] + nr[ends], cols[ends] + nc[ends]] == FREE).all()


def test_counter_clockwise_follows_the_right_hand_wall_ahead() -> None:
    known = partially_seen_room()
    space = grid.configuration_space(known)
    at = (10, 20)
    dist = grid.distance_field(space, [at])
    ccw = walls.choose(known, space, dist, at, (1.0, 0.0), 1, 17, 10, 2, [], None)
    cw = walls.choose(known, space, dist, at, (1.0, 0.0), -1, 17, 10, 2, [], None)
    assert ccw is not None and cw is not None
    assert ccw.kind == "wall" and ccw.cell[1] > at[1]                 # ahead, along the south wall
    assert ccw.cell[0] == pytest.approx(1 + 10, abs=1)               # 5 m (follow distance) off the wall face
    assert cw.cell[0] > at[0]                                        # clockwise goes the other way round


# ----------------------------------------------------------------------------------------- rooms ----
def test_a_doorway_closes_the_room() -> None:
    m = wall_with_door()
    known = np.where(m.solid, SOLID, FREE).astype(np.uint8)
    door = Doorway(12.5, 6.0, 1, 2.0, 1.0)
    space = grid.configuration_space(known)
    cut = rooms.cut_doors(space, [door])
    left, right = (12, 10), (12, 40)
    assert np.isfinite(grid.distance_field(space, [left])[right])
    assert not np.isfinite(grid.distance_field(cut, [left])[right])
    assert math.isfinite(rooms.door_distance(cut, left, door, -1))
    assert rooms.door_distance(cut, left, door, 1) == math.inf        # the far side: only through the door


def test_choose_door_skips_doorways_with_nothing_behind() -> None:
    m = wall_with_door()
    known = np.where(m.solid, SOLID, FREE).astype(np.uint8)
    space = grid.configuration_space(known)
    door = Doorway(12.5, 6.0, 1, 2.0, 1.0)
    views = rooms.view_cells(known, space, 2)
    assert rooms.choose_door(space, rooms.cut_doors(space, [door]), (12, 10), [door], views) is None
    assert door.resolved                                              # everything behind it is known
    known[8:16, 34:40] = UNSEEN                                       # something unseen in the far room
    views = rooms.view_cells(known, grid.configuration_space(known), 2)
    door.resolved = False
    choice = rooms.choose_door(space, rooms.cut_doors(space, [door]), (12, 10), [door], views)
    assert choice is not None and choice[0] is door and choice[1] == -1 and choice[2]


# -------------------------------------------------------------------------------------- explorer ----
def small_run(robots: int = 2, params: dict | None = None, ticks: int = 300):
    debug: list[list[dict]] = []

    def watch(view) -> None:
        debug.append([dict(a.debug) for a in view.actions])

    spec = {"robots": {"count": robots}, "algorithm": {"name": "minotaur", "params": params or {}}, "seed": 5,
            "stop": {"max_ticks": ticks}}
    poses = np.array([[4.0 + i, 6.0, 0.0] for i in range(robots)])
    result = Simulation(spec, truth=wall_with_door(), observers=[watch], start_poses=poses).run()
    return result, debug


def test_same_spec_same_run() -> None:
    a, _ = small_run()
    b, _ = small_run()
    assert a.summary["ticks"] == b.summary["ticks"] and a.summary["final_poses"] == b.summary["final_poses"]


def test_debug_reports_state_target_and_doorways() -> None:
    _, debug = small_run(robots=1)
    states = {d[0]["state"] for d in debug}
    assert states <= {"start", "room", "door", "greedy", "done"} and "room" in states
    last = debug[-1][0]
    assert last["spin"] in ("ccw", "cw") and isinstance(last["doorways"], list)
    assert any(d[0]["target"] is not None for d in debug)


def test_robots_in_one_room_split_their_spin() -> None:
    _, debug = small_run(robots=2)
    assert {debug[1][0]["spin"], debug[1][1]["spin"]} == {"ccw", "cw"}          # Alg. 2
    _, debug = small_run(robots=2, params={"spin": "ccw"})
    assert {debug[1][0]["spin"], debug[1][1]["spin"]} == {"ccw"}                # Alg. 1 for everyone


def test_explorer_class_contract() -> None:
    assert Minotaur.name == "minotaur" and Minotaur.Params is MinotaurParams


BAD_MESSAGES = [
    DoorwayList(0, ([1, 2],), (1.0, 2.0), ()), DoorwayList(0, ((1.0,) * 7, ("a",) * 7), (math.nan, 1.0), ()),
    DoorwayList(0, "x", (1, 2), ()), Heading(0, [1, 2], ()), DoorwayFound(0, [1], WIRE, -1),
    Bid(0, 1, [3], 2.0), Bid(0, 1, 3, "far"), AuctionResult(0, 1, WIRE, 1, 5), DoorwayFound(0, 1, WIRE, 0),
    Tried(0, ((1, 2.5),)), Tried(0, ((1, 2, 3),)),
]


def test_malformed_messages_are_ignored_not_fatal() -> None:
    """Messages come from other robots: a bad one must neither crash the receiver nor enter its book."""
    from swarm.api import Observation, Pose, RobotInfo

    agent = Minotaur()
    agent.reset(RobotInfo(id=1, n_robots=3, map_shape=(40, 40)), MinotaurParams(), np.random.default_rng(0))
    known = np.zeros((40, 40), np.uint8)
    known[5:35, 5:35] = FREE
    for tick, msg in enumerate(BAD_MESSAGES):
        agent.act(Observation(tick=tick, robot_id=1, pose=Pose(10.0, 10.0, 0.0), known=known, inbox=(msg,)))
    assert len(agent.book) == 0 and not agent.auctions.bid_in


@pytest.mark.parametrize("msg", BAD_MESSAGES[4:])   # (a list for a pair comes back as a tuple)
def test_malformed_messages_are_refused_by_the_codec(msg: object) -> None:
    from swarm.comm.messages import MessageError

    with pytest.raises(MessageError):
        decode(encode(msg))


# ------------------------------------------------------------------------------------------ peers ----
def test_peers_merge_changed_doorways_and_remember_targets_and_claims() -> None:
    from algorithms.minotaur.doorways import DoorwayBook
    from algorithms.minotaur.peers import Peers

    peers, book = Peers(), DoorwayBook()
    other = (3.0, 4.0, 0, 2.0, 0.5, 0, 0)
    peers.heard(10, DoorwayList(2, (WIRE, other), (5.0, 5.0), ()), book)
    assert len(book) == 2 and not book.doors[0].explored
    peers.heard(20, DoorwayList(2, (WIRE[:5] + (3, 1), other), (6.0, 5.0), WIRE), book)   # now explored
    assert len(book) == 2 and book.doors[0].explored
    assert [d.x for d in peers.claimed(30, 100)] == [WIRE[0]] and peers.claimed(200, 100) == []
    near = peers.targets_mask((40, 40), 25, 30, 1.0)
    assert near is not None and near[10, 12] and not near[10, 20]          # 1 m around (6, 5)
    assert peers.targets_mask((40, 40), 100, 30, 1.0) is None               # too old
    peers.heard(40, Heading(2, (math.nan, math.nan), ()), book)            # stopped, no doorway
    assert peers.targets_mask((40, 40), 41, 30, 1.0) is None and peers.claimed(41, 100) == []


def test_targets_mask_is_every_cell_within_the_radius_of_a_fresh_target_clipped_to_the_map() -> None:
    """The compiled stamp against the definition, cell by cell, with targets on, near and off the edges."""
    from algorithms.minotaur.peers import Peers

    rng = np.random.default_rng(3)
    for _ in range(50):
        shape = (int(rng.integers(4, 40)), int(rng.integers(4, 40)))
        peers = Peers()
        xy = rng.uniform(-3.0, 23.0, size=(int(rng.integers(1, 12)), 2))
        for i, (x, y) in enumerate(xy):
            peers.targets[i] = (float(x), float(y), 5)
        got = peers.targets_mask(shape, 6, 10, 1.5)
        k = math.ceil(1.5 / 0.5)
        rr, cc = np.mgrid[0:shape[0], 0:shape[1]]
        want = np.zeros(shape, bool)
        for x, y in xy:
            r, c = math.floor(y / 0.5), math.floor(x / 0.5)
            want |= (rr - r) ** 2 + (cc - c) ** 2 <= k * k
        assert got is not None and np.array_equal(got, want)


def test_same_run_over_zenoh() -> None:
    """Minotaur's messages and debug survive the wire: the zenoh transport gives the in-process result."""
    spec = {"map": {"kind": "building", "size": 50}, "robots": {"count": 3}, "algorithm": {"name": "minotaur"},
            "seed": 2, "stop": {"max_ticks": 200}}
    a = Simulation(spec).run().summary
    b = Simulation({**spec, "transport": "zenoh"}).run().summary
    assert a["final_poses"] == b["final_poses"] and a["messages"]["sent"] == b["messages"]["sent"]
    assert b["messages"]["malformed"] == 0 and b["acts"]["malformed"] == [0, 0, 0]


def test_the_room_step_on_windows_is_the_whole_maps_room_step() -> None:
    """Minotaur's room step decided around the robot (issue 47) picks what the whole-map rasters pick:
    buildings seen in patches, doorways cut, cells excluded, other robots' targets avoided; windows that
    cannot decide say so instead of guessing."""
    from maps import generate
    from swarm.api import Observation, Pose, RobotInfo, cell_centre

    from algorithms.minotaur import explorer as mex
    from algorithms.minotaur.cells import mask
    from algorithms.minotaur.doorways import Doorway

    decided = found_near = 0
    for seed in range(6):
        truth = generate("building", 100, seed)
        rng = np.random.default_rng(seed)
        known = np.where(truth.solid, SOLID, FREE).astype(np.uint8)
        known[rng.random(known.shape) < 0.02] = UNSEEN
        for _ in range(4):
            r, c = rng.integers(0, known.shape[0] - 40, size=2)
            known[r:r + int(rng.integers(10, 40)), c:c + int(rng.integers(10, 40))] = UNSEEN
        free = np.argwhere(known == FREE)
        for trial in range(8):
            agent = Minotaur()
            agent.reset(RobotInfo(id=1, n_robots=4, map_shape=known.shape), MinotaurParams(),
                        np.random.default_rng(trial))
            for k in range(int(rng.integers(0, 6))):        # doorways, cut out of the room
                x, y = cell_centre(*free[rng.integers(len(free))])
                agent.book.add(Doorway(x, y, int(rng.integers(0, 2)), 2.0, 0.5))
            for k in range(int(rng.integers(0, 20))):
                agent.excluded[tuple(int(v) for v in free[rng.integers(len(free))])] = 10**6
            for k in range(int(rng.integers(0, 8))):        # others' fresh targets
                x, y = cell_centre(*free[rng.integers(len(free))])
                agent.peers.targets[10 + k] = (x, y, 0)
            x, y = cell_centre(*free[rng.integers(len(free))])
            obs = Observation(tick=1, robot_id=1, pose=Pose(x, y, 0.0), known=known)
            got = agent._room_target_nearby(obs)
            space = grid.configuration_space(known, radius_m=agent.robot.radius)
            cut = rooms.cut_doors(space, agent.book)
            views = rooms.view_cells(known, space, mex.VIEW_REACH)
            blocked = mask(agent.excluded, known.shape)
            if blocked is not None:
                views &= ~blocked
            avoid = agent.peers.targets_mask(known.shape, 1, mex.TARGET_FRESH_TICKS, mex.TARGET_AVOID_M)
            start = rooms.snap(cut, (x, y))
            want = None
            if start is not None:
                if avoid is not None:
                    want = rooms.nearest_in_room(cut, start, views & ~avoid)
                if want is None:
                    want = rooms.nearest_in_room(cut, start, views)
            if got is not None:
                decided += 1
                assert got == ((want[0] if want is not None else None),), (seed, trial)
                found_near += got[0] is not None
    assert decided > 20 and found_near > 10, "most room steps must be decided near the robot"
