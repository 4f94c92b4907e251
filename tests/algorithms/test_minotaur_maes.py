"""Minotaur's ``variant = "maes"`` (issue 33): MAES drives to a candidate doorway and checks it there
(MinotaurAlgorithm.cs ``DoorwayDetection`` / ``AttemptAddDoorway``), covers corners, and takes the
nearest doorway before Greed. Each case is one where the default variant does something else, so each
test fails if the variant behaved like the default."""

from __future__ import annotations

import math

import numpy as np
import pytest

from algorithms.minotaur import maes, rooms
from algorithms.minotaur.doorways import Doorway
from algorithms.minotaur.explorer import Minotaur
from algorithms.minotaur.params import MinotaurParams
from swarm.api import FREE, SOLID, UNSEEN, InvalidInput, NavStatus, Observation, Pose, RobotInfo
from swarm.sim.loop import Simulation
from swarm.testing import check_explorer

from .test_minotaur_doorways import as_map, blank, gap, hallway, known_of, wall, wall_with_door


def agent(variant: str, shape: tuple[int, int], **params: object) -> Minotaur:
    a = Minotaur()
    a.reset(RobotInfo(id=0, n_robots=1, map_shape=shape, lidar_range=7.0),
            MinotaurParams(variant=variant, **params), np.random.default_rng(0))
    return a


def obs(tick: int, known: np.ndarray, x: float, y: float, theta: float = 0.0,
        nav: NavStatus = NavStatus()) -> Observation:
    return Observation(tick=tick, robot_id=0, pose=Pose(x, y, theta), known=known, nav=nav)


def visit(variant: str, known: np.ndarray, at: tuple[float, float], ticks: int = 80,
          **params: object) -> tuple[Minotaur, list[dict], list[tuple[float, float]]]:
    """A robot that stands at ``at`` except that it is on its goal, reported reached, the tick after it
    got a Door waypoint: the debug and the pose of every tick."""
    a = agent(variant, known.shape, **params)
    debug, poses = [], []
    pose, nav = at, NavStatus()
    for tick in range(ticks):
        poses.append(pose)
        debug.append(dict(a.act(obs(tick, known, *pose, nav=nav)).debug))
        if debug[-1]["mode"] == "check-door" and a.target is not None:
            pose, nav = a.target, NavStatus(goal=a.target, state="reached")
        else:
            pose, nav = at, NavStatus()
    return a, debug, poses


# ---------------------------------------------------------------------------- the check on arrival ----
def test_swarm_accepts_a_seen_door_from_the_map_maes_only_after_checking_it() -> None:
    known = known_of(wall_with_door())
    swarm, debug, _ = visit("swarm", known, (8.0, 6.0))
    assert len(debug[0]["doorways"]) == 1 and swarm.book.doors[0].found_tick == 0   # the first scan, the map
    assert all(d["mode"] != "check-door" for d in debug)

    a, debug, poses = visit("maes", known, (8.0, 6.0))
    first = next(t for t, d in enumerate(debug) if d["doorways"])
    assert first >= 1 and all(not d["doorways"] for d in debug[:first])
    # the nearest crossing (the lower jamb's face line meets the upper wall's): its Door waypoint, pulled back
    # VisionRadius cells towards the robot (lines 838-840), is where the robot stands, so it checks at once;
    # MAES's frame puts the jambs 2 doorWidth cells apart (lines 519-540, 863-864)
    ((t, cand, ok),) = a.checks
    assert (t, ok, cand.kind, cand.key) == (first, True, "cross", (10, 23))
    (door,) = a.book.doors
    assert (door.x, door.y, door.axis, door.width) == pytest.approx((12.5, 6.0, 1, 2.0))
    assert door.found_tick == first and (first, True) in [(t, ok) for t, _, ok in a.checks]


def test_maes_drives_to_a_gap_too_wide_for_a_door_and_drops_it() -> None:
    """The overhead of the paper's section 5.2: a 4 m hallway, which swarm's detector never considers,
    is a candidate that MAES drives to and forgets on arrival (jambs 8 cells apart > 2 doorWidth)."""
    known = known_of(hallway())
    swarm, debug, _ = visit("swarm", known, (8.0, 6.0))
    assert len(swarm.book) == 0 and all(d["mode"] != "check-door" for d in debug)

    a, debug, poses = visit("maes", known, (8.0, 6.0))
    assert len(a.book) == 0 and all(not d["doorways"] for d in debug)
    assert a.checks and not any(ok for *_, ok in a.checks)   # several walls in view: crossings (line 795)
    t, cand, _ = a.checks[0]
    assert debug[t - 1]["check"][:2] == (cand.kind, cand.key) and poses[t] == debug[t - 1]["target"]
    assert len({c.key for _, c, _ in a.checks}) == len(a.checks)              # each candidate tried once
    assert all(c.key in a.tried for _, c, _ in a.checks)


