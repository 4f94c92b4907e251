"""The xBOA exploration fitness on a belief grid: one object per decision, batched over whole populations.

The xBOA paper, section 4.2, Eq. 9, read as docs/boa.md section 4.2 recommends: a candidate is a flat vector
of K target cells (x1, y1, ..., xK, yK) (genes rounded to the nearest cell and clipped to the map); its
fitness is ``-(number of currently unknown cells predicted to be observed along the planned path)``,
raw and negative (Table 2 was tuned on raw counts, section 1 item 3), or 0 - the worst value - when the
plan is infeasible: a target unreachable or not passable, or the chained energy (moves + 45 degree
rotations, legs in order, K >= 2 = the paper's long-term strategy) over the battery (decisions 10-12).
The prediction is an optimistic lidar scan at every pose of the path (decision 13; ``beams.py``, ``gain.py``),
the path is the minimum-energy tree path (``tree.py``), which the robot then executes.

Works on any belief grid (shape, cell size): the sensor range in cells is ``lidar.range_m / cell_m``.

Evaluation modes (all exact and equal; a test checks it on every goal of the house map):

* ``"table"`` (short-term only): the per-decision gain table of section 11.1, one depth-first pass over the
  state tree; afterwards ``fitness(X)`` is a vectorised lookup.
* ``"lazy"``: evaluate only the distinct goals the optimiser asks for, memoised (section 11.2); long-term
  plans always use it, with one cached tree per leg source.
* ``"auto"``: table for short-term plans on maps up to ``TABLE_MAX_CELLS`` cells, lazy otherwise.

Multi-robot overlap (the paper's "future work", section 11.3): ``claimed`` cells - those other robots'
announced plans are predicted to observe - count as already known.
"""

from __future__ import annotations

from collections import OrderedDict
from dataclasses import dataclass
from typing import Any

import numpy as np

from swarm.api import InvalidInput, check_choice, check_int

from .beams import BeamTables, Lidar, visible_cells
from .gain import chain_gain, observed_cells, subtree_gains, tree_index
from .tree import StateTree

TABLE_MAX_CELLS = 128 * 128
UNSEEN, SOLID = 0, 2                  # swarm.api cell states (UNSEEN = 0 < FREE = 1 < SOLID = 2)


@dataclass(frozen=True, eq=False)
class Belief:
    """What a robot believes: ``unknown`` and ``occupied`` (known-occupied: stops beams, not passable) bool
    grids, row index = y (row 0 at the bottom), cells of ``cell_m`` metres. ``blocked`` (default: occupied)
    is what planning may not enter - a runtime can pass an inflated obstacle mask here."""

    unknown: np.ndarray
    occupied: np.ndarray
    cell_m: float = 1.0
    blocked: np.ndarray | None = None

    def __post_init__(self) -> None:
        u = np.ascontiguousarray(self.unknown, dtype=np.bool_)
        o = np.ascontiguousarray(self.occupied, dtype=np.bool_)
        b = o if self.blocked is None else np.ascontiguousarray(self.blocked, dtype=np.bool_)
        if u.ndim != 2 or u.shape != o.shape or b.shape != u.shape or min(u.shape) < 1:
            raise InvalidInput("belief", (u.shape, o.shape, b.shape), "unknown, occupied, blocked: equal 2-D shapes")
        if not (isinstance(self.cell_m, (int, float)) and self.cell_m > 0):
            raise InvalidInput("cell_m", self.cell_m, "a positive cell size in metres")
        object.__setattr__(self, "unknown", u)
        object.__setattr__(self, "occupied", o)
        object.__setattr__(self, "blocked", b)

    @property
    def shape(self) -> tuple[int, int]:
        return self.unknown.shape  # type: ignore[return-value]

    @classmethod
    def from_knowledge(cls, known: np.ndarray, cell_m: float = 0.5, blocked: np.ndarray | None = None) -> "Belief":
        """From a swarm knowledge map (uint8, UNSEEN = 0, FREE = 1, SOLID = 2)."""
        known = np.asarray(known)
        return cls(known == UNSEEN, known == SOLID, cell_m, blocked)

    @classmethod
    def from_logodds(cls, logodds: np.ndarray, cell_m: float = 1.0) -> "Belief":
        """From a log-odds grid, xBOA paper Eq. 8: occupied if > 0, free if < 0, unknown if = 0."""
        logodds = np.asarray(logodds)
        return cls(logodds == 0, logodds > 0, cell_m)


