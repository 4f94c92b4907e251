"""The obs and act packets (wire version 2): round trips exactly, and every malformed packet raises WireError."""

from __future__ import annotations

import dataclasses
import math
import struct
import zlib

import msgpack
import numpy as np
import pytest

from swarm.api import Action, NavStatus, Neighbour, Neighbours, Observation, Pose, RobotInfo, frozen_builder
from swarm.comm.messages import Heartbeat, encode
from swarm.transport.agent import AgentRunner, InboxDecoder
from swarm.transport.wire import (NAV_STATES, NEIGHBOUR, OBS_STATE, RAW_CELLS_BELOW, WIRE_VERSION, ObsDecoder,
                                  ResetPacket, WireError, decode_act, decode_obs, encode_act, encode_obs,
                                  pack_neighbours)
from swarm.transport.bearings import BearingRows, bearings
from swarm.transport.packing import ObsEncoder

MAP_CELLS = 40 * 40


MOVING = NavStatus(goal=(1.5, -2.25), state="moving", path_length=7.5, ticks_since_progress=3)


def obs_packet(idx=(3, 17, 900), val=(1, 2, 1), neighbours=(), nav=MOVING, inbox=(), collided=True) -> bytes:
    return encode_obs(12, 2, Pose(1.25, 3.5, -0.75), np.array(idx, np.int64), np.array(val, np.uint8), inbox,
                      neighbours, collided, nav, 10.5, 11.25)


def fields(packet: bytes) -> list:
    return msgpack.unpackb(packet, raw=False)


def repack(f: list) -> bytes:
    return msgpack.packb(f, use_bin_type=True)


def test_round_trip_is_exact():
    near = np.array([[False, True, True], [True, False, False], [True, False, False]])
    distance = np.array([[0.0, 1.5, 2.5], [1.5, 0.0, 3.0], [2.5, 3.0, 0.0]])
    bearing = np.array([[0.0, 0.1, -0.2], [3.0, 0.0, 0.3], [1.0, 0.4, 0.0]])
    xy = np.array([[1.0, 2.0], [3.0, 4.0], [5.0, 6.0]])
    lazy = Neighbours(0, near, distance, bearing, xy)
    expected = (Neighbour(1, 1.5, 0.1, 3.0, 4.0), Neighbour(2, 2.5, -0.2, 5.0, 6.0))
    for given in (lazy, expected):  # the runtime's arrays or plain tuples give the same bytes
        p = decode_obs(obs_packet(neighbours=given, inbox=(b"a", b"bc")), MAP_CELLS)
        assert (p.tick, p.robot_id, p.pose) == (12, 2, Pose(1.25, 3.5, -0.75))
        assert p.changed_idx.tolist() == [3, 17, 900] and p.changed_val.tolist() == [1, 2, 1]
        assert p.inbox == (b"a", b"bc") and p.collided is True
        assert p.nav == MOVING
        assert (p.distance_travelled, p.energy_used) == (10.5, 11.25)
        assert bool(p.neighbours) and len(p.neighbours) == 2 and p.neighbours == expected
        assert p.neighbours[1].id == 2 and isinstance(p.neighbours[1].id, int)
    p = decode_obs(obs_packet(idx=(), val=(), nav=NavStatus(), collided=False), MAP_CELLS)
    assert p.neighbours == () and not p.collided and p.nav == NavStatus() and len(p.changed_idx) == 0


def test_large_updates_are_compressed_small_ones_are_not():
    few = fields(obs_packet())
    assert len(few[6]) == 5 * 3
    idx = np.arange(0, 4 * RAW_CELLS_BELOW, 4)
    many = obs_packet(idx=idx, val=np.ones(len(idx), np.uint8))
    assert len(fields(many)[6]) < 5 * len(idx)
    assert decode_obs(many, MAP_CELLS).changed_idx.tolist() == idx.tolist()


