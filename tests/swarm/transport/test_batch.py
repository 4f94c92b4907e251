"""Batched packets (obs_batch / act_batch): the agents of one process see exactly what per-robot packets
give them, every malformed batch raises WireError and leaves the agents' maps as they were, and a run whose
local agents refuse their batch goes on without them."""

from __future__ import annotations

import math
import struct

import msgpack
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from swarm.api import Action, NavStatus, Neighbours, Pose, RobotInfo
from swarm.comm.medium import Envelope
from swarm.comm.messages import Heartbeat, MapRequest, encode
from swarm.transport.agent import AgentRunner
from swarm.transport.bearings import bearings
from swarm.transport.batch import (ACT_FIXED, ActBatchDecoder, ActBatchEncoder, BatchEncoder, ObsBatchDecoder,
                                   decode_obs_batch, encode_act_batch)
from swarm.transport.group import AgentGroup
from swarm.transport.wire import OBS_STATE, ResetPacket, WireError, encode_obs
from tests.swarm.transport.test_wire import random_tick

ROWS, COLS = 30, 40


def group(n: int, robots) -> AgentGroup:
    return AgentGroup([ResetPacket(RobotInfo(id=i, n_robots=n, map_shape=(ROWS, COLS)), "frontier", {}, 1, (3, i))
                       for i in robots])


def runners(n: int, robots) -> dict[int, AgentRunner]:
    return {i: AgentRunner(ResetPacket(RobotInfo(id=i, n_robots=n, map_shape=(ROWS, COLS)), "frontier", {}, 1, (3, i)))
            for i in robots}


def envelopes(rng: np.random.Generator, n: int) -> list[list[Envelope]]:
    """Each robot's inbox: real messages, one Envelope object per broadcast shared by all its receivers."""
    sent = [Envelope(s, 1, encode(m), m) for s in range(n) for m in
            (Heartbeat(sender=s, tick=3, x=float(s), y=1.5, theta=-0.5), MapRequest(sender=s, target=(s + 1) % n))
            if rng.random() < 0.4]
    return [[e for e in sent if e.sender != i and rng.random() < 0.7] for i in range(n)]


def test_a_batch_gives_every_robot_the_observation_its_own_packet_gives():
    """Random ticks against the per-robot packets decoded by AgentRunner: poses, navigator status (the same
    reuse of an unchanged one), counters, inbox messages, neighbours and the map mirrors, tick after tick."""
    rng = np.random.default_rng(35)
    for trial in range(40):
        n = int(rng.integers(1, 14))
        mine = sorted(rng.choice(n, int(rng.integers(1, n + 1)), replace=False).tolist())
        encoder, g, reference = BatchEncoder(mine, n), group(n, mine), runners(n, mine)
        for _ in range(3):
            t = random_tick(rng, n)
            t["inboxes"] = envelopes(rng, n)
            packet, ids = encoder(**t)
            live = [i for i in mine if t["live"][i]]
            assert ids == live
            if packet is None:
                continue
            tick, got_ids, observations = g.observe(packet)
            assert (tick, list(got_ids)) == (t["tick"], live)
            for i, obs in zip(got_ids, observations):
                idx = t["cells"][(t["ends"][i - 1] if i else 0):t["ends"][i]]
                per_robot = encode_obs(t["tick"], i, Pose(*t["poses"][i].tolist()), idx,
                                       t["known"][i].reshape(-1)[idx], tuple(e.data for e in t["inboxes"][i]),
                                       Neighbours(i, t["near"], t["distance"], bearings(t["poses"]),
                                                  t["poses"][:, :2].copy()),
                                       bool(t["collided"][i]), t["navs"][i], float(t["travelled"][i]),
                                       float(t["energy"][i]))
                want = reference[i].observe(per_robot)
                for name in ("tick", "robot_id", "pose", "inbox", "collided", "nav", "distance_travelled",
                             "energy_used"):
                    assert getattr(obs, name) == getattr(want, name), (trial, i, name)
                assert repr(obs.nav) == repr(want.nav)
                assert tuple(obs.neighbours) == tuple(want.neighbours) and bool(obs.neighbours) == bool(want.neighbours)
                assert np.array_equal(obs.known, want.known) and not obs.known.flags.writeable


