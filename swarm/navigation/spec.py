"""The run spec's ``[navigation]`` section: how the runtime drives a robot to its algorithm's goal.

Light (no compiled kernels), so :mod:`swarm.sim.spec` can build it without loading the navigator.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from swarm.base.params import OMIT_DEFAULT, check_choice, check_float, check_int

AVOIDANCE = ("none", "orca", "hrvo", "hl", "social_force")
"""``navigation.avoidance`` values (:data:`swarm.navigation.avoidance.BEHAVIOURS` names navground's types)."""


@dataclass(frozen=True)
class NavigationSpec:
    """How the runtime drives a robot to its algorithm's goal.

    ``unseen``: plan through unseen cells (``traversable``, optimistic) or not (``blocked``, the default,
    as MAES's pessimistic planner). ``margin_m``: clearance kept beyond the robot radius.
    ``stuck_ticks``: no progress for this long triggers a replan; after ``max_replans`` failed replans
    the goal is reported ``blocked`` to the algorithm. ``planner``: ``astar`` (optimal grid paths) or any
    planner registered under ``swarm.planners`` (``iboa``). ``avoidance``: a local inter-robot collision
    avoidance behaviour on the navigator's commands (``orca``, ``hrvo``, ``hl``, ``social_force``, from
    navground: :mod:`swarm.navigation.avoidance`), considering the robots within ``avoidance_range_m``;
    ``none`` (the default) drives the plan as is."""

    unseen: str = "blocked"
    margin_m: float = 0.05
    stuck_ticks: int = 30
    max_replans: int = 3
    planner: str = "astar"
    avoidance: str = field(default="none", metadata={OMIT_DEFAULT: True})
    avoidance_range_m: float = field(default=3.0, metadata={OMIT_DEFAULT: True})

    def __post_init__(self) -> None:
        from swarm.plugins.planners import check_planner

        check_choice("navigation.avoidance", self.avoidance, AVOIDANCE)
        check_float("navigation.avoidance_range_m", self.avoidance_range_m, 0.5, 100.0)

        check_choice("navigation.unseen", self.unseen, ("blocked", "traversable"))
        check_planner(self.planner)
        check_float("navigation.margin_m", self.margin_m, 0.0, 1.0)
        check_int("navigation.stuck_ticks", self.stuck_ticks, 1, 10_000)
        check_int("navigation.max_replans", self.max_replans, 0, 100)
