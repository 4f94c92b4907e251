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

from ..api import Action, Observation
from .wire import ResetPacket


@dataclass
class TickInput:
    """One robot's observation for a tick, plus what a remote agent needs to rebuild it."""

    obs: Observation
    changed_idx: np.ndarray | None = None      # knowledge cells changed since the previous observation
    inbox_bytes: tuple[bytes, ...] = ()        # the inbox messages' wire bytes
    neighbour_bytes: bytes | None = None       # the neighbours as wire records (None: pack obs.neighbours)


@dataclass
class HostStats:
    malformed: int = 0
    failures: dict[int, tuple[int, str]] = field(default_factory=dict)  # robot -> (tick, reason)


class AgentHost(Protocol):
    needs_delta: bool
    stats: HostStats

    def start(self, resets: Sequence[ResetPacket]) -> None: ...

    def act(self, tick: int, inputs: Sequence[TickInput | None]) -> list[Action | None]:
        """Actions for the robots given inputs (None for failed robots); None where a robot failed now."""
        ...

    def close(self) -> None: ...
