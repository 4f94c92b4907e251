"""IBOA-Levy continuous path planning around circular obstacles (IBOA (Lévy) section 2.3, Dash et al. 2025).

An individual is K intermediate waypoints (x1, y1, ..., xK, yK) inside the workspace box; the path is the
polyline start -> waypoints -> goal. Fitness, Eqs. 11-14: ``PL = D * (1 + w * P)`` with D the polyline
length (Eq. 11) and P the obstacle penalty summed over obstacles of the mean over sampled path points of
the penetration depth, O_b = |z - c_o| / R_o - 1 (Eq. 12; O_b < 0 inside obstacle o), w = 10.

Deliberate departure (docs/boa.md section 3.7): Eq. 13 as printed, ``P = P + mean(min(O_b, 0))``,
accumulates *negative* values, so a path through an obstacle would score better than the same path
outside. We use ``P = P + mean(max(-O_b, 0))`` (penetration counted positive). Eq. 10's typo (Y_st - X_go)
does not matter (F_D is not used by the fitness). Points are sampled uniformly along each segment
(``samples_per_segment`` per segment, both ends included); the paper's "any point" is not specified.

The optimiser is IBOA-Levy (Levy local moves, corrected nonlinear inertia weight; ``variants.py``) with
the paper's switch convention. The IBOA (Lévy) paper gives no population size, iteration count, a, c0 or beta; our
defaults are BOA's constants (a = 0.1, c0 = 0.01, p = 0.8) with 40 butterflies and 200 generations.
Note the origin bias of Eq. 9 (``W * Z`` shrinks every coordinate towards 0, section 1 item 5): the
planner works in coordinates relative to the workspace centre so that the pull goes towards the middle of
the box rather than its corner - a choice of frame the paper does not fix.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Mapping, Sequence

import numpy as np

from swarm.api import InvalidInput, check_float, check_int, from_mapping

from .engine import minimize
from .params import BOAParams


@dataclass(frozen=True)
class LevyPlannerParams:
    variant: str = "IBOA-Levy"
    n_waypoints: int = 3
    pop_size: int = 40
    max_gen: int = 200
    early_stop: int = 60
    penalty_weight: float = 10.0            # w of Eq. 14
    samples_per_segment: int = 25
    boa: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        from .variants import get_variant

        object.__setattr__(self, "variant", get_variant(self.variant).name)
        check_int("n_waypoints", self.n_waypoints, 1, 100)
        check_int("pop_size", self.pop_size, 2, 100_000)
        check_int("max_gen", self.max_gen, 0, 100_000)
        check_int("early_stop", self.early_stop, 1, 100_000)
        check_float("penalty_weight", self.penalty_weight, 0.0)
        check_int("samples_per_segment", self.samples_per_segment, 2, 10_000)
        from_mapping(BOAParams, dict(self.boa), prefix="boa.")


@dataclass(frozen=True)
class ContinuousPath:
    points: np.ndarray          # (K + 2, 2) start, waypoints, goal (x, y)
    length: float
    penalty: float              # P of the returned path (0 when it samples no penetration)
    clearance: float            # exact min over segments and obstacles of distance - radius (>= 0: collision-free)
    nfev: int


def _obstacles(obstacles: Any) -> np.ndarray:
    obs = np.asarray(obstacles, dtype=float).reshape(-1, 3)
    if not np.isfinite(obs).all() or (obs[:, 2] <= 0).any():
        raise InvalidInput("obstacles", obstacles, "(x, y, radius) rows with finite values and radius > 0")
    return obs


def polyline_lengths(P: np.ndarray) -> np.ndarray:
    """Eq. 11 for a batch of polylines (m, n, 2)."""
    return np.hypot(*np.moveaxis(np.diff(P, axis=1), -1, 0)).sum(axis=1)


def penalty(P: np.ndarray, obstacles: np.ndarray, samples: int) -> np.ndarray:
    """Eqs. 12-13 with the sign fixed: sum over obstacles of the mean penetration ``max(-O_b, 0)`` over the
    path points of each polyline (m, n, 2). The points are ``samples`` per segment plus, per segment and
    obstacle, the segment point closest to the obstacle's centre - so a segment cannot slip a penetration
    between two samples (our addition; the paper does not say how points are chosen)."""
    m, n, _ = P.shape
    s = np.linspace(0.0, 1.0, samples)
    a, b = P[:, :-1, None, :], P[:, 1:, None, :]
    pts = (a + (b - a) * s[None, None, :, None]).reshape(m, -1, 2)             # (m, S, 2)
    d = np.hypot(pts[:, :, None, 0] - obstacles[None, None, :, 0], pts[:, :, None, 1] - obstacles[None, None, :, 1])
    # closest point of every segment to every centre: (m, n-1, k)
    A, B = P[:, :-1, None, :], P[:, 1:, None, :]
    AB = B - A
    C = obstacles[None, None, :, :2]
    t = np.clip(((C - A) * AB).sum(-1) / np.maximum((AB * AB).sum(-1), 1e-300), 0.0, 1.0)
    dc = np.hypot(*np.moveaxis(A + t[..., None] * AB - C, -1, 0))
    d = np.concatenate([d, dc], axis=1)                                          # (m, S + n - 1, k)
    ob = d / obstacles[None, None, :, 2] - 1.0
    return np.maximum(-ob, 0.0).mean(axis=1).sum(axis=1)


def penalty_as_printed(P: np.ndarray, obstacles: np.ndarray, samples: int) -> np.ndarray:
    """Eq. 13 exactly as printed (``mean(min(O_b, 0))``): negative inside obstacles. Documentation only."""
    return -penalty(P, obstacles, samples)


def clearance(points: np.ndarray, obstacles: np.ndarray) -> float:
    """Exact minimum over the polyline's segments and the obstacles of (distance to centre - radius)."""
    a, b = points[:-1], points[1:]
    ab = b - a
    best = np.inf
    for (x, y, r) in obstacles:
        c = np.array([x, y])
        t = np.clip(((c - a) * ab).sum(1) / np.maximum((ab * ab).sum(1), 1e-300), 0.0, 1.0)
        d = np.hypot(*(a + t[:, None] * ab - c).T)
        best = min(best, float(d.min() - r))
    return best


