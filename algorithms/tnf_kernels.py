"""TNF's per-decision passes over a knowledge map, compiled: frontier clusters, information gain, view cells
and targets (the definitions are :mod:`algorithms.tnf_utility`'s; this module only computes them).

A TNF decision on a 300 x 300 map sees about 16 frontiers of about 130 cells in all, yet the numpy forms
of these steps made several whole-map passes each (a frontier mask, a labelling, ``nonzero``, a padded
copy per neighbour direction...): 80 % of a decision besides its distance field (issue 35). Here one
vectorised row pass finds the frontier cells, and everything after it touches only those cells and their
few neighbours. The results are the numpy forms' bit for bit (same sums in the same order, same
tie-breaks): ``tests/algorithms/test_tnf_kernels.py`` checks them on random maps against those forms, kept
as the oracle in ``tests/algorithms/tnf_oracle.py``.

The kernels take per-thread scratch arrays of the map's size that are all -1 between calls (they reset
what they touched), so no call fills or allocates a whole map.
"""

from __future__ import annotations

import threading

import numpy as np
from numba import njit


class _Scratch(threading.local):
    """Three int32 arrays of H * W cells, all -1 between kernel calls (each kernel resets what it set)."""

    def __init__(self) -> None:
        self.a = np.zeros(0, dtype=np.int32)
        self.b = np.zeros(0, dtype=np.int32)
        self.flat = np.zeros(0, dtype=np.int64)

    def get(self, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The first ``n`` cells of each (grown when a larger map comes; a smaller one, e.g. a decision's
        window, uses the front, which keeps the all -1 invariant as the whole does)."""
        if self.a.shape[0] < n:
            self.a = np.full(n, -1, dtype=np.int32)
            self.b = np.full(n, -1, dtype=np.int32)
            self.flat = np.empty(n, dtype=np.int64)
        return self.a[:n], self.b[:n], self.flat[:n]


_SCRATCH = _Scratch()
_NO_EXCLUDE = np.zeros((0, 0), dtype=np.bool_)


def frontier_clusters(known: np.ndarray, exclude: np.ndarray | None, min_size: int,
                      origin: tuple[int, int] = (0, 0)) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(cells int64[N, 2], owner int64[N], sizes int64[F], representative int64[F, 2]) of
    :func:`algorithms.tnf_utility.frontiers` for a uint8 map (C-contiguous). ``origin``: the map cell of
    ``known``'s cell (0, 0) when ``known`` is a window; centroids are summed in map coordinates, so the
    representatives are the whole map's bit for bit (the cells returned are the window's)."""
    h, w = known.shape
    index, _, flat = _SCRATCH.get(h * w)
    ex = _NO_EXCLUDE if exclude is None else np.ascontiguousarray(exclude, dtype=np.bool_)
    return _clusters(known, ex, max(int(min_size), 1), index, flat, int(origin[0]), int(origin[1]))


def view_labels(known: np.ndarray, cells: np.ndarray, owner: np.ndarray, reach: int
                ) -> tuple[np.ndarray, np.ndarray]:
    """Every cell within ``reach`` 4-connected steps through FREE cells of a frontier cell (the frontier
    cells included) as (flat index int64[V], frontier int64[V]); a cell in reach of several frontiers
    belongs to the lowest-index one among those that reach it in the fewest steps (the rule of
    :func:`algorithms.tnf_utility.frontier_targets`)."""
    h, w = known.shape
    slot, depth, _ = _SCRATCH.get(h * w)
    return _view_labels(known, cells, owner, reach, slot, depth)


@njit(cache=True)
def _frontier_flat(known, out):  # pragma: no cover - compiled
    """Flat indices of the FREE cells with an UNSEEN 4-neighbour, in row-major order, into ``out``; returns
    their number. The mask of each row is :func:`swarm.grid.frontier_mask`'s rule in the same branch-free
    form (it vectorises); the row is then scanned eight cells at a time, as frontier cells are rare."""
    h, w = known.shape
    wp = ((w + 7) // 8) * 8
    row = np.zeros(wp, np.uint8)
    packed = row.view(np.uint64)
    n = 0
    for r in range(h):
        up = known[r - 1] if r > 0 else known[r]
        down = known[r + 1] if r + 1 < h else known[r]
        k = known[r]
        for c in range(1, w - 1):
            row[c] = (k[c] == 1) & ((up[c] == 0) | (down[c] == 0) | (k[c - 1] == 0) | (k[c + 1] == 0))
        for c in (0, w - 1):
            side = (up[c] == 0) | (down[c] == 0)
            if c > 0:
                side |= k[c - 1] == 0
            if c + 1 < w:
                side |= k[c + 1] == 0
            row[c] = (k[c] == 1) & side
        for i in range(wp // 8):
            if packed[i]:
                for c in range(8 * i, 8 * i + 8):
                    if row[c]:
                        out[n] = r * w + c
                        n += 1
    return n


@njit(cache=True, inline="always")
def _root(parent, i):  # pragma: no cover - compiled
    while parent[i] != i:
        parent[i] = parent[parent[i]]
        i = parent[i]
    return i


@njit(cache=True, inline="always")
def _join(parent, i, j):  # pragma: no cover - compiled
    """Union keeping the lower index as the root, so a cluster's root is its first cell in row-major order."""
    a = _root(parent, i)
    b = _root(parent, j)
    if a < b:
        parent[b] = a
    elif b < a:
        parent[a] = b


@njit(cache=True)
def _clusters(known, exclude, min_size, index, flat, r_off, c_off):  # pragma: no cover - compiled
    """:func:`frontier_clusters`: 8-connected clusters numbered by their first cell in row-major order
    (scipy's labelling order), cells grouped by cluster and row-major within, centroids summed in that
    order (as ``np.bincount`` sums), excluded cells removed after clustering, small clusters dropped, and
    the representative the first cell nearest the centroid. ``index``: int32[H * W] all -1 (left so).
    ``r_off, c_off``: added to every cell's row and column in the centroid arithmetic (a window's origin)."""
    h, w = known.shape
    n = _frontier_flat(known, flat)
    for i in range(n):
        index[flat[i]] = i
    parent = np.arange(n)
    for i in range(n):
        p = flat[i]
        r = p // w
        c = p - r * w
        if c > 0 and index[p - 1] >= 0:
            _join(parent, i, index[p - 1])
        if r > 0:
            for dc in (-1, 0, 1):
                cc = c + dc
                if 0 <= cc < w and index[p - w + dc] >= 0:
                    _join(parent, i, index[p - w + dc])
    for i in range(n):
        index[flat[i]] = -1
    # number the clusters by first cell; group the cells by cluster, row-major within
    label_of = np.full(n, -1, np.int64)
    lab = np.empty(n, np.int64)
    m = 0
    for i in range(n):
        root = _root(parent, i)
        if label_of[root] < 0:
            label_of[root] = m
            m += 1
        lab[i] = label_of[root]
    size0 = np.zeros(m, np.int64)
    for i in range(n):
        size0[lab[i]] += 1
    pos = np.zeros(m, np.int64)
    for j in range(1, m):
        pos[j] = pos[j - 1] + size0[j - 1]
    rows = np.empty(n, np.int64)
    cols = np.empty(n, np.int64)
    glab = np.empty(n, np.int64)
    for i in range(n):
        j = pos[lab[i]]
        pos[lab[i]] += 1
        rows[j] = flat[i] // w
        cols[j] = flat[i] - rows[j] * w
        glab[j] = lab[i]
    cy = np.zeros(m)
    cx = np.zeros(m)
    for j in range(n):
        cy[glab[j]] += rows[j] + r_off + 0.5
        cx[glab[j]] += cols[j] + c_off + 0.5
    for q in range(m):
        cy[q] = cy[q] / size0[q]
        cx[q] = cx[q] / size0[q]
    # exclusion (after clustering), sizes of what is left, the size filter
    has_ex = exclude.shape[0] == h
    keep = np.ones(n, np.bool_)
    size = np.zeros(m, np.int64)
    for j in range(n):
        if has_ex and exclude[rows[j], cols[j]]:
            keep[j] = False
        else:
            size[glab[j]] += 1
    new = np.full(m, -1, np.int64)
    f = 0
    for q in range(m):
        if size[q] >= min_size:
            new[q] = f
            f += 1
    count = 0
    for j in range(n):
        if keep[j] and new[glab[j]] >= 0:
            count += 1
    cells = np.empty((count, 2), np.int64)
    owner = np.empty(count, np.int64)
    sizes = np.empty(f, np.int64)
    rep = np.empty((f, 2), np.int64)
    best = np.full(f, np.inf)
    t = 0
    for j in range(n):
        q = glab[j]
        if not keep[j] or new[q] < 0:
            continue
        o = new[q]
        cells[t, 0] = rows[j]
        cells[t, 1] = cols[j]
        owner[t] = o
        a = rows[j] + r_off + 0.5 - cy[q]
        b = cols[j] + c_off + 0.5 - cx[q]
        d2 = a * a + b * b
        if d2 < best[o]:   # strictly: ties keep the first cell
            best[o] = d2
            rep[o, 0] = rows[j]
            rep[o, 1] = cols[j]
        t += 1
    for q in range(m):
        if new[q] >= 0:
            sizes[new[q]] = size[q]
    return cells, owner, sizes, rep


@njit(cache=True)
def _view_labels(known, cells, owner, reach, slot, depth):  # pragma: no cover - compiled
    """:func:`view_labels`, breadth first, one depth at a time: a cell first met at depth ``step`` takes
    the label of the cell it was met from, and a lower label from another cell of depth ``step - 1``
    replaces it. ``slot`` (a visited cell's index in the output) and ``depth``: int32[H * W], all -1
    (left so)."""
    h, w = known.shape
    kf = known.reshape(h * w)
    n0 = cells.shape[0]
    cap = max(16, 8 * n0)
    out = np.empty(cap, np.int64)
    lab = np.empty(cap, np.int64)
    for i in range(n0):
        p = cells[i, 0] * w + cells[i, 1]
        out[i] = p
        lab[i] = owner[i]
        slot[p] = i
        depth[p] = 0
    n = n0
    head = 0
    for step in range(1, reach + 1):
        end = n
        while head < end:
            p = out[head]
            lp = lab[head]
            head += 1
            r = p // w
            c = p - r * w
            for k in range(4):
                if k == 0:
                    if r == 0:
                        continue
                    q = p - w
                elif k == 1:
                    if r + 1 >= h:
                        continue
                    q = p + w
                elif k == 2:
                    if c == 0:
                        continue
                    q = p - 1
                else:
                    if c + 1 >= w:
                        continue
                    q = p + 1
                if kf[q] != 1:
                    continue
                if depth[q] < 0:
                    if n == cap:
                        cap *= 2
                        bigger = np.empty(cap, np.int64)
                        bl = np.empty(cap, np.int64)
                        for i in range(n):  # not slice copies, which link numba's shape-error formatting
                            bigger[i] = out[i]
                            bl[i] = lab[i]
                        out = bigger
                        lab = bl
                    depth[q] = step
                    slot[q] = n
                    out[n] = q
                    lab[n] = lp
                    n += 1
                elif depth[q] == step and lp < lab[slot[q]]:
                    lab[slot[q]] = lp
    for i in range(n):
        slot[out[i]] = -1
        depth[out[i]] = -1
    return out[:n].copy(), lab[:n].copy()


@njit(cache=True)
def choose_targets(flat, lab, dist, representative, w):  # pragma: no cover - compiled
    """Each frontier's target among the view cells ``flat`` (labelled ``lab``) whose ``dist`` (float32, inf
    for none) is finite: the one nearest its representative cell (squared cells), then nearest by
    ``dist``, then the lower row, then column. Returns (cells int64[F, 2], (-1, -1) for none; the index
    into ``flat`` of each, -1 for none)."""
    f = representative.shape[0]
    out = np.full((f, 2), -1, np.int64)
    which = np.full(f, -1, np.int64)
    best_e = np.zeros(f, np.int64)
    for i in range(flat.shape[0]):
        d = dist[i]
        if not np.isfinite(d):
            continue
        o = lab[i]
        r = flat[i] // w
        c = flat[i] - r * w
        dr = r - representative[o, 0]
        dc = c - representative[o, 1]
        e = dr * dr + dc * dc
        j = which[o]
        if j >= 0:
            if e > best_e[o]:
                continue
            if e == best_e[o]:
                dj = dist[j]
                if d > dj:
                    continue
                if d == dj and (r > out[o, 0] or (r == out[o, 0] and c > out[o, 1])):
                    continue
        which[o] = i
        best_e[o] = e
        out[o, 0] = r
        out[o, 1] = c
    return out, which


@njit(cache=True)
def information(known, cells, owner, f, g_unseen, g_known):  # pragma: no cover - compiled
    """Per cell ``G(v_c) + sum over its 8 neighbours of G(v_n)`` (cells off the map count as known), and
    its sum per frontier in cell order (``np.bincount``'s order): (float64[N], float64[F])."""
    h, w = known.shape
    info = np.empty(cells.shape[0])
    raw = np.zeros(f)
    for i in range(cells.shape[0]):
        r = cells[i, 0]
        c = cells[i, 1]
        k = 0
        for dr in (-1, 0, 1):
            for dc in (-1, 0, 1):
                if dr == 0 and dc == 0:
                    continue
                rr = r + dr
                cc = c + dc
                if 0 <= rr < h and 0 <= cc < w and known[rr, cc] == 0:
                    k += 1
        own = g_unseen if known[r, c] == 0 else g_known
        v = own + k * g_unseen + (8 - k) * g_known
        info[i] = v
        raw[owner[i]] += v
    return info, raw
