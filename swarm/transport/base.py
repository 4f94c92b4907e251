"""The transport interface: how the runtime hands observations to agents and gets their actions back.

Two implementations with identical semantics (DESIGN.md section 5): :class:`~swarm.transport.inprocess.
InProcessHost` calls the algorithms directly; :class:`~swarm.transport.zenoh_host.ZenohHost` sends every
observation and action through real zenoh sessions, to agents in this process or in others. Either way the
runtime is the radio medium and steps in lockstep, so the transport never changes a result.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol, Sequence

import numpy as np

from ..api import Action, NavStatus, Observation
from .wire import ResetPacket


@dataclass
class TickBatch:
    """Every robot's observation of a tick as the runtime's arrays, row i = robot i, for hosts that pack all
    robots at once (zenoh): nothing per robot is built on the runtime's side. Read-only for the host."""

    live: np.ndarray                          # bool[R]: robots to ask (not failed)
    poses: np.ndarray                         # float64[R, 3]
    collided: np.ndarray                      # bool[R]: touched something since the last observation
    travelled: np.ndarray                     # float64[R]: metres travelled
    energy: np.ndarray                        # float64[R]: energy used
    navs: list[NavStatus | None]              # the navigators' status (None for robots not live)
    known: np.ndarray                         # uint8[R, H, W]: the knowledge maps
    cells: np.ndarray                         # int64: knowledge cells changed since the last observation,
    ends: np.ndarray                          # robot after robot: robot i's are cells[ends[i-1]:ends[i]]
    inboxes: list[tuple[bytes, ...]]          # the inbox messages' wire bytes
    near: np.ndarray                          # bool[R, R]: sensed neighbours (in range, line of sight)
    distance: np.ndarray                      # float64[R, R]: pair distances


@dataclass
class HostStats:
    malformed: int = 0
    failures: dict[int, tuple[int, str]] = field(default_factory=dict)  # robot -> (tick, reason)


class AgentHost(Protocol):
    batched: bool  # act() takes a TickBatch instead of one Observation per robot
    stats: HostStats

    def start(self, resets: Sequence[ResetPacket]) -> None: ...

    def act(self, tick: int, inputs: Sequence[Observation | None] | TickBatch) -> list[Action | None]:
        """Actions for the robots given their observations (None for failed robots), or a TickBatch for a
        batched host; None where a robot failed now."""
        ...

    def close(self) -> None: ...
