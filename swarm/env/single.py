"""The Gymnasium environment: one learning robot among scripted teammates (``swarm/Explore-v0``)."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np


from swarm.api import check_int
from .config import EnvConfig, Reward, check_render_mode, env_spec
from .core import ExplorationCore
from .render import RENDER_PX, check_render_px, render_rgb
from .spaces import action_space, observation_space


class SwarmEnv(gym.Env):
    """Robot ``learner`` is driven by the agent; every other robot runs the spec's ``algorithm`` (any
    registered explorer), all in the real runtime. ``spec`` and ``overrides`` are a run spec as
    :func:`swarm.run` takes them (``robots=8, size=50, radio="los", algorithm="tnf"``, any section as a
    table); the other keywords are :class:`~swarm.env.config.EnvConfig`'s. ``reset(seed=s)`` runs the spec
    with master seed ``s``: the same seed and actions give the same episode bit for bit."""

    metadata = {"render_modes": ["rgb_array"], "render_fps": 10}

    def __init__(self, spec: Any = None, *, learner: int = 0, action: str = "goal", delegate: bool = False,
                 ticks_per_step: int = 1, crop_cells: int = 32, observe_all: bool = False, margin_db: float = 60.0,
                 reward: Reward | dict[str, float] | None = None, render_mode: str | None = None,
                 render_px: int = RENDER_PX, **overrides: Any) -> None:
        check_int("learner", learner, 0, 999)
        config = EnvConfig(learners=(learner,), action=action, delegate=delegate, ticks_per_step=ticks_per_step,
                           crop_cells=crop_cells, observe_all=observe_all, margin_db=margin_db,
                           reward=Reward() if reward is None else reward)
        check_render_mode(render_mode, self.metadata["render_modes"])
        self.render_px = check_render_px(render_px)
        self.core = ExplorationCore(env_spec(spec, overrides), config)
        self.learner = learner
        self.render_mode = render_mode
        self.observation_space = observation_space(self.core)
        self.action_space = action_space(self.core)

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> tuple[dict, dict]:
        if seed is not None:
            check_int("seed", int(seed) if isinstance(seed, np.integer) else seed, 0, 2**63 - 1)
            super().reset(seed=int(seed))
            run_seed = int(seed)
        elif self._np_random is None:  # the first episode without a seed: the spec's own
            run_seed = self.core.base.seed
            super().reset(seed=run_seed)
        else:
            run_seed = int(self.np_random.integers(0, 2**63 - 1))
        self.core.reset(run_seed)
        return self.core.observation(0), self._info()

    def step(self, action: Any) -> tuple[dict, float, bool, bool, dict]:
        core = self.core
        core.step({self.learner: action})
        return (core.observation(0), float(core.rewards[0]), core.done and not core.truncated, core.truncated,
                self._info())

    def _info(self) -> dict[str, Any]:
        info = self.core.info()
        if self.core.config.action == "goal":
            info["action_mask"] = self.core.action_mask(0)
        return info

    def render(self) -> np.ndarray | None:
        if self.render_mode != "rgb_array" or self.core.sim is None:
            return None
        return render_rgb(self.core, self.render_px)

    def close(self) -> None:
        self.core.close()
