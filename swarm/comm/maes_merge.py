"""MAES's own map merges, for parity runs (``comm.map_sharing = "maes_heartbeat"`` or ``"maes_sync"``).

MAES robots broadcast their live ``SlamMap`` *object*, so a "merge" (``SlamMap.Synchronize``) overwrites
every participating map with the union, by reference (docs/maes.md sections 2 item 4, 5.4, 7.2-7.4):

* **heartbeat** (Greed ``Greed.cs`` lines 105-119, Minotaur ``MinotaurAlgorithm.cs`` lines 167-181): every
  ``share_every`` (10) ticks each robot broadcasts a heartbeat; a robot that receives **two or more** in
  one tick synchronises the **senders'** maps. Its own map is not part of the merge, and a robot that
  hears only one heartbeat (always, with two robots) merges nothing. The merge is **pairwise and in
  order** (issue 49 row 12): the first heartbeat's message is combined with each later one in turn
  (``combinedMessage.Combine(message)``, Greed.cs 114-118, MinotaurAlgorithm.cs 176-180), each
  ``Combine`` synchronising two maps, the later sender's and the first sender's (``SlamMap.Synchronize``
  of ``{other.map, map}``, Greed.cs 254-255, HeartbeatMessage.cs 56-57; ``Combine`` returns ``this``, so
  the first sender's stays the partner). With senders s0 < s1 < s2 (inbox order is broadcast order,
  ``CommunicationManager.cs`` 124-125, 190-191): s0 and s1 get s0 | s1, then s0 and s2 get s0 | s1 | s2;
  s1 keeps a part of the union. Every pair is one synchronisation (``merges``).
* **sync** (TNF, ``TnfExplorationAlgorithm.cs`` ``UpdateLogic`` lines 166-182, ``AwaitCommunication``
  lines 268-293): every ``share_every`` (20) ticks each robot that senses another robot broadcasts its map;
  next tick each of those broadcasters reads what it received and, if no sender has a higher id,
  synchronises its own map with the senders', so all of them end up with the union.

A heartbeat carries no map bytes here (MAES passes a reference): its wire size is the small
:class:`MapHeartbeat`. The merge reads the senders' maps at delivery, as MAES reads the live objects, and
each receiver is handled in robot order. The runtime's own sharing service is off in these modes.
"""

from __future__ import annotations

import dataclasses
from typing import Any, Sequence

import numpy as np

from swarm.results.metrics import InfoAges
from .messages import message

MODES = ("maes_heartbeat", "maes_sync")
DEFAULT_MERGE = ("maes_heartbeat", 10)
"""What ``map_sharing = "maes"`` means for an algorithm that declares no MAES merge of its own."""


def resolve(map_sharing: str, share_every: int, algorithm: type) -> tuple[str, int] | None:
    """The MAES merge mode and period of a run, or None when its map sharing is not a MAES one.
    ``maes`` takes them from the algorithm class's ``maes_map_merge = (mode, period)`` (TNF syncs every
    20 ticks; Greed and Minotaur heartbeat every 10; an algorithm MAES does not have gets
    :data:`DEFAULT_MERGE`); ``maes_heartbeat``/``maes_sync`` are used as given with ``share_every``."""
    if map_sharing in MODES:
        return map_sharing, share_every
    if map_sharing != "maes":
        return None
    mode, period = getattr(algorithm, "maes_map_merge", DEFAULT_MERGE)
    if mode not in MODES or not isinstance(period, int) or period < 1:
        raise ValueError(f"{algorithm.__name__}.maes_map_merge = {(mode, period)!r}; allowed: (one of {MODES}, a period >= 1)")
    return mode, period


@message("swarm.maes_heartbeat", version=1)
@dataclasses.dataclass(frozen=True)
class MapHeartbeat:
    """A MAES heartbeat: "my map, by reference" (the merge reads the sender's live map)."""

    sender: int
    tick: int

    def validate(self) -> None:
        from .messages import MessageError

        if not isinstance(self.tick, int) or isinstance(self.tick, bool):
            raise MessageError("maes_heartbeat: tick must be an integer")


class MaesMerge:
    """MAES's map merge of one run: which robots broadcast heartbeats, and what a tick's deliveries merge."""

    def __init__(self, n: int, mode: str, share_every: int, ages: InfoAges | None = None) -> None:
        """``ages``: told of every synchronisation (its members all hold each other's maps)."""
        if mode not in MODES:
            raise ValueError(f"mode {mode!r}; allowed: {', '.join(MODES)}")
        self.n, self.mode, self.share_every = n, mode, share_every
        self.ages = ages
        self.merges = 0  # synchronisations performed (heartbeat: one per pair merged; sync: one per receiver)
        self._broadcast: set[int] = set()  # sync: who broadcast in the last round (only they read next tick)

    def outgoing(self, tick: int, near: Any) -> list[list[MapHeartbeat]]:
        """The heartbeats each robot broadcasts this tick; ``near()`` gives the tick's sensed-neighbour mask
        (bool[R, R], read only in sync mode, where only robots that sense another broadcast)."""
        out: list[list[MapHeartbeat]] = [[] for _ in range(self.n)]
        if self.n < 2 or tick % self.share_every:
            return out
        senders = range(self.n) if self.mode == "maes_heartbeat" else np.flatnonzero(near().any(axis=1)).tolist()
        self._broadcast = set(senders)
        for i in senders:
            out[i].append(MapHeartbeat(sender=i, tick=tick))
        return out

    def receive(self, deliveries: Sequence[tuple[Any, Sequence[int]]], known: np.ndarray, live: np.ndarray,
                tick: int = 0) -> set[int]:
        """Merge what this tick's heartbeats call for into ``known`` (uint8[R, H, W], in place); returns the
        robots whose maps were overwritten (any cell of them may have changed). ``tick``: now (for ``ages``)."""
        heard: list[list[int]] = [[] for _ in range(self.n)]
        for msg, receivers in deliveries:
            if isinstance(msg, MapHeartbeat):
                for r in receivers:
                    if live[r]:
                        heard[r].append(msg.sender)
        changed: set[int] = set()
        for r, senders in enumerate(heard):
            senders = sorted(set(s for s in senders if live[s]))
            if self.mode == "maes_heartbeat":  # the first sender's map with each later one's, in turn
                groups = [[senders[0], s] for s in senders[1:]]
            else:  # only a robot that broadcast reads; the one with no higher-id sender merges
                groups = [[r, *senders]] if senders and r in self._broadcast and max(senders) < r else []
            for group in groups:
                union = np.maximum.reduce(known[group])
                for g in group:
                    known[g] = union
                changed.update(group)
                self.merges += 1
                if self.ages is not None:
                    self.ages.group(group, tick)
        return changed
