"""Batched packets: one ``obs_batch`` and one ``act_batch`` per tick for all the agents of one process.

The per-robot packets (:mod:`swarm.transport.wire`) cost a put, a msgpack frame and a Python decode per
robot and tick on each side; for the 16 agents of the benchmark that was most of the zenoh transport's
overhead (docs/performance-history.md). Agents that share the runtime's process are served instead by
one ``obs_batch`` put per tick, answered by one ``act_batch`` put (docs/wire-format.md, "Batched
packets"). A batch is columns, not 16 packets in a row: the robots' ids, the per-robot counts, the
state records, the changed map cells, the neighbour records, the inbox as references into one table of
distinct messages (a broadcast heard by 15 robots travels once). A compiled pass writes the columns on
the runtime's side and another checks them all on the agents' side before any map is touched, so a
batch costs two puts and a few array passes whatever the number of robots.

Every check the per-robot decoders make is made here (field types and sizes, nav states and flags, map
cells inside the map with values 0..2, finite goals and velocities, message references inside the table,
messages decoded one by one); a bad batch raises :class:`~swarm.transport.wire.WireError`, a bad message
is dropped and counted.
"""

from __future__ import annotations

import math
import struct
from functools import lru_cache
from typing import Any, NamedTuple, Sequence

import numpy as np
from numba import njit

from swarm.base.types import Action, NavStatus, frozen_builder
from swarm.comm.messages import MAX_BYTES_PER_TICK, MessageError, decode, encode
from swarm.knowledge.cellcodec import get_u32, put_raw_cells
from .bearings import _bearing
from .packing import OBS_STATE_DTYPE
from .wire import (COLLIDED, HAS_GOAL, MAX_PACKET_BYTES, NAV_STATES, NEIGHBOUR, NEIGHBOUR_DTYPE, OBS_STATE, WIRE_VERSION,
                   WireError, _NAV_INDEX, _pack, _unpack)

OBS_BATCH, ACT_BATCH = "obs_batch", "act_batch"
COUNTS = 3
"""Per-robot counts of an ``obs_batch``, in this order: changed cells, inbox messages, neighbours."""
CELLS, INBOX, NEIGHBOURS = range(COUNTS)

ACT_FIXED = struct.Struct("<4dB")
"""An ``act_batch`` record per robot: goal x, goal y, velocity v, omega (float64), flags (uint8)."""
ACT_GOAL, ACT_VELOCITY, ACT_CLEAR_GOAL, ACT_EXTRAS, ACT_RUNS, ACT_STRAIGHT = 1, 2, 4, 8, 16, 32
ACT_FLAGS = ACT_GOAL | ACT_VELOCITY | ACT_CLEAR_GOAL | ACT_EXTRAS | ACT_RUNS | ACT_STRAIGHT
_DRIVE_FLAG = {"path": 0, "runs": ACT_RUNS, "straight": ACT_STRAIGHT}
"""``Action.drive`` as flags (neither: "path"; a record with both is malformed)."""


def _drive(flags: int) -> str:
    return "straight" if flags & ACT_STRAIGHT else "runs" if flags & ACT_RUNS else "path"

_action = frozen_builder(Action)
_tuple_new = tuple.__new__


# ------------------------------------------------------------------------------------ obs_batch ----
_NAV_NUMBERS = struct.Struct("<3d3q")
"""A robot's navigator numbers as the batch writer reads them: goal x, goal y, path length (float64), ticks
since progress, state index, goal flag (int64)."""


