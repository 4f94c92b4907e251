"""Grid helpers for plugins: configuration space, shortest paths, distance fields, frontiers, targets.

Pure functions on the robot's knowledge map (``uint8[H, W]``, ``UNSEEN < FREE < SOLID``) and on boolean
rasters, the same ones the runtime's navigator uses, so an algorithm's idea of "reachable" is the
navigator's. Cells are ``(row, col)`` with row 0 at the bottom; metres are ``(x, y)``. Each helper's
docstring gives its return convention (None or ``inf`` for what cannot be reached) and its cost per call,
measured by benchmarks/api_costs.py; docs/plugins.md ("Grid helpers") has them as one table and shows how to
turn a frontier, which lies in inflated space, into a reachable goal.
"""

from __future__ import annotations

from swarm.grid import (DEFAULT_MARGIN_M, FrontierCluster, any_angle_length_m, cells_to_metres, configuration_space,
                    distance_field, erosion_depth, field_at, frontier_clusters, frontier_mask, grid_length_m,
                    inflation_offsets, nearest_in, nearest_reachable, nearest_reachable_unseen,
                    nearest_reachable_window, passable, path_length_m, plan, segment_clear, simplify, steps_length,
                    view_cells)
from swarm.grid.targets import default_view_reach_cells

DEFAULT_MARGIN_M: float
"""Extra clearance (m) on top of the robot radius, for tracking error and sensor noise: the navigator's
default, so ``configuration_space(known)`` is the space the navigator plans on."""

__all__ = [
    "DEFAULT_MARGIN_M", "FrontierCluster", "any_angle_length_m", "cells_to_metres", "configuration_space",
    "default_view_reach_cells", "distance_field", "erosion_depth", "field_at", "frontier_clusters", "frontier_mask",
    "grid_length_m", "inflation_offsets", "nearest_in", "nearest_reachable", "nearest_reachable_unseen",
    "nearest_reachable_window", "passable", "path_length_m", "plan", "segment_clear", "simplify", "steps_length",
    "view_cells",
]
