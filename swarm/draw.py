"""The pictures of a run drawn in Python, by the browser viewer's rules: the GIF/MP4 animation
(:mod:`swarm.record.animation`) and the RL environments' ``render()`` (:mod:`swarm.env.render`) both draw
with these functions, and the viewer (:mod:`swarm.viewer`) is given the same colours. It sits just above
:mod:`maps` (its material colours), under every tool that draws a run.

The map layer follows the viewer's union view (``paintCell`` in ``swarm/viewer/viewer.js``): a wall in
its material's colour once anyone has seen it, faded towards the unseen-floor grey before; floor seen or
unseen. Robots are discs with a heading line, optionally a trail and an id. The viewer itself draws on a
browser canvas, so its pixels are not these; what is shared is every colour and rule, so a frame of
``render()`` reads like the viewer at that tick.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from PIL import Image, ImageDraw, ImageFont

from maps import CELL_M, Map
from maps.render import palette

ROBOT_COLOURS = [(31, 119, 180), (255, 127, 14), (44, 160, 44), (214, 39, 40), (148, 103, 189), (140, 86, 75),
                 (227, 119, 194), (127, 127, 127), (188, 189, 34), (23, 190, 207)]
"""Robot ``i`` is drawn in ``ROBOT_COLOURS[i % 10]`` (matplotlib's tab10, as the report's figures)."""
UNSEEN_FREE = (205, 205, 205)
SEEN_FREE = (252, 252, 250)
UNSEEN_WALL_FADE = 0.55
"""An unseen wall is its material's colour moved this far towards ``UNSEEN_FREE`` (the viewer's ``faded``)."""
OUTLINE = (0, 0, 0)


def mix(a: Sequence[int], b: Sequence[int], f: float) -> tuple[int, int, int]:
    """``a`` moved a fraction ``f`` towards ``b``, rounded as the viewer's ``mix`` (JavaScript's
    ``Math.round``: halves up)."""
    return tuple(int(np.floor(x + f * (y - x) + 0.5)) for x, y in zip(a, b))  # type: ignore[return-value]


def union_layer(truth: Map, seen: np.ndarray, fade_unseen_walls: bool = True) -> np.ndarray:
    """uint8[H, W, 3], row 0 at the bottom (the map's rows): the map as the viewer's union view paints it
    when ``seen`` (bool[H, W]) cells have been seen by someone. ``fade_unseen_walls=False`` draws every
    wall in full colour (the animation: the building is the backdrop)."""
    colours = palette(truth)
    rgb = colours[truth.material].copy()
    free = ~truth.solid
    rgb[free & ~seen] = UNSEEN_FREE
    rgb[free & seen] = SEEN_FREE
    if fade_unseen_walls:
        faded = np.array([mix(c, UNSEEN_FREE, UNSEEN_WALL_FADE) for c in colours.tolist()], dtype=np.uint8)
        hidden = truth.solid & ~seen
        rgb[hidden] = faded[truth.material[hidden]]
    return rgb


def to_pixel(x: float, y: float, rows: int, scale: int) -> tuple[float, float]:
    """Picture coordinates (column, row) of the world point (x, y) m on a map of ``rows`` cells, north up."""
    return x / CELL_M * scale, (rows - y / CELL_M) * scale


def draw_robots(image: Image.Image, poses: np.ndarray, rows: int, scale: int, colours: Sequence[Sequence[int]],
                radius_px: float, trails: np.ndarray | None = None, labels: bool = False) -> None:
    """Draw each robot of ``poses`` (float[N, 3]: x, y, theta) on ``image``: a disc of ``radius_px`` in
    ``colours[i]`` with a black outline and heading line; ``trails`` (float[T, N, 2], oldest first) as a
    thin line in the robot's colour; ``labels``: its id beside it, outlined in white to stay readable."""
    draw = ImageDraw.Draw(image)
    font = ImageFont.load_default(size=max(12, int(2 * radius_px))) if labels else None
    for i, (x, y, theta) in enumerate(np.asarray(poses, dtype=np.float64)):
        colour = tuple(int(v) for v in colours[i])
        if trails is not None and len(trails) > 1:
            draw.line([to_pixel(float(a), float(b), rows, scale) for a, b in trails[:, i, :2]], fill=colour, width=1)
        cx, cy = to_pixel(x, y, rows, scale)
        r = radius_px
        draw.ellipse([cx - r, cy - r, cx + r, cy + r], fill=colour, outline=OUTLINE)
        draw.line([cx, cy, cx + 1.8 * r * np.cos(theta), cy - 1.8 * r * np.sin(theta)], fill=OUTLINE,
                  width=max(2, int(r / 3)))
        if font is not None:
            draw.text((cx + r + 1, cy - r - 1), str(i), fill=colour, font=font, anchor="lb", stroke_width=1,
                      stroke_fill=SEEN_FREE)