class BatchEncoder:
    """Writes a tick's ``obs_batch`` for a fixed set of robots from the runtime's arrays (the
    :class:`~swarm.transport.base.TickBatch` columns). Keeps each robot's last :class:`NavStatus` with its
    numbers, so the Python side of a tick is an identity check per robot, and its buffers from tick to tick."""

    def __init__(self, robots: Sequence[int], n_robots: int) -> None:
        self.robots = np.array(sorted(robots), dtype=np.int64)
        self._robot_list = self.robots.tolist()
        self._all = self._robot_list == list(range(n_robots))
        self._navs: list[NavStatus | None] = [None] * n_robots
        self._nav_buf = bytearray(_NAV_NUMBERS.size * n_robots)
        self._nav = np.frombuffer(self._nav_buf, dtype=np.uint8)  # the numbers, written by struct, read by the kernel
        m = len(self.robots)
        self._ids = np.zeros(m, dtype="<u4")
        self._counts = np.zeros((m, COUNTS), dtype="<u4")
        self._states = np.zeros(m, OBS_STATE_DTYPE)
        self._neighbours = np.zeros(m * n_robots, NEIGHBOUR_DTYPE)
        self._cells = np.zeros(1024, dtype=np.uint8)
        self._last_ids: tuple[bytes, list[int]] = (b"", [])

    def _note_navs(self, navs: Sequence[NavStatus | None]) -> None:
        seen, buf, size = self._navs, self._nav_buf, _NAV_NUMBERS.size
        for i in self._robot_list:
            nav = navs[i]
            if nav is not seen[i] and nav is not None:
                seen[i] = nav
                goal = nav.goal
                gx, gy = goal if goal is not None else (0.0, 0.0)
                _NAV_NUMBERS.pack_into(buf, size * i, gx, gy, nav.path_length, nav.ticks_since_progress,
                                       _NAV_INDEX[nav.state], HAS_GOAL if goal is not None else 0)

    def __call__(self, tick: int, live: np.ndarray, poses: np.ndarray, collided: np.ndarray, travelled: np.ndarray,
                 energy: np.ndarray, navs: Sequence[NavStatus | None], known: np.ndarray, cells: np.ndarray,
                 ends: np.ndarray, inboxes: Sequence[Sequence[Any]], near: np.ndarray,
                 distance: np.ndarray) -> tuple[bytes | None, list[int]]:
        """The batch for this encoder's robots that are ``live`` and the ids it carries (None and [] when
        none is). Arguments as :class:`~swarm.transport.packing.ObsEncoder` takes them; ``inboxes[i]`` are
        robot i's envelopes (``.data``: a message's wire bytes; one envelope object per broadcast)."""
        self._note_navs(navs)
        if len(self._cells) < 5 * len(cells):
            self._cells = np.zeros(2 * 5 * len(cells), dtype=np.uint8)
        m, n_cells, n_near = _write_columns(tick, self.robots, live, poses, collided, travelled, energy, self._nav,
                                            known, cells, ends, near, distance, self._ids, self._counts, self._states,
                                            self._cells, self._neighbours)
        if m == 0:
            return None, []
        ids_b = self._ids[:m].tobytes()
        if ids_b != self._last_ids[0]:
            self._last_ids = (ids_b, self._ids[:m].tolist())
        ids = self._last_ids[1]
        refs, table = b"", _NO_TABLE
        if any(inboxes) if self._all else any(inboxes[i] for i in ids):  # most ticks no message arrives
            refs, table = _inbox_refs(ids, inboxes, self._counts)
        packet = _pack([OBS_BATCH, WIRE_VERSION, tick, ids_b, self._counts[:m].tobytes(), self._states[:m].tobytes(),
                        self._cells[:5 * n_cells].tobytes(), self._neighbours[:n_near].tobytes(), refs, table])
        return packet, ids


_NO_TABLE: list[bytes] = []


def _inbox_refs(ids: list[int], inboxes: Sequence[Sequence[Any]], counts: np.ndarray) -> tuple[bytes, list[bytes]]:
    """The ``inbox`` column (uint32 references into the message table, robot after robot) and the table:
    each distinct message once, in order of first reference. Counts go into ``counts[:, INBOX]``."""
    where: dict[int, int] = {}
    table: list[bytes] = []
    refs: list[int] = []
    for k, i in enumerate(ids):
        inbox = inboxes[i]
        counts[k, INBOX] = len(inbox)
        for env in inbox:
            at = where.get(id(env))
            if at is None:
                at = where[id(env)] = len(table)
                table.append(env.data)
            refs.append(at)
    return struct.pack(f"<{len(refs)}I", *refs), table


