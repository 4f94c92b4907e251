"""The types an exploration algorithm implements and sees (re-exported by :mod:`swarm.api`).

Light: numpy only, never the runtime. Conventions: world coordinates in metres from the map's lower-left
corner, x right, y up, headings in radians counter-clockwise from +x. Knowledge maps are ``uint8[H, W]``
rasters of 0.5 m cells with ``UNSEEN = 0 < FREE = 1 < SOLID = 2``, so merging two maps is
``numpy.maximum``; ``known[row, col]`` covers ``x in [col*0.5, (col+1)*0.5)``, ``y in [row*0.5, (row+1)*0.5)``.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any, Callable, ClassVar, Mapping, NamedTuple, Protocol, Sequence, runtime_checkable

import numpy as np

UNSEEN: int = 0
"""Knowledge-map value of a cell not yet seen (by this robot or any robot whose map it received)."""
FREE: int = 1
"""Knowledge-map value of a cell seen empty."""
SOLID: int = 2
"""Knowledge-map value of a cell seen occupied (a wall); the largest, so merging maps is ``numpy.maximum``."""
CELL_M: float = 0.5
"""Edge of one cell in metres, of ground-truth maps (:mod:`maps`) and knowledge maps alike."""
ROBOT_RADIUS_M: float = 0.3
"""A robot's radius in metres, the default of :attr:`RobotInfo.radius` (read that one: it is the run's)."""


class Pose(NamedTuple):
    """Position (m) and heading (rad, CCW from +x)."""

    x: float
    """Metres from the map's left edge."""
    y: float
    """Metres from the map's bottom edge."""
    theta: float
    """Heading in radians, counter-clockwise from +x."""


def cell_of(x: float, y: float) -> tuple[int, int]:
    """(row, col) of the 0.5 m cell containing (x, y) metres (row 0 at the bottom). Not clipped: a point off
    the map gives a cell off it (negative, or >= the map's shape). Cost: O(1), under 1 us."""
    return int(math.floor(y / CELL_M)), int(math.floor(x / CELL_M))


def cell_centre(row: int, col: int) -> tuple[float, float]:
    """(x, y) of a cell's centre in metres: the goal to give :class:`Action` for a cell. Cost: O(1), under
    1 us."""
    return (col + 0.5) * CELL_M, (row + 0.5) * CELL_M


class Neighbour(NamedTuple):
    """Another robot this robot can sense this tick (within sensing range and line of sight)."""

    id: int
    """The other robot's id."""
    distance: float
    """Metres, centre to centre."""
    bearing: float
    """Radians relative to this robot's heading, counter-clockwise."""
    x: float
    """Its position estimate, metres."""
    y: float
    """Its position estimate, metres."""


def sensed_within(near: Any, distance: Any, row: int, range_m: float) -> tuple[np.ndarray, np.ndarray]:
    """``(cols, distances)`` of row ``row`` of a tick's (R, R) ``near`` mask and ``distance`` matrix: the
    robots it senses nearer than ``range_m``, in robot order."""
    cols = np.flatnonzero(near[row])
    cols = cols[distance[row, cols] < range_m]
    return cols, distance[row, cols]