@dataclass(frozen=True)
class Plan:
    """The path a fitness value was computed for: goals in order, poses after the start (row, col, heading)."""

    goals: tuple[tuple[int, int], ...]
    poses: tuple[tuple[int, int, int], ...]
    energy: int
    gain: int


def predicted_observed(belief: Belief, poses: Any, lidar: Lidar = Lidar()) -> np.ndarray:
    """bool[H, W]: cells the optimistic scans at ``poses`` ((row, col, heading) triples, e.g. another robot's
    announced plan) would observe on ``belief``. Pass it as ``claimed`` to ``ExplorationProblem`` /
    ``decide`` for the multi-robot overlap penalty."""
    tables = lidar.tables(belief.cell_m)
    out = np.zeros(belief.unknown.size, bool)
    p = np.asarray(poses, dtype=np.int64).reshape(-1, 3)
    ok = (p[:, 2] >= 0) & (p[:, 2] < 8)
    H, W = belief.shape
    observed_cells(belief.occupied.reshape(-1), H, W, p[ok], tables.trie_dr, tables.trie_dc, tables.trie_skip,
                   tables.trie_start, out)           # compiled: the trie walk of gain.py, one call for all poses
    for row, col, h in p[~ok].tolist():              # a heading outside 0..7: the reference's own indexing
        out[visible_cells(belief.occupied, row, col, h, tables)] = True
    return out.reshape(belief.shape)


class _SubtreeEvaluator:
    """Exact gains of states of one tree via ``gain.subtree_gains``, with its work arrays allocated once
    (about 40 bytes per reachable state plus 12 per cell: the decision's memory is bounded and visible)."""

    def __init__(self, tree: StateTree, tables: BeamTables, n_cells: int) -> None:
        n = len(tree.order)
        self.tree = tree
        self.pos = np.empty(len(tree.parent), np.int32)
        self.first = np.empty(n, np.int32)
        self.sib = np.empty(n, np.int32)
        tree_index(tree.order, tree.parent, self.pos, self.first, self.sib)
        self.need = np.zeros(n, np.bool_)
        self.marked = np.empty(n, np.int32)
        self.stack = np.empty(n + 1, np.int32)
        self.tps = np.empty(n + 1, np.int64)
        self.nxt = np.empty(n, np.int32)
        self.gpos = np.empty(n, np.int32)
        self.count = np.zeros(n_cells, np.int32)
        max_depth = int(tree.depth[tree.order[-1]])
        self.touched = np.empty((max_depth + 2) * (tables.max_fan_nodes + 1), np.int64)

    def gains(self, targets: np.ndarray, args: tuple[Any, ...], stamp: np.ndarray, sid: int) -> tuple[np.ndarray, int]:
        out = np.empty(len(targets), np.int64)
        t = self.tree
        sid = subtree_gains(t.order, t.parent, self.pos, self.first, self.sib, targets.astype(np.int32), *args,
                            stamp, sid, self.count, self.touched, self.need, self.marked, self.stack, self.tps,
                            self.nxt, self.gpos, out)
        return out, sid


