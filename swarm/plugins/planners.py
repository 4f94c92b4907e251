"""Path planners for the navigator, found by name like algorithms (entry-point group ``swarm.planners``).

A planner is a class with ``name`` and ``plan(space, start, goal, rng) -> int[N, 2] cells | None``: an
8-connected path of cells (consecutive cells are neighbours) through the robot's configuration space
(``space``, bool[H, W]); the navigator shortcuts it with :func:`swarm.grid.simplify`. Optionally it
declares ``Params`` (a dataclass its constructor takes; ``swarm plan --param`` sets its fields) and
``describe_last() -> str | None`` (one line about its last plan, which ``swarm plan`` prints). ``astar``
(the default, :func:`swarm.grid.plan`) is built in; ``iboa`` (the IBOA planner) is registered by the
``algorithms`` package. Plugins build on :mod:`swarm.api.grid`.
"""

from __future__ import annotations

from collections.abc import Mapping
from functools import lru_cache
from importlib.metadata import entry_points
from typing import Any, Protocol

import numpy as np

from swarm.base.errors import InvalidInput
from swarm.base.params import from_mapping

from swarm import grid

GROUP = "swarm.planners"


class PathPlanner(Protocol):
    name: str

    def plan(self, space: np.ndarray, start: tuple[int, int], goal: tuple[int, int],
             rng: np.random.Generator) -> np.ndarray | None: ...


class AStar:
    """Optimal 8-connected grid paths (:func:`swarm.grid.plan`)."""

    name = "astar"

    def plan(self, space: np.ndarray, start: tuple[int, int], goal: tuple[int, int],
             rng: np.random.Generator) -> np.ndarray | None:
        return grid.plan(space, start, goal)


def available() -> list[str]:
    return sorted({"astar", *(ep.name for ep in entry_points(group=GROUP))})


@lru_cache(maxsize=None)
def _planner_class(name: str) -> type:
    if name == "astar":
        return AStar
    for ep in entry_points(group=GROUP):
        if ep.name == name:
            try:
                return ep.load()
            except (ImportError, AttributeError) as exc:
                raise InvalidInput("navigation.planner", name, f"an installed planner ({exc})") from None
    raise InvalidInput("navigation.planner", name, " | ".join(available()))


def get_planner(name: str, params: Mapping[str, Any] | None = None, field: str = "--param") -> PathPlanner:
    """A fresh planner instance; ``params`` set fields of its ``Params`` (an error naming ``field`` for a
    planner that takes none, or for an unknown field)."""
    cls = _planner_class(name)
    params_cls = getattr(cls, "Params", None)
    if params_cls is None:
        if params:
            raise InvalidInput(field, dict(params), f"nothing: planner {name!r} takes no parameters")
        return cls()
    return cls(from_mapping(params_cls, params, prefix=f"{field} "))


def check_planner(name: str) -> str:
    _planner_class(name)
    return name
