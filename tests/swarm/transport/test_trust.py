"""Trust at the network boundary (issue 31): no packet crashes a run and no stranger steers or reads one.

Every test runs a real runtime listening on loopback and agents on their own zenoh sessions (threads of
this process, connected over TCP: to the runtime they are remote, exactly like ``swarm agent``). A
tampering agent runs the real algorithm through :class:`~swarm.transport.agent.AgentRunner` and adds bad
packets around its honest replies; each case must end with the run finishing exactly as it does
without the tampering, the bad packets dropped and counted.
"""

from __future__ import annotations

import socket
import threading
import time
import uuid
from typing import Callable

import msgpack
import numpy as np
import pytest
import zenoh

from swarm.api import Action
from swarm.comm.messages import Heartbeat, encode, full_update
from swarm.sim.loop import Simulation, TransportOptions
from swarm.transport.agent import AgentRunner
from swarm.transport.auth import RunSecret, RobotToken, sign_act
from swarm.transport.sessions import session_config
from swarm.transport.wire import WIRE_VERSION, decode_reset, encode_act

pytestmark = pytest.mark.timeout(300)

SPEC = {"seed": 4, "map": {"kind": "building", "size": 40}, "robots": {"count": 3}, "transport": "zenoh",
        "stop": {"max_ticks": 120}}
ACTS = ("malformed", "refused", "late", "duplicate")

# A tamper hook gets (tick, honest act bytes) and returns the packets to put, in order: (payload, attachment)
Tamper = Callable[[int, bytes, RobotToken], list[tuple[bytes, bytes | None]]]


def free_endpoint() -> str:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return f"tcp/127.0.0.1:{s.getsockname()[1]}"


def honest(tick: int, act: bytes, token: RobotToken) -> list[tuple[bytes, bytes | None]]:
    return [(act, sign_act(token, tick, act))]


def with_messages(*extra: bytes) -> Tamper:
    """The honest act with ``extra`` message bytes added to its outbox (signed by the robot's own agent)."""
    def tamper(tick: int, act: bytes, token: RobotToken) -> list[tuple[bytes, bytes | None]]:
        items = msgpack.unpackb(act)
        items[7] = [*items[7], *extra]
        packet = msgpack.packb(items, use_bin_type=True)
        return [(packet, sign_act(token, tick, packet))]
    return tamper


class Agent(threading.Thread):
    """One robot's agent on its own zenoh session, connected to the runtime over TCP, running the run's
    algorithm; ``tamper`` decides what it puts for each honest reply."""

    def __init__(self, endpoint: str, run_id: str, token: RobotToken, tamper: Tamper = honest,
                 user: str | None = None, password: str | None = None) -> None:
        super().__init__(daemon=True)
        self.endpoint, self.run_id, self.token, self.tamper = endpoint, run_id, token, tamper
        self.user, self.password = user or token.user, password or token.password
        self.connected = threading.Event()
        self.ended = threading.Event()

    def run(self) -> None:
        prefix = f"swarm/{self.run_id}/robot/{self.token.robot}"
        with zenoh.open(session_config(connect=[self.endpoint], user=self.user, password=self.password)) as s:
            deadline = time.monotonic() + 20
            while not list(s.info.peers_zid()):
                if time.monotonic() > deadline:
                    return
                time.sleep(0.01)
            self.connected.set()
            state: dict = {}

            def on_packet(sample: zenoh.Sample) -> None:
                kind = str(sample.key_expr).rsplit("/", 1)[-1]
                data = sample.payload.to_bytes()
                if kind == "reset":  # its attachment: the run nonce the act key is bound to
                    state["runner"] = AgentRunner(decode_reset(data))
                    state["token"] = self.token.for_run(sample.attachment.to_bytes())
                elif kind == "obs":
                    obs = state["runner"].observe(data)
                    act = state["runner"].answer(obs)
                    for payload, attachment in self.tamper(obs.tick, act, state["token"]):
                        s.put(f"{prefix}/act", payload, attachment=attachment,
                              congestion_control=zenoh.CongestionControl.BLOCK)

            subs = [s.declare_subscriber(f"{prefix}/{k}", zenoh.handlers.Callback(on_packet, indirect=False))
                    for k in ("reset", "obs")]
            end = s.declare_subscriber(f"swarm/{self.run_id}/end", lambda _: self.ended.set())
            token = s.liveliness().declare_token(f"{prefix}/alive")
            self.ended.wait(200)
            token.undeclare()
            end.undeclare()
            for sub in subs:
                sub.undeclare()


