"""Agents as plain Python objects in the runtime's process: the fastest transport."""

from __future__ import annotations

from typing import Sequence

from .. import registry
from ..api import Action, Observation
from .base import HostStats
from .timing import PhaseTimes, timed
from .wire import ResetPacket


class InProcessHost:
    batched = False

    def __init__(self, times: PhaseTimes | None = None) -> None:
        self.stats = HostStats()
        self.agents: list = []
        self._acts: list = []
        self._times = times

    def start(self, resets: Sequence[ResetPacket]) -> None:
        for reset in resets:
            agent = registry.create(reset.algorithm)
            agent.reset(reset.robot, registry.build_params(reset.algorithm, reset.params), reset.rng())
            self.agents.append(agent)
            self._acts.append(timed(self._times, "agent: algorithm", agent.act))

    def act(self, tick: int, inputs: Sequence[Observation | None]) -> list[Action | None]:
        acts = self._acts
        return [None if obs is None else check_action(acts[i](obs), i) for i, obs in enumerate(inputs)]

    def close(self) -> None:
        self.agents = []
        self._acts = []


def check_action(action: object, robot: int) -> Action:
    if not isinstance(action, Action):
        raise TypeError(f"robot {robot}: act() returned {type(action).__name__}, expected swarm.api.Action")
    return action