def plan_levy(obstacles: Any, start: Sequence[float], goal: Sequence[float], box: Sequence[Sequence[float]],
              rng: np.random.Generator, params: LevyPlannerParams = LevyPlannerParams()) -> ContinuousPath:
    """Plan a polyline from ``start`` to ``goal`` (x, y) inside ``box`` = ((xmin, xmax), (ymin, ymax))."""
    obs = _obstacles(obstacles)
    (x0, x1), (y0, y1) = box
    if not (x0 < x1 and y0 < y1):
        raise InvalidInput("box", box, "((xmin, xmax), (ymin, ymax)) with min < max")
    centre = np.array([(x0 + x1) / 2.0, (y0 + y1) / 2.0])
    s = np.asarray(start, float) - centre
    g = np.asarray(goal, float) - centre
    obs_c = obs.copy()
    obs_c[:, :2] -= centre
    K = params.n_waypoints
    w = params.penalty_weight

    def paths(X: np.ndarray) -> np.ndarray:
        m = len(X)
        return np.concatenate([np.broadcast_to(s, (m, 1, 2)), X.reshape(m, K, 2), np.broadcast_to(g, (m, 1, 2))], axis=1)

    def fitness(X: np.ndarray) -> np.ndarray:
        P = paths(X)
        return polyline_lengths(P) * (1.0 + w * penalty(P, obs_c, params.samples_per_segment))

    bounds = [(x0 - centre[0], x1 - centre[0]), (y0 - centre[1], y1 - centre[1])] * K
    boa = from_mapping(BOAParams, dict(params.boa), prefix="boa.")
    res = minimize(fitness, bounds, rng=rng, variant=params.variant, pop_size=params.pop_size,
                   max_gen=params.max_gen, early_stop=params.early_stop, params=boa)
    P = paths(res.x[None, :])
    pts = P[0] + centre
    return ContinuousPath(pts, float(polyline_lengths(P)[0]), float(penalty(P, obs_c, params.samples_per_segment)[0]),
                          clearance(pts, obs), res.nfev)
