"""TNF's frontier utility, ``U(f) = I(f) + D(f) - C(f)``, as pure functions of one robot's knowledge map.

See :mod:`algorithms.tnf` for the paper, the MAES implementation and every departure. In short:

- **I(f), information gain**: a Gaussian ``G(v) = A exp(-(v - B)^2 / (2 C^2))`` (A = 5, B = 0.5, C = 0.1,
  MAES's constants) of each cell's value ``v`` (0.5 for UNSEEN -- maximal uncertainty -- and 0 for FREE
  or SOLID), summed over the frontier's cells and their 8 neighbours: ``raw(f) = sum_c [G(v_c) +
  sum_{n in N8(c)} G(v_n)]``, about 5 per unseen neighbour slot. ``I(f) = raw(f) / max_g raw(g)``, so
  I lies in (0, 1] like the other terms.
- **D(f), distance term**: ``w = d(f) / d_max`` with ``d(f)`` the robot's path length to the frontier's
  target on its configuration space and ``d_max`` the largest over the candidates, so ``w`` lies in
  [0, 1]; ``D = w^(alpha-1) (1-w)^(beta-1)`` divided by its maximum (at the Beta mode), so D lies in [0, 1].
- **C(f), coordination penalty**: one wavefront (geodesic distance field) through the robot's non-solid
  cells from every destination other robots announced, bounded at ``R = penalty_radius_m``;
  ``C(f) = max(0, 1 - d_dest(f) / R)`` at the frontier's target: 1 at an announced destination, 0 from
  ``R`` on.

With ``variant = "maes"`` (:func:`score_frontiers`) the three terms are MAES's instead, bugs included
(``TnfExplorationAlgorithm.cs``; what is and is not reproduced is listed in :mod:`algorithms.tnf`):

- ``I(f) = k sum_c [G(v_c) + sum_{n in N8(c)} G(v_n)] / F`` with ``F`` the number of frontiers
  (:func:`maes_information`);
- ``D(f) = w^(alpha-1) (1-w)^(beta-1)``, ``w = sqrt(k sum_c |p - c| / Dmax)`` from the robot's position
  ``p`` in straight lines, ``Dmax`` the largest ``|p - c|`` over every frontier cell, ``w`` unclamped
  (:func:`maes_wavefront`, :func:`maes_distance_term`);
- ``C(f) = sum_r sqrt(k sum_c |p_r - c| / Dmax_r)`` over the sensed robots, ``p_r`` placed with the
  relative bearing as a global angle (:func:`maes_sensed_position`, :func:`maes_coordination`);

where ``k = MAES_CELL_WEIGHT`` turns a sum over our 0.5 m cells into MAES's sum over 1 m tiles (a frontier
``L`` metres long has ``L`` tiles in MAES and about ``2 L`` cells here).

A frontier's **target** is the cell the robot drives to: among the configuration-space cells from which
the frontier is in view (at most ``reach`` 4-connected steps through FREE cells from one of its cells,
the view rule of :mod:`swarm.grid.targets`) and that the robot can reach, the one nearest the frontier's
representative cell (its centre). A frontier with no such cell is not a candidate.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from swarm.api import CELL_M, SOLID, UNSEEN, cell_centre, grid

from . import tnf_kernels

GAUSS_A, GAUSS_B, GAUSS_C = 5.0, 0.5, 0.1
UNSEEN_VALUE = 0.5
"""A cell's value for the Gaussian: 0.5 for UNSEEN (the occupancy probability nobody knows), 0 otherwise."""

def gaussian(x: float | np.ndarray) -> float | np.ndarray:
    """MAES's information Gaussian: G(0.5) = 5, G(0) = G(1) = 5 e^-12.5 = 1.86e-5."""
    return GAUSS_A * np.exp(-((np.asarray(x, dtype=np.float64) - GAUSS_B) ** 2) / (2.0 * GAUSS_C ** 2))


G_UNSEEN = float(gaussian(UNSEEN_VALUE))
G_KNOWN = float(gaussian(0.0))

VARIANTS = ("swarm", "maes")
MAES_TILE_M = 1.0
MAES_CELL_WEIGHT = CELL_M / MAES_TILE_M
"""What one of our cells counts for in MAES's per-tile sums (its coarse tiles are 1 m, our cells 0.5 m)."""


