"""The agent wire format: what travels between the runtime and an agent (see docs/wire-format.md).

Three packets, each a msgpack array whose first two items are the packet kind and :data:`WIRE_VERSION`:

* ``reset`` (runtime -> agent, key ``swarm/<run>/robot/<id>/reset``): robot facts, algorithm, parameters,
  the robot's seed (``SeedSequence`` entropy and spawn key) and the map shape.
* ``obs`` (runtime -> agent, ``.../obs``): one tick's observation. Pose, navigation status and counters
  travel as one binary struct (:data:`OBS_STATE`), neighbours as binary records (:data:`NEIGHBOUR`), the
  knowledge map as the cells changed since the previous observation (flat indices as uint32 gaps + uint8
  values, zlib-compressed when large), the inbox as the messages' own wire bytes (:mod:`swarm.comm.messages`).
* ``act`` (agent -> runtime, ``.../act``): the decision for that tick, messages as wire bytes.

Decoding checks types and sizes and raises :class:`WireError`; the runtime drops and counts bad packets.
"""

from __future__ import annotations

import struct
import threading
import zlib
from dataclasses import dataclass
from typing import Any, NamedTuple, Sequence

import msgpack
import numpy as np
from numba import njit

from swarm.base.types import Action, NavStatus, Neighbour, Neighbours, Pose, RobotInfo, frozen_builder
from swarm.comm.messages import MAX_BYTES_PER_TICK, MAX_MESSAGES_PER_TICK, MessageError, decode, encode, gaps_u32
from swarm.knowledge.cellcodec import get_u32

WIRE_VERSION = 2
MAX_PACKET_BYTES = 8 * 1024 * 1024
NAV_STATES = ("idle", "planning", "moving", "reached", "unreachable", "blocked")


class WireError(ValueError):
    """A packet that does not follow the wire format."""


@dataclass(frozen=True)
class ResetPacket:
    robot: RobotInfo
    algorithm: str
    params: dict[str, Any]
    seed_entropy: int
    seed_spawn_key: tuple[int, ...]

    def rng(self) -> np.random.Generator:
        return np.random.default_rng(np.random.SeedSequence(self.seed_entropy, spawn_key=self.seed_spawn_key))


class ObsPacket(NamedTuple):
    """A decoded observation packet (a named tuple: built for every agent every tick, so it must be cheap)."""

    tick: int
    robot_id: int
    pose: Pose
    changed_idx: np.ndarray
    changed_val: np.ndarray
    inbox: tuple[bytes, ...]
    neighbours: Sequence[Neighbour]
    collided: bool
    nav: NavStatus
    distance_travelled: float
    energy_used: float


class ActPacket(NamedTuple):
    """A decoded act packet (a named tuple, as cheap to build as ObsPacket). ``action.messages`` holds the
    messages that decoded; ``bad_messages`` counts those that did not (dropped one by one) and those past
    the first :data:`~swarm.comm.messages.MAX_MESSAGES_PER_TICK` (never decoded); ``problems`` says why,
    one entry per undecodable message and one for the excess (for the run's ``message_dropped`` events)."""

    tick: int
    robot_id: int
    action: Action
    message_bytes: tuple[bytes, ...]
    bad_messages: int = 0
    problems: tuple[str, ...] = ()


_LOCAL = threading.local()


def _pack(items: list[Any]) -> bytes:
    """msgpack bytes of ``items`` from this thread's reused Packer (``packb`` builds one per call: +0.6 us a
    packet). Per thread because a Packer is not thread-safe and remote agents' callbacks run in zenoh's."""
    packer = getattr(_LOCAL, "packer", None)
    if packer is None:
        packer = _LOCAL.packer = msgpack.Packer(use_bin_type=True)
    return packer.pack(items)