@njit(cache=True)
def _write_columns(tick, robots, live, poses, collided, travelled, energy, nav, known, cells, ends, near, distance,
                   ids, counts, states, cell_buf, neighbours):  # pragma: no cover - compiled
    """Fill the columns for the live robots of ``robots`` (ascending ids): ids, per-robot counts (cells,
    neighbours; the inbox count 0, the caller's to set), state records, changed cells (uint32 gaps from
    0, then the values, robot after robot) and neighbour records. ``nav``: the robots' _NAV_NUMBERS
    records, back to back. Returns (robots written, cells, neighbours)."""
    n = poses.shape[0]
    flat = known.reshape(n, -1)
    nav_f = nav.view(np.float64)
    nav_i = nav.view(np.int64)
    m = 0
    c = 0
    q = 0
    for i in robots:
        if not live[i]:
            continue
        ids[m] = i
        s = states[m]
        s["x"] = poses[i, 0]
        s["y"] = poses[i, 1]
        s["theta"] = poses[i, 2]
        s["goal_x"] = nav_f[6 * i]
        s["goal_y"] = nav_f[6 * i + 1]
        s["path_length"] = nav_f[6 * i + 2]
        s["travelled"] = travelled[i]
        s["energy"] = energy[i]
        s["stalled"] = nav_i[6 * i + 3]
        s["nav"] = nav_i[6 * i + 4]
        s["flags"] = nav_i[6 * i + 5] | (COLLIDED if collided[i] else 0)
        first = ends[i - 1] if i > 0 else 0
        last = ends[i]
        k = last - first
        counts[m, CELLS] = k
        counts[m, INBOX] = 0
        put_raw_cells(cell_buf, 5 * c, cells, first, last, flat[i])
        c += k
        seen = 0
        for j in range(n):
            if near[i, j]:
                r = neighbours[q]
                r["id"] = j
                r["distance"] = distance[i, j]
                r["bearing"] = _bearing(poses[i, 0], poses[i, 1], poses[i, 2], poses[j, 0], poses[j, 1])
                r["x"] = poses[j, 0]
                r["y"] = poses[j, 1]
                q += 1
                seen += 1
        counts[m, NEIGHBOURS] = seen
        m += 1
    return m, c, q


class ObsBatch(NamedTuple):
    """A decoded ``obs_batch`` (checked): per robot of ``ids``, row k of each column."""

    tick: int
    ids: tuple[int, ...]
    states: list[tuple]              # OBS_STATE fields per robot
    state_bytes: bytes               # the same records as they came
    counts: np.ndarray | None        # uint32[m * COUNTS]: the counts column (None when no cell changed)
    cells: np.ndarray | None         # uint8: the cells column (gaps then values per robot); None if empty
    inbox: list[tuple[int, ...]]     # per robot: indices into ``messages`` (shared: read only)
    messages: list[bytes]
    near: tuple[int, ...]            # per robot: how many NEIGHBOUR records it has in ``neighbours``
    neighbours: bytes                # the records of every robot, one robot after another


def _u32s(n: int) -> struct.Struct:
    """The struct of ``n`` little-endian uint32 (cached: a batch reads three columns with it)."""
    fmt = _U32.get(n)
    if fmt is None:
        fmt = _U32[n] = struct.Struct(f"<{n}I")
    return fmt


_U32: dict[int, struct.Struct] = {}
_STATE, _NAV_AT, _FLAGS_AT = OBS_STATE.size, OBS_STATE.size - 2, OBS_STATE.size - 1
_COLUMN_TYPES = (bytes,) * 6


