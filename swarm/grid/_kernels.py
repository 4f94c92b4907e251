"""numba kernels behind :mod:`swarm.grid`: one exact shortest-path search and the supercover line test.

The search is Dijkstra with Dinitz's bucket queue. Distances are in cells (orthogonal step 1, diagonal
step sqrt(2)); bucket ``k`` holds cells whose tentative distance is in ``[k, k + 1)``. Because every step
costs at least 1, no cell in bucket ``k`` can improve another cell of bucket ``k``: when the search
reaches a bucket, all its cells are final and can be settled in any order. A step costs at most
sqrt(2) < 2, so only buckets k, k+1 and k+2 are ever live and three ring slots suffice. This gives an
exact octile shortest path with O(1) queue operations (no heap; its cost per call:
``benchmarks/speed/bench_grid.py``, docs/performance-history.md).

Grids arrive padded with one blocked cell on every side and flattened, so neighbours are fixed index
offsets and no bounds checks are needed.

Determinism: relaxation only accepts an improvement larger than ``EPS`` (so paths of equal octile length
that differ only by floating-point rounding do not replace each other), buckets are processed in insertion
order and neighbours in a fixed order (E, W, N, S, NE, NW, SE, SW); among the target cells of the first
bucket that contains any, the nearest wins with ties (within ``EPS``) to the lowest flat index, i.e. the
lowest row, then column; paths are read back from the distances by a fixed rule
(:func:`grid_descend_path`). Same inputs, same answer.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from swarm.base.types import CELL_M

SQRT2 = 1.4142135623730951
EPS = 1e-9
NO_TOUCHED = np.zeros(0, dtype=np.int32)


@njit(cache=True, inline="always")
def _grid_relax(q, nd, fk, dist, ring, count, n, s1, s2):  # pragma: no cover - compiled
    """Lower ``dist[q]`` to ``nd`` if better, queueing ``q`` when it changes bucket.

    While bucket ``fk`` is processed, ``nd`` lies in bucket fk+1 (ring slot s1) or fk+2 (slot s2), and a
    cell not yet settled had a distance of at least fk+1, so comparing with fk+2 and fk+3 tells whether
    it already sits in the new bucket (each cell enters each bucket at most once, so a slot never holds
    more than n entries). ``q`` is unsigned (see :func:`grid_bucket_search`).
    """
    old = dist[q]
    if nd < old - EPS:
        dist[q] = nd
        if nd < fk + 2.0:
            if old >= fk + 2.0:
                ring[np.uint64(s1 * n + count[s1])] = q
                count[s1] += 1
        elif old >= fk + 3.0:
            ring[np.uint64(s2 * n + count[s2])] = q
            count[s2] += 1


@njit(cache=True, inline="always")
def _is_target(targets, p, bits):  # pragma: no cover - compiled
    """Whether cell ``p`` is marked in ``targets``, a byte or (``bits``) a bit per cell."""
    if bits:
        return (targets[p >> 3] >> (p & 7)) & 1 != 0
    return targets[np.uint64(p)] != 0


@njit(cache=True)
def grid_bucket_search(free: np.ndarray, wp: int, seeds: np.ndarray, goal: int, targets: np.ndarray,
                       max_d: float, dist: np.ndarray, ring: np.ndarray,
                       touched: np.ndarray):  # pragma: no cover - compiled
    """Exact octile Dijkstra from ``seeds`` over cells with ``free[p] != 0``.

    free: uint8[n] padded flat grid. seeds: int64[K] flat indices of free cells. goal: a flat index to
    stop at, or -1. targets: the cells to stop at the nearest of, a byte each (uint8[n]) or a bit each
    (uint8[ceil(n / 8)], cell p in bit p % 8 of byte p // 8, as ``np.packbits(..., bitorder="little")``
    lays them out: an eighth of the memory for targets kept between searches), or an empty array. max_d: stop once the
    settled distance passes this (cells). dist: float64[n] workspace, overwritten with the result; ring:
    int32 workspace of at least 3 n entries. touched: an empty array (:data:`NO_TOUCHED`), or an int32
    array of at least 4 n entries; then ``dist`` must be all inf on entry (it is not filled: for a whole
    map that fill is 730 KB) and every cell given a distance is listed in ``touched`` (some more than
    once), so the caller can set them back to inf.

    Returns (best target index or -1, its distance, number of ``touched`` entries written). When the
    search stops early, cells beyond the last settled bucket hold tentative distances larger than every
    settled one; the callers only read settled cells.
    """
    n = free.shape[0]
    record = touched.shape[0] > 0
    if not record:
        dist[:] = np.inf
    nt = 0
    count = np.zeros(3, dtype=np.int64)
    target_bits = n > 8 and targets.shape[0] == (n + 7) // 8  # (a padded grid has at least 9 cells)
    has_targets = targets.shape[0] == n or target_bits
    for i in range(seeds.shape[0]):
        s = seeds[i]
        if dist[s] != 0.0:
            dist[s] = 0.0
            ring[count[0]] = s
            count[0] += 1
            if record:
                touched[nt] = s
                nt += 1
    best = -1
    best_d = np.inf
    k = 0
    slot = 0
    one = np.uint64(1)
    up = np.uint64(wp)
    while count[0] + count[1] + count[2] > 0:
        if k > max_d:
            break
        s1 = slot + 1 if slot < 2 else 0
        s2 = s1 + 1 if s1 < 2 else 0
        base = slot * n
        m = count[slot]
        fk = float(k)
        if goal >= 0 and dist[goal] < fk + 1.0:
            best = goal
            best_d = dist[goal]
            break
        if has_targets and m > 0:
            for i in range(m):
                p = ring[np.uint64(base + i)]
                d = dist[np.uint64(p)]
                if d >= fk and _is_target(targets, p, target_bits):
                    if d < best_d - EPS or (d <= best_d + EPS and p < best):
                        best = p
                        best_d = d
            if best >= 0:
                break
        for i in range(m):
            # Unsigned cell indices (all in the padded grid): numba compiles no negative-index wrap-around
            # for them, ~20 % of the search's time.
            p = np.uint64(ring[np.uint64(base + i)])
            dp = dist[p]
            if dp < fk:  # stale: settled earlier from a lower bucket
                continue
            if record:
                touched[np.uint64(nt)] = p
                nt += 1
            e = free[p + one] != 0
            w = free[p - one] != 0
            nn = free[p + up] != 0
            ss = free[p - up] != 0
            if e:
                _grid_relax(p + one, dp + 1.0, fk, dist, ring, count, n, s1, s2)
            if w:
                _grid_relax(p - one, dp + 1.0, fk, dist, ring, count, n, s1, s2)
            if nn:
                _grid_relax(p + up, dp + 1.0, fk, dist, ring, count, n, s1, s2)
            if ss:
                _grid_relax(p - up, dp + 1.0, fk, dist, ring, count, n, s1, s2)
            dd = dp + SQRT2
            if nn:
                if e and free[p + up + one] != 0:
                    _grid_relax(p + up + one, dd, fk, dist, ring, count, n, s1, s2)
                if w and free[p + up - one] != 0:
                    _grid_relax(p + up - one, dd, fk, dist, ring, count, n, s1, s2)
            if ss:
                if e and free[p - up + one] != 0:
                    _grid_relax(p - up + one, dd, fk, dist, ring, count, n, s1, s2)
                if w and free[p - up - one] != 0:
                    _grid_relax(p - up - one, dd, fk, dist, ring, count, n, s1, s2)
        count[slot] = 0
        k += 1
        slot = s1
    if record:  # cells still queued (tentative, or settled when the search stopped at their bucket)
        for sl in range(3):
            for i in range(count[sl]):
                touched[nt] = ring[sl * n + i]
                nt += 1
    return best, best_d, nt


@njit(cache=True)
def grid_bucket_settle(free: np.ndarray, wp: int, seeds: np.ndarray, marks: np.ndarray, remaining: int,
                       max_d: float, dist: np.ndarray, ring: np.ndarray,
                       touched: np.ndarray) -> int:  # pragma: no cover - compiled
    """:func:`grid_bucket_search` without a goal that stops once every marked cell is settled.

    marks: uint8[n], nonzero at the ``remaining`` distinct cells whose distances the caller wants (cells
    outside the space may be marked: they are never settled, so the search then runs to its end). The
    other arguments are :func:`grid_bucket_search`'s (``touched`` required, ``dist`` all inf on entry).
    Seeds, buckets and neighbours are processed in exactly its order, so every settled cell holds the
    distance the whole search gives it, bit for bit; stopping after the last marked cell only leaves the
    farther part of the map unsearched. Returns the number of ``touched`` entries written.
    """
    n = free.shape[0]
    nt = 0
    count = np.zeros(3, dtype=np.int64)
    for i in range(seeds.shape[0]):
        s = seeds[i]
        if dist[s] != 0.0:
            dist[s] = 0.0
            ring[count[0]] = s
            count[0] += 1
            touched[nt] = s
            nt += 1
    k = 0
    slot = 0
    one = np.uint64(1)
    up = np.uint64(wp)
    while remaining > 0 and count[0] + count[1] + count[2] > 0:
        if k > max_d:
            break
        s1 = slot + 1 if slot < 2 else 0
        s2 = s1 + 1 if s1 < 2 else 0
        base = slot * n
        m = count[slot]
        fk = float(k)
        for i in range(m):
            p = np.uint64(ring[np.uint64(base + i)])
            dp = dist[p]
            if dp < fk:  # stale: settled earlier from a lower bucket
                continue
            touched[np.uint64(nt)] = p
            nt += 1
            if marks[p] != 0:
                remaining -= 1
                if remaining == 0:
                    break
            e = free[p + one] != 0
            w = free[p - one] != 0
            nn = free[p + up] != 0
            ss = free[p - up] != 0
            if e:
                _grid_relax(p + one, dp + 1.0, fk, dist, ring, count, n, s1, s2)
            if w:
                _grid_relax(p - one, dp + 1.0, fk, dist, ring, count, n, s1, s2)
            if nn:
                _grid_relax(p + up, dp + 1.0, fk, dist, ring, count, n, s1, s2)
            if ss:
                _grid_relax(p - up, dp + 1.0, fk, dist, ring, count, n, s1, s2)
            dd = dp + SQRT2
            if nn:
                if e and free[p + up + one] != 0:
                    _grid_relax(p + up + one, dd, fk, dist, ring, count, n, s1, s2)
                if w and free[p + up - one] != 0:
                    _grid_relax(p + up - one, dd, fk, dist, ring, count, n, s1, s2)
            if ss:
                if e and free[p - up + one] != 0:
                    _grid_relax(p - up + one, dd, fk, dist, ring, count, n, s1, s2)
                if w and free[p - up - one] != 0:
                    _grid_relax(p - up - one, dd, fk, dist, ring, count, n, s1, s2)
        if remaining == 0:
            break
        count[slot] = 0
        k += 1
        slot = s1
    for sl in range(3):  # cells still queued (tentative, or settled when the search stopped in their bucket)
        for i in range(count[sl]):
            touched[nt] = ring[sl * n + i]
            nt += 1
    return nt


@njit(cache=True)
def grid_read_metres(dist: np.ndarray, cells: np.ndarray, max_d: float, touched: np.ndarray, nt: int,
                     out: np.ndarray) -> None:  # pragma: no cover - compiled
    """``out[i]`` = :func:`grid_field_metres`'s value at the padded flat index ``cells[i]`` (float32 metres,
    inf beyond ``max_d`` cells), then every ``touched[:nt]`` cell of ``dist`` back to inf."""
    for i in range(cells.shape[0]):
        d = dist[cells[i]]
        out[i] = d * CELL_M if d <= max_d + EPS else np.inf
    for i in range(nt):
        dist[touched[i]] = np.inf


@njit(cache=True)
def grid_field_metres(dist: np.ndarray, wp: int, max_d: float, out: np.ndarray) -> None:  # pragma: no cover
    """Write the padded cell distances into ``out`` (float32[H, W]) in metres; inf beyond ``max_d`` cells."""
    h, w = out.shape
    for r in range(h):
        base = (r + 1) * wp + 1
        for c in range(w):
            d = dist[base + c]
            out[r, c] = d * CELL_M if d <= max_d + EPS else np.inf


@njit(cache=True)
def grid_descend_path(free: np.ndarray, wp: int, dist: np.ndarray,
                      goal: int) -> np.ndarray:  # pragma: no cover - compiled
    """Walk from ``goal`` down the settled distance field to a seed; int64[N, 2] (row, col), seed first.

    At each cell the predecessor is a neighbour ``q`` (reachable by a legal step) with
    ``dist[q] + step == dist[cell]``. Several may qualify (equal-length paths); the one continuing the
    previous step's direction is preferred, then the fixed order E, W, N, S, NE, NW, SE, SW. Keeping the
    direction gives long straight runs, which :func:`grid_shortcut` then turns into few waypoints.
    """
    steps = np.array([1, -1, wp, -wp, wp + 1, wp - 1, -wp + 1, -wp - 1], dtype=np.int64)
    cost = np.array([1.0, 1.0, 1.0, 1.0, SQRT2, SQRT2, SQRT2, SQRT2])
    cap = 1
    buf = np.empty(64, dtype=np.int64)
    buf[0] = goal
    p = goal
    last = -1
    while dist[p] > 0.0:
        found = -1
        for t in range(9):
            j = last if t == 0 else t - 1
            if j < 0 or (t > 0 and j == last):
                continue
            q = p - steps[j]
            if free[q] == 0:
                continue
            if j >= 4:  # the step q -> p is diagonal: both cells beside it must be free
                dr = steps[j] - (1 if j == 4 or j == 6 else -1)
                if free[q + dr] == 0 or free[p - dr] == 0:
                    continue
            if dist[q] + cost[j] <= dist[p] + EPS:
                found = j
                break
        if found < 0:  # cannot happen on a settled field; stop rather than loop
            break
        p = p - steps[found]
        last = found
        if cap == buf.shape[0]:
            bigger = np.empty(2 * cap, dtype=np.int64)
            for i in range(cap):  # not a slice copy, which links numba's shape-error formatting
                bigger[i] = buf[i]
            buf = bigger
        buf[cap] = p
        cap += 1
    out = np.empty((cap, 2), dtype=np.int64)
    for i in range(cap):
        out[i, 0] = buf[cap - 1 - i] // wp - 1
        out[i, 1] = buf[cap - 1 - i] % wp - 1
    return out


@njit(cache=True, inline="always")
def grid_segment_clear(space: np.ndarray, r0: int, c0: int, r1: int, c1: int) -> bool:  # pragma: no cover
    """True when every cell touched by the segment between the two cell centres is True in ``space``.

    Supercover walk in exact integer arithmetic: the segment meets the k-th column boundary at parameter
    (k + 1/2) / |dc| and the k-th row boundary at (k + 1/2) / |dr|; comparing (2k + 1) |dr| with
    (2l + 1) |dc| tells which comes first. When both come at once the segment passes through a cell corner
    and all four cells around it are tested, since a robot centred on that corner overlaps all four.
    """
    if not space[r0, c0]:
        return False
    nr = abs(r1 - r0)
    nc = abs(c1 - c0)
    sr = 1 if r1 > r0 else -1
    sc = 1 if c1 > c0 else -1
    r = r0
    c = c0
    ir = 0
    ic = 0
    while ir < nr or ic < nc:
        a = (2 * ic + 1) * nr
        b = (2 * ir + 1) * nc
        if a == b:
            if not space[r, c + sc] or not space[r + sr, c]:
                return False
            r += sr
            c += sc
            ir += 1
            ic += 1
        elif a < b:
            c += sc
            ic += 1
        else:
            r += sr
            ir += 1
        if not space[r, c]:
            return False
    return True


@njit(cache=True)
def grid_shortcut(space: np.ndarray, path: np.ndarray) -> np.ndarray:  # pragma: no cover - compiled
    """Indices of the path cells kept by greedy line-of-sight shortcutting (first and last always kept).

    From each kept cell, extend the straight segment along the path while its supercover stays in
    ``space``; the last cell it reached is kept next. A step to the next path cell is always taken, so a
    valid input path gives a valid output, and by the triangle inequality it is never longer.
    """
    n = path.shape[0]
    keep = np.empty(n, dtype=np.int64)
    keep[0] = 0
    m = 1
    i = 0
    while i < n - 1:
        best = i + 1
        for j in range(i + 2, n):
            if grid_segment_clear(space, path[i, 0], path[i, 1], path[j, 0], path[j, 1]):
                best = j
            else:
                break
        keep[m] = best
        m += 1
        i = best
    return keep[:m]


@njit(cache=True)
def grid_frontier_mask(known: np.ndarray, exclude: np.ndarray, view: np.ndarray) -> None:  # pragma: no cover
    """``view`` = FREE cells with an UNSEEN 4-neighbour, minus ``exclude`` (or an empty array for none).

    Branch-free over each row's interior so the compiler vectorises it (about 10x the speed of testing
    cell by cell); a missing neighbour row is replaced by the row itself, which can never add a frontier
    cell (a cell must be FREE, not UNSEEN)."""
    h, w = known.shape
    for r in range(h):
        up = known[r - 1] if r > 0 else known[r]
        down = known[r + 1] if r + 1 < h else known[r]
        row = known[r]
        out = view[r]
        for c in range(1, w - 1):
            out[c] = (row[c] == 1) & ((up[c] == 0) | (down[c] == 0) | (row[c - 1] == 0) | (row[c + 1] == 0))
        for c in (0, w - 1):
            side = (up[c] == 0) | (down[c] == 0)
            if c > 0:
                side |= row[c - 1] == 0
            if c + 1 < w:
                side |= row[c + 1] == 0
            out[c] = (row[c] == 1) & side
    if exclude.shape[0] == h:
        for r in range(h):
            for c in range(w):
                view[r, c] = view[r, c] > exclude[r, c]  # a and not b, without a branch


@njit(cache=True)
def grid_view_cells(known: np.ndarray, exclude: np.ndarray, reach: int,
                    view: np.ndarray) -> int:  # pragma: no cover - compiled
    """Mark in ``view`` (bool[H, W], C-contiguous, all False on entry) the FREE cells at most ``reach``
    4-connected steps through FREE cells from a frontier cell (FREE with an UNSEEN 4-neighbour) that
    ``exclude`` does not hold (``exclude``: bool[H, W], or an empty array for none). Returns the number of
    frontier cells.

    One vectorised pass for the frontier cells, collected eight at a time (frontier cells are rare: a
    whole-map search on a 300 x 300 map finds ~160), then a breadth-first search bounded by ``reach``.
    """
    h, w = known.shape
    grid_frontier_mask(known, exclude, view)
    flat = view.reshape(-1)
    queue = np.empty(h * w, np.int32)
    n = 0
    words = flat.shape[0] // 8
    packed = flat[:8 * words].view(np.uint64)
    for i in range(words):
        if packed[i]:
            for p in range(8 * i, 8 * i + 8):
                if flat[p]:
                    queue[n] = p
                    n += 1
    for p in range(8 * words, flat.shape[0]):
        if flat[p]:
            queue[n] = p
            n += 1
    frontier = n
    head = 0
    for _ in range(reach):
        end = n
        while head < end:
            p = queue[head]
            head += 1
            r = p // w
            c = p - r * w
            if r > 0 and not view[r - 1, c] and known[r - 1, c] == 1:
                view[r - 1, c] = True
                queue[n] = p - w
                n += 1
            if r + 1 < h and not view[r + 1, c] and known[r + 1, c] == 1:
                view[r + 1, c] = True
                queue[n] = p + w
                n += 1
            if c > 0 and not view[r, c - 1] and known[r, c - 1] == 1:
                view[r, c - 1] = True
                queue[n] = p - 1
                n += 1
            if c + 1 < w and not view[r, c + 1] and known[r, c + 1] == 1:
                view[r, c + 1] = True
                queue[n] = p + 1
                n += 1
    return frontier


@njit(cache=True)
def grid_configuration_space(known: np.ndarray, unseen_ok: bool, row_offsets: np.ndarray, half_widths: np.ndarray,
                             out: np.ndarray) -> None:  # pragma: no cover - compiled
    """``out`` (uint8[H, W], 0/1) = passable cells whose rows ``r + row_offsets[k]`` are passable over
    columns ``c - half_widths[k] .. c + half_widths[k]`` for every k, cells off the map counting as
    blocked: the erosion of :func:`swarm.grid.configuration_space` (``row_offsets`` must include 0).

    Row runs are built once per half width (``runs[j][r, c]``: row r passable over c-j..c+j, from
    ``runs[j - 1]``), then each output row is the AND of the runs its offsets need; every inner loop is
    branch-free over a row with constant offsets, so the compiler vectorises it."""
    h, w = known.shape
    jmax = 0
    for k in range(half_widths.shape[0]):
        jmax = max(jmax, half_widths[k])
    runs = np.zeros((jmax + 1, h, w), np.uint8)
    for r in range(h):
        row = known[r]
        base = runs[0, r]
        if unseen_ok:
            for c in range(w):
                base[c] = row[c] != 2
        else:
            for c in range(w):
                base[c] = row[c] == 1
    for j in range(1, jmax + 1):  # only constant offsets in the inner loops: a variable one stops vectorising
        for r in range(h):
            prev = runs[j - 1, r]
            cur = runs[j, r]
            if j == 1:
                for c in range(1, w - 1):
                    cur[c] = prev[c - 1] & prev[c] & prev[c + 1]
            else:  # [c-j, c+j-2] and [c-j+2, c+j] cover [c-j, c+j] once j >= 2
                for c in range(j, w - j):
                    cur[c] = prev[c - 1] & prev[c + 1]
    for r in range(h):
        o = out[r]
        for c in range(w):
            o[c] = 1
        for k in range(row_offsets.shape[0]):
            rr = r + row_offsets[k]
            if rr < 0 or rr >= h:
                for c in range(w):
                    o[c] = 0
                break
            src = runs[half_widths[k], rr]
            for c in range(w):
                o[c] &= src[c]


PATH_OK, PATH_OUTSIDE, PATH_GAP = 0, 1, 2


@njit(cache=True)
def grid_path_problem(path: np.ndarray, h: int, w: int) -> int:  # pragma: no cover - compiled
    """PATH_OUTSIDE if a cell of ``path`` (int64[N, 2] rows and columns) is off an h x w grid (checked for
    the whole path first), else PATH_GAP if two consecutive cells are not 8-adjacent (or equal), else
    PATH_OK."""
    for i in range(path.shape[0]):
        if not (0 <= path[i, 0] < h and 0 <= path[i, 1] < w):
            return PATH_OUTSIDE
    for i in range(1, path.shape[0]):
        if abs(path[i, 0] - path[i - 1, 0]) > 1 or abs(path[i, 1] - path[i - 1, 1]) > 1:
            return PATH_GAP
    return PATH_OK


@njit(cache=True)
def grid_snap(space: np.ndarray, r: int, c: int, limit: int) -> tuple[int, int]:  # pragma: no cover - compiled
    """The True cell of ``space`` whose centre is nearest ``(r, c)`` within ``limit`` cells, ties to the
    lowest row then column; (-1, -1) when there is none (:func:`swarm.grid.nearest_in`).

    Looks in growing square windows: a window of half-size ``s`` is conclusive once its best cell is within
    ``s`` (every cell outside it is farther), or once it covers the grid."""
    if space[r, c]:
        return r, c
    h, w = space.shape
    full = max(h, w)
    cap = min(limit, full)
    size = 2
    while True:
        s = min(size, cap)
        best, br, bc = -1, -1, -1
        for rr in range(max(r - s, 0), min(r + s + 1, h)):
            for cc in range(max(c - s, 0), min(c + s + 1, w)):
                if space[rr, cc]:
                    d2 = (rr - r) * (rr - r) + (cc - c) * (cc - c)
                    if best < 0 or d2 < best:
                        best, br, bc = d2, rr, cc
        if best >= 0 and (best <= s * s or s >= full):
            if best > limit * limit:
                return -1, -1
            return br, bc
        if s >= cap:
            return -1, -1
        size *= 2