def test_a_three_metre_gap_swarm_accepts_is_too_wide_for_maes() -> None:
    """Swarm's ``max_door_width_m`` (3 m) against MAES's jamb rule, [3, 2 doorWidth] cells (1.5-2 m)."""
    known = known_of(as_map(gap(wall(blank(24, 12), 12, 0, 13, 12), 12, 4.5, 13, 7.5)))
    swarm, _, _ = visit("swarm", known, (8.0, 6.0))
    assert [d.width for d in swarm.book] == [3.0]
    a, _, _ = visit("maes", known, (8.0, 6.0))
    assert len(a.book) == 0 and a.checks
    wide, _, _ = visit("maes", known, (8.0, 6.0), maes_door_width=3)         # doorWidth = 3: up to 3 m
    assert [d.width for d in wide.book] == [3.0]


def test_an_unseen_far_side_is_not_a_door_yet() -> None:
    """AttemptAddDoorway needs the crossing seen: a gap whose continuation is UNSEEN is dropped."""
    known = known_of(wall_with_door())
    cand = maes.Candidate("gap", (10, 24), (8.0, 6.75), axis=1, line=24, side=-1, end=9, step=1)
    assert maes.check(known, cand, 2) is not None
    known[14:16, 24:26] = UNSEEN
    assert maes.check(known, cand, 2) is None


def test_door_in_a_corner_is_a_crossing_candidate() -> None:
    """The several-walls case: the dividing wall's line meets the floor's line short of the wall's end."""
    solid = wall(blank(24, 12), 12, 3, 13, 12)                                # the wall stops 2 m above the floor
    known = np.where(solid, SOLID, FREE).astype(np.uint8)
    cands = maes.candidates(known, (0, 0), (8.0, 5.0), 7, 2)
    cross = [c for c in cands if c.kind == "cross" and c.key == (2, 23)]
    assert cross, [c.key for c in cands]
    door = maes.check(known, cross[0], 2)
    assert door is not None and door.axis == 1 and door.x == pytest.approx(12.5)
    assert door.y == pytest.approx(2.0) and door.width == pytest.approx(2.0)
    assert all(c.key != (2, 2) for c in cands)                                # a real corner is no candidate


def test_a_wall_ahead_drops_the_door_waypoint_unchecked() -> None:
    """MinotaurAlgorithm.cs lines 264-283: a SOLID cell within VisionRadius - 2 tiles on the way."""
    known = known_of(wall_with_door())
    a = agent("maes", known.shape)
    a.act(obs(0, known, 8.0, 6.0))
    cand = maes.Candidate("gap", (10, 24), (8.0, 10.5), axis=1, line=24, side=-1, end=9, step=1)
    a.check, a.state, a.mode, a.target, a.check_since = cand, "room", "check-door", (8.0, 10.5), 0
    d = a.act(obs(1, known, 8.0, 8.0)).debug                                 # the top wall 3 m ahead
    assert d["check"] is None and a.checks == [] and len(a.book) == 0
    a.check, a.state, a.mode, a.target = cand, "room", "check-door", (8.0, 7.0)
    d = a.act(obs(2, known, 8.0, 3.0)).debug                                 # 8 m to the top wall: go on
    assert d["check"] is not None and a.target == (8.0, 7.0)


# ------------------------------------------------------------ which candidates, how often (issue 49) ----
def two_walls() -> np.ndarray:
    """A known open floor with a row wall (rows 20-21, cols 10-25) whose ends are unseen (so they show no
    faces) and a column wall (col 30, rows 5-35): from cell (15, 18) the robot sees both; beyond the row
    wall's east end its row is FREE again at (20, 28), a gap candidate, and the row wall's face line meets
    the column wall's at (19, 29), a crossing on the column wall only."""
    known = np.full((40, 40), FREE, np.uint8)
    known[20:22, 10:26] = SOLID
    known[19:23, 26:28] = UNSEEN
    known[19:23, 8:10] = UNSEEN
    known[5:36, 30] = SOLID
    return known


