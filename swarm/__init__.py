"""swarm: multi-robot exploration under realistic radio.

The few names a user needs, imported on first use (so ``import swarm`` and the command line stay fast)::

    import swarm
    result = swarm.run({"map": {"kind": "cave", "size": 60}, "robots": {"count": 4}, "seed": 1})
    result.summary["explored"], result.timeseries["explored"]
    truth = swarm.load_map("house.npz")          # or swarm.generate("building", 100, seed=7)

Plugins (exploration algorithms, planners) import from :mod:`swarm.api`; :func:`swarm.testing.check_explorer`
checks one.
"""

from __future__ import annotations

from importlib import import_module
from typing import Any

_EXPORTS = {
    "run": ("swarm.simulation", "run"),
    "Simulation": ("swarm.simulation", "Simulation"),
    "RunSpec": ("swarm.spec", "RunSpec"),
    "RunResult": ("swarm.result", "RunResult"),
    "Explorer": ("swarm.api", "Explorer"),
    "Observation": ("swarm.api", "Observation"),
    "Action": ("swarm.api", "Action"),
    "RobotInfo": ("swarm.api", "RobotInfo"),
    "InvalidInput": ("swarm.api", "InvalidInput"),
    "Map": ("maps", "Map"),
    "generate": ("maps", "generate"),
    "load_map": ("maps.io", "load_map"),
}

__all__ = sorted(_EXPORTS)


def __getattr__(name: str) -> Any:
    if name in _EXPORTS:
        module, attr = _EXPORTS[name]
        value = getattr(import_module(module), attr)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'swarm' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_EXPORTS))
