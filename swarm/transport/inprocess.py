"""Agents as plain Python objects in the runtime's process: the fastest transport."""

from __future__ import annotations

from typing import Sequence

from .. import registry
from ..api import Action
from .base import HostStats, TickInput
from .wire import ResetPacket


class InProcessHost:
    batched = False

    def __init__(self) -> None:
        self.stats = HostStats()
        self.agents: list = []

    def start(self, resets: Sequence[ResetPacket]) -> None:
        for reset in resets:
            agent = registry.create(reset.algorithm)
            agent.reset(reset.robot, registry.build_params(reset.algorithm, reset.params), reset.rng())
            self.agents.append(agent)

    def act(self, tick: int, inputs: Sequence[TickInput | None]) -> list[Action | None]:
        return [None if inp is None else check_action(self.agents[i].act(inp.obs), i)
                for i, inp in enumerate(inputs)]

    def close(self) -> None:
        self.agents = []


def check_action(action: object, robot: int) -> Action:
    if not isinstance(action, Action):
        raise TypeError(f"robot {robot}: act() returned {type(action).__name__}, expected swarm.api.Action")
    return action