def test_maes_single_wall_rule_only_when_exactly_one_wall_is_seen() -> None:
    """MinotaurAlgorithm.cs 795: the gap rule (796-821) when one wall is in view, else the crossings
    (825-847). Here the nearest candidate is a gap, but two walls are in view: MAES drives to the crossing."""
    known = two_walls()
    cands = maes.candidates(known, (0, 0), (9.25, 7.75), 7, 2)
    assert cands[0].kind == "gap" and cands[0].key == (20, 28)             # both rules: the gap is nearest
    a = agent("maes", known.shape)
    a.act(obs(0, known, 9.25, 7.75))
    d = a.act(obs(1, known, 9.25, 7.75)).debug
    assert d["check"][:2] == ("cross", (19, 29))
    alone = known.copy()
    alone[5:36, 30] = FREE                                                    # one wall: the gap rule only
    assert {c.kind for c in maes.candidates(alone, (0, 0), (9.25, 7.75), 7, 2, by_wall_count=True)} == {"gap"}


def test_maes_search_stops_at_the_first_tried_candidate() -> None:
    """MinotaurAlgorithm.cs 830-833 (and 809-812): a candidate already in ``_previousIntersections`` ends the
    search with ``return``: the next crossing, never tried, is not taken."""
    known = known_of(wall_with_door())
    cands = maes.candidates(known, (0, 0), (8.0, 6.0), 7, 2)
    assert [c.key for c in cands[:2]] == [(10, 23), (13, 23)]                 # two crossings, nearest first
    a = agent("maes", known.shape)
    a.tried.add((10, 23))
    a.act(obs(0, known, 8.0, 6.0))
    for tick in range(1, 30):
        d = a.act(obs(tick, known, 8.0, 6.0)).debug
        assert d["check"] is None and d["mode"] != "check-door"
    assert a.tried == {(10, 23)} and a.checks == []


def test_maes_scans_for_doorways_every_tick() -> None:
    """MinotaurAlgorithm.cs 231-252: DoorwayDetection runs in every UpdateLogic; ``scan_every`` (10) is
    swarm's cadence. Robot 0 finds its candidate at tick 1, not at tick 10."""
    known = two_walls()
    a = agent("maes", known.shape)
    a.act(obs(0, known, 9.25, 7.75))
    assert a.act(obs(1, known, 9.25, 7.75)).debug["check"] is not None


def test_tried_candidates_pool_only_with_the_second_heartbeat_of_a_tick() -> None:
    """Issue 49 row 2, MinotaurAlgorithm.cs 173-181 and HeartbeatMessage.cs 55: a receiver of two or more
    heartbeats in one tick adds every later sender's ``previousIntersections`` to its own, never the first
    sender's; a lone heartbeat adds nothing. The robot then stops its search at a pooled cell."""
    from algorithms.minotaur.messages import Tried

    known = known_of(wall_with_door())
    a = Minotaur()
    a.reset(RobotInfo(id=2, n_robots=3, map_shape=known.shape, lidar_range=7.0),
            MinotaurParams(variant="maes"), np.random.default_rng(0))
    at = Pose(8.0, 6.0, 0.0)
    a.act(Observation(tick=1, robot_id=2, pose=at, known=known, inbox=(Tried(0, ((3, 3),)),)))
    assert (3, 3) not in a.tried                                             # one heartbeat: nothing
    a.act(Observation(tick=11, robot_id=2, pose=at, known=known,
                      inbox=(Tried(0, ((4, 4),)), Tried(1, ((10, 23), (5, 5))))))
    assert {(10, 23), (5, 5)} <= a.tried and (4, 4) not in a.tried          # all but the first sender's
    assert a.checks == [] and a.check is None                                # (10, 23), the nearest, was pooled
    out = a.act(Observation(tick=20, robot_id=2, pose=at, known=known)).messages
    (mine,) = [m for m in out if isinstance(m, Tried)]                       # and it sends its own set
    assert mine.sender == 2 and set(mine.cells) == a.tried


# --------------------------------------------------------------------------------- corner coverage ----
def corner_room() -> tuple[np.ndarray, tuple[float, float]]:
    """A known open area with no walls, an unseen patch to the robot's right front, known space ahead."""
    known = np.full((60, 60), UNSEEN, np.uint8)
    known[10:50, 10:56] = FREE
    known[25:29, 40:44] = UNSEEN                                              # x 20-22, y 12.5-14.5 m: -6 to -20 deg
    return known, (15.0, 15.0)