def cell_information(known: np.ndarray, cells: np.ndarray) -> np.ndarray:
    """``G(v_c) + sum_{n in N8(c)} G(v_n)`` for each (row, col) in ``cells``; cells off the map count as known."""
    at = np.asarray(cells, dtype=np.int64).reshape(-1, 2)
    return tnf_kernels.information(_as_map(known), at, np.zeros(len(at), np.int64), 1, G_UNSEEN, G_KNOWN)[0]


def distance_term(w: np.ndarray, alpha: float, beta: float) -> np.ndarray:
    """``w^(alpha-1) (1-w)^(beta-1)`` on ``w`` in [0, 1], scaled so its maximum (the Beta mode) is 1."""
    w = np.clip(np.asarray(w, dtype=np.float64), 0.0, 1.0)
    if alpha + beta <= 2.0:      # alpha = beta = 1: flat
        return np.ones_like(w)
    mode = (alpha - 1.0) / (alpha + beta - 2.0)
    peak = mode ** (alpha - 1.0) * (1.0 - mode) ** (beta - 1.0)
    return w ** (alpha - 1.0) * (1.0 - w) ** (beta - 1.0) / peak


def coordination_penalty(distance_m: np.ndarray, radius_m: float) -> np.ndarray:
    """``max(0, 1 - d / radius)``: 1 at an announced destination, falling to 0 at ``radius_m`` and beyond."""
    d = np.asarray(distance_m, dtype=np.float64)
    if radius_m <= 0.0:
        return np.zeros_like(d)
    return np.clip(1.0 - d / radius_m, 0.0, 1.0)


# ------------------------------------------------------------------------ MAES's terms (variant maes) ----
def maes_information(raw: np.ndarray, n_frontiers: int) -> np.ndarray:
    """MAES's I: ``k raw / F`` (``TnfExplorationAlgorithm.cs`` lines 104-110: the Gaussian sum over each
    frontier cell and its 8 neighbours, divided by ``_frontiers.Count``)."""
    return MAES_CELL_WEIGHT * np.asarray(raw, dtype=np.float64) / n_frontiers


def maes_wavefront(fr: Frontiers, point_m: tuple[float, float]) -> np.ndarray:
    """MAES's ``WavefrontNormalized`` from ``point_m`` (x, y in metres) for every frontier of ``fr``:
    ``sqrt(k sum_c |p - c| / Dmax)``, ``|p - c|`` the straight-line distance to each cell's centre and
    ``Dmax`` the largest over all of ``fr``'s cells (lines 129-133, 140-142, and 153 / 301 for ``Dmax``).
    Unclamped: above 1 for any frontier whose cells' normalised distances add up to more than one tile.
    All zeros when every cell is at ``p`` (MAES divides 0 by 0 there)."""
    xy = (fr.cells[:, ::-1].astype(np.float64) + 0.5) * CELL_M
    d = np.hypot(xy[:, 0] - point_m[0], xy[:, 1] - point_m[1])
    d_max = float(d.max()) if len(d) else 0.0
    if d_max <= 0.0:
        return np.zeros(fr.count)
    return np.sqrt(MAES_CELL_WEIGHT * np.bincount(fr.owner, weights=d / d_max, minlength=fr.count))


def maes_distance_term(w: np.ndarray, alpha: float, beta: float) -> np.ndarray:
    """MAES's D, ``w^(alpha-1) (1-w)^(beta-1)`` on the unclamped ``w`` (lines 135-138): for ``w > 1`` the
    second factor is ``(negative)^(beta-1)``, large and negative for an odd ``beta - 1`` (beta = 10),
    large and positive for an even one. ``alpha`` and ``beta`` are whole numbers (MAES's are ``int``)."""
    w = np.asarray(w, dtype=np.float64)
    return np.power(w, alpha - 1.0) * np.power(1.0 - w, beta - 1.0)


def maes_sensed_position(x: float, y: float, distance: float, bearing: float) -> tuple[float, float]:
    """Where MAES's TNF puts a sensed robot: ``robot + distance (cos b, sin b)`` with ``b`` the bearing
    *relative to the robot's heading* used as a global angle (line 152: ``_robotPos +
    VectorFromDegreesAndMagnitude(neighbour.Angle, neighbour.Distance)``, where ``SenseNearbyRobots``
    gives the angle relative to the robot's forward, ``Robot2DController.cs`` lines 438-448). The true
    position is ``bearing + heading``; the two agree only when the robot heads along +x."""
    return x + distance * math.cos(bearing), y + distance * math.sin(bearing)


