"""One xBOA exploration decision: build the fitness for the robot's belief, run the optimiser, return the plan.

This is the whole "brain" of the xBOA paper's exploration loop (section 4.2, Fig. 2) and what a runtime plugin
calls once per decision: ``decide(belief, cell, heading, battery, params, rng)``. A new optimiser is made
for every decision (docs/boa.md decision 8: c restarts from its initial value each time).

If the best candidate found has no predicted gain (fitness 0), the optimiser is run again with fresh
random candidates, up to ``retries`` times (the paper does not say what its robot does then; a robot with
battery left would not stop while unknown space is in reach). If every attempt fails the decision returns
no plan, and the caller ends or pauses the mission.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Mapping

import numpy as np

from swarm.api import InvalidInput, check_choice, check_int, from_mapping

from .beams import Lidar
from .engine import minimize
from .fitness import Belief, ExplorationProblem, Plan
from .params import BOAParams
from .presets import preset_for
from .variants import get_variant


@dataclass(frozen=True)
class DecisionParams:
    """How a robot decides. ``preset="table2"`` starts from the paper's Table-2 values for the variant and
    population size (code switch convention); ``"defaults"`` from :class:`BOAParams` defaults. ``boa``
    overrides single fields either way."""

    variant: str = "xBOA"
    pop_size: int = 20
    max_gen: int = 30
    early_stop: int = 10
    n_goals: int = 1                   # 1 = short-term strategy; K > 1 = long-term (K goals in order)
    preset: str = "table2"
    boa: Mapping[str, Any] = field(default_factory=dict)
    fitness_mode: str = "auto"
    retries: int = 3
    overlap_penalty: bool = False      # multi-robot: others' announced plans count as already observed
    search: str = "boa"                # "boa" | "exhaustive" (short-term oracle: argmax of the gain table)

    def __post_init__(self) -> None:
        object.__setattr__(self, "variant", get_variant(self.variant).name)
        check_int("pop_size", self.pop_size, 1, 100_000)
        check_int("max_gen", self.max_gen, 0, 100_000)
        check_int("early_stop", self.early_stop, 1, 100_000)
        check_int("n_goals", self.n_goals, 1, 100)
        check_choice("preset", self.preset, ("table2", "defaults"))
        check_choice("fitness_mode", self.fitness_mode, ("auto", "table", "lazy"))
        check_int("retries", self.retries, 0, 100)
        check_choice("search", self.search, ("boa", "exhaustive"))
        if self.search == "exhaustive" and self.n_goals != 1:
            raise InvalidInput("search", self.search, "'boa' for long-term plans (n_goals > 1)")
        if not isinstance(self.overlap_penalty, bool):
            raise InvalidInput("overlap_penalty", self.overlap_penalty, "true or false")
        if not isinstance(self.boa, Mapping):
            raise InvalidInput("boa", self.boa, "a table of BOAParams fields")
        self.boa_params()                 # validate the overrides now

    def boa_params(self) -> BOAParams:
        base: dict[str, Any] = {}
        if self.preset == "table2":
            base.update(preset_for(self.variant, self.pop_size).params)
        base.update(self.boa)
        return from_mapping(BOAParams, base, prefix="boa.")


@dataclass(frozen=True)
class Decision:
    plan: Plan | None            # None: no candidate with a positive predicted gain was found
    fitness: float
    nfev: int                    # fitness evaluations (rows) over all attempts
    n_distinct: int              # distinct goal tuples among them
    attempts: int
    ngen: int


def decide(belief: Belief, cell: tuple[int, int], heading: int, battery: int | None, params: DecisionParams,
           rng: np.random.Generator, *, lidar: Lidar = Lidar(), claimed: np.ndarray | None = None) -> Decision:
    """Choose the next goal(s) for a robot at ``cell`` (row, col) with ``heading`` (0..7, 2 = north) and
    ``battery`` steps (moves + 45 degree rotations) left, None for unlimited. ``claimed``: cells others'
    announced plans will observe (``fitness.predicted_observed``), counted as known."""
    problem = ExplorationProblem(belief, cell, heading, battery, n_goals=params.n_goals, lidar=lidar,
                                 mode=params.fitness_mode, claimed=claimed)
    if params.search == "exhaustive":
        gains = problem.gain_table()
        r, c = np.unravel_index(int(np.argmax(gains)), gains.shape)
        x = np.array([c, r], float)
        f = float(problem(x[None, :])[0])
        plan = problem.plan(x) if f < 0 else None
        return Decision(plan, f, gains.size, gains.size, 1, 0)
    best, attempts, ngen = minimize_with_restarts(problem, problem.bounds, params, rng)
    plan = problem.plan(best.x) if best.f < 0 else None
    return Decision(plan, best.f, problem.nfev, problem.n_distinct, attempts, ngen)


def minimize_with_restarts(fun: Any, bounds: Any, params: DecisionParams,
                           rng: np.random.Generator) -> tuple[Any, int, int]:
    """The optimiser run up to ``params.retries + 1`` times, stopping at the first run that finds a feasible
    goal (negative fitness): the best result, the runs made and the generations used in all of them."""
    boa = params.boa_params()
    best = None
    attempts = ngen = 0
    for attempts in range(1, params.retries + 2):
        res = minimize(fun, bounds, rng=rng, variant=params.variant, pop_size=params.pop_size,
                       max_gen=params.max_gen, early_stop=params.early_stop, params=boa)
        ngen += res.ngen
        if best is None or res.f < best.f:
            best = res
        if res.f < 0:
            break
    assert best is not None
    return best, attempts, ngen
