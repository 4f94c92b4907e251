"""The radio medium as the runtime sees it: broadcasts judged by the radio, lost, throttled and delivered.

**Medium.** Messages a robot broadcasts during tick t are encoded (their size is a metric), judged by the
radio's link matrix computed from positions at send time, optionally thinned by seeded packet loss and a
per-link byte budget, and appear in each receiver's inbox at tick t+1, ordered by (sender, sequence). A
robot never receives its own broadcast. (MAES judges links at receive time; we use send time, as a real
radio does, docs/design.md section 4.) Two options make the channel more than a fixed threshold: packet
errors drawn from each pair's margin (``radio.per``, :mod:`radio.per`) and multi-hop relaying
(``comm.relay = "flood"``): each robot forwards every message it hears for the first time, one tick per
hop, and a receiver gets the original message once (docs/radio.md, "Relaying").
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from numba import njit

from swarm.base.params import OMIT_DEFAULT, check_choice, check_float, check_int
from swarm.results.schema import DROP_CAUSES

from .messages import (MAP_ZLIB_LEVEL, MAX_BYTES_PER_TICK, MAX_MESSAGE_BYTES, MAX_MESSAGES_PER_TICK, MapUpdate,
                       MessageError, encode)

if TYPE_CHECKING:
    from radio.per import PacketErrorCurve

SHARING_MODES = ("delta", "full", "off", "maes", "maes_heartbeat", "maes_sync")
LINK_TIMES = ("send", "receive")
RELAY_MODES = ("none", "flood")
LOSS_CAUSES = ("link", "loss", "bandwidth", "packet_error")
"""Why one delivery failed, as :attr:`Envelope.lost` codes (indices) give it when an observer asks for them
(:attr:`Medium.note_losses`): no link (or a failed receiver), ``comm.loss``, the byte budget, a packet error
on a link above the sensitivity. The drop counts fold ``packet_error`` into ``dropped_loss`` (and a packet
error below the sensitivity is ``link``, as there), docs/comm-metrics.md."""
_LINK, _LOSS, _BANDWIDTH, _PACKET_ERROR = range(len(LOSS_CAUSES))


@dataclass(frozen=True)
class CommSpec:
    """The ``[comm]`` section of a run spec.

    ``map_sharing``: ``delta`` (default), ``full`` or ``off``, or for MAES parity ``maes_heartbeat`` /
    ``maes_sync`` (MAES's own merges, :mod:`swarm.comm.maes_merge`) or ``maes`` (the merge MAES's version of the
    run's algorithm does, at its period: see :func:`swarm.comm.maes_merge.resolve`); ``share_every`` ticks
    (MAES heartbeats every 10, MAES's TNF syncs every 20; a swarm spread over its map spends most of its time
    sharing, and sharing less often is its lever: 1,000 robots sharing every 200 ticks run in real time and
    reach 50 % explored 7 % later; 16 robots take 15-32 % longer, docs/performance.md). ``loss``: probability
    that a message is lost on each link (seeded, independent per message and receiver). ``bandwidth``: bytes
    per tick each link carries
    (0 = unlimited); what exceeds it is dropped in send order. ``neighbour_range_m``: robots within this
    range and in line of sight appear in ``Observation.neighbours`` (0 = the lidar range). ``link_at``:
    judge a message's link from the positions when it is sent (``send``, default, as a radio does) or when
    it is read a tick later (``receive``, as MAES does, docs/maes.md section 6.1). ``relay``: ``none``
    (default, as MAES: messages reach direct neighbours only) or ``flood``: every robot forwards each message
    it receives for the first time, one tick per hop, over at most ``relay_hops`` hops from the sender
    (the sender's own broadcast is hop 1, so ``relay_hops = 1`` relays nothing). ``relay_hops`` is allowed
    and unused with ``relay = "none"`` (a sweep may include both). Both are left out of the canonical form
    while at their defaults (run keys unchanged). ``map_zlib_level``: the zlib level of the map updates the
    runtime's map sharing builds (default 6; 1 compresses a 1,000-robot swarm's updates 3-7x faster into
    1.3-2.5x the bytes, 0 stores them; the bytes are results, and under a packet-error radio or a bandwidth
    cap they change what arrives: docs/radio.md). Left out of the canonical form at 6.
    """

    map_sharing: str = "delta"
    share_every: int = 10
    loss: float = 0.0
    bandwidth: int = 0
    neighbour_range_m: float = 0.0
    link_at: str = field(default="send", metadata={OMIT_DEFAULT: True})
    relay: str = field(default="none", metadata={OMIT_DEFAULT: True})
    relay_hops: int = field(default=4, metadata={OMIT_DEFAULT: True})
    map_zlib_level: int = field(default=MAP_ZLIB_LEVEL, metadata={OMIT_DEFAULT: True})

    def __post_init__(self) -> None:
        check_choice("comm.map_sharing", self.map_sharing, SHARING_MODES)
        check_choice("comm.link_at", self.link_at, LINK_TIMES)
        check_choice("comm.relay", self.relay, RELAY_MODES)
        check_int("comm.relay_hops", self.relay_hops, 1, 1000)
        check_int("comm.map_zlib_level", self.map_zlib_level, 0, 9)
        check_int("comm.share_every", self.share_every, 1, 1_000_000)
        check_float("comm.loss", self.loss, 0.0, 1.0)
        check_int("comm.bandwidth", self.bandwidth, 0)
        check_float("comm.neighbour_range_m", self.neighbour_range_m, 0.0)

    @property
    def longest_delivery_ticks(self) -> int:
        """The most ticks after it is sent that a broadcast can still reach a robot: the next tick, or flooded,
        one tick a hop (what the age-of-information snapshots must outlast, swarm.results.metrics.InfoAges)."""
        return self.relay_hops if self.relay == "flood" else 1


@dataclass
class Envelope:
    """One encoded message in flight; after delivery, ``delivered_to`` (int64) lists the robots that got it. A relayed
    copy (``comm.relay = "flood"``) keeps the original's ``sender``, ``seq``, ``data`` and ``message``; ``hop``
    counts transmissions from the sender (1: the sender's own) and ``via`` is the robot that transmits the
    copy (-1: the sender itself); ``delivered_to`` lists only robots for which it was the first copy. ``lost``
    is None unless the medium notes losses (:attr:`Medium.note_losses`, for the recorder): then it lists
    ``(receiver, cause)`` for every other robot this transmission failed to reach, ``cause`` an index into
    :data:`LOSS_CAUSES` (a relayed copy that reached a robot already holding the message is not lost)."""

    sender: int
    seq: int
    data: bytes
    message: Any
    delivered_to: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    hop: int = 1
    via: int = -1
    lost: list[tuple[int, int]] | None = None

    @property
    def transmitter(self) -> int:
        """The robot whose radio sends this copy (whose links judge it)."""
        return self.sender if self.via < 0 else self.via


@dataclass
class CommStats:
    """What the medium counted over a run; ``malformed``: messages an algorithm (or its remote agent) tried
    to send that were dropped before the radio (see :meth:`Medium.envelope`), ``malformed_by_robot`` per
    sender."""

    sent: int = 0
    bytes_sent: int = 0
    delivered: int = 0
    bytes_delivered: int = 0
    dropped_link: int = 0
    dropped_loss: int = 0
    dropped_bandwidth: int = 0
    malformed: int = 0
    map_bytes_sent: int = 0
    contact: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    """Per robot: the tick after the last one at which a message reached it (-1: never); see :attr:`last_contact`."""
    malformed_by_robot: list[int] = field(default_factory=list)
    relaying: bool = False
    relayed: int = 0
    bytes_relayed: int = 0
    duplicates: int = 0

    def as_dict(self) -> dict[str, Any]:
        """The counts as ``summary["messages"]``; ``relayed``, ``bytes_relayed`` and ``duplicates`` only when
        relaying (so runs without it keep their results bit for bit)."""
        out = {"sent": self.sent, "bytes_sent": self.bytes_sent, "delivered": self.delivered,
               "bytes_delivered": self.bytes_delivered, "dropped_link": self.dropped_link,
               "dropped_loss": self.dropped_loss, "dropped_bandwidth": self.dropped_bandwidth,
               "malformed": self.malformed, "malformed_by_robot": list(self.malformed_by_robot),
               "map_bytes_sent": self.map_bytes_sent, "last_contact": self.last_contact}
        if self.relaying:
            out.update(relayed=self.relayed, bytes_relayed=self.bytes_relayed, duplicates=self.duplicates)
        return out

    @property
    def last_contact(self) -> list[int]:
        """Per robot: the tick after the last one at which a message reached it, -1 if none has (a list)."""
        return self.contact.tolist()

    @property
    def dropped(self) -> int:
        """Messages dropped on the way, all causes (:data:`swarm.results.schema.DROP_CAUSES`)."""
        return sum(getattr(self, cause) for cause in DROP_CAUSES)

    def count_malformed(self, robot: int, n: int = 1) -> None:
        self.malformed += n
        self.malformed_by_robot[robot] += n


class Medium:
    """Carries envelopes from outboxes at tick t to inboxes at tick t+1 through the link matrix.

    Counting, per transmission (a broadcast or a relayed copy, each in ``sent`` and ``bytes_sent``), every
    other robot is exactly one of: ``delivered`` (its first copy of the message: into its inbox),
    ``duplicates`` (relaying: it had the message already, or got it from another copy this tick),
    ``dropped_link`` (out of reach: below the sensitivity, or lost to packet errors there),
    ``dropped_loss`` (within reach but lost: ``comm.loss``, or packet errors at or above the sensitivity),
    ``dropped_bandwidth``. So ``(n - 1) * sent = delivered + duplicates + dropped``.
    """

    def __init__(self, n: int, spec: CommSpec, rng: np.random.Generator,
                 map_shape: tuple[int, int] | None = None, packet_errors: PacketErrorCurve | None = None,
                 error_rng: np.random.Generator | None = None) -> None:
        """``map_shape``: the knowledge maps' shape, which every MapUpdate an algorithm sends must have.
        ``packet_errors``: the radio's PER curve (None: off), drawn from ``error_rng`` (the run's channel
        stream); ``rng`` draws ``comm.loss``."""
        self.n = n
        self.spec = spec
        self.rng = rng
        self.map_shape = tuple(map_shape) if map_shape is not None else None
        self.relaying = spec.relay == "flood"
        self.stats = CommStats(contact=np.full(n, -1, dtype=np.int64), malformed_by_robot=[0] * n,
                               relaying=self.relaying)
        self.dropped: list[tuple[int, str]] = []  # (sender, reason) of messages dropped since last read
        self.note_losses = False
        """Set by an observer that wants each envelope's failed deliveries (:attr:`Envelope.lost`); off, the
        medium does no work for them (the draws and counts are the same either way)."""
        self._seq = [0] * n
        self.packet_errors = packet_errors
        if packet_errors is not None and error_rng is None:
            raise ValueError("packet errors need their generator (error_rng)")
        self.error_rng = error_rng
        self._every = np.arange(n, dtype=np.int64)
        # Relaying: the robots holding each message still spreading ((sender, seq) -> ids), the copies each
        # robot forwards next tick, and the messages those copies carry.
        self._holders: dict[tuple[int, int], set[int]] = {}
        self._pending: list[list[Envelope]] = [[] for _ in range(n)]
        self._pending_keys: set[tuple[int, int]] = set()

    def envelope(self, sender: int, msg: Any) -> Envelope | None:
        """Encode a message an algorithm (or its remote agent) sends from ``sender``; None when it is
        malformed, counted and noted in :attr:`dropped`: its ``sender`` is not the robot (a forgery), it is
        not a registered message or does not encode, it is larger than a message may be, or it is a map
        update of another map's shape or with a corrupt payload (it would fail every receiver's merge)."""
        data = self._checked(sender, msg)
        return None if data is None else self._sealed(sender, data, msg)

    def _checked(self, sender: int, msg: Any) -> bytes | None:
        """The wire bytes of a message ``sender``'s algorithm sends, or None (counted, noted) if malformed."""
        problem = _outgoing_problem(sender, msg, self.map_shape)
        data = b""
        if problem is None:
            try:
                data = encode(msg)
            except (MessageError, TypeError, ValueError, OverflowError) as exc:
                problem = f"does not encode ({type(exc).__name__})"
            else:
                if len(data) > MAX_MESSAGE_BYTES:
                    problem = f"{len(data)} bytes, more than {MAX_MESSAGE_BYTES}"
        if problem is not None:
            self.stats.count_malformed(sender)
            self.dropped.append((sender, problem))
            return None
        return data

    def _sealed(self, sender: int, data: bytes, msg: Any) -> Envelope:
        self._seq[sender] += 1
        return Envelope(sender, self._seq[sender], data, msg)

    def outbox(self, sender: int, messages: Sequence[Any]) -> list[Envelope]:
        """The envelopes of the messages ``sender``'s algorithm sends in one tick (each checked as by
        :meth:`envelope`), within its per-tick budget: the first :data:`MAX_MESSAGES_PER_TICK` messages, as
        long as their encoded bytes stay within :data:`MAX_BYTES_PER_TICK`; the rest are dropped, counted as
        malformed and noted in :attr:`dropped` once, with their number."""
        out: list[Envelope] = []
        used = 0
        for k, msg in enumerate(messages):
            if k == MAX_MESSAGES_PER_TICK:
                self._over_budget(sender, len(messages) - k, f"more than {MAX_MESSAGES_PER_TICK} messages")
                break
            data = self._checked(sender, msg)
            if data is None:
                continue
            used += len(data)
            if used > MAX_BYTES_PER_TICK:
                self._over_budget(sender, len(messages) - k, f"more than {MAX_BYTES_PER_TICK} bytes")
                break
            out.append(self._sealed(sender, data, msg))
        return out

    def _over_budget(self, sender: int, n: int, what: str) -> None:
        self.stats.count_malformed(sender, n)
        self.dropped.append((sender, f"{n} message(s) over the per-tick budget ({what} from one robot in a tick)"))

    def service_envelope(self, sender: int, msg: Any) -> Envelope:
        """Encode a message of the runtime's own map-sharing service (built here: not checked again)."""
        data = encode(msg)
        self._seq[sender] += 1
        return Envelope(sender, self._seq[sender], data, msg)

    def deliver(self, tick: int, outboxes: Sequence[Sequence[Envelope]], link: np.ndarray,
                margin: np.ndarray | None = None) -> list[list[Envelope]]:
        """Inboxes for tick+1. ``link[i, j]``: a message transmitted by j reaches i (judged at send time);
        ``margin[i, j]``: that pair's margin in dB (-inf: cannot receive), needed with packet errors. Only the
        columns of robots with something in their outbox are read."""
        if self.packet_errors is not None or self.relaying:
            return self._deliver_channel(tick, outboxes, link, margin)
        n = self.n
        stats = self.stats
        budget = np.full((n, n), self.spec.bandwidth, dtype=np.int64) if self.spec.bandwidth else None
        note = self.note_losses
        lost = None
        delivered: list[Envelope] = []
        reached: list[np.ndarray] = []
        counts: list[int] = []
        grouped = self.spec.loss == 0.0 and budget is None  # a sender's envelopes all reach the same robots
        for j in range(n):
            if not outboxes[j]:
                continue
            in_reach = np.flatnonzero(link[:, j])
            others = in_reach[in_reach != j]  # every receiver when nothing is lost
            unreached = [(i, _LINK) for i in np.flatnonzero(~link[:, j]).tolist() if i != j] if note else []
            for env in outboxes[j]:
                size = len(env.data)
                stats.sent += 1
                stats.bytes_sent += size
                if isinstance(env.message, MapUpdate):
                    stats.map_bytes_sent += size
                receivers = in_reach
                stats.dropped_link += (n - 1) - len(receivers)
                if note:
                    lost = env.lost = list(unreached)
                targets = others
                if self.spec.loss > 0.0 and len(receivers):
                    keep = self.rng.random(len(receivers)) >= self.spec.loss
                    stats.dropped_loss += int((~keep).sum())
                    targets = receivers[keep]
                    targets = targets[targets != j]
                    if lost is not None:
                        lost.extend((i, _LOSS) for i in receivers[~keep].tolist())
                if budget is not None:
                    targets = np.array(self._within_budget(budget, targets.tolist(), j, size, lost), dtype=np.int64)
                stats.contact[targets] = tick + 1
                env.delivered_to = targets
                stats.delivered += len(targets)
                stats.bytes_delivered += size * len(targets)
                delivered.append(env)
                if not grouped:
                    reached.append(targets)
                    counts.append(1)
            if grouped:
                reached.append(others)
                counts.append(len(outboxes[j]))
        return Inboxes(n, delivered, reached, counts)

    def _deliver_channel(self, tick: int, outboxes: Sequence[Sequence[Envelope]], link: np.ndarray,
                         margin: np.ndarray | None) -> list[list[Envelope]]:
        """:meth:`deliver` with packet errors or relaying (the plain loop above is the fast path without):
        per transmission, the link or the packet-error draws, then ``comm.loss``, the byte budget, and the
        first-copy filter that feeds the next hop; inboxes sorted by (sender, sequence)."""
        n = self.n
        stats = self.stats
        inboxes: list[list[Envelope]] = [[] for _ in range(n)]
        budget = np.full((n, n), self.spec.bandwidth, dtype=np.int64) if self.spec.bandwidth else None
        log_keep = None
        if self.packet_errors is not None:
            if margin is None:
                raise ValueError("packet errors need the pairs' margins")
            log_keep = self.packet_errors.log_keep(margin)
        touched: set[tuple[int, int]] = set()
        note = self.note_losses
        lost = None
        for j in range(n):
            if not outboxes[j]:
                continue
            others = np.delete(self._every, j)  # every other robot
            linked = link[others, j]
            keep_j = log_keep[others, j] if log_keep is not None else None
            for env in outboxes[j]:
                if note:
                    lost = env.lost = []
                size = len(env.data)
                stats.sent += 1
                stats.bytes_sent += size
                if isinstance(env.message, MapUpdate):
                    stats.map_bytes_sent += size
                if env.hop > 1:
                    stats.relayed += 1
                    stats.bytes_relayed += size
                if keep_j is None:
                    reach = others[linked]
                    stats.dropped_link += (n - 1) - len(reach)
                    if lost is not None:
                        lost.extend((i, _LINK) for i in others[~linked].tolist())
                else:
                    reach = self._survive_errors(others, linked, keep_j, size, lost)
                if self.spec.loss > 0.0 and len(reach):
                    keep = self.rng.random(len(reach)) >= self.spec.loss
                    stats.dropped_loss += int((~keep).sum())
                    if lost is not None:
                        lost.extend((i, _LOSS) for i in reach[~keep].tolist())
                    reach = reach[keep]
                targets = reach.tolist()
                if budget is not None:
                    targets = self._within_budget(budget, targets, j, size, lost)
                if self.relaying:
                    targets = self._first_copies(env, targets)
                    touched.add((env.sender, env.seq))
                for i in targets:
                    inboxes[i].append(env)
                    stats.contact[i] = tick + 1
                env.delivered_to = np.array(targets, dtype=np.int64)
                stats.delivered += len(targets)
                stats.bytes_delivered += size * len(targets)
        if self.relaying:
            for key in touched - self._pending_keys:  # the flood of these messages is over
                del self._holders[key]
            for box in inboxes:
                box.sort(key=_inbox_order)
        return Inboxes.from_lists(inboxes)

    def _survive_errors(self, others: np.ndarray, linked: np.ndarray, log_keep: np.ndarray, size: int,
                        lost: list[tuple[int, int]] | None = None) -> np.ndarray:
        """The robots of ``others`` that receive a ``size``-byte transmission despite packet errors: one
        uniform draw per robot, kept when it is at least the robot's PER (``-expm1(8 size log_keep)``, as
        :meth:`radio.per.PacketErrorCurve.per`: 1 without signal, 0 far above the sensitivity). The lost are
        counted as ``dropped_link`` below the sensitivity (not ``linked``), else as ``dropped_loss``, and
        listed in ``lost`` (when given) as ``link`` or ``packet_error``."""
        assert self.error_rng is not None
        kept = np.empty(len(others), dtype=np.bool_)
        below, above = _kept_despite_errors(self.error_rng.random(len(others)), log_keep, 8.0 * size, linked, kept)
        self.stats.dropped_link += below
        self.stats.dropped_loss += above
        if lost is not None and below + above:
            failed = np.flatnonzero(~kept)
            lost.extend(zip(others[failed].tolist(), np.where(linked[failed], _PACKET_ERROR, _LINK).tolist()))
        return others[kept]

    def _first_copies(self, env: Envelope, targets: list[int]) -> list[int]:
        """Relaying: the robots of ``targets`` that get ``env``'s message for the first time (the others are
        counted as duplicates); each queues a copy to forward next tick unless the hop limit is reached."""
        key = (env.sender, env.seq)
        holders = self._holders.get(key)
        if holders is None:
            holders = self._holders[key] = {env.sender}
        new = [i for i in targets if i not in holders]
        self.stats.duplicates += len(targets) - len(new)
        holders.update(new)
        if new and env.hop < self.spec.relay_hops:
            for i in new:
                self._pending[i].append(Envelope(env.sender, env.seq, env.data, env.message, hop=env.hop + 1, via=i))
            self._pending_keys.add(key)
        return new

    def add_relays(self, outboxes: list[list[Envelope]], failed: np.ndarray) -> None:
        """Relaying: append to each robot's outbox, after its own messages, the copies it forwards this tick
        (of the messages it received first this tick); a robot that failed forwards nothing."""
        if not self._pending_keys:
            return
        flags = failed.tolist()
        kept: set[tuple[int, int]] = set()
        for i, copies in enumerate(self._pending):
            if not copies:
                continue
            if not flags[i]:
                outboxes[i].extend(copies)
                kept.update((c.sender, c.seq) for c in copies)
            self._pending[i] = []
        for key in self._pending_keys - kept:
            self._holders.pop(key, None)
        self._pending_keys = set()

    def deliveries(self, outboxes: Sequence[Sequence[Envelope]]) -> list[tuple[Any, list[int]]]:
        """A tick's delivered messages with the robots each reached, in inbox order (sender, then sequence):
        what :meth:`MapSharing.receive_tick` takes. Relayed copies of one message are one entry."""
        out = [(env.message, env.delivered_to) for box in outboxes for env in box if len(env.delivered_to)]
        if not self.relaying:
            return out
        merged: dict[tuple[int, int], tuple[Any, list[int]]] = {}
        for box in outboxes:
            for env in box:
                if len(env.delivered_to):
                    merged.setdefault((env.sender, env.seq), (env.message, []))[1].extend(env.delivered_to)
        return [(msg, sorted(ids)) for _, (msg, ids) in sorted(merged.items(), key=lambda item: item[0])]

    def _within_budget(self, budget: np.ndarray, targets: list[int], sender: int, size: int,
                       lost: list[tuple[int, int]] | None = None) -> list[int]:
        """The receivers whose link from ``sender`` still carries ``size`` bytes this tick (charged); the
        others count as dropped for bandwidth (and are listed in ``lost``, when given)."""
        kept = []
        for i in targets:
            if budget[i, sender] < size:
                self.stats.dropped_bandwidth += 1
                if lost is not None:
                    lost.append((i, _BANDWIDTH))
                continue
            budget[i, sender] -= size
            kept.append(i)
        return kept