class ExplorationProblem:
    """Fitness of one decision for a robot at ``cell`` = (row, col) with ``heading`` (0..7, 2 = north) and
    ``battery`` steps left (None: unlimited)."""

    def __init__(self, belief: Belief, cell: tuple[int, int], heading: int, battery: int | None, *, n_goals: int = 1,
                 lidar: Lidar = Lidar(), mode: str = "auto", claimed: np.ndarray | None = None,
                 tree_cache_mb: float = 64.0) -> None:
        H, W = belief.shape
        check_int("n_goals", n_goals, 1, 1000)
        if battery is not None:
            check_int("battery", battery, 0)
        check_int("heading", heading, 0, 7)
        check_choice("mode", mode, ("auto", "table", "lazy"))
        if not (0 <= cell[0] < H and 0 <= cell[1] < W):
            raise InvalidInput("cell", cell, f"a (row, col) inside {H} x {W}")
        if mode == "table" and n_goals > 1:
            raise InvalidInput("mode", mode, "'lazy' or 'auto' for long-term plans (n_goals > 1)")
        self.belief = belief
        self.shape = (H, W)
        self.cell = (int(cell[0]), int(cell[1]))
        self.heading = heading
        self.battery = battery
        self.n_goals = n_goals
        self.tables: BeamTables = lidar.tables(belief.cell_m)
        unknown = belief.unknown if claimed is None else belief.unknown & ~np.asarray(claimed, bool)
        self._unknown = np.ascontiguousarray(unknown.ravel())
        self._occupied = np.ascontiguousarray(belief.occupied.ravel())
        self.tree = StateTree.build(belief.blocked, self.cell, heading, battery)
        self._trees: OrderedDict[int, StateTree] = OrderedDict()      # leg trees other than the root
        # long-term legs: one tree per leg source, least recently used dropped beyond the memory budget
        self._max_trees = max(2, int(tree_cache_mb * 2**20 // (13 * H * W * 8 + 1)))
        self._stamp = np.full(H * W, -1, np.int64)
        self._sid = 0
        self.mode = ("table" if n_goals == 1 and H * W <= TABLE_MAX_CELLS else "lazy") if mode == "auto" else mode
        self._eval: _SubtreeEvaluator | None = None
        self.nfev = 0
        self._memo: dict[tuple[int, ...], float] = {}
        self._cell_f = np.full(H * W, np.nan)
        self._seen = np.zeros(H * W, np.bool_)
        if self.mode == "table":
            self._cell_f = self._table_fitness()

    # --------------------------------------------------------------- the optimiser's view
    @property
    def bounds(self) -> list[tuple[float, float]]:
        """Per-gene bounds, decision 10: x in [0, W-1], y in [0, H-1], repeated per goal."""
        H, W = self.shape
        return [(0.0, float(W - 1)), (0.0, float(H - 1))] * self.n_goals

    def cells(self, X: np.ndarray) -> np.ndarray:
        """Flat goal-cell indices (m, K) of candidate rows: round to nearest (half up), clip to the map."""
        H, W = self.shape
        X = np.asarray(X, dtype=float).reshape(len(X), self.n_goals, 2)
        col = np.clip(np.floor(X[..., 0] + 0.5), 0, W - 1).astype(np.int64)
        row = np.clip(np.floor(X[..., 1] + 0.5), 0, H - 1).astype(np.int64)
        return row * W + col

    def __call__(self, X: np.ndarray) -> np.ndarray:
        cells = self.cells(X)
        self.nfev += len(cells)
        if self.n_goals == 1:
            c = cells[:, 0]
            self._seen[c] = True
            missing = np.unique(c[np.isnan(self._cell_f[c])])
            if len(missing):
                self._cell_f[missing] = self._lazy_single(missing)
            return self._cell_f[c].copy()
        out = np.empty(len(cells))
        for i, row in enumerate(map(tuple, cells.tolist())):
            f = self._memo.get(row)
            if f is None:
                f = self._memo[row] = -float(self._chain(row)[1])
            out[i] = f
        return out

    @property
    def n_distinct(self) -> int:
        """Distinct goal tuples evaluated so far (table mode: distinct cells looked up)."""
        return len(self._memo) if self.n_goals > 1 else int(self._seen.sum())

    # --------------------------------------------------------------- tables and plans
    def gain_table(self) -> np.ndarray:
        """Short-term: predicted gain of every goal cell (H, W); 0 where infeasible. Exhaustive oracle."""
        if self.n_goals != 1:
            raise InvalidInput("n_goals", self.n_goals, "1 for a gain table")
        f = self._cell_f if self.mode == "table" else self._table_fitness()
        return (-f).reshape(self.shape).astype(np.int64)

    def energy_table(self) -> np.ndarray:
        """Steps to reach each cell from the start pose (-1: unreachable within the battery)."""
        H, W = self.shape
        return self.tree.energy(np.arange(H * W)).reshape(H, W)

    def plan(self, x: np.ndarray) -> Plan | None:
        """The path candidate ``x`` was scored on (None if infeasible)."""
        goals = tuple(int(c) for c in self.cells(np.asarray(x, float)[None, :])[0])
        states, gain, energy = self._chain(goals, want_states=True)
        if states is None:
            return None
        W = self.shape[1]
        poses: list[tuple[int, int, int]] = []
        src = self.tree
        for st in states:
            poses.extend(src.path(st)[1:])
            src = self._tree_from(st)
        return Plan(tuple(divmod(g, W) for g in goals), tuple(poses), energy, gain)

    # --------------------------------------------------------------- internals
    def _kernel_args(self) -> tuple[Any, ...]:
        t = self.tables
        H, W = self.shape
        return H, W, self._unknown, self._occupied, t.trie_dr, t.trie_dc, t.trie_skip, t.trie_start

    def _evaluator(self) -> _SubtreeEvaluator:
        if self._eval is None:
            self._eval = _SubtreeEvaluator(self.tree, self.tables, self.shape[0] * self.shape[1])
        return self._eval

    def _table_fitness(self) -> np.ndarray:
        st = self.tree.cell_state
        ok = st >= 0
        gains, self._sid = self._evaluator().gains(st[ok], self._kernel_args(), self._stamp, self._sid)
        out = np.zeros(len(st))
        out[ok] = np.where(gains > 0, -gains, 0)
        return out

    def _lazy_single(self, cells: np.ndarray) -> np.ndarray:
        st = self.tree.cell_state[cells]
        ok = st >= 0
        out = np.zeros(len(cells))
        if ok.any():
            gains, self._sid = self._evaluator().gains(st[ok], self._kernel_args(), self._stamp, self._sid)
            out[ok] = np.where(gains > 0, -gains, 0)
        return out

    def _tree_from(self, state: int) -> StateTree:
        if state == self.tree.root:
            return self.tree
        tree = self._trees.get(state)
        if tree is None:
            W = self.shape[1]
            cell, h = divmod(int(state), 8)
            tree = StateTree.build(self.belief.blocked, divmod(cell, W), h, self.battery)
            self._trees[state] = tree
            while len(self._trees) > self._max_trees:
                self._trees.popitem(last=False)
        else:
            self._trees.move_to_end(state)
        return tree

    def _chain(self, goals: tuple[int, ...], want_states: bool = False) -> tuple[Any, int, int]:
        """(end states per leg or None, union gain, energy) of visiting ``goals`` in order."""
        src = self.tree
        energy = 0
        gain = 0
        sid = self._sid
        self._sid += 1
        states = []
        args = self._kernel_args()
        for g in goals:
            st = int(src.cell_state[g])
            if st < 0:
                return None, 0, 0
            energy += int(src.depth[st])
            if self.battery is not None and energy > self.battery:
                return None, 0, 0
            gain += chain_gain(st, src.parent, *args, self._stamp, sid)
            states.append(st)
            if len(states) < len(goals):
                src = self._tree_from(st)
        return (states if want_states else True), gain, energy
