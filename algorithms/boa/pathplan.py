"""IBOA grid path planning (the IBOA (Kent) paper, section 4, Zhai et al. 2023): one free cell per grid row between start
and goal, interpolated into a connected 8-connected path, path length as fitness, IBOA-Kent with GA
mutation, then the two path-simplification strategies.

Encoding (section 4.1): an individual has one gene per grid line strictly between the start's and the
goal's line - the column of the waypoint in that row (continuous, rounded, then moved to the nearest free
cell of its row, ties to the left). Lines are rows when the start and goal are further apart vertically
than horizontally, columns otherwise (the paper's maps have start and goal in opposite corners, so rows).

Interpolation (the paper's is unspecified beyond "until all adjacent grids in the path are continuous"):
consecutive waypoints are in adjacent lines; they are joined by the shortest 8-connected path (no corner
cutting). When the two-row band between them holds an octile-optimal connection (one diagonal step plus
straight steps, checked in O(1) from free-run tables) that is it; otherwise an A* leg is computed and
memoised (a plan's cost grows with the legs it needs around walls; figures in
docs/performance-history.md, "Figures moved out of module docstrings"). Deliberate departure: the paper
discards individuals that cannot be interpolated inside the band; our legs may leave the band, so the encoding can represent every path (its optimum is the optimal grid
path: the last visits of each row form a valid waypoint sequence) and maps that need detours (buildings)
are still solved. Disconnected legs get a large finite penalty (the engine needs finite fitness).

Mutation ("the mutation process of GA ... to avoid the detour path", operator and rate not given): by
default one gene is set to the mean of its two neighbours (a waypoint moved between the waypoints of the
rows above and below, which removes a detour), with probability 0.5 per individual and generation; the
GA random-reset mutation is the alternative (``mutation_kind="reset"``). Either way the mutant is
evaluated and accepted greedily like any other trial, so x and fitness stay consistent. The smoothing
mutation gave the shorter grid paths when both were measured (docs/performance-history.md, "Figures
moved out of module docstrings").

Simplification (section 4.2), applied to the best path's cell centres:

* Strategy 1 (rectangle rule): a point between P(i) and P(j) is removable when the rectangle spanned by
  the two cells - widened to 3 cells across when they share a row or column (case 2, the 3 x 3 frame) - is
  entirely free. Cases 1-2 are the 3 x 2 / 3 x 3 frames of consecutive points; case 3 (chains of removable
  points) is read as extending j as far as the rectangle stays free.
* Strategy 2 (partially blocked n x 2 rectangles): for P(i) and P(j) in adjacent rows (or columns), a point
  between them is removable when the free runs from each end towards the other reach n_p = ceil(n_in / 2)
  cells, n_in = (|x_j - x_i| - 1) / 2 as printed. Deliberate addition: we also require the straight segment
  to touch only free cells (``shortest.segment_free``): the printed run condition alone does not guarantee a
  collision-free shortcut, and chains of overlapping shortcuts (5->6->7->8 to 5->8) are only accepted when
  the long segment itself is free.
* Optional ``"los"`` pass (ours): plain line-of-sight string pulling on top, to show how far the paper's
  strategies are from the best shortcutting of the same path.

Every removal replaces a polyline by its chord, so simplification never lengthens a path.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Mapping

import numpy as np

from swarm.api import InvalidInput, check_choice, check_float, check_int, from_mapping
from swarm.api.grid import plan as grid_plan, steps_length

from .engine import minimize
from .params import BOAParams
from .shortest import SQRT2, _segment_free, astar, path_length


@dataclass(frozen=True)
class IBOAPlannerParams:
    """The IBOA (Kent) paper uses population 200 (20 x 20 map) or 4000 (40 x 40) and 50 iterations; its flow chart says
    50 individuals. Our default (60 x 50) keeps a 50 x 50 map under a second; raise it for quality."""

    variant: str = "IBOA-Kent"
    pop_size: int = 60
    max_gen: int = 50
    early_stop: int = 25
    mutation_rate: float = 0.5
    mutation_kind: str = "smooth"             # "smooth" (gene -> mean of its neighbours: removes detours) | "reset"
    simplify: str = "paper"                   # "none" | "paper" (strategies 1 and 2) | "los" (paper + string pulling)
    boa: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        from .variants import get_variant

        object.__setattr__(self, "variant", get_variant(self.variant).name)
        check_int("pop_size", self.pop_size, 2, 100_000)
        check_int("max_gen", self.max_gen, 0, 100_000)
        check_int("early_stop", self.early_stop, 1, 100_000)
        check_float("mutation_rate", self.mutation_rate, 0.0, 1.0)
        check_choice("mutation_kind", self.mutation_kind, ("smooth", "reset"))
        check_choice("simplify", self.simplify, ("none", "paper", "los"))
        if not isinstance(self.boa, Mapping):
            raise InvalidInput("boa", self.boa, "a table of BOAParams fields")
        self.boa_params()

    def boa_params(self) -> BOAParams:
        return from_mapping(BOAParams, {"mutation_rate": self.mutation_rate, "mutation_kind": self.mutation_kind,
                                        **self.boa}, prefix="boa.")


@dataclass(frozen=True)
class GridPath:
    """A planned path: ``cells`` is the 8-connected cell path (start to goal), ``waypoints`` the simplified
    polyline through cell centres (equal to ``cells`` without simplification)."""

    cells: tuple[tuple[int, int], ...]
    waypoints: tuple[tuple[int, int], ...]
    grid_length: float          # octile length of ``cells``
    length: float               # Euclidean length of ``waypoints``
    nfev: int = 0
    history: tuple[float, ...] = ()


# ---------------------------------------------------------------- band legs
def _runs(free: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For each cell of each row: first and last column of its free run (-1 on blocked cells)."""
    H, W = free.shape
    left = np.full((H, W), -1, np.int64)
    right = np.full((H, W), -1, np.int64)
    for r in range(H):
        start = -1
        for c in range(W):
            if free[r, c]:
                start = c if start < 0 else start
                left[r, c] = start
            else:
                start = -1
        end = -1
        for c in range(W - 1, -1, -1):
            if free[r, c]:
                end = c if end < 0 else end
                right[r, c] = end
            else:
                end = -1
    return left, right


