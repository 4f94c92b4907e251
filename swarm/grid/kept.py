"""The whole-map target search's inputs, kept per map and brought up to date row band by row band.

A whole-map search (:func:`swarm.grid.nearest_reachable_unseen` when the nearest unknown is far) needs the
map's configuration space, its view cells and the mask of targets (view cells in the space). Built from
scratch they are about a third of a search, yet a robot's map changes little between two of its
searches: only a few percent of its rows differ (figures: docs/performance-history.md).

So each map keeps :class:`KeptInputs`: a 2-bit copy of the map the arrays describe
(:mod:`swarm.packed_maps`), the space padded as the search reads it (the unpadded space is a view of its
interior) and the targets (its view cells in the space). :func:`refresh` compares the map with the copy
eight cells at a time and recomputes only the rows within ``margin`` of a changed row, where ``margin`` covers
everything a row depends on (the erosion's row offsets for the space; ``reach`` steps plus the frontier
test's neighbour for the view cells). It runs the same kernels on a slice of the map that extends
``margin`` rows beyond the band and keeps the band's rows, which the slice's edges cannot reach, so every
kept row is what a whole-map computation gives, bit for bit (``tests/swarm/grid/test_grid_kept.py`` checks it
on growing maps).

Entries are found by the map's buffer (a robot's knowledge map is one array for a whole run), but an entry
is never trusted: any map is compared with the copy, so a reused buffer or a different map only means more
rows to recompute. The targets kept are those without an exclusion mask; a search with one computes its
own (the space is kept either way). :mod:`swarm.grid.memo` holds on to the copy and the space
instead of copying them, and trusts them only while the entry's ``version`` is the one it saw.
"""

from __future__ import annotations

import threading
from collections import OrderedDict
from typing import NamedTuple

import numpy as np
from numba import njit

from ..packed_maps import copy_cell_if_changed, pack8, packed_size
from ._kernels import grid_configuration_space, grid_view_cells
from .local import NO_TARGET, mark_targets, search_targets

MAX_ENTRIES = 64
"""Maps kept per thread: one per robot of a team of up to 64. Each entry holds four map-sized byte arrays
(360 KB for a 150 m map, 1.4 MB for a 300 m one); the least recently searched map is dropped first, and
all of them when a map of another size comes (as :mod:`swarm.grid.memo` does). A team larger than this
searches its maps round robin, so every search would find its entry dropped and rebuild it: at 32 entries
that made a 64-robot run cost 2.3x a 32-robot one instead of 2x (docs/performance-history.md)."""

_NEVER = 255
"""Fills a new entry's copy (every cell 3): no knowledge map holds it, so the first refresh recomputes
every row."""


class KeptInputs(NamedTuple):
    copy: np.ndarray      # uint8[ceil(H W / 4)]: the map the other arrays describe, 2 bits a cell
    space: np.ndarray     # uint8[H, W]: its configuration space (0/1): the interior of ``pad``, not a copy
    pad: np.ndarray       # uint8[H + 2, W + 2]: the space with a blocked one-cell border, as the search reads it
    targets: np.ndarray   # uint8[ceil((H + 2) (W + 2) / 8)]: view cells (no exclusion) in the space, a bit
    #                       per cell of ``pad`` (swarm.grid._kernels.grid_bucket_search's bit layout)
    row_targets: np.ndarray  # int64[H]: targets per row, so the total costs H additions
    version: np.ndarray   # int64[1]: counts the refreshes that changed something (see swarm.grid.memo)


Key = tuple[int, tuple[int, int], float, float, bool, int]


class _Kept(threading.local):
    def __init__(self) -> None:
        self.entries: OrderedDict[Key, KeptInputs] = OrderedDict()
        self.far: set[Key] = set()  # kept maps whose last target search went past its window (went_far)
        self.dist = np.zeros(0, dtype=np.float64)      # all inf between searches (see clean_workspace)
        self.touched = np.zeros(0, dtype=np.int32)


_KEPT = _Kept()