class Inboxes(Sequence):
    """The envelopes delivered to every robot in one tick: ``inboxes[i]`` is robot i's, in inbox order
    (sender, then sequence), a read-only :class:`Inbox`.

    Held as the tick's delivered envelopes in groups that reached the same robots (a sender's whole outbox
    when nothing is lost on the way) and, per robot, the positions of its groups among them (one compiled
    pass): a swarm's sharing tick delivers about a million (envelope, receiver) pairs, which per-robot lists
    cost a million appends to build and the observations as many again to read, and a swarm that asks for
    missed updates sends tens of requests a robot to the same receivers (2,500 robots: 165 million pairs
    for 2,500 groups' 4 million)."""

    __slots__ = ("envelopes", "_starts", "_order", "_objects", "_first", "_counts", "_sizes")

    def __init__(self, n: int, envelopes: list[Envelope], receivers: list[np.ndarray],
                 counts: Sequence[int] | None = None) -> None:
        """``receivers[g]``: the robots group g reached (int64); group g is ``counts[g]`` consecutive
        envelopes (default: one each); the envelopes in inbox order."""
        self.envelopes = envelopes
        self._starts = np.zeros(n + 1, dtype=np.int64)
        if receivers:
            flat = np.concatenate(receivers) if len(receivers) > 1 else receivers[0]
            lengths = np.array([len(r) for r in receivers], dtype=np.int64)
        else:
            flat, lengths = _NO_ROBOTS, _NO_ROBOTS
        self._order = np.empty(len(flat), dtype=np.int64)
        _index_inboxes(lengths, flat.astype(np.int64, copy=False), self._starts, self._order)
        self._objects: np.ndarray | None = None
        self._counts: np.ndarray | None = None  # None: one envelope a group
        self._first = self._sizes = _NO_ROBOTS
        if counts is not None and len(counts) != len(envelopes):
            self._counts = np.asarray(counts, dtype=np.int64)
            self._first = np.cumsum(self._counts) - self._counts
            sums = np.zeros(len(self._order) + 1, dtype=np.int64)
            np.cumsum(self._counts[self._order], out=sums[1:])
            self._sizes = sums[self._starts]  # each robot's envelopes: _sizes[r + 1] - _sizes[r]

    def _positions(self, robot: int) -> np.ndarray:
        """The positions among :attr:`envelopes` of robot ``robot``'s envelopes, in inbox order."""
        groups = self._order[self._starts[robot]:self._starts[robot + 1]]
        if self._counts is None:
            return groups
        sizes = self._counts[groups]
        ends = np.cumsum(sizes)
        return np.repeat(self._first[groups] - (ends - sizes), sizes) + np.arange(ends[-1] if len(ends) else 0)

    @classmethod
    def from_lists(cls, inboxes: Sequence[Sequence[Envelope]]) -> "Inboxes":
        """The same inboxes as per-robot lists (envelopes shared by several robots once)."""
        index: dict[int, int] = {}
        envelopes: list[Envelope] = []
        reached: list[list[int]] = []
        for robot, inbox in enumerate(inboxes):
            for env in inbox:
                k = index.get(id(env))
                if k is None:
                    k = index[id(env)] = len(envelopes)
                    envelopes.append(env)
                    reached.append([])
                reached[k].append(robot)
        order = sorted(range(len(envelopes)), key=lambda k: (envelopes[k].sender, envelopes[k].seq))
        return cls(len(inboxes), [envelopes[k] for k in order],
                   [np.array(reached[k], dtype=np.int64) for k in order])

    @classmethod
    def empty(cls, n: int) -> "Inboxes":
        return cls(n, [], [])

    def __len__(self) -> int:
        return self._starts.shape[0] - 1

    def __getitem__(self, robot: int) -> "Inbox":  # type: ignore[override]
        if not -len(self) <= robot < len(self):
            raise IndexError(robot)
        robot %= len(self)
        return Inbox(self, robot)

    def __bool__(self) -> bool:
        return bool(self._order.shape[0])

    def size(self, robot: int) -> int:
        """How many envelopes robot ``robot`` received."""
        sizes = self._starts if self._counts is None else self._sizes
        return int(sizes[robot + 1] - sizes[robot])

    def messages(self, robot: int) -> tuple[Any, ...]:
        """Robot ``robot``'s messages in inbox order (what its observation carries)."""
        if self._starts[robot] == self._starts[robot + 1]:
            return ()
        if self._objects is None:
            self._objects = np.empty(len(self.envelopes), dtype=object)
            self._objects[:] = [env.message for env in self.envelopes]
        return tuple(self._objects[self._positions(robot)].tolist())


