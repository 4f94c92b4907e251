"""A small explorer with rich debug info and its own messages, for recorder tests
(loaded as ``tests.swarm.viewer.agents:DebugExplorer``)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from swarm import grid
from swarm.api import Action, cell_centre, cell_of
from swarm.comm.messages import message


@message("test.viewer.note")
@dataclass(frozen=True)
class Note:
    sender: int
    tick: int


class DebugExplorer:
    """Drives to the nearest reachable unseen cell; its debug mixes numpy values, a set, a tuple and NaN
    (what the recorder must normalise deterministically) and changes every 10 ticks; it sends a Note every
    7 ticks."""

    name = "debug-explorer"

    def reset(self, robot, params, rng):
        self.id = robot.id

    def act(self, obs):
        found = grid.nearest_reachable_unseen(obs.known, cell_of(obs.pose.x, obs.pose.y))
        goal = cell_centre(*found[0]) if found else None
        debug = {"phase": obs.tick // 10, "target": goal, "frontier": [goal, (1.0, 1.0)] if goal else [],
                 "weights": np.arange(3, dtype=np.float32) * (obs.tick // 10), "tags": {"b", "a"},
                 "nan": float("nan"), "n": np.int64(self.id)}
        messages = (Note(self.id, obs.tick),) if obs.tick % 7 == 0 else ()
        if goal is None:
            return Action(velocity=(0.0, 0.0), debug=debug, messages=messages)
        return Action(goal=goal, debug=debug, messages=messages)
