"""Starting poses: ``together`` (packed around one random point, MAES ``SpawnRobotsTogether``) or ``random``
(spread uniformly). Both use only cells of the largest region a robot can drive in, keep robots
``SPACING_M`` apart, and are a pure function of (map, mode, count, rng, heading). Headings are uniform at
random, or with ``heading = "maes"`` all +y as MAES spawns them (:data:`HEADING_MODES`)."""

from __future__ import annotations

from collections import deque

import numpy as np
from scipy import ndimage

from maps import CELL_M, Map
from maps.raster import FOUR, robot_space
from swarm.base.errors import InvalidInput

HEADING_MODES = ("random", "maes")
"""``random``: uniform in [-pi, pi). ``maes``: pi/2 (+y) for every robot, as MAES spawns them: ``RobotSpawner.cs``
instantiates the robot prefab (line 333) and sets only its position (350-351), so it keeps the prefab's identity
rotation (``MaesRobot2D.prefab`` line 496, ``m_LocalRotation {0, 0, 0, 1}``), and the robot's forward is its
``Transform.up`` (``Robot2DController.cs`` 195-199), world +y."""

SPACING_M = 0.7
"""Centre-to-centre distance between spawned robots: two 0.3 m radii plus 0.1 m."""


def drivable_region(truth: Map) -> np.ndarray:
    """Cells where a robot's centre fits, restricted to the largest 4-connected region."""
    space = robot_space(truth.free)
    labels, n = ndimage.label(space, structure=FOUR)
    if n == 0:
        raise InvalidInput("map", truth.summary(), "a map with room for a 0.6 m robot")
    sizes = np.bincount(labels.ravel())
    sizes[0] = 0
    return labels == int(sizes.argmax())


def spawn(truth: Map, mode: str, count: int, rng: np.random.Generator, heading: str = "random") -> np.ndarray:
    """``float64[count, 3]`` poses (x, y, heading). The random headings are drawn under ``heading = "maes"``
    too, so the generator is left where it is left by a default spawn."""
    region = drivable_region(truth)
    cells = np.argwhere(region)
    if mode == "together":
        start = tuple(cells[int(rng.integers(len(cells)))])
        order = _bfs_order(region, start)
    elif mode == "random":
        order = cells[rng.permutation(len(cells))]
    else:
        raise InvalidInput("robots.spawn", mode, "'together' | 'random'")
    chosen = _spaced(order, count)
    if len(chosen) < count:
        raise InvalidInput("robots.count", count,
                           f"at most {len(chosen)} robots fit in this map's drivable space ({SPACING_M} m apart)")
    xy = (np.asarray(chosen, dtype=np.float64)[:, ::-1] + 0.5) * CELL_M
    headings = rng.uniform(-np.pi, np.pi, size=count)
    if heading == "maes":
        headings = np.full(count, np.pi / 2)
    elif heading != "random":
        raise InvalidInput("robots.heading", heading, " | ".join(repr(m) for m in HEADING_MODES))
    return np.column_stack([xy, headings])


def _bfs_order(region: np.ndarray, start: tuple[int, int]):
    """Cells of ``region`` in breadth-first order from ``start`` (4-neighbours), lazily."""
    h, w = region.shape
    seen = np.zeros_like(region)
    seen[start] = True
    queue = deque([start])
    while queue:
        r, c = queue.popleft()
        yield (r, c)
        for dr, dc in ((-1, 0), (1, 0), (0, -1), (0, 1)):
            nr, nc = r + dr, c + dc
            if 0 <= nr < h and 0 <= nc < w and region[nr, nc] and not seen[nr, nc]:
                seen[nr, nc] = True
                queue.append((nr, nc))


def _spaced(order, count: int) -> list[tuple[int, int]]:
    """Greedily take cells in ``order`` whose centres are at least SPACING_M from those already taken.

    The cells taken so far are kept in a set and each candidate looks only at the offsets closer than the
    spacing (a swarm's 10,000 robots would otherwise compare every candidate with every robot taken)."""
    min_cells2 = (SPACING_M / 0.5) ** 2
    reach = int(np.ceil(np.sqrt(min_cells2)))
    near = [(dr, dc) for dr in range(-reach, reach + 1) for dc in range(-reach, reach + 1)
            if dr * dr + dc * dc < min_cells2]
    taken: list[tuple[int, int]] = []
    occupied: set[tuple[int, int]] = set()
    for cell in order:
        r, c = int(cell[0]), int(cell[1])
        if any((r + dr, c + dc) in occupied for dr, dc in near):
            continue
        occupied.add((r, c))
        taken.append((r, c))
        if len(taken) == count:
            break
    return taken
