"""Transports: in-process and zenoh give identical runs; remote agents join, may die, may misbehave.

Every test here opens real zenoh sessions on loopback (no mocks) and closes them; each has a timeout.
"""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import threading
import time
import uuid

import msgpack
import pytest
import zenoh

from swarm.api import Action
from swarm.sim.loop import Simulation, TransportOptions
from swarm.transport.auth import RunSecret, sign_act
from swarm.transport.sessions import session_config
from swarm.transport.wire import WIRE_VERSION, decode_obs, encode_act

pytestmark = pytest.mark.timeout(240)

SPEC = {"seed": 4, "map": {"kind": "building", "size": 40}, "robots": {"count": 3}, "stop": {"max_ticks": 300}}


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


SECRET = RunSecret.generate()


def start_agent(endpoint: str, run_id: str, robot: int, secret: RunSecret = SECRET) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "swarm", "agent", "--connect", endpoint, "--run", run_id,
                             "--robot", str(robot), "--timeout", "60"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env={**os.environ, "PYTHONHASHSEED": "7",
                                 "SWARM_TOKEN": secret.robot_token(run_id, robot).text()})


def remote_options(robots=(1,)):
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    return endpoint, TransportOptions(listen=(endpoint,), remote=tuple(robots), timeout_s=20.0,
                                      run_id=f"test-{uuid.uuid4().hex[:8]}", secret=SECRET)


def test_inprocess_and_zenoh_give_bit_identical_runs():
    a = Simulation({**SPEC, "transport": "inprocess"}).run()
    b = Simulation({**SPEC, "transport": "zenoh"}).run()
    strip = lambda r: {k: v for k, v in r.deterministic_view().items() if k not in ("spec", "key")}  # noqa: E731
    assert strip(a) == strip(b)
    assert a.summary["messages"]["delivered"] > 0, "map sharing was exercised"


def test_agent_in_another_process_gives_the_same_run():
    local = Simulation({**SPEC, "transport": "zenoh"}).run()
    endpoint, options = remote_options()
    sim = Simulation({**SPEC, "transport": "zenoh"}, transport=options)
    agent = None
    try:
        result_box = {}
        runner = threading.Thread(target=lambda: result_box.setdefault("r", sim.run()))
        runner.start()
        agent = start_agent(endpoint, options.run_id, 1)
        runner.join(180)
        assert not runner.is_alive()
        remote = result_box["r"]
        out, err = agent.communicate(timeout=30)
        assert agent.returncode == 0, err
        assert "run ended" in err
    finally:
        if agent and agent.poll() is None:
            agent.kill()
    assert remote.summary["final_poses"] == local.summary["final_poses"]
    assert remote.timeseries == local.timeseries
    assert remote.summary["failed_robots"] == []


def test_parallel_runs_with_the_same_ids_never_cross_talk():
    """Two identical runs with remote agents at the same time, with a third session bridging both networks:
    keys are namespaced per run, so each run still equals a solo run."""
    solo = Simulation({**SPEC, "transport": "zenoh"}).run()
    runs = [remote_options() for _ in range(2)]
    bridge = zenoh.open(session_config(connect=[ep for ep, _ in runs]))
    procs, threads, results = [], [], {}
    try:
        for k, (ep, opts) in enumerate(runs):
            sim = Simulation({**SPEC, "transport": "zenoh"}, transport=opts)
            t = threading.Thread(target=lambda k=k, sim=sim: results.setdefault(k, sim.run()))
            t.start()
            threads.append(t)
            procs.append(start_agent(ep, opts.run_id, 1))
        for t in threads:
            t.join(180)
        for p in procs:
            p.communicate(timeout=30)
    finally:
        for p in procs:
            if p.poll() is None:
                p.kill()
        bridge.close()
    for k in range(2):
        assert results[k].timeseries == solo.timeseries
        assert results[k].summary["acts"] == {kind: [0, 0, 0] for kind in ("malformed", "refused", "late", "duplicate")}


def test_killed_remote_agent_fails_its_robot_and_the_run_goes_on():
    endpoint, options = remote_options()
    spec = {**SPEC, "transport": "zenoh", "stop": {"max_ticks": 400}}
    options = TransportOptions(listen=options.listen, remote=(1,), timeout_s=5.0, run_id=options.run_id, secret=SECRET)
    holder: dict = {}

    def kill_at_tick_100(view):
        if view.tick == 100 and "agent" in holder:
            holder["agent"].send_signal(signal.SIGKILL)
            holder["agent"].wait(10)
            holder["killed_at"] = view.tick

    sim = Simulation(spec, transport=options, observers=(kill_at_tick_100,))
    box = {}
    t = threading.Thread(target=lambda: box.setdefault("r", sim.run()))
    t.start()
    holder["agent"] = start_agent(endpoint, options.run_id, 1)
    t.join(120)
    assert not t.is_alive(), "the run must not hang when an agent dies"
    r = box["r"]
    assert r.summary["ticks"] == 400 or r.summary["stop_reason"] == "explored"
    assert r.summary["failed_robots"] == [1]
    event = [e for e in r.events if e["event"] == "agent_failed"][0]
    assert event["robot"] == 1 and event["tick"] == holder["killed_at"] + 1
    assert r.summary["distance_m"][1] > 0, "robot 1 drove before its agent died"


