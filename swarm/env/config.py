"""The options of the learning environments (:mod:`swarm.env`), validated once with one-line errors.

The run itself is an ordinary run spec (every section an option: map kind and size, robot count, radio
model, comm, lidar, motion, stop, ...), given as a spec, a mapping, TOML or keyword overrides exactly as
:func:`swarm.run` takes them. :class:`EnvConfig` holds what is the environment's own: who learns, what
an action and an observation are, and the reward. docs/python-api.md section "Learning" is the guide.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Mapping

from swarm.base.errors import InvalidInput

from swarm.api import check_bool, check_choice, check_float, check_int
from swarm.sim.spec import RunSpec
from swarm.sim.spec_input import resolve

ENV_DEFAULTS: dict[str, Any] = {"map": {"kind": "building", "size": 30}, "robots": {"count": 4},
                                "stop": {"max_ticks": 3000, "explored": 0.95}}
"""The run when no spec is given: 4 robots on a 30 x 30 building, to 95 % explored or 5 simulated minutes
(short episodes; any of it can be overridden)."""
ACTIONS = ("goal", "velocity")
SECTORS = 8
"""Goal choices: the nearest frontier cell in each 45-degree sector around the robot (east first, CCW)."""


@dataclass(frozen=True)
class Reward:
    """Per learning robot and step: ``own`` x m^2 its own lidar revealed to it (cells its map did not
    hold; maps merged from teammates do not count) + ``team`` x m^2 of the map's free area the whole team
    explored (the shared team reward, the same for every robot) - ``time_penalty`` per tick -
    ``collision_penalty`` per contact the robot began (walls or robots)."""

    own: float = 1.0
    team: float = 0.0
    time_penalty: float = 0.0
    collision_penalty: float = 0.0

    def __post_init__(self) -> None:
        for name in ("own", "team", "time_penalty", "collision_penalty"):
            check_float(f"reward.{name}", getattr(self, name), -1e6, 1e6)


@dataclass(frozen=True)
class EnvConfig:
    """What the environment adds to a run spec.

    - ``learners``: robot ids the policy drives (None: every robot, the PettingZoo default); every other
      robot runs the spec's ``algorithm`` (any registered explorer) as in :func:`swarm.run`.
    - ``action``: ``"goal"`` (discrete: 0 keeps the current goal, 1..8 drive to the nearest frontier
      cell of a 45-degree sector, :data:`SECTORS`) or ``"velocity"`` (continuous ``[-1, 1]^2``: forward
      speed and turn rate as fractions of ``motion.max_speed`` / ``motion.max_turn_rate``).
    - ``delegate``: goal mode only, one more discrete action: this step the robot's own explorer (the
      spec's ``algorithm``) decides, as a scripted teammate would.
    - ``ticks_per_step``: ticks (0.1 s each) one ``step()`` simulates; a goal is set at the first, a
      velocity held for all.
    - ``crop_cells``: side of the egocentric knowledge-map crop, in 0.5 m cells (even; the robot's cell
      sits at ``[crop_cells // 2, crop_cells // 2]``).
    - ``observe_all``: neighbours' positions and link margins for every robot, also those out of radio
      reach (privileged information, e.g. for a centralised critic); by default only linked robots.
    - ``margin_db``: link margins are clipped to +-this and scaled to [-1, 1].
    """

    learners: tuple[int, ...] | None = None
    action: str = "goal"
    delegate: bool = False
    ticks_per_step: int = 1
    crop_cells: int = 32
    observe_all: bool = False
    margin_db: float = 60.0
    reward: Reward = field(default_factory=Reward)

    def __post_init__(self) -> None:
        if self.learners is not None:
            if isinstance(self.learners, (str, bytes)) or not hasattr(self.learners, "__iter__"):
                raise InvalidInput("learners", self.learners, "robot ids, e.g. [0], or None for every robot")
            ids = tuple(self.learners)
            for i in ids:
                check_int("learners", i, 0, 999)
            if not ids or len(set(ids)) != len(ids):
                raise InvalidInput("learners", list(ids), "distinct robot ids, at least one")
            object.__setattr__(self, "learners", tuple(sorted(ids)))
        check_choice("action", self.action, ACTIONS)
        check_bool("delegate", self.delegate)
        if self.delegate and self.action != "goal":
            raise InvalidInput("delegate", True, "only with action = 'goal' (a discrete action)")
        check_int("ticks_per_step", self.ticks_per_step, 1, 10_000)
        check_int("crop_cells", self.crop_cells, 4, 512)
        if self.crop_cells % 2:
            raise InvalidInput("crop_cells", self.crop_cells, "an even number of cells from 4 to 512")
        check_bool("observe_all", self.observe_all)
        check_float("margin_db", self.margin_db, 0.0, 1000.0, lo_open=True)
        if isinstance(self.reward, Mapping):
            object.__setattr__(self, "reward", _reward(self.reward))
        elif not isinstance(self.reward, Reward):
            raise InvalidInput("reward", self.reward, "a table of own, team, time_penalty, collision_penalty")

    def learner_ids(self, robots: int) -> tuple[int, ...]:
        """The learning robots of a run of ``robots`` robots (an id beyond the team is an error)."""
        if self.learners is None:
            return tuple(range(robots))
        for i in self.learners:
            if i >= robots:
                raise InvalidInput("learners", list(self.learners), f"robot ids below robots.count ({robots})")
        return self.learners

    @property
    def n_actions(self) -> int:
        """Goal mode: keep, one per sector, and delegate if on."""
        return 1 + SECTORS + int(self.delegate)


def _reward(table: Mapping[str, Any]) -> Reward:
    known = ("own", "team", "time_penalty", "collision_penalty")
    for key in table:
        if key not in known:
            raise InvalidInput(f"reward.{key}", table[key], ", ".join(known))
    return Reward(**dict(table))


def env_spec(spec: Any = None, overrides: Mapping[str, Any] | None = None) -> RunSpec:
    """The run spec of an environment: ``spec`` and keyword ``overrides`` as :func:`swarm.run` reads them,
    on top of :data:`ENV_DEFAULTS` when no spec is given. The env drives agents in this process, so the
    transport must be ``inprocess``."""
    resolved = resolve(ENV_DEFAULTS if spec is None else spec, overrides)
    if resolved.transport != "inprocess":
        raise InvalidInput("transport", resolved.transport, "'inprocess' (the environment steps the agents itself)")
    return resolved




def check_render_mode(render_mode: Any, modes: list[str]) -> None:
    """``render_mode`` is None or one of ``modes``; anything else (an array too) is one line naming it."""
    if render_mode is not None and not (isinstance(render_mode, str) and render_mode in modes):
        raise InvalidInput("render_mode", render_mode, "None or " + " | ".join(repr(m) for m in modes))


def episode_seed(seed: int | None, rng: "np.random.Generator | None", spec_seed: int) -> tuple[int, "np.random.Generator"]:
    """``(run seed, generator)`` for ``reset(seed=...)``: a given seed is the run's master seed and restarts
    the generator from it; without one, the first episode runs the spec's own seed and later ones draw
    their seed from the generator, so a sequence of resets is deterministic too."""
    import numpy as np

    if seed is not None:
        check_int("seed", seed if not isinstance(seed, np.integer) else int(seed), 0, 2**63 - 1)
        return int(seed), np.random.default_rng(int(seed))
    if rng is None:
        return spec_seed, np.random.default_rng(spec_seed)
    return int(rng.integers(0, 2**63 - 1)), rng


__all__ = ["ACTIONS", "ENV_DEFAULTS", "EnvConfig", "Reward", "SECTORS", "check_render_mode", "env_spec", "episode_seed"]