def test_a_broadcast_travels_once_per_batch_and_unchanged_navigators_keep_their_status():
    rng = np.random.default_rng(1)
    t = random_tick(rng, 4)
    t["live"][:] = True
    beat = Heartbeat(sender=0, tick=2, x=1.0, y=2.0, theta=0.0)
    shared = Envelope(0, 1, encode(beat), beat)
    t["inboxes"] = [[], [shared], [shared], [shared]]
    encoder, g = BatchEncoder(range(4), 4), group(4, range(4))
    packet, _ = encoder(**t)
    assert msgpack.unpackb(packet)[9] == [shared.data], "one entry in the message table"
    _, _, first = g.observe(packet)
    assert first[1].inbox == first[3].inbox == (beat,) and first[1].inbox[0] is first[3].inbox[0]
    t["tick"] += 1
    t["inboxes"] = [[]] * 4
    _, _, second = g.observe(encoder(**t)[0])
    assert all(a.nav is b.nav for a, b in zip(first, second)), "the same NavStatus while its bytes stand"
    t["tick"] += 1
    t["navs"] = [NavStatus(goal=(-0.0, 0.0) if i == 2 else None) for i in range(4)]
    _, _, third = g.observe(encoder(**t)[0])
    assert repr(third[2].nav.goal) == "(-0.0, 0.0)" and third[0].nav == NavStatus()


def valid_batch(n: int = 3) -> tuple[list, AgentGroup]:
    rng = np.random.default_rng(3)
    t = random_tick(rng, n)
    t["live"][:] = True
    t["inboxes"] = envelopes(rng, n)
    t["inboxes"][0] = [Envelope(1, 1, encode(MapRequest(1, 0)), MapRequest(1, 0))]
    t["near"][0, 1] = True
    while not len(t["cells"]):
        t = {**t, **{k: v for k, v in random_tick(rng, n).items() if k in ("cells", "ends", "known")}}
    packet, _ = BatchEncoder(range(n), n)(**t)
    return msgpack.unpackb(packet), group(n, range(n))


def u32(*v: int) -> bytes:
    return struct.pack(f"<{len(v)}I", *v)


