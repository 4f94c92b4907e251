"""The agent wire format: what travels between the runtime and an agent (see docs/wire-format.md).

Three packets, each a msgpack array whose first two items are the packet kind and :data:`WIRE_VERSION`:

* ``reset`` (runtime -> agent, key ``swarm/<run>/robot/<id>/reset``): robot facts, algorithm, parameters,
  the robot's seed (``SeedSequence`` entropy and spawn key) and the map shape.
* ``obs`` (runtime -> agent, ``.../obs``): one tick's observation. The knowledge map travels as the cells
  changed since the previous observation (flat indices as uint32 gaps + uint8 values, zlib), the inbox as
  the messages' own wire bytes (:mod:`swarm.messages`).
* ``act`` (agent -> runtime, ``.../act``): the decision for that tick, messages as wire bytes.

Decoding checks types and sizes and raises :class:`WireError`; the runtime drops and counts bad packets.
"""

from __future__ import annotations

import zlib
from dataclasses import dataclass
from typing import Any

import msgpack
import numpy as np

from ..api import Action, NavStatus, Neighbour, Neighbours, Pose, RobotInfo
from ..messages import MessageError, decode, encode, gaps_u32

WIRE_VERSION = 1
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


@dataclass(frozen=True)
class ObsPacket:
    tick: int
    robot_id: int
    pose: Pose
    changed_idx: np.ndarray
    changed_val: np.ndarray
    inbox: tuple[bytes, ...]
    neighbours: tuple[Neighbour, ...]
    collided: bool
    nav: NavStatus
    distance_travelled: float
    energy_used: float


@dataclass(frozen=True)
class ActPacket:
    tick: int
    robot_id: int
    action: Action
    message_bytes: tuple[bytes, ...]


def _pack(items: list[Any]) -> bytes:
    return msgpack.packb(items, use_bin_type=True)


def _unpack(data: bytes, kind: str) -> list[Any]:
    if not isinstance(data, (bytes, bytearray, memoryview)) or len(data) > MAX_PACKET_BYTES:
        raise WireError(f"{kind}: not bytes or larger than {MAX_PACKET_BYTES} bytes")
    try:
        items = msgpack.unpackb(data, raw=False, strict_map_key=False, max_bin_len=MAX_PACKET_BYTES)
    except Exception as exc:  # msgpack raises many unrelated exception types on corrupt input
        raise WireError(f"{kind}: undecodable ({type(exc).__name__})") from None
    if not isinstance(items, list) or len(items) < 2 or items[0] != kind:
        raise WireError(f"expected a {kind!r} packet")
    if items[1] != WIRE_VERSION:
        raise WireError(f"{kind}: wire version {items[1]!r}, expected {WIRE_VERSION}")
    return items[2:]


def _num(v: Any, what: str) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)) or v != v or v in (float("inf"), float("-inf")):
        raise WireError(f"{what}: not a finite number")
    return float(v)


def _int(v: Any, what: str) -> int:
    if isinstance(v, bool) or not isinstance(v, int):
        raise WireError(f"{what}: not an integer")
    return v


# ---------------------------------------------------------------------------------------- reset ----
def encode_reset(p: ResetPacket) -> bytes:
    r = p.robot
    return _pack(["reset", WIRE_VERSION, r.id, r.n_robots, list(r.map_shape), r.radius, r.lidar_range, r.max_speed,
                  r.max_turn_rate, r.tick_seconds, r.battery, p.algorithm, p.params, p.seed_entropy,
                  list(p.seed_spawn_key)])


def decode_reset(data: bytes) -> ResetPacket:
    f = _unpack(data, "reset")
    if len(f) != 13:
        raise WireError("reset: wrong number of fields")
    robot = RobotInfo(id=_int(f[0], "id"), n_robots=_int(f[1], "n_robots"), map_shape=tuple(f[2]),
                      radius=f[3], lidar_range=f[4], max_speed=f[5], max_turn_rate=f[6], tick_seconds=f[7],
                      battery=f[8])
    return ResetPacket(robot=robot, algorithm=str(f[9]), params=dict(f[10]), seed_entropy=_int(f[11], "seed"),
                       seed_spawn_key=tuple(int(k) for k in f[12]))


