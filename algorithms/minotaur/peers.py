"""What one robot knows of the others: where they were, where they are going, which doorway they are
going through, and the doorway lists they broadcast.

Alg. 2 has every robot broadcast "map, including walls, explored area, doorways and known robots
location". Positions come from the runtime's map updates (``MapUpdate.pose``) and sensed neighbours;
targets and doorway claims from Minotaur's :class:`~.messages.DoorwayList` heartbeats and
:class:`~.messages.Heading` messages. A robot uses them to split the spin (Alg. 2), to leave a doorway
another robot is going through to it, and to keep its greedy targets away from other robots' targets
(MAES's Minotaur excludes other robots' destinations when it re-targets, docs/maes.md section 7.2).
"""

from __future__ import annotations

import math
from collections.abc import Iterator

import numpy as np

from swarm.api import CELL_M, cell_of

from .doorways import Doorway, DoorwayBook, Wire, valid_wire
from .messages import DoorwayList, Heading


class Peers:
    def __init__(self) -> None:
        self.poses: dict[int, tuple[float, float, int]] = {}        # robot -> (x, y, tick heard)
        self.targets: dict[int, tuple[float, float, int]] = {}
        self.doors: dict[int, tuple[Doorway, int]] = {}             # robot -> (doorway it goes through, tick)
        self._lists: dict[int, tuple[tuple, frozenset]] = {}        # robot -> its last doorway list

    def saw(self, robot: int, x: float, y: float, tick: int) -> None:
        self.poses[robot] = (float(x), float(y), tick)

    def fresh_poses(self, tick: int, max_age: int) -> Iterator[tuple[int, float, float]]:
        for robot, (x, y, t) in self.poses.items():
            if tick - t <= max_age:
                yield robot, x, y

    def heard(self, tick: int, m: DoorwayList | Heading, book: DoorwayBook) -> None:
        """Merge a heartbeat or heading into ``book`` and remember the sender's target and doorway."""
        if isinstance(m, DoorwayList):
            for w in self._new_entries(m.sender, m.doors):
                book.add(Doorway.from_wire(w, tick))
        t = m.target
        if all(isinstance(v, (int, float)) and math.isfinite(v) for v in t):
            self.targets[m.sender] = (float(t[0]), float(t[1]), tick)
        else:
            self.targets.pop(m.sender, None)
        if valid_wire(m.door):
            door, _ = book.add(Doorway.from_wire(m.door, tick))  # type: ignore[arg-type]
            self.doors[m.sender] = (door, tick)
        else:
            self.doors.pop(m.sender, None)

    def _new_entries(self, sender: int, doors: tuple) -> list[Wire]:
        """The valid entries of a doorway list that its sender's previous list did not have: a robot
        repeats its whole list every heartbeat, and merging only what changed keeps this cheap."""
        last, seen = self._lists.get(sender, ((), frozenset()))
        if doors == last:
            return []
        try:
            entries = frozenset(doors)
        except TypeError:                        # an unhashable (malformed) entry
            entries = frozenset(w for w in doors if valid_wire(w))
        self._lists[sender] = (doors, entries)
        return [w for w in entries - seen if valid_wire(w)]

    def claimed(self, tick: int, max_age: int) -> list[Doorway]:
        """Doorways other robots said (within ``max_age`` ticks) they are going through."""
        return [d for d, t in self.doors.values() if tick - t <= max_age]

    def targets_mask(self, shape: tuple[int, int], tick: int, max_age: int, radius_m: float) -> np.ndarray | None:
        """Cells within ``radius_m`` of other robots' current targets (heard within ``max_age``), or None."""
        fresh = [(x, y) for x, y, t in self.targets.values() if tick - t <= max_age]
        if not fresh:
            return None
        h, w = shape
        mask = np.zeros((h, w), dtype=bool)
        k = math.ceil(radius_m / CELL_M)
        yy, xx = np.mgrid[-k:k + 1, -k:k + 1]
        disc = yy * yy + xx * xx <= k * k
        for x, y in fresh:
            r, c = cell_of(x, y)
            r0, r1, c0, c1 = max(r - k, 0), min(r + k + 1, h), max(c - k, 0), min(c + k + 1, w)
            if r0 >= r1 or c0 >= c1:
                continue
            mask[r0:r1, c0:c1] |= disc[r0 - (r - k):r1 - (r - k), c0 - (c - k):c1 - (c - k)]
        return mask