def remote_run(tampers: dict[int, Tamper], extra: Callable[[str, str, RunSecret], None] | None = None,
               spec: dict | None = None, timeout_s: float = 20.0, run_id: str | None = None,
               secret: RunSecret | None = None):
    """Run SPEC with the robots in ``tampers`` remote; ``extra(endpoint, run_id, secret)`` may start more
    sessions (injectors) before the agents join. A new run id and secret unless given."""
    endpoint = free_endpoint()
    run_id, secret = run_id or f"t-{uuid.uuid4().hex[:8]}", secret or RunSecret.generate()
    options = TransportOptions(listen=(endpoint,), remote=tuple(sorted(tampers)), timeout_s=timeout_s, run_id=run_id,
                               secret=secret)
    sim = Simulation(spec or SPEC, transport=options)
    box: dict = {}
    runner = threading.Thread(target=lambda: box.setdefault("r", sim.run()), daemon=True)
    runner.start()
    if extra is not None:  # the run waits for its agents: injectors are in place before the first tick
        extra(endpoint, run_id, secret)
    agents = [Agent(endpoint, run_id, secret.robot_token(run_id, r), t) for r, t in sorted(tampers.items())]
    for a in agents:
        a.start()
    for a in agents:
        assert a.connected.wait(30), "the agent's authenticated session never linked"
    runner.join(240)
    assert not runner.is_alive(), "the run must finish"
    return box["r"]


def same_run(a, b) -> None:
    """Everything a run computed is the same (the counts of dropped packets aside)."""
    for key in ("ticks", "explored", "coverage", "final_poses", "distance_m", "collisions", "plans", "ticks_to",
                "failed_robots"):
        assert a.summary[key] == b.summary[key], key
    assert a.timeseries == b.timeseries
    for key in ("sent", "delivered", "bytes_sent", "bytes_delivered", "dropped_link"):
        assert a.summary["messages"][key] == b.summary["messages"][key], key


@pytest.fixture(scope="module")
def clean():
    return Simulation({**SPEC, "transport": "inprocess"}).run()


def test_authenticated_remote_agents_equal_in_process(clean):
    r = remote_run({1: honest, 2: honest})
    assert r.deterministic_view()["summary"] == clean.deterministic_view()["summary"]
    assert r.timeseries == clean.timeseries
    assert r.summary["acts"] == {k: [0, 0, 0] for k in ACTS}


def test_forged_sender_and_wrong_shape_are_dropped_counted_and_the_run_goes_on(clean):
    forged = encode(Heartbeat(sender=0, tick=1, x=1.0, y=1.0, theta=0.0))
    small = encode(full_update(1, 1, 1, np.zeros((3, 3), np.uint8), (1.0, 1.0, 0.0)))
    r = remote_run({1: with_messages(forged, small), 2: honest})
    same_run(r, clean)
    ticks = r.summary["ticks"]
    assert r.summary["messages"]["malformed_by_robot"] == [0, 2 * ticks, 0]
    assert r.summary["messages"]["malformed"] == 2 * ticks
    reasons = {e["reason"] for e in r.events if e["event"] == "message_dropped"}
    assert any("claims sender" in x for x in reasons) and any("shape" in x for x in reasons)
    assert all(e["robot"] == 1 for e in r.events if e["event"] == "message_dropped")
    assert sum(e["event"] == "message_dropped" for e in r.events) == min(100, 2 * ticks)  # capped


def test_undecodable_and_corrupt_messages_are_dropped_one_by_one(clean):
    corrupt = msgpack.packb(["swarm.map_update", 1, 1, 1, 1, False, [80, 80], 5, b"not zlib", [1.0, 1.0, 0.0]],
                            use_bin_type=True)
    r = remote_run({1: with_messages(b"\x00random bytes", corrupt), 2: honest})
    same_run(r, clean)
    assert r.summary["messages"]["malformed_by_robot"] == [0, 2 * r.summary["ticks"], 0]
    assert r.summary["acts"]["malformed"] == [0, 0, 0], "the rest of each act was taken"


def test_a_duplicate_reply_is_counted_not_taken(clean):
    def twice(tick, act, token):
        other = encode_act(tick, 1, Action(velocity=(1.0, 1.0)))  # a different, valid decision: must not win
        return [(act, sign_act(token, tick, act)), (other, sign_act(token, tick, other))]

    r = remote_run({1: twice, 2: honest})
    same_run(r, clean)
    duplicates = r.summary["acts"]["duplicate"]
    # the last tick's second reply may come after the run has ended (nothing waits for it)
    assert duplicates[0] == duplicates[2] == 0 and r.summary["ticks"] - 1 <= duplicates[1] <= r.summary["ticks"]


