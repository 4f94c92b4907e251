"""The lidar: exact grid ray casting on the truth raster, writing each robot's knowledge map.

**Traversal.** Rays start at the robot's *true* pose (docs/maes.md section 5.1) and walk the 0.5 m ``truth.solid``
raster with the Amanatides-Woo DDA: the cells a ray passes through, in order, each with its *entry
distance* (0 for the robot's own cell; the distance at which the ray crosses into it). The first boundary
crossings come from the boundary coordinates, later ones add the constant spacing (classic A-W; the
rounding drift is ~1e-15 m per step, far below anything physical). When the ray passes exactly through a
cell corner it steps in x first, so it "enters" the x-neighbour for zero length: a ray never slips between
two diagonally touching solid cells.

**What a ray observes** (exact; ternary mode). A ray observes, in order, every cell it enters at a distance
``<= range_m``, up to and including the first solid cell. An observed solid cell becomes SOLID, and the
ray's range is its entry distance. An observed free cell becomes FREE iff its *centre* is within
``range_m`` of the sensor. The centre rule makes the result independent of the ray angles in open space:
with enough rays (below) an unobstructed robot sees exactly the free cells whose centre lies within range,
a disc. Writes are elementwise maxima (SOLID is sticky, as in MAES).

**Automatic ray count.** A cell of side ``s`` whose centre is at distance ``d <= R`` contains a disc of
radius ``s/2`` that subtends the open angle ``2 asin(s / 2d) >= theta = 2 asin(s / 2R)``. If consecutive
rays are less than ``theta`` apart, one of them crosses that disc and so enters the cell at a distance
``< d <= R``. Hence ``n = floor(360 deg / theta) + 1`` rays for a full circle (``floor(fov / theta) + 2``
for a sector, whose two edge rays are both cast). R = 7 m gives 88 rays. MAES uses floor(4 pi R) = 87,
which this argument does not cover; the bound is conservative (the square is wider than its inscribed
disc), and in random trials even 85 rays at 7 m skipped nothing, but only 88 comes with a proof.

**Measured ranges** (``float32[R, n_rays]``): the entry distance of the first solid cell, ``+inf`` if the
ray reaches ``range_m`` without hitting one (no return), ``NaN`` for robots that are not active.

**Settled robots** (ternary mode, ``Lidar.scan(..., measure=False)``, as the runtime scans). A robot
whose scan would write nothing is not cast. Writes are maxima of what the truth says, so a scan changes
nothing when every cell its rays can reach already holds it: free cells at least FREE, solid cells exactly
SOLID, all of them seen in the tracker. The cells checked are those within range of any point of the
robot's cell, a superset of what its rays enter, less solid cells whose four neighbours are all solid
(rays step between 4-neighbours and stop at the first solid cell, so none enters them), unless the robot
stands in one. Settled robots are those driving through rooms that they, or the robots that shared their
maps, have seen (how many on the runtime benchmark: docs/performance-history.md).

**Log-odds mode** (noisy lidar; xBOA paper section 4.1, Eqs. 5-8). The measured range is
``z = t + (noise_std + noise_per_metre * t) * N(0, 1)`` (clamped at 0; ``z > range_m`` is no return),
with the normals drawn from the ``rng`` passed to :meth:`Lidar.scan`. The inverse sensor model walks the
ray ignoring the truth: the *hit cell* is the first cell whose extent along the ray contains ``z`` (a solid
cell entered exactly at ``z`` counts, so a noise-free scan hits exactly the observed solid cell); cells
before it with centre within range are misses. Without a return every cell entered within range (centre
within range) is a miss. Each cell takes one vote per ray; per scan and robot a cell with more hit than
miss votes adds ``logodds_hit`` to its log-odds, one with more misses adds ``logodds_miss`` (Eq. 7: each
increment is the log-likelihood ratio of the observation; ties change nothing). The vote keeps the many
rays that cross a cell near the robot from counting as many independent observations (docs/boa.md
section 8.1). Values are clamped to ``[logodds_min, logodds_max]`` and classified by Eq. 8; the knowledge
map of every cell voted on is overwritten with the class when it is FREE or SOLID (evidence may flip a
cell; a cell back at "unknown" keeps what the map had). The ground-truth ``seen`` raster always follows the
exact noise-free rule above.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numba import njit
from scipy import ndimage

from maps import Map
from swarm.base.errors import InvalidInput
from swarm.base.params import OMIT_DEFAULT, check_choice, check_float, check_int
from swarm.base.types import CELL_M, FREE, SOLID
from swarm.knowledge.maps import ExplorationTracker, LogOddsGrid, active_flags
from swarm.knowledge.planes import KnowledgePlanes, no_planes, note_raise
from swarm.knowledge.tiles import TiledLayout, tile_offset
from swarm.util.jitops import opaque, select

_NO_PLANE = no_planes()[0]

__all__ = ["MODES", "ExplorationTracker", "Lidar", "LidarParams", "auto_rays", "ray_angles", "warm_up"]

MODES: tuple[str, ...] = ("ternary", "logodds")
MAX_RANGE_M = 1000.0
MAX_RAYS = 100_000


def auto_rays(range_m: float, fov_deg: float = 360.0, cell_m: float = CELL_M) -> int:
    """Fewest rays whose spacing is below ``theta = 2 asin(cell / (2 range))``, which guarantees that no
    free cell with its centre in range is skipped in open space (proof in the module docstring)."""
    theta = 2.0 * math.asin(min(1.0, cell_m / (2.0 * range_m)))
    fov = math.radians(fov_deg)
    if fov_deg >= 360.0:
        return int(math.floor(fov / theta)) + 1
    return int(math.floor(fov / theta)) + 2


def ray_angles(n_rays: int, fov_deg: float = 360.0) -> np.ndarray:
    """Ray directions relative to the heading, radians, centred on it. A full circle starts at the heading
    and spaces ``2 pi / n``; a sector spans ``[-fov/2, +fov/2]`` with both ends cast."""
    if fov_deg >= 360.0:
        out = 2.0 * np.pi * np.arange(n_rays, dtype=np.float64) / n_rays
    elif n_rays == 1:
        out = np.zeros(1, dtype=np.float64)
    else:
        half = math.radians(fov_deg) / 2.0
        out = np.linspace(-half, half, n_rays, dtype=np.float64)
    out.setflags(write=False)
    return out


@dataclass(frozen=True)
class LidarParams:
    """Lidar configuration (the ``[lidar]`` section of a run spec).

    ``range_m`` 7 m is the MAES campaign value; ``rays = None`` picks :func:`auto_rays`. Noise needs
    ``mode = "logodds"``: a ternary map cannot unlearn a false wall (SOLID is sticky). The log-odds
    defaults are the reference reconstruction's (docs/boa.md section 8.1; the paper gives no sensor
    probabilities): +0.85 per hit and -0.4 per miss, i.e. log(0.7/0.3) and log(0.4/0.6) rounded, the usual
    inverse sensor model with p(occupied | hit) = 0.7 and p(occupied | miss) = 0.4; clamped at +-5;
    thresholds 0 as in the paper's Eq. 8 (log-odds 0 is the prior p = 0.5).

    ``robots_occlude`` (ternary mode): other robots' discs stop the rays (a robot hides what is behind it)
    without entering the map: a ray that ends on a robot writes the free cells before it and nothing else.
    """

    range_m: float = 7.0
    fov_deg: float = 360.0
    rays: int | None = None
    noise_std: float = 0.0
    noise_per_metre: float = 0.0
    mode: str = "ternary"
    logodds_hit: float = 0.85
    logodds_miss: float = -0.4
    logodds_min: float = -5.0
    logodds_max: float = 5.0
    logodds_occupied_above: float = 0.0
    logodds_free_below: float = 0.0
    robots_occlude: bool = field(default=False, metadata={OMIT_DEFAULT: True})

    def __post_init__(self) -> None:
        def put(name: str, value: object) -> None:
            object.__setattr__(self, name, value)   # normalise ints from TOML to floats: stable spec hashes

        put("range_m", check_float("range_m", self.range_m, 0.0, MAX_RANGE_M, lo_open=True))
        put("fov_deg", check_float("fov_deg", self.fov_deg, 0.0, 360.0, lo_open=True))
        if self.rays is not None:
            check_int("rays", self.rays, 1, MAX_RAYS)
        put("noise_std", check_float("noise_std", self.noise_std, 0.0))
        put("noise_per_metre", check_float("noise_per_metre", self.noise_per_metre, 0.0))
        check_choice("mode", self.mode, MODES)
        put("logodds_hit", check_float("logodds_hit", self.logodds_hit, 0.0, lo_open=True))
        put("logodds_miss", check_float("logodds_miss", self.logodds_miss, hi=0.0, hi_open=True))
        put("logodds_max", check_float("logodds_max", self.logodds_max, 0.0, lo_open=True))
        put("logodds_min", check_float("logodds_min", self.logodds_min, hi=0.0, hi_open=True))
        # Both classes must stay reachable inside the clamp: min < free_below <= occupied_above < max.
        put("logodds_free_below", check_float("logodds_free_below", self.logodds_free_below,
                                              self.logodds_min, self.logodds_max, lo_open=True, hi_open=True))
        put("logodds_occupied_above", check_float("logodds_occupied_above", self.logodds_occupied_above,
                                                  self.logodds_free_below, self.logodds_max, hi_open=True))
        if not isinstance(self.robots_occlude, bool):
            raise InvalidInput("robots_occlude", self.robots_occlude, "true or false")
        if self.robots_occlude and self.mode != "ternary":
            raise InvalidInput("robots_occlude", True, "false with mode = 'logodds' (robots occlude the ternary "
                                                       "lidar only)")
        if self.mode == "ternary":
            for name in ("noise_std", "noise_per_metre"):
                if getattr(self, name) != 0.0:
                    raise InvalidInput(name, getattr(self, name),
                                       "0 in mode 'ternary' (noisy ranges need mode = 'logodds')")

    @property
    def n_rays(self) -> int:
        """``rays``, or the automatic count for this range and field of view."""
        return self.rays if self.rays is not None else auto_rays(self.range_m, self.fov_deg)

    @property
    def noisy(self) -> bool:
        return self.noise_std > 0.0 or self.noise_per_metre > 0.0


# ------------------------------------------------------------------------------------------ kernels
@njit(cache=True)
def _lidar_first_bad_pose(poses: np.ndarray, active: np.ndarray, rows: int, cols: int, cell: float) -> int:
    """Index of the first active robot whose pose is not finite or not inside the map, else -1."""
    for r in range(poses.shape[0]):
        if active[r]:
            x = poses[r, 0]
            y = poses[r, 1]
            if not (x >= 0.0 and x < cols * cell and y >= 0.0 and y < rows * cell and np.isfinite(poses[r, 2])):
                return r
    return -1


@njit(cache=True)
def _lidar_ray_start(x: float, y: float, dx: float, dy: float,
                     cell: float) -> tuple[int, int, int, int, float, float, float, float]:
    """Amanatides-Woo set-up of a ray from (x, y) along the unit vector (dx, dy): its cell (row, col), the
    steps (+-1 or 0), the distances to the first column and row boundaries (inf if never crossed) and the
    distances between boundaries. Both walks use this, so they compute bit-identical crossing times."""
    col = int(math.floor(x / cell))
    row = int(math.floor(y / cell))
    step_c, t_x, d_x = 0, np.inf, 0.0
    if dx != 0.0:
        step_c = 1 if dx > 0.0 else -1
        t_x = ((col + (1 if dx > 0.0 else 0)) * cell - x) / dx
        d_x = cell / abs(dx)
    step_r, t_y, d_y = 0, np.inf, 0.0
    if dy != 0.0:
        step_r = 1 if dy > 0.0 else -1
        t_y = ((row + (1 if dy > 0.0 else 0)) * cell - y) / dy
        d_y = cell / abs(dy)
    return row, col, step_r, step_c, t_x, t_y, d_x, d_y


@njit(cache=True, inline="always")
def _lidar_advance(t_x: float, t_y: float, d_x: float, d_y: float) -> tuple[bool, float, float]:
    """One Amanatides-Woo step of the two boundary distances: whether the ray crosses a column boundary
    next (``t_x <= t_y``), and the distances after the step: the crossed one moves on by its spacing, the
    other gets ``+ 0.0``. These are the float operations of ``t_x += d_x * in_x; t_y += d_y * (1 - in_x)``
    with a 0/1 ``in_x``, value for value, but picked by two selects
    (:mod:`swarm.util.jitops`): the walk's loop-carried chain is then compare -> select, not compare ->
    convert -> multiply -> add, which bound the walk (the 16-robot scan is ~25 % faster, measured)."""
    in_x = t_x <= t_y
    n_x = opaque(t_x + d_x)
    z_x = opaque(t_x + 0.0)
    n_y = opaque(t_y + d_y)
    z_y = opaque(t_y + 0.0)
    return in_x, select(in_x, n_x, z_x), select(in_x, z_y, n_y)


@njit(cache=True, inline="always")
def _note_own_sight(own: np.ndarray, i: int, seers: np.ndarray, at: np.uint64) -> int:
    """Mark cell ``at`` seen by a robot's own lidar (bit ``i`` of the flat uint64 mask ``own``); returns 1 on
    the robot's first own sighting of it, which also counts in ``seers[at]``. Branch-free: a compare-and-write
    here made the walk three times slower (measured); at most 65,535 robots
    (:meth:`ExplorationTracker.track_robots`), so the uint16 count cannot overflow."""
    o = np.uint64(i)
    w = o >> np.uint64(6)
    b = o & np.uint64(63)
    word = own[w]
    first = np.int64(((word >> b) & np.uint64(1)) ^ np.uint64(1))
    own[w] = word | (np.uint64(1) << b)
    seers[at] += first
    return first


@njit(cache=True, inline="always")
def _own_bit(own: np.ndarray, i: int) -> int:  # pragma: no cover - compiled
    """Bit ``i`` of the flat uint64 own-sight mask ``own``."""
    o = np.uint64(i)
    return np.int64((own[o >> np.uint64(6)] >> (o & np.uint64(63))) & np.uint64(1))


@njit(cache=True, inline="always")
def _lidar_walk_visible(solid: np.ndarray, cols: int, known: np.ndarray, known_base: int, write_known: bool,
                        seen: np.ndarray, x: float, y: float, dx: float, dy: float, range_m: float,
                        cell: float, p_free: np.ndarray, p_solid: np.ndarray, robot: int, own: np.ndarray,
                        own_base: int, seers: np.ndarray, own_cells: np.ndarray,
                        tiles_w: int = 0) -> tuple[float, int, int]:
    """Walk one ray by the exact rule (module docstring). ``solid``, ``seen`` and ``known`` are flat views
    of the rasters, ``cols`` wide (``known`` of all robots: this robot's map starts at ``known_base``).
    Marks ``seen`` (and the robot's map with a maximum when ``write_known``); returns (entry distance of
    the first solid cell or inf, newly seen free cells, cells of the robot's map it turned FREE). Needs a solid outer edge, which :class:`maps.Map`
    guarantees, to stay on the raster; indices are unsigned, so no negative-index code is compiled. With
    planes (``p_free`` not empty, :mod:`swarm.knowledge.planes`) every cell it raises in robot ``robot``'s
    map is noted there too. With an own-sight mask (``own`` not empty: flat, this robot's mask from
    ``own_base``; :meth:`~swarm.knowledge.maps.ExplorationTracker.track_robots`) every cell marked in ``seen``
    is marked in it too, and a first own sighting counts in ``own_cells[robot]`` and ``seers``. ``tiles_w``
    above 0: ``known`` holds tiled maps that many tiles wide (:mod:`swarm.knowledge.tiles`)."""
    planes = p_free.shape[0] > 0
    tracking = own.shape[0] > 0
    mine = 0
    row, col, step_r, step_c, t_x, t_y, d_x, d_y = _lidar_ray_start(x, y, dx, dy, cell)
    r2 = range_m * range_m
    t_entry = 0.0
    new = 0
    fresh = 0
    # A cell entered at t has its centre within t + cell / sqrt(2): no need to measure it that early.
    sure = range_m - 0.7072 * cell
    k = row * cols + col
    step_k = step_r * cols
    while True:
        at = np.uint64(k)
        mine_at = np.uint64(known_base + (k if tiles_w == 0 else tile_offset(row, col, tiles_w)))
        if solid[at]:
            if write_known:
                if planes and known[mine_at] != SOLID:
                    note_raise(p_free, p_solid, k, robot, SOLID)
                known[mine_at] = SOLID
            seen[at] = True
            if tracking:
                own_cells[robot] += mine + _note_own_sight(own, own_base + k, seers, at)
            return t_entry, new, fresh
        if t_entry <= sure:
            in_range = True
        else:
            cx = (col + 0.5) * cell - x
            cy = (row + 0.5) * cell - y
            in_range = cx * cx + cy * cy <= r2
        if in_range:
            if write_known and known[mine_at] < FREE:
                known[mine_at] = FREE
                fresh += 1
                if planes:
                    note_raise(p_free, p_solid, k, robot, FREE)
            if not seen[at]:
                seen[at] = True
                new += 1
            if tracking:
                mine += _note_own_sight(own, own_base + k, seers, at)
        t_entry = min(t_x, t_y)
        in_x, t_x, t_y = _lidar_advance(t_x, t_y, d_x, d_y)
        col = select(in_x, col + step_c, col)
        row = select(in_x, row, row + step_r)
        k = select(in_x, k + step_c, k + step_k)
        if t_entry > range_m:
            if tracking:
                own_cells[robot] += mine
            return np.inf, new, fresh


@njit(cache=True)
def _lidar_ternary_kernel(solid: np.ndarray, poses: np.ndarray, active: np.ndarray, cos_a: np.ndarray,
                          sin_a: np.ndarray, range_m: float, cell: float, known: np.ndarray,
                          seen: np.ndarray, ranges: np.ndarray, required: np.ndarray, half_widths: np.ndarray,
                          cast: np.ndarray, fresh: np.ndarray, p_free: np.ndarray, p_solid: np.ndarray,
                          own: np.ndarray, seers: np.ndarray, own_cells: np.ndarray, tiles_w: int = 0) -> int:
    """One tick of the ternary lidar for every robot and ray. Returns the number of newly seen free
    cells, or ``-(r + 1)`` (nothing written) if robot r's pose is invalid. With a ``required`` raster
    (:func:`_required_raster`; empty: cast every robot) a robot whose scan would write nothing
    (:func:`_lidar_settled`) is not cast: its ranges are NaN and ``cast[r]`` is False (True for robots
    cast). ``fresh[r]`` grows by the cells of robot r's map the scan turned from UNSEEN to FREE. ``own``,
    ``seers``, ``own_cells``: the tracker's own-sight buffers (empty: not kept); kept, a robot is settled only
    if its own lidar has also seen every cell in reach. ``tiles_w`` above 0: ``known`` is a tiled stack
    ``uint8[R, size]`` that many tiles wide (:mod:`swarm.knowledge.tiles`)."""
    rows, cols = solid.shape
    bad = _lidar_first_bad_pose(poses, active, rows, cols, cell)
    if bad >= 0:
        return -(bad + 1)
    solid_flat, known_flat, seen_flat = solid.reshape(solid.size), known.reshape(known.size), seen.reshape(seen.size)
    own_flat, seers_flat, own_bits = own.reshape(own.size), seers.reshape(seers.size), own.shape[1] * 64
    skip_settled = required.shape[0] == rows
    required_flat = required.reshape(required.size)
    map_cells = rows * cols if tiles_w == 0 else known.shape[1]
    new = 0
    for r in range(poses.shape[0]):
        cast[r] = False
        if not active[r]:
            for i in range(cos_a.shape[0]):
                ranges[r, i] = np.nan
            continue
        x = poses[r, 0]
        y = poses[r, 1]
        if skip_settled and _lidar_settled(required_flat, known_flat, r * map_cells, seen_flat, rows, cols,
                                           int(math.floor(y / cell)), int(math.floor(x / cell)), half_widths,
                                           own_flat, r * own_bits, tiles_w):
            for i in range(cos_a.shape[0]):
                ranges[r, i] = np.nan
            continue
        cast[r] = True
        ch = math.cos(poses[r, 2])
        sh = math.sin(poses[r, 2])
        for i in range(cos_a.shape[0]):
            dx = ch * cos_a[i] - sh * sin_a[i]
            dy = sh * cos_a[i] + ch * sin_a[i]
            t_hit, n_new, n_fresh = _lidar_walk_visible(solid_flat, cols, known_flat, r * map_cells, True,
                                                        seen_flat, x, y, dx, dy, range_m, cell, p_free, p_solid, r,
                                                        own_flat, r * own_bits, seers_flat, own_cells, tiles_w)
            new += n_new
            fresh[r] += n_fresh
            ranges[r, i] = t_hit
    return new


@njit(cache=True)
def _lidar_measure_kernel(solid: np.ndarray, poses: np.ndarray, active: np.ndarray, cos_a: np.ndarray,
                          sin_a: np.ndarray, range_m: float, cell: float, seen: np.ndarray,
                          ranges: np.ndarray, limits: np.ndarray, own: np.ndarray, seers: np.ndarray,
                          own_cells: np.ndarray) -> int:
    """The ternary lidar's ranges and ``seen`` cells for every active robot, nothing written into a map (a
    robot with a localisation error writes them from its estimated pose: :func:`_lidar_belief_kernel`).
    ``limits`` (``float64[R, n_rays]``, or empty: none): a ray reaches no further than its limit (another
    robot in the way). Returns the newly seen free cells, or ``-(r + 1)`` if robot r's pose is invalid."""
    rows, cols = solid.shape
    bad = _lidar_first_bad_pose(poses, active, rows, cols, cell)
    if bad >= 0:
        return -(bad + 1)
    solid_flat, seen_flat = solid.reshape(solid.size), seen.reshape(seen.size)
    own_flat, seers_flat, own_bits = own.reshape(own.size), seers.reshape(seers.size), own.shape[1] * 64
    unused = np.zeros(1, dtype=np.uint8)
    p_none = np.zeros((0, 1), dtype=np.uint64)
    limited = limits.shape[0] > 0
    new = 0
    for r in range(poses.shape[0]):
        if not active[r]:
            for i in range(cos_a.shape[0]):
                ranges[r, i] = np.nan
            continue
        ch = math.cos(poses[r, 2])
        sh = math.sin(poses[r, 2])
        for i in range(cos_a.shape[0]):
            dx = ch * cos_a[i] - sh * sin_a[i]
            dy = sh * cos_a[i] + ch * sin_a[i]
            reach = min(range_m, limits[r, i]) if limited else range_m
            t_hit, n_new, _ = _lidar_walk_visible(solid_flat, cols, unused, 0, False, seen_flat, poses[r, 0],
                                                  poses[r, 1], dx, dy, reach, cell, p_none, p_none, r, own_flat,
                                                  r * own_bits, seers_flat, own_cells)
            new += n_new
            ranges[r, i] = t_hit
    return new


@njit(cache=True)
def _lidar_belief_kernel(poses: np.ndarray, ranges: np.ndarray, cos_a: np.ndarray, sin_a: np.ndarray,
                         range_m: float, cell: float, known: np.ndarray, limits: np.ndarray) -> int:
    """Write measured ``ranges`` into each robot's map from the pose it believes it has (``poses``): along
    each ray (its angle relative to the believed heading), the cells entered before the range whose centre
    is within ``range_m`` become at least FREE and the cell holding the range point SOLID; with no return
    (inf) every cell entered within range with its centre within range becomes at least FREE; a NaN range
    (robot not active) writes nothing. Rays stop at the map's edge. A robot whose believed position is off
    the map writes nothing. From the true pose this writes exactly what the ternary lidar writes (the same
    walk, the same crossing distances). ``limits`` (as :func:`_lidar_measure_kernel`'s) shorten rays that
    ended on another robot. Returns the number of robots that wrote nothing for being off the map."""
    n_robots, rows, cols = known.shape
    limited = limits.shape[0] > 0
    off = 0
    for r in range(n_robots):
        x = poses[r, 0]
        y = poses[r, 1]
        if not (x >= 0.0 and x < cols * cell and y >= 0.0 and y < rows * cell and np.isfinite(poses[r, 2])):
            if not np.isnan(ranges[r, 0]):
                off += 1
            continue
        ch = math.cos(poses[r, 2])
        sh = math.sin(poses[r, 2])
        mine = known[r]
        for i in range(cos_a.shape[0]):
            z = ranges[r, i]
            if np.isnan(z):
                continue
            reach = min(range_m, limits[r, i]) if limited else range_m
            r2 = reach * reach
            dx = ch * cos_a[i] - sh * sin_a[i]
            dy = sh * cos_a[i] + ch * sin_a[i]
            row, col, step_r, step_c, t_x, t_y, d_x, d_y = _lidar_ray_start(x, y, dx, dy, cell)
            t_entry = 0.0
            while 0 <= row < rows and 0 <= col < cols:
                t_exit = min(t_x, t_y)
                if t_entry > reach:
                    break
                if z <= t_entry or (z < t_exit and np.isfinite(z)):
                    mine[row, col] = SOLID       # the cell whose extent along the ray holds the range point
                    break
                cx = (col + 0.5) * cell - x
                cy = (row + 0.5) * cell - y
                if cx * cx + cy * cy <= r2 and mine[row, col] < FREE:
                    mine[row, col] = FREE
                in_x, t_x, t_y = _lidar_advance(t_x, t_y, d_x, d_y)
                t_entry = t_exit
                if in_x:
                    col += step_c
                else:
                    row += step_r
    return off


@njit(cache=True, inline="always")
def _lidar_settled(required: np.ndarray, known: np.ndarray, known_base: int, seen: np.ndarray, rows: int,
                   cols: int, row0: int, col0: int, half_widths: np.ndarray, own: np.ndarray, own_base: int,
                   tiles_w: int = 0) -> bool:
    """Whether a ternary scan from a pose in cell (row0, col0) would write nothing: every cell its rays
    can reach (the cells within range of any point of the robot's cell, rows ``row0 - K .. row0 + K`` with
    ``half_widths[k]`` columns each side) already holds what a ray would leave there, in the robot's map
    (``known`` from ``known_base``) and in ``seen``. ``required`` (flat): 1 for a free cell (the ray leaves
    it at least FREE), 2 for a solid cell a ray can enter (it becomes exactly SOLID), 0 for a solid cell
    enclosed by solid 4-neighbours, which no ray enters (rays step 4-connected and stop at the first solid
    cell). A robot in a solid cell (``required`` not 1) writes it at distance 0, so it is never settled.
    Flat views, as in :func:`_lidar_walk_visible`. With an own-sight mask (``own`` not empty: flat uint64
    bits, this robot's from bit ``own_base``) every such cell must also be marked in it, so a robot crossing
    cells only others saw is cast."""
    if required[row0 * cols + col0] != 1:
        return False
    reach = (half_widths.shape[0] - 1) // 2
    for k in range(half_widths.shape[0]):
        row = row0 - reach + k
        if row < 0 or row >= rows:
            continue
        lo = max(col0 - half_widths[k], 0)
        hi = min(col0 + half_widths[k] + 1, cols)
        a = row * cols + lo
        b = row * cols + hi
        req, was_seen = required[a:b], seen[a:b]
        unsettled = False
        if tiles_w == 0:
            mine = known[known_base + a:known_base + b]
            for c in range(b - a):  # branch-free on slices (no index arithmetic), so the row's test vectorises
                q = req[c]
                m = mine[c]
                unsettled |= (m < q) | ((q == 2) & (m != 2)) | ((q != 0) & (was_seen[c] == 0))
        else:
            for c in range(b - a):
                q = req[c]
                m = known[known_base + tile_offset(row, lo + c, tiles_w)]
                unsettled |= (m < q) | ((q == 2) & (m != 2)) | ((q != 0) & (was_seen[c] == 0))
        if not unsettled and own.shape[0] > 0:
            for c in range(b - a):
                unsettled |= (req[c] != 0) & (_own_bit(own, own_base + a + c) == 0)
        if unsettled:
            return False
    return True


@njit(cache=True, inline="always")
def _lidar_walk_votes(solid: np.ndarray, x: float, y: float, dx: float, dy: float, z: float,
                      t_hit: float, range_m: float, cell: float, votes: np.ndarray, mark: np.ndarray,
                      touched: np.ndarray, n_touched: int) -> int:
    """Inverse-sensor-model votes of one ray with measured range ``z`` (inf = no return); see the module
    docstring. Walks regardless of the truth (noise may carry a ray into a wall), stopping at the raster
    edge. Returns the new length of ``touched``."""
    rows, cols = solid.shape
    row, col, step_r, step_c, t_x, t_y, d_x, d_y = _lidar_ray_start(x, y, dx, dy, cell)
    r2 = range_m * range_m
    limit = z if z <= range_m else range_m
    t_entry = 0.0
    while True:
        t_next = t_x if t_x <= t_y else t_y
        hit = z <= range_m and (z < t_next or (z == t_hit and t_entry == t_hit and solid[row, col]))
        vote = 0
        if hit:
            vote = 1
        else:
            cx = (col + 0.5) * cell - x
            cy = (row + 0.5) * cell - y
            if cx * cx + cy * cy <= r2:
                vote = -1
        if vote != 0:
            if not mark[row, col]:
                mark[row, col] = True
                touched[n_touched] = row * cols + col
                n_touched += 1
            votes[row, col] += vote
        if hit:
            return n_touched
        t_entry = min(t_x, t_y)
        in_x, t_x, t_y = _lidar_advance(t_x, t_y, d_x, d_y)
        col = select(in_x, col + step_c, col)
        row = select(in_x, row, row + step_r)
        if t_entry > limit or row < 0 or row >= rows or col < 0 or col >= cols:
            return n_touched


@njit(cache=True)
def _lidar_logodds_kernel(solid: np.ndarray, poses: np.ndarray, active: np.ndarray, cos_a: np.ndarray,
                          sin_a: np.ndarray, range_m: float, cell: float, noise: np.ndarray,
                          noise_std: float, noise_per_metre: float, logodds: np.ndarray, hit: float,
                          miss: float, lo: float, hi: float, occupied_above: float, free_below: float,
                          known: np.ndarray, seen: np.ndarray, ranges: np.ndarray, votes: np.ndarray,
                          mark: np.ndarray, touched: np.ndarray, vote_poses: np.ndarray, own: np.ndarray,
                          seers: np.ndarray, own_cells: np.ndarray) -> int:
    """One tick of the log-odds lidar for every robot and ray (``noise``: standard normals [R, n_rays],
    ignored when both noise parameters are 0). Returns newly seen free cells or ``-(r + 1)``. Ranges are
    measured from ``poses`` and voted along rays from ``vote_poses`` (where the robots believe they are:
    ``poses`` itself without a localisation error); a robot that believes itself off the map votes nothing."""
    rows, cols = solid.shape
    bad = _lidar_first_bad_pose(poses, active, rows, cols, cell)
    if bad >= 0:
        return -(bad + 1)
    solid_flat, known_flat, seen_flat = solid.reshape(solid.size), known.reshape(known.size), seen.reshape(seen.size)
    own_flat, seers_flat, own_bits = own.reshape(own.size), seers.reshape(seers.size), own.shape[1] * 64
    noisy = noise_std > 0.0 or noise_per_metre > 0.0
    hit32 = np.float32(hit)
    miss32 = np.float32(miss)
    lo32 = np.float32(lo)
    hi32 = np.float32(hi)
    occ32 = np.float32(occupied_above)
    free32 = np.float32(free_below)
    new = 0
    for r in range(poses.shape[0]):
        if not active[r]:
            for i in range(cos_a.shape[0]):
                ranges[r, i] = np.nan
            continue
        x = poses[r, 0]
        y = poses[r, 1]
        ch = math.cos(poses[r, 2])
        sh = math.sin(poses[r, 2])
        bx = vote_poses[r, 0]
        by = vote_poses[r, 1]
        bch = math.cos(vote_poses[r, 2])
        bsh = math.sin(vote_poses[r, 2])
        votes_on = bx >= 0.0 and bx < cols * cell and by >= 0.0 and by < rows * cell and np.isfinite(vote_poses[r, 2])
        n_touched = 0
        for i in range(cos_a.shape[0]):
            dx = ch * cos_a[i] - sh * sin_a[i]
            dy = sh * cos_a[i] + ch * sin_a[i]
            t_hit, n_new, _ = _lidar_walk_visible(solid_flat, cols, known_flat, r * rows * cols, False, seen_flat,
                                                  x, y, dx, dy, range_m, cell, _NO_PLANE, _NO_PLANE, r,
                                                  own_flat, r * own_bits, seers_flat, own_cells)
            new += n_new
            z = t_hit
            if noisy and t_hit <= range_m:
                z = t_hit + (noise_std + noise_per_metre * t_hit) * noise[r, i]
                if z < 0.0:
                    z = 0.0
                if z > range_m:
                    z = np.inf
            ranges[r, i] = z
            if votes_on:
                n_touched = _lidar_walk_votes(solid, bx, by, bch * cos_a[i] - bsh * sin_a[i],
                                              bsh * cos_a[i] + bch * sin_a[i], z, t_hit, range_m, cell, votes, mark,
                                              touched, n_touched)
        for k in range(n_touched):
            row = touched[k] // cols
            col = touched[k] % cols
            v = votes[row, col]
            votes[row, col] = 0
            mark[row, col] = False
            if v == 0:
                continue
            value = logodds[r, row, col]
            if v > 0:
                value = min(value + hit32, hi32)
            else:
                value = max(value + miss32, lo32)
            logodds[r, row, col] = value
            if value > occ32:
                known[r, row, col] = SOLID
            elif value < free32:
                known[r, row, col] = FREE
    return new


_NO_LIMITS = np.zeros((0, 0), dtype=np.float64)
"""The ``limits`` that limit nothing (robots do not occlude)."""


@njit(cache=True)
def _lidar_occlusion_kernel(poses: np.ndarray, active: np.ndarray, pairs: np.ndarray, cos_a: np.ndarray,
                            sin_a: np.ndarray, radius: float, out: np.ndarray) -> None:  # pragma: no cover
    """For each pair (a, b) both ways: where each of a's rays first meets b's disc (the smaller root of
    ``|p + t d - c|^2 = radius^2``, t > 0), kept in ``out[a, i]`` if nearer than what is there. Inactive
    robots still occlude (a failed robot stands where it stopped)."""
    r2 = radius * radius
    for k in range(pairs.shape[0]):
        for side in range(2):
            a = pairs[k, side]
            b = pairs[k, 1 - side]
            if not active[a]:
                continue
            ox = poses[b, 0] - poses[a, 0]
            oy = poses[b, 1] - poses[a, 1]
            c = ox * ox + oy * oy - r2
            if c <= 0.0:
                continue   # overlapping discs (a collision): no ray of a starts outside b
            ch = math.cos(poses[a, 2])
            sh = math.sin(poses[a, 2])
            for i in range(cos_a.shape[0]):
                dx = ch * cos_a[i] - sh * sin_a[i]
                dy = sh * cos_a[i] + ch * sin_a[i]
                bb = dx * ox + dy * oy
                if bb <= 0.0:
                    continue
                disc = bb * bb - c
                if disc < 0.0:
                    continue
                t = bb - math.sqrt(disc)
                if t < out[a, i]:
                    out[a, i] = t


_CAST_EVERY_ROBOT = np.zeros((0, 0), dtype=np.uint8)
"""The ``required`` raster that asks the ternary kernel to cast every active robot (``measure=True``)."""


def _required_raster(solid: np.ndarray) -> np.ndarray:
    """``uint8[H, W]`` for :func:`_lidar_settled`: 1 for free cells, 2 for solid cells with a free
    4-neighbour, 0 for solid cells whose 4-neighbours are all solid (the map's outside counts as solid)."""
    s = np.asarray(solid, dtype=bool)
    enclosed = ndimage.binary_erosion(s, structure=ndimage.generate_binary_structure(2, 1), border_value=1)
    required = np.where(s, 2, 1).astype(np.uint8)
    required[enclosed] = 0
    return required


def _reach_half_widths(range_m: float, cell: float) -> np.ndarray:
    """Columns each side of the robot's cell, per row offset ``-K .. K``, of the cells a ray may enter within
    ``range_m``: those with a point within range of some point of the robot's cell (cell gaps
    ``(|dr| - 1)+, (|dc| - 1)+``), with a relative margin of 1e-9 for the walk's rounding (~1e-15 m a step)."""
    reach = (range_m * (1.0 + 1e-9)) / cell
    k = int(math.floor(reach)) + 1
    widths = np.empty(2 * k + 1, dtype=np.int64)
    for i, dr in enumerate(range(-k, k + 1)):
        gap_r = max(abs(dr) - 1, 0)
        widths[i] = int(math.floor(math.sqrt(max(reach * reach - gap_r * gap_r, 0.0)))) + 1
    return widths


# ------------------------------------------------------------------------------------------- sensor
class Lidar:
    """The swarm's lidars on one truth map: one :meth:`scan` per tick casts every robot's rays in a single
    numba kernel call. See the module docstring for the exact semantics.

    ``tracker`` receives the ground-truth ``seen`` cells; by default the lidar makes its own
    (:attr:`tracker`); :meth:`scan` may also be handed one per call. :class:`ExplorationTracker` lives in
    :mod:`swarm.knowledge.maps` and is re-exported here. In log-odds mode :attr:`logodds` holds the per-robot
    belief once the first scan has fixed the number of robots.
    """

    def __init__(self, truth: Map, params: LidarParams | None = None,
                 tracker: ExplorationTracker | None = None) -> None:
        self.truth = truth
        self.params = params if params is not None else LidarParams()
        self.tracker = self._check_tracker(tracker) if tracker is not None else ExplorationTracker(truth)
        self.n_rays: int = self.params.n_rays
        self.angles: np.ndarray = ray_angles(self.n_rays, self.params.fov_deg)
        self._cos = np.ascontiguousarray(np.cos(self.angles))
        self._sin = np.ascontiguousarray(np.sin(self.angles))
        self._solid = np.ascontiguousarray(truth.solid, dtype=np.uint8).copy()  # writable: one numba type
        self.logodds: LogOddsGrid | None = None
        self._votes = np.zeros(0, dtype=np.int32)
        self._mark = np.zeros(0, dtype=np.bool_)
        self._touched = np.zeros(0, dtype=np.int64)
        self._no_noise = np.zeros((1, 1), dtype=np.float64)
        self._required = np.zeros((0, 0), dtype=np.uint8)   # built on the first scan that skips settled robots
        self._half_widths = _reach_half_widths(self.params.range_m, CELL_M)
        self._cast = np.zeros(0, dtype=np.bool_)
        self._freed = np.zeros(0, dtype=np.int64)  # the counts nobody asked for (``scan(freed=None)``)

    @property
    def shape(self) -> tuple[int, int]:
        return self.truth.shape

    def scan(self, poses: np.ndarray, known: np.ndarray, rng: np.random.Generator | None = None,
             active: np.ndarray | None = None, tracker: ExplorationTracker | None = None, *,
             measure: bool = True, freed: np.ndarray | None = None,
             planes: KnowledgePlanes | None = None, write: bool = True,
             write_poses: np.ndarray | None = None, limits: np.ndarray | None = None) -> np.ndarray | None:
        """Cast every active robot's rays from ``poses`` (``float64[R, 3]``: x, y, theta) and write what
        they observe into ``known`` (``uint8[R, H, W]``, C-contiguous, modified in place) and into the
        tracker (``tracker`` if given, else :attr:`tracker`). Returns the measured ranges
        ``float32[R, n_rays]`` (inf = no return, NaN = inactive). ``rng`` is required when the lidar is
        noisy; it is used only then.

        ``measure=False`` is for callers that only want the maps written (the runtime): it returns None,
        and in ternary mode a robot whose scan provably writes nothing is not cast. That is a robot every
        cell of whose reach (the cells within range of any point of its cell) already holds what a ray
        would leave there, in its map and in the tracker; about a third of the robot-ticks of the
        16-robot benchmark, which travel through explored rooms. The maps and the tracker end exactly as
        with every robot cast. :attr:`cast` tells which robots were.

        ``freed`` (``int64[R]``, ternary mode): ``freed[r]`` grows by the cells of robot r's map this scan
        turned from UNSEEN to FREE, so a caller can keep each map's count of free cells without reading the
        maps (:class:`swarm.results.metrics.FreeCounts`).

        ``planes`` (ternary mode): the knowledge planes of ``known`` (:mod:`swarm.knowledge.planes`), which the
        scan keeps up to date with every cell it raises.

        ``write=False`` (ternary mode): measure only (the ranges, as float64, and the tracker's seen cells),
        every active robot cast, ``known`` untouched: for robots that write from an estimated pose
        (:meth:`write_from`). ``write_poses`` (log-odds mode): vote along the rays from these poses instead,
        where the robots believe they are (the ranges are still measured from ``poses``). ``limits``
        (``write=False``): how far each ray may reach (:meth:`occlusion`)."""
        trk = self.tracker if tracker is None else self._check_tracker(tracker)
        pose = np.ascontiguousarray(poses, dtype=np.float64)
        if pose.ndim != 2 or pose.shape[1] != 3:
            raise InvalidInput("poses", pose.shape, "an array of shape (R, 3): x, y (m), theta (rad)")
        n = pose.shape[0]
        tiles_w = self._check_known(known, n)
        if tiles_w and (self.params.mode != "ternary" or not write):
            raise InvalidInput("known", "tiled maps", f"dense maps for a {self.params.mode} lidar"
                               f"{'' if write else ' measuring without writing'}")
        act = active_flags(n, active)
        ranges = np.empty((n, self.n_rays), dtype=np.float32)
        p = self.params
        if self._cast.shape[0] != n:
            self._cast = np.zeros(n, dtype=np.bool_)
            self._freed = np.zeros(n, dtype=np.int64)
        if freed is not None and (freed.dtype != np.int64 or freed.shape != (n,)):
            raise InvalidInput("freed", (freed.dtype, freed.shape), f"an int64 array of shape ({n},)")
        if not write:
            if p.mode != "ternary" or planes is not None:
                raise InvalidInput("write", write, "True unless the lidar is ternary and no planes are given")
            ranges = np.empty((n, self.n_rays), dtype=np.float64)   # exact: write_from walks to these distances
            new = _lidar_measure_kernel(self._solid, pose, act, self._cos, self._sin, p.range_m, CELL_M,
                                        trk.seen_buffer, ranges, _NO_LIMITS if limits is None else limits,
                                        *self._sight(trk, n))
            self._cast[:] = act
        elif p.mode == "ternary":
            required = _CAST_EVERY_ROBOT
            if not measure:
                if self._required.shape[0] == 0:
                    self._required = _required_raster(self.truth.solid)
                required = self._required
            p_free, p_solid = no_planes() if planes is None else (planes.free, planes.solid)
            new = _lidar_ternary_kernel(self._solid, pose, act, self._cos, self._sin, p.range_m, CELL_M,
                                        known, trk.seen_buffer, ranges, required, self._half_widths, self._cast,
                                        self._freed if freed is None else freed, p_free, p_solid,
                                        *self._sight(trk, n), tiles_w)
        else:
            if planes is not None:
                raise InvalidInput("planes", "given", "none: a log-odds lidar may lower cells, which planes cannot mirror")
            if p.noisy:
                if not isinstance(rng, np.random.Generator):
                    raise InvalidInput("rng", rng, "a numpy.random.Generator (the lidar is noisy)")
                noise = rng.standard_normal((n, self.n_rays))
            else:
                noise = self._no_noise
            grid = self._logodds_for(n)
            voting = pose if write_poses is None else np.ascontiguousarray(write_poses, dtype=np.float64)
            if voting.shape != pose.shape:
                raise InvalidInput("write_poses", voting.shape, f"an array of shape {pose.shape}")
            new = _lidar_logodds_kernel(self._solid, pose, act, self._cos, self._sin, p.range_m, CELL_M,
                                        noise, p.noise_std, p.noise_per_metre, grid.values, p.logodds_hit,
                                        p.logodds_miss, p.logodds_min, p.logodds_max,
                                        p.logodds_occupied_above, p.logodds_free_below, known,
                                        trk.seen_buffer, ranges, self._votes, self._mark,
                                        self._touched, voting, *self._sight(trk, n))
            self._cast[:] = act
        if new < 0:
            r = -new - 1
            raise InvalidInput(f"poses[{r}]", tuple(float(v) for v in pose[r]),
                               f"a finite pose inside the map (0 <= x < {self.truth.width_m:g}, "
                               f"0 <= y < {self.truth.height_m:g} m)")
        trk.add_seen(new)
        return ranges if measure else None

    def write_from(self, poses: np.ndarray, ranges: np.ndarray, known: np.ndarray,
                   limits: np.ndarray | None = None) -> int:
        """Write measured ``ranges`` (``float64[R, n_rays]``, from :meth:`scan` with ``write=False``) into
        ``known`` from the poses the robots believe they have (``float64[R, 3]``): what a robot with a
        localisation error maps (:func:`_lidar_belief_kernel`; from the true poses, exactly what a ternary
        scan writes). Returns how many robots believed themselves off the map and wrote nothing."""
        pose = np.ascontiguousarray(poses, dtype=np.float64)
        if pose.ndim != 2 or pose.shape[1] != 3 or ranges.shape != (pose.shape[0], self.n_rays):
            raise InvalidInput("poses", pose.shape, f"(R, 3) poses with ranges of shape (R, {self.n_rays})")
        if self._check_known(known, pose.shape[0]):
            raise InvalidInput("known", "tiled maps", "dense maps for robots writing from estimated poses")
        return int(_lidar_belief_kernel(pose, np.ascontiguousarray(ranges, dtype=np.float64), self._cos, self._sin,
                                        self.params.range_m, CELL_M, known, _NO_LIMITS if limits is None else limits))

    def occlusion(self, poses: np.ndarray, radius: float, active: np.ndarray | None = None) -> np.ndarray:
        """How far each robot's rays reach before another robot's disc of ``radius`` (``float64[R, n_rays]``,
        inf where no robot is in the way within range): what ``robots_occlude`` hides. Only pairs closer than
        the range plus a diameter are examined (a k-d tree finds them)."""
        from scipy.spatial import cKDTree

        pose = np.ascontiguousarray(poses, dtype=np.float64)
        n = pose.shape[0]
        out = np.full((n, self.n_rays), np.inf)
        if n < 2:
            return out
        pairs = cKDTree(pose[:, :2]).query_pairs(self.params.range_m + 2 * radius, output_type="ndarray")
        act = active_flags(n, active)
        _lidar_occlusion_kernel(pose, act, np.ascontiguousarray(pairs, dtype=np.int64), self._cos, self._sin,
                                radius, out)
        return out

    @property
    def cast(self) -> np.ndarray:
        """Per robot of the last scan: whether its rays were cast (read-only ``bool[R]``; all active robots
        unless it was a ternary scan with ``measure=False``)."""
        view = self._cast.view()
        view.setflags(write=False)
        return view

    @staticmethod
    def _sight(tracker: ExplorationTracker, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The tracker's own-sight buffers for a scan of ``n`` robots (empty when it does not track robots)."""
        own, seers, counts = tracker.sight_buffers
        if counts.shape[0] not in (0, n):
            raise InvalidInput("tracker", f"tracking {counts.shape[0]} robots", f"tracking {n} robots or none")
        return own, seers, counts

    def _check_tracker(self, tracker: ExplorationTracker) -> ExplorationTracker:
        if not isinstance(tracker, ExplorationTracker) or tracker.shape != self.truth.shape:
            raise InvalidInput("tracker", getattr(tracker, "shape", tracker),
                               f"an ExplorationTracker of this map (shape {self.truth.shape})")
        return tracker

    def _check_known(self, known: np.ndarray, n: int) -> int:
        """Check the maps a scan writes: dense ``uint8[n, H, W]`` (returns 0) or tiled ``uint8[n, size]``
        (:class:`swarm.knowledge.tiles.TiledLayout`; returns its width in tiles)."""
        want = (n, *self.shape)
        layout = TiledLayout(self.shape)
        if (not isinstance(known, np.ndarray) or known.dtype != np.uint8
                or known.shape not in (want, (n, layout.size))):
            got = (getattr(known, "dtype", type(known).__name__), getattr(known, "shape", None))
            raise InvalidInput("known", got, f"a uint8 array of shape {want} (or tiled, {(n, layout.size)})")
        if not (known.flags.c_contiguous and known.flags.writeable):
            raise InvalidInput("known", "a non-contiguous or read-only array", "a writable C-contiguous array")
        return layout.tiles[1] if known.ndim == 2 else 0

    def _logodds_for(self, n: int) -> LogOddsGrid:
        if self.logodds is None:
            p = self.params
            self.logodds = LogOddsGrid(n, self.shape, p.logodds_occupied_above, p.logodds_free_below)
            rows, cols = self.shape
            self._votes = np.zeros((rows, cols), dtype=np.int32)
            self._mark = np.zeros((rows, cols), dtype=np.bool_)
            self._touched = np.zeros(rows * cols, dtype=np.int64)
        elif self.logodds.n_robots != n:
            raise InvalidInput("poses", n, f"{self.logodds.n_robots} robots, as in the first log-odds scan")
        return self.logodds


def warm_up() -> None:
    """Compile (or load from numba's on-disk cache) every sensing and knowledge kernel on a tiny map, so
    a timed loop is not charged for compilation (``benchmarks/speed/bench_sensing.py`` calls it before timing).
    The runtime does not call it: its arrays are of other numba types (read-only poses, for one), so the
    run loads its own versions on first use, ~0.15 s for all of a 16-robot run's kernels."""
    from swarm.knowledge.maps import empty_knowledge, merge

    solid = np.ones((8, 8), dtype=bool)
    solid[1:-1, 1:-1] = False
    truth = Map(solid=solid, material=solid.astype(np.uint8), materials=("air", "concrete"))
    poses = np.array([[2.1, 2.2, 0.3]], dtype=np.float64)
    for params in (LidarParams(range_m=2.0), LidarParams(range_m=2.0, mode="logodds", noise_std=0.01)):
        lidar = Lidar(truth, params)
        known = empty_knowledge(truth.shape, 1)
        lidar.scan(poses, known, np.random.default_rng(0))
        lidar.tracker.update_coverage(poses[:, :2])
    other = empty_knowledge(truth.shape)
    merge(other.copy(), other)
    other.setflags(write=False)
    merge(other.copy(), other)   # read-only views are a separate numba type
