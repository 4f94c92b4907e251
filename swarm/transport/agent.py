"""The agent side of a transport: one robot's algorithm fed from observation packets.

Keeps a mirror of the robot's knowledge map (updated from each packet's changed cells), rebuilds the
exact :class:`~swarm.api.Observation` the in-process transport would give, calls the algorithm and encodes
its action. Used for agents in the runtime's process over zenoh and by ``swarm agent`` in other processes.
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np

from swarm.base.types import Observation, frozen_builder
from swarm.comm.messages import MessageError, decode
from swarm.grid._validate import vouch_known
from swarm.plugins import explorers as registry
from .inprocess import check_action
from .timing import PhaseTimes, timed
from .wire import ObsDecoder, ResetPacket, encode_act

_observation = frozen_builder(Observation)  # the same Observation, a third of the constructor's cost


class InboxDecoder:
    """Inbox messages decoded once per distinct payload and tick, however many agents of this process hear
    them: a broadcast reaches up to n - 1 agents with the same bytes. The decoded messages are frozen and
    shared, exactly as the in-process transport shares them. A message this process cannot decode (a type
    its algorithm does not register, e.g. an agent run with another ``--algorithm``) is left out of the
    inbox and counted in :attr:`undecodable`: one unknown message must not cost the whole observation."""

    def __init__(self) -> None:
        self._tick: int | None = None
        self._seen: dict[bytes, Any] = {}
        self.undecodable = 0

    def decode(self, tick: int, blobs: Sequence[bytes]) -> tuple[Any, ...]:
        if not blobs:
            return ()
        if tick != self._tick:
            self._tick = tick
            self._seen.clear()
        seen, out = self._seen, []
        for b in blobs:
            msg = seen.get(b)
            if msg is None:
                try:
                    msg = seen[b] = decode(b)
                except MessageError:
                    self.undecodable += 1
                    continue
            out.append(msg)
        return tuple(out)

    def decode_table(self, blobs: Sequence[bytes]) -> list[Any]:
        """Each of ``blobs`` decoded (an ``obs_batch``'s message table, which holds every message once: no
        lookup by bytes, whose hashing cost more than it saved), None for those that do not decode (counted
        in :attr:`undecodable`)."""
        out = []
        for b in blobs:
            try:
                out.append(decode(b))
            except MessageError:
                self.undecodable += 1
                out.append(None)
        return out


class AgentRunner:
    def __init__(self, reset: ResetPacket, algorithm: str | None = None, inbox: InboxDecoder | None = None,
                 times: PhaseTimes | None = None) -> None:
        self.robot = reset.robot
        name = algorithm or reset.algorithm
        params = reset.params if name == reset.algorithm else {}
        self.algorithm = registry.create(name)
        self.algorithm.reset(reset.robot, registry.build_params(name, params), reset.rng())
        self.known = np.zeros(tuple(reset.robot.map_shape), dtype=np.uint8)
        self._flat = self.known.reshape(-1)
        self._view = self.known.view()
        self._view.flags.writeable = False
        vouch_known(self._view, trusted=True)  # new zeros; values are checked (0..2) before a packet writes them
        self._inbox = timed(times, "agent: inbox decode", (inbox or InboxDecoder()).decode)
        self._decode = timed(times, "agent: obs decode", ObsDecoder(self.known.size, reset.robot.n_robots))
        self._act = timed(times, "agent: algorithm", self.algorithm.act)
        self._encode_act = timed(times, "agent: act encode", encode_act)

    def observe(self, packet: bytes) -> Observation:
        """The observation an obs packet carries, the map mirror updated; raises WireError, leaving the map
        as it was, for a bad one."""
        p = self._decode(packet)
        inbox = self._inbox(p.tick, p.inbox)
        if len(p.changed_idx):
            self._flat[p.changed_idx] = p.changed_val
        return _observation(tick=p.tick, robot_id=p.robot_id, pose=p.pose, known=self._view, inbox=inbox,
                            neighbours=p.neighbours, collided=p.collided, nav=p.nav,
                            distance_travelled=p.distance_travelled, energy_used=p.energy_used)

    def answer(self, obs: Observation) -> bytes:
        """The act packet carrying the algorithm's decision on ``obs``."""
        return self._encode_act(obs.tick, obs.robot_id, check_action(self._act(obs), obs.robot_id))

    def handle(self, packet: bytes) -> bytes:
        """The act packet answering an obs packet; raises WireError, leaving the map as it was, for a bad one."""
        return self.answer(self.observe(packet))
