"""Small algorithms for runtime tests (loaded as ``tests.swarm.agents:Class``)."""

from __future__ import annotations

from dataclasses import dataclass

from swarm.api import Action
from swarm.comm.messages import message


@message("test.ping")
@dataclass(frozen=True)
class Ping:
    sender: int
    tick: int


class Talker:
    """Stands still, broadcasts a Ping every tick, and logs (tick, sender, sent_tick) of what it hears."""

    name = "talker"
    log: dict[int, list[tuple[int, int, int]]] = {}

    def reset(self, robot, params, rng):
        self.id = robot.id
        Talker.log[self.id] = []

    def act(self, obs):
        for m in obs.inbox:
            if isinstance(m, Ping):
                Talker.log[self.id].append((obs.tick, m.sender, m.tick))
        return Action(velocity=(0.0, 0.0), messages=(Ping(self.id, obs.tick),))


class Quiet:
    """Stands still and says nothing."""

    name = "quiet"

    def reset(self, robot, params, rng):
        pass

    def act(self, obs):
        return Action(velocity=(0.0, 0.0))


class Leaver:
    """Robot 0 stands still, every other robot drives straight ahead at full speed; all broadcast a Ping
    every tick and log what they hear (as Talker)."""

    name = "leaver"
    log: dict[int, list[tuple[int, int, int]]] = {}

    def reset(self, robot, params, rng):
        self.id, self.speed = robot.id, robot.max_speed
        Leaver.log[self.id] = []

    def act(self, obs):
        for m in obs.inbox:
            if isinstance(m, Ping):
                Leaver.log[self.id].append((obs.tick, m.sender, m.tick))
        v = 0.0 if self.id == 0 else self.speed
        return Action(velocity=(v, 0.0), messages=(Ping(self.id, obs.tick),))
