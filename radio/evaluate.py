"""The per-tick fast path: all-pairs wall walk and eqs. 1-2 in one numba call.

:meth:`radio.models.LinkModel.evaluate` runs once per tick for every robot pair, so its Python overhead
matters as much as the walk: one dispatch here replaces a position check, the walk and the budget (each
numba dispatch with many arguments costs microseconds). The pieces are the same kernels the one-pair and
heatmap paths use (:func:`radio.crossings._radio_all_pairs`, :func:`radio.pathloss._radio_link_budget`),
so every path gives the same numbers.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .crossings import (_bucket_of, _distance, _radio_all_pairs, _radio_bucket_robots, _radio_pairs_with,
                        _radio_walk_segment, _radio_walk_until, _run_buffers)
from .pathloss import GLOBAL, LOS, MAES, MIN_DISTANCE_M, MULTIWALL, _radio_link_budget


@njit(cache=True)
def _radio_first_outside(xy, width, height):  # pragma: no cover
    """Index of the first row that is not a finite point in [0, width) x [0, height), or -1."""
    for i in range(xy.shape[0]):
        x = xy[i, 0]
        y = xy[i, 1]
        if not (0.0 <= x < width and 0.0 <= y < height):  # NaN fails every comparison
            return i
    return -1


CELL, WIDTH, HEIGHT, TOL, ALPHA, BETA, FREQ_TERM, MAX_RANGE = range(8)
"""Slots of the ``params`` vector (scalars travel in one array: each numba argument costs dispatch time)."""
DISTANCE, WALL_DB, PATH_LOSS, CHARGED, RSSI = range(5)
"""Planes of the float64[5, R, R] output block."""


@njit(cache=True)
def _radio_evaluate(blocks, xy, params, cross_db, metre_db, per_metre, code, tx, sens, out, walls, counts,
                    link):  # pragma: no cover
    """Check the positions, then fill every output; returns the first bad row (nothing filled) or -1."""
    bad = _radio_first_outside(xy, params[WIDTH], params[HEIGHT])
    if bad >= 0:
        return bad
    _radio_all_pairs(blocks, params[CELL], xy, params[TOL], cross_db, metre_db, per_metre, out[DISTANCE], walls,
                     out[WALL_DB], counts)
    _radio_link_budget(code, out[DISTANCE], walls, out[WALL_DB], tx, sens, params[ALPHA], params[BETA],
                       params[FREQ_TERM], params[MAX_RANGE], True, out[PATH_LOSS], out[CHARGED], out[RSSI], link)
    for i in range(xy.shape[0]):
        out[RSSI, i, i] = np.nan
        link[i, i] = False
    return -1


@njit(cache=True)
def _radio_link_columns(blocks, xy, params, cross_db, metre_db, per_metre, code, tx, sens, senders,
                        link, rssi_out, distance_out):  # pragma: no cover
    """``link[i, k]``: the message of robot ``senders[k]`` reaches robot i, exactly as
    :func:`_radio_evaluate` judges it, walking only the pairs with a sender; ``rssi_out`` and
    ``distance_out`` get the pairs' RSSI and distance (what shadowing and packet errors read) unless they
    have no rows (the plain link question). Returns the first bad row (nothing filled) or -1."""
    bad = _radio_first_outside(xy, params[WIDTH], params[HEIGHT])
    if bad >= 0:
        return bad
    n = xy.shape[0]
    m = senders.shape[0]
    distance = np.empty((n, m))
    walls = np.empty((n, m), np.int32)
    wall_db = np.empty((n, m))
    _radio_pairs_with(blocks, params[CELL], xy, params[TOL], cross_db, metre_db, per_metre, senders, distance,
                      walls, wall_db)
    path_loss = np.empty((n, 1))
    charged = np.empty((n, 1))
    rssi = np.empty((n, 1))
    ok = np.empty((n, 1), np.bool_)
    for k in range(m):
        j = senders[k]
        _radio_link_budget(code, distance[:, k:k + 1], walls[:, k:k + 1], wall_db[:, k:k + 1], tx[j:j + 1], sens,
                           params[ALPHA], params[BETA], params[FREQ_TERM], params[MAX_RANGE], False, path_loss,
                           charged, rssi, ok)
        for i in range(n):
            link[i, k] = ok[i, 0] and i != j
        if rssi_out.shape[0]:
            for i in range(n):
                rssi_out[i, k] = rssi[i, 0] if i != j else np.nan
                distance_out[i, k] = distance[i, k]
    return -1


@njit(cache=True)
def _radio_link_all(blocks, free_ids, xy, params, cross_db, metre_db, per_metre, code, tx, sens,
                    reach, link):  # pragma: no cover
    """:func:`_radio_evaluate`'s ``link`` alone: each pair walked once (from its lower index, the same walk),
    eqs. 1-2 as :func:`radio.pathloss._radio_link_budget` computes them, both directions; none of the
    float planes or the material counts (n^2 x 61 bytes: 6 GB for 10,000 robots). A walk stops once the
    walls so far rule out both directions (:func:`radio.crossings._radio_walk_until`), a pair inside one free
    rectangle (``free_ids``, :attr:`radio.crossings.WallRaster.free_ids`) is not walked (it crosses nothing,
    the walk's answer), and the global model walks nothing.

    ``reach`` (m, ``inf`` for none): no link holds between robots farther apart (:meth:`LinkModel.reach`);
    robots are then put in square buckets of at least that side and only pairs in neighbouring buckets are judged,
    the others left unlinked, so a spread swarm judges its near pairs, not all n^2 / 2. Returns the first
    bad row (nothing filled) or -1."""
    bad = _radio_first_outside(xy, params[WIDTH], params[HEIGHT])
    if bad >= 0:
        return bad
    n = xy.shape[0]
    run_start, run_end, run_len = _run_buffers(blocks, cross_db.shape[0])
    rect = _free_rectangles(free_ids, xy, params[CELL])
    gx = 1
    gy = 1
    side = max(params[WIDTH], params[HEIGHT]) + 1.0
    if np.isfinite(reach) and reach > 0.0:
        side = max(reach, params[WIDTH] / 1024.0, params[HEIGHT] / 1024.0)   # at most 1024 x 1024 buckets
        gx = max(int(math.ceil(params[WIDTH] / side)), 1)
        gy = max(int(math.ceil(params[HEIGHT] / side)), 1)
        if gx < 4 and gy < 4:              # every pair is in neighbouring buckets anyway: one bucket
            gx = gy = 1
    link[:, :] = False
    count = np.zeros(gx * gy + 1, np.int64)
    order = np.empty(n, np.int64)
    _radio_bucket_robots(xy, side, gx, gy, order, count)  # robots by bucket, in robot order within one
    for i in range(n):
        home = _bucket_of(xy[i, 0], xy[i, 1], side, gx, gy)
        cx, cy = home // gy, home % gy
        for bx in range(max(cx - 1, 0), min(cx + 2, gx)):
            for by in range(max(cy - 1, 0), min(cy + 2, gy)):
                b = bx * gy + by
                for t in range(count[b], count[b + 1]):
                    j = order[t]
                    if j <= i:
                        continue
                    ij, ji = _pair_link(blocks, rect[i] != 0 and rect[i] == rect[j], xy, params, cross_db,
                                        metre_db, per_metre, code, tx, sens, i, j, run_start, run_end, run_len)
                    link[i, j] = ij
                    link[j, i] = ji
    return -1


@njit(cache=True)
def _radio_groups_mutual(blocks, free_ids, xy, params, cross_db, metre_db, per_metre, code, tx, sens,
                         labels):  # pragma: no cover
    """The groups of links that hold both ways, into ``labels`` (0, 1, ... by smallest member), by union-find:
    a pair is judged (:func:`_pair_link`, the same walk) only while its robots are not yet joined, so a
    gathered swarm judges about n pairs, not n^2 / 2. With one transmit power and one sensitivity every link
    holds both ways or neither, and these are :func:`radio.models.groups_of`'s strongly connected groups.
    Returns the first bad row (nothing filled) or -1."""
    bad = _radio_first_outside(xy, params[WIDTH], params[HEIGHT])
    if bad >= 0:
        return bad
    n = xy.shape[0]
    run_start, run_end, run_len = _run_buffers(blocks, cross_db.shape[0])
    rect = _free_rectangles(free_ids, xy, params[CELL])
    parent = np.arange(n)
    for i in range(n):
        for j in range(i + 1, n):
            a = i
            while parent[a] != a:
                parent[a] = parent[parent[a]]
                a = parent[a]
            b = j
            while parent[b] != b:
                parent[b] = parent[parent[b]]
                b = parent[b]
            if a == b:
                continue
            ij, ji = _pair_link(blocks, rect[i] != 0 and rect[i] == rect[j], xy, params, cross_db, metre_db,
                                per_metre, code, tx, sens, i, j, run_start, run_end, run_len)
            if ij and ji:
                parent[max(a, b)] = min(a, b)
    found = 0
    for i in range(n):
        a = i
        while parent[a] != a:
            a = parent[a]
        if a == i:  # the smallest member of its group is its root: groups appear in order of it
            labels[i] = found
            found += 1
        else:
            labels[i] = labels[a]
    return -1


@njit(cache=True, inline="always")
def _free_rectangles(free_ids, xy, cell):  # pragma: no cover
    """Each robot's free rectangle (:attr:`radio.crossings.WallRaster.free_ids`; 0: none)."""
    rows, cols = free_ids.shape
    out = np.empty(xy.shape[0], np.int32)
    for k in range(xy.shape[0]):
        out[k] = free_ids[min(int(xy[k, 1] / cell), rows - 1), min(int(xy[k, 0] / cell), cols - 1)]
    return out


@njit(cache=True, inline="always")
def _pair_link(blocks, clear, xy, params, cross_db, metre_db, per_metre, code, tx, sens, i, j, run_start,
               run_end, run_len):  # pragma: no cover
    """(i hears j, j hears i) for the pair i < j, as :func:`_radio_evaluate` judges them; ``clear``: both in one
    free rectangle (no wall between them, so no walk)."""
    if code == GLOBAL:
        return True, True
    d = _distance(xy[i, 0], xy[i, 1], xy[j, 0], xy[j, 1])
    cell, tol = params[CELL], params[TOL]
    if code == LOS:
        walls = 0 if clear else _radio_walk_segment(blocks, cell, xy[i, 0], xy[i, 1], xy[j, 0], xy[j, 1], tol,
                                                     run_start, run_end, run_len)
        ok = walls == 0 and d <= params[MAX_RANGE]
        return ok, ok
    if code == MULTIWALL:
        pl = 10.0 * params[ALPHA] * math.log10(max(d, MIN_DISTANCE_M)) + params[BETA] + params[FREQ_TERM]
        a1 = tx[j] - pl
        a2 = tx[i] - pl
    else:  # MAES: no distance term
        a1 = tx[j]
        a2 = tx[i]
    w = 0.0
    if not clear:
        _, w, _ = _radio_walk_until(blocks, cell, xy[i, 0], xy[i, 1], xy[j, 0], xy[j, 1], tol, run_start, run_end,
                                    run_len, cross_db, metre_db, per_metre, a1, sens[i], a2, sens[j])
    return a1 - w >= sens[i], a2 - w >= sens[j]


@njit(cache=True)
def _radio_link_columns_only(blocks, free_ids, xy, params, cross_db, metre_db, per_metre, code, tx, sens,
                             senders, reach, link):  # pragma: no cover
    """:func:`_radio_link_columns`' ``link`` alone, each pair's walk stopped once its walls rule out the link
    (as :func:`_radio_link_all`); pairs farther apart than ``reach`` (m) are not judged (no link holds
    there). Returns the first bad row (nothing filled) or -1."""
    bad = _radio_first_outside(xy, params[WIDTH], params[HEIGHT])
    if bad >= 0:
        return bad
    n = xy.shape[0]
    run_start, run_end, run_len = _run_buffers(blocks, cross_db.shape[0])
    rect = _free_rectangles(free_ids, xy, params[CELL])
    for k in range(senders.shape[0]):
        j = senders[k]
        for i in range(n):
            if i == j:
                link[i, k] = False
                continue
            dx = xy[i, 0] - xy[j, 0]
            dy = xy[i, 1] - xy[j, 1]
            if dx * dx + dy * dy > reach * reach:
                link[i, k] = False
                continue
            a, b = min(i, j), max(i, j)
            ab, ba = _pair_link(blocks, rect[a] != 0 and rect[a] == rect[b], xy, params, cross_db, metre_db,
                                per_metre, code, tx, sens, a, b, run_start, run_end, run_len)
            link[i, k] = ab if i == a else ba
    return -1


@njit(cache=True)
def _radio_distances(xy, distance):  # pragma: no cover
    """The all-pairs distance matrix exactly as :func:`_radio_evaluate` fills it (each pair from its lower
    index), without the walls."""
    n = xy.shape[0]
    for i in range(n):
        distance[i, i] = 0.0
        for j in range(i + 1, n):
            d = _distance(xy[i, 0], xy[i, 1], xy[j, 0], xy[j, 1])
            distance[i, j] = d
            distance[j, i] = d
