"""The IBOA grid planner (IBOA (Kent), ``pathplan.plan_iboa``) as a navigation planner for the runtime.

Registered under the ``swarm.planners`` entry-point group as ``iboa``, so a run spec selects it with
``navigation = {planner = "iboa"}``. The navigator calls ``plan(space, start, goal, rng)`` with the robot's
configuration space (True = the robot's centre may be there) and its own planner stream; this returns
int[N, 2] cells, consecutive ones 8-adjacent and every one inside ``space``.

Choices, and why:

* **Window, not the whole map.** IBOA's cost grows with the number of grid lines between start and goal
  (one gene each) and with the A* legs it runs around walls on the whole grid (seconds on a large
  grid; docs/performance-history.md, "Figures moved out of module docstrings"). So the plan runs on the
  bounding box of start and goal grown by ``margin_cells`` on every side; detours outside that box are
  not representable. A box larger than ``max_window_cells``, or no path inside it, falls back to the
  runtime's A* (:func:`swarm.grid.plan`) on the whole space. The fallback is decided by sizes, never by
  the clock, so runs stay reproducible.
* **Smaller budget.** Population 30, 30 generations, early stop after 10 (IBOA (Kent): 200-4000 x 50):
  the runtime plans every time a goal changes, and the measured lengths are within a few percent of the
  paper-size budget after the navigator's shortcutting (``benchmarks/experiments/bench_xboa_runtime.py
  planner``).
* **Output shape.** IBOA's result is its simplified polyline (paper strategies 1 and 2), whose segments
  are collision-free by the planner's supercover test. The navigator wants cells, consecutive ones
  8-adjacent (``grid.simplify`` rejects longer steps), so each segment is expanded to the cells of its
  supercover walk. Every segment is re-checked with :func:`swarm.grid.segment_clear` (the runtime's own
  rule) before it is used; a failure falls back to A*. The navigator then shortcuts the route further by
  line of sight, which never lengthens it.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from swarm.api import CELL_M, InvalidInput, check_int, from_mapping, grid

from .pathplan import GridPath, IBOAPlannerParams, plan_iboa


RUNTIME_BUDGET = {"pop_size": 30, "max_gen": 30, "early_stop": 10}
"""The IBOA budget of a runtime plan (see the module docstring); the fields of ``iboa`` not given keep it."""


@dataclass(frozen=True)
class IBOAPlannerSettings:
    """How the runtime planner bounds IBOA's work (see the module docstring); the plug-in's ``Params``.
    ``iboa`` may be given as a table of :class:`IBOAPlannerParams` fields (``swarm plan --param
    iboa.pop_size=200``); fields it does not set keep :data:`RUNTIME_BUDGET` and the planner defaults."""

    margin_cells: int = 12
    max_window_cells: int = 120 * 120
    iboa: IBOAPlannerParams = field(default_factory=lambda: IBOAPlannerParams(**RUNTIME_BUDGET))

    def __post_init__(self) -> None:
        check_int("margin_cells", self.margin_cells, 0, 10_000)
        check_int("max_window_cells", self.max_window_cells, 1, 10**8)
        if isinstance(self.iboa, Mapping):
            object.__setattr__(self, "iboa", from_mapping(IBOAPlannerParams, {**RUNTIME_BUDGET, **self.iboa},
                                                          prefix="iboa."))
        elif not isinstance(self.iboa, IBOAPlannerParams):
            raise InvalidInput("iboa", self.iboa, "a table of IBOA planner parameters")


@dataclass
class PlanStats:
    """What this planner did, per outcome (for benchmarks and notes)."""

    iboa: int = 0
    fallback_size: int = 0
    fallback_failed: int = 0
    fallback_unsafe: int = 0


class IBOAPlanner:
    """``swarm.planners`` plug-in ``iboa``."""

    name = "iboa"
    Params = IBOAPlannerSettings

    def __init__(self, settings: IBOAPlannerSettings | None = None) -> None:
        self.settings = settings or IBOAPlannerSettings()
        self.stats = PlanStats()
        self.last_waypoints: list[tuple[int, int]] | None = None   # IBOA's polyline of the last plan (diagnostics)
        self.last_plan: GridPath | None = None
        self._last_note = ""

    def describe_last(self) -> str | None:
        """One line about the last plan (``swarm plan`` prints it)."""
        if self.last_plan is None:
            return f"{self.settings.iboa.variant}: {self._last_note}" if self._last_note else None
        p = self.last_plan
        return (f"{self.settings.iboa.variant}: {p.nfev} evaluations, {len(p.waypoints)} waypoints, grid path "
                f"{p.grid_length * CELL_M:.2f} m before simplification, {p.length * CELL_M:.2f} m after")

    def plan(self, space: np.ndarray, start: tuple[int, int], goal: tuple[int, int],
             rng: np.random.Generator) -> np.ndarray | None:
        space = np.asarray(space, dtype=bool)
        self.last_waypoints, self.last_plan, self._last_note = None, None, ""
        start = (int(start[0]), int(start[1]))
        goal = (int(goal[0]), int(goal[1]))
        if not (space[start] and space[goal]):
            return None
        s = self.settings
        H, W = space.shape
        r0, r1 = max(min(start[0], goal[0]) - s.margin_cells, 0), min(max(start[0], goal[0]) + s.margin_cells + 1, H)
        c0, c1 = max(min(start[1], goal[1]) - s.margin_cells, 0), min(max(start[1], goal[1]) + s.margin_cells + 1, W)
        if (r1 - r0) * (c1 - c0) > s.max_window_cells:
            self.stats.fallback_size += 1
            self._last_note = (f"window of {(r1 - r0) * (c1 - c0)} cells > max_window_cells = {s.max_window_cells}: "
                               "A* instead")
            return grid.plan(space, start, goal)
        window = ~space[r0:r1, c0:c1]
        found = plan_iboa(window, (start[0] - r0, start[1] - c0), (goal[0] - r0, goal[1] - c0), rng, s.iboa)
        if found is None:
            self.stats.fallback_failed += 1
            self._last_note = "no path in the window: A* instead"
            return grid.plan(space, start, goal)
        points = [(r + r0, c + c0) for r, c in found.waypoints]
        cells = expand(space, points)
        if cells is None:
            self.stats.fallback_unsafe += 1
            self._last_note = "a segment left the configuration space: A* instead"
            return grid.plan(space, start, goal)
        self.stats.iboa += 1
        self.last_waypoints, self.last_plan = points, found
        return cells


def expand(space: np.ndarray, points: list[tuple[int, int]]) -> np.ndarray | None:
    """The cells of each segment's supercover walk, in order (int[N, 2]); None if a segment leaves ``space``."""
    out: list[tuple[int, int]] = [points[0]]
    for a, b in zip(points[:-1], points[1:]):
        if not grid.segment_clear(space, a, b):
            return None
        out.extend(supercover_walk(a, b)[1:])
    cells = np.array(out, dtype=np.int64)
    if not space[cells[:, 0], cells[:, 1]].all():
        return None
    return cells