def _unpack(data: bytes, kind: str, fields: int, limit: int = MAX_PACKET_BYTES) -> list[Any]:
    """The packet's items, kind and version included, checked to be a ``kind`` packet of this wire version
    with ``fields`` fields after them and at most ``limit`` bytes."""
    if not isinstance(data, (bytes, bytearray, memoryview)) or len(data) > limit:
        raise WireError(f"{kind}: not bytes or larger than {limit} bytes")
    try:
        items = msgpack.unpackb(data, raw=False, strict_map_key=False, max_bin_len=limit)
    except Exception as exc:  # msgpack raises many unrelated exception types on corrupt input
        raise WireError(f"{kind}: undecodable ({type(exc).__name__})") from None
    if type(items) is not list or len(items) < 2 or items[0] != kind:
        raise WireError(f"expected a {kind!r} packet")
    if items[1] != WIRE_VERSION:
        raise WireError(f"{kind}: wire version {items[1]!r}, expected {WIRE_VERSION}")
    if len(items) != fields + 2:
        raise WireError(f"{kind}: wrong number of fields")
    return items


def _num(v: Any, what: str) -> float:
    if type(v) is float and -_INF < v < _INF:  # the common case first; the comparison also rejects NaN
        return v
    if isinstance(v, bool) or not isinstance(v, (int, float)) or v != v or v in (float("inf"), float("-inf")):
        raise WireError(f"{what}: not a finite number")
    return float(v)


def _int(v: Any, what: str) -> int:
    if isinstance(v, bool) or not isinstance(v, int):
        raise WireError(f"{what}: not an integer")
    return v


_INF = float("inf")


# ---------------------------------------------------------------------------------------- reset ----
def encode_reset(p: ResetPacket) -> bytes:
    r = p.robot
    return _pack(["reset", WIRE_VERSION, r.id, r.n_robots, list(r.map_shape), r.radius, r.lidar_range, r.max_speed,
                  r.max_turn_rate, r.tick_seconds, r.battery, p.algorithm, p.params, p.seed_entropy,
                  list(p.seed_spawn_key)])


def decode_reset(data: bytes) -> ResetPacket:
    """A reset packet, every field checked (an agent must not trip over a bad one)."""
    f = _unpack(data, "reset", 13)[2:]
    robot_id, n_robots = _int(f[0], "reset: id"), _int(f[1], "reset: n_robots")
    shape = f[2]
    if (type(shape) is not list or len(shape) != 2 or not all(type(v) is int and 0 < v <= 100_000 for v in shape)
            or not 0 <= robot_id < n_robots <= 100_000):
        raise WireError("reset: bad robot id, robot count or map shape")
    if type(f[9]) is not str or type(f[10]) is not dict or type(f[12]) is not list:
        raise WireError("reset: algorithm must be a string, params a map, the spawn key a list")
    seed = _int(f[11], "reset: seed")
    spawn_key = tuple(_int(k, "reset: spawn key") for k in f[12])
    if seed < 0 or any(k < 0 for k in spawn_key) or len(spawn_key) > 8:
        raise WireError("reset: seed and spawn key must be non-negative integers")
    robot = RobotInfo(id=robot_id, n_robots=n_robots, map_shape=(shape[0], shape[1]), radius=_num(f[3], "reset: radius"),
                      lidar_range=_num(f[4], "reset: lidar range"), max_speed=_num(f[5], "reset: max speed"),
                      max_turn_rate=_num(f[6], "reset: max turn rate"), tick_seconds=_num(f[7], "reset: tick"),
                      battery=None if f[8] is None else _num(f[8], "reset: battery"))
    return ResetPacket(robot=robot, algorithm=f[9], params=f[10], seed_entropy=seed, seed_spawn_key=spawn_key)


# ------------------------------------------------------------------------------------------ obs ----
# The obs packet's fixed fields, one little-endian struct (docs/wire-format.md): x, y, theta, goal x, goal y,
# path length, distance travelled, energy used (float64), ticks since progress (uint32), nav state (uint8,
# an index into NAV_STATES), flags (uint8: bit 0 collided, bit 1 has a goal). Binary instead of msgpack
# lists: packing and unpacking nested lists of floats was most of the obs packet's cost.
OBS_STATE = struct.Struct("<8dIBB")
NEIGHBOUR = struct.Struct("<I4d")          # id (uint32), distance, bearing, x, y (float64)
NEIGHBOUR_DTYPE = np.dtype([("id", "<u4"), ("distance", "<f8"), ("bearing", "<f8"), ("x", "<f8"), ("y", "<f8")])
COLLIDED, HAS_GOAL = 1, 2
RAW_CELLS_BELOW = 64                       # fewer changed cells travel uncompressed (zlib costs more than it saves)
_NAV_INDEX = {name: k for k, name in enumerate(NAV_STATES)}


