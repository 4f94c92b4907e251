"""Fuzzing the wire (issue 31): every packet and message decoder, and the medium, over random and mutated
input. A decoder may only answer a value or its own error (WireError / MessageError); the medium may
only take a message or drop and count it; a real run with an agent spraying such packets finishes with
the result of a clean run.

Case counts (also printed with ``-s``): the hypothesis tests run ``CASES`` examples each; the live run
puts ``LIVE_PER_TICK`` hostile packets per tick.
"""

from __future__ import annotations

import math

import msgpack
import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from swarm.api import Action
from swarm.comm.medium import CommSpec, Medium
from swarm.comm.sharing import MapSharing
from swarm.comm.messages import Heartbeat, MapRequest, MessageError, decode, delta_update, encode, full_update, registered
from swarm.transport.auth import sign_act
from swarm.transport.batch import ActBatchDecoder, ActBatchEncoder, ObsBatchDecoder
from swarm.transport.wire import (WIRE_VERSION, ObsDecoder, WireError, decode_act, decode_reset, encode_act,
                                  encode_obs, encode_reset)
from tests.swarm.transport.test_batch import valid_batch  # at import: its module's @given tests must not be
                                                          # defined inside a running @given (nested_given)

CASES = 300
LIVE_PER_TICK = 6
SHAPE = (16, 16)
FUZZ = settings(max_examples=CASES, deadline=None, suppress_health_check=[HealthCheck.too_slow])

# msgpack-able values, nested: what a hostile peer can put in any field
leaves = (st.none() | st.booleans() | st.integers(min_value=-(2**64), max_value=2**64) | st.floats()
          | st.text(max_size=20) | st.binary(max_size=64))
values = st.recursive(leaves, lambda inner: st.lists(inner, max_size=5) | st.dictionaries(st.text(max_size=5), inner, max_size=4),
                      max_leaves=20)


def _packb(items) -> bytes:
    try:
        return msgpack.packb(items, use_bin_type=True)
    except (OverflowError, ValueError, TypeError):  # an integer msgpack cannot hold: send it as garbage
        return b"\xc1" + repr(items).encode()[:100]


def valid_act() -> list:
    return msgpack.unpackb(encode_act(7, 1, Action(goal=(1.0, 2.0), messages=(Heartbeat(1, 7, 1.0, 2.0, 0.5),))))


def valid_obs() -> list:
    from swarm.api import NavStatus, Pose
    packet = encode_obs(3, 1, Pose(1.0, 2.0, 0.5), np.array([0, 5, 17]), np.array([1, 2, 1], np.uint8),
                        (encode(Heartbeat(0, 2, 1.0, 1.0, 0.0)),), (), False, NavStatus(), 1.5, 2.5)
    return msgpack.unpackb(packet)


def valid_obs_batch() -> list:
    return valid_batch()[0]


def valid_act_batch() -> list:
    return msgpack.unpackb(ActBatchEncoder()(7, [0, 1], [Action(goal=(1.0, 2.0)), Action(
        velocity=(0.5, 0.0), messages=(Heartbeat(1, 7, 1.0, 2.0, 0.5),), debug={"k": 1})]))


def batch_decoders() -> dict:
    """The batch decoders as the runtime's side calls them (3 robots, a 30 x 40 map; acts of robots 0, 1)."""
    obs = ObsBatchDecoder(3, 30 * 40)
    return {"obs_batch": obs, "act_batch": lambda blob: ActBatchDecoder()(blob, 7, [0, 1])}


def valid_reset() -> list:
    from swarm.api import RobotInfo
    from swarm.transport.wire import ResetPacket
    return msgpack.unpackb(encode_reset(ResetPacket(RobotInfo(1, 3, SHAPE), "frontier", {"recheck_ticks": 5}, 9, (3, 1))))


def valid_messages() -> list[list]:
    known = np.zeros(SHAPE, np.uint8)
    known[2:5, 3:9] = 1
    return [msgpack.unpackb(encode(m)) for m in (
        Heartbeat(1, 3, 1.0, 2.0, 0.5), MapRequest(1, 2), full_update(1, 1, 3, known, (1.0, 1.0, 0.0)),
        delta_update(1, 2, 3, known, (1.0, 1.0, 0.0), np.flatnonzero(known)))]


def mutated(template: list, data: st.DataObject) -> bytes:
    """``template`` with one to three fields replaced by random values, or cut, or extended."""
    items = list(template)
    for _ in range(data.draw(st.integers(1, 3))):
        how = data.draw(st.sampled_from(["replace", "replace", "cut", "extend"]))
        if how == "replace" and items:
            items[data.draw(st.integers(0, len(items) - 1))] = data.draw(values)
        elif how == "cut" and items:
            items = items[: data.draw(st.integers(0, len(items) - 1))]
        else:
            items.append(data.draw(values))
    return _packb(items)


@FUZZ
@given(st.binary(max_size=400))
def test_random_bytes_never_escape_the_decoders(blob):
    for decoder, error in ((decode_act, WireError), (ObsDecoder(SHAPE[0] * SHAPE[1]), WireError),
                           (decode_reset, WireError), (decode, MessageError),
                           *((d, WireError) for d in batch_decoders().values())):
        try:
            decoder(blob)
        except error:
            pass