def _nearest_free(free: np.ndarray) -> np.ndarray:
    """nearest[r, c]: the free column of row r nearest to c (ties to the left); -1 for rows without one."""
    H, W = free.shape
    out = np.full((H, W), -1, np.int64)
    cols = np.arange(W)
    for r in range(H):
        fc = np.flatnonzero(free[r])
        if len(fc) == 0:
            continue
        idx = np.searchsorted(fc, cols)
        lo = fc[np.clip(idx - 1, 0, len(fc) - 1)]
        hi = fc[np.clip(idx, 0, len(fc) - 1)]
        out[r] = np.where(np.abs(cols - lo) <= np.abs(hi - cols), lo, hi)
    return out


class _Legs:
    """Shortest-leg lengths between waypoints of adjacent rows: O(1) band test, memoised A* otherwise."""

    def __init__(self, blocked: np.ndarray) -> None:
        self.blocked = np.ascontiguousarray(blocked, dtype=np.bool_)
        self.free = ~self.blocked
        self.left, self.right = _runs(self.free)
        self.memo: dict[tuple[int, int, int], float] = {}

    def band_ok(self, k: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Whether (k, a) -> (k+1, b) has an octile-optimal path inside rows k, k+1 (vectorised)."""
        up = b >= a
        # a <= b: row k free on [a, m+1], row k+1 free on [m, b] for some m in [a, b-1]
        E = self.right[k, a]
        S = self.left[k + 1, b]
        ok_up = np.maximum(a, S) <= np.minimum(b - 1, E - 1)
        # a > b: row k free on [m-1, a], row k+1 free on [b, m] for some m in [b+1, a]
        E2 = self.left[k, a]
        S2 = self.right[k + 1, b]
        ok_dn = np.maximum(b + 1, E2 + 1) <= np.minimum(a, S2)
        return np.where(a == b, True, np.where(up, ok_up, ok_dn))

    def lengths(self, k: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        d = np.abs(b - a)
        out = np.where(d == 0, 1.0, d - 1 + SQRT2)
        for i in np.flatnonzero(~self.band_ok(k, a, b)):
            key = (int(k[i]), int(a[i]), int(b[i]))
            v = self.memo.get(key)
            if v is None:
                path = grid_plan(self.free, (key[0], key[1]), (key[0] + 1, key[2]))
                v = self.memo[key] = math.inf if path is None else steps_length(path)
            out[i] = v
        return out

    def path(self, k: int, a: int, b: int) -> list[tuple[int, int]]:
        """Cells of the leg (k, a) -> (k+1, b), both ends included."""
        if a == b:
            return [(k, a), (k + 1, b)]
        if bool(self.band_ok(np.array([k]), np.array([a]), np.array([b]))[0]):
            if b > a:
                m = max(a, int(self.left[k + 1, b]))
                return [(k, c) for c in range(a, m + 1)] + [(k + 1, c) for c in range(m + 1, b + 1)]
            m = min(a, int(self.right[k + 1, b]))
            return [(k, c) for c in range(a, m - 1, -1)] + [(k + 1, c) for c in range(m - 1, b - 1, -1)]
        p = grid_plan(self.free, (k, a), (k + 1, b))
        if p is None:
            raise ValueError("disconnected leg")
        return [(int(r), int(c)) for r, c in p.tolist()]


# ---------------------------------------------------------------- simplification
def _rect_free(free_cum: np.ndarray, p: tuple[int, int], q: tuple[int, int], H: int, W: int) -> bool:
    r0, r1 = sorted((p[0], q[0]))
    c0, c1 = sorted((p[1], q[1]))
    if r0 == r1:
        r0, r1 = r0 - 1, r1 + 1
    elif c0 == c1:
        c0, c1 = c0 - 1, c1 + 1
    if r0 < 0 or c0 < 0 or r1 >= H or c1 >= W:
        return False
    blocked = free_cum[r1 + 1, c1 + 1] - free_cum[r0, c1 + 1] - free_cum[r1 + 1, c0] + free_cum[r0, c0]
    return blocked == 0


def simplify_rectangles(blocked: np.ndarray, points: list[tuple[int, int]]) -> list[tuple[int, int]]:
    """Strategy 1 (see module doc): drop points inside free rectangles spanned by an anchor and a later point."""
    blocked = np.asarray(blocked, bool)
    H, W = blocked.shape
    cum = np.zeros((H + 1, W + 1), np.int64)
    cum[1:, 1:] = blocked.astype(np.int64).cumsum(0).cumsum(1)
    out = [points[0]]
    i = 0
    n = len(points)
    while i < n - 1:
        j = i + 1
        while j + 1 < n and _rect_free(cum, points[i], points[j + 1], H, W):
            j += 1
        out.append(points[j])
        i = j
    return out


def simplify_runs(blocked: np.ndarray, points: list[tuple[int, int]]) -> list[tuple[int, int]]:
    """Strategy 2 (see module doc): partially blocked n x 2 rectangles, with an exact collision check."""
    blocked = np.ascontiguousarray(blocked, dtype=np.bool_)
    out = [points[0]]
    i = 0
    n = len(points)
    while i < n - 1:
        j = i + 1
        while j + 1 < n and _runs_ok(blocked, points[i], points[j + 1]):
            j += 1
        out.append(points[j])
        i = j
    return out


def _runs_ok(blocked: np.ndarray, p: tuple[int, int], q: tuple[int, int]) -> bool:
    dr, dc = q[0] - p[0], q[1] - p[1]
    if abs(dr) == 1 and abs(dc) >= 2:
        step, span = 1 if dc > 0 else -1, abs(dc)
        runs = (_run(blocked, p[0], p[1], 0, step), _run(blocked, q[0], q[1], 0, -step))
    elif abs(dc) == 1 and abs(dr) >= 2:
        step, span = 1 if dr > 0 else -1, abs(dr)
        runs = (_run(blocked, p[0], p[1], step, 0), _run(blocked, q[0], q[1], -step, 0))
    else:
        return False
    n_in = (span - 1) / 2.0
    n_p = math.ceil(0.5 * n_in)
    if min(runs) < n_p:
        return False
    return bool(_segment_free(blocked, p[0], p[1], q[0], q[1]))


def _run(blocked: np.ndarray, r: int, c: int, dr: int, dc: int) -> int:
    """Free cells from (r, c) (exclusive) in direction (dr, dc) before a blocked cell or the edge."""
    H, W = blocked.shape
    k = 0
    r, c = r + dr, c + dc
    while 0 <= r < H and 0 <= c < W and not blocked[r, c]:
        k += 1
        r, c = r + dr, c + dc
    return k


def simplify_los(blocked: np.ndarray, points: list[tuple[int, int]]) -> list[tuple[int, int]]:
    """Greedy line-of-sight string pulling: from each anchor jump to the farthest visible later point."""
    blocked = np.ascontiguousarray(blocked, dtype=np.bool_)
    out = [points[0]]
    i = 0
    n = len(points)
    while i < n - 1:
        j = n - 1
        while j > i + 1 and not _segment_free(blocked, points[i][0], points[i][1], points[j][0], points[j][1]):
            j -= 1
        out.append(points[j])
        i = j
    return out


# ---------------------------------------------------------------- the planner
def plan_iboa(blocked: np.ndarray, start: tuple[int, int], goal: tuple[int, int], rng: np.random.Generator,
              params: IBOAPlannerParams = IBOAPlannerParams()) -> GridPath | None:
    """Plan from ``start`` to ``goal`` ((row, col) cells) on a bool grid (True = blocked); None if the goal
    cannot be reached. Deterministic given ``rng``'s state."""
    blocked = np.ascontiguousarray(blocked, dtype=np.bool_)
    H, W = blocked.shape
    for name, p in (("start", start), ("goal", goal)):
        if not (0 <= p[0] < H and 0 <= p[1] < W) or blocked[p]:
            raise InvalidInput(name, p, f"a free (row, col) cell inside {H} x {W}")
    if not isinstance(rng, np.random.Generator):
        raise InvalidInput("rng", rng, "a numpy.random.Generator")
    transpose = abs(goal[1] - start[1]) > abs(goal[0] - start[0])
    grid = blocked.T.copy() if transpose else blocked
    s = (start[1], start[0]) if transpose else tuple(start)
    g = (goal[1], goal[0]) if transpose else tuple(goal)
    flip = g[0] < s[0]
    if flip:                                      # always plan upwards in the working frame
        grid = grid[::-1].copy()
        s, g = (grid.shape[0] - 1 - s[0], s[1]), (grid.shape[0] - 1 - g[0], g[1])
    cells, nfev, hist = _plan_rows(grid, s, g, rng, params)
    if cells is None:
        return None
    if flip:
        cells = [(grid.shape[0] - 1 - r, c) for r, c in cells]
    if transpose:
        cells = [(c, r) for r, c in cells]
    if params.simplify == "none":
        way = list(cells)
    else:
        way = simplify_runs(blocked, simplify_rectangles(blocked, cells))
        if params.simplify == "los":
            way = simplify_los(blocked, way)
    return GridPath(tuple(cells), tuple(way), path_length(cells), path_length(way), nfev, hist)


def _plan_rows(grid: np.ndarray, s: tuple[int, int], g: tuple[int, int], rng: np.random.Generator,
               params: IBOAPlannerParams) -> tuple[list[tuple[int, int]] | None, int, tuple[float, ...]]:
    H, W = grid.shape
    n_genes = g[0] - s[0] - 1
    if n_genes < 1:                               # start and goal in the same or adjacent rows: one leg
        p = astar(grid, s, g)
        return p, 0, ()
    legs = _Legs(grid)
    nearest = _nearest_free(legs.free)
    rows = np.arange(s[0] + 1, g[0])
    if (nearest[rows, 0] < 0).any():
        return None, 0, ()
    penalty = 4.0 * H * W
    ks = np.arange(s[0], g[0])                    # leg k joins row k and row k + 1

    def waypoints(X: np.ndarray) -> np.ndarray:
        col = np.clip(np.floor(X + 0.5), 0, W - 1).astype(np.int64)
        mid = nearest[rows[None, :], col]
        m = len(X)
        return np.concatenate([np.full((m, 1), s[1]), mid, np.full((m, 1), g[1])], axis=1)

    def fitness(X: np.ndarray) -> np.ndarray:
        wp = waypoints(X)
        m, n = wp.shape
        k = np.broadcast_to(ks, (m, n - 1)).ravel()
        lengths = legs.lengths(k, wp[:, :-1].ravel(), wp[:, 1:].ravel()).reshape(m, n - 1)
        total = lengths.sum(axis=1)
        return np.where(np.isfinite(total), total, penalty)

    res = minimize(fitness, [(0.0, float(W - 1))] * n_genes, rng=rng, variant=params.variant,
                   pop_size=params.pop_size, max_gen=params.max_gen, early_stop=params.early_stop,
                   params=params.boa_params())
    if res.f >= penalty:
        return None, res.nfev, tuple(res.history)
    wp = waypoints(res.x[None, :])[0]
    cells: list[tuple[int, int]] = [(int(s[0]), int(s[1]))]
    for i, k in enumerate(ks):
        leg = legs.path(int(k), int(wp[i]), int(wp[i + 1]))
        cells.extend(leg[1:])
    return cells, res.nfev, tuple(res.history)


@dataclass(frozen=True)
class PlanReport:
    """What ``swarm plan`` prints: the IBOA path beside the optimal 8-connected and any-angle lengths."""

    path: GridPath | None
    astar_length: float
    any_angle_length: float


def plan_report(blocked: np.ndarray, start: tuple[int, int], goal: tuple[int, int], rng: np.random.Generator,
                params: IBOAPlannerParams = IBOAPlannerParams()) -> PlanReport:
    """Plan with IBOA and compute both reference lengths (cells; multiply by the cell size for metres)."""
    from .shortest import any_angle_length, astar_length

    p = plan_iboa(blocked, start, goal, rng, params)
    return PlanReport(p, astar_length(blocked, start, goal), any_angle_length(blocked, start, goal))


def plan_path(blocked: np.ndarray, start: tuple[int, int], goal: tuple[int, int], rng: np.random.Generator,
              planner: str = "iboa", params: IBOAPlannerParams = IBOAPlannerParams()) -> list[tuple[int, int]] | None:
    """The navigation hook: the path to follow as (row, col) cells, ``planner = "astar" | "iboa"``.

    ``"iboa"`` returns the simplified waypoints (consecutive points joined by collision-free straight
    segments); ``"astar"`` the optimal 8-connected cell path.
    """
    check_choice("planner", planner, ("astar", "iboa"))
    if planner == "astar":
        return astar(blocked, start, goal)
    p = plan_iboa(blocked, start, goal, rng, params)
    return None if p is None else list(p.waypoints)
