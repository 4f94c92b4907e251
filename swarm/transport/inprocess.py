"""Agents as plain Python objects in the runtime's process: the fastest transport.

Builds each live robot's :class:`~swarm.api.Observation` from the tick's :class:`TickBatch` and calls its
algorithm directly. Neighbours are handed over lazily (:class:`~swarm.api.Neighbours` over the tick's
shared matrices): most algorithms never read them.
"""

from __future__ import annotations

from typing import Any, Callable, Iterator, Sequence

import numpy as np

from swarm.base.errors import short_repr
from swarm.base.types import DRIVES, Action, Neighbours, Observation, frozen_builder
from swarm.comm.medium import Inboxes
from swarm.plugins import explorers as registry
from .base import HostStats, TickBatch
from .bearings import BearingRows
from .timing import PhaseTimes, timed
from .wire import ResetPacket

_observation = frozen_builder(Observation)  # Observation(...) without the frozen __init__'s cost (16 a tick)


class InProcessHost:
    mirrors = False

    def __init__(self, times: PhaseTimes | None = None) -> None:
        self.stats = HostStats()
        self.agents: list = []
        self._acts: list = []
        self._times = times
        # Unmeasured, each robot's observation is built just before it acts and dropped after: a swarm's
        # inboxes (tens of thousands of messages a robot) then never all live at once
        self._observations = iter_observations if times is None else timed(times, "host: inputs", observations)

    def start(self, resets: Sequence[ResetPacket]) -> None:
        for reset in resets:
            agent = registry.create(reset.algorithm)
            agent.reset(reset.robot, registry.build_params(reset.algorithm, reset.params), reset.rng())
            self.agents.append(agent)
            self._acts.append(timed(self._times, "agent: algorithm", agent.act))

    def act(self, batch: TickBatch) -> list[Action | None]:
        acts = self._acts
        return [None if obs is None else check_action(acts[i](obs), i)
                for i, obs in enumerate(self._observations(batch))]

    def close(self) -> None:
        self.agents = []
        self._acts = []


def observations(batch: TickBatch) -> list[Observation | None]:
    """Each live robot's Observation of the tick (None for the others)."""
    return list(iter_observations(batch))


def iter_observations(batch: TickBatch) -> Iterator[Observation | None]:
    """:func:`observations` one robot at a time, in robot order."""
    distance = batch.travelled.tolist()
    energy = [d + r for d, r in zip(distance, batch.rotation.tolist())]  # float64 sums, as numpy's
    neighbours = _neighbours(batch)
    hit = batch.collided.tolist()
    live = batch.live.tolist()
    tick, views, navs, inboxes = batch.tick, batch.views, batch.navs, batch.inboxes
    messages = inboxes.messages if isinstance(inboxes, Inboxes) else None
    for i, pose in enumerate(batch.pose_tuples):
        if not live[i]:
            yield None
            continue
        if messages is not None:
            inbox = messages(i)
        else:
            inbox = tuple([env.message for env in inboxes[i]]) if inboxes[i] else ()
        yield _observation(tick=tick, robot_id=i, pose=pose, known=views[i], inbox=inbox,
                           neighbours=neighbours[i], collided=hit[i], nav=navs[i],
                           distance_travelled=distance[i], energy_used=energy[i])


def _neighbours(batch: TickBatch) -> list[Sequence[Any]]:
    """Robots in sensing range and line of sight, per robot, built when first read (the tick's matrices are
    computed once and shared by every robot's :class:`~swarm.api.Neighbours`)."""
    n = len(batch.pose_tuples)
    if n == 1:
        return [()]
    p = batch.poses.copy()
    near = _Lazy(lambda: batch.sight()[1], batch.sight_near)
    distance = _Lazy(lambda: batch.sight()[0])
    bearing = BearingRows(p)                    # per row and read: robots read few bearings
    xy = p[:, :2].copy()
    return [Neighbours(i, near, distance, bearing, xy) for i in range(n)]


class _Lazy:
    """A tick's (R, R) matrix computed on first read and then shared by every robot's
    :class:`~swarm.api.Neighbours` (most algorithms never read their neighbours), which only index it.
    ``near`` (the near mask's): the robots near one robot without the matrix (:meth:`TickBatch.sight_near`)."""

    __slots__ = ("_make", "_value", "near")

    def __init__(self, make: Callable[[], np.ndarray],
                 near: Callable[[int, float], tuple[np.ndarray, np.ndarray]] | None = None) -> None:
        self._make = make
        self._value: np.ndarray | None = None
        self.near = near

    def value(self) -> np.ndarray:
        if self._value is None:
            self._value = self._make()
        return self._value

    def __getitem__(self, key: Any) -> np.ndarray:
        return self.value()[key]


def check_action(action: object, robot: int) -> Action:
    if not isinstance(action, Action):
        raise TypeError(f"robot {robot}: act() returned {type(action).__name__}, expected swarm.api.Action")
    if not isinstance(action.drive, str) or action.drive not in DRIVES:
        raise TypeError(f"robot {robot}: Action.drive is {short_repr(action.drive, 40)}; allowed: "
                        f"{', '.join(map(repr, DRIVES))}")
    return action
