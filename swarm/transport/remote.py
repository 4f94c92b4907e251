"""``swarm agent``: run one robot's algorithm in this process against a simulation elsewhere.

The agent connects to the runtime's ``listen`` endpoint as its robot's zenoh user (authenticated with the
robot token, :mod:`swarm.transport.auth`), subscribes to its robot's keys, announces itself with a
liveliness token, takes the ``reset`` packet (algorithm, parameters, seed; its attachment is the run
nonce the act key is bound to) and then answers every observation with an act packet signed for its tick,
until the runtime publishes ``end``.
"""

from __future__ import annotations

import queue
import time
from typing import Callable

import zenoh

from swarm.base.errors import InvalidInput

from .agent import AgentRunner
from .auth import NONCE_BYTES, RobotToken, sign_act
from .sessions import open_session
from .wire import WireError, decode_reset
from .zenoh_host import BLOCK, CLOSE_TIMEOUT_S, close_session


def run_agent(connect: str, run_id: str, robot: int, token: RobotToken, algorithm: str | None = None,
              timeout_s: float = 60.0, log: Callable[[str], None] = print) -> int:
    """Serve one robot until the run ends; returns a process exit status (0 = the run ended normally)."""
    prefix = f"swarm/{run_id}"
    inbox: queue.SimpleQueue[tuple[str, bytes, bytes | None]] = queue.SimpleQueue()

    def push(kind: str) -> Callable[[zenoh.Sample], None]:
        def put(sample: zenoh.Sample) -> None:
            attachment = sample.attachment
            inbox.put((kind, sample.payload.to_bytes(), attachment.to_bytes() if attachment is not None else None))
        return put

    session = open_session("--connect", [connect], connect=[connect], user=token.user, password=token.password)
    declared = []
    try:
        deadline = time.monotonic() + timeout_s
        while not list(session.info.peers_zid()):
            if time.monotonic() > deadline:
                log(f"swarm agent: no runtime at {connect} accepted robot {robot}'s token after {timeout_s:g} s "
                    "(not running, another run, or a wrong token)")
                return 1
            time.sleep(0.01)
        for kind in ("reset", "obs"):
            declared.append(session.declare_subscriber(f"{prefix}/robot/{robot}/{kind}",
                                                       zenoh.handlers.Callback(push(kind), indirect=False)))
        declared.append(session.declare_subscriber(f"{prefix}/end", zenoh.handlers.Callback(push("end"), indirect=False)))
        act = session.declare_publisher(f"{prefix}/robot/{robot}/act", congestion_control=BLOCK)
        declared.append(act)
        declared.append(session.liveliness().declare_token(f"{prefix}/robot/{robot}/alive"))
        runner: AgentRunner | None = None
        act_key = b""
        while True:
            try:
                kind, data, attachment = inbox.get(timeout=timeout_s)
            except queue.Empty:
                log(f"swarm agent: nothing from the runtime for {timeout_s:g} s; giving up")
                return 1
            if kind == "end":
                log("swarm agent: run ended")
                return 0
            if kind == "reset":
                try:
                    if attachment is None or len(attachment) != NONCE_BYTES:
                        raise WireError(f"reset: no {NONCE_BYTES}-byte run nonce attached (a runtime of another "
                                        "swarm version?)")
                    reset = decode_reset(data)
                    runner = AgentRunner(reset, algorithm)
                except (WireError, InvalidInput) as exc:
                    log(f"swarm agent: cannot start from the runtime's reset packet ({str(exc)[:200]})")
                    return 2
                token = token.for_run(attachment)
                act_key = token.act_key
                log(f"swarm agent: robot {robot} of run {run_id}, algorithm {algorithm or reset.algorithm}")
            elif kind == "obs" and runner is not None:
                try:
                    obs = runner.observe(data)
                except WireError as exc:  # dropped unanswered: the runtime's timeout decides what follows
                    log(f"swarm agent: dropped a malformed obs packet ({exc})")
                    continue
                reply = runner.answer(obs)
                act.put(reply, attachment=sign_act(token, obs.tick, reply, act_key))
    finally:
        for d in reversed(declared):
            try:
                d.undeclare()
            except Exception:
                pass
        close_session(session, CLOSE_TIMEOUT_S)  # bounded: the exit status is decided
