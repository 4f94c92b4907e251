"""Hardening, round two (issue 48): the socket before authentication and one agent's share of a run.

Real processes and real zenoh sessions on loopback, no mocks; every test is bounded in time and count.
"""

from __future__ import annotations

import json
import os
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

pytestmark = pytest.mark.timeout(180)


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class HalfOpenFlood(threading.Thread):
    """``n`` TCP connections to 127.0.0.1:``port``, each sending two bytes (a zenoh frame's length, never
    its body) and holding; all closed and opened anew every ``renew_s`` seconds, until :meth:`stop`."""

    def __init__(self, port: int, n: int = 300, renew_s: float = 3.0) -> None:
        super().__init__(daemon=True)
        self.port, self.n, self.renew_s = port, n, renew_s
        self.waves = 0
        self._halt = threading.Event()

    def run(self) -> None:
        held: list[socket.socket] = []
        try:
            while not self._halt.is_set():
                for s in held:
                    s.close()
                held = []
                for _ in range(self.n):
                    s = socket.socket()
                    s.setblocking(False)
                    try:
                        s.connect(("127.0.0.1", self.port))
                    except OSError:  # BlockingIOError: in progress
                        pass
                    held.append(s)
                time.sleep(0.05)
                for s in held:
                    try:
                        s.send(b"\x00\x01")
                    except OSError:
                        pass
                self.waves += 1
                self._halt.wait(self.renew_s)
        finally:
            for s in held:
                s.close()

    def stop(self) -> None:
        self._halt.set()
        self.join(10)


