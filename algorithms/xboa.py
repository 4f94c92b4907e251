"""xBOA exploration in the swarm runtime (Bendahmane & Tlemsani 2022, the xBOA paper in docs/papers.md).

What follows the paper. Each decision, the robot's own optimiser searches goal cells on the robot's own
knowledge map (section 4.2): a candidate is a flat vector of K goal cells (K = 1 is the short-term
strategy, K > 1 the long-term one, section 4.3); its fitness is minus the number of currently unknown
cells predicted to be observed along the planned path (Eq. 9 read as docs/boa.md section 4.2
recommends: an optimistic raycast at every pose of the path, unknown cells do not stop a beam, known
walls do), or 0 when the plan is infeasible: a goal not reachable, or the energy of the chained legs
(moves + 45 degree rotations) over the battery. Population, generations, early stop and the Table-2
presets are the paper's (section 5.2; ``algorithms.boa.DecisionParams``); every variant of the family can
be selected (``variant``: xboa, boa, mboa, aboa, saboa, iboa-kent, iboa-levy). Whole populations are
evaluated at once and short-term fitness is a per-decision gain table, exact (docs/boa.md section 11,
``algorithms.boa.fitness``). Multi-robot (section 5.4.4): every robot has its own optimiser and RNG
stream; maps travel through the runtime's map-sharing service, so the paper's central shared map is the
special case of ``radio.model = "global"`` with ``comm.share_every = 1``.

Departures, all deliberate:

1. **Tiles.** The decision runs on a coarsened belief: ``tile_cells`` x ``tile_cells`` knowledge cells
   (2 x 2 = 1 m tiles by default, the paper's cell size) make one tile. A tile is *occupied* (stops beams)
   if any of its cells is SOLID, *unknown* (counts as gain) if all of its cells are UNSEEN, and *passable*
   if one of its cells is in the robot's configuration space (radius + ``grid.DEFAULT_MARGIN_M``) and
   reachable from the robot through known-free space. Why: 1 m is the paper's cell, a decision over a
   whole 150 m map costs several times less at 1 m than at 0.5 m (figures: docs/performance-history.md,
   "Figures moved out of module docstrings"), and passability from the configuration space means every
   goal tile holds a cell the navigator can drive to (``tile_cells = 1`` decides on the knowledge cells
   themselves). The chosen tile becomes a metre goal (its reachable cell nearest the tile centre) and the runtime's navigator drives there; the
   paper's 8-direction steps and rotations remain the *energy model inside the fitness*, not how the
   robot moves. Unseen tiles in the inside corner of a wall junction count as walls (see ``coarsen``).
2. **Known-free paths.** The tree of minimum-energy paths runs through passable tiles only, i.e. over
   known-free space, because the runtime's navigator plans pessimistically by default
   (``navigation.unseen = "blocked"``); the paper plans through unknown space. The fitness scores the path
   the robot can actually follow.
3. **Sensor.** The predicted scan is the runtime's lidar: ``fov_deg`` (360 by default, the runtime's
   default; the paper's robot has 180) and the robot's lidar range (7 m by default; the paper's 4 m),
   1 degree resolution as in the paper.
4. **Search box.** The genes' bounds are the bounding box of the passable tiles, not the whole map
   (decision 10 of docs/boa.md). No feasible goal lies outside it, so the optimum is unchanged, but
   on a 150 m map a random population would otherwise be ~95 % infeasible. The belief is cropped to that
   box plus the sensor range (exact: nothing farther can be observed from a reachable pose).
5. **Horizon.** A decision may plan at most ``horizon_steps`` steps (12 by default; the battery left
   caps it too). The paper's only limit is the battery, and its fitness has no distance term, so with a
   large battery the robot crosses the map for the single best view, which on seeded 50 m buildings took
   far longer to reach 99 % than a 12-step horizon (docs/performance-history.md, "Figures moved out of
   module docstrings"; ``benchmarks/experiments/bench_xboa_runtime.py sweep``). ``horizon_steps = 0``
   restores the paper's battery-only constraint.
6. **Battery.** Energy is counted from the runtime's odometry: one step = a move of one tile (1 m by
   default) or a 45 degree turn, ``steps = distance_m / tile_m + turned_rad / (pi / 4)``. The fitness
   tree counts a diagonal move as one step although it is 1.41 tiles long, and the navigator's continuous
   path differs from the tree's, so the tree is given ``remaining / energy_margin`` steps (1.5 covers an
   all-diagonal path). When the battery is spent the robot stops where it is. ``battery_steps = None``
   (default) and ``RobotInfo.battery = None`` mean unlimited.
7. **Fallback.** When the optimiser finds no tile with predicted gain (after ``retries`` restarts), the
   robot heads for the nearest reachable unseen cell (``grid.nearest_reachable_unseen``, as frontier
   does): a tile counts as known once one of its cells is seen, so small unseen pockets are invisible to
   the tile belief, and a mission should not end while such pockets remain in reach.
8. **Re-deciding.** A robot decides when it has no goal, when its goal is reached, reported unreachable or
   blocked (the goal tile is then excluded for ``exclude_ticks``), when every tile its goal pose was
   predicted to observe has been seen (the target region is gone, e.g. through a teammate's map), or when
   a lower-id robot announces, for the same or a later tick, a plan that will observe at least half of
   that region (simultaneous decisions on the same map: the lower id keeps its target).
9. **Overlap penalty** (``overlap_penalty``, on by default; the paper's future work, docs/boa.md
   section 11.3): each decision is announced in an ``xboa.target`` message (goals and the tile poses of
   the planned path); a robot counts the cells others' announced paths will observe as already known.
   Fallback targets are announced too (as a single pose) and teammates' announced goals are avoided by
   the fallback when another target exists. Claims expire after ``claim_ticks`` or when the robot
   announces again. Set it off for the paper's implicit coordination.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any, Mapping

import numpy as np

from algorithms.boa import Belief, DecisionParams, Lidar, Plan, heading_index, predicted_observed
from algorithms.boa.decision import minimize_with_restarts
from algorithms.boa.fitness import ExplorationProblem
from algorithms.boa.variants import VARIANTS, get_variant
from swarm.api import (
    CELL_M, SOLID, UNSEEN, Action, InvalidInput, Observation, RobotInfo, cell_centre, cell_of, check_bool,
    check_float, check_int, grid
)
from swarm.api.messages import MessageError, message

SNAP_CELLS = 4                  # as the navigator: a robot pushed into inflated space snaps back within 2 m
IDLE_RECHECK_TICKS = 20         # an idle robot looks again this often (teammates' maps may open new space)
CONFLICT_SHARE = 0.5            # a simultaneous lower-id plan observing this share of my region: re-decide
VARIANT_NAMES = tuple(sorted(v.lower() for v in VARIANTS))


# ------------------------------------------------------------------------------------ parameters ----
@dataclass(frozen=True)
class XBOAParams:
    """Optimiser settings as :class:`algorithms.boa.DecisionParams` (paper Table 2 presets), then the
    runtime-integration settings of the module docstring."""

    variant: str = "xboa"              # xboa | boa | mboa | aboa | saboa | iboa-kent | iboa-levy (| xaboa)
    pop_size: int = 20
    max_gen: int = 30
    early_stop: int = 10
    n_goals: int = 1                   # 1 = short-term strategy; K > 1 = long-term (K goals in order)
    preset: str = "table2"             # "table2" (paper Table 2 for variant and pop size) | "defaults"
    boa: Mapping[str, Any] = field(default_factory=dict)   # BOAParams overrides
    retries: int = 3                   # fresh restarts when the best candidate has no gain
    search: str = "boa"                # "boa" | "exhaustive" (argmax of the gain table; short-term only)
    battery_steps: int | None = None   # None: RobotInfo.battery if set, else unlimited
    energy_margin: float = 1.5
    horizon_steps: int = 12            # steps one decision may plan (0: the battery only, as the paper)
    tile_cells: int = 2                # knowledge cells per tile side (2 = 1 m tiles)
    fov_deg: float = 360.0             # predicted scan; match the run's lidar.fov_deg
    overlap_penalty: bool = True
    claim_ticks: int = 600
    exclude_ticks: int = 300

    def __post_init__(self) -> None:
        if not isinstance(self.variant, str):
            raise InvalidInput("variant", self.variant, " | ".join(VARIANT_NAMES))
        try:
            canonical = get_variant(self.variant).name.lower()
        except InvalidInput:
            raise InvalidInput("variant", self.variant, " | ".join(VARIANT_NAMES)) from None
        object.__setattr__(self, "variant", canonical)
        if not isinstance(self.boa, Mapping):
            raise InvalidInput("boa", self.boa, "a table of BOAParams fields")
        object.__setattr__(self, "boa", dict(self.boa))
        self.decision_params()                      # validates the optimiser fields
        if self.battery_steps is not None:
            check_int("battery_steps", self.battery_steps, 0, 10**9)
        check_float("energy_margin", self.energy_margin, 1.0, 10.0)
        check_int("horizon_steps", self.horizon_steps, 0, 10**9)
        check_int("tile_cells", self.tile_cells, 1, 4)
        check_float("fov_deg", self.fov_deg, 0.0, 360.0, lo_open=True)
        Lidar(fov_deg=self.fov_deg)                 # an even multiple of the 1 degree resolution
        check_bool("overlap_penalty", self.overlap_penalty)
        check_int("claim_ticks", self.claim_ticks, 1, 10**7)
        check_int("exclude_ticks", self.exclude_ticks, 0, 10**7)

    def decision_params(self) -> DecisionParams:
        return DecisionParams(variant=self.variant, pop_size=self.pop_size, max_gen=self.max_gen,
                              early_stop=self.early_stop, n_goals=self.n_goals, preset=self.preset,
                              boa=self.boa, retries=self.retries, overlap_penalty=self.overlap_penalty,
                              search=self.search)


Params = XBOAParams


# -------------------------------------------------------------------------------------- messages ----
@message("xboa.target")
@dataclass(frozen=True, eq=False)
class TargetAnnouncement:
    """A robot's decision at ``tick``: its goals (x, y in metres) and the poses of its planned path as
    int16[N, 3] (row, col of a knowledge cell inside the pose's tile, heading 0..7). No poses: the robot
    has no plan (claims from it are dropped)."""

    sender: int
    tick: int
    gain: int
    goals: tuple[tuple[float, float], ...]
    poses: np.ndarray

    def validate(self) -> None:
        p = self.poses
        if not isinstance(p, np.ndarray) or p.ndim != 2 or p.shape[1] != 3 or p.shape[0] > 100_000 \
                or not np.issubdtype(p.dtype, np.integer):
            raise MessageError("xboa.target: poses must be an int[N, 3] array")
        if len(p) and ((p < 0).any() or (p[:, 2] > 7).any()):
            raise MessageError("xboa.target: pose cells must be >= 0 and headings 0..7")
        if not isinstance(self.tick, int) or not isinstance(self.gain, int):
            raise MessageError("xboa.target: tick and gain must be integers")
        if not all(isinstance(g, tuple) and len(g) == 2 and all(isinstance(v, (int, float)) and math.isfinite(v)
                                                                  for v in g) for g in self.goals):
            raise MessageError("xboa.target: goals must be finite (x, y) pairs")


@dataclass
class _Claim:
    tick: int                       # the sender's decision tick
    received: int
    poses: np.ndarray


# ------------------------------------------------------------------------------------------ tiles ----
@dataclass(frozen=True)
class TileView:
    """One decision's tile belief, cropped to the reachable tiles' box plus the sensor range.

    ``origin`` is the window's first (row, col) in the full tile grid; ``box`` the search bounds in window
    coordinates, ``[(col_lo, col_hi), (row_lo, row_hi)]``; ``reach`` the reachable configuration-space
    knowledge cells (full map)."""

    factor: int
    origin: tuple[int, int]
    belief: Belief
    box: list[tuple[float, float]]
    start: tuple[int, int]
    reach: np.ndarray
    shape: tuple[int, int]          # the full tile grid


def coarsen(known: np.ndarray, reach: np.ndarray, f: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(unknown, occupied, passable) tile grids by the rule of departure 1. Cells beyond the map's edge
    (when its size is not a multiple of ``f``) count as SOLID and unreachable.

    Wall junctions: the tile inside the corner where two walls meet is usually never seen (the lidar sees
    wall faces), and the beam model lets a 45 degree beam slip between two occupied tiles that touch only
    at a corner, so the unseen corner tile would leak phantom gain into closed rooms forever. An unknown
    tile with occupied 4-neighbours on two perpendicular sides is therefore taken as occupied and known."""
    H, W = known.shape
    Ht, Wt = -(-H // f), -(-W // f)
    if (H, W) != (Ht * f, Wt * f):
        k = np.full((Ht * f, Wt * f), SOLID, np.uint8)
        k[:H, :W] = known
        r = np.zeros((Ht * f, Wt * f), bool)
        r[:H, :W] = reach
        known, reach = k, r
    unknown = np.ones((Ht, Wt), bool)
    occupied = np.zeros((Ht, Wt), bool)
    passable = np.zeros((Ht, Wt), bool)
    for i in range(f):                  # f * f strided views: ~20x faster than reductions over a 4-D view
        for j in range(f):
            sub = known[i::f, j::f]
            unknown &= sub == UNSEEN
            occupied |= sub == SOLID
            passable |= reach[i::f, j::f]
    corner = unknown & _wall_corner(occupied)
    return unknown & ~corner, occupied | corner, passable


def _wall_corner(occupied: np.ndarray) -> np.ndarray:
    """Tiles with occupied 4-neighbours on two perpendicular sides (the inside corner of a wall junction)."""
    pad = np.pad(occupied, 1)
    up, down = pad[2:, 1:-1], pad[:-2, 1:-1]
    left, right = pad[1:-1, :-2], pad[1:-1, 2:]
    return (up | down) & (left | right)


def tile_view(known: np.ndarray, reach: np.ndarray, start_cell: tuple[int, int], f: int, range_tiles: float,
              horizon: int | None = None) -> TileView | None:
    """The decision's cropped tile belief (None when no tile is passable). With a ``horizon`` (steps),
    tiles farther than that (Chebyshev distance in tiles) from the robot's tile are not passable: no path
    of that many steps reaches them, so the result is exact and the window smaller."""
    unknown, occupied, passable = coarsen(known, reach, f)
    if horizon is not None:
        tr, tc = start_cell[0] // f, start_cell[1] // f
        near = np.zeros_like(passable)
        near[max(tr - horizon, 0):tr + horizon + 1, max(tc - horizon, 0):tc + horizon + 1] = True
        passable &= near
    rows = np.flatnonzero(passable.any(axis=1))
    cols = np.flatnonzero(passable.any(axis=0))
    if len(rows) == 0:
        return None
    m = int(math.ceil(range_tiles)) + 1
    Ht, Wt = passable.shape
    r0, r1 = max(int(rows[0]) - m, 0), min(int(rows[-1]) + m + 1, Ht)
    c0, c1 = max(int(cols[0]) - m, 0), min(int(cols[-1]) + m + 1, Wt)
    win = (slice(r0, r1), slice(c0, c1))
    belief = Belief(unknown[win], occupied[win], CELL_M * f, ~passable[win])
    box = [(float(cols[0] - c0), float(cols[-1] - c0)), (float(rows[0] - r0), float(rows[-1] - r0))]
    start = (start_cell[0] // f - r0, start_cell[1] // f - c0)
    return TileView(f, (r0, c0), belief, box, start, reach, (Ht, Wt))


def coarsen_window(known: np.ndarray, reach: np.ndarray | None, f: int, tiles: tuple[int, int, int, int]
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``coarsen(known, reach, f)`` read at tile rows ``t0:t1`` and columns ``u0:u1`` (``tiles``, clipped to
    the tile grid), bit for bit, at the cost of the window instead of the map: the window is coarsened with
    one more ring of tiles (the wall-corner rule reads each tile's 4 neighbours) and the ring is dropped.
    ``reach`` None: no cell is reachable (only ``unknown`` and ``occupied`` are wanted)."""
    H, W = known.shape
    Ht, Wt = -(-H // f), -(-W // f)
    t0, t1, u0, u1 = max(tiles[0], 0), min(tiles[1], Ht), max(tiles[2], 0), min(tiles[3], Wt)
    e0, e1, g0, g1 = max(t0 - 1, 0), min(t1 + 1, Ht), max(u0 - 1, 0), min(u1 + 1, Wt)
    cells = (slice(e0 * f, min(e1 * f, H)), slice(g0 * f, min(g1 * f, W)))
    sub = known[cells]
    unknown, occupied, passable = coarsen(sub, np.zeros(sub.shape, bool) if reach is None else reach[cells], f)
    keep = (slice(t0 - e0, t1 - e0), slice(u0 - g0, u1 - g0))
    return unknown[keep], occupied[keep], passable[keep]


REACH_MARGIN_CELLS = 40
"""How far (cells, 20 m) beyond the decision's horizon box the first reachability window reaches; each
further try doubles it (see :func:`local_reach`)."""


def local_reach(known: np.ndarray, radius_m: float, here: tuple[int, int], f: int, horizon: int
                ) -> tuple[tuple[int, int], np.ndarray] | None:
    """What a horizon-bounded decision needs of ``isfinite(distance_field(configuration_space(known), start))``
    with ``start = nearest_in(space, here, SNAP_CELLS)``, computed on a window around the robot instead of
    the whole map: (start, reach), with ``reach`` bool[H, W] exact inside the box of tiles within
    ``horizon`` of the start's tile and False elsewhere; None when no start is in reach of ``here``.

    Why it is exact: paths have no corner cutting, so reachability is 4-connectivity of the configuration
    space, and a window's space equals the map's away from the window's cut edges (it is computed with
    the erosion's depth more). A component of the window's space that holds the start is reachable; one
    that does not touch a cut edge is not; one that does touches could join the start's outside the
    window, and then a window twice as wide is tried (up to the whole map). So a decision costs the area
    around its horizon, not the map's (issue 47: xBOA's cost per robot-tick grew with the map's area)."""
    from scipy import ndimage

    H, W = known.shape
    depth = grid.erosion_depth(radius_m, grid.DEFAULT_MARGIN_M)

    def space_of(r0: int, r1: int, c0: int, c1: int) -> np.ndarray:
        s0, s1, q0, q1 = max(r0 - depth, 0), min(r1 + depth, H), max(c0 - depth, 0), min(c1 + depth, W)
        space = grid.configuration_space(known[s0:s1, q0:q1], radius_m, grid.DEFAULT_MARGIN_M)
        return space[r0 - s0:r1 - s0, c0 - q0:c1 - q0]

    r0, r1, c0, c1 = (max(here[0] - SNAP_CELLS, 0), min(here[0] + SNAP_CELLS + 1, H),
                      max(here[1] - SNAP_CELLS, 0), min(here[1] + SNAP_CELLS + 1, W))
    snapped = grid.nearest_in(space_of(r0, r1, c0, c1), (here[0] - r0, here[1] - c0), SNAP_CELLS)
    if snapped is None:
        return None
    start = (snapped[0] + r0, snapped[1] + c0)
    tr, tc = start[0] // f, start[1] // f
    b0, b1 = max(tr - horizon, 0) * f, min((tr + horizon + 1) * f, H)       # the horizon box, in cells
    d0, d1 = max(tc - horizon, 0) * f, min((tc + horizon + 1) * f, W)
    margin = REACH_MARGIN_CELLS
    while True:
        R0, R1, C0, C1 = max(b0 - margin, 0), min(b1 + margin, H), max(d0 - margin, 0), min(d1 + margin, W)
        labels, _ = ndimage.label(space_of(R0, R1, C0, C1))
        mine = labels[start[0] - R0, start[1] - C0]
        box = labels[b0 - R0:b1 - R0, d0 - C0:d1 - C0]
        cut = [labels[0]] if R0 > 0 else []
        cut += [labels[-1]] if R1 < H else []
        cut += [labels[:, 0]] if C0 > 0 else []
        cut += [labels[:, -1]] if C1 < W else []
        open_ = np.setdiff1d(np.concatenate(cut), [0, mine]) if cut else np.zeros(0, labels.dtype)
        if len(open_) == 0 or not np.isin(box, open_).any():
            reach = np.zeros(known.shape, bool)
            reach[b0:b1, d0:d1] = box == mine
            return start, reach
        margin *= 2


def local_tile_view(known: np.ndarray, reach: np.ndarray, start_cell: tuple[int, int], f: int,
                    range_tiles: float, horizon: int) -> TileView | None:
    """``tile_view(known, reach, start_cell, f, range_tiles, horizon)``, bit for bit, for a ``reach`` that
    is exact inside the horizon box (:func:`local_reach`): the horizon box and the belief's window are
    coarsened on their own (:func:`coarsen_window`), not the whole map."""
    H, W = known.shape
    Ht, Wt = -(-H // f), -(-W // f)
    tr, tc = start_cell[0] // f, start_cell[1] // f
    near = (max(tr - horizon, 0), min(tr + horizon + 1, Ht), max(tc - horizon, 0), min(tc + horizon + 1, Wt))
    _, _, passable_near = coarsen_window(known, reach, f, near)
    rows = np.flatnonzero(passable_near.any(axis=1))
    cols = np.flatnonzero(passable_near.any(axis=0))
    if len(rows) == 0:
        return None
    m = int(math.ceil(range_tiles)) + 1
    first_r, last_r = int(rows[0]) + near[0], int(rows[-1]) + near[0]
    first_c, last_c = int(cols[0]) + near[2], int(cols[-1]) + near[2]
    r0, r1 = max(first_r - m, 0), min(last_r + m + 1, Ht)
    c0, c1 = max(first_c - m, 0), min(last_c + m + 1, Wt)
    unknown, occupied, _ = coarsen_window(known, None, f, (r0, r1, c0, c1))
    passable = np.zeros(unknown.shape, bool)
    a0, a1, g0, g1 = max(near[0], r0), min(near[1], r1), max(near[2], c0), min(near[3], c1)
    passable[a0 - r0:a1 - r0, g0 - c0:g1 - c0] = passable_near[a0 - near[0]:a1 - near[0], g0 - near[2]:g1 - near[2]]
    belief = Belief(unknown, occupied, CELL_M * f, ~passable)
    box = [(float(first_c - c0), float(last_c - c0)), (float(first_r - r0), float(last_r - r0))]
    start = (tr - r0, tc - c0)
    return TileView(f, (r0, c0), belief, box, start, reach, (Ht, Wt))


def tile_cells(tiles: np.ndarray, f: int, shape: tuple[int, int]) -> np.ndarray:
    """Flat knowledge-cell indices (n, f*f) of full-grid tiles (n, 2); cells beyond the map are clipped
    onto the edge (such tiles never count as unknown, see :func:`coarsen`)."""
    d = np.arange(f)
    rr = np.minimum(tiles[:, 0, None, None] * f + d[None, :, None], shape[0] - 1)
    cc = np.minimum(tiles[:, 1, None, None] * f + d[None, None, :], shape[1] - 1)
    return (rr * shape[1] + cc).reshape(len(tiles), f * f)


def goal_cell(view: TileView, tile: tuple[int, int]) -> tuple[int, int]:
    """The reachable knowledge cell of a full-grid tile nearest its centre (ties: lowest row, then column)."""
    f = view.factor
    r0, c0 = tile[0] * f, tile[1] * f
    block = view.reach[r0:r0 + f, c0:c0 + f]
    rr, cc = np.nonzero(block)
    if len(rr) == 0:                                    # cannot happen for a passable tile
        return min(r0 + f // 2, view.reach.shape[0] - 1), min(c0 + f // 2, view.reach.shape[1] - 1)
    d2 = (2 * rr + 1 - f) ** 2 + (2 * cc + 1 - f) ** 2
    i = int(np.argmin(d2))
    return int(r0 + rr[i]), int(c0 + cc[i])


# ---------------------------------------------------------------------------------------- search ----
@dataclass(frozen=True)
class Choice:
    plan: Plan | None
    gain: int
    nfev: int


def search(problem: ExplorationProblem, box: list[tuple[float, float]], excluded: np.ndarray,
           dp: DecisionParams, rng: np.random.Generator) -> Choice:
    """``algorithms.boa.decide`` with the search box of departure 4 and goal exclusions: an excluded goal
    tile scores 0 (infeasible) without changing which paths the tree may use."""
    bad = excluded.ravel()
    if dp.search == "exhaustive":
        gains = problem.gain_table().ravel().copy()
        gains[bad] = 0
        k = int(np.argmax(gains))
        if gains[k] <= 0:
            return Choice(None, 0, gains.size)
        r, c = divmod(k, problem.shape[1])
        plan = problem.plan(np.array([c, r], float))
        return Choice(plan, int(gains[k]), gains.size)

    def fitness(X: np.ndarray) -> np.ndarray:
        f = problem(X)
        return np.where(bad[problem.cells(X)].any(axis=1), 0.0, f)

    best, _, _ = minimize_with_restarts(fitness, box * dp.n_goals, dp, rng)
    plan = problem.plan(best.x) if best.f < 0 else None
    return Choice(plan, int(-best.f) if plan is not None else 0, problem.nfev)


# ------------------------------------------------------------------------------------- explorer ----
class XBOA:
    """The xBOA explorer (see the module docstring)."""

    name = "xboa"
    Params = XBOAParams

    def reset(self, robot: RobotInfo, params: XBOAParams, rng: np.random.Generator) -> None:
        self.robot = robot
        self.params = params
        self.rng = rng
        self.dp = params.decision_params()
        self.lidar = Lidar(fov_deg=params.fov_deg, range_m=robot.lidar_range)
        self.tile_m = CELL_M * params.tile_cells
        battery = params.battery_steps if params.battery_steps is not None else robot.battery
        self.battery: float | None = None if battery is None else float(battery)
        self.goals: list[tuple[float, float]] = []      # metre goals still to visit, current first
        self.regions: list[np.ndarray] = []             # per goal: knowledge cells (n, f*f) of its target tiles
        self.gain = 0
        self.decided_at = -1
        self.idle_until = -1
        self.excluded: dict[tuple[int, int], int] = {}  # full-grid tile -> tick until which it is excluded
        self.claims: dict[int, _Claim] = {}
        self.redecide = False
        self.announced_empty = True

    # ------------------------------------------------------------------------------------- act ----
    def act(self, obs: Observation) -> Action:
        self._read_inbox(obs)
        left = self._battery_left(obs)
        if left is not None and left <= 0:
            return self._stop(obs, "battery", left)
        nav = obs.nav
        current = self.goals[0] if self.goals else None
        mine = current is not None and nav.goal == current
        if mine and nav.state in ("unreachable", "blocked"):
            self._exclude(obs, current)
            self._drop_plan()
        elif mine and nav.state == "reached":
            self.goals.pop(0)
            self.regions.pop(0)
            if self.goals:
                return self._go(obs, "next_goal", left, clear=True)
        elif self.goals and (self.redecide or self._region_seen(obs.known)):
            self._drop_plan()
        self.redecide = False
        if self.goals:
            return self._go(obs, "follow", left)
        if obs.tick < self.idle_until:
            return self._idle(obs, "idle", left)
        return self._decide(obs, left)

    # -------------------------------------------------------------------------------- deciding ----
    def _decide(self, obs: Observation, left: float | None) -> Action:
        t0 = time.perf_counter()
        p = self.params
        f = p.tile_cells
        known = obs.known
        here = _clip(cell_of(obs.pose.x, obs.pose.y), known.shape)
        view = None
        budget = None if left is None else int(max(left, 0.0) / p.energy_margin)
        limits = [v for v in (budget, p.horizon_steps or None) if v is not None]
        horizon = min(limits) if limits else None
        range_tiles = self.lidar.range_m / self.tile_m
        if horizon is not None:                       # the usual case: only the horizon's window is read
            found = local_reach(known, self.robot.radius, here, f, horizon)
            if found is not None:
                view = local_tile_view(known, found[1], found[0], f, range_tiles, horizon)
        else:                                         # the paper's battery-only constraint: the whole map
            space = grid.configuration_space(known, self.robot.radius, grid.DEFAULT_MARGIN_M)
            start = grid.nearest_in(space, here, SNAP_CELLS)
            if start is not None:
                reach = np.isfinite(grid.distance_field(space, start))
                view = tile_view(known, reach, start, f, range_tiles, horizon)
        choice = Choice(None, 0, 0)
        claimed = None
        if view is not None:
            claimed = self._claimed(known, view, obs.tick)
            problem = ExplorationProblem(view.belief, view.start, heading_index(obs.pose.theta), horizon,
                                         n_goals=p.n_goals, lidar=self.lidar, claimed=claimed)
            choice = search(problem, view.box, self._excluded_mask(view, obs.tick), self.dp, self.rng)
        self.decided_at = obs.tick
        if choice.plan is not None and view is not None:
            self._adopt(view, choice, claimed)
            msg = self._announcement(obs.tick, view, choice)
            return self._go(obs, "decided", left, clear=True, messages=(msg,), extra=_timing(choice, t0))
        fallback = self._fallback(obs, known, here, budget)
        if fallback is not None:
            self.goals, self.regions, self.gain = [fallback], [np.zeros((0, f * f), np.int64)], 0
            r, c = cell_of(*fallback)
            msg = TargetAnnouncement(self.robot.id, obs.tick, 0, (fallback,), np.array([[r, c, 0]], np.int16))
            self.announced_empty = False
            return self._go(obs, "fallback", left, clear=True, messages=(msg,), extra=_timing(choice, t0))
        self.idle_until = obs.tick + IDLE_RECHECK_TICKS
        return self._idle(obs, "no_target", left, extra=_timing(choice, t0))

    def _adopt(self, view: TileView, choice: Choice, claimed: np.ndarray | None) -> None:
        """Turn the plan's goal tiles into metre goals and remember each goal's target region."""
        plan = choice.plan
        assert plan is not None
        r0, c0 = view.origin
        belief = view.belief
        fresh = belief.unknown if claimed is None else belief.unknown & ~claimed
        ends = _leg_ends(plan)
        self.goals, self.regions = [], []
        prev = 0
        for goal, end in zip(plan.goals, ends):
            tile = (goal[0] + r0, goal[1] + c0)
            self.goals.append(cell_centre(*goal_cell(view, tile)))
            region = predicted_observed(belief, [plan.poses[end]], self.lidar) & fresh
            if not region.any():                        # the goal pose sees nothing new: use the whole leg
                region = predicted_observed(belief, plan.poses[prev:end + 1], self.lidar) & fresh
            tiles = np.argwhere(region) + np.array([r0, c0])
            self.regions.append(tile_cells(tiles, view.factor, view.reach.shape))
            prev = end + 1
        self.gain = choice.gain

    def _fallback(self, obs: Observation, known: np.ndarray, here: tuple[int, int], budget: int | None
                  ) -> tuple[float, float] | None:
        """Departure 6: the nearest reachable unseen cell within the battery, away from the robot's failed
        goals and, when possible, from the goals teammates announced."""
        own = _tile_mask(known.shape, self.params.tile_cells, list(self.excluded))
        masks = [own]
        if self.params.overlap_penalty and self.claims:
            theirs = [tuple(int(v) // self.params.tile_cells for v in c.poses[-1, :2]) for c in self.claims.values()]
            masks.insert(0, own | _tile_mask(known.shape, self.params.tile_cells, theirs))
        for mask in masks:
            found = grid.nearest_reachable_unseen(known, here, self.robot.radius, exclude=mask)
            if found is not None:
                cell, dist = found
                if budget is not None and dist / self.tile_m > budget:
                    return None
                return cell_centre(*cell)
        return None

    # --------------------------------------------------------------------------- coordination ----
    def _read_inbox(self, obs: Observation) -> None:
        coarse: list[Any] = []  # the tiles around my target region, coarsened once for all the tick's claims
        for msg in obs.inbox:
            if not isinstance(msg, TargetAnnouncement) or msg.sender == obs.robot_id:
                continue
            if len(msg.poses) == 0:
                self.claims.pop(msg.sender, None)
                continue
            self.claims.pop(msg.sender, None)       # re-inserted last: the dict stays in order of receipt
            self.claims[msg.sender] = _Claim(msg.tick, obs.tick, np.asarray(msg.poses, np.int64))
            if (self.params.overlap_penalty and self.goals and not self.redecide and msg.sender < obs.robot_id
                    and msg.tick >= self.decided_at and self._overlaps(obs.known, msg.poses, coarse)):
                self.redecide = True
        claims = self.claims                        # oldest first (see above): drop expired ones from the front
        while claims:
            oldest = next(iter(claims))
            if obs.tick - claims[oldest].received <= self.params.claim_ticks:
                break
            del claims[oldest]

    def _overlaps(self, known: np.ndarray, poses: np.ndarray, coarse: list[Any]) -> bool:
        """Whether ``poses`` (another robot's plan) will observe at least CONFLICT_SHARE of my target region.
        ``coarse``: empty, or the tile belief around the region from an earlier call of this tick (a swarm's
        robot hears hundreds of claims a tick; coarsening the whole map for each made xBOA's cost grow with
        robots x map area; now only the region plus the sensor's range is coarsened, once a tick)."""
        region = self.regions[0] if self.regions else None
        if region is None or len(region) == 0:
            return False
        f = self.params.tile_cells
        tiles = np.stack(np.unravel_index(region[:, 0], known.shape), axis=1) // f
        t0, u0 = tiles.min(axis=0)
        t1, u1 = tiles.max(axis=0) + 1
        seen = self._seen_from(known, (int(t0), int(t1), int(u0), int(u1)), poses, coarse)
        return float(seen[tiles[:, 0] - t0, tiles[:, 1] - u0].mean()) >= CONFLICT_SHARE

    def _claimed(self, known: np.ndarray, view: TileView, tick: int) -> np.ndarray | None:
        """Cells of the window that other robots' live claims will observe (departure 8)."""
        if not self.params.overlap_penalty or not self.claims:
            return None
        r0, c0 = view.origin
        h, w = view.belief.shape
        poses = np.concatenate([c.poses for c in self.claims.values()])
        return self._seen_from(known, (r0, r0 + h, c0, c0 + w), poses)

    def _seen_from(self, known: np.ndarray, tiles: tuple[int, int, int, int], poses: np.ndarray,
                   crop: list[Any] | None = None) -> np.ndarray:
        """``predicted_observed`` on the whole tile belief at knowledge-cell ``poses``, read at tile rows
        ``t0:t1`` and columns ``u0:u1`` (``tiles``), computed on those tiles plus the sensor's range: no
        farther pose sees into them, and a beam that leaves that box (a box around its pose) never comes
        back, so the answer is the whole map's bit for bit. ``crop``: empty, or the cropped belief of an
        earlier call with the same ``tiles`` and map (kept by the caller for the tick)."""
        f = self.params.tile_cells
        m = int(math.ceil(self.lidar.range_m / self.tile_m)) + 1
        t0, t1, u0, u1 = tiles
        shape = (-(-known.shape[0] // f), -(-known.shape[1] // f))
        e0, e1, g0, g1 = max(t0 - m, 0), min(t1 + m, shape[0]), max(u0 - m, 0), min(u1 + m, shape[1])
        if crop:
            belief = crop[0]
        else:
            unknown, occupied, _ = coarsen_window(known, None, f, (e0, e1, g0, g1))
            belief = Belief(unknown, occupied, self.tile_m)
            if crop is not None:
                crop.append(belief)
        p = _tile_poses(poses, f, shape, self.lidar, (e0, e1, g0, g1))
        seen = predicted_observed(belief, p, self.lidar)
        return seen[t0 - e0:t1 - e0, u0 - g0:u1 - g0]

    def _announcement(self, tick: int, view: TileView, choice: Choice) -> TargetAnnouncement:
        assert choice.plan is not None
        f = view.factor
        poses = np.array(choice.plan.poses, np.int64).reshape(-1, 3)
        poses[:, 0] = (poses[:, 0] + view.origin[0]) * f + f // 2
        poses[:, 1] = (poses[:, 1] + view.origin[1]) * f + f // 2
        self.announced_empty = False
        return TargetAnnouncement(self.robot.id, tick, choice.gain, tuple(self.goals), poses.astype(np.int16))

    def _withdraw(self, tick: int) -> tuple[TargetAnnouncement, ...]:
        if self.announced_empty:
            return ()
        self.announced_empty = True
        return (TargetAnnouncement(self.robot.id, tick, 0, (), np.zeros((0, 3), np.int16)),)

    # -------------------------------------------------------------------------------- bookkeeping ----
    def _battery_left(self, obs: Observation) -> float | None:
        """Departure 5: steps left, from odometry (moves in tiles + turns in 45 degree units)."""
        if self.battery is None:
            return None
        turned = max(obs.energy_used - obs.distance_travelled, 0.0)
        return self.battery - (obs.distance_travelled / self.tile_m + turned / (math.pi / 4.0))

    def _region_seen(self, known: np.ndarray) -> bool:
        """Every tile the current goal was chosen to observe has a seen cell (the target region is gone)."""
        region = self.regions[0] if self.regions else None
        if region is None or len(region) == 0:
            return False
        return not bool((known.reshape(-1)[region] == UNSEEN).all(axis=1).any())

    def _exclude(self, obs: Observation, goal: tuple[float, float]) -> None:
        f = self.params.tile_cells
        r, c = _clip(cell_of(*goal), obs.known.shape)
        self.excluded[(r // f, c // f)] = obs.tick + self.params.exclude_ticks

    def _excluded_mask(self, view: TileView, tick: int) -> np.ndarray:
        self.excluded = {t: until for t, until in self.excluded.items() if until > tick}
        mask = np.zeros(view.belief.shape, bool)
        r0, c0 = view.origin
        h, w = mask.shape
        for (r, c) in self.excluded:
            for rr in range(r - 1, r + 2):              # the tile and its 8 neighbours
                for cc in range(c - 1, c + 2):
                    if 0 <= rr - r0 < h and 0 <= cc - c0 < w:
                        mask[rr - r0, cc - c0] = True
        return mask

    def _drop_plan(self) -> None:
        self.goals, self.regions, self.gain = [], [], 0

    # ------------------------------------------------------------------------------------ actions ----
    def _debug(self, mode: str, left: float | None, extra: Mapping[str, Any] | None = None) -> dict[str, Any]:
        d: dict[str, Any] = {"mode": mode, "variant": self.params.variant,
                             "goal": self.goals[0] if self.goals else None, "goals": list(self.goals),
                             "gain": self.gain, "battery_left": left}
        if extra:
            d.update(extra)
        return d

    def _go(self, obs: Observation, mode: str, left: float | None, clear: bool = False,
            extra: Mapping[str, Any] | None = None, messages: tuple[Any, ...] = ()) -> Action:
        return Action(goal=self.goals[0], clear_goal=clear, messages=messages, debug=self._debug(mode, left, extra))

    def _idle(self, obs: Observation, mode: str, left: float | None, extra: Mapping[str, Any] | None = None) -> Action:
        return Action(velocity=(0.0, 0.0), clear_goal=True, messages=self._withdraw(obs.tick),
                      debug=self._debug(mode, left, extra))

    def _stop(self, obs: Observation, mode: str, left: float | None) -> Action:
        self._drop_plan()
        return self._idle(obs, mode, left)


# ---------------------------------------------------------------------------------------- helpers ----
def _clip(cell: tuple[int, int], shape: tuple[int, int]) -> tuple[int, int]:
    return min(max(cell[0], 0), shape[0] - 1), min(max(cell[1], 0), shape[1] - 1)


def _timing(choice: Choice, t0: float) -> dict[str, Any]:
    """Debug fields of a decision: fitness evaluations and wall time (never read back: runs stay reproducible)."""
    return {"nfev": choice.nfev, "decision_ms": (time.perf_counter() - t0) * 1000.0}


def _tile_mask(shape: tuple[int, int], f: int, tiles: list[tuple[int, int]]) -> np.ndarray:
    """bool[H, W] knowledge cells of the given tiles and their 8 neighbouring tiles."""
    mask = np.zeros(shape, bool)
    for (r, c) in tiles:
        mask[max((r - 1) * f, 0):(r + 2) * f, max((c - 1) * f, 0):(c + 2) * f] = True
    return mask


def _leg_ends(plan: Plan) -> list[int]:
    """Index in ``plan.poses`` where each goal's leg ends (a leg enters its goal cell only at its end)."""
    ends, i = [], 0
    for goal in plan.goals:
        while i < len(plan.poses) - 1 and (plan.poses[i][0], plan.poses[i][1]) != goal:
            i += 1
        ends.append(i)
        i += 1
    return [min(e, len(plan.poses) - 1) for e in ends]


def _tile_poses(poses: np.ndarray, f: int, shape: tuple[int, int], lidar: Lidar,
                box: tuple[int, int, int, int] | None = None) -> np.ndarray:
    """Distinct tile poses (int64[N, 3]) of knowledge-cell poses, inside the tile grid (with a full-circle
    lidar the heading does not change what a pose sees, so it is dropped before de-duplication). With a
    ``box`` (tile rows t0:t1, columns u0:u1) only the poses inside it, relative to its corner."""
    p = np.asarray(poses, np.int64).reshape(-1, 3).copy()
    p[:, 0] //= f
    p[:, 1] //= f
    if lidar.fov_deg >= 360.0:
        p[:, 2] = 0
    t0, t1, u0, u1 = (0, shape[0], 0, shape[1]) if box is None else box
    p = p[(p[:, 0] >= t0) & (p[:, 0] < min(t1, shape[0])) & (p[:, 1] >= u0) & (p[:, 1] < min(u1, shape[1]))]
    p[:, 0] -= t0
    p[:, 1] -= u0
    width = max(min(u1, shape[1]) - u0, 1)
    key = (p[:, 0] * width + p[:, 1]) * 65536 + (p[:, 2] + 32768)   # headings are int16: one int per pose
    key = np.unique(key)                                             # (a 1-D unique: ~10x np.unique(axis=0))
    out = np.empty((len(key), 3), np.int64)
    out[:, 2] = key % 65536 - 32768
    cell = key // 65536
    out[:, 0], out[:, 1] = np.divmod(cell, width)
    return out


__all__ = ["XBOA", "Params", "TargetAnnouncement", "TileView", "XBOAParams", "coarsen", "coarsen_window", "local_reach",
           "local_tile_view", "search", "tile_view"]
