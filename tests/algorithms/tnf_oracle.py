"""TNF's frontier scoring as it was computed before issue 35 (numpy passes over the whole map and a whole
distance field), kept verbatim as the oracle for the compiled form in algorithms.tnf_utility and
algorithms.tnf_kernels: both must agree bit for bit (tests/algorithms/test_tnf_kernels.py)."""

from __future__ import annotations

import math

import numpy as np
from scipy import ndimage

from algorithms.tnf_utility import (G_KNOWN, G_UNSEEN, FrontierScore, Frontiers, coordination_penalty,
                                    distance_term, maes_coordination, maes_distance_term, maes_information,
                                    maes_wavefront)
from swarm.api import FREE, SOLID, UNSEEN, cell_centre, grid

_N8 = ((-1, -1), (-1, 0), (-1, 1), (0, -1), (0, 1), (1, -1), (1, 0), (1, 1))
_EIGHT = np.ones((3, 3), dtype=bool)


def cell_information(known: np.ndarray, cells: np.ndarray) -> np.ndarray:
    h, w = known.shape
    unseen = np.zeros((h + 2, w + 2), dtype=np.int64)
    unseen[1:-1, 1:-1] = known == UNSEEN
    r, c = cells[:, 0] + 1, cells[:, 1] + 1
    n_unseen = sum(unseen[r + dr, c + dc] for dr, dc in _N8)
    own = np.where(unseen[r, c] == 1, G_UNSEEN, G_KNOWN)
    return own + n_unseen * G_UNSEEN + (8 - n_unseen) * G_KNOWN


def score_frontiers(known, start, destinations, *, alpha, beta, robot_radius_m, penalty_radius_m, reach,
                    exclude=None, min_size=1, margin_m=grid.DEFAULT_MARGIN_M, variant="swarm", position_m=None,
                    sensed_m=None) -> list[FrontierScore]:
    space = grid.configuration_space(known, robot_radius_m, margin_m)
    here = grid.nearest_in(space, start, reach + 1)
    if here is None:
        return []
    fr = frontiers(known, exclude, min_size)
    if not fr.count:
        return []
    field = grid.distance_field(space, here)
    if exclude is not None:
        field[exclude] = np.inf
    targets = targets_of(known, fr, field, reach)
    keep = np.flatnonzero(targets[:, 0] >= 0)
    if not len(keep):
        return []
    raw = np.bincount(fr.owner, weights=cell_information(known, fr.cells), minlength=fr.count)[keep]
    cells = targets[keep]
    dist = field[cells[:, 0], cells[:, 1]].astype(np.float64)
    if variant == "maes":
        gain = maes_information(raw, fr.count)
        here_m = cell_centre(*start) if position_m is None else position_m
        dterm = maes_distance_term(maes_wavefront(fr, here_m)[keep], alpha, beta)
        sensed = np.zeros((0, 2)) if sensed_m is None else sensed_m
        penalty = maes_coordination(fr, sensed)[keep]
        return _ranked(cells, fr, keep, raw, gain, dist, dterm, penalty)
    d_max = float(dist.max())
    w = dist / d_max if d_max > 0.0 else np.zeros_like(dist)
    gain = raw / raw.max()
    dterm = distance_term(w, alpha, beta)
    penalty = np.zeros(len(keep))
    if len(destinations) and penalty_radius_m > 0.0:
        d_dest = destination_distance(known, destinations, cells, penalty_radius_m)
        penalty = coordination_penalty(d_dest, penalty_radius_m)
    return _ranked(cells, fr, keep, raw, gain, dist, dterm, penalty)


def _ranked(cells, fr, keep, raw, gain, dist, dterm, penalty) -> list[FrontierScore]:
    utility = gain + dterm - penalty
    scores = [FrontierScore(target=(int(cells[j, 0]), int(cells[j, 1])), size=int(fr.sizes[i]),
                            raw_gain=float(raw[j]), gain=float(gain[j]), distance_m=float(dist[j]),
                            distance=float(dterm[j]), penalty=float(penalty[j]), utility=float(utility[j]))
              for j, i in enumerate(keep.tolist())]
    scores.sort(key=lambda s: (-s.utility, s.target))
    return scores


