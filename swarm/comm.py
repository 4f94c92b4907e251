"""Communication as the runtime sees it: the radio medium, the map-sharing service, and their metrics.

**Medium.** Messages a robot broadcasts during tick t are encoded (their size is a metric), judged by the
radio's link matrix computed from positions at send time, optionally thinned by seeded packet loss and a
per-link byte budget, and appear in each receiver's inbox at tick t+1, ordered by (sender, sequence). A
robot never receives its own broadcast. (MAES judges links at receive time; we use send time, as a real
radio does, docs/design.md section 4.) Two options make the channel more than a fixed threshold: packet
errors drawn from each pair's margin (``radio.per``, :mod:`radio.per`) and multi-hop relaying
(``comm.relay = "flood"``): each robot forwards every message it hears for the first time, one tick per
hop, and a receiver gets the original message once (docs/radio.md, "Relaying").

**Map sharing** is a runtime service configured per run (``comm.map_sharing``), so every algorithm shares
maps the same way and comparisons are fair: every ``share_every`` ticks each robot broadcasts a
:class:`~swarm.messages.MapUpdate` with the cells changed since its previous update (``delta``) or its
whole map (``full``). Receivers merge updates into their own map (elementwise max) before they act. A
receiver that notices a gap in a sender's sequence numbers asks for its full map
(:class:`~swarm.messages.MapRequest`); the sender broadcasts it next tick, so deltas converge to what full
maps would give even over lossy links. A delta's cells are found by comparing the robot's map with a copy
of what its last update said, only where something was written since (its lidar windows, merged cells)
when the runtime reports its scans (``lidar_reach``), else over the whole map: the same cells either way.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Sequence

import numpy as np
from numba import njit

from maps.params import OMIT_DEFAULT, check_choice, check_float, check_int

from .api import CELL_M
from .knowledge import check_writable_map, merge_cells_many, merge_cells_many_changed, merge_cells_many_counted
from .metrics import FreeCounts, InfoAges
from .messages import MAX_MESSAGE_BYTES, MapRequest, MapUpdate, MessageError, decode, delta_update, encode, full_update
from .packed_maps import packed_copy, packed_size, sync_box_packed, sync_changes_packed
from .schema import DROP_CAUSES

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
    ``maes_sync`` (MAES's own merges, :mod:`swarm.maes_merge`) or ``maes`` (the merge MAES's version of the
    run's algorithm does, at its period: see :func:`swarm.maes_merge.resolve`); ``share_every`` ticks
    (MAES heartbeats every 10, MAES's TNF syncs every 20). ``loss``: probability that a message is lost on each link
    (seeded, independent per message and receiver). ``bandwidth``: bytes per tick each link carries
    (0 = unlimited); what exceeds it is dropped in send order. ``neighbour_range_m``: robots within this
    range and in line of sight appear in ``Observation.neighbours`` (0 = the lidar range). ``link_at``:
    judge a message's link from the positions when it is sent (``send``, default, as a radio does) or when
    it is read a tick later (``receive``, as MAES does, docs/maes.md section 6.1). ``relay``: ``none``
    (default, as MAES: messages reach direct neighbours only) or ``flood``: every robot forwards each message
    it receives for the first time, one tick per hop, over at most ``relay_hops`` hops from the sender
    (the sender's own broadcast is hop 1, so ``relay_hops = 1`` relays nothing). ``relay_hops`` is allowed
    and unused with ``relay = "none"`` (a sweep may include both). Both are left out of the canonical form
    while at their defaults (run keys unchanged).
    """

    map_sharing: str = "delta"
    share_every: int = 10
    loss: float = 0.0
    bandwidth: int = 0
    neighbour_range_m: float = 0.0
    link_at: str = field(default="send", metadata={OMIT_DEFAULT: True})
    relay: str = field(default="none", metadata={OMIT_DEFAULT: True})
    relay_hops: int = field(default=4, metadata={OMIT_DEFAULT: True})

    def __post_init__(self) -> None:
        check_choice("comm.map_sharing", self.map_sharing, SHARING_MODES)
        check_choice("comm.link_at", self.link_at, LINK_TIMES)
        check_choice("comm.relay", self.relay, RELAY_MODES)
        check_int("comm.relay_hops", self.relay_hops, 1, 1000)
        check_int("comm.share_every", self.share_every, 1, 1_000_000)
        check_float("comm.loss", self.loss, 0.0, 1.0)
        check_int("comm.bandwidth", self.bandwidth, 0)
        check_float("comm.neighbour_range_m", self.neighbour_range_m, 0.0)


