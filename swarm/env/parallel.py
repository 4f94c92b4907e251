"""The PettingZoo environment: every robot (or the ``learners``) an agent, stepping together."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from pettingzoo import ParallelEnv

from swarm.base.errors import InvalidInput

from .config import EnvConfig, Reward, check_render_mode, env_spec, episode_seed
from .core import ExplorationCore
from .render import RENDER_PX, check_render_px, render_rgb
from .spaces import action_space, observation_space


class SwarmParallelEnv(ParallelEnv):
    """One agent ``robot_<id>`` per learning robot (every robot by default; others run the spec's
    ``algorithm``). ``spec`` and ``overrides`` are a run spec as :func:`swarm.run` takes them; the other
    keywords are :class:`~swarm.env.config.EnvConfig`'s. All agents end together, when the run stops:
    terminated when the map is explored (``stop.explored``), truncated at ``stop.max_ticks`` or a stall.
    ``reset(seed=s)`` runs the spec with master seed ``s`` (without a seed: the spec's seed first, then a
    deterministic sequence)."""

    metadata = {"name": "swarm_explore_v0", "render_modes": ["rgb_array"], "render_fps": 10,
                "is_parallelizable": True}

    def __init__(self, spec: Any = None, *, learners: Any = None, action: str = "goal", delegate: bool = False,
                 ticks_per_step: int = 1, crop_cells: int = 32, observe_all: bool = False, margin_db: float = 60.0,
                 reward: Reward | dict[str, float] | None = None, render_mode: str | None = None,
                 render_px: int = RENDER_PX, **overrides: Any) -> None:
        config = EnvConfig(learners=learners, action=action, delegate=delegate, ticks_per_step=ticks_per_step,
                           crop_cells=crop_cells, observe_all=observe_all, margin_db=margin_db,
                           reward=Reward() if reward is None else reward)
        check_render_mode(render_mode, self.metadata["render_modes"])
        self.render_px = check_render_px(render_px)
        self.core = ExplorationCore(env_spec(spec, overrides), config)
        self.render_mode = render_mode
        self.possible_agents = [f"robot_{i}" for i in self.core.learners]
        self.agents: list[str] = []
        self._pairs = list(zip(self.possible_agents, self.core.learners))
        self._agent_set = frozenset(self.possible_agents)
        self._observation_space = observation_space(self.core)
        self._action_space = action_space(self.core)
        self._rng: np.random.Generator | None = None

    def observation_space(self, agent: str) -> Any:
        """The same ``Dict`` space for every agent (swarm.env.spaces.observation_space)."""
        return self._observation_space

    def action_space(self, agent: str) -> Any:
        return self._action_space

    def reset(self, seed: int | None = None, options: dict[str, Any] | None = None) -> tuple[dict, dict]:
        run_seed, self._rng = episode_seed(seed, self._rng, self.core.base.seed)
        self.core.reset(run_seed)
        self.agents = list(self.possible_agents)
        return self._observations(), self._infos()

    def step(self, actions: dict[str, Any]) -> tuple[dict, dict, dict, dict, dict]:
        if not self.agents:
            raise RuntimeError("step() after every agent is done: call reset()")
        if not isinstance(actions, Mapping):
            raise InvalidInput("actions", actions, "a dict of agent name -> action, e.g. {'robot_0': 1}")
        if not actions.keys() >= self._agent_set:
            missing = [a for a in self.agents if a not in actions]
            raise InvalidInput("actions", list(actions)[:8], f"an action for every live agent (missing {missing[:4]})")
        core = self.core
        core.step({robot: actions[a] for a, robot in self._pairs})
        obs, infos = self._observations(), self._infos()
        rewards = dict(zip(self.agents, core.rewards.tolist()))
        truncated = core.truncated
        terminated = core.done and not truncated
        terminations = dict.fromkeys(self.agents, terminated)
        truncations = dict.fromkeys(self.agents, truncated)
        if core.done:
            self.agents = []
        return obs, rewards, terminations, truncations, infos

    def _observations(self) -> dict[str, dict[str, np.ndarray]]:
        """Every agent's observation: views of this step's arrays (:meth:`ExplorationCore.observation`)."""
        core = self.core
        rows = zip(self.possible_agents, core.crop, core.pose, core.neighbours, core.inbox)
        if core.config.action != "goal":
            return {a: {"map": m, "pose": p, "neighbours": n, "inbox": i} for a, m, p, n, i in rows}
        return {a: {"map": m, "pose": p, "neighbours": n, "inbox": i, "choices": c}
                for (a, m, p, n, i), c in zip(rows, core.choices)}

    def _infos(self) -> dict[str, dict[str, Any]]:
        """The run's tick, explored fraction and stop reason, and (goal mode) each agent's action mask."""
        core = self.core
        shared = core.info()
        tick, explored, reason = shared["tick"], shared["explored"], shared["stop_reason"]
        if core.config.action != "goal":
            return {a: {"tick": tick, "explored": explored, "stop_reason": reason} for a in self.possible_agents}
        return {a: {"tick": tick, "explored": explored, "stop_reason": reason, "action_mask": mask}
                for a, mask in zip(self.possible_agents, core.masks)}

    def render(self) -> np.ndarray | None:
        if self.render_mode != "rgb_array" or self.core.sim is None:
            return None
        return render_rgb(self.core, self.render_px)

    def close(self) -> None:
        self.core.close()


def parallel_env(spec: Any = None, **kwargs: Any) -> SwarmParallelEnv:
    """PettingZoo's constructor convention: ``swarm.env.parallel_env(robots=8, size=50)``."""
    return SwarmParallelEnv(spec, **kwargs)
