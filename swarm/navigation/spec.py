"""The run spec's ``[navigation]`` section: how the runtime drives a robot to its algorithm's goal.

Light (no compiled kernels), so :mod:`swarm.sim.spec` can build it without loading the navigator.
"""

from __future__ import annotations

from dataclasses import dataclass

from swarm.base.params import check_choice, check_float, check_int


@dataclass(frozen=True)
class NavigationSpec:
    """How the runtime drives a robot to its algorithm's goal.

    ``unseen``: plan through unseen cells (``traversable``, optimistic) or not (``blocked``, the default,
    as MAES's pessimistic planner). ``margin_m``: clearance kept beyond the robot radius.
    ``stuck_ticks``: no progress for this long triggers a replan; after ``max_replans`` failed replans
    the goal is reported ``blocked`` to the algorithm. ``planner``: ``astar`` (optimal grid paths) or any
    planner registered under ``swarm.planners`` (``iboa``)."""

    unseen: str = "blocked"
    margin_m: float = 0.05
    stuck_ticks: int = 30
    max_replans: int = 3
    planner: str = "astar"

    def __post_init__(self) -> None:
        from swarm.plugins.planners import check_planner

        check_choice("navigation.unseen", self.unseen, ("blocked", "traversable"))
        check_planner(self.planner)
        check_float("navigation.margin_m", self.margin_m, 0.0, 1.0)
        check_int("navigation.stuck_ticks", self.stuck_ticks, 1, 10_000)
        check_int("navigation.max_replans", self.max_replans, 0, 100)
