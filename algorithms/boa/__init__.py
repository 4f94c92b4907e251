"""The Butterfly Optimization family and the xBOA exploration problem.

* Optimiser: one ask/tell engine (``engine.Optimizer``, ``engine.minimize``) for BOA, xBOA, mBOA, ABOA,
  SABOA, IBOA-Kent, IBOA-Levy (and xABOA) as small strategy pieces (``variants``, ``operators``, ``draws``,
  ``schedules``), every ambiguity a named option in ``params.BOAParams``, the paper's Table 2 in ``presets``.
* Exploration (xBOA paper): ``fitness`` (belief, batched exact fitness, per-decision gain table), ``tree``
  (minimum-energy paths), ``beams``/``gain`` (lidar fans and numba kernels), ``decision`` (one decision -
  what a runtime plugin calls), ``gridworld``/``scenario`` (the paper's 24 x 24 experiment).
* Path planning: ``pathplan`` (IBOA grid planner, IBOA (Kent)), ``pathplan_levy`` (IBOA-Levy continuous
  planner, IBOA (Lévy)), ``shortest`` (A*, any-angle optimum, collision tests).

Specification: docs/boa.md; papers (docs/papers.md): Bendahmane & Tlemsani 2022 (xBOA), Zhai et al. 2023 (IBOA-Kent),
Dash et al. 2025 (IBOA-Levy).
"""

from .beams import Lidar, heading_index
from .decision import Decision, DecisionParams, decide
from .engine import Optimizer, Result, minimize
from .fitness import Belief, ExplorationProblem, Plan, predicted_observed
from .params import BOAParams
from .pathplan import GridPath, IBOAPlannerParams, PlanReport, plan_iboa, plan_path, plan_report
from .pathplan_levy import ContinuousPath, LevyPlannerParams, plan_levy
from .presets import PRESETS, Preset, get_preset, preset_for
from .scenario import MissionResult, PaperSetup, run_mission
from .shortest import any_angle_length, astar, astar_length
from .variants import FAMILY, VARIANTS, Variant, get_variant

__all__ = [
    "BOAParams", "Belief", "ContinuousPath", "Decision", "DecisionParams", "ExplorationProblem", "FAMILY",
    "GridPath", "IBOAPlannerParams", "LevyPlannerParams", "Lidar", "MissionResult", "Optimizer", "PRESETS",
    "PaperSetup", "Plan", "PlanReport", "Preset", "Result", "VARIANTS", "Variant", "any_angle_length", "astar", "astar_length",
    "decide", "get_preset", "get_variant", "heading_index", "minimize", "plan_iboa", "plan_levy", "plan_path",
    "plan_report",
    "predicted_observed", "preset_for", "run_mission",
]