@dataclass
class Envelope:
    """One encoded message in flight; after delivery, ``delivered_to`` lists the robots that got it. A relayed
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
    delivered_to: list[int] = field(default_factory=list)
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
    last_contact: list[int] = field(default_factory=list)
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
               "map_bytes_sent": self.map_bytes_sent, "last_contact": list(self.last_contact)}
        if self.relaying:
            out.update(relayed=self.relayed, bytes_relayed=self.bytes_relayed, duplicates=self.duplicates)
        return out

    @property
    def dropped(self) -> int:
        """Messages dropped on the way, all causes (:data:`swarm.schema.DROP_CAUSES`)."""
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
        self.stats = CommStats(last_contact=[-1] * n, malformed_by_robot=[0] * n, relaying=self.relaying)
        self.dropped: list[tuple[int, str]] = []  # (sender, reason) of messages dropped since last read
        self.note_losses = False
        """Set by an observer that wants each envelope's failed deliveries (:attr:`Envelope.lost`); off, the
        medium does no work for them (the draws and counts are the same either way)."""
        self._seq = [0] * n
        self.packet_errors = packet_errors
        if packet_errors is not None and error_rng is None:
            raise ValueError("packet errors need their generator (error_rng)")
        self.error_rng = error_rng
        self._others = [np.array([i for i in range(n) if i != j], dtype=np.int64) for j in range(n)]
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
        self._seq[sender] += 1
        return Envelope(sender, self._seq[sender], data, msg)

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
        inboxes: list[list[Envelope]] = [[] for _ in range(n)]
        budget = np.full((n, n), self.spec.bandwidth, dtype=np.int64) if self.spec.bandwidth else None
        note = self.note_losses
        lost = None
        for j in range(n):
            if not outboxes[j]:
                continue
            in_reach = np.flatnonzero(link[:, j])
            others = [i for i in in_reach.tolist() if i != j]  # every receiver when nothing is lost
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
                    targets = [i for i in receivers[keep].tolist() if i != j]
                    if lost is not None:
                        lost.extend((i, _LOSS) for i in receivers[~keep].tolist())
                if budget is not None:
                    targets = self._within_budget(budget, targets, j, size, lost)
                for i in targets:
                    inboxes[i].append(env)
                    stats.last_contact[i] = tick + 1
                env.delivered_to.extend(targets)
                stats.delivered += len(targets)
                stats.bytes_delivered += size * len(targets)
        return inboxes

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
            others = self._others[j]
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
                    stats.last_contact[i] = tick + 1
                env.delivered_to.extend(targets)
                stats.delivered += len(targets)
                stats.bytes_delivered += size * len(targets)
        if self.relaying:
            for key in touched - self._pending_keys:  # the flood of these messages is over
                del self._holders[key]
            for box in inboxes:
                box.sort(key=_inbox_order)
        return inboxes

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
        out = [(env.message, env.delivered_to) for box in outboxes for env in box if env.delivered_to]
        if not self.relaying:
            return out
        merged: dict[tuple[int, int], tuple[Any, list[int]]] = {}
        for box in outboxes:
            for env in box:
                if env.delivered_to:
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


class MapSharing:
    """The map-sharing service: builds each robot's MapUpdates and merges the ones it receives."""

    def __init__(self, n: int, shape: tuple[int, int], spec: CommSpec, lidar_reach: int | None = None,
                 monotone: bool = False, ages: InfoAges | None = None, free: FreeCounts | None = None) -> None:
        """``ages``: told of every update sent and of every merge that leaves a receiver holding the sender's
        whole map; ``free``: told how the merges change each map's count of FREE cells (age of information,
        docs/comm-metrics.md).

        ``lidar_reach``: the owner's promise that apart from this service's merges only a lidar writes into
        the maps, within ``lidar_reach`` cells (rows and columns) of each robot's cell, and that it reports
        every scan with :meth:`scanned` from the start. A delta then compares only the places written since the robot's
        last update (:func:`swarm.knowledge.sync_box`), not both whole maps: the same cells. Without it
        (None) every delta compares the whole maps. ``monotone``: the owner's promise that no cell of a map
        ever decreases (the ternary lidar; a log-odds lidar may turn SOLID back to FREE), which lets a
        broadcast full map reach most receivers as a delta (:meth:`_merge_full`)."""
        self.n = n
        self.spec = spec
        self.enabled = spec.map_sharing in ("delta", "full") and n > 1  # the maes modes: swarm.maes_merge
        # Each robot's map as of its last update, 2 bits a cell (swarm.packed_maps): deltas are the cells
        # that differ from it
        self.last_shared = (np.zeros((n, packed_size(shape[0] * shape[1])), dtype=np.uint8)
                            if spec.map_sharing == "delta" else None)
        self.seq = [0] * n
        self.seen_seq = [[0] * n for _ in range(n)]          # [receiver][sender] last seq merged
        self._complete = [[True] * n for _ in range(n)]      # [receiver][sender] merged each of its updates so far
        self.whole = [[True] * n for _ in range(n)]          # [receiver][sender] holds all the sender's updates
        self.monotone = monotone
        self.ages = ages
        self.free = free
        self._merges: list[tuple[np.ndarray, int, int]] = []  # this tick's (receivers, sender, sent tick): ages
        self._raised = np.zeros(0, dtype=np.int64)  # scratch: the cells a delta raised, receiver after receiver
        self.full_requested = [False] * n
        self.requests: list[list[int]] = [[] for _ in range(n)]  # targets each robot will ask next tick
        self.lidar_reach = lidar_reach if self.enabled and self.last_shared is not None else None
        # Since each robot's last update: the box of rows and columns its lidar may have written
        # (r0, r1, c0, c1; empty while r0 >= r1) and the cells merges raised (arrays).
        self._boxes = np.zeros((n, 4), dtype=np.int64)
        self._merged: list[list[np.ndarray]] = [[] for _ in range(n)]
        self._whole = [False] * n  # a full map was merged: compare the whole maps

    def scanned(self, poses: np.ndarray) -> None:
        """The lidar scanned from ``poses`` (``float64[R, 3]``) this tick: widen each robot's box of places to
        compare by its lidar window (nothing to do unless constructed with ``lidar_reach``)."""
        if self.lidar_reach is not None:
            _grow_boxes(self._boxes, np.ascontiguousarray(poses, dtype=np.float64), self.lidar_reach, CELL_M)

    def outgoing(self, tick: int, known: np.ndarray, poses: np.ndarray) -> list[list[Any]]:
        """Service messages each robot broadcasts this tick (updates due, full maps asked for, requests)."""
        out: list[list[Any]] = [[] for _ in range(self.n)]
        if not self.enabled:
            return out
        due = tick % self.spec.share_every == 0
        if not (due or any(self.full_requested) or any(self.requests)):  # most ticks
            return out
        pose_rows = poses.tolist()
        payloads: dict[bytes, tuple[bytes, bytes]] = {}  # this tick's full maps (full_update)
        for i in range(self.n):
            for target in self.requests[i]:
                out[i].append(MapRequest(sender=i, target=target))
            self.requests[i] = []
            full = self.spec.map_sharing == "full" or self.full_requested[i]
            if not (due or self.full_requested[i]):
                continue
            self.full_requested[i] = False
            if full:
                since = None
                if self.last_shared is not None and self.monotone:  # the cells since the previous update: _merge_full
                    changed = self._changed_since_update(i, known[i])  # last_shared[i] becomes known[i]
                    since = (self.seq[i], changed, known[i].reshape(-1)[changed])
                elif self.last_shared is not None:
                    self.last_shared[i] = packed_copy(known[i])
                    self._forget_writes(i)
                self.seq[i] += 1
                update = full_update(i, self.seq[i], tick, known[i], tuple(pose_rows[i]), payloads)
                update.__dict__["_since"] = since  # this process's note (see _take); never on the wire
                out[i].append(update)
                continue
            assert self.last_shared is not None
            changed = self._changed_since_update(i, known[i])  # ascending, as delta_update wants them
            if len(changed):
                self.seq[i] += 1
                update = delta_update(i, self.seq[i], tick, known[i], tuple(pose_rows[i]), changed)
                update.__dict__["_since"] = None  # built here (see _take): never on the wire
                out[i].append(update)
        if self.ages is not None:
            self.ages.sent(tick)
        return out

    def _changed_since_update(self, i: int, known: np.ndarray) -> np.ndarray:
        """Robot i's cells that differ from its last update, copied into ``last_shared[i]``."""
        assert self.last_shared is not None
        if self.lidar_reach is None or self._whole[i]:
            self._forget_writes(i)
            return sync_changes_packed(known, self.last_shared[i])
        merged = self._merged[i]
        extra = merged[0] if len(merged) == 1 else np.concatenate(merged) if merged else _NO_CELLS
        changed = sync_box_packed(known, self.last_shared[i], self._boxes[i], extra)
        self._forget_writes(i)
        return changed

    def _forget_writes(self, i: int) -> None:
        """Robot i's map equals its last update: nothing written since."""
        self._boxes[i] = _EMPTY_BOX
        self._merged[i] = []
        self._whole[i] = False

    def receive(self, receiver: int, messages: Sequence[Any], known: np.ndarray,
                tick: int = 0) -> list[np.ndarray | None]:
        """Handle one receiver's service messages of a tick: merge every MapUpdate and note MapRequests
        addressed to it. Returns, per merged update, the flat indices it carried (None for a full map: any
        cell may have changed). Other messages are left to the algorithm. ``tick``: now (for :attr:`ages`)."""
        for msg in messages:
            if isinstance(msg, MapUpdate) and msg.shape != known.shape:
                raise MessageError(f"map_update: shape {msg.shape} does not match the receiver's {known.shape}")
        if any(isinstance(msg, MapUpdate) for msg in messages):
            check_writable_map(known)
        touched: list[np.ndarray | None] = []
        stack, rows = known[np.newaxis], np.zeros(1, dtype=np.int64)
        robot = np.array([receiver], dtype=np.int64)
        for msg in messages:
            self._take(msg, [receiver], stack, rows, [touched], robot)
        if self.ages is not None:
            self.ages.merged(self._merges, tick)
        self._merges = []
        return touched

    def receive_tick(self, deliveries: Sequence[tuple[Any, Sequence[int]]], known: np.ndarray,
                     live: np.ndarray, cells: bool = True, tick: int = 0) -> list[list[np.ndarray | None]]:
        """:meth:`receive` for every robot at once: ``deliveries`` are a tick's messages with the robots each
        reached, in the order the inboxes list them (sender, then sequence), and ``known`` the maps
        (``uint8[R, H, W]``); robots not ``live`` are left alone. The same effect and the same lists as
        calling :meth:`receive` per robot with its inbox, but each map update is merged into all its
        receivers in one compiled call (a long many-robot run merges a great many). ``cells=False``: the lists
        stay empty (the in-process runtime does not read them). ``tick``: now (for :attr:`ages`)."""
        check_writable_map(known)
        touched: list[list[np.ndarray | None]] = [[] for _ in range(self.n)]
        flags = live.tolist()
        for msg, receivers in deliveries:
            if not isinstance(msg, (MapUpdate, MapRequest)):
                continue
            ids = [r for r in receivers if flags[r]]
            if not ids:
                continue
            if isinstance(msg, MapUpdate) and msg.shape != known.shape[1:]:
                raise MessageError(f"map_update: shape {msg.shape} does not match the receiver's {known.shape[1:]}")
            lists = [touched[r] for r in ids] if cells else None
            rows = np.array(ids, dtype=np.int64)
            self._take(msg, ids, known, rows, lists, rows)
        if self.ages is not None:
            self.ages.merged(self._merges, tick)
        self._merges = []
        return touched

    def _take(self, msg: Any, ids: list[int], stack: np.ndarray, rows: np.ndarray,
              lists: list[list[np.ndarray | None]] | None, robots: np.ndarray) -> None:
        """One service message reaching robots ``ids`` (``robots``: the same as an array), whose maps are
        ``stack[rows]`` (checked): merge a
        MapUpdate into each, note what it wrote for their next deltas, append the cells it carried (None for
        a full map) to ``lists[k]`` for robot ``ids[k]`` (unless None) and book its sequence number; or note
        a MapRequest addressed to one of them. Notes for :attr:`ages` which of them now hold the sender's
        whole map: all after a full map; after a delta, those that merged every earlier update of the sender
        since their last full map of it (a gap leaves a receiver partial until the full map it asks for)."""
        if isinstance(msg, MapRequest):
            if msg.target in ids:
                self.full_requested[msg.target] = True
            return
        if not isinstance(msg, MapUpdate):
            return
        tracking = self.lidar_reach is not None
        sender, seq = msg.sender, msg.seq
        ours = "_since" in msg.__dict__  # built by this service, not sent by an algorithm
        whole: list[int] = []  # the receivers that now hold the sender's whole map (for ages)
        everyone = len(ids)
        if msg.full:
            carried = self._merge_full(msg, ids, stack, rows)
            if self.free is not None:
                self.free.dirty[robots] = True  # counted afresh when next read
        else:
            idx, values = msg.cells()  # int64 and uint8, in range: checked when decoded
            if ours and tracking:  # the common case: merged and its receivers' books kept in one tight loop
                ids, at, whole = self._take_delta(ids, stack, rows, robots, idx, values, sender, seq, lists)
                lists = None if lists is None else [lists[k] for k in at]
            elif self.free is not None:
                merge_cells_many_counted(stack, rows, idx, values, robots, self.free.freed)
            else:
                merge_cells_many(stack, rows, idx, values)
            carried = [idx] * len(ids)
        delta_gap = not msg.full and self.spec.map_sharing == "delta"
        if lists is not None:
            for cells, into in zip(carried, lists):
                into.append(cells)
        for r, cells in zip(ids, carried):
            if tracking:
                if cells is None:
                    self._whole[r] = True  # any cell may have changed: the next delta compares all
                else:
                    self._merged[r].append(cells)
            seen = self.seen_seq[r]
            last = seen[sender]
            if delta_gap and seq != last + 1 and sender not in self.requests[r]:
                self.requests[r].append(sender)
            if not ours or msg.full or seq != last + 1:  # an update an algorithm sent counts as a gap
                self._complete[r][sender] = ours and msg.full
            holds = self.whole[r]
            if msg.full:
                holds[sender] = True
                whole.append(r)
            elif seq == last + 1:
                if holds[sender]:
                    whole.append(r)
            elif seq > last:
                holds[sender] = False  # a gap: partial until the full map it asks for
            seen[sender] = seq if msg.full else max(last, seq)
        if whole:  # (the order of the receivers does not matter: swarm.metrics.InfoAges.merged)
            self._merges.append((robots if len(whole) == everyone else np.array(whole, dtype=np.int64), sender,
                                 msg.tick))

    def _take_delta(self, ids: list[int], stack: np.ndarray, rows: np.ndarray, robots: np.ndarray,
                    idx: np.ndarray, values: np.ndarray, sender: int, seq: int,
                    lists: list[list[np.ndarray | None]] | None) -> tuple[list[int], list[int], list[int]]:
        """Merge this service's delta ``seq`` from ``sender`` (cells ``idx``) into robots ``ids`` (``robots``
        as an array; maps ``stack[rows]``), counting their FREE cells for :attr:`free`, and keep the books of
        every receiver that had merged the sender's previous update: the cells the merge raised in its map
        are listed for its next delta (and in ``lists``) and the update becomes its last merged one; nothing
        else changes. Returns the other receivers and their positions in ``ids`` (a gap or an old update:
        :meth:`_take`'s general rules), and the receivers booked here that now hold the sender's whole map
        (for :attr:`ages`). Each delta reaches up to n - 1 robots, so this runs n^2 times a sharing tick: it
        keeps to what that case needs, and lists only what changed (robots that share maps mostly know what
        they hear already), which the receivers' next deltas then compare (docs/performance-history.md)."""
        need = len(ids) * len(idx)
        if self._raised.shape[0] < need:
            self._raised = np.empty(2 * need, dtype=np.int64)
        ends = np.empty(len(ids), dtype=np.int64)
        merge_cells_many_changed(stack, rows, idx, values, self._raised, ends,
                                 robots, None if self.free is None else self.free.freed)
        raised = self._raised
        merged, seen_seq, holds = self._merged, self.seen_seq, self.whole
        gapped: list[int] = []
        rest: list[int] = []
        whole: list[int] = []
        before, start = seq - 1, 0
        for k, (r, end) in enumerate(zip(ids, ends.tolist())):
            seen = seen_seq[r]
            if seen[sender] == before:
                seen[sender] = seq
                if holds[r][sender]:
                    whole.append(r)
                if end > start:
                    cells = raised[start:end].copy()
                    merged[r].append(cells)
                    if lists is not None:
                        lists[k].append(cells)
            else:
                gapped.append(k)
                rest.append(r)
            start = end
        return rest, gapped, whole

    def _merge_full(self, msg: MapUpdate, ids: list[int], stack: np.ndarray,
                    rows: np.ndarray) -> list[np.ndarray | None]:
        """Merge a full map into robots ``ids`` (maps ``stack[rows]``); per receiver, the cells the merge may
        have changed (None: any). A full map this service built in delta mode on monotone maps notes the cells
        where it differs from its sender's previous update (``outgoing``). A receiver that merged every update
        of the sender up to that one already holds at least the previous update everywhere (merges take
        maxima and no cell decreases), so taking just those cells gives the same map: a broadcast full map
        then costs its receivers a delta's work instead of the whole map's each, which grew with the square of
        the team (docs/performance-history.md)."""
        since = msg.__dict__.get("_since")
        quick: list[int] = []
        if since is not None:
            prev, cells, values = since
            sender = msg.sender
            quick = [k for k, r in enumerate(ids) if self._complete[r][sender] and self.seen_seq[r][sender] == prev]
        carried: list[np.ndarray | None] = [None] * len(ids)
        if quick:
            merge_cells_many(stack, rows[quick], cells, values)
            for k in quick:
                carried[k] = cells
        if len(quick) < len(ids):
            dense = msg.dense()
            for k, row in enumerate(rows.tolist()):
                if carried[k] is None:
                    flat = stack[row].reshape(-1)
                    np.maximum(flat, dense, out=flat)
            # The decoded map would live as long as the message (inboxes, queued deliveries): 360 KB on a
            # 300-tile map, 10 MB of a 64-robot run's peak. A later delivery of it decodes again.
            msg.__dict__.pop("_dense", None)
        return carried


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