def test_unsigned_and_mis_signed_acts_are_refused_and_counted(clean):
    """Packets on robot 1's act key without a valid tag (random bytes, an oversized payload, an act signed
    with another run's key, a replay of tick 0's signed reply): refused and counted, never taken, even when
    they arrive before the honest reply."""
    wrong = RunSecret.generate()
    first: dict = {}

    def hostile(tick, act, token):
        first.setdefault("act", (act, sign_act(token, tick, act)))
        forged = encode_act(tick, 1, Action(velocity=(1.0, 0.0)))
        other_key = wrong.robot_token(token.run_id, 1)
        return [(b"\x00" * 64, None), (b"x" * (3 << 20), sign_act(other_key, tick, b"x")),
                (forged, sign_act(other_key, tick, forged)), (forged, b"\x00" * 40),
                first["act"] if tick > 0 else (forged, None),
                (act, sign_act(token, tick, act))]

    r = remote_run({1: hostile, 2: honest})
    same_run(r, clean)
    ticks = r.summary["ticks"]
    assert r.summary["acts"]["refused"] == [0, 4 * ticks + 1, 0]
    assert r.summary["acts"]["duplicate"] == [0, ticks - 1, 0], "the replayed tick-0 reply: tick 0 was answered"
    assert r.summary["acts"]["late"] == [0, 0, 0]


def test_strangers_cannot_connect_and_other_agents_cannot_act_or_listen_for_a_robot(clean):
    """An unauthenticated session never links to the runtime; robot 2's authenticated agent cannot act for
    robot 1 (remote) or robot 0 (local) nor read their observations: the run is unchanged."""
    seen: dict[str, list] = {"stranger": [], "agent2": []}
    sessions = []

    def inject(endpoint: str, run_id: str, secret: RunSecret) -> None:
        robot2 = secret.robot_token(run_id, 2)
        deadline = time.monotonic() + 30
        while True:  # the runtime's listener opens in its thread: retry until this authenticated session links
            agent2 = zenoh.open(session_config(connect=[endpoint], user=robot2.user, password=robot2.password))
            time.sleep(0.2)
            if list(agent2.info.peers_zid()) or time.monotonic() > deadline:
                break
            agent2.close()
        stranger = zenoh.open(session_config(connect=[endpoint]))
        wrong_pw = zenoh.open(session_config(connect=[endpoint], user="robot-1", password="guess"))
        sessions.extend([stranger, wrong_pw, agent2])
        time.sleep(1.5)  # connect timeout: a refused session has given up by now
        assert list(agent2.info.peers_zid())
        assert not list(stranger.info.peers_zid()) and not list(wrong_pw.info.peers_zid())
        for name, s in (("stranger", stranger), ("agent2", agent2)):
            for key in (f"swarm/{run_id}/robot/0/**", f"swarm/{run_id}/robot/1/**", f"swarm/{run_id}/**"):
                s.declare_subscriber(key, lambda sample, n=name: seen[n].append(str(sample.key_expr)),
                                     allowed_origin=zenoh.Locality.REMOTE)  # not its own puts

        def flood() -> None:
            for k in range(400):
                for robot in (0, 1):
                    t1 = secret.robot_token(run_id, robot)
                    act = encode_act(k, robot, Action(velocity=(1.0, 1.0)))
                    for s in (stranger, agent2):
                        try:
                            s.put(f"swarm/{run_id}/robot/{robot}/act", act, attachment=sign_act(robot2, k, act))
                            s.put(f"swarm/{run_id}/robot/{robot}/act", act, attachment=sign_act(t1, k, act))
                        except zenoh.ZError:
                            return
                time.sleep(0.002)

        threading.Thread(target=flood, daemon=True).start()

    try:
        r = remote_run({1: honest, 2: honest}, extra=inject)
    finally:
        for s in sessions:
            s.close()
    same_run(r, clean)
    assert seen == {"stranger": [], "agent2": []}, "no observation of robots 0 and 1 reached them"
    assert r.summary["acts"] == {k: [0, 0, 0] for k in ACTS}, "nothing reached the runtime to count"


def test_a_signed_reply_for_another_robot_key_is_refused():
    """Robot 2's agent signs a reply with its own key and puts it on its own key, claiming robot 1 in the
    packet: malformed (wrong robot), not taken for robot 1."""
    def claims_robot_1(tick, act, token):
        other = encode_act(tick, 1, Action(velocity=(0.5, 0.0)))
        return [(other, sign_act(token, tick, other))]

    r = remote_run({1: honest, 2: claims_robot_1}, spec={**SPEC, "stop": {"max_ticks": 30}})
    assert r.summary["acts"]["malformed"] == [0, 0, r.summary["ticks"]]
    assert r.summary["failed_robots"] == []


@pytest.mark.parametrize("run_id", ["*", "**", "$*", "a/b", "a?b", "a#b", "a b", "", "x" * 101])
def test_run_ids_with_key_expression_syntax_are_refused(run_id):
    from swarm.base.errors import InvalidInput
    from swarm.transport.zenoh_host import ZenohHost

    with pytest.raises(InvalidInput, match="run id"):
        ZenohHost(run_id)


def test_wire_version_is_unchanged_by_signing():
    """The signature travels as the zenoh attachment: the act packet itself keeps its layout."""
    act = encode_act(3, 1, Action(goal=(1.0, 2.0)))
    assert msgpack.unpackb(act)[:4] == ["act", WIRE_VERSION, 3, 1]
