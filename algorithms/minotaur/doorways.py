"""Doorways as a robot knows them: geometry, which sides they were seen from, whether anyone passed.

Alg. 3 ends with "if any doorway is seen from both sides or was passed through, mark it as explored";
MAES (docs/maes.md section 7.2) marks a doorway explored when a heartbeat brings the same doorway seen with
the opposite exit direction. We keep the two facts separately (``sides`` bitmask, ``passed``) so they
merge by OR when doorway lists meet, whatever order messages arrive in.

Doorways are axis-aligned: ``axis`` 0 is an opening that runs along x (a horizontal wall, crossed along
y), ``axis`` 1 runs along y (a vertical wall, crossed along x), as ``maps.building`` records true doors.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from swarm.api import CELL_M

MATCH_M = 1.25
"""Two doorway records with the same axis and centres closer than this are the same doorway (two scans of
a 1 m wall find its gap on each of the wall's two cell rows, 0.5 m apart)."""
SIDE_CLEAR_M = 0.25
"""A point is on a side of a doorway when it is this far beyond the wall's face."""

Wire = tuple[float, float, int, float, float, int, int]
"""A doorway on the wire: (x, y, axis, width, depth, sides, passed)."""


@dataclass
class Doorway:
    """One doorway; ``x, y`` is the centre of the opening (m), ``width`` along the wall, ``depth`` across."""

    x: float
    y: float
    axis: int
    width: float
    depth: float
    sides: int = 0              # bit 0: seen from the low side (-normal), bit 1: from the high side
    passed: bool = False
    found_tick: int = 0
    resolved: bool = False      # local: nothing unseen is left behind it (not shared, re-checked)
    failed_until: int = -1      # local: the navigator could not get through; skip until this tick
    _cut: tuple[int, int, int, int] | None = field(default=None, repr=False, compare=False)
    _wire: tuple[tuple[int, bool], Wire] | None = field(default=None, init=False, repr=False, compare=False)

    # ---------------------------------------------------------------------------------- geometry ----
    @property
    def explored(self) -> bool:
        return self.sides == 3 or self.passed

    @property
    def normal(self) -> tuple[float, float]:
        return (0.0, 1.0) if self.axis == 0 else (1.0, 0.0)

    def across(self, x: float, y: float) -> float:
        """Signed distance of a point from the door's centre line along the normal."""
        return y - self.y if self.axis == 0 else x - self.x

    def along(self, x: float, y: float) -> float:
        """Signed distance of a point from the door's centre along the opening."""
        return x - self.x if self.axis == 0 else y - self.y

    def side_of(self, x: float, y: float) -> int:
        """-1 or +1 when the point is clearly on one side of the wall, 0 inside it."""
        d = self.across(x, y)
        if abs(d) <= self.depth / 2 + SIDE_CLEAR_M:
            return 0
        return 1 if d > 0 else -1

    def in_front(self, x: float, y: float, slack_m: float = 0.5) -> bool:
        """The point is within the opening's extent along the wall (widened by ``slack_m``)."""
        return abs(self.along(x, y)) <= self.width / 2 + slack_m

    def point(self, side: int, distance_m: float) -> tuple[float, float]:
        """The point ``distance_m`` from the wall's face on ``side``, in front of the opening's centre."""
        nx, ny = self.normal
        d = side * (self.depth / 2 + distance_m)
        return self.x + nx * d, self.y + ny * d

    def cut(self) -> tuple[int, int, int, int]:
        """Cells (r0, c0, r1, c1), inclusive, that close the opening for "without passing a doorway"
        searches: the opening across the wall's thickness, one cell wider than the gap on each end."""
        if self._cut is None:
            half_w, half_d = self.width / 2, self.depth / 2
            if self.axis == 0:
                x0, x1, y0, y1 = self.x - half_w, self.x + half_w, self.y - half_d, self.y + half_d
            else:
                x0, x1, y0, y1 = self.x - half_d, self.x + half_d, self.y - half_w, self.y + half_w
            c0, c1 = math.floor(x0 / CELL_M + 1e-6), math.ceil(x1 / CELL_M - 1e-6) - 1
            r0, r1 = math.floor(y0 / CELL_M + 1e-6), math.ceil(y1 / CELL_M - 1e-6) - 1
            if self.axis == 0:
                c0, c1 = c0 - 1, c1 + 1
            else:
                r0, r1 = r0 - 1, r1 + 1
            self._cut = (r0, c0, r1, c1)
        return self._cut

    def matches(self, other: Doorway) -> bool:
        return self.axis == other.axis and math.hypot(self.x - other.x, self.y - other.y) < MATCH_M

    # --------------------------------------------------------------------------------------- wire ----
    def wire(self) -> Wire:
        """The record as others receive it. Kept while its explored facts stay (the geometry never changes
        after a record is made): every heartbeat sends the whole list."""
        key = (self.sides, self.passed)
        if self._wire is None or self._wire[0] != key:
            self._wire = (key, (round(self.x, 3), round(self.y, 3), self.axis, round(self.width, 3),
                                round(self.depth, 3), self.sides, int(self.passed)))
        return self._wire[1]

    @classmethod
    def from_wire(cls, w: Wire, tick: int = 0) -> Doorway:
        x, y, axis, width, depth, sides, passed = w
        return cls(float(x), float(y), int(axis), float(width), float(depth), int(sides) & 3, bool(passed),
                   found_tick=tick)


def valid_wire(w: object) -> bool:
    """A received doorway tuple that is safe to use (messages come from other robots: never trust them)."""
    if not isinstance(w, tuple) or len(w) != 7:
        return False
    x, y, axis, width, depth, sides, passed = w
    finite, num = math.isfinite, (int, float)     # spelled out: every heartbeat entry that changed comes here
    return (isinstance(x, num) and not isinstance(x, bool) and finite(x)
            and isinstance(y, num) and not isinstance(y, bool) and finite(y)
            and isinstance(width, num) and not isinstance(width, bool) and finite(width)
            and isinstance(depth, num) and not isinstance(depth, bool) and finite(depth)
            and axis in (0, 1) and 0 < width <= 50 and 0 < depth <= 50 and isinstance(sides, int)
            and isinstance(passed, int) and 0 <= x <= 1e5 and 0 <= y <= 1e5)


class DoorwayBook:
    """The doorways one robot knows, matched by position, merged by OR of their explored facts.

    Lookups go through a grid of ``MATCH_M`` buckets (a match is always in the 3 x 3 buckets around a
    point), because every heartbeat brings every doorway its sender knows. ``version`` changes whenever a
    record is added or changes, so derived views can be cached."""

    def __init__(self) -> None:
        self.doors: list[Doorway] = []
        self._buckets: dict[tuple[int, int, int], list[Doorway]] = {}
        self.version = 0
        self._xy = np.zeros((0, 2))
        self._wire: tuple[int, tuple[Wire, ...]] = (-1, ())
        self._found: dict[tuple[int, float, float], tuple[int, Doorway | None]] = {}
        self._boxes = np.zeros((0, 4), dtype=np.int64)

    def __iter__(self):
        return iter(self.doors)

    def __len__(self) -> int:
        return len(self.doors)

    @staticmethod
    def _key(door: Doorway) -> tuple[int, int, int]:
        return door.axis, math.floor(door.x / MATCH_M), math.floor(door.y / MATCH_M)

    def find(self, door: Doorway) -> Doorway | None:
        return self._find_at(door.axis, door.x, door.y)

    def _find_at(self, axis: int, x: float, y: float) -> Doorway | None:
        """The first record (bucket by bucket) matching a doorway with this axis and centre. Heartbeats and
        scans bring the same doorways over and over: an answer is remembered while no record is added
        (only a new record can change it: records never move)."""
        hit = self._found.get((axis, x, y))
        if hit is not None and hit[0] == len(self.doors):
            return hit[1]
        bx, by = math.floor(x / MATCH_M), math.floor(y / MATCH_M)
        found = None
        for dx in (-1, 0, 1):
            for dy in (-1, 0, 1):
                for d in self._buckets.get((axis, bx + dx, by + dy), ()):
                    if d.axis == axis and math.hypot(d.x - x, d.y - y) < MATCH_M:   # Doorway.matches
                        found = d
                        break
                if found is not None:
                    break
            if found is not None:
                break
        self._found[(axis, x, y)] = (len(self.doors), found)
        return found

    def add(self, door: Doorway) -> tuple[Doorway, bool]:
        """Add or merge; returns (the stored record, whether it is new)."""
        known = self.find(door)
        if known is None:
            self.doors.append(door)
            self._buckets.setdefault(self._key(door), []).append(door)
            self._xy = np.vstack([self._xy, [[door.x, door.y]]])
            self.version += 1
            return door, True
        self._merge(known, door.sides, door.passed)
        return known, False

    def add_wire(self, w: Wire, tick: int = 0) -> tuple[Doorway, bool]:
        """``add(Doorway.from_wire(w, tick))`` for a valid wire tuple, without making the record unless it
        is new."""
        known = self._find_at(int(w[2]), float(w[0]), float(w[1]))
        if known is None:
            return self.add(Doorway.from_wire(w, tick))
        self._merge(known, int(w[5]) & 3, bool(w[6]))
        return known, False

    def _merge(self, known: Doorway, sides: int, passed: bool) -> None:
        sides, passed = known.sides | sides, known.passed or passed
        if (sides, passed) != (known.sides, known.passed):
            known.sides, known.passed = sides, passed
            self.version += 1

    def touch(self) -> None:
        """A record's explored facts changed in place."""
        self.version += 1

    def unexplored(self, tick: int) -> list[Doorway]:
        return [d for d in self.doors if not d.explored and not d.resolved and d.failed_until < tick]

    def near(self, x: float, y: float, radius: float) -> list[int]:
        """Indices of the doorways whose centre is within ``radius`` of (x, y)."""
        if not self.doors:
            return []
        d2 = (self._xy[:, 0] - x) ** 2 + (self._xy[:, 1] - y) ** 2
        return np.flatnonzero(d2 <= radius * radius).tolist()

    def cut_boxes(self) -> np.ndarray:
        """Every record's :meth:`Doorway.cut` as int64[N, 4] rows (r0, c0, r1, c1), in record order (kept:
        records are only added, and their geometry never changes)."""
        if len(self._boxes) != len(self.doors):
            self._boxes = np.array([d.cut() for d in self.doors], dtype=np.int64).reshape(-1, 4)
        return self._boxes

    def wire(self) -> tuple[Wire, ...]:
        version, wire = self._wire
        if version != self.version:
            wire = tuple(map(Doorway.wire, self.doors))
            self._wire = (self.version, wire)
        return wire
