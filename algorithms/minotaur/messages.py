"""Minotaur's radio messages (paper section 3.2 and 3.4, Alg. 2 and 4; MAES's ``Messages/*``).

- :class:`DoorwayList`: every ``share_every`` ticks (the map-sharing cadence), the doorways the robot
  knows with their explored facts, its current target and the doorway it is going through, if any. The
  paper and MAES put the doorway list in the map heartbeat (Alg. 2 "broadcasts map, including walls,
  explored area, doorways and known robots location"; MAES's heartbeat also carries the destination);
  the runtime's ``MapUpdate`` is a fixed type, so the list travels beside it.
- :class:`Heading`: sent whenever the robot picks a new target or doorway, so that others can leave it
  to it at once rather than at the next heartbeat (MAES's Minotaur excludes other robots'
  destinations when it re-targets; it learns them from heartbeats).
- :class:`DoorwayFound`: "Communicate doorway location to all robots": opens an auction.
- :class:`Bid`: the ACK with the bidder's path length to the doorway, only from robots that reach it on
  the auctioneer's side without passing another doorway.
- :class:`AuctionResult`: the winners, the lowest half of the bids (rounded down, the auctioneer's own
  bid included).
- :class:`Tried` (``variant = "maes"`` only): with each doorway list, the candidate doorway cells the
  sender has tried, MAES's heartbeat field ``previousIntersections`` (HeartbeatMessage.cs 39, 47).

Every message validates itself when decoded (a malformed one is dropped and counted by the runtime),
and receivers check again what they use: messages come from other robots. Doorways travel as plain tuples (:data:`.doorways.Wire`, spelled out in the annotations because the
codec turns lists back into tuples by reading them); receivers validate them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from swarm.api.messages import MessageError, message

from .doorways import valid_wire


def _int(v: Any) -> bool:
    return isinstance(v, int) and not isinstance(v, bool)


def _point(v: Any) -> bool:
    """A (x, y) pair of numbers (NaN allowed: "no target")."""
    if not isinstance(v, tuple) or len(v) != 2:
        return False
    x, y = v
    return (isinstance(x, (int, float)) and not isinstance(x, bool)
            and isinstance(y, (int, float)) and not isinstance(y, bool))


def _check(ok: bool, what: str) -> None:
    if not ok:
        raise MessageError(what)

@message("minotaur.doorways")
@dataclass(frozen=True)
class DoorwayList:
    sender: int
    doors: tuple[tuple[float, float, int, float, float, int, int], ...]   # Wire tuples
    target: tuple[float, float]          # where the sender is going; NaN when it has no target
    door: tuple[float, ...]              # the Wire of the doorway it is going through, or ()

    def validate(self) -> None:
        _check(isinstance(self.doors, tuple) and len(self.doors) <= 100_000
               and all(valid_wire(w) for w in self.doors), "minotaur.doorways: bad doorway list")
        _check(_point(self.target) and (self.door == () or valid_wire(self.door)), "minotaur.doorways: bad heading")


@message("minotaur.heading")
@dataclass(frozen=True)
class Heading:
    sender: int
    target: tuple[float, float]          # NaN when the robot stopped
    door: tuple[float, ...]              # the Wire of the doorway it is going through, or ()

    def validate(self) -> None:
        _check(self.is_valid(), "minotaur.heading: bad fields")

    def is_valid(self) -> bool:
        return valid_heading(self.target, self.door)


def valid_heading(target: Any, door: Any) -> bool:
    """A heading's (and a doorway list's) target and doorway fields are safe to use."""
    return _point(target) and (door == () or valid_wire(door))


@message("minotaur.doorway_found")
@dataclass(frozen=True)
class DoorwayFound:
    sender: int
    auction: int
    door: tuple[float, float, int, float, float, int, int]                 # a Wire tuple
    side: int               # the side of the doorway the auctioneer is on (-1 / +1)

    def validate(self) -> None:
        _check(_int(self.auction) and valid_wire(self.door) and self.side in (-1, 1),
               "minotaur.doorway_found: bad fields")


@message("minotaur.bid")
@dataclass(frozen=True)
class Bid:
    sender: int
    auctioneer: int
    auction: int
    distance: float         # path length (m) to the doorway on the auctioneer's side

    def validate(self) -> None:
        _check(_int(self.auctioneer) and _int(self.auction) and isinstance(self.distance, (int, float))
               and not isinstance(self.distance, bool) and math.isfinite(self.distance) and self.distance >= 0,
               "minotaur.bid: bad fields")


@message("minotaur.auction_result")
@dataclass(frozen=True)
class AuctionResult:
    sender: int
    auction: int
    door: tuple[float, float, int, float, float, int, int]                 # a Wire tuple
    side: int
    winners: tuple[int, ...]

    def validate(self) -> None:
        _check(_int(self.auction) and valid_wire(self.door) and self.side in (-1, 1)
               and isinstance(self.winners, tuple) and all(_int(w) for w in self.winners),
               "minotaur.auction_result: bad fields")


@message("minotaur.tried")
@dataclass(frozen=True)
class Tried:
    """MAES's heartbeat's ``previousIntersections`` (MinotaurAlgorithm.cs 169, HeartbeatMessage.cs 39-47):
    the candidate cells (row, col) the sender has tried, sent by the MAES variant with its doorway list."""

    sender: int
    cells: tuple[tuple[int, int], ...]

    def validate(self) -> None:
        _check(isinstance(self.cells, tuple) and len(self.cells) <= 1_000_000
               and all(isinstance(c, tuple) and len(c) == 2 and _int(c[0]) and _int(c[1]) for c in self.cells),
               "minotaur.tried: bad cells")