class Neighbours(Sequence[Neighbour]):
    """A robot's sensed neighbours, built into :class:`Neighbour` tuples only when first read (most
    algorithms never look, and building them for 16 packed robots costs more than the rest of a tick).

    Holds the tick's (R, R) ``near`` mask, distance and bearing matrices and (R, 2) positions, and this
    robot's row. A read-only sequence ordered by robot id; empty when nobody is in range. Cost: the first
    full read builds every tuple, O(R); ``bool(...)`` and :meth:`within` build none or only the near ones."""

    __slots__ = ("_source", "_items")

    def __init__(self, row: int, near: Any, distance: Any, bearing: Any, xy: Any) -> None:
        self._source: tuple[Any, ...] | None = (row, near, distance, bearing, xy)
        self._items: tuple[Neighbour, ...] | None = None

    def _all(self) -> tuple[Neighbour, ...]:
        if self._items is None:
            assert self._source is not None
            row, near, distance, bearing, xy = self._source
            cols = np.flatnonzero(near[row])
            self._items = tuple(Neighbour(*r) for r in zip(cols.tolist(), distance[row, cols].tolist(),
                                                           bearing[row, cols].tolist(), xy[cols, 0].tolist(),
                                                           xy[cols, 1].tolist()))
            self._source = None
        return self._items

    def within(self, range_m: float) -> tuple[Neighbour, ...]:
        """The neighbours closer than ``range_m`` (in robot order), without building the others: a robot in
        a swarm senses hundreds, and a check such as "is anyone right behind me" needs the nearest few."""
        if self._source is None:
            return tuple(n for n in self._all() if n.distance < range_m)
        row, near, distance, bearing, xy = self._source
        query = getattr(near, "near", None)  # the runtime's: a spatial index, not the (R, R) matrices
        cols, dist = query(row, range_m) if query is not None else sensed_within(near, distance, row, range_m)
        if not len(cols):
            return ()
        return tuple(Neighbour(*r) for r in zip(cols.tolist(), dist.tolist(), bearing[row, cols].tolist(),
                                                xy[cols, 0].tolist(), xy[cols, 1].tolist()))

    def __getitem__(self, index):  # type: ignore[override]
        return self._all()[index]

    def __len__(self) -> int:
        return len(self._all())

    def __iter__(self):
        return iter(self._all())

    def __bool__(self) -> bool:
        if self._source is not None:
            row, near = self._source[0], self._source[1]
            return bool(near[row].any())
        return bool(self._items)

    def __eq__(self, other: object) -> bool:
        return tuple(self) == tuple(other) if isinstance(other, Sequence) else NotImplemented

    def __repr__(self) -> str:
        return f"Neighbours{self._all()!r}"


@dataclass(frozen=True)
class NavStatus:
    """What the runtime's navigator is doing for this robot."""

    goal: tuple[float, float] | None = None
    """The goal (x, y) metres the state refers to, None when idle."""
    state: str = "idle"
    """``idle``, ``planning``, ``moving``, ``reached``, ``unreachable`` or ``blocked`` (docs/plugins.md)."""
    path_length: float = 0.0
    """Metres of planned path left to drive (0.0 without a path)."""
    ticks_since_progress: int = 0
    """Ticks since the remaining path last shrank by 5 cm (the navigator replans after 30)."""


@dataclass(frozen=True)
class RobotInfo:
    """Static facts about one robot, given to ``Explorer.reset``."""

    id: int
    """This robot's id, ``0 .. n_robots - 1``."""
    n_robots: int
    """How many robots the run has."""
    map_shape: tuple[int, int]
    """(H, W) of ``Observation.known``, in cells."""
    radius: float = ROBOT_RADIUS_M
    """Metres; pass it to the grid helpers' ``radius_m``."""
    lidar_range: float = 7.0
    """Metres."""
    max_speed: float = 1.0
    """m/s; ``Action.velocity`` is clipped to it."""
    max_turn_rate: float = 2.0
    """rad/s; ``Action.velocity`` is clipped to it."""
    tick_seconds: float = 0.1
    """Simulated seconds per tick."""
    battery: float | None = None
    """Energy budget (algorithm-defined units), None = unlimited."""


@dataclass(frozen=True)
class Observation:
    """Everything a robot knows at the start of its decision in tick ``tick``."""

    tick: int
    """The tick number, from 0."""
    robot_id: int
    """This robot's id."""
    pose: Pose
    """Where the robot is (metres, radians)."""
    known: np.ndarray
    """uint8[H, W], a read-only view of the robot's own map (UNSEEN/FREE/SOLID); copy it to change it."""
    inbox: tuple[Any, ...] = ()
    """Messages delivered this tick (sent by others at tick - 1), ordered by sender."""
    neighbours: Sequence[Neighbour] = ()
    """Robots in sensing range and line of sight (:class:`Neighbours`: built only when read)."""
    collided: bool = False
    """Touched a wall or robot since the last decision."""
    nav: NavStatus = NavStatus()
    """What the navigator is doing."""
    distance_travelled: float = 0.0
    """Metres driven since the start."""
    energy_used: float = 0.0
    """Metres driven plus radians turned (see swarm.world.physics)."""


