"""HouseExpo floor plans (Li et al., "HouseExpo: A Large-scale 2D Indoor Layout Dataset", IROS 2020;
https://github.com/TeaganLi/HouseExpo): the JSON format's rules, rasterised onto swarm's 0.5 m cells.

A plan is one JSON object::

    {"id": "0a1b...", "room_num": 3, "bbox": {"min": [x1, y1], "max": [x2, y2]},
     "verts": [[x, y], ...],                                    # metres: ONE polygon, the free space's outline
     "room_category": {"kitchen": [[x1, y1, x2, y2], ...], ...}}  # room bounding boxes, metres

HouseExpo's own reader (``pseudoslam/envs/simulator/jsonReader.py``, lines 40-47) scales ``verts`` by
``meter2pixel`` (16 px/m in ``pseudoslam/envs/config/config.yaml``), pads the image by one pixel and fills the
polygon with ``cv2.drawContours(..., -1)``: inside is free, everything else (the outline, the slits it makes
for interior walls, the outside) is obstacle; a door is simply where the outline lets two rooms meet.

We do the same, then go to 0.5 m cells:

1. **Fine raster.** 16 px/m as HouseExpo (8 x 8 pixels per cell); a pixel is free if its centre is inside the
   polygon (even-odd rule). The map's lower-left corner is ``(min x - 0.5, min y - 0.5)`` of ``verts``: one
   cell of wall all round, and the outline's extreme edges fall on cell boundaries. ``x``/``y`` keep the
   JSON's axes (y up), so a map looks vertically flipped against HouseExpo's PNGs (image rows run down).
2. **Cells.** A cell is free only if all its 64 pixels are free (the ROS importer's rule): an interior wall
   (a slit of ~0.1-0.2 m) never leaks, but it becomes at least one cell thick.
3. **Doors.** That rule can shut a door narrower than ~1 m that does not line up with the cells. So, while
   the free cells form several regions, the wall cell that is at least half free in the fine raster, touches
   two regions, and is the most free of such cells (ties: lowest row, then column) is opened. A door cell is
   mostly free (only its jambs' corners are wall), a plain wall cell is not (a whole slit crosses it), so
   doors open first. Regions that no half-free cell joins stay separate (a sliver narrower than a cell).

**Scale.** ``scale`` multiplies every coordinate first (default 1: the plan's metres). swarm's planner needs
an opening of 3 free cells (1.5 m) for the default 0.3 m robot (:mod:`swarm.grid.cspace`), and HouseExpo's
doors are 0.8-0.9 m and many hallways 1-1.2 m: at scale 1 such a robot cannot leave its room. ``scale =
2.5`` makes every opening of 0.8 m at least 2 m, which always holds 3 whole cells (the walls, 0.1-0.2 m, grow
to 1-2 cells); :data:`EXPLORABLE_SCALE`.

Walls get one material (default ``concrete``): HouseExpo's room categories are bounding boxes of rooms, not
of walls, and a wall is shared by two rooms, so they say nothing sensible about wall materials.
"""

from __future__ import annotations

import json
import math
from typing import Any

import numpy as np

from swarm.base.errors import InvalidInput, shorten

FORMAT = "houseexpo"
PIXELS_PER_M = 16
"""HouseExpo's ``meter2pixel`` default (``pseudoslam/envs/config/config.yaml``)."""
PIXELS_PER_CELL = 8
"""0.5 m cells of 16 px/m pixels."""
MAX_BYTES = 16 * 2**20
MAX_VERTS = 20_000
"""The real plans have tens to a few hundred vertices."""
MAX_SIDE_M = 500.0
"""A house wider or longer than this is refused (HouseExpo's largest are a few tens of metres)."""
MAX_COORD_M = 1e6
MIN_FREE_TO_OPEN = 0.5
MIN_SCALE, MAX_SCALE = 0.5, 8.0
EXPLORABLE_SCALE = 2.5
"""The scale at which HouseExpo's narrowest doors (0.8 m) pass the default robot (module docstring)."""