class Inbox(Sequence):
    """One robot's envelopes of a tick, in inbox order (a view into :class:`Inboxes`)."""

    __slots__ = ("_all", "_robot", "_len")

    def __init__(self, inboxes: Inboxes, robot: int) -> None:
        self._all, self._robot, self._len = inboxes, robot, inboxes.size(robot)

    def __len__(self) -> int:
        return self._len

    def __getitem__(self, k: Any) -> Any:
        positions = self._all._positions(self._robot)
        if isinstance(k, slice):
            return [self._all.envelopes[j] for j in positions[k].tolist()]
        return self._all.envelopes[int(positions[k])]

    def __iter__(self) -> Any:
        envelopes = self._all.envelopes
        return (envelopes[j] for j in self._all._positions(self._robot).tolist())

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Sequence) and list(self) == list(other)

    __hash__ = None  # type: ignore[assignment]

    def __repr__(self) -> str:
        return f"Inbox({list(self)!r})"


_NO_ROBOTS = np.zeros(0, dtype=np.int64)


@njit(cache=True)
def _index_inboxes(lengths: np.ndarray, flat: np.ndarray, starts: np.ndarray,
                   order: np.ndarray) -> None:  # pragma: no cover - compiled
    """Envelope k reached robots ``flat[sum(lengths[:k]):...]``: per robot, the positions of its envelopes
    (ascending) at ``order[starts[r]:starts[r + 1]]``. A counting sort."""
    n = starts.shape[0] - 1
    for j in range(flat.shape[0]):
        starts[flat[j] + 1] += 1
    for r in range(n):
        starts[r + 1] += starts[r]
    fill = starts[:n].copy()
    j = 0
    for k in range(lengths.shape[0]):
        for _ in range(lengths[k]):
            r = flat[j]
            order[fill[r]] = k
            fill[r] += 1
            j += 1