def bad_packets() -> dict[str, bytes]:
    good = fields(obs_packet(neighbours=(Neighbour(1, 1.0, 0.0, 2.0, 3.0),)))
    state = bytearray(good[4])

    def with_field(k: int, value) -> bytes:
        f = list(good)
        f[k] = value
        return repack(f)

    def with_state(offset: int, byte: int) -> bytes:
        s = bytearray(state)
        s[offset] = byte
        return with_field(4, bytes(s))

    raw_cells = struct.pack("<2I2B", 5, 7, 1, 1)
    return {
        "garbage": b"\x00garbage",
        "version 1": repack(["obs", 1] + good[2:]),
        "wrong kind": repack(["act"] + good[1:]),
        "too few fields": repack(good[:-1]),
        "tick not an integer": with_field(2, 1.5),
        "robot not an integer": with_field(3, "2"),
        "state too short": with_field(4, bytes(state[:-1])),
        "state not bytes": with_field(4, [1.0, 2.0, 3.0]),
        "unknown nav state": with_state(68, len(NAV_STATES)),
        "unknown flag bits": with_state(69, 4),
        "negative cell count": with_field(5, -1),
        "cell count not an integer": with_field(5, "3"),
        "cells not bytes": with_field(6, [1, 2]),
        "cells shorter than the count": with_field(5, 4),
        "corrupt compressed cells": with_field(6, b"\x78\x01garbage"),
        "compressed cells of the wrong length": repack(good[:5] + [2, zlib.compress(raw_cells + b"\x00")] + good[7:]),
        "cell outside the map": repack(good[:5] + [1, struct.pack("<IB", MAP_CELLS, 1)] + good[7:]),
        "cell value above solid": repack(good[:5] + [2, struct.pack("<2I2B", 5, 7, 1, 3)] + good[7:]),
        "inbox not a list": with_field(7, b"msg"),
        "inbox item not bytes": with_field(7, ["msg"]),
        "neighbours of a wrong length": with_field(8, good[8] + b"\x00"),
        "neighbours as a list": with_field(8, [[1, 1.0, 0.0, 2.0, 3.0]]),
    }


@pytest.mark.parametrize("name", list(bad_packets()))
def test_malformed_obs_raises_wire_error(name):
    with pytest.raises(WireError):
        decode_obs(bad_packets()[name], MAP_CELLS)


def test_formats_are_the_documented_sizes():
    assert OBS_STATE.size == 70 and NEIGHBOUR.size == 36 and WIRE_VERSION == 2


def runner(inbox: InboxDecoder | None = None) -> AgentRunner:
    robot = RobotInfo(id=2, n_robots=3, map_shape=(40, 40))
    return AgentRunner(ResetPacket(robot, "frontier", {}, 1, (2,)), inbox=inbox)


def test_agent_leaves_out_an_undecodable_inbox_message_and_counts_it():
    """A message the agent cannot decode (garbage, or a type its algorithm does not register) costs that
    message, not the observation: the rest of the inbox and the map cells still arrive."""
    shared = InboxDecoder()
    r = runner(shared)
    beat = encode(Heartbeat(sender=1, tick=11, x=1.0, y=2.0, theta=0.5))
    unknown = msgpack.packb(["nobody.registered_this", 1, 1, 2.0])
    obs = r.observe(obs_packet(inbox=(b"\x93\xa3bad", beat, unknown), idx=(3, 9), val=(1, 2)))
    assert obs.inbox == (Heartbeat(sender=1, tick=11, x=1.0, y=2.0, theta=0.5),)
    assert shared.undecodable == 2
    assert r.known.reshape(-1)[[3, 9]].tolist() == [1, 2]


def test_inbox_messages_are_decoded_once_per_payload_and_tick():
    shared = InboxDecoder()
    beat = encode(Heartbeat(sender=1, tick=11, x=1.0, y=2.0, theta=0.5))
    a = shared.decode(12, (beat,))
    b = shared.decode(12, (bytes(beat),))
    assert a == b and a[0] is b[0], "one decoded message shared by the agents of a tick"
    c = shared.decode(13, (beat,))
    assert c == a and c[0] is not a[0], "the cache holds one tick only"