def test_corner_rays_cover_thirty_degrees_to_the_right() -> None:
    known, at = corner_room()
    cells = maes.corner(known, at, 0.0, 7, 1)
    assert cells and all(known[c] == UNSEEN for c in cells)
    for r, c in cells:
        bearing = math.degrees(math.atan2((r + 0.5) * 0.5 - at[1], (c + 0.5) * 0.5 - at[0]))
        assert -31 <= bearing <= 0
    assert maes.corner(known, at, 0.0, 7, -1) == []                         # mirrored: the left is all known
    ahead = known.copy()
    ahead[28:32, 44:50] = UNSEEN                                              # 8 and 9 m straight ahead unseen
    assert maes.corner(ahead, at, 0.0, 7, 1) == []                          # IsAheadExploreable: no corner


def test_maes_approaches_the_corner_where_swarm_follows_the_edge() -> None:
    known, at = corner_room()
    modes = {}
    for variant in ("swarm", "maes"):
        a = agent(variant, known.shape, spin="ccw")
        d = a.act(obs(101, known, *at)).debug                               # past the start phase
        modes[variant] = (d["mode"], a.anchor)
    assert modes["swarm"][0] != "corner"
    mode, anchor = modes["maes"]
    assert mode == "corner" and known[anchor] == UNSEEN and 25 <= anchor[0] < 29 and 40 <= anchor[1] < 44


# ------------------------------------------------------------------------------ doorway before Greed ----
def three_rooms() -> tuple[np.ndarray, list[Doorway]]:
    """Rooms A | B | C (x 1-10, 11-20, 21-29 m) through 2 m doors at y 5-7; A known, B known but for a
    patch near the first door, C unseen; the first door explored, the second not."""
    solid = blank(30, 12)
    wall(solid, 10, 0, 11, 12)
    wall(solid, 20, 0, 21, 12)
    gap(solid, 10, 5, 11, 7)
    gap(solid, 20, 5, 21, 7)
    known = np.where(solid, SOLID, FREE).astype(np.uint8)
    known[18:22, 22:28] = UNSEEN                                              # B: x 11-14, y 9-11
    known[:, 42:] = UNSEEN                                                    # C
    doors = [Doorway(10.5, 6.0, 1, 2.0, 1.0, sides=3), Doorway(20.5, 6.0, 1, 2.0, 1.0, sides=1)]
    return known, doors


def test_maes_takes_the_nearest_doorway_before_a_nearer_unseen_cell() -> None:
    """swarm's greedy_if_nearer goes to the unseen cell in B, nearer than the unexplored door to C; MAES
    goes to the door (MovetoNearestDoorway before MoveToNearestUnseen), whatever greedy_if_nearer says."""
    known, doors = three_rooms()
    choices = {}
    for variant, nearer in (("swarm", True), ("swarm", False), ("maes", True)):
        a = agent(variant, known.shape, greedy_if_nearer=nearer)
        for d in doors:
            a.book.add(Doorway(d.x, d.y, d.axis, d.width, d.depth, sides=d.sides))
        dbg = a.act(obs(1, known, 8.0, 6.0)).debug
        choices[(variant, nearer)] = (dbg["state"], dbg["mode"], dbg["door"])
    assert choices[("swarm", True)][:2] == ("greedy", "greedy")
    assert choices[("swarm", False)][:2] == ("door", "door-anywhere")
    state, mode, door = choices[("maes", True)]
    assert (state, mode) == ("door", "door-nearest") and door[:3] == (20.5, 6.0, 1)


def test_nearest_door_ignores_rooms_and_what_lies_behind() -> None:
    known, doors = three_rooms()
    from swarm.api import grid
    space = grid.configuration_space(known)
    start = rooms.snap(space, (8.0, 6.0))
    door, side, dist = rooms.nearest_door(space, start, doors)
    assert door is doors[0] and side == -1 and 0 < dist < 3
    assert rooms.nearest_door(space, start, []) is None


