"""swarm: multi-robot exploration under realistic radio.

The few names a user needs, imported on first use (so ``import swarm`` and the command line stay fast)::

    import swarm
    result = swarm.run({"map": {"kind": "cave", "size": 60}, "seed": 1}, robots=4)   # or a TOML file
    result.summary["explored"], result.timeseries["explored"]
    runs = swarm.campaign.run("grid.toml", "results/grid", workers=2).runs()   # a pandas DataFrame
    truth = swarm.load_map("house.npz")          # or swarm.generate("building", 100, seed=7)

Plugins (exploration algorithms, planners) import from :mod:`swarm.api`; :func:`swarm.testing.check_explorer`
checks one. ``swarm.env`` holds the Gymnasium and PettingZoo environments (``pip install 'swarm-sim[rl]'``),
imported only when used. docs/python-api.md is the guide.
"""

from __future__ import annotations

from importlib import import_module
from typing import Any

_EXPORTS = {
    "run": ("swarm.sim.python_api", "run"),
    "resolve_spec": ("swarm.sim.python_api", "resolve_spec"),
    "Simulation": ("swarm.sim.loop", "Simulation"),
    "RunSpec": ("swarm.sim.spec", "RunSpec"),
    "RunResult": ("swarm.results.result", "RunResult"),
    "Explorer": ("swarm.api", "Explorer"),
    "Observation": ("swarm.api", "Observation"),
    "Action": ("swarm.api", "Action"),
    "RobotInfo": ("swarm.api", "RobotInfo"),
    "InvalidInput": ("swarm.base.errors", "InvalidInput"),
    "Map": ("maps", "Map"),
    "generate": ("maps", "generate"),
    "load_map": ("maps.io", "load_map"),
}

_SUBPACKAGES = ("campaign", "env")
"""Reached as ``swarm.campaign`` / ``swarm.env`` without importing them first (``swarm.env`` needs the rl extra)."""

__all__ = sorted(_EXPORTS)


def __getattr__(name: str) -> Any:
    if name in _EXPORTS:
        module, attr = _EXPORTS[name]
        value = getattr(import_module(module), attr)
        globals()[name] = value
        return value
    if name in _SUBPACKAGES:
        return import_module(f"swarm.{name}")  # the import binds it as an attribute of this package
    raise AttributeError(f"module 'swarm' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_EXPORTS) | set(_SUBPACKAGES))
