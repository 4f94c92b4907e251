"""The agent side of a transport: one robot's algorithm fed from observation packets.

Keeps a mirror of the robot's knowledge map (updated from each packet's changed cells), rebuilds the
exact :class:`~swarm.api.Observation` the in-process transport would give, calls the algorithm and encodes
its action. Used for agents in the runtime's process over zenoh and by ``swarm agent`` in other processes.
"""

from __future__ import annotations

import numpy as np

from .. import registry
from ..api import Observation
from ..messages import decode
from .inprocess import check_action
from .wire import ResetPacket, decode_obs, encode_act


class AgentRunner:
    def __init__(self, reset: ResetPacket, algorithm: str | None = None) -> None:
        self.robot = reset.robot
        name = algorithm or reset.algorithm
        params = reset.params if name == reset.algorithm else {}
        self.algorithm = registry.create(name)
        self.algorithm.reset(reset.robot, registry.build_params(name, params), reset.rng())
        self.known = np.zeros(tuple(reset.robot.map_shape), dtype=np.uint8)
        self._flat = self.known.reshape(-1)
        self._view = self.known.view()
        self._view.flags.writeable = False

    def handle(self, packet: bytes) -> bytes:
        p = decode_obs(packet, self.known.size)
        self._flat[p.changed_idx] = p.changed_val
        obs = Observation(tick=p.tick, robot_id=p.robot_id, pose=p.pose, known=self._view,
                          inbox=tuple(decode(b) for b in p.inbox), neighbours=p.neighbours, collided=p.collided,
                          nav=p.nav, distance_travelled=p.distance_travelled, energy_used=p.energy_used)
        action = check_action(self.algorithm.act(obs), p.robot_id)
        return encode_act(p.tick, p.robot_id, action)
