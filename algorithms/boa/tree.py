"""Energy-optimal paths from the robot: a breadth-first tree over (cell, heading) states.

Energy is counted in steps as in the xBOA paper (section 5.2, "Step number: number of moves and
rotations"; docs/boa.md decision 12): a 45 degree rotation in place is one step, a move to the
neighbouring cell in the current heading is one step. Every edge costs 1, so breadth-first search gives
exact minimum-energy paths, and the path to a goal is the chain of parents in one tree - the robot later
executes *that* path, so the fitness it was chosen for is the fitness it gets (section 11.1, "path identity
matters").

Deliberate departure: the paper plans with A* on cells (octile lengths) and then counts steps; we
minimise the counted steps directly (a diagonal move costs one step like a straight one, rotations are
part of the cost). Diagonal moves may not cut corners (both side cells must be passable). Unknown cells
are passable (optimistic planning, as the paper's screenshots show paths through unknown space).

A goal cell's path ends in the first state of that cell that the search reaches (minimum energy; ties
broken by search order: forward move first, then counter-clockwise, then clockwise rotation).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from .beams import HEADING_DC, HEADING_DR

_DR = HEADING_DR
_DC = HEADING_DC


@njit(cache=True)
def _bfs(blocked: np.ndarray, start_state: int, max_steps: int, parent: np.ndarray, depth: np.ndarray,
         order: np.ndarray, cell_state: np.ndarray) -> int:
    H, W = blocked.shape
    depth[start_state] = 0
    parent[start_state] = -1
    order[0] = start_state
    cell_state[start_state >> 3] = start_state
    head, tail = 0, 1
    while head < tail:
        s = order[head]
        head += 1
        d = depth[s]
        if d >= max_steps:
            continue
        cell = s >> 3
        h = s & 7
        r = cell // W
        c = cell - r * W
        rr = r + _DR[h]
        cc = c + _DC[h]
        if 0 <= rr < H and 0 <= cc < W and not blocked[rr, cc]:
            if _DR[h] == 0 or _DC[h] == 0 or (not blocked[rr, c] and not blocked[r, cc]):
                ncell = rr * W + cc
                ns = ncell * 8 + h
                if depth[ns] < 0:
                    depth[ns] = d + 1
                    parent[ns] = s
                    order[tail] = ns
                    tail += 1
                    if cell_state[ncell] < 0:
                        cell_state[ncell] = ns
        for hh in ((h + 1) & 7, (h + 7) & 7):
            ns = cell * 8 + hh
            if depth[ns] < 0:
                depth[ns] = d + 1
                parent[ns] = s
                order[tail] = ns
                tail += 1
    return tail


@dataclass(frozen=True)
class StateTree:
    """Minimum-energy tree from one (cell, heading) state over a passability grid.

    States are ``(row * W + col) * 8 + heading``. ``depth[s]`` is the energy (steps) to reach s, -1 when
    unreachable within ``max_steps``; ``cell_state[cell]`` the state that ends the path to that cell.
    """

    shape: tuple[int, int]
    root: int
    parent: np.ndarray          # int32[S]
    depth: np.ndarray           # int32[S]
    order: np.ndarray           # int32[n] reachable states in search order (parents before children)
    cell_state: np.ndarray      # int32[H*W]

    @classmethod
    def build(cls, blocked: np.ndarray, cell: tuple[int, int], heading: int, max_steps: int | None = None) -> "StateTree":
        blocked = np.ascontiguousarray(blocked, dtype=np.bool_)
        H, W = blocked.shape
        S = H * W * 8
        parent = np.full(S, -1, np.int32)
        depth = np.full(S, -1, np.int32)
        order = np.empty(S, np.int32)
        cell_state = np.full(H * W, -1, np.int32)
        root = (cell[0] * W + cell[1]) * 8 + heading
        limit = np.iinfo(np.int32).max if max_steps is None else int(max_steps)
        n = _bfs(blocked, root, limit, parent, depth, order, cell_state)
        return cls((H, W), root, parent, depth, order[:n].copy(), cell_state)

    def energy(self, cells: np.ndarray) -> np.ndarray:
        """Steps to reach each flat cell index (-1 when unreachable)."""
        st = self.cell_state[cells]
        return np.where(st >= 0, self.depth[np.maximum(st, 0)], -1)

    def path(self, state: int) -> list[tuple[int, int, int]]:
        """(row, col, heading) poses from the root to ``state`` inclusive."""
        W = self.shape[1]
        out = []
        s = int(state)
        while s >= 0:
            cell, h = divmod(s, 8)
            out.append((cell // W, cell % W, h))
            s = int(self.parent[s])
        return out[::-1]

    def path_to_cell(self, row: int, col: int) -> list[tuple[int, int, int]]:
        st = int(self.cell_state[row * self.shape[1] + col])
        if st < 0:
            raise ValueError(f"cell ({row}, {col}) is not reachable")
        return self.path(st)