class ObsBatchDecoder:
    """Decodes the ``obs_batch`` packets of a run of ``n_robots`` robots with maps of ``map_cells`` cells,
    every field checked (:func:`apply_cells` then writes the cells); raises WireError. Columns are read
    with struct and bytes operations, the cells with one compiled pass: numpy's per-call cost on a column
    of 16 values is more than the work. The robot ids, checked once, are kept while they stay the same
    bytes (every tick while no robot fails)."""

    __slots__ = ("n_robots", "map_cells", "_ids", "_limit")

    def __init__(self, n_robots: int, map_cells: int) -> None:
        self.n_robots = n_robots
        self.map_cells = map_cells
        self._ids: tuple[bytes, tuple[int, ...]] = (b"", ())
        # The batch carries the tick's inbox messages once: up to every robot's per-tick budget on top of
        # a packet's usual limit, so one agent's outbox (issue 48) cannot make it too large for the others.
        self._limit = MAX_PACKET_BYTES + n_robots * MAX_BYTES_PER_TICK

    def __call__(self, data: bytes) -> ObsBatch:
        _, _, tick, ids_b, counts_b, states_b, cells_b, near_b, refs_b, messages = _unpack(data, OBS_BATCH, 8,
                                                                                          self._limit)
        if type(tick) is not int or tick < 0:
            raise WireError("obs_batch: tick must be a non-negative integer")
        if tuple(map(type, (ids_b, counts_b, states_b, cells_b, near_b, refs_b))) != _COLUMN_TYPES:
            raise WireError("obs_batch: ids, counts, states, cells, neighbours and inbox must be byte strings")
        if type(messages) is not list or (messages and not all(type(b) is bytes for b in messages)):
            raise WireError("obs_batch: messages must be a list of byte strings")
        m = len(ids_b) >> 2
        if not m or len(ids_b) != 4 * m or len(counts_b) != 4 * COUNTS * m or len(states_b) != _STATE * m:
            raise WireError("obs_batch: ids, counts and states must hold the same number of robots (at least one)")
        if ids_b == self._ids[0]:
            ids = self._ids[1]
        else:
            ids = _u32s(m).unpack(ids_b)
            if ids[-1] >= self.n_robots or any(a >= b for a, b in zip(ids, ids[1:])):
                raise WireError("obs_batch: robot ids not ascending or outside the run")
            self._ids = (ids_b, ids)
        counts = _u32s(COUNTS * m).unpack(counts_b)
        n_cells, n_inbox = sum(counts[CELLS::COUNTS]), sum(counts[INBOX::COUNTS])
        n_near = sum(counts[NEIGHBOURS::COUNTS])
        if len(cells_b) != 5 * n_cells or len(refs_b) != 4 * n_inbox or len(near_b) != NEIGHBOUR.size * n_near:
            raise WireError("obs_batch: the cells, inbox or neighbours column does not match its counts")
        if (max(states_b[_NAV_AT::_STATE]) >= len(NAV_STATES)
                or max(states_b[_FLAGS_AT::_STATE]) & ~(COLLIDED | HAS_GOAL)):
            raise WireError("obs_batch: unknown nav state or flags")
        counts_a = cells = None
        if n_cells:
            counts_a = np.frombuffer(counts_b, dtype="<u4")
            cells = np.frombuffer(cells_b, dtype=np.uint8)
            problem = _check_cells(cells, counts_a, self.map_cells)
            if problem:
                raise WireError(_CELL_PROBLEMS[problem])
        inbox: list[tuple[int, ...]] = _no_inboxes(m)
        if n_inbox:
            refs = _u32s(n_inbox).unpack(refs_b)
            if max(refs) >= len(messages):
                raise WireError("obs_batch: inbox refers past the message table")
            inbox = list(inbox)
            at = 0
            for k, n in enumerate(counts[INBOX::COUNTS]):
                inbox[k] = refs[at:at + n]
                at += n
        return _tuple_new(ObsBatch, (tick, ids, list(OBS_STATE.iter_unpack(states_b)), states_b, counts_a, cells, inbox,
                                     messages, counts[NEIGHBOURS::COUNTS] if n_near else _no_near(m), near_b))


@lru_cache(maxsize=None)
def _no_inboxes(m: int) -> list[tuple[int, ...]]:
    return [()] * m


@lru_cache(maxsize=None)
def _no_near(m: int) -> tuple[int, ...]:
    return (0,) * m


def decode_obs_batch(data: bytes, n_robots: int, map_cells: int) -> ObsBatch:
    """One ``obs_batch``, checked (see :class:`ObsBatchDecoder`, which a group keeps to decode its own)."""
    return ObsBatchDecoder(n_robots, map_cells)(data)


_CELL_PROBLEMS = ("", "obs_batch: map cell value other than unseen, free or solid",
                  "obs_batch: map cells outside the map or not ascending")