def inputs_for(known: np.ndarray, radius_m: float, margin_m: float, unseen_ok: bool, reach: int, *,
               keep: bool = True, key: Key | None = None) -> KeptInputs:
    """The kept inputs for the map in ``known``'s buffer with these search parameters (a new entry when
    there is none); call :func:`refresh` before using them. ``keep=False`` gives new inputs that are not
    kept: for a map converted for this one search (another dtype or layout), whose buffer is gone after it.
    ``key``: :func:`key_of` for these arguments, when the caller already has it (reading the buffer's
    address costs more than the dictionary lookup)."""
    h, w = known.shape
    if not keep:
        return _new_inputs(h, w)
    if key is None:
        key = key_of(known, radius_m, margin_m, unseen_ok, reach)
    entries = _KEPT.entries
    entry = entries.get(key)
    if entry is None:
        if entries and next(iter(entries.values())).space.shape != (h, w):
            forget_all()  # another run's map size: those entries can never be found again
        entry = entries[key] = _new_inputs(h, w)
        while len(entries) > MAX_ENTRIES:
            _KEPT.far.discard(entries.popitem(last=False)[0])
    entries.move_to_end(key)
    return entry


def key_of(known: np.ndarray, radius_m: float, margin_m: float, unseen_ok: bool, reach: int) -> Key:
    """The key of the map in ``known``'s buffer with these search parameters."""
    return known.__array_interface__["data"][0], known.shape, radius_m, margin_m, unseen_ok, reach


def went_far(key: Key) -> bool:
    """Whether the last target search on this kept map found its target only past the local window (or
    none): a hint for :func:`swarm.grid.nearest_reachable_unseen`, which then skips the window, because
    the next search most likely goes far too. A hint only: both stages give the same answer."""
    return key in _KEPT.far


def note_far(key: Key, far: bool) -> None:
    """Record for :func:`went_far` how the search on a kept map (one with an entry) ended."""
    if far and key in _KEPT.entries:
        _KEPT.far.add(key)
    else:
        _KEPT.far.discard(key)