def test_malformed_actions_are_dropped_and_counted():
    """A hand-written agent on a raw zenoh session answers with garbage, wrong versions, forged ticks and
    oversized payloads before behaving: the runtime counts them and never crashes."""
    endpoint, options = remote_options()
    spec = {**SPEC, "transport": "zenoh", "stop": {"max_ticks": 12}}
    sim = Simulation(spec, transport=options)
    box = {}
    t = threading.Thread(target=lambda: box.setdefault("r", sim.run()))
    t.start()
    prefix = f"swarm/{options.run_id}/robot/1"
    bad = [b"\x00garbage", msgpack.packb(["act", WIRE_VERSION + 1]), msgpack.packb(["act", WIRE_VERSION, 0]),
           encode_act(999, 1, Action()), b"x" * (9 * 1024 * 1024),
           msgpack.packb(["act", WIRE_VERSION, 5, 1, ["a", 1], None, False, [b"\x01"], None])]
    token = SECRET.robot_token(options.run_id, 1)
    with zenoh.open(session_config(connect=[endpoint], user=token.user, password=token.password)) as s:
        while not list(s.info.peers_zid()):
            time.sleep(0.01)
        answered = []
        nonce = threading.Event()

        def on_reset(sample):  # the run nonce the act key is bound to
            nonlocal token
            token = token.for_run(sample.attachment.to_bytes())
            nonce.set()

        def on_obs(sample):
            assert nonce.is_set()
            packet = decode_obs(sample.payload.to_bytes(), 80 * 80)
            k = len(answered)
            answered.append(packet.tick)
            reply = bad[k] if k < len(bad) else encode_act(packet.tick, 1, Action())
            # BLOCK as the real agent's publisher: zenoh's default (DROP) may lose the 9 MB reply on a busy machine
            s.put(f"{prefix}/act", reply, attachment=sign_act(token, packet.tick, reply),
                  congestion_control=zenoh.CongestionControl.BLOCK)

        reset = s.declare_subscriber(f"{prefix}/reset", zenoh.handlers.Callback(on_reset, indirect=False))
        sub = s.declare_subscriber(f"{prefix}/obs", zenoh.handlers.Callback(on_obs, indirect=False))
        alive = s.liveliness().declare_token(f"{prefix}/alive")
        t.join(60)
        alive.undeclare()
        sub.undeclare()
        reset.undeclare()
    assert not t.is_alive()
    r = box["r"]
    assert r.summary["acts"]["malformed"] == [0, len(bad), 0]
    assert r.summary["failed_robots"] == [] and r.summary["ticks"] == 12


def test_phase_timers_see_each_step_and_change_no_result():
    """``TransportOptions.times`` (bench_transport --split) measures without changing the run, and an
    unmeasured run calls the plain functions (no wrapper). The local agents are served by one batch each way
    per tick, whichever way their maps reach them."""
    from swarm.transport.timing import PhaseTimes, timed

    strip = lambda r: {k: v for k, v in r.deterministic_view().items() if k not in ("spec", "key")}  # noqa: E731
    plain = Simulation({**SPEC, "transport": "zenoh"}).run()
    ticks, robots = plain.summary["ticks"], SPEC["robots"]["count"]
    for share_maps in (True, False):
        times = {t: PhaseTimes() for t in ("inprocess", "zenoh")}
        runs = {t: Simulation({**SPEC, "transport": t},
                              transport=TransportOptions(times=times[t], share_maps=share_maps)).run() for t in times}
        assert strip(runs["zenoh"]) == strip(plain) == strip(runs["inprocess"])
        z, i = times["zenoh"], times["inprocess"]
        for phase in ("zenoh: obs put", "agent: observe", "agent: act encode", "zenoh: act put", "host: act decode",
                      "host: batch", "host: neighbours", "host: obs encode"):
            assert z.calls[phase] == ticks, phase
        assert z.calls["agent: algorithm"] == ticks * robots
        assert z.calls.get("host: changed cells", 0) == (0 if share_maps else ticks)
        assert i.calls["agent: algorithm"] == ticks * robots and i.calls["host: inputs"] == ticks
        assert z.get("agent: observe") > 0 and z.get("zenoh: obs put") > 0
    fn = len
    assert timed(None, "x", fn) is fn


RUN_LISTENING = [sys.executable, "-m", "swarm", "run", "--transport", "zenoh", "--size", "20", "--robots", "2",
                 "--max-ticks", "20", "--remote", "1", "--agent-timeout", "20"]


def test_a_listen_endpoint_that_cannot_be_bound_fails_before_any_agent_command_is_printed():
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        endpoint = f"tcp/127.0.0.1:{taken.getsockname()[1]}"
        proc = subprocess.run([*RUN_LISTENING, "--listen", endpoint], capture_output=True, text=True, timeout=120,
                              env={k: v for k, v in os.environ.items() if k != "SWARM_TOKEN"}, check=False)
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.startswith("swarm: error: --listen: ") and proc.stderr.count("\n") == 1, proc.stderr
    assert "waiting for" not in proc.stderr + proc.stdout


def test_the_agent_command_is_printed_once_the_runtime_listens_and_starts_the_agent():
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    env = {k: v for k, v in os.environ.items() if k != "SWARM_TOKEN"}
    run = subprocess.Popen([*RUN_LISTENING, "--listen", endpoint], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                           text=True, env=env)
    agent = None
    try:
        line = run.stderr.readline()
        assert line.startswith(f"waiting for: swarm agent --connect {endpoint} --run "), line
        with socket.create_connection(("127.0.0.1", int(endpoint.rsplit(":", 1)[1])), timeout=5):
            pass  # the endpoint is bound when the command is printed
        agent = subprocess.Popen([sys.executable, "-m", *line.split("waiting for: ", 1)[1].split()],
                                 stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
        out, err = run.communicate(timeout=120)
        assert run.returncode == 0, err
        assert "stopped at tick" in out
    finally:
        for proc in (run, agent):
            if proc is not None and proc.poll() is None:
                proc.kill()
                proc.wait(10)