@njit(cache=True)
def _check_cells(cells, counts, map_cells):  # pragma: no cover - compiled
    """0 if every robot's cells (``counts[COUNTS k]`` of them, robot after robot) are ascending (non-zero
    gaps after the first), inside the map and of values 0..2; else 1 (a value) or 2 (an index)."""
    c = 0
    for k in range(counts.shape[0] // COUNTS):
        n = np.int64(counts[COUNTS * k])
        base = 5 * c
        for j in range(n):
            if cells[base + 4 * n + j] > 2:
                return 1
        at = np.int64(0)
        for j in range(n):
            gap = get_u32(cells, base + 4 * j)
            if j > 0 and gap == 0:
                return 2
            at += gap
        if n and at >= map_cells:
            return 2
        c += n
    return 0


def apply_cells(batch: ObsBatch, rows: np.ndarray, maps: np.ndarray) -> None:
    """Write each robot's changed cells into its map ``maps[rows[k]]`` (``uint8[M, H, W]``; ``rows``
    int64[m]) for robot ``batch.ids[k]``: a checked batch, cells inside the map with values 0..2."""
    if batch.cells is not None:
        _apply_cells(maps.reshape(maps.shape[0], -1), rows, batch.counts, batch.cells)


@njit(cache=True)
def _apply_cells(maps, rows, counts, cells):  # pragma: no cover - compiled
    c = 0
    for k in range(rows.shape[0]):
        n = np.int64(counts[COUNTS * k])
        base = 5 * c
        at = 0
        flat = maps[rows[k]]
        for j in range(n):
            at += get_u32(cells, base + 4 * j)
            flat[at] = cells[base + 4 * n + j]
        c += n


# ------------------------------------------------------------------------------------ act_batch ----
class ActBatchEncoder:
    """Writes the ``act_batch`` answering an ``obs_batch``. A robot whose algorithm returns the very
    :class:`Action` object of its last tick (algorithms keep one while their goal stands) gets its last
    record again, without reading the action's fields: most ticks every record is reused."""

    def __init__(self) -> None:
        self._last: dict[int, tuple[Action, bytes]] = {}
        self._ids: tuple[tuple[int, ...], bytes] = ((), b"")

    def __call__(self, tick: int, ids: Sequence[int], actions: Sequence[Action]) -> bytes:
        """The batch for robots ``ids``; ``actions[k]`` is robot ``ids[k]``'s."""
        if tuple(ids) != self._ids[0]:
            self._ids = (tuple(ids), _u32s(len(ids)).pack(*ids))
        last = self._last
        records = []
        extras: list[list[Any]] = []
        for robot, action in zip(ids, actions):
            seen = last.get(robot)
            if seen is not None and seen[0] is action:
                records.append(seen[1])
                continue
            record, extra = _act_record(action)
            records.append(record)
            if extra is None:
                last[robot] = (action, record)
            else:
                extras.append(extra)
                last.pop(robot, None)
        return _pack([ACT_BATCH, WIRE_VERSION, tick, self._ids[1], b"".join(records), extras])


def _act_record(action: Action) -> tuple[bytes, list[Any] | None]:
    """An action's ACT_FIXED record and its extras entry (None without messages or debug)."""
    goal, velocity = action.goal, action.velocity
    flags = (ACT_CLEAR_GOAL if action.clear_goal else 0) | _DRIVE_FLAG[action.drive]
    gx = gy = v = w = 0.0
    if goal is not None:
        gx, gy = goal
        flags |= ACT_GOAL
    if velocity is not None:
        v, w = velocity
        flags |= ACT_VELOCITY
    messages, debug = action.messages, action.debug
    extra = None
    if messages or debug is not None:
        flags |= ACT_EXTRAS
        extra = [[encode(msg) for msg in messages] if messages else [], dict(debug) if debug is not None else None]
    return ACT_FIXED.pack(gx, gy, v, w, flags), extra


def encode_act_batch(tick: int, ids: Sequence[int], actions: Sequence[Action]) -> bytes:
    """The ``act_batch`` answering an ``obs_batch`` of robots ``ids`` (see :class:`ActBatchEncoder`, which a
    group keeps)."""
    return ActBatchEncoder()(tick, ids, actions)


class ActBatchDecoder:
    """Decodes the ``act_batch`` answering each tick's ``obs_batch``, checked. Reuses a robot's previous
    :class:`Action` while its record is the same bytes and carries no messages (most ticks): the action
    is frozen and equal, and building it was most of the decoding."""

    def __init__(self) -> None:
        self._last: dict[int, tuple[bytes, Action]] = {}
        self._batch: tuple[bytes, bytes, list[tuple[Action | None, int]]] = (b"", b"", [])
        self._ids: tuple[Sequence[int] | None, bytes] = (None, b"")

    def __call__(self, data: bytes, tick: int, ids: Sequence[int]) -> list[tuple[Action | None, int]]:
        """Per robot of ``ids`` (the batch asked of them this tick): its action and how many of its messages
        did not decode (dropped one by one); the action is None for a robot whose record is malformed
        (a non-finite goal or velocity, unknown flags). Raises WireError when the batch as a whole is
        malformed: it does not decode, or answers another tick or other robots."""
        _, _, got_tick, ids_b, fixed, extras = _unpack(data, ACT_BATCH, 4)
        m = len(ids)
        if got_tick != tick or type(got_tick) is not int:
            raise WireError("act_batch: answers another tick")
        if ids is not self._ids[0]:  # the batch encoder hands the same list while the robots stay the same
            self._ids = (ids, _u32s(m).pack(*ids))
        if ids_b != self._ids[1]:
            raise WireError("act_batch: answers other robots")
        if type(fixed) is not bytes or len(fixed) != ACT_FIXED.size * m or type(extras) is not list:
            raise WireError("act_batch: records must be bytes, one per robot, and extras a list")
        same = self._batch
        if not extras and fixed == same[1] and ids_b == same[0]:  # every robot does what it did last tick
            return same[2]  # (shared with the last call: read only)
        out: list[tuple[Action | None, int]] = []
        last = self._last
        size = ACT_FIXED.size
        extra_at = 0
        for k, (gx, gy, v, w, flags) in enumerate(ACT_FIXED.iter_unpack(fixed)):
            robot = ids[k]
            if flags & ~ACT_FLAGS or flags & (ACT_RUNS | ACT_STRAIGHT) == ACT_RUNS | ACT_STRAIGHT or (flags & ACT_GOAL and not (math.isfinite(gx) and math.isfinite(gy))) or (
                    flags & ACT_VELOCITY and not (math.isfinite(v) and math.isfinite(w))):
                out.append((None, 0))
                if flags & ACT_EXTRAS:
                    extra_at += 1
                continue
            if not flags & ACT_EXTRAS:
                record = fixed[size * k:size * (k + 1)]
                seen = last.get(robot)
                if seen is not None and seen[0] == record:
                    out.append((seen[1], 0))
                    continue
                action = _action(goal=(gx, gy) if flags & ACT_GOAL else None,
                                 velocity=(v, w) if flags & ACT_VELOCITY else None, messages=(), debug=None,
                                 clear_goal=bool(flags & ACT_CLEAR_GOAL), drive=_drive(flags))
                last[robot] = (record, action)
                out.append((action, 0))
                continue
            if extra_at >= len(extras):
                raise WireError("act_batch: fewer extras than records that announce them")
            extra = extras[extra_at]
            extra_at += 1
            if type(extra) is not list or len(extra) != 2 or type(extra[0]) is not list or not (
                    extra[1] is None or type(extra[1]) is dict) or not all(type(b) is bytes for b in extra[0]):
                out.append((None, 0))
                continue
            decoded = []
            for blob in extra[0]:
                try:
                    decoded.append(decode(blob))
                except MessageError:
                    continue
            action = Action(goal=(gx, gy) if flags & ACT_GOAL else None,
                            velocity=(v, w) if flags & ACT_VELOCITY else None, messages=tuple(decoded),
                            debug=extra[1], clear_goal=bool(flags & ACT_CLEAR_GOAL), drive=_drive(flags))
            last.pop(robot, None)
            out.append((action, len(extra[0]) - len(decoded)))
        if extra_at != len(extras):
            raise WireError("act_batch: more extras than records that announce them")
        if not extras and None not in (a for a, _ in out):
            self._batch = (ids_b, fixed, out)
        return out


__all__ = ["ACT_BATCH", "ACT_FIXED", "OBS_BATCH", "ActBatchDecoder", "ActBatchEncoder", "BatchEncoder", "ObsBatch",
           "ObsBatchDecoder", "apply_cells", "decode_obs_batch", "encode_act_batch"]