def maes_coordination(fr: Frontiers, sensed_m: np.ndarray) -> np.ndarray:
    """MAES's C for every frontier: ``sum_r maes_wavefront(fr, p_r)[f]`` over the sensed robots'
    positions ``sensed_m`` (float[K, 2], metres; K = 0: no penalty) (lines 144-157). It grows with the
    distance from ``p_r``, so it penalises the frontiers *far* from the others."""
    total = np.zeros(fr.count)
    for px, py in np.asarray(sensed_m, dtype=np.float64).reshape(-1, 2).tolist():
        total = total + maes_wavefront(fr, (px, py))
    return total


@dataclass(frozen=True)
class FrontierScore:
    """One candidate frontier and the terms of its utility."""

    target: tuple[int, int]     # configuration-space cell the robot would drive to
    size: int                   # frontier cells
    raw_gain: float             # sum of the Gaussian over the cells and their 8 neighbours
    gain: float                 # I: raw_gain / the largest raw_gain among candidates (maes: k raw_gain / F)
    distance_m: float           # path length from the robot to ``target``
    distance: float             # D (maes: MAES's, from straight lines, unclamped w)
    penalty: float              # C (maes: MAES's, from the sensed robots)
    utility: float              # I + D - C


def score_frontiers(known: np.ndarray, start: tuple[int, int], destinations: np.ndarray, *, alpha: float,
                    beta: float, robot_radius_m: float, penalty_radius_m: float, reach: int,
                    exclude: np.ndarray | None = None, min_size: int = 1,
                    margin_m: float = grid.DEFAULT_MARGIN_M, variant: str = "swarm",
                    position_m: tuple[float, float] | None = None, sensed_m: np.ndarray | None = None
                    ) -> list[FrontierScore]:
    """Every reachable frontier's utility terms, best first (ties: lower target row, then column).

    ``start`` is the robot's cell (snapped into the configuration space when it lies in inflated space);
    ``destinations`` int[K, 2] the cells other robots announced (K may be 0: no penalty). ``exclude``
    (bool[H, W]) removes cells both as frontier cells and as targets.

    ``variant = "maes"``: MAES's terms (the module docstring) from ``position_m`` (the robot's (x, y) in
    metres; default the centre of ``start``) and ``sensed_m`` (float[K, 2]: the sensed robots where MAES
    puts them, :func:`maes_sensed_position`); ``destinations``, ``penalty_radius_m`` are then unused. F and
    ``Dmax`` count every frontier, reachable or not, as MAES scores them all before it looks for a path.
    """
    terms = _terms(known, start, destinations, alpha=alpha, beta=beta, robot_radius_m=robot_radius_m,
                   penalty_radius_m=penalty_radius_m, reach=reach, exclude=exclude, min_size=min_size,
                   margin_m=margin_m, variant=variant, position_m=position_m, sensed_m=sensed_m)
    return [] if terms is None else _ranked(*terms)


def best_frontier(known: np.ndarray, start: tuple[int, int], destinations: np.ndarray, *, alpha: float,
                  beta: float, robot_radius_m: float, penalty_radius_m: float, reach: int,
                  exclude: np.ndarray | None = None, min_size: int = 1,
                  margin_m: float = grid.DEFAULT_MARGIN_M, variant: str = "swarm",
                  position_m: tuple[float, float] | None = None, sensed_m: np.ndarray | None = None
                  ) -> FrontierScore | None:
    """``score_frontiers(...)[0]`` (None when it is empty), without building and sorting the others."""
    terms = _terms(known, start, destinations, alpha=alpha, beta=beta, robot_radius_m=robot_radius_m,
                   penalty_radius_m=penalty_radius_m, reach=reach, exclude=exclude, min_size=min_size,
                   margin_m=margin_m, variant=variant, position_m=position_m, sensed_m=sensed_m)
    if terms is None:
        return None
    cells, fr, keep, raw, gain, dist, dterm, penalty = terms
    utility = gain + dterm - penalty
    if np.isnan(utility).any():   # Python's sort orders NaN keys its own way: take its answer
        return _ranked(*terms)[0]
    # the sort key (-utility, row, col): the largest utility, then the lowest row, then column
    j = int(np.lexsort((cells[:, 1], cells[:, 0], -utility))[0])
    return _score(cells, fr, keep, raw, gain, dist, dterm, penalty, utility, j)