# ------------------------------------------------------------------------------------------ runs ----
def short_run(variant: str, ticks: int = 400) -> tuple[dict, list[list[dict]]]:
    debug: list[list[dict]] = []

    def watch(view) -> None:
        debug.append([dict(a.debug) for a in view.actions])

    spec = {"robots": {"count": 2}, "algorithm": {"name": "minotaur", "params": {"variant": variant}}, "seed": 5,
            "stop": {"max_ticks": ticks}}
    poses = np.array([[4.0 + i, 6.0, 0.0] for i in range(2)])
    result = Simulation(spec, truth=wall_with_door(), observers=[watch], start_poses=poses).run()
    return result.summary, debug


def test_maes_runs_are_deterministic_and_not_the_default() -> None:
    a, da = short_run("maes")
    b, _ = short_run("maes")
    assert (a["ticks"], a["final_poses"], a["explored"]) == (b["ticks"], b["final_poses"], b["explored"])
    modes = {d["mode"] for tick in da for d in tick}
    assert "check-door" in modes
    s, ds = short_run("swarm")
    assert "check-door" not in {d["mode"] for tick in ds for d in tick}
    assert s["final_poses"] != a["final_poses"]


def test_maes_explores_a_building_with_its_doors() -> None:
    spec = {"map": {"kind": "building", "size": 30}, "robots": {"count": 2},
            "algorithm": {"name": "minotaur", "params": {"variant": "maes"}}, "seed": 4, "stop": {"max_ticks": 8000}}
    last: dict[int, dict] = {}

    def watch(view) -> None:
        for i, act in enumerate(view.actions):
            last[i] = dict(act.debug)

    summary = Simulation(spec, observers=[watch]).run().summary
    assert summary["stop_reason"] == "explored"
    assert any(last[i]["doorways"] for i in last)


def test_variant_is_checked() -> None:
    with pytest.raises(InvalidInput):
        MinotaurParams(variant="unity")
    with pytest.raises(InvalidInput):
        MinotaurParams(maes_door_width=0)
    assert MinotaurParams().variant == "swarm"


def test_check_explorer_passes_for_the_maes_variant() -> None:
    report = check_explorer("minotaur", params={"variant": "maes"})    # raises at the first failed check
    assert "determinism" in report.checks and "transports" in report.checks


# ------------------------------------------------------------------------------- MAES's auction (row 6) ----
def auctioneer(n_bids: int) -> tuple[Minotaur, list]:
    """Robot 0 of 6 (MAES variant) runs an auction for the door of ``wall_with_door`` and hears ``n_bids``
    bids from robots 1.. (distances 1, 2, ...) before it closes; what it sends at the close."""
    from algorithms.minotaur.messages import Bid

    known = known_of(wall_with_door())
    a = Minotaur()
    a.reset(RobotInfo(id=0, n_robots=6, map_shape=known.shape, lidar_range=7.0),
            MinotaurParams(variant="maes"), np.random.default_rng(0))
    door, _ = a.book.add(Doorway(12.5, 6.0, 1, 2.0, 1.0, sides=1))
    a.state = "room"
    a.auctions.start(0, door, -1, 4.0)
    bids = tuple(Bid(k, 0, 1, float(k)) for k in range(1, n_bids + 1))
    pose = Pose(8.0, 6.0, 0.0)
    a.act(Observation(tick=2, robot_id=0, pose=pose, known=known, inbox=bids))
    sent = list(a.act(Observation(tick=3, robot_id=0, pose=pose, known=known)).messages)
    return a, sent


def test_maes_auction_rule_from_bidding_message() -> None:
    """BiddingMessage.cs 63-86 over the other robots' bids (the auctioneer never bids): three bids send the
    two lowest and the auctioneer and mark the doorway explored; two send the auctioneer alone, with no
    result message; one sends nobody. The paper's rule (default variant) would send floor(n/2) of all
    bids, the auctioneer's included, and always announce."""
    from algorithms.minotaur.auction import maes_outcome
    from algorithms.minotaur.messages import AuctionResult

    assert [maes_outcome({k: float(k) for k in range(n)}) for n in range(6)] == [
        ((), False), ((), False), ((), True), ((0, 1), True), ((0, 1), True), ((0, 1, 2), True)]
    a, sent = auctioneer(3)
    (result,) = [m for m in sent if isinstance(m, AuctionResult)]
    assert result.winners == (1, 2) and a.state == "door" and a.book.doors[0].explored
    a, sent = auctioneer(2)
    assert not any(isinstance(m, AuctionResult) for m in sent)
    assert a.state == "door" and a.mode == "auction" and a.book.doors[0].explored
    a, sent = auctioneer(1)
    assert not any(isinstance(m, AuctionResult) for m in sent)
    assert a.mode != "auction" and not a.book.doors[0].explored             # (its room is done: door-nearest)