class PackedNeighbours(Neighbours):
    """Neighbours as they arrive in an obs packet, turned into :class:`Neighbour` tuples only when first read,
    like the in-process transport's :class:`~swarm.api.Neighbours` (most algorithms never look)."""

    __slots__ = ("_raw", "_span")

    def __init__(self, raw: bytes, start: int = 0, end: int | None = None) -> None:
        """The records in ``raw[start:end]`` (a batch's column holds every robot's, one after another)."""
        self._source = None  # not super().__init__: that takes the runtime's arrays
        self._items = None
        self._raw = raw
        self._span = (start, end)

    def _all(self) -> tuple[Neighbour, ...]:
        if self._items is None:
            start, end = self._span
            raw = self._raw if start == 0 and end is None else memoryview(self._raw)[start:end]
            self._items = tuple(Neighbour._make(r) for r in NEIGHBOUR.iter_unpack(raw))
        return self._items

    def __bool__(self) -> bool:
        return True  # decode_obs gives () when there are none


def pack_neighbours(neighbours: Any) -> bytes:
    """The ``neighbours`` field: one NEIGHBOUR record per neighbour. (The zenoh host writes all robots'
    records from the tick's arrays, :mod:`swarm.transport.packing`; this is the per-robot reference.)"""
    return b"".join(NEIGHBOUR.pack(*n) for n in neighbours)


def pack_cells(changed_idx: np.ndarray, changed_val: np.ndarray) -> bytes:
    """The ``cells`` field: uint32 gaps then uint8 values, zlib-compressed only when that is shorter and
    there are at least RAW_CELLS_BELOW cells; a decoder tells the two apart by the length (raw = 5 n).
    Small updates (most ticks change a handful of cells) are packed by struct: half numpy's cost there."""
    n = len(changed_idx)
    if n == 0:
        return b""  # most ticks
    if n < RAW_CELLS_BELOW:
        idx = changed_idx.tolist()
        return struct.pack(f"<{n}I{n}B", *[b - a for a, b in zip([0, *idx], idx)], *changed_val.tolist())
    raw = gaps_u32(np.asarray(changed_idx, dtype=np.int64)) + np.asarray(changed_val, dtype=np.uint8).tobytes()
    packed = zlib.compress(raw, 1)
    return packed if len(packed) < len(raw) else raw


def encode_obs(tick: int, robot_id: int, pose: Pose, changed_idx: np.ndarray, changed_val: np.ndarray,
               inbox: tuple[bytes, ...], neighbours: Any, collided: bool, nav: NavStatus,
               distance_travelled: float, energy_used: float) -> bytes:
    goal = nav.goal
    flags = (COLLIDED if collided else 0) | (HAS_GOAL if goal is not None else 0)
    gx, gy = goal if goal is not None else (0.0, 0.0)
    state = OBS_STATE.pack(pose[0], pose[1], pose[2], gx, gy, nav.path_length, distance_travelled, energy_used,
                           nav.ticks_since_progress, _NAV_INDEX[nav.state], flags)
    return _pack(["obs", WIRE_VERSION, tick, robot_id, state, len(changed_idx), pack_cells(changed_idx, changed_val),
                  list(inbox), neighbours if type(neighbours) is bytes else pack_neighbours(neighbours)])


def _cells(n: Any, cells: Any, map_cells: int) -> tuple[np.ndarray, np.ndarray]:
    """Changed flat indices and values from the ``cells`` field, checked against the map size."""
    n = _int(n, "changed cells")
    if n < 0 or not isinstance(cells, bytes):
        raise WireError("obs: bad map cells")
    if not n:
        return _NO_CELLS, _NO_VALUES
    raw = np.frombuffer(cells if len(cells) == 5 * n else _inflate(cells, 5 * n), dtype=np.uint8)
    idx = np.empty(n, dtype=np.int64)
    problem = _read_cells(raw, n, map_cells, idx)
    if problem:
        raise WireError(_CELL_PROBLEMS[problem])
    return idx, raw[4 * n:]


_CELL_PROBLEMS = ("", "obs: map cell value other than unseen, free or solid", "obs: map cells outside the map")