def check_scale(scale: object, field: str = "scale") -> float:
    if (not isinstance(scale, (int, float)) or isinstance(scale, bool) or not math.isfinite(scale)
            or not MIN_SCALE <= scale <= MAX_SCALE):
        raise InvalidInput(field, scale, f"a number from {MIN_SCALE:g} to {MAX_SCALE:g} (multiplies the plan's "
                                         f"metres; {EXPLORABLE_SCALE:g} lets the default robot through 0.8 m doors)")
    return float(scale)


def parse_plan(data: bytes, source: str, scale: float = 1.0) -> dict[str, Any]:
    """The checked plan: ``verts`` (metres times ``scale``) as an (N, 2) float array, plus ``id``, ``room_num``
    and the room categories."""
    try:
        doc = json.loads(data.decode("utf-8"))
    except (UnicodeDecodeError, ValueError, RecursionError):
        raise InvalidInput("map file", source, "a HouseExpo plan: a UTF-8 JSON object with 'verts'") from None
    if not isinstance(doc, dict):
        raise InvalidInput("map file", source, "a HouseExpo plan: a JSON object with 'verts' (not a "
                                               f"{type(doc).__name__})")
    if "verts" not in doc:
        raise InvalidInput("verts", None, f"a list of [x, y] vertices in metres (missing in {shorten(source, 60)})")
    raw = doc["verts"]
    if not isinstance(raw, list) or not 3 <= len(raw) <= MAX_VERTS:
        what = f"{len(raw)} vertices" if isinstance(raw, list) else raw
        raise InvalidInput("verts", what, f"a list of 3..{MAX_VERTS} [x, y] vertices in metres")
    for i, v in enumerate(raw):
        if not (isinstance(v, list) and len(v) == 2
                and all(isinstance(c, (int, float)) and not isinstance(c, bool) for c in v)
                and all(math.isfinite(c) and abs(c) <= MAX_COORD_M for c in v)):
            raise InvalidInput(f"verts[{i}]", v, f"[x, y]: two finite numbers of metres, |value| <= {MAX_COORD_M:g}")
    verts = np.array(raw, dtype=np.float64) * scale
    if len(verts) > 3 and np.array_equal(verts[0], verts[-1]):
        verts = verts[:-1]  # a closed list repeats its first vertex
    span = verts.max(axis=0) - verts.min(axis=0)
    if span.max() > MAX_SIDE_M:
        raise InvalidInput("verts", f"{span[0]:.1f} m x {span[1]:.1f} m" + (f" at scale {scale:g}" if scale != 1 else ""),
                           f"a house of at most {MAX_SIDE_M:g} m per side")
    x, y = verts[:, 0], verts[:, 1]
    area = 0.5 * abs(float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))
    if area < 0.25 or span.min() < 0.5:
        raise InvalidInput("verts", f"{len(verts)} vertices, {span[0]:.2f} m x {span[1]:.2f} m, area {area:.3f} m2",
                           "a polygon enclosing at least one 0.5 m cell")
    categories = doc.get("room_category", {})
    if not isinstance(categories, dict):
        raise InvalidInput("room_category", categories, "a table of room category -> list of [x1, y1, x2, y2]")
    room_num = doc.get("room_num")
    if room_num is not None and (not isinstance(room_num, int) or isinstance(room_num, bool) or room_num < 0):
        raise InvalidInput("room_num", room_num, "a non-negative integer")
    plan_id = doc.get("id")
    if plan_id is not None and not isinstance(plan_id, str):
        raise InvalidInput("id", plan_id, "a string")
    return {"verts": verts, "id": plan_id, "room_num": room_num,
            "categories": sorted(str(k)[:40] for k in categories)[:50], "area_m2": area, "scale": scale}