def frontiers(known, exclude=None, min_size=1) -> Frontiers:
    mask = grid.frontier_mask(known)
    rows_any, cols_any = np.flatnonzero(mask.any(axis=1)), np.flatnonzero(mask.any(axis=0))
    empty = np.zeros((0, 2), dtype=np.int64)
    none = Frontiers(empty, np.zeros(0, np.int64), np.zeros(0, np.int64), empty)
    if not len(rows_any):
        return none
    r0, c0 = max(int(rows_any[0]) - 1, 0), max(int(cols_any[0]) - 1, 0)
    labels, n = ndimage.label(mask[r0:int(rows_any[-1]) + 2, c0:int(cols_any[-1]) + 2], structure=_EIGHT)
    rows, cols = np.nonzero(labels)
    lab = labels[rows, cols].astype(np.int64) - 1
    order = np.argsort(lab, kind="stable")
    rows, cols, lab = rows[order] + r0, cols[order] + c0, lab[order]
    sizes = np.bincount(lab, minlength=n)
    cy = np.bincount(lab, weights=rows + 0.5, minlength=n) / sizes
    cx = np.bincount(lab, weights=cols + 0.5, minlength=n) / sizes
    if exclude is not None:
        keep = ~exclude[rows, cols]
        rows, cols, lab = rows[keep], cols[keep], lab[keep]
        sizes = np.bincount(lab, minlength=n)
    d2 = (rows + 0.5 - cy[lab]) ** 2 + (cols + 0.5 - cx[lab]) ** 2
    big = sizes >= max(min_size, 1)
    if not big.any():
        return none
    if not big.all():
        keep = big[lab]
        rows, cols, d2, lab = rows[keep], cols[keep], d2[keep], np.cumsum(big)[lab[keep]] - 1
        sizes = sizes[big]
    best = np.lexsort((np.arange(len(lab)), d2, lab))
    first = best[np.searchsorted(lab[best], np.arange(len(sizes)))]
    cells = np.column_stack((rows, cols)).astype(np.int64)
    return Frontiers(cells=cells, owner=lab, sizes=sizes.astype(np.int64), representative=cells[first])


def targets_of(known, fr, field, reach) -> np.ndarray:
    h, w = known.shape
    free = (known == FREE).reshape(-1)
    flat = fr.cells[:, 0] * w + fr.cells[:, 1]
    seen_flat, seen_lab = [flat], [fr.owner]
    visited = np.zeros(h * w, dtype=bool)
    visited[flat] = True
    front, front_lab = flat, fr.owner
    for _ in range(reach):
        r, c = np.divmod(front, w)
        cand, cand_lab = [], []
        for dr, dc in ((-1, 0), (1, 0), (0, -1), (0, 1)):
            rr, cc = r + dr, c + dc
            ok = (rr >= 0) & (rr < h) & (cc >= 0) & (cc < w)
            cand.append((rr * w + cc)[ok])
            cand_lab.append(front_lab[ok])
        cf, cl = np.concatenate(cand), np.concatenate(cand_lab)
        keep = free[cf] & ~visited[cf]
        cf, cl = cf[keep], cl[keep]
        order = np.lexsort((cl, cf))
        cf, cl = cf[order], cl[order]
        first = np.ones(len(cf), dtype=bool)
        first[1:] = cf[1:] != cf[:-1]
        front, front_lab = cf[first], cl[first]
        visited[front] = True
        seen_flat.append(front)
        seen_lab.append(front_lab)
    allf, alll = np.concatenate(seen_flat), np.concatenate(seen_lab)
    dist = field.reshape(-1)[allf]
    ok = np.isfinite(dist)
    allf, alll, dist = allf[ok], alll[ok], dist[ok]
    out = np.full((fr.count, 2), -1, dtype=np.int64)
    if not len(allf):
        return out
    rr, cc = np.divmod(allf, w)
    reps = fr.representative
    e2 = (rr - reps[alll, 0]) ** 2 + (cc - reps[alll, 1]) ** 2
    order = np.lexsort((cc, rr, dist, e2, alll))
    labels, first = np.unique(alll[order], return_index=True)
    j = order[first]
    out[labels, 0], out[labels, 1] = rr[j], cc[j]
    return out


def destination_distance(known, destinations, cells, radius_m) -> np.ndarray:
    open_ = known != SOLID
    h, w = known.shape
    sources = []
    for r, c in np.asarray(destinations, dtype=np.int64).reshape(-1, 2).tolist():
        snapped = grid.nearest_in(open_, (min(max(r, 0), h - 1), min(max(c, 0), w - 1)), 4)
        if snapped is not None:
            sources.append(snapped)
    if not sources:
        return np.full(len(cells), math.inf)
    field = grid.distance_field(open_, np.array(sources, dtype=np.int64), max_dist_m=radius_m)
    return field[cells[:, 0], cells[:, 1]].astype(np.float64)
