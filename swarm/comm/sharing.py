"""The map-sharing service: each robot's map updates, built and merged.

**Map sharing** is a runtime service configured per run (``comm.map_sharing``), so every algorithm shares
maps the same way and comparisons are fair: every ``share_every`` ticks each robot broadcasts a
:class:`~swarm.comm.messages.MapUpdate` with the cells changed since its previous update (``delta``) or its
whole map (``full``). Receivers merge updates into their own map (elementwise max) before they act. A
receiver that notices a gap in a sender's sequence numbers asks for its full map
(:class:`~swarm.comm.messages.MapRequest`); the sender broadcasts it next tick, so deltas converge to what full
maps would give even over lossy links. A delta's cells are found by comparing the robot's map with a copy
of what its last update said, only where something was written since (its lidar windows, merged cells)
when the runtime reports its scans (``lidar_reach``), else over the whole map: the same cells either way.
"""

from __future__ import annotations

from collections import deque
from typing import Any, Callable, Sequence

import numpy as np
from numba import njit

from swarm.base.errors import InvalidInput
from swarm.base.types import CELL_M
from swarm.knowledge.maps import (check_writable_map, mark_tiles, merge_cells_many, merge_cells_many_changed,
                                  merge_cells_many_counted, merge_delta_booked_kernel as _merge_delta_booked)
from swarm.knowledge.cellcodec import pack2, values_at2
from swarm.knowledge.packed import (packed_copy, packed_size, rising_cells, sync_box_tiles_packed,
                                    sync_changes_packed)
from swarm.knowledge.planes import (KnowledgePlanes, book_receivers, merge_into_many, merge_into_many_tiled,
                                    note_cells, note_map)
from swarm.knowledge.tiles import TiledLayout, sync_tiles_packed
from swarm.results.metrics import FreeCounts, InfoAges
from swarm.util.memory import lazy_zeros

from .medium import CommSpec
from .messages import MapRequest, MapUpdate, MessageError, delta_update, full_update


HISTORY_UPDATES = 8
"""How many of its latest updates each robot remembers the cells of, so that a full map it broadcasts reaches
a receiver that missed some of them as the cells of those updates (:meth:`MapSharing._merge_full`)."""
HISTORY_CELLS = 16_384
"""...and at most this many cells in all (int64: 128 KB a robot); a receiver further behind takes the whole map."""
CATCH_UP = True
"""Merge a full map into a receiver that missed a few of its sender's updates as just their cells (exact on
monotone maps; off: such receivers take the sender's whole map, as before; the tests compare both)."""

RISING_ONLY = True
"""Merge a full map into a receiver that takes all of it by reading first where it holds more than the
receiver's last update (:meth:`MapSharing._merge_rising`; exact on monotone maps; off: every known cell of
the map is merged, as before; the tests compare both)."""

DROP_DECODED_CELLS = 4096
"""A delta of this many cells or more drops its decoded cells and plain bytes once merged into all its
receivers (the zlib payload stays: a later reader, such as a recorder's journal, decodes it again)."""

TILE = 32
"""Merges note the places they changed in a robot's map as tiles of TILE x TILE cells, which its next delta
compares with its last update."""