def fine_free(verts: np.ndarray, origin: tuple[float, float], shape: tuple[int, int]) -> np.ndarray:
    """bool[rows, cols] of pixels (1/16 m, row 0 at the bottom) whose centre is inside the polygon (even-odd)."""
    rows, cols = shape
    x0, y0 = origin
    a, b = verts, np.roll(verts, -1, axis=0)
    keep = a[:, 1] != b[:, 1]                                         # horizontal edges cross no scanline
    a, b = a[keep], b[keep]
    lo, hi = np.minimum(a[:, 1], b[:, 1]), np.maximum(a[:, 1], b[:, 1])
    free = np.zeros(shape, dtype=bool)
    xs_of_cols = x0 + (np.arange(cols) + 0.5) / PIXELS_PER_M
    for r in range(rows):
        yc = y0 + (r + 0.5) / PIXELS_PER_M
        hit = (lo <= yc) & (yc < hi)                                  # half-open: a vertex counts once
        if not hit.any():
            continue
        ea, eb = a[hit], b[hit]
        xs = np.sort(ea[:, 0] + (yc - ea[:, 1]) * (eb[:, 0] - ea[:, 0]) / (eb[:, 1] - ea[:, 1]))
        # even-odd: a pixel is inside when an odd number of crossings lie left of its centre
        free[r] = (np.searchsorted(xs, xs_of_cols) % 2) == 1
    return free


def cells_from_pixels(free: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(all pixels free, fraction of pixels free) per 0.5 m cell."""
    k = PIXELS_PER_CELL
    blocks = free.reshape(free.shape[0] // k, k, free.shape[1] // k, k)
    fraction = blocks.mean(axis=(1, 3))
    return fraction == 1.0, fraction


def open_doors(cell_free: np.ndarray, fraction: np.ndarray) -> tuple[np.ndarray, int]:
    """Reopen doors the all-pixels rule shut (module docstring, step 3); returns (free cells, cells opened)."""
    from scipy import ndimage

    free = cell_free.copy()
    opened = 0
    candidates = (~free) & (fraction >= MIN_FREE_TO_OPEN)
    while True:
        labels, count = ndimage.label(free)  # 4-connected, as robots move between cells sharing a side
        if count <= 1 or not candidates.any():
            return free, opened
        padded = np.pad(labels, 1)
        neigh = np.stack([padded[:-2, 1:-1], padded[2:, 1:-1], padded[1:-1, :-2], padded[1:-1, 2:]])
        lowest = np.where(neigh > 0, neigh, np.iinfo(labels.dtype).max).min(axis=0)
        highest = neigh.max(axis=0)
        joins = candidates & (highest > 0) & (lowest < highest)       # touches two different regions
        if not joins.any():
            return free, opened
        score = np.where(joins, fraction, -1.0)
        best = np.flatnonzero(score == score.max())[0]               # ties: lowest row, then column
        r, c = divmod(int(best), free.shape[1])
        free[r, c] = True
        candidates[r, c] = False
        opened += 1


def rasterise(plan: dict[str, Any]) -> tuple[np.ndarray, dict[str, Any]]:
    """swarm's ``solid`` raster (row 0 at the bottom) of a parsed plan, and what the import records."""
    verts = plan["verts"]
    cell = PIXELS_PER_CELL / PIXELS_PER_M
    lo = verts.min(axis=0)
    origin = (float(lo[0]) - cell, float(lo[1]) - cell)
    span = verts.max(axis=0) - lo
    cols = int(math.ceil(span[0] / cell - 1e-9)) + 2
    rows = int(math.ceil(span[1] / cell - 1e-9)) + 2
    pixels = fine_free(verts, origin, (rows * PIXELS_PER_CELL, cols * PIXELS_PER_CELL))
    cell_free, fraction = cells_from_pixels(pixels)
    free, opened = open_doors(cell_free, fraction)
    if not free.any():
        raise InvalidInput("verts", f"{len(verts)} vertices, area {plan['area_m2']:.2f} m2",
                           "a polygon with room for at least one whole 0.5 m cell")
    params = {"format": FORMAT, "id": plan["id"], "room_num": plan["room_num"], "room_categories": plan["categories"],
              "origin": [round(origin[0], 6), round(origin[1], 6)], "pixels_per_m": PIXELS_PER_M,
              "doors_opened": opened, "polygon_area_m2": round(plan["area_m2"], 3), "scale": plan["scale"]}
    return ~free, params
