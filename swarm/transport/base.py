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


ACT_COUNTS = ("malformed", "refused", "late", "duplicate")
"""What a host counts per robot about act packets it did not take: ``malformed`` (does not decode, or
answers another tick or robot), ``refused`` (unsigned or wrongly signed), ``late`` (signed for another
tick), ``duplicate`` (a second valid reply for the same tick)."""


@dataclass
class HostStats:
    """What the host counted (per robot) and which robots' agents failed."""

    counts: dict[str, dict[int, int]] = field(default_factory=lambda: {k: {} for k in (*ACT_COUNTS, "bad_messages")})
    failures: dict[int, tuple[int, str]] = field(default_factory=dict)  # robot -> (tick, reason)

    def count(self, kind: str, robot: int, n: int = 1) -> None:
        """Add ``n`` to robot ``robot``'s ``kind`` counter (``bad_messages``: messages in taken acts that did
        not decode, dropped one by one)."""
        per_robot = self.counts[kind]
        per_robot[robot] = per_robot.get(robot, 0) + n

    def per_robot(self, kind: str, n: int) -> list[int]:
        """Robot by robot, the ``kind`` counts of a run of ``n`` robots."""
        per_robot = self.counts[kind]
        return [per_robot.get(i, 0) for i in range(n)]


class AgentHost(Protocol):
    batched: bool  # act() takes a TickBatch instead of one Observation per robot
    stats: HostStats

    def start(self, resets: Sequence[ResetPacket]) -> None: ...

    def act(self, tick: int, inputs: Sequence[Observation | None] | TickBatch) -> list[Action | None]:
        """Actions for the robots given their observations (None for failed robots), or a TickBatch for a
        batched host; None where a robot failed now."""
        ...

    def close(self) -> None: ...
