"""The doorway auction (paper section 3.4, Alg. 4) as bookkeeping, separate from the robot's motion.

Protocol, with the tick each step happens at when the auctioneer finds a doorway at tick t:

- t: the auctioneer broadcasts :class:`DoorwayFound` and records its own bid (the paper: "Alice too
  will respond to the auction with an ACK and its own bid");
- t+1: every robot that hears it and reaches the doorway on the auctioneer's side without passing
  another doorway answers with a :class:`Bid` (its path length); the others stay silent;
- t+2: bids arrive; at t + ``auction_ticks`` the auctioneer closes the auction: the lowest half of
  all bids, rounded down (so 4 bidders send 2, 2 send 1, a lone robot sends nobody and keeps exploring
  its room, Alg. 1), win; it broadcasts :class:`AuctionResult`;
- a bidder obeys a result naming it only within ``result_timeout_ticks`` of its bid.

Lost messages only shrink the auction: a lost announcement or bid is a robot that does not take part,
a lost result is a winner that stays in the room. Nobody ever waits for a message, so nothing deadlocks.
Two robots that find the same doorway at once both open an auction; when one hears the other's, the
higher id withdraws and bids in the lower id's auction.

Departures from MAES (docs/maes.md section 7.2): MAES's auctioneer never bids, lets ``ceil(n/2)`` win and
goes through itself when n = 2; we follow the paper and the issue (the auctioneer bids, ``floor(n/2)``
win, ties broken by robot id). ``maes=True`` (Minotaur's ``variant = "maes"``, issue 49 row 6) runs MAES's
rule instead (:func:`maes_outcome`, ``BiddingMessage.cs`` 58-86).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from .doorways import Doorway
from .messages import AuctionResult, Bid, DoorwayFound


@dataclass
class OpenAuction:
    door: Doorway
    side: int
    closes: int
    bids: dict[int, float] = field(default_factory=dict)
    go_self: bool = False          # maes: the auctioneer goes through itself and marks the doorway explored


def maes_outcome(bids: dict[int, float]) -> tuple[tuple[int, ...], bool]:
    """MAES's ``BiddingMessage.Process`` (``BiddingMessage.cs`` 58-86) over the n bids of *other* robots (the
    auctioneer never bids): ``(n + 1) / 2 > 1`` (n >= 3): the ``(n + 1) / 2`` lowest win and the auctioneer
    goes too (lines 63-74); ``n / 2 == 1`` (n = 2): the auctioneer alone (76-81); n <= 1: nobody (83-85).
    Returns (winners, whether the auctioneer goes); ties go to the lower robot id (MAES: bid arrival order)."""
    n = len(bids)
    ranked = sorted(bids.items(), key=lambda kv: (kv[1], kv[0]))
    if (n + 1) // 2 > 1:
        return tuple(robot for robot, _ in ranked[: (n + 1) // 2]), True
    return (), n // 2 == 1


def winners(bids: dict[int, float]) -> tuple[int, ...]:
    """The lowest half of the bids, rounded down; ties go to the lower robot id."""
    ranked = sorted(bids.items(), key=lambda kv: (kv[1], kv[0]))
    return tuple(robot for robot, _ in ranked[: len(ranked) // 2])


class Auctions:
    """One robot's auctions: those it runs and those it bid in."""

    def __init__(self, robot: int, auction_ticks: int, result_timeout_ticks: int, maes: bool = False) -> None:
        self.robot = robot
        self.maes = maes
        self.auction_ticks = auction_ticks
        self.result_timeout = result_timeout_ticks
        self.open: dict[int, OpenAuction] = {}
        self.bid_in: dict[tuple[int, int], int] = {}      # (auctioneer, auction) -> tick of our bid
        self.next_id = 0
        self.log: list[tuple[int, str, dict]] = []        # (tick, event, details): for tests and the viewer

    # ---------------------------------------------------------------------------- as auctioneer ----
    def start(self, tick: int, door: Doorway, side: int, own_distance: float) -> DoorwayFound:
        self.next_id += 1
        own = {} if self.maes else {self.robot: own_distance}      # MAES's auctioneer never bids
        auction = OpenAuction(door, side, tick + self.auction_ticks, own)
        self.open[self.next_id] = auction
        self.log.append((tick, "start", {"auction": self.next_id, "door": door.wire(), "side": side}))
        return DoorwayFound(self.robot, self.next_id, door.wire(), side)

    def running_for(self, door: Doorway) -> int | None:
        for aid, a in self.open.items():
            if a.door.matches(door):
                return aid
        return None

    def withdraw(self, tick: int, aid: int) -> None:
        self.open.pop(aid, None)
        self.log.append((tick, "withdraw", {"auction": aid}))

    def receive_bid(self, tick: int, bid: Bid) -> None:
        a = self.open.get(bid.auction) if bid.auctioneer == self.robot else None
        if a is None or tick > a.closes:
            return
        a.bids[bid.sender] = float(bid.distance)
        self.log.append((tick, "bid", {"auction": bid.auction, "from": bid.sender, "distance": bid.distance}))

    def close_due(self, tick: int) -> list[tuple[OpenAuction, AuctionResult | None]]:
        """The auctions due now, each with the result to broadcast (None: MAES announces nothing, when fewer
        than three bids came, ``BiddingMessage.cs`` 76-86)."""
        out: list[tuple[OpenAuction, AuctionResult | None]] = []
        for aid in [aid for aid, a in self.open.items() if tick >= a.closes]:
            a = self.open.pop(aid)
            if self.maes:
                won, a.go_self = maes_outcome(a.bids)
            else:
                won = winners(a.bids)
            self.log.append((tick, "close", {"auction": aid, "bids": dict(a.bids), "winners": won}))
            announce = not self.maes or len(a.bids) >= 3
            out.append((a, AuctionResult(self.robot, aid, a.door.wire(), a.side, won) if announce else None))
        return out

    # -------------------------------------------------------------------------------- as bidder ----
    def bid(self, tick: int, found: DoorwayFound, distance: float) -> Bid:
        self.bid_in[(found.sender, found.auction)] = tick
        self.log.append((tick, "bid_sent", {"auctioneer": found.sender, "auction": found.auction,
                                            "distance": distance}))
        return Bid(self.robot, found.sender, found.auction, float(distance))

    def won(self, tick: int, result: AuctionResult) -> bool:
        """Whether this robot should go through the doorway of ``result`` now."""
        at = self.bid_in.pop((result.sender, result.auction), None)
        if at is None or tick - at > self.result_timeout:
            return False
        return self.robot in result.winners

    def expire(self, tick: int) -> None:
        horizon = tick - self.result_timeout
        if self.bid_in and min(self.bid_in.values()) < horizon:
            self.bid_in = {k: t for k, t in self.bid_in.items() if t >= horizon}
