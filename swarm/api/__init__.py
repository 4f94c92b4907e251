"""The plugin boundary: everything an exploration algorithm (or a path planner) may use from swarm.

An algorithm is a class with a ``name``, a frozen-dataclass ``Params`` and two methods::

    from swarm.api import Action, Observation, RobotInfo, check_int, grid

    @dataclass(frozen=True)
    class Params:
        patience: int = 50
        def __post_init__(self) -> None:
            check_int("patience", self.patience, 1, 10_000)   # a bad value is a one-line error

    class MyExplorer:
        name = "mine"
        Params = Params
        def reset(self, robot: RobotInfo, params: Params, rng: np.random.Generator) -> None: ...
        def act(self, obs: Observation) -> Action: ...

Register it under the ``swarm.algorithms`` entry-point group (``mine = "mypkg.explorer:MyExplorer"``) or
pass ``"mypkg.explorer:MyExplorer"`` as the algorithm name; ``swarm algorithms check mine`` checks it.
docs/plugins.md is the guide.

What is here: the types (:class:`Observation`, :class:`Action`, :class:`RobotInfo`, :class:`NavStatus`, the
cell constants and conversions, defined in :mod:`swarm.base.types`), the parameter validators and
:class:`InvalidInput` (:mod:`swarm.api.params`), the grid helpers (:mod:`swarm.api.grid`: configuration
space, plans, distance fields, frontiers, the nearest reachable unseen cell) and the message codec
(:mod:`swarm.api.messages`: :func:`message` to declare a message type, :class:`MessageError`). Nothing
outside ``swarm.api`` is part of the contract; ``algorithms/`` imports nothing else from swarm. Every
name's docstring states its return convention (and, for the grid helpers, its cost per call);
``python -m pdoc swarm.api -o docs/api`` renders them as the API reference.

A facade over lower packages: may import ``swarm.base``, ``swarm.grid``, ``swarm.comm``; nothing below it
imports ``swarm.api``, so what plugins see can grow without tangling the runtime.
"""

from __future__ import annotations

from swarm.base.types import (CELL_M, FREE, ROBOT_RADIUS_M, SOLID, UNSEEN, Action, Explorer, NavStatus, Neighbour,
                              Neighbours, NoParams, Observation, Pose, RobotInfo, cell_centre, cell_of, frozen_builder)

from .params import (OMIT_DEFAULT, InvalidInput, check_bool, check_choice, check_float, check_int, from_mapping,
                     to_mapping)

# Constants carry no docstring of their own: the API reference (pdoc) reads these annotation-only
# declarations' docstrings, which tests/test_api_reference.py keeps equal to the defining module's.
UNSEEN: int
"""Knowledge-map value of a cell not yet seen (by this robot or any robot whose map it received)."""
FREE: int
"""Knowledge-map value of a cell seen empty."""
SOLID: int
"""Knowledge-map value of a cell seen occupied (a wall); the largest, so merging maps is ``numpy.maximum``."""
CELL_M: float
"""Edge of one cell in metres, of ground-truth maps (:mod:`maps`) and knowledge maps alike."""
ROBOT_RADIUS_M: float
"""A robot's radius in metres, the default of :attr:`RobotInfo.radius` (read that one: it is the run's)."""
OMIT_DEFAULT: str
"""Field metadata key: ``field(default=..., metadata={OMIT_DEFAULT: True})`` leaves the field out of
:func:`to_mapping` while it holds its default. A setting added to an existing section carries it, so every
spec written before it existed keeps its canonical form and its run key (campaign folders resume)."""

__all__ = [
    "Action", "CELL_M", "Explorer", "FREE", "InvalidInput", "OMIT_DEFAULT", "NavStatus", "Neighbour", "Neighbours", "NoParams",
    "Observation", "Pose", "ROBOT_RADIUS_M", "RobotInfo", "SOLID", "UNSEEN", "cell_centre", "cell_of", "check_bool",
    "check_choice", "check_float", "check_int", "from_mapping", "frozen_builder", "to_mapping",
    "grid", "messages", "params",   # the submodules, so the API reference (pdoc) documents them too
]