def _new_inputs(h: int, w: int) -> KeptInputs:
    pad = np.zeros((h + 2, w + 2), np.uint8)  # the space is its interior: one array less per kept map (-0.36 MB
    # per robot on a 300-tile map; docs/performance-history.md)
    return KeptInputs(np.full(packed_size(h * w), _NEVER, np.uint8), pad[1:-1, 1:-1], pad,
                      np.zeros(((h + 2) * (w + 2) + 7) // 8, np.uint8), np.zeros(h, np.int64), np.zeros(1, np.int64))


def clean_workspace(n: int) -> tuple[np.ndarray, np.ndarray]:
    """This thread's distance array for whole-map searches of ``n`` padded cells, all inf, and room for the
    list of cells a search touches (:func:`swarm.grid._kernels.grid_bucket_search`): the search sets those
    back to inf, so the next one need not fill 730 KB (a 300 x 300 map) first, ~25 us in the run."""
    k = _KEPT
    if k.dist.shape[0] != n:
        k.dist = np.full(n, np.inf)
        k.touched = np.empty(4 * n, dtype=np.int32)
    return k.dist, k.touched


def forget_all() -> None:
    """Drop every kept entry of this thread, and the hints about them."""
    _KEPT.entries.clear()
    _KEPT.far.clear()


@njit(cache=True)
def refresh(known, copy, space, pad, targets, row_targets, version, unseen_ok, row_offsets, half_widths,
            reach, margin):  # pragma: no cover - compiled
    """Bring the arrays of :class:`KeptInputs` up to date with ``known`` (``version`` counts up when
    anything changed); ``margin`` >= the erosion depth and >= ``reach + 1``. Returns the number of
    targets. ``pad`` is written through ``space``, its interior."""
    h, w = known.shape
    cur = known.reshape(-1)
    words = cur.shape[0] // 8
    cur64, prev16 = cur[:8 * words].view(np.uint64), copy[:2 * words].view(np.uint16)
    dirty = np.zeros(h, np.bool_)
    for k in range(words):  # a map differs from its last search's in a few words: compare 8 cells at once
        if pack8(cur64[k]) != np.uint64(prev16[k]):
            for i in range(8 * k, 8 * k + 8):
                if copy_cell_if_changed(cur, copy, i):
                    dirty[i // w] = True
    for i in range(8 * words, cur.shape[0]):
        if copy_cell_if_changed(cur, copy, i):
            dirty[i // w] = True
    changed = np.zeros(h, np.bool_)
    any_change = False
    for r in range(h):
        if dirty[r]:
            any_change = True
            for rr in range(max(r - margin, 0), min(r + margin + 1, h)):
                changed[rr] = True
    r = 0
    while r < h:
        if not changed[r]:
            r += 1
            continue
        a = r
        while r < h and changed[r]:
            r += 1
        _recompute_band(known, a, r, space, targets, row_targets, unseen_ok, row_offsets,
                        half_widths, reach, margin)
    if any_change:
        version[0] += 1
    total = 0
    for r in range(h):
        total += row_targets[r]
    return total


@njit(cache=True, inline="always")
def _recompute_band(known, a, b, space, targets, row_targets, unseen_ok, row_offsets, half_widths,
                    reach, margin):  # pragma: no cover - compiled
    """Rows ``a:b`` of the space and targets, from the slice of ``known`` that extends
    ``margin`` rows beyond them (clipped to the map, whose edge the kernels treat as the map's edge)."""
    h, w = known.shape
    lo = max(a - margin, 0)
    hi = min(b + margin, h)
    part = known[lo:hi]
    part_space = np.empty((hi - lo, w), np.uint8)
    grid_configuration_space(part, unseen_ok, row_offsets, half_widths, part_space)
    seen = np.zeros((hi - lo, w), np.bool_)
    grid_view_cells(part, np.zeros((0, 0), np.bool_), reach, seen)
    for r in range(a, b):
        sp = part_space[r - lo]
        vw = seen[r - lo]
        krow = space[r]  # pad's row r + 1, within its border
        q = (r + 1) * (w + 2) + 1  # the bit of (r, 0) in the padded layout
        count = 0
        for c in range(w):
            krow[c] = sp[c]
            t = vw[c] & (sp[c] != 0)
            j, b = (q + c) >> 3, (q + c) & 7
            targets[j] = (np.int64(targets[j]) & ~(1 << b)) | (np.int64(t) << b)
            count += t
        row_targets[r] = count


@njit(cache=True)
def map_target(known, exclude, reach, unseen_ok, row_offsets, half_widths, sr, sc, snap, dist, ring, touched, copy,
               space, pad, targets, row_targets, version, margin):  # pragma: no cover - compiled
    """The whole-map stage of :func:`swarm.grid.nearest_reachable_unseen` in one call: :func:`refresh` the
    kept inputs (``copy`` .. ``version``, see :class:`KeptInputs`), then snap and search
    (:func:`swarm.grid.local.search_targets`, on the all-inf ``dist`` of :func:`clean_workspace`, which it
    leaves all inf). With an exclusion mask (``exclude`` bool[H, W], or empty
    for none) the targets are computed afresh from the kept space. Returns what
    ``search_targets`` returns, with the path to the target (for :mod:`swarm.grid.memo`) and the kept
    space."""
    h, w = known.shape
    total = refresh(known, copy, space, pad, targets, row_targets, version, unseen_ok, row_offsets,
                    half_widths, reach, margin)
    marks = targets
    if exclude.shape[0] == h:
        seen = np.zeros((h, w), np.bool_)
        marks = np.zeros((h + 2) * (w + 2), np.uint8)  # a byte per cell, computed for this search only
        total = 0
        if grid_view_cells(known, exclude, reach, seen) > 0:
            total = mark_targets(seen, pad, exclude, marks.reshape(h + 2, w + 2))
    if total == 0:
        return NO_TARGET, -1, -1, np.inf, -1, -1, np.empty((0, 0), np.uint8), np.empty((0, 2), np.int64)
    return search_targets(space, pad, marks, sr, sc, snap, True, dist, ring, touched)