DRIVES: tuple[str, ...] = ("path", "runs", "straight")
"""The ways :attr:`Action.drive` may ask to be driven to a goal."""


@dataclass(frozen=True)
class Action:
    """A decision. ``goal`` (x, y) in metres: the runtime plans and drives there on the robot's own map.
    ``velocity`` (v m/s, omega rad/s): direct control, overrides navigation for this tick. Neither: keep
    doing what it was doing (follow the current goal, if any). ``messages`` are broadcast this tick and
    delivered next tick to every robot the radio reaches. ``debug`` is free-form (shown by the viewer).
    ``drive`` says how to drive to ``goal`` under MAES's motion model (``motion.model = "maes"``, see
    :mod:`swarm.navigation.maes_drive`): ``"path"`` tile by tile along a planned path (MAES's
    ``PathAndMoveTo``), ``"runs"`` along the straight runs of a planned path (TNF's path steps) or
    ``"straight"`` in one straight move (MAES's ``MoveTo``); the continuous model plans and follows a
    smooth path whatever it says."""

    goal: tuple[float, float] | None = None
    """(x, y) metres, or None: plan and drive there (setting the same goal again changes nothing)."""
    velocity: tuple[float, float] | None = None
    """(v m/s, omega rad/s), or None: direct control for this tick only."""
    messages: tuple[Any, ...] = ()
    """Registered messages to broadcast this tick (a tuple)."""
    debug: Mapping[str, Any] | None = None
    """Free-form, msgpack-able; shown by the viewer, not part of a run's result."""
    clear_goal: bool = False
    """True drops the current goal first (the navigator goes idle)."""
    drive: str = "path"
    """One of :data:`DRIVES`; only MAES's motion model reads it."""


def frozen_builder(cls: type) -> Callable[..., Any]:
    """``cls(**fields)`` for a frozen dataclass, called with every field by keyword, built without the
    generated ``__init__``: that sets each field through ``object.__setattr__`` (frozen), 2.1 us for an
    Observation against 0.7 us, and the runtime and transports build several per robot per tick. The
    result is the same object (equal, same repr); callers must pass every field (tests compare with the
    constructor). Gives the constructor itself if ``cls`` has slots or a ``__post_init__``."""
    plain = (dataclasses.is_dataclass(cls) and "__slots__" not in cls.__dict__
             and not hasattr(cls, "__post_init__"))
    if not plain:
        return cls
    new = object.__new__

    def build(**fields: Any) -> Any:
        obj = new(cls)
        obj.__dict__.update(fields)
        return obj

    return build


@runtime_checkable
class Explorer(Protocol):
    """The algorithm interface: one instance per robot, built without arguments (docs/plugins.md)."""

    name: ClassVar[str]
    """The algorithm's name, shown in results."""
    Params: ClassVar[type]
    """A frozen dataclass of the parameters, every field with a default (:class:`NoParams` if none)."""

    def reset(self, robot: RobotInfo, params: Any, rng: np.random.Generator) -> None:
        """Once, before the first tick: the robot's facts, the built ``Params`` and the robot's own random
        generator (draw every random number from it: runs are bit-reproducible)."""

    def act(self, obs: Observation) -> Action:
        """Once per tick while the robot is alive: the decision for ``obs`` (never change ``obs``). Its cost
        is the robot's share of a tick: keep it to a few grid helper calls."""


@dataclass(frozen=True)
class NoParams:
    """The ``Params`` of an algorithm without parameters (an empty frozen dataclass)."""


__all__ = [
    "Action", "CELL_M", "DRIVES", "Explorer", "FREE", "NavStatus", "Neighbour", "Neighbours", "NoParams", "Observation", "Pose",
    "ROBOT_RADIUS_M", "RobotInfo", "SOLID", "UNSEEN", "cell_centre", "cell_of", "sensed_within",
]