# ------------------------------------------------------------------------------------------ obs ----
def encode_obs(tick: int, robot_id: int, pose: Pose, changed_idx: np.ndarray, changed_val: np.ndarray,
               inbox: tuple[bytes, ...], neighbours: tuple[Neighbour, ...], collided: bool, nav: NavStatus,
               distance_travelled: float, energy_used: float) -> bytes:
    idx = np.asarray(changed_idx, dtype=np.int64)
    cells = zlib.compress(gaps_u32(idx) + np.asarray(changed_val, dtype=np.uint8).tobytes(), 1) if len(idx) else b""
    rows = neighbours.rows() if isinstance(neighbours, Neighbours) else [list(n) for n in neighbours]
    return _pack(["obs", WIRE_VERSION, tick, robot_id, list(pose), len(idx), cells, list(inbox), rows, collided,
                  [list(nav.goal) if nav.goal is not None else None, nav.state, nav.path_length,
                   nav.ticks_since_progress], distance_travelled, energy_used])


def decode_obs(data: bytes, map_cells: int) -> ObsPacket:
    f = _unpack(data, "obs")
    if len(f) != 11:
        raise WireError("obs: wrong number of fields")
    tick, robot, pose, n, cells, inbox, neighbours, collided, nav, dist, energy = f
    n = _int(n, "changed cells")
    if n:
        try:
            raw = zlib.decompress(cells, bufsize=5 * n + 16)
        except (zlib.error, TypeError):
            raise WireError("obs: corrupt map cells") from None
        if len(raw) != 5 * n:
            raise WireError("obs: wrong map cells length")
        idx = np.cumsum(np.frombuffer(raw[: 4 * n], dtype="<u4").astype(np.int64))
        val = np.frombuffer(raw[4 * n:], dtype=np.uint8)
        if idx[-1] >= map_cells or (val > 2).any():
            raise WireError("obs: map cells outside the map")
    else:
        idx, val = np.zeros(0, np.int64), np.zeros(0, np.uint8)
    goal = None if nav[0] is None else (float(nav[0][0]), float(nav[0][1]))
    return ObsPacket(tick=tick, robot_id=robot, pose=Pose(*(float(v) for v in pose)), changed_idx=idx, changed_val=val,
                     inbox=tuple(bytes(b) for b in inbox),
                     neighbours=tuple(Neighbour(int(a), float(b), float(c), float(d), float(e)) for a, b, c, d, e in neighbours),
                     collided=bool(collided), nav=NavStatus(goal=goal, state=str(nav[1]), path_length=float(nav[2]),
                                                            ticks_since_progress=int(nav[3])),
                     distance_travelled=float(dist), energy_used=float(energy))


# ------------------------------------------------------------------------------------------ act ----
def encode_act(tick: int, robot_id: int, action: Action) -> bytes:
    messages = [encode(m) for m in action.messages]
    return _pack(["act", WIRE_VERSION, tick, robot_id,
                  list(action.goal) if action.goal is not None else None,
                  list(action.velocity) if action.velocity is not None else None,
                  bool(action.clear_goal), messages, dict(action.debug) if action.debug is not None else None])


def decode_act(data: bytes) -> ActPacket:
    """An action from an untrusted agent: every field checked; messages decoded and validated."""
    f = _unpack(data, "act")
    if len(f) != 7:
        raise WireError("act: wrong number of fields")
    tick, robot, goal, velocity, clear_goal, messages, debug = f
    tick, robot = _int(tick, "tick"), _int(robot, "robot")
    if goal is not None:
        if not isinstance(goal, list) or len(goal) != 2:
            raise WireError("act: goal must be [x, y]")
        goal = (_num(goal[0], "goal x"), _num(goal[1], "goal y"))
    if velocity is not None:
        if not isinstance(velocity, list) or len(velocity) != 2:
            raise WireError("act: velocity must be [v, omega]")
        velocity = (_num(velocity[0], "v"), _num(velocity[1], "omega"))
    if not isinstance(messages, list) or not all(isinstance(m, bytes) for m in messages):
        raise WireError("act: messages must be a list of byte strings")
    if debug is not None and not isinstance(debug, dict):
        raise WireError("act: debug must be a map")
    try:
        decoded = tuple(decode(m) for m in messages)
    except MessageError as exc:
        raise WireError(f"act: bad message ({exc})") from None
    action = Action(goal=goal, velocity=velocity, messages=decoded, debug=debug, clear_goal=bool(clear_goal))
    return ActPacket(tick=tick, robot_id=robot, action=action, message_bytes=tuple(messages))
