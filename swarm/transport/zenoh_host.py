"""Observations and actions through real zenoh sessions, in lockstep.

Key expressions (``<run>`` is unique per run, so parallel runs never cross-talk):

* ``swarm/<run>/robot/<id>/reset``  runtime -> agent: robot facts, algorithm, parameters, seed
* ``swarm/<run>/robot/<id>/obs``    runtime -> agent: the observation of tick t
* ``swarm/<run>/robot/<id>/act``    agent -> runtime: the action for tick t
* ``swarm/<run>/robot/<id>/alive``  liveliness token of a remote agent (its loss = the agent died)
* ``swarm/<run>/local/obs``         runtime -> the agents in its own process: one ``obs_batch`` per tick
* ``swarm/<run>/local/act``         those agents -> runtime: one ``act_batch`` per tick
* ``swarm/<run>/end``               runtime -> agents: the run is over

Agents in the runtime's process share its session and are served together
(:class:`~swarm.transport.group.AgentGroup`): one batched put per tick to a ``Callback(indirect=False)``
subscriber, which keeps the packet within the put; the group then decides for all of them and answers
with one batched put (docs/measurements.md A4 has the cost of each layout; :mod:`swarm.transport.batch`
the packets). They read their maps in the runtime's memory unless ``share_maps`` is False. Remote
agents connect to the runtime's ``listen`` endpoint; the runtime waits for every live agent's action for
tick t before advancing, so thread timing never changes a result. A remote agent that loses its
liveliness token or stays silent for ``timeout_s`` is marked failed at that tick and its robot stops.
Sessions open in peer mode with multicast scouting off and no endpoints unless given (loopback only).

**Trust** (:mod:`swarm.transport.auth`). Local robots' keys never leave this session: the ``local/obs`` and
``local/act`` publishers and subscribers are session-local, so no packet from the network can act for them.
A listening runtime admits only sessions that pass zenoh's usrpwd authentication as a remote robot's user
and lets each see and send only its own robot's keys (zenoh access control). Every act packet of a
remote robot must carry a valid HMAC tag for its tick under that robot's key; the first signed reply per
robot and tick is taken; a later one for a tick already answered (a second reply, a replay) is counted
(``duplicate``), one for a tick not asked or given up on (``late``), unsigned or wrongly signed ones are
refused and counted (``refused``), a taken one that does not decode is counted (``malformed``) and the
robot keeps doing what it did.
"""

from __future__ import annotations

import threading
import time
import uuid
from typing import Callable, Sequence

import numpy as np
import zenoh

from swarm.base.types import Action
from .auth import Credentials, RunSecret, access_control, check_run_id, new_nonce, verify_act
from .base import HostStats, TickBatch
from .batch import ActBatchDecoder, BatchEncoder
from .group import AgentGroup
from .packing import ObsEncoder
from .sessions import open_session, session_config
from .timing import PhaseTimes, timed
from .wire import ResetPacket, WireError, decode_act, encode_reset

BLOCK = zenoh.CongestionControl.BLOCK
_NO_CELLS = np.zeros(0, dtype=np.int64)


def new_run_id(key: str) -> str:
    return f"{key}-{uuid.uuid4().hex[:8]}"


LOCAL, REMOTE = zenoh.Locality.SESSION_LOCAL, zenoh.Locality.REMOTE


def robot_of(key_expr: object) -> int | None:
    """The robot id in ``swarm/<run>/robot/<id>/...``."""
    parts = str(key_expr).split("/")
    try:
        return int(parts[parts.index("robot") + 1])
    except (ValueError, IndexError):
        return None