_Terms = tuple[np.ndarray, "Frontiers", np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]


def _terms(known: np.ndarray, start: tuple[int, int], destinations: np.ndarray, *, alpha: float, beta: float,
           robot_radius_m: float, penalty_radius_m: float, reach: int, exclude: np.ndarray | None, min_size: int,
           margin_m: float, variant: str, position_m: tuple[float, float] | None, sensed_m: np.ndarray | None
           ) -> _Terms | None:
    """The candidates of :func:`score_frontiers` and their terms: (target cells, frontiers, index of each
    candidate's frontier, raw gain, I, path length, D, C), or None when there is no candidate.

    swarm's variant works on the window of the map that holds everything the robot knows (see
    :func:`_known_window`); the target cells come back in map coordinates."""
    known = np.asarray(known)
    dest = np.asarray(destinations, dtype=np.int64).reshape(-1, 2)
    window = None if variant == "maes" else _known_window(known, start, reach, robot_radius_m, margin_m,
                                                              penalty_radius_m)
    r0, r1, c0, c1 = (0, known.shape[0], 0, known.shape[1]) if window is None else window
    terms = _terms_on(known[r0:r1, c0:c1], (start[0] - r0, start[1] - c0), dest, (r0, c0), known.shape,
                      alpha=alpha, beta=beta, robot_radius_m=robot_radius_m, penalty_radius_m=penalty_radius_m,
                      reach=reach, exclude=None if exclude is None else exclude[r0:r1, c0:c1], min_size=min_size,
                      margin_m=margin_m, variant=variant, position_m=position_m, sensed_m=sensed_m)
    if terms is None or window is None:
        return terms
    return (terms[0] + np.array([r0, c0]), *terms[1:])


WINDOW_SHARE = 0.5
"""A decision crops the map to what the robot knows only while that window is at most this share of it."""