@njit(cache=True)
def _read_cells(raw: np.ndarray, n: int, map_cells: int, idx: np.ndarray) -> int:  # pragma: no cover - compiled
    """Flat indices from ``n`` little-endian uint32 gaps into ``idx``, checked in one pass with the ``n``
    values after them: 0, or 1 for a value that is not a cell state, 2 for a cell outside the map (numpy
    took five calls and a scalar comparison per packet)."""
    for k in range(4 * n, 5 * n):
        if raw[k] > 2:
            return 1
    at = 0
    for k in range(n):
        at += get_u32(raw, 4 * k)
        if at >= map_cells:
            return 2
        idx[k] = at
    return 0


def _inflate(data: bytes, size: int) -> bytes:
    """zlib-decompress exactly ``size`` bytes; never inflates past that (a small packet cannot claim gigabytes)."""
    d = zlib.decompressobj()
    try:
        raw = d.decompress(data, size + 1)
    except zlib.error:
        raise WireError("obs: corrupt map cells") from None
    if len(raw) != size or not d.eof or d.unconsumed_tail or d.unused_data:
        raise WireError("obs: wrong map cells length")
    return raw


_NO_CELLS, _NO_VALUES = np.zeros(0, np.int64), np.zeros(0, np.uint8)
_NO_CELLS.flags.writeable = False
_NO_VALUES.flags.writeable = False


class ObsDecoder:
    """Decodes one agent's obs packets, checked: field types and sizes, map cells inside the map, a known nav
    state. Reuses the previous :class:`NavStatus` while its bytes are unchanged (most ticks), as the runtime's
    navigator reuses its own: building the frozen dataclass was a sixth of the decoding. ``n_robots``: the
    run's robot count; the packet's inbox may hold each other robot's per-tick budget of messages on top of
    a packet's usual limit (others' traffic must not make a robot's observation too large to take)."""

    __slots__ = ("map_cells", "_nav_bytes", "_nav", "_limit")

    def __init__(self, map_cells: int, n_robots: int = 1) -> None:
        self.map_cells = map_cells
        self._nav_bytes = b""
        self._nav = NavStatus()
        self._limit = MAX_PACKET_BYTES + max(n_robots - 1, 0) * MAX_BYTES_PER_TICK

    def __call__(self, data: bytes) -> ObsPacket:
        _, _, tick, robot, state, n, cells, inbox, neighbours = _unpack(data, "obs", 7, self._limit)
        if type(tick) is not int or type(robot) is not int:
            raise WireError("obs: tick and robot must be integers")
        if type(state) is not bytes or len(state) != OBS_STATE.size:
            raise WireError(f"obs: state must be {OBS_STATE.size} bytes")
        if type(inbox) is not list or (inbox and not all(type(b) is bytes for b in inbox)):
            raise WireError("obs: inbox must be a list of byte strings")
        if type(neighbours) is not bytes or len(neighbours) % NEIGHBOUR.size:
            raise WireError(f"obs: neighbours must be a multiple of {NEIGHBOUR.size} bytes")
        x, y, theta, gx, gy, path_length, dist, energy, stalled, nav_state, flags = OBS_STATE.unpack(state)
        if nav_state >= len(NAV_STATES) or flags > COLLIDED | HAS_GOAL:
            raise WireError("obs: unknown nav state or flags")
        if n == 0 and type(n) is int and type(cells) is bytes:  # most packets: no cell changed
            idx, val = _NO_CELLS, _NO_VALUES
        else:
            idx, val = _cells(n, cells, self.map_cells)
        nav_bytes = state[24:48] + state[64:]  # the collided flag too: a rare miss, cheaper than masking it
        if nav_bytes != self._nav_bytes:
            self._nav = _nav_status(goal=(gx, gy) if flags & HAS_GOAL else None, state=NAV_STATES[nav_state],
                                    path_length=path_length, ticks_since_progress=stalled)
            self._nav_bytes = nav_bytes
        # tuple.__new__: the named tuples' own __new__ is a Python function, half of their cost here
        pose = _tuple_new(Pose, (x, y, theta))
        return _tuple_new(ObsPacket, (tick, robot, pose, idx, val, tuple(inbox) if inbox else (),
                                      PackedNeighbours(neighbours) if neighbours else (), bool(flags & COLLIDED),
                                      self._nav, dist, energy))


