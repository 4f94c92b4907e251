"""``swarm.run``: one run from Python, read and validated as ``swarm run`` reads its flags.

::

    import swarm
    r = swarm.run("run.toml", robots=8, algorithm="tnf", radio={"model": "los"})
    r.summary["ticks_to"]["0.99"], r.timeseries["explored"]

The campaign side is :mod:`swarm.campaign` (``swarm.campaign.run``, ``load``, ``load_timeseries``);
docs/python-api.md is the guide.
"""

from __future__ import annotations

from typing import Any, Callable, Sequence

from swarm.base.errors import InvalidInput
from swarm.results.result import RunResult
from .spec import RunSpec
from .spec_input import resolve


def run(spec: Any = None, /, *, observers: Sequence[Callable[[Any], None]] = (), **overrides: Any) -> RunResult:
    """Run one simulation and return its :class:`~swarm.results.result.RunResult`.

    ``spec``: None (every default: 4 robots, frontier explorer, 50 x 50 building, seed 0), a
    :class:`~swarm.sim.spec.RunSpec`, a mapping of spec sections, TOML text, or the path of a TOML run spec
    (``swarm run --print-spec`` writes one). ``overrides`` are applied on top as ``swarm run``'s flags are:
    ``map`` (``"building"``, ``"cave"`` or a map file), ``size``, ``map_seed``, ``robots``, ``spawn``,
    ``algorithm``, ``seed``, ``max_ticks``, ``explored``, ``transport``, ``params`` (the algorithm's),
    ``map_params``, or any section as a table merged into the spec's (``lidar={"range_m": 4}``;
    ``radio="los"`` names the radio model alone).
    ``observers`` are called after every tick with a :class:`~swarm.sim.loop.TickView`.

    Bad input raises :class:`swarm.InvalidInput` with the one-line message the command line prints.
    """
    from .loop import Simulation

    resolved = resolve(spec, overrides)
    return Simulation(resolved, observers=check_observers(observers)).run()


def check_observers(observers: Any) -> tuple[Callable[[Any], None], ...]:
    """``observers`` as a tuple of callables, or a one-line error naming the first that is not one (a bare
    callable, or a non-sequence, would otherwise fail mid-run with a TypeError)."""
    if isinstance(observers, (str, bytes)) or not isinstance(observers, Sequence):
        raise InvalidInput("observers", observers, "a list of callables, each called with a TickView after every tick")
    for i, observer in enumerate(observers):
        if not callable(observer):
            raise InvalidInput(f"observers[{i}]", observer, "a callable taking a TickView")
    return tuple(observers)


def resolve_spec(spec: Any = None, /, **overrides: Any) -> RunSpec:
    """The :class:`~swarm.sim.spec.RunSpec` :func:`run` would run (``spec.to_toml()`` shows every default)."""
    return resolve(spec, overrides)


__all__ = ["resolve_spec", "run"]
