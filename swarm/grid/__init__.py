"""Grid helpers for navigation and exploration: configuration space, shortest paths, distance fields,
frontiers and the nearest reachable unseen cell. Pure functions on numpy arrays; no runtime imports.
May import: ``swarm.base``, ``swarm.knowledge`` (the 2-bit copies its kept inputs compare against).

Conventions (see :mod:`swarm.api`): knowledge maps are ``uint8[H, W]`` with UNSEEN=0 < FREE=1 < SOLID=2;
cells are (row, col) with row 0 at the bottom; ``known[row, col]`` covers x in [col*0.5, (col+1)*0.5),
y in [row*0.5, (row+1)*0.5); metres are (x, y). Bad input raises :class:`swarm.base.errors.InvalidInput`.

Typical use (the runtime's navigator)::

    space = configuration_space(known)              # where the robot's centre may be
    start, goal = nearest_in(space, s, 4), nearest_in(space, g, 4)
    path = plan(space, start, goal)                 # int[N, 2] cells, or None
    waypoints = simplify(space, path)               # float[M, 2] metres, collision-free segments

Module map: :mod:`.cspace` (passable, configuration_space, nearest_in), :mod:`.search` (plan,
distance_field, field_at, nearest_reachable), :mod:`.path` (simplify, path_length_m, segment_clear),
:mod:`.frontiers` (frontier_mask, frontier_clusters), :mod:`.reference` (optimal grid and any-angle lengths), :mod:`.targets` (nearest_reachable_unseen, view_cells),
:mod:`.local` (the navigator's exact local-first plan, the target search's compiled window stage),
:mod:`.memo` (a far target search's path, reused by the plan that follows it), :mod:`.kept` (the whole-map
target search's inputs, kept per map and updated where it changed), :mod:`._kernels` (the numba search and
line kernels).
"""

from .cspace import DEFAULT_MARGIN_M, configuration_space, inflation_offsets, nearest_in, passable
from .frontiers import FrontierCluster, frontier_clusters, frontier_mask
from .local import erosion_depth
from .path import cells_to_metres, path_length_m, segment_clear, simplify
from .reference import any_angle_length_m, grid_length_m, steps_length
from .search import distance_field, field_at, nearest_reachable, nearest_reachable_window, plan
from .targets import nearest_reachable_unseen, view_cells

__all__ = [
    "DEFAULT_MARGIN_M", "FrontierCluster", "any_angle_length_m", "cells_to_metres", "configuration_space",
    "distance_field", "erosion_depth", "field_at", "frontier_clusters", "frontier_mask", "grid_length_m",
    "inflation_offsets", "nearest_in", "nearest_reachable", "nearest_reachable_unseen", "nearest_reachable_window",
    "passable", "path_length_m", "plan", "segment_clear", "simplify", "steps_length", "view_cells",
]
