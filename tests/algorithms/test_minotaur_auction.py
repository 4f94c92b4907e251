"""Minotaur's doorway auction (paper section 3.4, Alg. 4) on a hand-made two-room map, and the auction
bookkeeping on its own (winners, late bids, late results)."""

from __future__ import annotations

import numpy as np
import pytest

from algorithms.minotaur.auction import Auctions, winners
from algorithms.minotaur.doorways import Doorway
from algorithms.minotaur.messages import AuctionResult, Bid, DoorwayFound
from swarm.sim.loop import Simulation
from tests.algorithms.test_minotaur_doorways import as_map, blank, gap, wall

DOOR_X = (16.0, 17.0)          # the dividing wall; the door is y in [5, 7)


def two_rooms():
    """Room A (x 1..16 m) and room B (x 17..39 m), 10 m deep, one 2 m door between them."""
    solid = wall(blank(40, 12), *DOOR_X[:1], 0, DOOR_X[1], 12)
    return as_map(gap(solid, DOOR_X[0], 5, DOOR_X[1], 7))


# Robots 0-3 in room A, 6 m from the door; robot 4 at the far end of room B, out of sight of the door.
POSES = np.array([[10.0, 4.0, 0.0], [10.0, 6.0, 0.0], [10.0, 8.0, 0.0], [8.0, 6.0, 0.0], [36.0, 6.0, 0.0]])


def run_two_rooms(ticks: int, explored: float = 1.0, **comm: object) -> tuple[list, np.ndarray, list, dict]:
    """Every message sent (tick, sender, message), robot x positions and radio links per tick, and the run
    summary. ``explored`` 1.0 keeps the run going to ``ticks``."""
    sent: list[tuple[int, int, object]] = []
    xs: list[np.ndarray] = []
    links: list[np.ndarray] = []

    def watch(view) -> None:
        for robot, envelopes in enumerate(view.sent):
            for env in envelopes:
                sent.append((view.tick, robot, env.message))
        xs.append(view.poses[:, 0].copy())
        links.append(view.links.link.copy())

    spec = {"robots": {"count": 5}, "algorithm": {"name": "minotaur"}, "seed": 11, "radio": {"model": "multiwall"},
            "comm": dict(comm), "stop": {"max_ticks": ticks, "explored": explored}}
    result = Simulation(spec, truth=two_rooms(), observers=[watch], start_poses=POSES).run()
    return sent, np.array(xs), links, result.summary


@pytest.fixture(scope="module")
def two_room_run():
    return run_two_rooms(400)


def test_first_auction_is_in_room_a_and_sends_exactly_two_through(two_room_run) -> None:
    sent, xs, _, _ = two_room_run
    found = [(t, s, m) for t, s, m in sent if isinstance(m, DoorwayFound)]
    assert found, "nobody auctioned the doorway"
    _, auctioneer, announce = found[0]
    assert auctioneer in (0, 1, 2, 3)
    door = Doorway.from_wire(announce.door)
    assert door.axis == 1 and DOOR_X[0] <= door.x <= DOOR_X[1] and 5.0 <= door.y <= 7.0
    assert announce.side == -1                                    # announced from room A's side

    bids = {s for t, s, m in sent if isinstance(m, Bid) and (m.auctioneer, m.auction) == (auctioneer, announce.auction)}
    assert bids == {0, 1, 2, 3} - {auctioneer}                    # everyone in room A, nobody else
    (t1, _, result), = [(t, s, m) for t, s, m in sent
                        if isinstance(m, AuctionResult) and s == auctioneer and m.auction == announce.auction]
    assert len(result.winners) == 2 and set(result.winners) <= {0, 1, 2, 3}

    # The two winners go through the door; the other two stay in room A meanwhile.
    through = []
    for w in result.winners:
        beyond = np.flatnonzero(xs[t1:, w] > DOOR_X[1] + 1.0)
        assert beyond.size, f"winner {w} never went through"
        through.append(t1 + int(beyond[0]))
    losers = sorted({0, 1, 2, 3} - set(result.winners))
    assert (xs[t1:max(through) + 20, losers] < DOOR_X[0]).all(), "a loser left room A"


def test_robot_in_other_room_hears_but_never_bids(two_room_run) -> None:
    sent, _, links, _ = two_room_run
    t0, auctioneer, _ = next((t, s, m) for t, s, m in sent if isinstance(m, DoorwayFound))
    assert links[t0][4, auctioneer]                               # the announcement reached robot 4
    assert not [m for t, s, m in sent if isinstance(m, Bid) and s == 4]


def test_auction_survives_lossy_radio() -> None:
    """Half the messages lost: auctions still close (time out) and exploration finishes."""
    sent, _, _, summary = run_two_rooms(6000, explored=0.99, loss=0.5)
    assert summary["stop_reason"] == "explored"
    results = [m for t, s, m in sent if isinstance(m, AuctionResult)]
    found = [m for t, s, m in sent if isinstance(m, DoorwayFound)]
    assert len(results) == len(found)                             # every auction closed


# ------------------------------------------------------------------------------------ bookkeeping ----
def test_winners_are_the_lowest_half_rounded_down() -> None:
    assert winners({0: 5.0, 1: 1.0, 2: 3.0, 3: 2.0}) == (1, 3)
    assert winners({0: 5.0, 1: 1.0, 2: 3.0}) == (1,)
    assert winners({7: 1.0}) == ()
    assert winners({4: 2.0, 2: 2.0, 9: 1.0, 3: 7.0}) == (9, 2)   # ties go to the lower id


def test_auction_closes_on_time_and_ignores_late_bids() -> None:
    a = Auctions(robot=0, auction_ticks=3, result_timeout_ticks=20)
    door = Doorway(16.5, 6.0, 1, 2.0, 1.0)
    found = a.start(10, door, -1, own_distance=4.0)
    a.receive_bid(12, Bid(1, 0, found.auction, 1.0))
    a.receive_bid(12, Bid(2, 0, found.auction, 9.0))
    a.receive_bid(12, Bid(3, 7, found.auction, 0.5))             # someone else's auction
    assert a.close_due(12) == []
    ((_, result),) = a.close_due(13)
    assert result.winners == (1,)
    a.receive_bid(14, Bid(4, 0, found.auction, 0.1))             # too late: nothing left open
    assert a.close_due(20) == [] and not a.open


def test_bidder_obeys_only_fresh_results_naming_it() -> None:
    b = Auctions(robot=2, auction_ticks=3, result_timeout_ticks=20)
    found = DoorwayFound(0, 1, (16.5, 6.0, 1, 2.0, 1.0, 1, 0), -1)
    b.bid(5, found, 3.0)
    assert b.won(8, AuctionResult(0, 1, found.door, -1, (2, 0)))
    b.bid(30, DoorwayFound(0, 2, found.door, -1), 3.0)
    assert not b.won(60, AuctionResult(0, 2, found.door, -1, (2,)))   # result came after the timeout
    assert not b.won(61, AuctionResult(0, 3, found.door, -1, (2,)))   # never bid in that one
