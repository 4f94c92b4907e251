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