def supercover_walk(a: tuple[int, int], b: tuple[int, int]) -> list[tuple[int, int]]:
    """Cells a straight segment between two cell centres touches, in order from ``a`` to ``b``, consecutive
    cells sharing a side - except where the segment passes exactly through a corner: there the walk goes
    through one of the two side cells (the other is in the segment's supercover too, which
    ``grid.segment_clear`` has checked, so the diagonal step cuts no corner)."""
    (r, c), (r1, c1) = a, b
    dr, dc = r1 - r, c1 - c
    sr, sc = (1 if dr > 0 else -1), (1 if dc > 0 else -1)
    nr, nc = abs(dr), abs(dc)
    out = [(r, c)]
    ir = ic = 0                             # steps taken along rows / columns
    while ir < nr or ic < nc:
        # compare the crossing parameters of the next horizontal and vertical cell boundaries:
        # t_row = (2 ir + 1) / (2 nr), t_col = (2 ic + 1) / (2 nc); cross-multiplied to stay in integers
        lhs = (2 * ir + 1) * nc
        rhs = (2 * ic + 1) * nr
        if ic >= nc or (ir < nr and lhs < rhs):
            r += sr
            ir += 1
            out.append((r, c))
        elif ir >= nr or lhs > rhs:
            c += sc
            ic += 1
            out.append((r, c))
        else:                               # exactly through a corner: a side cell, then the diagonal one
            out.append((r + sr, c))
            r += sr
            c += sc
            ir += 1
            ic += 1
            out.append((r, c))
    return out


def path_length_cells(cells: np.ndarray) -> float:
    """Euclidean length of a cell polyline, in cells."""
    d = np.diff(np.asarray(cells, dtype=float), axis=0)
    return float(np.hypot(d[:, 0], d[:, 1]).sum()) if len(d) else 0.0


__all__ = ["IBOAPlanner", "IBOAPlannerSettings", "PlanStats", "expand", "supercover_walk"]