_NO_CELLS = np.zeros(0, dtype=np.int64)
_EMPTY_BOX = np.array([0, 0, 0, 0], dtype=np.int64)


@njit(cache=True)
def _grow_boxes(boxes: np.ndarray, poses: np.ndarray, reach: int, cell: float) -> None:  # pragma: no cover
    """Widen each robot's box (r0, r1, c0, c1) by the window of ``reach`` cells around its cell; the cell is
    truncated as the runtime's other lidar windows take it (``int(y / cell)``)."""
    for k in range(poses.shape[0]):
        r = np.int64(poses[k, 1] / cell)
        c = np.int64(poses[k, 0] / cell)
        if boxes[k, 0] >= boxes[k, 1]:  # empty: start from this window
            boxes[k, 0], boxes[k, 1], boxes[k, 2], boxes[k, 3] = r - reach, r + reach + 1, c - reach, c + reach + 1
        else:
            boxes[k, 0] = min(boxes[k, 0], r - reach)
            boxes[k, 1] = max(boxes[k, 1], r + reach + 1)
            boxes[k, 2] = min(boxes[k, 2], c - reach)
            boxes[k, 3] = max(boxes[k, 3], c + reach + 1)


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


def decode_or_none(data: bytes) -> Any:
    """Decode a message from an untrusted source; None if malformed."""
    try:
        return decode(data)
    except MessageError:
        return None