def wait_listening(port: int, proc: subprocess.Popen, timeout_s: float = 60.0) -> None:
    """Until something accepts TCP connections on ``port`` (the runtime's zenoh listener)."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        assert proc.poll() is None, proc.communicate()
        try:
            with socket.create_connection(("127.0.0.1", port), timeout=0.5):
                return
        except OSError:
            time.sleep(0.1)
    raise AssertionError(f"nothing listens on port {port}")


def swarm(*args: str, env: dict[str, str] | None = None) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "swarm", *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, env={**os.environ, **(env or {})})


def test_a_half_open_connection_flood_keeps_no_agent_out_and_the_result_is_written(tmp_path: Path):
    """Issue 48 items 1-2: 300 half-open connections renewed every 3 s, from before the agents start until
    the run is over; both agents join, the run finishes promptly with its --json written, exit status 0."""
    port = free_port()
    endpoint, run_id, token, out = f"tcp/127.0.0.1:{port}", "flood48", tmp_path / "token", tmp_path / "r.json"
    runtime = swarm("run", "--transport", "zenoh", "--robots", "3", "--size", "30", "--max-ticks", "60",
                    "--listen", endpoint, "--remote", "1", "--remote", "2", "--token-file", str(token),
                    "--run-id", run_id, "--json", str(out))
    flood = HalfOpenFlood(port)
    agents: list[subprocess.Popen] = []
    try:
        wait_listening(port, runtime)
        flood.start()
        time.sleep(1.0)  # the first wave is in place before any agent connects
        agents = [swarm("agent", "--connect", endpoint, "--run", run_id, "--robot", str(r), "--token-file",
                        str(token), "--timeout", "40") for r in (1, 2)]
        t0 = time.monotonic()
        _, err = runtime.communicate(timeout=75)
        elapsed = time.monotonic() - t0
        assert flood.is_alive() and flood.waves >= 2, "the flood lasted the whole run"
    finally:
        flood.stop()
        for p in (runtime, *agents):
            if p.poll() is None:
                p.kill()
            p.communicate(timeout=30)
    assert runtime.returncode == 0, err[-2000:]
    result = json.loads(out.read_text())
    assert result["summary"]["failed_robots"] == [], [e for e in result["events"] if e["event"] == "agent_failed"]
    assert result["summary"]["ticks"] == 60
    assert elapsed < 45, f"the run took {elapsed:.1f} s"
    for a in agents:
        assert a.returncode == 0


def test_acts_captured_in_one_run_are_refused_in_the_next_with_the_same_run_id_and_secret():
    """Issue 48 item 4: run A's agent for robot 1 signs its own (different) decisions; run B, started with
    the same run id and secret, gets those captured acts replayed before each honest reply. Each run's
    nonce binds the signatures: B refuses every replay and equals the clean run."""
    from swarm.api import Action
    from swarm.sim.loop import Simulation
    from swarm.transport.auth import RunSecret, sign_act
    from swarm.transport.wire import encode_act
    from tests.swarm.transport.test_trust import SPEC, honest, remote_run, same_run

    spec = {**SPEC, "stop": {"max_ticks": 40}}
    run_id, secret = "replay48", RunSecret.generate()
    captured: dict[int, tuple[bytes, bytes]] = {}

    def own_decision(tick, act, token):  # run A: robot 1's agent drives its own way, validly signed
        mine = encode_act(tick, 1, Action(velocity=(1.0, 1.0)))
        captured[tick] = (mine, sign_act(token, tick, mine))
        return [captured[tick]]

    def replay_first(tick, act, token):  # run B: the captured act for this tick, then the honest one
        return [*([captured[tick]] if tick in captured else []), (act, sign_act(token, tick, act))]

    remote_run({1: own_decision, 2: honest}, spec=spec, run_id=run_id, secret=secret)
    assert len(captured) >= 40
    clean = Simulation({**spec, "transport": "inprocess"}).run()
    b = remote_run({1: replay_first, 2: honest}, spec=spec, run_id=run_id, secret=secret)
    same_run(b, clean)
    assert b.summary["acts"]["refused"] == [0, b.summary["ticks"], 0], "every replay refused"


def test_one_agent_flooding_its_outbox_fails_and_stalls_no_other_robot():
    """Issue 48 item 3: robot 1's authenticated agent puts one valid, signed, 8 MB act holding 170,000
    heartbeats at ticks 1 and 2 (its own decisions otherwise). Only the first MAX_MESSAGES_PER_TICK of each
    are taken, the rest dropped, counted as robot 1's malformed messages and noted in events; local robot
    0 and remote robot 2 never fail and the run keeps its pace."""
    import msgpack

    from swarm.comm.messages import MAX_MESSAGES_PER_TICK, Heartbeat, encode
    from swarm.transport.auth import sign_act
    from swarm.transport.wire import MAX_PACKET_BYTES
    from tests.swarm.transport.test_trust import SPEC, honest, remote_run

    flood = 170_000

    def heartbeats(tick, act, token):
        if tick not in (1, 2):
            return honest(tick, act, token)
        items = msgpack.unpackb(act)
        items[7] = [*items[7], *[encode(Heartbeat(sender=1, tick=tick, x=1.0, y=2.0, theta=0.3))] * flood]
        packet = msgpack.packb(items, use_bin_type=True)
        assert 8_000_000 < len(packet) <= MAX_PACKET_BYTES
        return [(packet, sign_act(token, tick, packet))]

    t0 = time.monotonic()
    r = remote_run({1: heartbeats, 2: honest}, spec={**SPEC, "stop": {"max_ticks": 40}})
    elapsed = time.monotonic() - t0
    assert r.summary["failed_robots"] == [], [e for e in r.events if e["event"] == "agent_failed"]
    assert r.summary["ticks"] == 40
    assert r.summary["acts"]["malformed"] == [0, 0, 0]
    over = 2 * (flood - MAX_MESSAGES_PER_TICK)
    assert r.summary["messages"]["malformed_by_robot"][0] == r.summary["messages"]["malformed_by_robot"][2] == 0
    assert r.summary["messages"]["malformed_by_robot"][1] == over
    budget = [e for e in r.events if e["event"] == "message_dropped" and "per-tick budget" in e["reason"]]
    assert [(e["tick"], e["robot"]) for e in budget] == [(1, 1), (2, 1)]
    assert elapsed < 60, f"40 ticks took {elapsed:.0f} s"


def test_messages_that_do_not_decode_at_all_are_counted_and_each_gets_an_event():
    """Issue 48 item 10 (first half): robot 1's agent adds an oversized, an unknown-type and a deeply nested
    message to its act at ticks 1-3. Each is dropped, counted as robot 1's malformed message and gets its
    own ``message_dropped`` event saying why; the run is the clean one."""
    import msgpack

    from swarm.comm.messages import MAX_MESSAGE_BYTES
    from swarm.sim.loop import Simulation
    from swarm.transport.auth import sign_act
    from tests.swarm.transport.test_trust import SPEC, honest, remote_run, same_run

    bad = [b"\x00" * (MAX_MESSAGE_BYTES + 1), msgpack.packb(["no.such.type", 1, 1]), b"\x91" * 5000 + b"\xc0"]

    def undecodable(tick, act, token):
        if tick not in (1, 2, 3):
            return honest(tick, act, token)
        items = msgpack.unpackb(act)
        items[7] = [*items[7], *bad]
        packet = msgpack.packb(items, use_bin_type=True)
        return [(packet, sign_act(token, tick, packet))]

    spec = {**SPEC, "stop": {"max_ticks": 30}}
    r = remote_run({1: undecodable, 2: honest}, spec=spec)
    same_run(r, Simulation({**spec, "transport": "inprocess"}).run())
    assert r.summary["messages"]["malformed_by_robot"] == [0, 9, 0]
    drops = [e for e in r.events if e["event"] == "message_dropped"]
    assert [(e["tick"], e["robot"]) for e in drops] == [(t, 1) for t in (1, 2, 3) for _ in bad]
    reasons = [e["reason"] for e in drops[:3]]
    assert "larger than" in reasons[0] and "unknown message type" in reasons[1] and "undecodable" in reasons[2]
    assert all(r.startswith("does not decode") for r in reasons)


class Chatty:
    """A module:Class algorithm whose robot 1 sends 100 heartbeats a tick (robot 0 stays quiet)."""

    name = "chatty"

    def reset(self, robot, params, rng):
        self.id = robot.id

    def act(self, obs):
        from swarm.api import Action
        from swarm.comm.messages import Heartbeat

        x, y, theta = obs.pose
        beats = tuple(Heartbeat(sender=self.id, tick=obs.tick, x=x, y=y, theta=theta) for _ in range(100))
        return Action(velocity=(0.2, 0.1), messages=beats if self.id == 1 else ())


def test_the_per_tick_budget_is_the_same_in_process_and_over_zenoh():
    """The budget is applied where every transport's actions meet the radio: an in-process algorithm that
    sends 100 messages a tick has 64 sent and 36 dropped and counted, with one event a tick, exactly as
    over zenoh (bit-identical results)."""
    from swarm.comm.messages import MAX_MESSAGES_PER_TICK
    from swarm.sim.loop import Simulation

    spec = {"seed": 3, "map": {"kind": "building", "size": 30}, "robots": {"count": 2},
            "algorithm": {"name": "tests.swarm.transport.test_hardening:Chatty"}, "stop": {"max_ticks": 20}}
    a = Simulation({**spec, "transport": "inprocess"}).run()
    b = Simulation({**spec, "transport": "zenoh"}).run()
    ticks = a.summary["ticks"]
    assert a.summary["messages"]["malformed_by_robot"] == [0, (100 - MAX_MESSAGES_PER_TICK) * ticks]
    sent = a.summary["messages"]["sent"]  # robot 1's heartbeats and the runtime's map sharing
    assert MAX_MESSAGES_PER_TICK * ticks <= sent < (MAX_MESSAGES_PER_TICK + 1) * ticks
    budget = [e for e in a.events if e["event"] == "message_dropped"]
    assert [(e["tick"], e["robot"]) for e in budget] == [(t, 1) for t in range(ticks)]
    assert "36 message(s) over the per-tick budget" in budget[0]["reason"]
    def strip(r):
        return {k: v for k, v in r.deterministic_view().items() if k not in ("spec", "key")}

    assert strip(a) == strip(b)


def make_certificates(folder: Path) -> tuple[str, str, str]:
    """A throw-away certificate authority and a certificate it signed for localhost / 127.0.0.1: the
    paths of the CA's certificate, the server's certificate and its private key (PEM)."""
    import datetime
    import ipaddress

    from cryptography import x509
    from cryptography.hazmat.primitives import hashes, serialization
    from cryptography.hazmat.primitives.asymmetric import ec
    from cryptography.x509.oid import NameOID

    now = datetime.datetime.now(datetime.UTC)
    ca_key, key = ec.generate_private_key(ec.SECP256R1()), ec.generate_private_key(ec.SECP256R1())
    ca_name = x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, "swarm test CA")])
    ca = (x509.CertificateBuilder().subject_name(ca_name).issuer_name(ca_name).public_key(ca_key.public_key())
          .serial_number(x509.random_serial_number()).not_valid_before(now - datetime.timedelta(hours=1))
          .not_valid_after(now + datetime.timedelta(hours=2))
          .add_extension(x509.BasicConstraints(ca=True, path_length=None), critical=True).sign(ca_key, hashes.SHA256()))
    leaf = (x509.CertificateBuilder().subject_name(x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, "localhost")]))
            .issuer_name(ca_name).public_key(key.public_key()).serial_number(x509.random_serial_number())
            .not_valid_before(now - datetime.timedelta(hours=1)).not_valid_after(now + datetime.timedelta(hours=2))
            .add_extension(x509.SubjectAlternativeName([x509.DNSName("localhost"),
                                                        x509.IPAddress(ipaddress.ip_address("127.0.0.1"))]), critical=False)
            .add_extension(x509.BasicConstraints(ca=False, path_length=None), critical=True).sign(ca_key, hashes.SHA256()))
    paths = (folder / "ca.pem", folder / "server.pem", folder / "server.key")
    paths[0].write_bytes(ca.public_bytes(serialization.Encoding.PEM))
    paths[1].write_bytes(leaf.public_bytes(serialization.Encoding.PEM))
    paths[2].write_bytes(key.private_bytes(serialization.Encoding.PEM, serialization.PrivateFormat.PKCS8,
                                           serialization.NoEncryption()))
    return tuple(str(p) for p in paths)


def test_a_tls_endpoint_carries_the_run_and_refuses_plain_tcp(tmp_path: Path, monkeypatch: pytest.MonkeyPatch):
    """docs/security.md's recipe: the runtime listens on tls/localhost:PORT with SWARM_TLS_CERTIFICATE and
    SWARM_TLS_PRIVATE_KEY; an agent given SWARM_TLS_ROOT_CA joins and drives its robot; a plain-TCP zenoh
    session to the same port never links."""
    import uuid

    import zenoh

    from swarm.sim.loop import Simulation, TransportOptions
    from swarm.transport.auth import RunSecret
    from swarm.transport.sessions import session_config

    ca, cert, key = make_certificates(tmp_path)
    monkeypatch.setenv("SWARM_TLS_CERTIFICATE", cert)
    monkeypatch.setenv("SWARM_TLS_PRIVATE_KEY", key)
    port = free_port()
    endpoint, run_id, secret = f"tls/localhost:{port}", f"tls-{uuid.uuid4().hex[:8]}", RunSecret.generate()
    spec = {"seed": 1, "map": {"kind": "building", "size": 30}, "robots": {"count": 2}, "transport": "zenoh",
            "stop": {"max_ticks": 40}}
    sim = Simulation(spec, transport=TransportOptions(listen=(endpoint,), remote=(1,), timeout_s=20, run_id=run_id,
                                                      secret=secret))
    box: dict = {}
    runner = threading.Thread(target=lambda: box.setdefault("r", sim.run()), daemon=True)
    runner.start()
    token = secret.robot_token(run_id, 1)
    plain = zenoh.open(session_config(connect=[f"tcp/localhost:{port}"], user=token.user, password=token.password))
    agent = swarm("agent", "--connect", endpoint, "--run", run_id, "--robot", "1", "--timeout", "40",
                  env={"SWARM_TOKEN": token.text(), "SWARM_TLS_ROOT_CA": ca})
    try:
        runner.join(120)
        assert not runner.is_alive(), "the run must finish"
        assert not list(plain.info.peers_zid()), "a plain-TCP session never linked to the TLS endpoint"
        _, err = agent.communicate(timeout=30)
    finally:
        plain.close()
        if agent.poll() is None:
            agent.kill()
            agent.communicate(timeout=30)
    assert agent.returncode == 0, err[-2000:]
    r = box["r"]
    assert r.summary["failed_robots"] == [] and r.summary["distance_m"][1] > 0.5
    assert r.summary["acts"] == {k: [0, 0] for k in ("malformed", "refused", "late", "duplicate")}


def test_agents_near_their_byte_budget_do_not_fail_the_local_robot():
    """Three remote agents each send one valid 3 MB message (a minotaur doorway list of 75,000 doorways,
    inside the 4 MiB per-tick budget) at tick 1: the runtime's own batch for its local robot 0 then holds
    9 MB, more than a packet from the network may; it is the runtime's own packet, so robot 0 goes on.
    (The senders' own test agents decode each other's lists on zenoh's thread and may lose their link.)"""
    import msgpack

    from algorithms.minotaur.messages import DoorwayList
    from swarm.comm.messages import MAX_BYTES_PER_TICK, encode
    from swarm.transport.auth import sign_act
    from swarm.transport.wire import MAX_PACKET_BYTES
    from tests.swarm.transport.test_trust import SPEC, honest, remote_run

    def doorways(tick, act, token):
        if tick != 1:
            return honest(tick, act, token)
        doors = tuple((1.0 + k % 1000, 2.0 + k // 1000, k % 2, 1.5, 0.5, 1, 0) for k in range(75_000))
        blob = encode(DoorwayList(sender=token.robot, doors=doors, target=(1.0, 1.0), door=()))
        assert 3 * len(blob) > MAX_PACKET_BYTES and len(blob) <= MAX_BYTES_PER_TICK
        items = msgpack.unpackb(act)
        items[7] = [*items[7], blob]
        packet = msgpack.packb(items, use_bin_type=True)
        return [(packet, sign_act(token, tick, packet))]

    spec = {**SPEC, "robots": {"count": 4}, "stop": {"max_ticks": 6}}
    r = remote_run({1: doorways, 2: doorways, 3: doorways}, spec=spec)
    assert 0 not in r.summary["failed_robots"], [e for e in r.events if e["event"] == "agent_failed"]
    assert r.summary["messages"]["malformed"] == 0 and r.summary["ticks"] == 6
    assert r.summary["messages"]["delivered"] >= 3, "the lists reached robot 0"


def test_a_remote_robots_observation_may_carry_every_other_robots_budget():
    """Two other robots' full per-tick budgets (4 MiB each) in one robot's inbox make an 8 MiB+ obs packet:
    its agent takes it (the limit grows with the run's robot count), where it used to drop it and let its
    robot time out. A packet larger than every budget together is still refused."""
    import numpy as np

    from swarm.base.types import NavStatus
    from swarm.comm.messages import MAX_BYTES_PER_TICK
    from swarm.transport.wire import MAX_PACKET_BYTES, WireError, decode_obs, encode_obs

    def obs(inbox):
        return encode_obs(5, 2, (1.0, 2.0, 0.0), np.zeros(0, np.int64), np.zeros(0, np.uint8), inbox, (), False,
                          NavStatus(), 0.0, 0.0)

    full = obs((b"\x00" * (MAX_BYTES_PER_TICK - 16),) * 2)
    assert len(full) > MAX_PACKET_BYTES
    assert len(decode_obs(full, 100, n_robots=3).inbox) == 2
    with pytest.raises(WireError, match="larger than"):
        decode_obs(obs((b"\x00" * (MAX_BYTES_PER_TICK - 16),) * 5), 100, n_robots=3)
