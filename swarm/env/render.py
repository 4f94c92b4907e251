"""``render()`` of the RL environments: the team's knowledge scaled to a readable picture, robots drawn
as discs with their heading and id (learning robots blue, scripted teammates red), north up."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
from PIL import Image, ImageDraw, ImageFont

from swarm.api import CELL_M, check_int

if TYPE_CHECKING:
    from .core import ExplorationCore

RENDER_PX = 600
"""Default length in pixels of the picture's longer side."""
UNKNOWN = (175, 175, 175)
UNKNOWN_WALL = (130, 130, 130)
"""Walls nobody has seen yet: a shade darker than unknown free space, so the unexplored building shows."""
FREE = (255, 255, 255)
WALL = (0, 0, 0)
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
    return x / CELL_M * scale, (shape[0] - y / CELL_M) * scale


def render_rgb(core: ExplorationCore, render_px: int = RENDER_PX) -> np.ndarray:
    """``uint8[H * s, W * s, 3]`` with ``s = cell_px(map shape, render_px)``: the union of the robots' maps
    (known free white, known walls black, unknown grey, unseen walls darker grey), every robot a disc of
    its real radius (at least 4 px) with a heading line and its id."""
    sim = core.sim
    union = sim.known.max(axis=0)
    shape = union.shape
    scale = cell_px(shape, render_px)
    image = np.empty((*shape, 3), dtype=np.uint8)
    image[:] = UNKNOWN
    image[sim.truth.solid & (union == 0)] = UNKNOWN_WALL
    image[union == 1] = FREE
    image[union == 2] = WALL
    picture = Image.fromarray(np.ascontiguousarray(np.repeat(np.repeat(image[::-1], scale, 0), scale, 1)), "RGB")
    draw = ImageDraw.Draw(picture)
    radius = max(4.0, sim.motion.radius / CELL_M * scale)
    font = ImageFont.load_default(size=max(12, int(2 * radius)))
    learners = set(core.learners)
    for robot, (x, y, theta) in enumerate(np.asarray(sim.world.poses, dtype=np.float64)):
        cx, cy = world_to_pixel(x, y, shape, scale)
        colour = LEARNER if robot in learners else SCRIPTED
        draw.ellipse([cx - radius, cy - radius, cx + radius, cy + radius], fill=colour, outline=WALL)
        draw.line([cx, cy, cx + 1.8 * radius * np.cos(theta), cy - 1.8 * radius * np.sin(theta)], fill=WALL,
                  width=max(1, int(radius / 3)))
        draw.text((cx + radius + 1, cy - radius - 1), str(robot), fill=colour, font=font, anchor="lb",
                  stroke_width=1, stroke_fill=FREE)
    return np.asarray(picture, dtype=np.uint8).copy()
