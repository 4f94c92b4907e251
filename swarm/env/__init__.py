"""Learning environments over the real runtime (pymunk world, lidar, radio-gated messaging, map sharing,
knowledge maps): a PettingZoo ``ParallelEnv`` with one agent per robot and a Gymnasium ``Env`` with one
learning robot among scripted teammates. Needs the ``rl`` extra (``pip install 'swarm-sim[rl]'``);
``import swarm`` never imports this package.

::

    import gymnasium as gym
    import swarm.env                                     # registers swarm/Explore-v0, swarm/ExploreVelocity-v0
    env = gym.make("swarm/Explore-v0", robots=4, size=30, algorithm="tnf", radio="multiwall")
    penv = swarm.env.parallel_env(robots=8, size=50)     # PettingZoo

Observations, actions, rewards and seeding: docs/python-api.md ("Learning"). The engine under both is
:class:`~swarm.env.core.ExplorationCore`, which needs neither library. May import: ``swarm.sim``, ``swarm.api``
and every package below them.
"""

from __future__ import annotations

from importlib import import_module
from typing import Any

from .config import EnvConfig, Reward

ENV_IDS = {"swarm/Explore-v0": {}, "swarm/ExploreVelocity-v0": {"action": "velocity"}}
"""Gymnasium ids registered on import: discrete goal choices, and continuous velocities."""
_LAZY = {"SwarmEnv": "single", "SwarmParallelEnv": "parallel", "parallel_env": "parallel",
         "ExplorationCore": "core"}
_RL_EXTRA = "pip install 'swarm-sim[rl]'"


def register_envs() -> None:
    """Register :data:`ENV_IDS` with Gymnasium (done on import when Gymnasium is installed)."""
    import gymnasium

    for env_id, kwargs in ENV_IDS.items():
        if env_id not in gymnasium.registry:
            gymnasium.register(env_id, entry_point="swarm.env.single:SwarmEnv", kwargs=dict(kwargs),
                               disable_env_checker=False)


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        try:
            value = getattr(import_module(f".{_LAZY[name]}", __name__), name)
        except ModuleNotFoundError as exc:
            if exc.name in ("gymnasium", "pettingzoo"):
                raise ModuleNotFoundError(f"swarm.env.{name} needs {exc.name}: {_RL_EXTRA}", name=exc.name) from None
            raise
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


try:
    register_envs()
except ModuleNotFoundError:  # without the rl extra: the core still imports, the ids are not registered
    pass

__all__ = ["ENV_IDS", "EnvConfig", "ExplorationCore", "Reward", "SwarmEnv", "SwarmParallelEnv", "parallel_env",
           "register_envs"]