@njit(cache=True)
def _kept_despite_errors(u, log_keep, bits, linked, kept):  # pragma: no cover - compiled
    """``kept[k]``: the draw ``u[k]`` is at least the PER ``-expm1(bits * log_keep[k])``; returns how many were
    lost (below the sensitivity: not ``linked``, at or above it)."""
    below = 0
    above = 0
    for k in range(u.shape[0]):
        ok = u[k] >= -math.expm1(bits * log_keep[k])
        kept[k] = ok
        if not ok:
            if linked[k]:
                above += 1
            else:
                below += 1
    return below, above


def _inbox_order(env: Envelope) -> tuple[int, int]:
    return env.sender, env.seq


def _outgoing_problem(sender: int, msg: Any, shape: tuple[int, int] | None) -> str | None:
    """Why a message an algorithm sends from ``sender`` cannot go on the radio, or None."""
    claimed = getattr(msg, "sender", None)
    if isinstance(claimed, bool) or not isinstance(claimed, (int, np.integer)) or claimed != sender:
        return f"claims sender {str(claimed)[:20]}"
    if isinstance(msg, MapUpdate):
        try:
            msg.validate()
            if shape is not None and msg.shape != shape:
                return f"map update of shape {msg.shape}, the maps are {shape}"
            msg.dense() if msg.full else msg.cells()  # decoded once; receivers reuse it
        except MessageError as exc:
            return str(exc)[:100]
        except Exception as exc:  # a hand-built update with fields of the wrong types
            return f"map update with bad fields ({type(exc).__name__})"
    return None