@FUZZ
@given(st.data())
def test_mutated_packets_decode_or_raise_only_wire_errors(data):
    kind = data.draw(st.sampled_from(["act", "obs", "reset", "obs_batch", "act_batch"]))
    template = {"act": valid_act, "obs": valid_obs, "reset": valid_reset, "obs_batch": valid_obs_batch,
                "act_batch": valid_act_batch}[kind]()
    blob = mutated(template, data)
    try:
        {"act": decode_act, "obs": ObsDecoder(SHAPE[0] * SHAPE[1]), "reset": decode_reset,
         **batch_decoders()}[kind](blob)
    except WireError:
        pass


@FUZZ
@given(st.data())
def test_mutated_messages_decode_or_raise_only_message_errors_and_then_pass_the_medium(data):
    """A message that decodes may still be unfit to send (forged sender, wrong shape, corrupt payload):
    the medium drops it, and whatever it lets through merges into every receiver without an error."""
    template = data.draw(st.sampled_from(valid_messages()))
    blob = mutated(template, data) if data.draw(st.booleans()) else _packb(template)
    try:
        msg = decode(blob)
    except MessageError:
        return
    medium = Medium(3, CommSpec(), np.random.default_rng(0), map_shape=SHAPE)
    env = medium.envelope(1, msg)
    assert (env is None) == (medium.stats.malformed == 1)
    if env is None:
        return
    sharing = MapSharing(3, SHAPE, CommSpec())
    known = np.zeros((3, *SHAPE), np.uint8)
    sharing.receive_tick([(env.message, [0, 2])], known, np.ones(3, bool))
    assert known.max() <= 2


@FUZZ
@given(sender=st.integers(-3, 5), fields=st.lists(values, min_size=0, max_size=6),
       kind=st.sampled_from(sorted(registered())))
def test_any_object_an_algorithm_returns_is_sent_or_dropped(sender, fields, kind):
    """In process an algorithm hands the medium Python objects, not bytes: built with arbitrary field
    values (or not a message at all), each is encoded or dropped and counted, never an exception."""
    cls = registered()[kind]
    try:
        msg = cls(*fields)
    except TypeError:
        msg = tuple(fields)  # not a message
    medium = Medium(4, CommSpec(), np.random.default_rng(0), map_shape=SHAPE)
    robot = sender % 4
    env = medium.envelope(robot, msg)
    assert (env is None) == (medium.stats.malformed_by_robot[robot] == 1)


def test_a_live_run_survives_an_agent_spraying_hostile_packets():
    """A remote agent that, every tick, puts random bytes, mutated acts (signed and unsigned) and acts
    carrying mutated messages around its honest reply: the run ends as a clean one does."""
    from swarm.sim.loop import Simulation
    from tests.swarm.transport.test_trust import SPEC, Agent, remote_run, same_run

    rng = np.random.default_rng(31)
    templates = valid_messages()
    cases = {"n": 0}

    def random_value(depth: int = 0):
        makers = [lambda: None, lambda: bool(rng.integers(2)), lambda: int(rng.integers(-10**6, 10**6)),
                  lambda: float(rng.normal() * 1e3), lambda: rng.bytes(int(rng.integers(0, 30))),
                  lambda: [random_value(depth + 1) for _ in range(rng.integers(0, 4))],
                  lambda: {"k": random_value(depth + 1)}]
        return makers[int(rng.integers(0, 7 if depth < 2 else 5))]()

    def mutate(items: list) -> bytes:
        items = list(items)
        items[int(rng.integers(0, len(items)))] = random_value()
        return _packb(items)

    def spray(tick, act, token):
        out = []
        for _ in range(LIVE_PER_TICK):
            cases["n"] += 1
            how = rng.integers(0, 4)
            if how == 0:  # random bytes, unsigned or signed for a tick that never comes (the robot's own agent
                # could sign them for this tick: that is its decision to make, and would be taken)
                blob = rng.bytes(int(rng.integers(0, 200)))
                out.append((blob, sign_act(token, tick + 10_000, blob) if rng.integers(2) else None))
            elif how == 1:  # a mutated act, signed for an earlier tick or unsigned: never taken
                blob = mutate(msgpack.unpackb(act))
                out.append((blob, sign_act(token, max(tick - 1, 0), blob) if tick else None))
            else:  # the honest act's outbox with mutated messages added, sent unsigned: refused
                items = msgpack.unpackb(act)
                items[7] = [*items[7], *[mutate(templates[int(rng.integers(len(templates)))]) for _ in range(2)]]
                out.append((_packb(items), None))
        return [*out, (act, sign_act(token, tick, act))]

    clean = Simulation({**SPEC, "transport": "inprocess"}).run()
    from tests.swarm.transport.test_trust import honest
    r = remote_run({1: spray, 2: honest})
    same_run(r, clean)
    assert r.summary["acts"]["malformed"] == [0, 0, 0]
    assert sum(r.summary["acts"]["refused"]) + sum(r.summary["acts"]["duplicate"]) + sum(r.summary["acts"]["late"]) > 0
    assert cases["n"] == LIVE_PER_TICK * r.summary["ticks"] or cases["n"] >= LIVE_PER_TICK * (r.summary["ticks"] - 1)
    assert Agent  # the agent class the live run used
    print(f"live run: {cases['n']} hostile packets")


def test_mutations_are_not_all_trivially_rejected():
    """The fuzzers reach past the first check: some mutated acts and messages still decode."""
    rng_ok = 0
    template = valid_act()
    for k in range(200):
        items = list(template)
        items[8] = {"k": k}  # debug: any map is fine
        try:
            decode_act(_packb(items))
            rng_ok += 1
        except WireError:
            pass
    assert rng_ok == 200
    assert not math.isnan(decode_act(_packb(template)).action.goal[0])
    assert WIRE_VERSION == template[1]
