"""Per-call cost of the plugin helpers of :mod:`swarm.api.grid`, the numbers their docstrings quote.

    python benchmarks/api_costs.py            # median of 7 repeats, ms per call

The map is a realistic knowledge map: a 150 m building (300 x 300 cells) seen within 40 m of a free cell
near its centre, the rest UNSEEN, as a robot's map looks some way into a run. Each helper is timed warm
(numba kernels compiled, per-thread workspaces allocated), on the inputs a plugin would pass;
``nearest_reachable_unseen`` keeps its inputs per map, so it is timed on the same map again and on a
fresh copy (a map that changed since its last search costs between the two).
"""

from __future__ import annotations

import timeit
from typing import Callable

import numpy as np

from maps import generate
from swarm.api import FREE, SOLID, UNSEEN, grid


def knowledge_map(size_m: int = 150, seen_m: float = 40.0, seed: int = 7) -> tuple[np.ndarray, tuple[int, int]]:
    """A building's cells seen within ``seen_m`` of the free cell nearest its centre, and that cell (which
    may lie in inflated space)."""
    truth = generate("building", size_m, seed=seed)
    known = np.where(truth.solid, SOLID, FREE).astype(np.uint8)
    h, w = known.shape
    rows, cols = np.nonzero(known == FREE)
    i = int(np.argmin((rows - h / 2) ** 2 + (cols - w / 2) ** 2))
    start = int(rows[i]), int(cols[i])
    rr, cc = np.indices(known.shape)
    known[(rr - start[0]) ** 2 + (cc - start[1]) ** 2 > (seen_m / 0.5) ** 2] = UNSEEN
    return known, start


def cases(known: np.ndarray, start: tuple[int, int]) -> dict[str, Callable[[], object]]:
    """One call of each helper on ``known``, as a plugin makes it."""
    space = grid.configuration_space(known)
    start = grid.nearest_in(space, start)
    assert start is not None
    far = grid.nearest_reachable_unseen(known, start, local_first_m=None)
    assert far is not None
    goal = far[0]
    path = grid.plan(space, start, goal)
    assert path is not None
    frontier = grid.frontier_mask(known)
    view = grid.view_cells(known, 2)
    cluster = max(grid.frontier_clusters(known), key=lambda c: c.size)
    return {
        "passable": lambda: grid.passable(known),
        "configuration_space": lambda: grid.configuration_space(known),
        "nearest_in (1 cell off)": lambda: grid.nearest_in(space, cluster.representative, 8),
        "plan": lambda: grid.plan(space, start, goal),
        "distance_field": lambda: grid.distance_field(space, start),
        "distance_field (max 10 m)": lambda: grid.distance_field(space, start, 10.0),
        "field_at (cluster cells)": lambda: grid.field_at(space, start, cluster.cells),
        "nearest_reachable (view cells)": lambda: grid.nearest_reachable(space, start, view),
        "nearest_reachable_unseen": lambda: grid.nearest_reachable_unseen(known, start),
        "nearest_reachable_unseen (whole map)": lambda: grid.nearest_reachable_unseen(known, start,
                                                                                      local_first_m=None),
        "nearest_reachable_unseen (new map)": lambda: grid.nearest_reachable_unseen(known.copy(), start),
        "(known.copy(), to subtract)": lambda: known.copy(),
        "frontier_mask": lambda: grid.frontier_mask(known),
        "frontier_clusters": lambda: grid.frontier_clusters(known),
        "view_cells": lambda: grid.view_cells(known, 2),
        "simplify": lambda: grid.simplify(space, path),
        "segment_clear": lambda: grid.segment_clear(space, start, goal),
        "cells_to_metres": lambda: grid.cells_to_metres(path),
        "steps_length": lambda: grid.steps_length(path),
        "path_length_m": lambda: grid.path_length_m(grid.cells_to_metres(path)),
        "grid_length_m": lambda: grid.grid_length_m(space, start, goal),
        "any_angle_length_m": lambda: grid.any_angle_length_m(space, start, goal),
        f"(map {known.shape}, {int((known == FREE).sum())} free cells, {int(frontier.sum())} frontier cells, "
        f"goal {far[1]:.0f} m, path {len(path)} cells)": lambda: None,
    }


def main() -> None:
    known, start = knowledge_map()
    for name, call in cases(known, start).items():
        call()  # warm: compile, allocate
        number = 5
        best = sorted(timeit.repeat(call, number=number, repeat=7))[3] / number
        print(f"{name:40s} {best * 1e3:9.3f} ms")


if __name__ == "__main__":
    main()
