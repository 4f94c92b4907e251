"""The transport interface: how the runtime hands observations to agents and gets their actions back.

Two implementations with identical semantics (docs/design.md section 5): :class:`~swarm.transport.inprocess.
InProcessHost` calls the algorithms directly; :class:`~swarm.transport.zenoh_host.ZenohHost` sends every
observation and action through real zenoh sessions, to agents in this process or in others. Both get the
same :class:`TickBatch` of the tick's arrays and build what they ship from it. Either way the runtime is
the radio medium and steps in lockstep, so the transport never changes a result.
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass, field
from typing import Any, Callable, Protocol, Sequence

import numpy as np

from swarm.base.types import Action, NavStatus, Pose, sensed_within
from .wire import ResetPacket


class TickBatch:
    """Every robot's observation of a tick as the runtime's arrays, row i = robot i: the one thing the
    runtime hands any host. A host reads what it needs; the parts that cost work (neighbours, the cells
    changed since the last observation) are computed on first read and then shared. Read-only for hosts."""

    __slots__ = ("tick", "live", "poses", "pose_tuples", "collided", "travelled", "rotation", "navs", "known",
                 "views", "inboxes", "_sight", "_sight_value", "_changed", "_changed_value", "_near", "_near_value")

    def __init__(self, tick: int, live: np.ndarray, poses: np.ndarray, pose_tuples: list[Pose],
                 collided: np.ndarray, travelled: np.ndarray, rotation: np.ndarray, navs: list[NavStatus | None],
                 known: np.ndarray, views: Sequence[np.ndarray], inboxes: list[list[Any]],
                 sight: Callable[[], tuple[np.ndarray, np.ndarray]],
                 changed: Callable[[], tuple[np.ndarray, np.ndarray]] | None = None,
                 near: Callable[[], Any] | None = None) -> None:
        self.tick = tick
        self.live = live                # bool[R]: robots to ask (not failed)
        self.poses = poses              # float64[R, 3]
        self.pose_tuples = pose_tuples  # the same poses as Pose tuples
        self.collided = collided        # bool[R]: touched something since the last observation
        self.travelled = travelled      # float64[R]: metres travelled
        self.rotation = rotation        # float64[R]: radians turned; energy used = travelled + rotation
        self.navs = navs                # the navigators' status (None for robots not live)
        self.known = known              # uint8[R, H, W]: the knowledge maps
        self.views = views              # robot i's map as its algorithm sees it (read-only)
        self.inboxes = inboxes          # the envelopes delivered to each robot (.message, .data: wire bytes)
        self._sight, self._sight_value = sight, None
        self._changed, self._changed_value = changed, None
        self._near, self._near_value = near, None  # builds an index with .near(row, range_m) (radio.SightIndex)

    def asking(self, live: np.ndarray) -> TickBatch:
        """This batch asking only the robots of ``live`` (a host that decides some robots itself hands the
        others to another host this way); parts computed so far are shared."""
        other = copy.copy(self)
        other.live = live
        return other

    def sight(self) -> tuple[np.ndarray, np.ndarray]:
        """``(distance, near)``: pair distances (m, float64[R, R]) and who senses whom (bool[R, R]: in range,
        in line of sight)."""
        if self._sight_value is None:
            self._sight_value = self._sight()
        return self._sight_value

    def sight_near(self, row: int, range_m: float) -> tuple[np.ndarray, np.ndarray]:
        """``(cols, distances)``: the robots robot ``row`` senses (:meth:`sight`) nearer than ``range_m``, in
        robot order, the same values as :meth:`sight`'s row. Read from the matrices once they exist, else
        from a spatial index of the tick's robots, which looks only at the robots within ``range_m``."""
        if self._sight_value is None and self._near is not None and math.isfinite(range_m):
            if self._near_value is None:
                self._near_value = self._near()
            return self._near_value.near(row, range_m)
        distance, near = self.sight()
        return sensed_within(near, distance, row, range_m)

    def changed(self) -> tuple[np.ndarray, np.ndarray]:
        """``(cells, ends)``: per robot, the flat indices of its knowledge cells changed since its last
        observation, robot i's at ``cells[ends[i-1]:ends[i]]``; only for a host that keeps map mirrors
        (:attr:`AgentHost.mirrors`)."""
        if self._changed is None:
            raise RuntimeError("changed cells are tracked only for a host with mirrors = True")
        if self._changed_value is None:
            self._changed_value = self._changed()
        return self._changed_value


ACT_COUNTS = ("malformed", "refused", "late", "duplicate")
"""What a host counts per robot about act packets it did not take: ``malformed`` (does not decode, or
answers another tick or robot), ``refused`` (unsigned or wrongly signed), ``late`` (signed for another
tick), ``duplicate`` (a second valid reply for the same tick)."""


@dataclass
class HostStats:
    """What the host counted (per robot) and which robots' agents failed."""

    counts: dict[str, dict[int, int]] = field(default_factory=lambda: {k: {} for k in (*ACT_COUNTS, "bad_messages")})
    failures: dict[int, tuple[int, str]] = field(default_factory=dict)  # robot -> (tick, reason)
    dropped: list[tuple[int, str]] = field(default_factory=list)
    """(robot, reason) of the messages dropped since the runtime last read this (``bad_messages``): it
    turns them into ``message_dropped`` events, as it does for those the radio's medium refuses."""

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
    mirrors: bool  # the host ships map changes, so the runtime tracks each robot's cells since its last tick
    stats: HostStats

    def start(self, resets: Sequence[ResetPacket]) -> None: ...

    def act(self, batch: TickBatch) -> list[Action | None]:
        """Every live robot's action for the tick's observations; None for robots not live and for those
        whose agent failed now (recorded in :attr:`stats`)."""
        ...

    def close(self) -> None: ...