class ZenohHost:
    def __init__(self, run_id: str, listen: Sequence[str] = (), remote: Sequence[int] = (),
                 timeout_s: float = 10.0, join_timeout_s: float = 60.0, times: PhaseTimes | None = None,
                 secret: RunSecret | None = None, share_maps: bool = True) -> None:
        """``listen``: endpoints remote agents connect to (authenticated with robot tokens derived from
        ``secret``, a fresh one if None); ``times`` (for benchmarks): where the ticks go, see
        :mod:`swarm.transport.timing`; ``share_maps``: the agents in this process read the runtime's maps in
        place (False: they keep mirrors fed with the changed cells, as remote agents do)."""
        self.stats = HostStats()
        self.share_maps = share_maps
        self.mirrors = bool(remote) or not share_maps  # packets carry changed cells to someone
        self._times = times
        self._decode_act = timed(times, "host: act decode", decode_act)
        self.run_id = check_run_id(run_id, "run id")
        self.prefix = f"swarm/{run_id}"
        self.remote = set(remote)
        self.timeout_s = timeout_s
        self.join_timeout_s = join_timeout_s
        self.secret = secret or RunSecret.generate()
        self.nonce = new_nonce()  # this start's: acts signed for another run (same id and secret) are refused
        self._tokens = {r: self.secret.robot_token(run_id, r).for_run(self.nonce) for r in sorted(self.remote)}
        self._credentials: Credentials | None = None
        if listen:
            self._credentials = Credentials(list(self._tokens.values()))
            try:
                self.session = open_session("--listen", list(listen), listen=listen,
                                            dictionary_file=str(self._credentials.path),
                                            access_control=access_control(self.prefix, sorted(self.remote)))
            except BaseException:
                self._credentials.remove()
                raise
        else:
            self.session = zenoh.open(session_config())
        self._cond = threading.Condition()
        self._tick = -1  # the tick whose replies are awaited
        self._taken: dict[int, int] = {}  # remote robot -> the last tick whose reply was taken
        self._replies: dict[int, bytes] = {}
        self._alive: set[int] = set()
        self._lost: set[int] = set()
        self._publishers: dict[int, zenoh.Publisher] = {}
        self._puts: dict[int, Callable[[bytes], None]] = {}  # the obs publishers' put, timed when asked
        self._declared: list = []
        self.group: AgentGroup | None = None  # the agents in this process
        self._local_obs: list[bytes] = []     # what the local keys' callbacks received (one packet a tick)
        self._local_act: list[bytes] = []
        self._decode_batch = timed(times, "host: act decode", ActBatchDecoder())
        if self.remote:
            self._declared.append(self.session.liveliness().declare_subscriber(
                f"{self.prefix}/robot/*/alive", zenoh.handlers.Callback(self._on_alive, indirect=False), history=True))

    # ---------------------------------------------------------------------------------- callbacks ----
    def _act_subscriber(self, robot: int) -> None:
        """One subscriber per remote robot's act key, so a reply needs no key parsing: it takes only the
        network's samples, checks each reply's signature and tick, keeps the first and wakes act()."""
        replies = self._replies
        token = self._tokens[robot]
        key = token.act_key
        stats = self.stats
        taken = self._taken

        def on_act(sample: zenoh.Sample) -> None:
            data = sample.payload.to_bytes()
            attachment = sample.attachment
            tick = verify_act(token, key, attachment.to_bytes() if attachment is not None else None, data)
            with self._cond:
                if tick is None:
                    stats.count("refused", robot)
                elif tick == self._tick and robot not in replies:
                    replies[robot] = data
                    taken[robot] = tick
                    self._cond.notify_all()
                elif tick <= taken.get(robot, -1):  # a second reply (or a replay) for a tick already answered
                    stats.count("duplicate", robot)
                else:  # a tick not asked yet, or one given up on
                    stats.count("late", robot)

        self._declared.append(self.session.declare_subscriber(
            f"{self.prefix}/robot/{robot}/act", zenoh.handlers.Callback(on_act, indirect=False), allowed_origin=REMOTE))

    def _on_alive(self, sample: zenoh.Sample) -> None:
        robot = robot_of(sample.key_expr)
        if robot is None:
            return
        with self._cond:
            if sample.kind == zenoh.SampleKind.PUT:
                self._alive.add(robot)
            else:
                self._lost.add(robot)
            self._cond.notify_all()

    def _local_group(self, resets: Sequence[ResetPacket]) -> None:
        """The agents of this process as one :class:`AgentGroup` behind the session-local ``local/obs`` and
        ``local/act`` keys. Their callbacks run inside the puts, in :meth:`act`'s thread, and only keep the
        packet; the group answers in :meth:`_answer_local`, outside zenoh's callback, so an algorithm that
        raises stops the run exactly as it does in process."""
        self.group = AgentGroup(resets, times=self._times)
        obs = self.session.declare_publisher(f"{self.prefix}/local/obs", congestion_control=BLOCK,
                                             allowed_destination=LOCAL)
        act = self.session.declare_publisher(f"{self.prefix}/local/act", congestion_control=BLOCK,
                                             allowed_destination=LOCAL)
        self._declared += [obs, act]
        self._put_obs_batch = timed(self._times, "zenoh: obs put", obs.put)
        self._put_act_batch = timed(self._times, "zenoh: act put", act.put)
        for key, inbox in (("obs", self._local_obs), ("act", self._local_act)):
            self._declared.append(self.session.declare_subscriber(
                f"{self.prefix}/local/{key}", zenoh.handlers.Callback(lambda sample, inbox=inbox: inbox.append(
                    sample.payload.to_bytes()), indirect=False), allowed_origin=LOCAL))

    def _answer_local(self, tick: int, ids: list[int]) -> bytes | None:
        """The local agents' act batch for the obs batch just delivered (None, the robots marked failed, if
        the group refused it or nothing arrived)."""
        delivered, replies = self._local_obs, self._local_act
        replies.clear()
        if len(delivered) != 1:
            reason = "the local agents' observation was not delivered once"
        else:
            try:
                self._put_act_batch(self.group.handle(delivered.pop()))
            except WireError as exc:
                reason = f"the local agents refused their observation ({str(exc)[:80]})"
            else:
                if len(replies) == 1:
                    return replies.pop()
                reason = "the local agents' action was not delivered once"
        delivered.clear()
        replies.clear()
        for i in ids:
            self.stats.failures[i] = (tick, reason)
        return None

    # ---------------------------------------------------------------------------------- interface ----
    def start(self, resets: Sequence[ResetPacket]) -> None:
        n = len(resets)
        local = [r for r in resets if r.robot.id not in self.remote]
        self._local_mask = np.zeros(n, dtype=bool)
        self._local_mask[[r.robot.id for r in local]] = True
        self._encode = timed(self._times, "host: obs encode", ObsEncoder(n, compress=self.remote))
        self._encode_batch = timed(self._times, "host: obs encode", BatchEncoder([r.robot.id for r in local], n))
        self._no_ends = np.zeros(n, dtype=np.int64)
        if local:
            self._local_group(local)
        for reset in resets:
            i = reset.robot.id
            if i not in self.remote:
                continue
            self._act_subscriber(i)
            publisher = self.session.declare_publisher(f"{self.prefix}/robot/{i}/obs", congestion_control=BLOCK,
                                                       allowed_destination=REMOTE)
            self._publishers[i] = publisher
            self._puts[i] = timed(self._times, "zenoh: obs put", publisher.put)
        if self.remote:
            deadline = time.monotonic() + self.join_timeout_s
            with self._cond:
                self._cond.wait_for(lambda: self.remote <= self._alive or time.monotonic() > deadline,
                                    timeout=self.join_timeout_s)
            missing = self.remote - self._alive
            for i in sorted(missing):
                self.stats.failures[i] = (0, "never joined")
            for reset in resets:
                if reset.robot.id in self.remote and reset.robot.id not in missing:
                    self.session.put(f"{self.prefix}/robot/{reset.robot.id}/reset", encode_reset(reset),
                                     attachment=self.nonce, congestion_control=BLOCK)

    def act(self, batch: TickBatch) -> list[Action | None]:
        tick = batch.tick
        asked = batch.live
        if self.stats.failures:  # failed here, not yet in the runtime's live mask (e.g. never joined)
            asked = asked.copy()
            asked[list(self.stats.failures)] = False
        with self._cond:
            self._replies.clear()
            self._tick = tick
        cells, ends = batch.changed() if self.mirrors else (_NO_CELLS, self._no_ends)
        distance, near = batch.sight()
        energy = batch.travelled + batch.rotation
        actions: list[Action | None] = [None] * len(asked)
        remote = []
        if self.remote:  # first, so remote agents work while the local ones do
            inboxes = [tuple([env.data for env in inbox]) if inbox else () for inbox in batch.inboxes]
            packets = self._encode(tick, asked & ~self._local_mask, batch.poses, batch.collided, batch.travelled,
                                   energy, batch.navs, batch.known, cells, ends, inboxes, near, distance)
            for i, packet in enumerate(packets):
                if packet is not None:
                    remote.append(i)
                    self._puts[i](packet)
        if self.group is not None:
            self._act_local(tick, asked, batch, energy, cells, ends, near, distance, actions)
        if remote:
            self._wait(remote)
            self._take_remote(tick, remote, actions)
        return actions

    def _act_local(self, tick: int, asked: np.ndarray, batch: TickBatch, energy: np.ndarray, cells: np.ndarray,
                   ends: np.ndarray, near: np.ndarray, distance: np.ndarray, actions: list[Action | None]) -> None:
        """The local agents' actions into ``actions``: one batch put, answered synchronously by the group."""
        if self.share_maps:
            self.group.share_maps(batch.views)  # once: the runtime keeps its views for the whole run
            cells, ends = _NO_CELLS, self._no_ends
        packet, ids = self._encode_batch(tick, asked, batch.poses, batch.collided, batch.travelled, energy,
                                         batch.navs, batch.known, cells, ends, batch.inboxes, near, distance)
        if packet is None:
            return
        self._put_obs_batch(packet)
        reply = self._answer_local(tick, ids)
        if reply is None:
            return
        try:
            taken = self._decode_batch(reply, tick, ids)
        except WireError:
            for i in ids:
                self.stats.count("malformed", i)
                actions[i] = Action()
            return
        for i, (action, bad) in zip(ids, taken):
            if action is None:
                self.stats.count("malformed", i)
                action = Action()
            elif bad:
                self.stats.count("bad_messages", i, bad)
                self.stats.dropped.append((i, f"{bad} message(s) do not decode"))
            actions[i] = action

    def _take_remote(self, tick: int, live: list[int], actions: list[Action | None]) -> None:
        """The remote agents' replies for ``tick`` into ``actions``: decoded, checked and counted."""
        with self._cond:
            replies = dict(self._replies)
            lost = set(self._lost)
        decode = self._decode_act
        for i in live:
            data = replies.get(i)
            if data is None:
                self.stats.failures[i] = (tick, "agent lost" if i in lost else f"no action within {self.timeout_s:g} s")
                continue
            try:
                packet = decode(data)
            except WireError:
                self.stats.count("malformed", i)
                actions[i] = Action()
                continue
            if packet.tick != tick or packet.robot_id != i:
                self.stats.count("malformed", i)
                actions[i] = Action()
                continue
            if packet.bad_messages:
                self.stats.count("bad_messages", i, packet.bad_messages)
                self.stats.dropped.extend((i, problem) for problem in packet.problems)
            actions[i] = packet.action

    def _wait(self, waiting: list[int]) -> None:
        """Until every robot in ``waiting`` has replied or is lost, or ``timeout_s`` has passed."""
        t0 = time.perf_counter()
        deadline = time.monotonic() + self.timeout_s
        with self._cond:
            self._cond.wait_for(lambda: all(i in self._replies or i in self._lost for i in waiting)
                                or time.monotonic() > deadline, timeout=self.timeout_s)
        if self._times is not None:
            self._times.add("zenoh: wait for remote replies", time.perf_counter() - t0)

    def close(self) -> None:
        """Tell the agents the run is over and close the session, in at most about :data:`CLOSE_TIMEOUT_S`
        seconds and never raising: the run's result is computed by now, and no network trouble (zenoh's
        own "close operation timed out!", connections that never finish their handshake) may cost it."""
        try:
            self.session.put(f"{self.prefix}/end", b"end", congestion_control=BLOCK)
        except Exception:  # the session may already be failing; closing below is what matters
            pass
        for d in [*self._declared, *self._publishers.values()]:
            try:
                d.undeclare()
            except Exception:
                pass
        close_session(self.session, CLOSE_TIMEOUT_S)
        if self._credentials is not None:
            self._credentials.remove()


CLOSE_TIMEOUT_S = 5.0
"""How long :meth:`ZenohHost.close` waits for zenoh to close the session before leaving it to finish (or
not) in a daemon thread."""


def close_session(session: zenoh.Session, timeout_s: float) -> bool:
    """``session.close()`` in a daemon thread, waited for at most ``timeout_s``; True if it closed in time.
    zenoh's errors are swallowed: a session that cannot close cleanly is still given up."""
    def close() -> None:
        try:
            session.close()
        except Exception:
            pass

    closer = threading.Thread(target=close, name="swarm-zenoh-close", daemon=True)
    closer.start()
    closer.join(timeout_s)
    return not closer.is_alive()
