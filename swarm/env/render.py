"""``render()`` of the RL environments: the team's knowledge scaled to a readable picture, robots drawn
as discs with their heading and id (learning robots blue, scripted teammates red), north up.

Drawn by :mod:`swarm.draw`, the rules and colours of the browser viewer's union view (walls in
their material's colour once seen, faded before; floor seen or unseen), so a frame reads like the viewer
at that tick and like the run's GIF."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from maps.render import upscale
from swarm.api import CELL_M, UNSEEN, check_int
from swarm.draw import SEEN_FREE, UNSEEN_FREE, draw_robots, to_pixel, union_layer

if TYPE_CHECKING:
    from .core import ExplorationCore

RENDER_PX = 600
"""Default length in pixels of the picture's longer side."""
UNKNOWN = UNSEEN_FREE
"""Floor no robot has seen (walls nobody has seen are their material's colour faded towards it)."""
FREE = SEEN_FREE
LEARNER = (40, 90, 230)
SCRIPTED = (220, 40, 40)


def check_render_px(value: Any) -> int:
    """``render_px`` is an int in [32, 4000] (pixels on the picture's longer side)."""
    check_int("render_px", value, 32, 4000)
    return int(value)


def cell_px(shape: tuple[int, int], render_px: int) -> int:
    """Whole pixels per 0.5 m cell so the longer side of a ``shape`` map is at most ``render_px`` (>= 1)."""
    return max(1, render_px // max(shape))


def world_to_pixel(x: float, y: float, shape: tuple[int, int], scale: int) -> tuple[float, float]:
    """Picture coordinates (column, row) of the world point (x, y) m, north up."""
    return to_pixel(x, y, shape[0], scale)


def render_rgb(core: ExplorationCore, render_px: int = RENDER_PX) -> np.ndarray:
    """``uint8[H * s, W * s, 3]`` with ``s = cell_px(map shape, render_px)``: the map as the team knows it
    (a cell is seen when some robot's map has it), every robot a disc of its real radius (at least 4 px)
    with a heading line and its id."""
    sim = core.sim
    union = sim.known.max(axis=0)
    shape = union.shape
    scale = cell_px(shape, render_px)
    picture = upscale(union_layer(sim.truth, union != UNSEEN), scale)
    learners = set(core.learners)
    poses = np.asarray(sim.world.poses, dtype=np.float64)
    colours = [LEARNER if robot in learners else SCRIPTED for robot in range(len(poses))]
    draw_robots(picture, poses, shape[0], scale, colours, max(4.0, sim.motion.radius / CELL_M * scale), labels=True)
    return np.asarray(picture, dtype=np.uint8).copy()