_tuple_new = tuple.__new__
_nav_status, _action = frozen_builder(NavStatus), frozen_builder(Action)


def decode_obs(data: bytes, map_cells: int, n_robots: int = 1) -> ObsPacket:
    """One observation packet, checked (see :class:`ObsDecoder`, which agents keep to decode theirs)."""
    return ObsDecoder(map_cells, n_robots)(data)


# ------------------------------------------------------------------------------------------ act ----
def encode_act(tick: int, robot_id: int, action: Action) -> bytes:
    messages = [encode(m) for m in action.messages] if action.messages else []
    goal, velocity, debug = action.goal, action.velocity, action.debug
    drive = DRIVE_CODES[action.drive]
    clear: bool | int = bool(action.clear_goal) if not drive else int(bool(action.clear_goal)) | drive << 1
    return _pack(["act", WIRE_VERSION, tick, robot_id, list(goal) if goal is not None else None,
                  list(velocity) if velocity is not None else None, clear, messages,
                  dict(debug) if debug is not None else None])


DRIVE_CODES: dict[str, int] = {"path": 0, "runs": 1, "straight": 2}
"""``Action.drive`` in an ``act`` packet's ``clear_goal`` field: a bool for "path" (as before drives existed),
else the integer ``clear_goal | code << 1``."""
_DRIVE_NAMES = {code: name for name, code in DRIVE_CODES.items()}


def _clear_and_drive(field: Any) -> tuple[bool, str]:
    """An ``act`` packet's ``clear_goal`` field: a bool, or an integer ``clear_goal | drive << 1``."""
    if type(field) is bool:
        return field, "path"
    if type(field) is int and 0 <= field < 2 * (len(DRIVE_CODES)):
        return bool(field & 1), _DRIVE_NAMES[field >> 1]
    raise WireError("act: clear_goal must be a bool or an integer clear_goal | drive << 1 (drive 0..2)")


def _pair(v: Any, what: str) -> tuple[float, float] | None:
    """A ``[a, b]`` field of finite numbers as a tuple of floats, or None."""
    if v is None:
        return None
    if type(v) is not list or len(v) != 2:
        raise WireError(f"act: {what} must be a list of two numbers")
    return _num(v[0], what), _num(v[1], what)


def decode_act(data: bytes) -> ActPacket:
    """An action from an untrusted agent: every field checked; messages decoded and validated."""
    _, _, tick, robot, goal, velocity, clear_goal, messages, debug = _unpack(data, "act", 7)
    tick, robot = _int(tick, "tick"), _int(robot, "robot")
    goal, velocity = _pair(goal, "goal"), _pair(velocity, "velocity")
    clear, drive = _clear_and_drive(clear_goal)
    if type(messages) is not list:
        raise WireError("act: messages must be a list of byte strings")
    if debug is not None and not isinstance(debug, dict):
        raise WireError("act: debug must be a map")
    if not messages:
        action = _action(goal=goal, velocity=velocity, messages=(), debug=debug, clear_goal=clear, drive=drive)
        return _tuple_new(ActPacket, (tick, robot, action, (), 0, ()))
    if not all(isinstance(m, bytes) for m in messages):
        raise WireError("act: messages must be a list of byte strings")
    problems = []
    if len(messages) > MAX_MESSAGES_PER_TICK:  # never decoded: one packet must not cost the run 170,000 decodes
        problems.append(f"{len(messages) - MAX_MESSAGES_PER_TICK} message(s) over the per-tick budget (more than "
                        f"{MAX_MESSAGES_PER_TICK} messages from one robot in a tick)")
    decoded, kept = [], []
    for m in messages[:MAX_MESSAGES_PER_TICK]:
        try:
            decoded.append(decode(m))
        except MessageError as exc:
            problems.append(f"does not decode ({str(exc)[:80]})")
            continue
        kept.append(m)
    action = Action(goal=goal, velocity=velocity, messages=tuple(decoded), debug=debug, clear_goal=clear, drive=drive)
    return ActPacket(tick=tick, robot_id=robot, action=action, message_bytes=tuple(kept),
                     bad_messages=len(messages) - len(kept), problems=tuple(problems))