def edit(f: list, what: str) -> list:
    f = list(f)
    states, cells = bytearray(f[5]), bytearray(f[6])
    if what == "kind":
        f[0] = "obs"
    elif what == "version":
        f[1] = 1
    elif what == "tick":
        f[2] = -1
    elif what == "tick type":
        f[2] = 1.5
    elif what == "column type":
        f[4] = list(f[4])
    elif what == "too few fields":
        f = f[:-1]
    elif what == "no robots":
        f[3], f[4], f[5] = b"", b"", b""
    elif what == "counts length":
        f[4] = f[4][:-4]
    elif what == "ids not ascending":
        f[3] = u32(1, 0, 2)
    elif what == "id outside the run":
        f[3] = u32(0, 1, 3)
    elif what == "nav state":
        states[OBS_STATE.size - 2] = 6
        f[5] = bytes(states)
    elif what == "flags":
        states[OBS_STATE.size - 1] = 4
        f[5] = bytes(states)
    elif what == "cells length":
        f[6] = f[6][:-1]
    elif what == "cell value":
        cells[-1] = 3
        f[6] = bytes(cells)
    elif what == "cell outside the map":
        cells[0:4] = u32(ROWS * COLS)
        f[6] = bytes(cells)
    elif what == "neighbours length":
        f[7] = f[7] + b"\0"
    elif what == "inbox past the table":
        f[8] = u32(*([5] * (len(f[8]) // 4)))
    elif what == "messages":
        f[9] = ["x"] * len(f[9])
    return f


PROBLEMS = ["kind", "version", "tick", "tick type", "column type", "too few fields", "no robots", "counts length",
            "ids not ascending", "id outside the run", "nav state", "flags", "cells length", "cell value",
            "cell outside the map", "neighbours length", "inbox past the table", "messages"]


@pytest.mark.parametrize("what", PROBLEMS)
def test_a_malformed_batch_raises_wire_error_and_writes_no_map(what):
    f, g = valid_batch()
    assert f[8] and f[9] and f[7] and f[6], "the template exercises every column"
    g.observe(msgpack.packb(f, use_bin_type=True))  # the valid one is taken
    before = g.maps.copy()
    with pytest.raises(WireError):
        g.observe(msgpack.packb(edit(f, what), use_bin_type=True))
    assert np.array_equal(g.maps, before)
    with pytest.raises(WireError):
        decode_obs_batch(msgpack.packb(edit(f, what), use_bin_type=True), 3, ROWS * COLS)


def test_a_group_that_reads_its_maps_in_place_refuses_map_cells_and_robots_it_does_not_serve():
    f, g = valid_batch()
    shared = [np.zeros((ROWS, COLS), np.uint8) for _ in range(3)]
    g.share_maps(shared)
    with pytest.raises(WireError, match="in place"):
        g.observe(msgpack.packb(f, use_bin_type=True))
    other = group(3, [0, 2])
    with pytest.raises(WireError, match="does not serve"):
        other.observe(msgpack.packb(f, use_bin_type=True))


# ------------------------------------------------------------------------------------ act_batch ----
ACTIONS = [Action(), Action(goal=(1.5, -2.0)), Action(goal=(-0.0, 0.0), clear_goal=True),
           Action(velocity=(0.5, -1.0)), Action(goal=(3.0, 4.0), messages=(Heartbeat(4, 11, 1.0, 2.0, 0.5),),
                                                 debug={"k": [1, 2]})]


def test_act_batch_round_trips_exactly_and_reuses_what_did_not_change():
    ids = [0, 2, 3, 4, 7]
    encoder, decoder = ActBatchEncoder(), ActBatchDecoder()
    for tick in range(3):
        packet = encoder(tick, ids, ACTIONS)
        got = decoder(packet, tick, ids)
        assert [a for a, _ in got] == ACTIONS and [repr(a) for a, _ in got] == [repr(a) for a in ACTIONS]
        assert [bad for _, bad in got] == [0] * 5
        assert [math.copysign(1, v) for v in got[2][0].goal] == [-1.0, 1.0]
        if tick:
            assert got[1][0] is first[1][0], "an unchanged record gives the same Action"
            assert got[4][0] is not first[4][0], "an action with messages is decoded afresh"
        first = got
    assert encode_act_batch(5, ids, ACTIONS) == encoder(5, ids, ACTIONS)


def act_fields(ids=(0, 1), records=None, extras=None, tick=7) -> bytes:
    records = records if records is not None else [(1.0, 2.0, 0.0, 0.0, 1), (0.0, 0.0, 0.5, 0.1, 2)]
    return msgpack.packb(["act_batch", 2, tick, u32(*ids), b"".join(ACT_FIXED.pack(*r) for r in records),
                          extras if extras is not None else []], use_bin_type=True)


@pytest.mark.parametrize("packet", [
    act_fields(tick=8), act_fields(ids=(0, 2)), act_fields(ids=(0,), records=[(1.0, 2.0, 0.0, 0.0, 1)]),
    act_fields(records=[(1.0, 2.0, 0.0, 0.0, 9)], extras=[[[], None]]), act_fields(extras=[[[], None]]),
    b"\x00garbage", msgpack.packb(["act_batch", 2, 7, u32(0, 1)]),
    msgpack.packb(["act", 2, 7, 0, None, None, False, [], None]),
])
def test_a_malformed_act_batch_raises_wire_error(packet):
    with pytest.raises(WireError):
        ActBatchDecoder()(packet, 7, [0, 1])


def test_a_bad_record_costs_its_robot_and_a_bad_message_only_itself():
    good = encode(Heartbeat(sender=1, tick=1, x=1.0, y=2.0, theta=0.5))
    got = ActBatchDecoder()(act_fields(records=[(math.nan, 2.0, 0.0, 0.0, 1), (0.0, 0.0, 0.5, 0.1, 2 | 8)],
                                       extras=[[[b"\x93bad", good], {"x": 1}]]), 7, [0, 1])
    assert got[0] == (None, 0)
    assert got[1][0] == Action(velocity=(0.5, 0.1), messages=(Heartbeat(1, 1, 1.0, 2.0, 0.5),), debug={"x": 1})
    assert got[1][1] == 1
    got = ActBatchDecoder()(act_fields(records=[(1.0, 2.0, 0.0, 0.0, 64), (1.0, math.inf, 0.0, 0.0, 0)]), 7, [0, 1])
    assert got[0] == (None, 0) and got[1][0] == Action(), "unknown flags refused; unflagged numbers are not read"
    got = ActBatchDecoder()(act_fields(records=[(1.0, 2.0, 0.0, 0.0, 8), (0.0, 0.0, 0.0, 0.0, 0)],
                                       extras=[[["not bytes"], None]]), 7, [0, 1])
    assert got[0] == (None, 0) and got[1][0] == Action()


def test_act_batch_carries_the_drive_and_refuses_two_drives_at_once():
    actions = [Action(goal=(1.0, 2.0), drive="runs"), Action(goal=(1.0, 2.0), clear_goal=True, drive="straight"),
               Action(goal=(1.0, 2.0))]
    got = ActBatchDecoder()(ActBatchEncoder()(3, [0, 1, 2], actions), 3, [0, 1, 2])
    assert [a for a, _ in got] == actions
    got = ActBatchDecoder()(act_fields(records=[(1.0, 2.0, 0.0, 0.0, 1 | 16 | 32), (1.0, 2.0, 0.0, 0.0, 1 | 32)]),
                            7, [0, 1])
    assert got[0] == (None, 0) and got[1][0] == Action(goal=(1.0, 2.0), drive="straight")


# -------------------------------------------------------------------------------------- live run ----
def test_local_agents_that_refuse_their_batch_fail_and_the_run_goes_on(monkeypatch):
    """A batch the group cannot take (here: our encoder made to corrupt tick 40's) marks the local robots
    failed at that tick, as a remote agent that stops answering is; the run ends normally."""
    import swarm.transport.zenoh_host as zh
    from swarm.sim.loop import Simulation

    class Corrupting(zh.BatchEncoder):
        def __call__(self, tick, *args):
            packet, ids = super().__call__(tick, *args)
            return (packet[:-3] if tick == 40 else packet), ids

    monkeypatch.setattr(zh, "BatchEncoder", Corrupting)
    spec = {"seed": 4, "map": {"kind": "building", "size": 40}, "robots": {"count": 3}, "stop": {"max_ticks": 80},
            "transport": "zenoh"}
    r = Simulation(spec).run()
    assert r.summary["failed_robots"] == [0, 1, 2]
    events = [e for e in r.events if e["event"] == "agent_failed"]
    assert [e["tick"] for e in events] == [40] * 3 and "refused" in events[0]["reason"]


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.data())
def test_bytes_flipped_inside_any_column_decode_or_raise_wire_error(data):
    """Random bytes of a valid batch's columns overwritten: the group takes it (cells inside the map, values
    0..2) or raises WireError and writes no map; nothing else."""
    f, g = valid_batch()
    column = data.draw(st.sampled_from([3, 4, 5, 6, 7, 8]))
    raw = bytearray(f[column])
    for _ in range(data.draw(st.integers(1, 4))):
        if raw:
            raw[data.draw(st.integers(0, len(raw) - 1))] = data.draw(st.integers(0, 255))
    f[column] = bytes(raw)
    before = g.maps.copy()
    try:
        _, _, observations = g.observe(msgpack.packb(f, use_bin_type=True))
    except WireError:
        assert np.array_equal(g.maps, before)
        return
    assert g.maps.max() <= 2 and all(len(tuple(o.neighbours)) >= 0 for o in observations)
