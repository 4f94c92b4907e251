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
FREE: int = 1
SOLID: int = 2
CELL_M: float = 0.5
"""Edge of one cell in metres, of ground-truth maps (:mod:`maps`) and knowledge maps alike."""
ROBOT_RADIUS_M: float = 0.3


class Pose(NamedTuple):
    """Position (m) and heading (rad, CCW from +x)."""

    x: float
    y: float
    theta: float


def cell_of(x: float, y: float) -> tuple[int, int]:
    """(row, col) of the 0.5 m cell containing (x, y)."""
    return int(math.floor(y / CELL_M)), int(math.floor(x / CELL_M))


def cell_centre(row: int, col: int) -> tuple[float, float]:
    """(x, y) of a cell's centre in metres."""
    return (col + 0.5) * CELL_M, (row + 0.5) * CELL_M


class Neighbour(NamedTuple):
    """Another robot this robot can sense this tick (within sensing range and line of sight)."""

    id: int
    distance: float
    bearing: float          # relative to this robot's heading, radians
    x: float                # absolute position estimate
    y: float


class Neighbours(Sequence[Neighbour]):
    """A robot's sensed neighbours, built into :class:`Neighbour` tuples only when first read (most
    algorithms never look, and building them for 16 packed robots costs more than the rest of a tick).

    Holds the tick's (R, R) ``near`` mask, distance and bearing matrices and (R, 2) positions, and this
    robot's row."""

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
        cols = np.flatnonzero(near[row])
        cols = cols[distance[row, cols] < range_m]
        return tuple(Neighbour(*r) for r in zip(cols.tolist(), distance[row, cols].tolist(),
                                                bearing[row, cols].tolist(), xy[cols, 0].tolist(),
                                                xy[cols, 1].tolist()))

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
    state: str = "idle"     # idle | moving | reached | unreachable | blocked
    path_length: float = 0.0
    ticks_since_progress: int = 0


@dataclass(frozen=True)
class RobotInfo:
    """Static facts about one robot, given to ``Explorer.reset``."""

    id: int
    n_robots: int
    map_shape: tuple[int, int]
    radius: float = ROBOT_RADIUS_M
    lidar_range: float = 7.0
    max_speed: float = 1.0
    max_turn_rate: float = 2.0
    tick_seconds: float = 0.1
    battery: float | None = None   # energy budget (algorithm-defined units), None = unlimited


@dataclass(frozen=True)
class Observation:
    """Everything a robot knows at the start of its decision in tick ``tick``."""

    tick: int
    robot_id: int
    pose: Pose
    known: np.ndarray                       # uint8[H, W], read-only view of the robot's own map
    inbox: tuple[Any, ...] = ()             # messages delivered this tick (sent by others at tick - 1)
    neighbours: Sequence[Neighbour] = ()    # robots in sensing range and line of sight
    collided: bool = False                  # touched a wall or robot since the last decision
    nav: NavStatus = NavStatus()
    distance_travelled: float = 0.0         # metres since the start
    energy_used: float = 0.0                # moves + rotations, see swarm.world.physics


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
    velocity: tuple[float, float] | None = None
    messages: tuple[Any, ...] = ()
    debug: Mapping[str, Any] | None = None
    clear_goal: bool = False
    drive: str = "path"


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
    """The algorithm interface; see the module docstring."""

    name: ClassVar[str]
    Params: ClassVar[type]

    def reset(self, robot: RobotInfo, params: Any, rng: np.random.Generator) -> None: ...

    def act(self, obs: Observation) -> Action: ...


@dataclass(frozen=True)
class NoParams:
    """For algorithms without parameters."""


__all__ = [
    "Action", "CELL_M", "DRIVES", "Explorer", "FREE", "NavStatus", "Neighbour", "Neighbours", "NoParams", "Observation", "Pose",
    "ROBOT_RADIUS_M", "RobotInfo", "SOLID", "UNSEEN", "cell_centre", "cell_of",
]