def _known_window(known: np.ndarray, start: tuple[int, int], reach: int, robot_radius_m: float, margin_m: float,
                  penalty_radius_m: float) -> tuple[int, int, int, int] | None:
    """Rows ``r0:r1`` and columns ``c0:c1`` of the bounding box of the robot's known (not UNSEEN) cells and
    its own cell, widened by every distance a term reads beyond a known cell, or None when that window is
    more than ``WINDOW_SHARE`` of the map (the whole map is then as cheap).

    Why the terms are the whole map's: the configuration space, the frontiers, the view cells and the
    robot's paths lie in known free cells; the erosion reads ``depth`` cells beyond them, the frontier
    test and the information term one, the snap ``reach + 1``; the coordination wavefront runs through
    unseen cells too, but only ``penalty_radius_m`` from a target cell, and a destination farther than
    that (snapped at most 4 cells) changes nothing. Cells the window leaves out are UNSEEN, as the
    kernels take the outside of a map to be, or beyond every bound. Why: TNF scores every frontier of
    the map, so each decision built whole-map rasters; early in a swarm's run a robot knows a small
    part of a large map (issue 47)."""
    h, w = known.shape
    k = np.asarray(known)
    if k.dtype == np.uint8 and k.flags.c_contiguous and w % 8 == 0:
        rows = np.flatnonzero(k.view(np.uint64).reshape(h, w // 8).any(axis=1))   # 8 cells a word
    else:
        rows = np.flatnonzero(k.any(axis=1))
    if len(rows) == 0:
        return None
    cols = np.flatnonzero(k[rows[0]:rows[-1] + 1].any(axis=0))
    depth = grid.erosion_depth(robot_radius_m, margin_m)
    m = max(depth, reach + 2, int(math.ceil(penalty_radius_m / CELL_M)) + 6) + 2
    r0 = max(min(int(rows[0]), start[0]) - m, 0)
    r1 = min(max(int(rows[-1]), start[0]) + m + 1, h)
    c0 = max(min(int(cols[0]), start[1]) - m, 0)
    c1 = min(max(int(cols[-1]), start[1]) + m + 1, w)
    if (r1 - r0) * (c1 - c0) > WINDOW_SHARE * h * w:
        return None
    return r0, r1, c0, c1


def _terms_on(known: np.ndarray, start: tuple[int, int], destinations: np.ndarray, origin: tuple[int, int],
              shape: tuple[int, int], *, alpha: float, beta: float, robot_radius_m: float, penalty_radius_m: float,
              reach: int, exclude: np.ndarray | None, min_size: int, margin_m: float, variant: str,
              position_m: tuple[float, float] | None, sensed_m: np.ndarray | None) -> _Terms | None:
    """:func:`_terms` on ``known``: the whole map, or a window of it (:func:`_known_window`) whose cell (0, 0)
    is map cell ``origin``, of a map of ``shape``; ``start`` and the target cells in ``known``'s
    coordinates, ``destinations`` in map cells (clipped to the map, then kept if inside ``known``)."""
    space = grid.configuration_space(known, robot_radius_m, margin_m)
    here = grid.nearest_in(space, start, reach + 1)
    if here is None:
        return None
    k = _as_map(known)
    fr = frontiers(k, exclude, min_size, origin)
    if not fr.count:
        return None
    targets, dist_all = frontier_targets(k, fr, space, here, reach, exclude)
    keep = np.flatnonzero(targets[:, 0] >= 0)
    if not len(keep):
        return None
    _, raw_all = tnf_kernels.information(k, fr.cells, fr.owner, fr.count, G_UNSEEN, G_KNOWN)
    raw = raw_all[keep]
    cells = targets[keep]
    dist = dist_all[keep].astype(np.float64)
    if variant == "maes":
        gain = maes_information(raw, fr.count)
        here_m = cell_centre(*start) if position_m is None else position_m
        dterm = maes_distance_term(maes_wavefront(fr, here_m)[keep], alpha, beta)
        sensed = np.zeros((0, 2)) if sensed_m is None else sensed_m
        penalty = maes_coordination(fr, sensed)[keep]
        return cells, fr, keep, raw, gain, dist, dterm, penalty
    d_max = float(dist.max())
    w = dist / d_max if d_max > 0.0 else np.zeros_like(dist)
    gain = raw / raw.max()
    dterm = distance_term(w, alpha, beta)
    penalty = np.zeros(len(keep))
    if len(destinations) and penalty_radius_m > 0.0:
        dest = np.column_stack((np.clip(destinations[:, 0], 0, shape[0] - 1),
                                np.clip(destinations[:, 1], 0, shape[1] - 1))) - np.array(origin)
        inside = (dest[:, 0] >= 0) & (dest[:, 0] < k.shape[0]) & (dest[:, 1] >= 0) & (dest[:, 1] < k.shape[1])
        d_dest = (_destination_distance(known, dest[inside], cells, penalty_radius_m) if inside.any()
                  else np.full(len(cells), math.inf))
        penalty = coordination_penalty(d_dest, penalty_radius_m)
    return cells, fr, keep, raw, gain, dist, dterm, penalty


def _score(cells: np.ndarray, fr: Frontiers, keep: np.ndarray, raw: np.ndarray, gain: np.ndarray, dist: np.ndarray,
           dterm: np.ndarray, penalty: np.ndarray, utility: np.ndarray, j: int) -> FrontierScore:
    return FrontierScore(target=(int(cells[j, 0]), int(cells[j, 1])), size=int(fr.sizes[keep[j]]),
                         raw_gain=float(raw[j]), gain=float(gain[j]), distance_m=float(dist[j]),
                         distance=float(dterm[j]), penalty=float(penalty[j]), utility=float(utility[j]))


def _ranked(cells: np.ndarray, fr: Frontiers, keep: np.ndarray, raw: np.ndarray, gain: np.ndarray,
            dist: np.ndarray, dterm: np.ndarray, penalty: np.ndarray) -> list[FrontierScore]:
    utility = gain + dterm - penalty
    scores = [_score(cells, fr, keep, raw, gain, dist, dterm, penalty, utility, j) for j in range(len(keep))]
    scores.sort(key=lambda s: (-s.utility, s.target))
    return scores


# ---------------------------------------------------------------------------------------- pieces ----


@dataclass(frozen=True, eq=False)
class Frontiers:
    """All frontier clusters of a map as flat arrays (no per-cluster Python objects: a map can have a
    hundred clusters and a decision must stay cheap).

    Clusters are those of :func:`swarm.grid.frontier_clusters` (8-connected groups of the frontier mask,
    ordered by their first cell in row-major order; the representative is the cell nearest the centroid,
    ties to the first), minus excluded cells, without clusters under ``min_size`` cells.
    """

    cells: np.ndarray            # int64[N, 2] (row, col), grouped by cluster, row-major within a cluster
    owner: np.ndarray            # int64[N] cluster index of each cell
    sizes: np.ndarray            # int64[F]
    representative: np.ndarray   # int64[F, 2]

    @property
    def count(self) -> int:
        return int(self.sizes.shape[0])


def frontiers(known: np.ndarray, exclude: np.ndarray | None = None, min_size: int = 1,
              origin: tuple[int, int] = (0, 0)) -> Frontiers:
    """The frontier clusters of ``known`` (see :class:`Frontiers`).

    Excluded cells are removed *after* clustering: a frontier cut by an exclusion disc stays one frontier
    (its other cells, its centroid), as a robot that gave up one spot of a frontier still sees one
    frontier; its representative is then the remaining cell nearest the centroid. (Splitting it into
    separate clusters instead was measured 7-13 % slower on 50 x 50 caves and buildings with 1-2 robots.)

    Compiled (:func:`algorithms.tnf_kernels.frontier_clusters`): one pass finds the frontier cells, the
    rest touches only them. ``origin``: the map cell of ``known``'s (0, 0) when ``known`` is a window of
    the map (the representatives are then the whole map's, in window coordinates).
    """
    cells, owner, sizes, rep = tnf_kernels.frontier_clusters(_as_map(known), exclude, min_size, origin)
    return Frontiers(cells=cells, owner=owner, sizes=sizes, representative=rep)


def frontier_targets(known: np.ndarray, fr: Frontiers, space: np.ndarray, here: tuple[int, int], reach: int,
                     exclude: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Each frontier's target, int64[F, 2] ((-1, -1) for none), and the path length to it (float32[F]
    metres, inf for none): the reachable view cell nearest its representative (see the module
    docstring); ties go to the shorter path, then the lower row, then column.

    View cells grow from the frontiers' cells, ``reach`` 4-connected steps through FREE cells (only the
    cells near frontiers are touched, not the whole map). A cell within reach of two frontiers keeps the
    label that arrives first (the lowest frontier index at equal depth). A view cell is reachable when it
    is in ``space``, not in ``exclude`` and the robot's path from ``here`` reaches it
    (:func:`swarm.grid.field_at`: the distance field's values at these cells only, bit for bit).
    """
    k = _as_map(known)
    h, w = k.shape
    flat, lab = tnf_kernels.view_labels(k, fr.cells, fr.owner, reach)
    cand = space.reshape(-1)[flat]
    if exclude is not None:
        cand &= ~exclude.reshape(-1)[flat]
    dist = np.full(len(flat), np.inf, dtype=np.float32)
    at = np.flatnonzero(cand)
    if len(at):
        rows, cols = np.divmod(flat[at], w)
        dist[at] = grid.field_at(space, here, np.column_stack((rows, cols)))
    targets, which = tnf_kernels.choose_targets(flat, lab, dist, fr.representative, w)
    return targets, np.where(which >= 0, dist[np.maximum(which, 0)], np.float32(np.inf))


def _as_map(known: np.ndarray) -> np.ndarray:
    """``known`` as the compiled passes take it: C-contiguous uint8 (the runtime's maps already are)."""
    k = np.asarray(known)
    if k.dtype != np.uint8 or not k.flags.c_contiguous:
        k = np.ascontiguousarray(k, dtype=np.uint8)
    return k


def _destination_distance(known: np.ndarray, destinations: np.ndarray, cells: np.ndarray, radius_m: float
                          ) -> np.ndarray:
    """Geodesic distance (m) from the nearest announced destination to each of ``cells``, through every
    non-solid cell (unseen included: it is a proximity measure, not a path), ``inf`` beyond ``radius_m``.
    Destinations in a cell this robot knows as solid snap to the nearest non-solid cell within 2 m."""
    open_ = known != SOLID
    h, w = known.shape
    dest = np.asarray(destinations, dtype=np.int64).reshape(-1, 2)
    dest = np.column_stack((np.minimum(np.maximum(dest[:, 0], 0), h - 1), np.minimum(np.maximum(dest[:, 1], 0), w - 1)))
    sources = []
    for (r, c), fine in zip(dest.tolist(), open_[dest[:, 0], dest[:, 1]].tolist()):
        snapped = (r, c) if fine else grid.nearest_in(open_, (r, c), 4)
        if snapped is not None:
            sources.append(snapped)
    if not sources:
        return np.full(len(cells), math.inf)
    return grid.field_at(open_, np.array(sources, dtype=np.int64), cells, max_dist_m=radius_m).astype(np.float64)