# ------------------------------------------------------------------ others' destinations, spin (row 9) ----
def test_maes_stores_its_own_waypoint_as_others_destinations_and_does_not_split_the_spin() -> None:
    """HeartbeatMessage.cs 54: the "destination" stored for a later sender of pooled heartbeats is the
    receiver's own waypoint (a MAES bug), so MAES's Greed keeps away from where the robot itself was going,
    not from where the others go; and MAES has one wall-following direction, no Alg. 2 split."""
    from algorithms.minotaur.messages import Heading, Tried
    from swarm.api import Neighbour

    known = np.full((40, 40), FREE, np.uint8)
    known[30:, :] = UNSEEN                                                   # unseen from y = 15 m up
    a = Minotaur()
    a.reset(RobotInfo(id=2, n_robots=3, map_shape=known.shape, lidar_range=7.0),
            MinotaurParams(variant="maes"), np.random.default_rng(0))
    a.target = (3.25, 14.75)                                                 # its own waypoint: cell (29, 6)
    inbox = (Heading(1, (10.25, 14.75), ()), Tried(0, ()), Tried(1, ()))     # robot 1 heads for cell (29, 20)
    a._read_inbox(Observation(tick=10, robot_id=2, pose=Pose(10.0, 10.0, 0.0), known=known, inbox=inbox))
    assert a.maes_dest == {1: (29, 6)}                                       # not robot 1's real target
    own = a._own_destinations(known.shape)
    assert own is not None and own[28:30, 6:8].all() and own.sum() == 4 and not own[29, 20]
    near = (Neighbour(id=0, distance=1.0, bearing=0.0, x=11.0, y=10.0),)
    for variant, spin in (("swarm", -1), ("maes", 1)):                      # robot 2 ranks second of 0 and 2
        b = agent(variant, known.shape)
        b.id = 2
        b._choose_spin(Observation(tick=10, robot_id=2, pose=Pose(10.0, 10.0, 0.0), known=known, neighbours=near))
        assert b.spin == spin, variant


# ------------------------------------------------------------------------ doorway reports (row 8) ----
def test_maes_ignores_a_reported_doorway_behind_a_known_one_and_never_bids_on_a_known_one() -> None:
    """DoorwayFoundMessage.cs 52-75: a receiver whose path to the reported doorway passes a doorway it knows
    neither records it nor bids (58-63); one with a clear path records it and bids (65-67); one that already
    knows it never bids (its own centre is on the path). Swarm records every report."""
    from algorithms.minotaur.messages import Bid, DoorwayFound

    known, doors = three_rooms()
    known[:, 42:] = FREE                                                      # C known too: every door reachable
    report = DoorwayFound(5, 1, Doorway(20.5, 6.0, 1, 2.0, 1.0).wire(), 1)   # the B | C door, from C's side

    def hear(variant: str, x: float, knows: list[Doorway]) -> tuple[Minotaur, list]:
        a = Minotaur()
        a.reset(RobotInfo(id=0, n_robots=6, map_shape=known.shape, lidar_range=7.0),
                MinotaurParams(variant=variant), np.random.default_rng(0))
        for d in knows:
            a.book.add(Doorway(d.x, d.y, d.axis, d.width, d.depth))
        a.state = "room"
        a._read_inbox(Observation(tick=5, robot_id=0, pose=Pose(x, 6.0, 0.0), known=known, inbox=(report,)))
        return a, [msg for msg in a.outbox if isinstance(msg, Bid)]

    a, bids = hear("maes", 5.0, doors[:1])                                   # in A: the way passes door A | B
    assert len(a.book) == 1 and bids == []
    s, _ = hear("swarm", 5.0, doors[:1])
    assert len(s.book) == 2
    a, bids = hear("maes", 15.0, doors[:1])                                  # in B: a clear way
    assert len(a.book) == 2 and len(bids) == 1 and bids[0].distance > 0
    a, bids = hear("maes", 15.0, doors)                                      # it knows the B | C door already
    assert bids == []
    s, sbids = hear("swarm", 25.0, doors)                                    # swarm bids from C's side
    assert len(sbids) == 1