class MapSharing:
    """The map-sharing service: builds each robot's MapUpdates and merges the ones it receives."""

    def __init__(self, n: int, shape: tuple[int, int], spec: CommSpec, lidar_reach: int | None = None,
                 monotone: bool = False, ages: InfoAges | None = None, free: FreeCounts | None = None,
                 planes: KnowledgePlanes | None = None, layout: TiledLayout | None = None,
                 written: Any = None, dense: Callable[[int], np.ndarray] | None = None) -> None:
        """``ages``: told of every update sent and of every merge that leaves a receiver holding the sender's
        whole map; ``free``: told how the merges change each map's count of FREE cells (age of information,
        docs/comm-metrics.md).

        ``lidar_reach``: the owner's promise that apart from this service's merges only a lidar writes into
        the maps, within ``lidar_reach`` cells (rows and columns) of each robot's cell, and that it reports
        every scan with :meth:`scanned` from the start. A delta then compares only the places written since the robot's
        last update (:func:`swarm.knowledge.maps.sync_box`), not both whole maps: the same cells. Without it
        (None) every delta compares the whole maps. ``monotone``: the owner's promise that no cell of a map
        ever decreases (the ternary lidar; a log-odds lidar may turn SOLID back to FREE), which lets a
        broadcast full map reach most receivers as a delta (:meth:`_merge_full`). ``planes``: the maps'
        knowledge planes (:mod:`swarm.knowledge.planes`), which every merge then goes through: an update
        costs a few words a cell for all its receivers, and writes only the maps it raises. ``layout``: the
        maps are a tiled stack of this layout (:mod:`swarm.knowledge.tiles`), which needs the planes; the
        copies of the last updates are then kept in the same tiled order, and ``written(robots, cells)`` is
        told of every merge (:meth:`swarm.knowledge.tiles.TiledKnowledge.note_cells`). ``dense(i)``: robot i's
        tiled map as a row-major array, copied from the tiles it may have written
        (:meth:`swarm.knowledge.tiles.TiledKnowledge.dense`), for the full maps it sends; without it the whole
        map is untiled (50 ms on a 2,000-tile building, once per robot asked for its map)."""
        self.n = n
        self.shape = (int(shape[0]), int(shape[1]))
        self._narrow_cells = shape[0] * shape[1] < 2**31  # history cells kept as int32 (half the memory)
        self.layout = layout
        self.written = written
        self.dense = dense
        if layout is not None and (planes is None or layout.shape != self.shape):
            raise InvalidInput("layout", "tiled maps", "dense maps unless knowledge planes are kept (64 robots or "
                               "more, the ternary lidar, swarm map sharing)")
        cells = shape[0] * shape[1] if layout is None else layout.size
        self.planes = planes
        self.spec = spec
        self.enabled = spec.map_sharing in ("delta", "full") and n > 1  # the maes modes: swarm.comm.maes_merge
        # Each robot's map as of its last update, 2 bits a cell (swarm.knowledge.packed): deltas are the cells
        # that differ from it
        self.last_shared = (lazy_zeros((n, packed_size(cells)), np.uint8)
                            if spec.map_sharing == "delta" else None)
        self.seq = [0] * n
        # Each robot's latest updates (seq, the cells that changed since the one before), oldest first, and
        # [receiver, sender] -> the last update of the sender it had merged in an unbroken run when it missed
        # one (it holds at least the sender's map as of that update): see _merge_full
        self._history: list[deque[tuple[int, np.ndarray]]] = [deque() for _ in range(n)]
        self._history_cells = [0] * n
        self._gapped: dict[int, dict[int, int]] = {}  # sender -> {receiver: a}
        # [receiver, sender]: the last update merged; merged each of the sender's updates so far; holds all of
        # them (arrays, so that a delta's receivers are booked in the compiled merge: a swarm's sharing round
        # books n^2 of them)
        self.seen_seq = np.zeros((n, n), dtype=np.int32)
        self._complete = np.ones((n, n), dtype=np.bool_)
        self.whole = np.ones((n, n), dtype=np.bool_)
        self.monotone = monotone
        self.ages = ages
        self.free = free
        self._merges: list[tuple[np.ndarray, int, int]] = []  # this tick's (receivers, sender, sent tick): ages
        self._raised = np.zeros(0, dtype=np.int64)  # scratch: the cells a delta raised, receiver after receiver
        self.full_requested = [False] * n
        self.requests: list[list[int]] = [[] for _ in range(n)]  # targets each robot will ask next tick
        self.lidar_reach = lidar_reach if self.enabled and self.last_shared is not None else None
        # Since each robot's last update: the box of rows and columns its lidar may have written
        # (r0, r1, c0, c1; empty while r0 >= r1) and the tiles of TILE x TILE cells in which merges raised
        # cells (a byte each; a list of the cells themselves held a swarm's whole relayed news per robot)
        self._boxes = np.zeros((n, 4), dtype=np.int64)
        tiles = (-(-shape[0] // TILE), -(-shape[1] // TILE))
        self._dirty = lazy_zeros((n, *tiles), np.uint8) if self.lidar_reach is not None else None
        self._whole = np.zeros(n, dtype=np.bool_)  # a full map was merged: compare the whole maps
        self._rest = np.empty(n, dtype=np.int64)   # scratch of the compiled delta merge: receivers it did not book
        self._held = np.empty(n, dtype=np.int64)   # and those it booked that hold the sender's whole map
        # This tick's decoded full maps, by payload object (and shape): robots whose maps converged send the
        # very same payload (messages.full_update), which each message's far-behind receivers would decode
        self._decoded: dict[tuple[int, tuple[int, int], str], tuple[bytes, Any]] = {}
        # receive_tick's count of the full maps still to merge per payload object: a decoded map is kept only
        # while another message of the tick carries it (10,000 robots' distinct repairs held 30,000 cells each)
        self._uses: dict[int, int] | None = None

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
        payloads: dict[tuple[int, int, int], tuple[np.ndarray, bytes | None, bytes, int]] = {}  # this tick's full
        # maps (full_update; each keyed packed map is a row of last_shared, which only its robot's turn changes)
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
                    values, history = self._values(known[i], changed), tuple(self._history[i])
                    # the note holds the history's (narrow) copy of the cells: a swarm asked for its full maps
                    # held a second, int64 copy per robot until delivered (1.2 GB at 10,000 robots)
                    since = (self.seq[i], self._remember(i, self.seq[i] + 1, changed), values, history)
                else:
                    self._history[i].clear()  # no note of the cells: the history would have a hole
                    self._history_cells[i] = 0
                    if self.last_shared is not None:
                        self.last_shared[i] = packed_copy(known[i])
                        self._forget_writes(i)
                self.seq[i] += 1
                packed = None if self.last_shared is None else self.last_shared[i]  # known[i], packed
                wire = None
                if self.layout is not None:  # the wire's map is row-major: built only for a new payload
                    def wire(i=i, mine=known[i]):
                        rows = self.dense(i) if self.dense is not None else self.layout.untile(mine)
                        return pack2(rows.reshape(-1))
                update = full_update(i, self.seq[i], tick, known[i], tuple(pose_rows[i]), payloads, packed,
                                     wire=wire, shape=self.shape, level=self.spec.map_zlib_level)
                update.__dict__["_since"] = since  # this process's note (see _take); never on the wire
                out[i].append(update)
                continue
            assert self.last_shared is not None
            changed = self._changed_since_update(i, known[i])  # ascending, as delta_update wants them
            if len(changed):
                self.seq[i] += 1
                self._remember(i, self.seq[i], changed)
                update = delta_update(i, self.seq[i], tick, known[i], tuple(pose_rows[i]), changed,
                                      values=None if self.layout is None else self._values(known[i], changed),
                                      shape=self.shape, level=self.spec.map_zlib_level)
                update.__dict__["_since"] = None  # built here (see _take): never on the wire
                if self.layout is not None and len(changed) >= DROP_DECODED_CELLS:
                    # a swarm's round (tiled maps): its receivers decompress the payload once (zlib, ~0.1 ms)
                    # rather than every large delta keeping its plain bytes until delivered (10,000 robots:
                    # 550 MB at the round's peak)
                    update.__dict__.pop("_plain", None)
                out[i].append(update)
        if self.ages is not None and any(isinstance(m, MapUpdate) for msgs in out for m in msgs):
            self.ages.sent(tick)  # (a tick of requests only: nothing for a snapshot to serve)
        return out

    def _remember(self, i: int, seq: int, changed: np.ndarray) -> np.ndarray:
        """Note robot i's update ``seq`` and the cells it changed (as int32 on maps under 2^31 cells: a
        10,000-robot swarm's histories took 1.3 GB as int64), dropping the oldest beyond
        :data:`HISTORY_UPDATES` or :data:`HISTORY_CELLS`. Returns the cells as kept (read only)."""
        history = self._history[i]
        kept = changed.astype(np.int32) if self._narrow_cells else changed
        history.append((seq, kept))
        self._history_cells[i] += len(changed)
        while history and (len(history) > HISTORY_UPDATES or self._history_cells[i] > HISTORY_CELLS):
            self._history_cells[i] -= len(history.popleft()[1])
        return kept

    def _changed_since_update(self, i: int, known: np.ndarray) -> np.ndarray:
        """Robot i's cells that differ from its last update, copied into ``last_shared[i]``."""
        assert self.last_shared is not None
        if self.layout is not None:
            whole = self.lidar_reach is None or self._whole[i]
            changed = sync_tiles_packed(known, self.last_shared[i], self.layout, None if whole else self._boxes[i],
                                        None if whole else self._dirty[i], TILE)
            self._forget_writes(i)
            return changed
        if self.lidar_reach is None or self._whole[i]:
            self._forget_writes(i)
            return sync_changes_packed(known, self.last_shared[i])
        assert self._dirty is not None
        changed = sync_box_tiles_packed(known, self.last_shared[i], self._boxes[i], self._dirty[i], TILE)
        self._forget_writes(i)
        return changed

    def _forget_writes(self, i: int) -> None:
        """Robot i's map equals its last update: nothing written since."""
        self._boxes[i] = _EMPTY_BOX
        if self._dirty is not None:
            self._dirty[i] = 0
        self._whole[i] = False

    def receive(self, receiver: int, messages: Sequence[Any], known: np.ndarray,
                tick: int = 0) -> list[np.ndarray | None]:
        """Handle one receiver's service messages of a tick: merge every MapUpdate and note MapRequests
        addressed to it. Returns, per merged update, the flat indices it carried (None for a full map: any
        cell may have changed). Other messages are left to the algorithm. ``tick``: now (for :attr:`ages`)."""
        if self.layout is not None:
            raise InvalidInput("known", "tiled maps", "receive_tick (the runtime's), not receive, for tiled maps")
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
        if self.planes is not None:  # merged map by map here: bring the receiver's bits up to date
            note_map(self.planes.free, self.planes.solid, known.reshape(-1), receiver)
        if self.ages is not None:
            self.ages.merged(self._merges, tick)
        self._merges = []
        self._decoded.clear()
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
        everyone_live = bool(live.all())
        self._uses = {}
        for msg, _ in deliveries:
            if isinstance(msg, MapUpdate) and msg.full:
                self._uses[id(msg.payload)] = self._uses.get(id(msg.payload), 0) + 1
        for msg, receivers in deliveries:
            if not isinstance(msg, (MapUpdate, MapRequest)):
                continue
            rows = np.asarray(receivers, dtype=np.int64)
            if not everyone_live:
                rows = rows[live[rows]]
            if isinstance(msg, MapRequest):  # only its target acts on it (a swarm sends tens a robot a tick)
                self._note_request(msg, rows)
                continue
            if not len(rows):
                continue
            if isinstance(msg, MapUpdate) and msg.shape != self.shape:
                raise MessageError(f"map_update: shape {msg.shape} does not match the receiver's {self.shape}")
            ids = rows.tolist()
            lists = [touched[r] for r in ids] if cells else None
            self._take(msg, ids, known, rows, lists, rows)
        if self.ages is not None:
            self.ages.merged(self._merges, tick)
        self._merges = []
        self._decoded.clear()
        self._uses = None
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
            self._note_request(msg, robots)
            return
        if not isinstance(msg, MapUpdate):
            return
        tracking = self.lidar_reach is not None
        sender, seq = msg.sender, msg.seq
        ours = "_since" in msg.__dict__  # built by this service, not sent by an algorithm
        whole: list[int] = []  # the receivers that now hold the sender's whole map (for ages)
        everyone = len(ids)
        if msg.full:
            quick, caught = self._merge_full(msg, ids, stack, rows)
            self._merged_payload(msg)
            if self.free is not None:
                self.free.dirty[robots] = True  # counted afresh when next read
            if lists is None:  # the books of every receiver at once (a swarm's full map reaches hundreds)
                self._book_full(msg, robots, quick, caught, self.shape[1], ours)
                return
            since = _wide(msg.__dict__["_since"][1]) if quick.any() else None
            carried = [since if q else None for q in quick.tolist()]
            for members, cells in caught:
                for k in np.flatnonzero(members).tolist():
                    carried[k] = cells
        else:
            idx, values = msg.cells()  # int64 and uint8, in range: checked when decoded
            if ours and tracking:  # the common case: merged and its receivers' books kept in one tight loop
                ids, at, whole = self._take_delta(ids, stack, rows, robots, idx, values, sender, seq, lists)
                lists = None if lists is None else [lists[k] for k in at]
            elif self._planes_for(stack) is not None:
                self._into_many(stack, robots, idx, values,
                                _NO_CELLS if self.free is None else self.free.freed, _NO_DIRTY, TILE)
            elif self.free is not None:
                merge_cells_many_counted(stack, rows, idx, values, robots, self.free.freed)
            else:
                merge_cells_many(stack, rows, idx, values)
            carried = [idx] * len(ids)
            if len(idx) >= DROP_DECODED_CELLS:  # merged into every receiver: let go of the decoded and plain
                msg.__dict__.pop("_cells", None)  # copies (a 10,000-robot round held gigabytes of them until
                msg.__dict__.pop("_plain", None)  # the messages left the inboxes); a later reader decodes again
        delta_gap = not msg.full and self.spec.map_sharing == "delta"
        if lists is not None:
            for cells, into in zip(carried, lists):
                into.append(cells)
        for r, cells in zip(ids, carried):
            if tracking:
                if cells is None:
                    self._whole[r] = True  # any cell may have changed: the next delta compares all
                elif len(cells):
                    mark_tiles(self._dirty[r], cells, self.shape[1], TILE)
            last = int(self.seen_seq[r, sender])
            if delta_gap and seq != last + 1 and sender not in self.requests[r]:
                self.requests[r].append(sender)
            if not ours or msg.full or seq != last + 1:  # an update an algorithm sent counts as a gap
                if not ours or msg.full:
                    self._gapped.get(sender, _NONE_GAPPED).pop(r, None)
                elif self._complete[r, sender]:  # the first update it missed: it holds the sender's map as of
                    self._gapped.setdefault(sender, {})[r] = last  # `last` (merges take maxima) until a full
                                                                  # map (_merge_full)
                self._complete[r, sender] = ours and msg.full
            if msg.full:
                self.whole[r, sender] = True
                whole.append(r)
            elif seq == last + 1:
                if self.whole[r, sender]:
                    whole.append(r)
            elif seq > last:
                self.whole[r, sender] = False  # a gap: partial until the full map it asks for
            self.seen_seq[r, sender] = seq if msg.full else max(last, seq)
        if whole:  # (the order of the receivers does not matter: swarm.results.metrics.InfoAges.merged)
            self._merges.append((robots if len(whole) == everyone else np.array(whole, dtype=np.int64), sender,
                                 msg.tick))

    def _note_request(self, msg: MapRequest, robots: np.ndarray) -> None:
        """A map request reached ``robots``: its target, if among them, broadcasts its full map next tick.
        (Checked on the array: a swarm's robot sends tens of requests a tick to a thousand receivers.)"""
        if np.count_nonzero(robots == msg.target):
            self.full_requested[msg.target] = True

    def _take_delta(self, ids: list[int], stack: np.ndarray, rows: np.ndarray, robots: np.ndarray,
                    idx: np.ndarray, values: np.ndarray, sender: int, seq: int,
                    lists: list[list[np.ndarray | None]] | None) -> tuple[list[int], list[int], list[int]]:
        """Merge this service's delta ``seq`` from ``sender`` (cells ``idx``) into robots ``ids`` (``robots``
        as an array; maps ``stack[rows]``), counting their FREE cells for :attr:`free`, noting the tiles where
        it raised cells for their next deltas, and keep the books of every receiver that had merged the
        sender's previous update: the update becomes its last merged one (and the cells it raised are listed
        in ``lists``, for a host with mirrors); nothing else changes. Returns the other receivers and their
        positions in ``ids`` (a gap or an old update: :meth:`_take`'s general rules), and the receivers booked
        here that now hold the sender's whole map (for :attr:`ages`). Each delta reaches up to n - 1 robots,
        so this runs n^2 times a sharing round: merge and books are one compiled call
        (docs/performance-history.md)."""
        assert self._dirty is not None
        freed = self.free.freed if self.free is not None else _NO_CELLS
        planes = self._planes_for(stack)
        if lists is None:
            if planes is not None:
                self._into_many(stack, robots, idx, values, freed,
                                self._dirty, TILE)
                n_rest, n_held = book_receivers(robots, self.seen_seq, self.whole, sender, seq, self._rest,
                                                self._held)
            else:
                n_rest, n_held = _merge_delta_booked(stack, rows, robots, idx, values, freed, self.seen_seq,
                                                     self.whole, sender, seq, self._dirty, TILE, self._rest,
                                                     self._held)
            gapped = self._rest[:n_rest].tolist()
            return [ids[k] for k in gapped], gapped, self._held[:n_held].tolist()
        need = len(ids) * len(idx)
        if self._raised.shape[0] < need:
            self._raised = np.empty(2 * need, dtype=np.int64)
        ends = np.empty(len(ids), dtype=np.int64)
        merge_cells_many_changed(stack, rows, idx, values, self._raised, ends,
                                 robots, None if self.free is None else self.free.freed)
        raised = self._raised
        gapped: list[int] = []
        rest: list[int] = []
        whole: list[int] = []
        before, start = seq - 1, 0
        for k, (r, end) in enumerate(zip(ids, ends.tolist())):
            if end > start:
                cells = raised[start:end].copy()
                mark_tiles(self._dirty[r], cells, self.shape[1], TILE)
                if planes is not None:
                    note_cells(planes.free, planes.solid, stack[r].reshape(-1), r, cells)
            if self.seen_seq[r, sender] == before:
                self.seen_seq[r, sender] = seq
                if self.whole[r, sender]:
                    whole.append(r)
                if end > start:
                    lists[k].append(cells)
            else:
                gapped.append(k)
                rest.append(r)
            start = end
        return rest, gapped, whole

    def _planes_for(self, stack: np.ndarray) -> KnowledgePlanes | None:
        """The planes, when the merge is into the maps they mirror (every robot's: :meth:`receive_tick`)."""
        return self.planes if self.planes is not None and stack.shape[0] == self.n else None

    def _merge_full(self, msg: MapUpdate, ids: list[int], stack: np.ndarray,
                    rows: np.ndarray) -> tuple[np.ndarray, list[tuple[np.ndarray, np.ndarray]]]:
        """Merge a full map into robots ``ids`` (maps ``stack[rows]``). Returns per receiver whether the merge
        took only the cells since the sender's previous update (``msg``'s ``_since`` note), and the groups
        (receivers as a mask over ``ids``, cells) that took only the cells of the few updates they missed;
        every other receiver may have changed anywhere.

        A full map this service built in delta mode on monotone maps notes the cells where it differs from
        its sender's previous update, and the cells of the updates before (``outgoing``). A receiver that
        merged every update of the sender up to the previous one already holds at least that update
        everywhere (merges take maxima and no cell decreases), so taking just those cells gives the same map:
        a broadcast full map then costs its receivers a delta's work instead of the whole map's each, which
        grew with the square of the team (docs/performance-history.md). The same holds for a receiver that
        missed a few updates (it asked for this map): it holds the sender's map as of the last update it
        merged in an unbroken run, so the cells of the updates since are all it can lack, read from this
        map (a swarm's gap repairs were most of a 1,000-robot run once its robots had explored much).
        The other receivers take the sender's known cells, which are all that can raise theirs: in a swarm
        (with knowledge planes) only those cells are merged, so a map is written (and its memory taken,
        swarm.util.memory) only where it changes; in a team the whole decoded map is, which costs less than
        listing its known cells."""
        since = msg.__dict__.get("_since")
        robots = np.asarray(rows, dtype=np.int64)
        quick = np.zeros(len(ids), dtype=np.bool_)
        caught: list[tuple[np.ndarray, np.ndarray]] = []
        rest = np.ones(len(ids), dtype=np.bool_)
        planes = self._planes_for(stack)
        if since is not None:
            prev, cells, values, history = since
            cells = _wide(cells)
            if stack.shape[0] == self.n:  # the receivers' books are their rows (receive_tick)
                quick = self._complete[robots, msg.sender] & (self.seen_seq[robots, msg.sender] == prev)
            else:
                quick = np.array([self._complete[r, msg.sender] and self.seen_seq[r, msg.sender] == prev
                                  for r in ids], dtype=np.bool_)
            rest &= ~quick
            if quick.any():
                self._merge_cells(stack, planes, robots[quick], cells, values)
            if CATCH_UP and history and rest.any():
                caught = self._catch_up(msg, ids, stack, robots, rest, prev, cells, history, planes)
                for members, _ in caught:
                    rest &= ~members
        if rest.any():
            others = robots[rest]
            sent = self._sent_packed(msg) if planes is not None and RISING_ONLY else None
            if sent is not None:  # a swarm, the map still the sender's copy: only the cells each receiver lacks
                self._merge_rising(stack, others, sent)
            elif planes is not None:  # a swarm: the sender's known cells, so only the pages they raise are written
                known_cells, known_values = self._decode(msg, "known")
                self._into_many(stack, others, known_cells, known_values,
                                _NO_CELLS, _NO_DIRTY, TILE)
            else:  # a team: the whole decoded map, cheaper than listing its known cells
                dense = self._decode(msg, "dense")
                for row in others.tolist():
                    flat = stack[row].reshape(-1)
                    np.maximum(flat, dense, out=flat)
            # The decoded map or cells would live as long as the message (inboxes, queued deliveries); a later
            # delivery of it decodes again.
            msg.__dict__.pop("_known", None)
            msg.__dict__.pop("_dense", None)
        return quick, caught

    def _sent_packed(self, msg: MapUpdate) -> np.ndarray | None:
        """The 2-bit copy of full map ``msg`` this service keeps (its sender's ``last_shared`` row, which is the
        map sent while the sender has built no update since: its sequence number is the message's, and
        ``last_shared[sender]`` changes only with a new update), or None: a map an algorithm sent, or a later
        one."""
        if ("_since" in msg.__dict__ and self.last_shared is not None and self.seq[msg.sender] == msg.seq
                and msg.shape == self.shape):
            return self.last_shared[msg.sender]
        return None

    def _merge_rising(self, stack: np.ndarray, robots: np.ndarray, sent: np.ndarray) -> None:
        """Merge the full map whose 2-bit copy is ``sent`` into each of ``robots``
        (their rows of the whole ``stack``, through the planes), reading only the cells where it holds more
        than the receiver's last update (:func:`swarm.knowledge.packed.rising_cells`): the receiver's map
        holds at least that update (maps only rise), so no other cell can rise. The same maps as merging
        every known cell, which a robot meeting its sender for the first time did (~700,000 cells at 1,000
        robots on 600 tiles, most of them already held once the swarm's maps converge)."""
        assert self.last_shared is not None
        cells = np.empty(4 * len(sent), dtype=np.int64)  # room for every cell (resident only where written)
        values = np.empty(4 * len(sent), dtype=np.uint8)
        for r in robots.tolist():
            k = rising_cells(sent, self.last_shared[r], cells, values)
            if not k:
                continue
            one = np.array([r], dtype=np.int64)
            if self.layout is None:
                self._into_many(stack, one, cells[:k], values[:k], _NO_CELLS, _NO_DIRTY, TILE)
            else:  # the copies are in tiled order: the planes and books take row-major cells
                offsets = cells[:k]
                self._into_many(stack, one, self.layout.cells(offsets), values[:k], _NO_CELLS, _NO_DIRTY, TILE,
                                offsets=offsets)

    def _decode(self, msg: MapUpdate, kind: str) -> Any:
        """``msg.known_cells()`` (kind "known") or ``msg.dense()``, decoded once per payload in a tick: the same
        payload object holds the same map (it is immutable bytes, kept alive here while the key is in use)."""
        key = (id(msg.payload), msg.shape, kind)
        hit = self._decoded.get(key)
        if hit is not None and hit[0] is msg.payload:
            return hit[1]
        value = msg.known_cells() if kind == "known" else msg.dense()
        if self._uses is None or self._uses.get(id(msg.payload), 0) > 1:  # another message of the tick has it
            self._decoded[key] = (msg.payload, value)
        return value

    def _merged_payload(self, msg: MapUpdate) -> None:
        """Full map ``msg`` is merged: once no other message of the tick carries its payload, forget its
        decoding (receive_tick; :meth:`receive` keeps them to the end of its call)."""
        if self._uses is None:
            return
        left = self._uses.get(id(msg.payload), 0) - 1
        if left > 0:
            self._uses[id(msg.payload)] = left
            return
        self._uses.pop(id(msg.payload), None)
        for kind in ("known", "dense"):
            hit = self._decoded.get((id(msg.payload), msg.shape, kind))
            if hit is not None and hit[0] is msg.payload:
                del self._decoded[(id(msg.payload), msg.shape, kind)]

    def _merge_cells(self, stack: np.ndarray, planes: KnowledgePlanes | None, robots: np.ndarray,
                     cells: np.ndarray, values: np.ndarray) -> None:
        """Merge ``values`` at ``cells`` (ascending) into the maps of ``robots`` (their rows of ``stack``)."""
        if planes is not None:
            self._into_many(stack, robots, cells, values, _NO_CELLS,
                            _NO_DIRTY, TILE)
        else:
            merge_cells_many(stack, robots, cells, values)

    def _catch_up(self, msg: MapUpdate, ids: list[int], stack: np.ndarray, robots: np.ndarray, rest: np.ndarray,
                  prev: int, cells: np.ndarray, history: tuple[tuple[int, np.ndarray], ...],
                  planes: KnowledgePlanes | None) -> list[tuple[np.ndarray, np.ndarray]]:
        """:meth:`_merge_full` for the receivers in ``rest`` that missed some of the sender's updates after
        an unbroken run up to update ``a`` (the last they merged, or ``_gapped`` once they noticed the gap)
        still in the sender's ``history`` (its updates up to
        ``prev``, oldest first, each with the cells it changed; ``cells``: those since ``prev``): each takes
        the union of the cells of updates ``a + 1`` .. ``msg.seq`` with this map's values there. Returns the
        groups that did, one per ``a``."""
        first = history[0][0]
        if history[-1][0] != prev:
            return []
        groups: dict[int, list[int]] = {}
        sender = msg.sender
        gapped = self._gapped.get(sender, _NONE_GAPPED)
        for k in np.flatnonzero(rest).tolist():
            r = ids[k]
            a = int(self.seen_seq[r, sender]) if self._complete[r, sender] else gapped.get(r)
            if a is not None and first - 1 <= a < prev:
                groups.setdefault(a, []).append(k)
        if not groups:
            return []
        out = []
        values_at = self._full_values(msg)
        union, upto = cells, prev  # the cells of updates upto + 1 .. msg.seq, grown from the nearest group back
        steps = dict(history)
        for a in sorted(groups, reverse=True):
            while upto > a:
                union = union_sorted(union, steps[upto])
                upto -= 1
            members = np.zeros(len(ids), dtype=np.bool_)
            members[groups[a]] = True
            self._merge_cells(stack, planes, robots[members], union, values_at(union))
            out.append((members, union))
        out.reverse()  # furthest behind first, as before
        return out

    def _into_many(self, stack: np.ndarray, robots: np.ndarray, idx: np.ndarray, values: np.ndarray,
                   counts: np.ndarray, dirty: np.ndarray, tile: int, offsets: np.ndarray | None = None) -> None:
        """:func:`swarm.knowledge.planes.merge_into_many` into the maps of ``robots`` in ``stack``, dense or
        tiled (then the owner's ``written`` hook hears which robots may have changed which cells; ``offsets``:
        where cells ``idx`` sit in a tiled map, when the caller has them)."""
        assert self.planes is not None
        mask = self.planes.mask(robots)
        if self.layout is None:
            merge_into_many(stack, self.planes.free, self.planes.solid, mask, idx, values, counts, dirty, tile)
        else:
            at = self.layout.offsets(idx) if offsets is None else offsets
            merge_into_many_tiled(stack, self.shape[1], at, self.planes.free, self.planes.solid, mask, idx, values,
                                  counts, dirty, tile)
            if self.written is not None:
                self.written(robots, idx)

    def _values(self, known: np.ndarray, cells: np.ndarray) -> np.ndarray:
        """Robot's map ``known`` (dense, or flat tiled) at row-major ``cells``."""
        if self.layout is None:
            return known.reshape(-1)[cells]
        return known[self.layout.offsets(cells)]

    def _full_values(self, msg: MapUpdate) -> Any:
        """How to read full map ``msg``'s values at given cells (a map this service built): from its sender's
        packed copy while that still holds the map sent (:meth:`_sent_packed`), else from the message's bytes
        (a swarm's full maps keep only their zlib payload: each read would decompress a megabyte)."""
        packed = self._sent_packed(msg)
        if packed is not None:
            if self.layout is not None:
                return lambda cells: values_at2(packed, self.layout.offsets(cells))
            return lambda cells: values_at2(packed, cells)
        return msg.values_at

    def _book_full(self, msg: MapUpdate, robots: np.ndarray, quick: np.ndarray,
                   caught: list[tuple[np.ndarray, np.ndarray]], width: int, ours: bool) -> None:
        """:meth:`_take`'s books after a full map reached ``robots`` (``quick``: those that took only the
        cells since the sender's previous update; ``caught``: groups that took the cells of the updates they
        missed), for every receiver at once: a quick or caught-up one's next delta compares the tiles of those
        cells, another one's the whole map; each now holds the sender's whole map, has merged its update
        ``msg.seq`` and is complete unless an algorithm sent the map."""
        sender = msg.sender
        if self.lidar_reach is not None:
            narrow = quick.copy()
            for members, _ in caught:
                narrow |= members
            self._whole[robots[~narrow]] = True
            if quick.any():
                self._mark_cells(robots[quick], msg.__dict__["_since"][1], width)
            for members, cells in caught:
                self._mark_cells(robots[members], cells, width)
        gapped = self._gapped.get(sender)
        if gapped:  # (a few receivers; a swarm's full map reaches hundreds)
            waiting = np.fromiter(gapped, dtype=np.int64, count=len(gapped))
            for r in waiting[np.isin(waiting, robots)].tolist():
                del gapped[r]
        self._complete[robots, sender] = ours
        self.whole[robots, sender] = True
        self.seen_seq[robots, sender] = msg.seq
        self._merges.append((robots, sender, msg.tick))

    def _mark_cells(self, robots: np.ndarray, cells: np.ndarray, width: int) -> None:
        """Note the tiles of ``cells`` as written in the maps of ``robots`` (for their next deltas)."""
        assert self._dirty is not None
        if len(cells):
            rows, cols = np.divmod(_wide(cells), width)
            tiles = np.unique((rows // TILE) * self._dirty.shape[2] + cols // TILE)
            tr, tc = np.divmod(tiles, self._dirty.shape[2])
            self._dirty[robots[:, None], tr[None, :], tc[None, :]] = 1

_NO_CELLS = np.zeros(0, dtype=np.int64)
_NONE_GAPPED: dict[int, int] = {}  # (read only)
_NO_DIRTY = np.zeros((0, 1, 1), dtype=np.uint8)
_EMPTY_BOX = np.array([0, 0, 0, 0], dtype=np.int64)


def _wide(cells: np.ndarray) -> np.ndarray:
    """``cells`` as int64 (a history's cells are int32 on maps under 2^31 cells; the merges take int64)."""
    return cells if cells.dtype == np.int64 else cells.astype(np.int64)


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


@njit(cache=True)
def union_sorted(a: np.ndarray, b: np.ndarray) -> np.ndarray:  # pragma: no cover - compiled
    """The ascending distinct union of two ascending distinct int64 arrays, in one pass (the cells of a sender's
    missed updates: each update's cells are sorted)."""
    out = np.empty(a.shape[0] + b.shape[0], dtype=np.int64)
    i = j = m = 0
    while i < a.shape[0] and j < b.shape[0]:
        if a[i] < b[j]:
            out[m] = a[i]
            i += 1
        elif b[j] < a[i]:
            out[m] = b[j]
            j += 1
        else:
            out[m] = a[i]
            i += 1
            j += 1
        m += 1
    while i < a.shape[0]:
        out[m] = a[i]
        i += 1
        m += 1
    while j < b.shape[0]:
        out[m] = b[j]
        j += 1
        m += 1
    return out[:m]