def test_lazy_neighbours_pack_like_their_tuples_for_every_robot():
    rng = np.random.default_rng(3)
    n = 7
    near = rng.random((n, n)) < 0.5
    np.fill_diagonal(near, False)
    near[4] = False  # a robot with no neighbour
    distance, bearing, xy = rng.random((n, n)) * 9, rng.random((n, n)) * 6 - 3, rng.random((n, 2)) * 50
    for i in range(n):
        lazy = Neighbours(i, near, distance, bearing, xy)
        expected = tuple(Neighbours(i, near, distance, bearing, xy))
        assert pack_neighbours(lazy) == pack_neighbours(expected) == b"".join(NEIGHBOUR.pack(*t) for t in expected)


def reference_bearing(p, q) -> float:
    """The plain definition: the direction to q, relative to p's heading, wrapped into [-pi, pi)."""
    return (math.atan2(q[1] - p[1], q[0] - p[0]) - p[2] + math.pi) % (2 * math.pi) - math.pi


def test_bearings_follow_the_plain_definition_bit_for_bit():
    rng = np.random.default_rng(5)
    for n in (1, 2, 9):
        poses = np.column_stack((rng.random((n, 2)) * 30, rng.random(n) * 20 - 10))
        poses[n // 2] = poses[0]  # a robot on top of another: atan2(0, 0)
        b = bearings(poses)
        assert b.shape == (n, n) and np.all((-math.pi <= b) & (b < math.pi))
        expected = [[reference_bearing(p, q) for q in poses.tolist()] for p in poses.tolist()]
        assert b.tolist() == expected
        rows = BearingRows(poses)                # what the in-process transport hands out: read per row
        for i in range(n):
            cols = np.flatnonzero(rng.random(n) < 0.6)
            assert rows[i, cols].tolist() == [expected[i][j] for j in cols.tolist()]


def random_tick(rng: np.random.Generator, n: int) -> dict:
    """One tick's arrays for ObsEncoder: every case of the packet (no / few / compressible cells, inboxes,
    robots not live, goals and none, ticks and counters of every msgpack integer width)."""
    rows, cols = 30, 40
    pieces = [np.sort(rng.choice(rows * cols, int(rng.choice([0, 0, 3, RAW_CELLS_BELOW, 200])), replace=False))
              for _ in range(n)]
    near = rng.random((n, n)) < 0.4
    np.fill_diagonal(near, False)
    navs = [NavStatus(goal=None if rng.random() < 0.3 else (float(rng.random()), -2.5),
                      state=str(rng.choice(NAV_STATES)), path_length=float(rng.random()),
                      ticks_since_progress=int(rng.choice([0, 200, 70000]))) for _ in range(n)]
    return dict(tick=int(rng.choice([0, 5, 200, 70000, 2 ** 33])), live=rng.random(n) < 0.8,
                poses=np.column_stack((rng.random((n, 2)) * 60, rng.random(n) * 8 - 4)), collided=rng.random(n) < 0.3,
                travelled=rng.random(n) * 100, energy=rng.random(n) * 200, navs=navs,
                known=rng.integers(0, 3, (n, rows, cols)).astype(np.uint8),
                cells=np.concatenate(pieces).astype(np.int64), ends=np.cumsum([len(p) for p in pieces]),
                inboxes=[tuple(rng.bytes(int(rng.integers(1, 300))) for _ in range(int(rng.integers(0, 3))))
                         for _ in range(n)],
                near=near, distance=rng.random((n, n)) * 9)


def test_obs_encoder_writes_encode_obs_bytes_for_every_robot():
    """The batched packet writer against the one-robot encoder, neighbours from the full bearing matrix;
    without ``compress`` large updates travel raw and decode to the same observation."""
    rng = np.random.default_rng(6)
    for trial in range(60):
        n = int(rng.integers(1, 18))
        encoder, raw_encoder = ObsEncoder(n, compress=range(n)), ObsEncoder(n)
        for _ in range(2):  # the second tick reuses the encoders' nav cache
            t = random_tick(rng, n)
            t["navs"][0] = encoder._navs[0] or t["navs"][0]  # an unchanged status object
            got, raw = encoder(**t), raw_encoder(**t)
            b, xy = bearings(t["poses"]), t["poses"][:, :2].copy()
            for i in range(n):
                if not t["live"][i]:
                    assert got[i] is None and raw[i] is None
                    continue
                idx = t["cells"][(t["ends"][i - 1] if i else 0):t["ends"][i]]
                expected = encode_obs(t["tick"], i, Pose(*t["poses"][i].tolist()), idx, t["known"][i].reshape(-1)[idx],
                                      t["inboxes"][i], Neighbours(i, t["near"], t["distance"], b, xy),
                                      bool(t["collided"][i]), t["navs"][i], float(t["travelled"][i]),
                                      float(t["energy"][i]))
                assert got[i] == expected, (trial, i)
                assert len(fields(raw[i])[6]) == 5 * len(idx)
                a, e = decode_obs(raw[i], 30 * 40), decode_obs(expected, 30 * 40)
                assert a.changed_idx.tolist() == e.changed_idx.tolist() == idx.tolist()
                assert a.changed_val.tolist() == e.changed_val.tolist()
                assert a._replace(changed_idx=None, changed_val=None) == e._replace(changed_idx=None, changed_val=None)


# ------------------------------------------------------------------------------------------ act ----
def act_fields(**change) -> list:
    f = ["act", WIRE_VERSION, 12, 2, [1.5, -2.0], None, False, [], None]
    names = ("kind", "version", "tick", "robot", "goal", "velocity", "clear_goal", "messages", "debug")
    for name, value in change.items():
        f[names.index(name)] = value
    return f


@pytest.mark.parametrize("action", [
    Action(), Action(goal=(1.5, -2.0)), Action(goal=(-0.0, 0.0)), Action(velocity=(0.5, -1.0), clear_goal=True),
    Action(goal=(3.0, 4.0), messages=(Heartbeat(sender=2, tick=11, x=1.0, y=2.0, theta=0.5),), debug={"k": [1, 2]}),
    Action(goal=(1.0, 2.0), drive="straight"), Action(goal=(1.0, 2.0), clear_goal=True, drive="runs"),
    Action(goal=(1.0, 2.0), drive="runs", messages=(Heartbeat(sender=2, tick=11, x=1.0, y=2.0, theta=0.5),)),
])
def test_act_round_trips_exactly(action):
    p = decode_act(encode_act(12, 2, action))
    assert (p.tick, p.robot_id) == (12, 2)
    assert p.action == action and repr(p.action) == repr(action)
    if action.goal is not None:  # the sign of a zero survives
        assert [math.copysign(1, v) for v in p.action.goal] == [math.copysign(1, v) for v in action.goal]


def test_act_numbers_may_be_integers_and_come_back_as_floats():
    p = decode_act(repack(act_fields(goal=[3, 4], velocity=[1, 0])))
    assert p.action.goal == (3.0, 4.0) and all(type(v) is float for v in (*p.action.goal, *p.action.velocity))


@pytest.mark.parametrize("change", [
    {"tick": 1.0}, {"tick": True}, {"robot": "2"}, {"goal": [1.0]}, {"goal": (1.0, 2.0, 3.0)}, {"goal": "xy"},
    {"goal": [float("nan"), 1.0]}, {"goal": [1.0, float("inf")]}, {"goal": [True, 1.0]}, {"goal": [1.0, "2"]},
    {"velocity": [float("-inf"), 0.0]}, {"velocity": {"v": 1}}, {"messages": b"m"}, {"messages": ["m"]},
    {"debug": [1]}, {"kind": "obs"}, {"version": 1},
])
def test_malformed_act_raises_wire_error(change):
    with pytest.raises(WireError):
        decode_act(repack(act_fields(**change)))
    with pytest.raises(WireError):
        decode_act(repack(act_fields()[:-1]))


def test_messages_that_do_not_decode_are_dropped_one_by_one_and_counted():
    from swarm.comm.messages import Heartbeat, encode

    good = encode(Heartbeat(sender=2, tick=1, x=1.0, y=2.0, theta=0.5))
    bad = [b"\x93\xa3bad", b"", encode(Heartbeat(sender=2, tick=1, x=float("nan"), y=2.0, theta=0.5)),
           msgpack.packb(["swarm.heartbeat", 1, 2, "t", 1.0, 2.0, 0.5]), msgpack.packb(["swarm.map_request", 1, 2, 1.5])]
    p = decode_act(repack(act_fields(messages=[bad[0], good, *bad[1:], good])))
    assert p.bad_messages == len(bad)
    assert p.action.messages == (Heartbeat(2, 1, 1.0, 2.0, 0.5),) * 2 and p.message_bytes == (good, good)


def test_agent_decoder_reuses_an_unchanged_nav_status_and_notices_every_change():
    decoder = ObsDecoder(MAP_CELLS)
    first = decoder(obs_packet(idx=(), val=()))
    assert decoder(obs_packet(idx=(), val=())).nav is first.nav
    for nav in (NavStatus(goal=(1.5, -2.25), state="moving", path_length=7.5, ticks_since_progress=4),
                NavStatus(goal=(1.5, -2.25), state="blocked", path_length=7.5, ticks_since_progress=4),
                NavStatus(goal=None, state="blocked", path_length=7.5, ticks_since_progress=4),
                NavStatus(goal=(0.0, 0.0), state="blocked", path_length=7.5, ticks_since_progress=4),
                NavStatus(goal=(-0.0, 0.0), state="blocked", path_length=7.5, ticks_since_progress=4)):
        got = decoder(obs_packet(nav=nav)).nav
        assert got == nav and repr(got) == repr(nav)


def test_frozen_builder_builds_the_constructors_objects():
    obs = dict(tick=1, robot_id=2, pose=Pose(1.0, 2.0, 3.0), known=np.zeros((2, 2), np.uint8), inbox=(),
               neighbours=(), collided=False, nav=MOVING, distance_travelled=1.0, energy_used=2.0)
    for cls, kw in ((Observation, obs), (NavStatus, dict(goal=None, state="idle", path_length=0.0, ticks_since_progress=0)),
                    (Action, dict(goal=(1.0, 2.0), velocity=None, messages=(), debug=None, clear_goal=False))):
        built = frozen_builder(cls)(**kw)
        assert type(built) is cls and built == cls(**kw) and repr(built) == repr(cls(**kw))
        with pytest.raises(dataclasses.FrozenInstanceError):
            built.tick = 5

    @dataclasses.dataclass(frozen=True)
    class Checked:
        x: int

        def __post_init__(self) -> None:
            assert self.x > 0

    assert frozen_builder(Checked) is Checked


def test_the_drive_rides_in_clear_goal_and_a_path_drive_keeps_the_old_bool():
    """``Action.drive`` (MAES's motion model) shares the ``clear_goal`` field: a bool as before for "path",
    else the integer clear_goal | drive << 1; anything else is refused."""
    assert msgpack.unpackb(encode_act(1, 0, Action(goal=(1.0, 2.0))))[6] is False
    assert msgpack.unpackb(encode_act(1, 0, Action(goal=(1.0, 2.0), clear_goal=True, drive="straight")))[6] == 5
    for bad in (6, -1, 1.0, "runs", None):
        with pytest.raises(WireError, match="clear_goal"):
            decode_act(msgpack.packb(act_fields(clear_goal=bad)))
