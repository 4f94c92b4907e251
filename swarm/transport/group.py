"""The agents of one process served by batches: one ``obs_batch`` in, one ``act_batch`` out per tick.

:class:`AgentGroup` is :class:`~swarm.transport.agent.AgentRunner` for several robots at once: it checks a
whole batch (:mod:`swarm.transport.batch`) before any algorithm runs, rebuilds for every robot the exact
:class:`~swarm.api.Observation` the in-process transport gives, runs the algorithms in robot order and
answers with one packet. The zenoh host uses it for the agents that live in the runtime's own process.

The knowledge maps reach a group one of two ways. A group in the runtime's memory reads the runtime's
maps in place (:meth:`AgentGroup.share_maps`: read-only views, as in-process agents get them), so its
batches carry no map cells: zero-copy, the map is most of an observation's bytes and never needs to
move within a process. Otherwise it keeps a mirror of each robot's map and writes each batch's changed
cells into it, as agents in other processes do (``TransportOptions(share_maps=False)`` runs the local
agents that way, for tests and for measuring what shipping the maps costs).
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np

from swarm.base.types import NavStatus, Observation, Pose, frozen_builder
from swarm.grid._validate import vouch_known
from swarm.plugins import explorers as registry
from .agent import InboxDecoder
from .batch import ActBatchEncoder, ObsBatch, ObsBatchDecoder, apply_cells
from .inprocess import check_action
from .timing import PhaseTimes, timed
from .wire import COLLIDED, HAS_GOAL, NAV_STATES, NEIGHBOUR, OBS_STATE, PackedNeighbours, ResetPacket, WireError

_observation, _nav = frozen_builder(Observation), frozen_builder(NavStatus)
_RECORD, _STATE = NEIGHBOUR.size, OBS_STATE.size
_NAV_FROM, _NAV_TO, _NAV_TAIL = 24, 48, 64  # OBS_STATE offsets: goal x .. path length, ticks since progress ..
_tuple_new = tuple.__new__


class AgentGroup:
    """The algorithms of robots ``resets`` (one process), fed from ``obs_batch`` packets."""

    def __init__(self, resets: Sequence[ResetPacket], times: PhaseTimes | None = None) -> None:
        if not resets:
            raise ValueError("an agent group needs at least one robot")
        first = resets[0].robot
        self.n_robots = first.n_robots
        self.ids = [r.robot.id for r in resets]
        self.row_of = {robot: k for k, robot in enumerate(self.ids)}
        self.maps: np.ndarray | None = np.zeros((len(resets), *first.map_shape), dtype=np.uint8)
        # new zeros (not scanned); a packet's cells are checked (0..2) before they are written
        self._views = [vouch_known(_read_only(m), trusted=True) for m in self.maps]
        self._shared: Sequence[np.ndarray] | None = None
        self._decode = ObsBatchDecoder(self.n_robots, self.maps[0].size)
        self._acts = []
        for reset in resets:
            algorithm = registry.create(reset.algorithm)
            algorithm.reset(reset.robot, registry.build_params(reset.algorithm, reset.params), reset.rng())
            self._acts.append(timed(times, "agent: algorithm", algorithm.act))
        self._navs: list[tuple[Any, Any]] = [(None, None)] * len(resets)  # per row: (nav fields, NavStatus)
        self._rows: dict[tuple[int, ...], tuple[list[int], np.ndarray]] = {}  # ids of a batch -> their rows
        self._inbox = InboxDecoder()
        self.observe = timed(times, "agent: observe", self.observe)
        self._encode = timed(times, "agent: act encode", ActBatchEncoder())

    def share_maps(self, views: Sequence[np.ndarray]) -> None:
        """Read robot i's map from ``views[i]`` (the runtime's read-only views) instead of a mirror; batches
        must then carry no map cells."""
        if views is self._shared:
            return
        self._shared = views
        self._views = [views[i] for i in self.ids]
        self.maps = None

    def observe(self, packet: bytes) -> tuple[int, tuple[int, ...], list[Observation]]:
        """The tick, the robots and their observations an ``obs_batch`` carries, the map mirrors updated;
        raises WireError, leaving every map as it was, for a bad batch (or one naming a robot not here)."""
        b = self._decode(packet)
        rows = self._rows.get(b.ids)
        if rows is None:
            row_of = self.row_of
            if not all(robot in row_of for robot in b.ids):
                raise WireError("obs_batch: names a robot this group does not serve")
            rows = self._rows[b.ids] = ([row_of[robot] for robot in b.ids],
                                        np.array([row_of[robot] for robot in b.ids], dtype=np.int64))
        if b.cells is not None:
            if self.maps is None:
                raise WireError("obs_batch: map cells for agents that read their maps in place")
            apply_cells(b, rows[1], self.maps)
        return b.tick, b.ids, self._observations(b, rows[0])

    def _observations(self, b: ObsBatch, rows: list[int]) -> list[Observation]:
        tick, views, navs, near, records, raw = b.tick, self._views, self._navs, b.near, b.neighbours, b.state_bytes
        messages = self._inbox.decode_table(b.messages) if b.messages else ()
        out = []
        at = 0  # where robot k's neighbour records start
        for k, (x, y, theta, gx, gy, path_length, travelled, energy, stalled, state, flags) in enumerate(b.states):
            row = rows[k]
            # the nav fields' bytes (goal, path length, ticks since progress, state, flags): compared as bytes,
            # so a goal of -0.0 is not taken for 0.0 (the collided flag rides along: a rare miss)
            key = raw[_STATE * k + _NAV_FROM:_STATE * k + _NAV_TO] + raw[_STATE * k + _NAV_TAIL:_STATE * (k + 1)]
            seen_key, nav = navs[row]
            if key != seen_key:  # the same NavStatus while nothing in it changed, as the runtime's navigator keeps
                nav = _nav(goal=(gx, gy) if flags & HAS_GOAL else None, state=NAV_STATES[state],
                           path_length=path_length, ticks_since_progress=stalled)
                navs[row] = (key, nav)
            refs = b.inbox[k]
            inbox = tuple([messages[j] for j in refs if messages[j] is not None]) if refs else ()
            neighbours: Any = ()
            if near[k]:
                end = at + _RECORD * near[k]
                neighbours = PackedNeighbours(records, at, end)
                at = end
            out.append(_observation(tick=tick, robot_id=b.ids[k], pose=_tuple_new(Pose, (x, y, theta)),
                                    known=views[row], inbox=inbox, neighbours=neighbours,
                                    collided=bool(flags & COLLIDED), nav=nav, distance_travelled=travelled,
                                    energy_used=energy))
        return out

    def handle(self, packet: bytes) -> bytes:
        """The ``act_batch`` answering an ``obs_batch``: every robot's algorithm run in robot order."""
        tick, ids, observations = self.observe(packet)
        acts, row_of = self._acts, self.row_of
        actions = [check_action(acts[row_of[robot]](obs), robot) for robot, obs in zip(ids, observations)]
        return self._encode(tick, ids, actions)


def _read_only(a: np.ndarray) -> np.ndarray:
    view = a.view()
    view.flags.writeable = False
    return view
