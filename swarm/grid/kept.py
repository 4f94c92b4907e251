"""The whole-map target search's inputs, kept per map and brought up to date row band by row band.

A whole-map search (:func:`swarm.grid.nearest_reachable_unseen` when the nearest unknown is far) needs the
map's configuration space, its view cells and the mask of targets (view cells in the space). Built from
scratch they are about a third of a search, yet a robot's map changes little between two of its
searches: only a few percent of its rows differ (figures: docs/performance-history.md).

So each map keeps :class:`KeptInputs`: a 2-bit copy of the map the arrays describe
(:mod:`swarm.knowledge.packed`), its configuration space and its targets (view cells in the space), both a bit
per cell of the padded grid the search reads; a search unpacks the space into this thread's padded byte
grid (~15 us on a 600 x 600 map), so a kept map costs 180 KB instead of 1.4 MB (64 robots on a 300-tile
map: 12 MB instead of 89; docs/performance-history.md). :func:`refresh` compares the map with the copy
512 cells at a time (then 8, where they differ) and recomputes only the rows within ``margin`` of a
changed row, where ``margin`` covers everything a row depends on (the erosion's row offsets for the space; ``reach`` steps plus the frontier
test's neighbour for the view cells). It runs the same kernels on a slice of the map that extends
``margin`` rows beyond the band and keeps the band's rows, which the slice's edges cannot reach, so every
kept row is what a whole-map computation gives, bit for bit (``tests/swarm/grid/test_grid_kept.py`` checks it
on growing maps).

Entries are found by the map's buffer (a robot's knowledge map is one array for a whole run), but an entry
is never trusted: any map is compared with the copy, so a reused buffer or a different map only means more
rows to recompute. The targets kept are those without an exclusion mask; a search with one computes its
own (the space is kept either way). :mod:`swarm.grid.memo` holds on to the copy and the space's bits
instead of copying them, and trusts them only while the entry's ``version`` is the one it saw.
"""

from __future__ import annotations

import threading
from collections import OrderedDict
from typing import NamedTuple

import numpy as np
from numba import njit

from swarm.knowledge.packed import CHUNK_WORDS, copy_cell_if_changed, differing_words, packed_size, sync_chunk
from ._kernels import grid_configuration_space, grid_view_cells
from .local import NO_TARGET, mark_targets, search_targets

MAX_ENTRIES = 64
"""Maps kept per thread: one per robot of a team of up to 64. Each entry holds a 2-bit map and two 1-bit
ones (45 KB for a 150 m map, 180 KB for a 300 m one); the least recently searched map is dropped first, and
all of them when a map of another size comes (as :mod:`swarm.grid.memo` does). A team larger than this
searches its maps round robin, so every search would find its entry dropped and rebuild it: at 32 entries
that made a 64-robot run cost 2.3x a 32-robot one instead of 2x (docs/performance-history.md)."""

MAX_BYTES = 1 << 27
"""...and at most this much memory in all (128 MB): on a 2,000-tile building (4000 x 4000 cells) an entry is
8 MB, and a swarm of 10,000 robots never finds its entry anyway, so 64 of them would hold half a gigabyte for
nothing. Maps of 600 x 600 cells (1,000 robots: 1 MB an entry) stay at 64 entries."""

_NEVER = 255
"""Fills a new entry's copy (every cell 3): no knowledge map holds it, so the first refresh recomputes
every row."""


class KeptInputs(NamedTuple):
    copy: np.ndarray      # uint8[ceil(H W / 4)]: the map the other arrays describe, 2 bits a cell
    space: np.ndarray     # uint8[ceil((H + 2) (W + 2) / 8)]: its configuration space with a blocked border
    #                       (the search's padded grid), a bit per cell in np.packbits's little bit order
    targets: np.ndarray   # the same layout: view cells (no exclusion) in the space, as
    #                       swarm.grid._kernels.grid_bucket_search reads bit targets
    row_targets: np.ndarray  # int64[H]: targets per row, so the total costs H additions
    version: np.ndarray   # int64[1]: counts the refreshes that changed something (see swarm.grid.memo)


Key = tuple[int, tuple[int, int], float, float, bool, int]


class _Kept(threading.local):
    def __init__(self) -> None:
        self.entries: OrderedDict[Key, KeptInputs] = OrderedDict()
        self.budgets: OrderedDict[Key, int] = OrderedDict()  # the window that decided each map's last search
        self.shape: tuple[int, int] | None = None  # the size of every kept map (one size at a time)
        self.limit = MAX_ENTRIES  # how many entries of that size are kept (set with each new entry)
        self.pad = np.zeros(0, dtype=np.uint8)         # the searched map's space, unpacked (see unpack_buffer)


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
        if entries and _KEPT.shape != (h, w):
            forget_all()  # another run's map size: those entries can never be found again
        _KEPT.shape = (h, w)
        entry = entries[key] = _new_inputs(h, w)
        limit = _KEPT.limit = max(1, min(MAX_ENTRIES, MAX_BYTES // _entry_bytes(entry)))
        while len(entries) > limit:
            entries.popitem(last=False)
    entries.move_to_end(key)
    return entry


def would_evict(key: Key) -> bool:
    """Whether a whole-map search of the map ``key`` would build its inputs from scratch and drop another
    map's to keep them: the map has no entry and the entries are at their limit (a swarm larger than
    :data:`MAX_ENTRIES` searching its maps round robin, which never finds its entry)."""
    return key not in _KEPT.entries and _full(key[1])


def rebuilds(known: np.ndarray) -> bool:
    """:func:`would_evict` for any search of the map in ``known``'s buffer: none of its searches is kept and
    the entries are at their limit (so no far search remembered a plan on it either, :mod:`swarm.grid.memo`)."""
    if not _full(known.shape):  # (a team: no need to read the buffer's address)
        return False
    address = known.__array_interface__["data"][0]
    return not any(key[0] == address for key in _KEPT.entries)


def _full(shape: tuple[int, int]) -> bool:
    """Whether the entries, of maps of ``shape``, are at their limit (as :func:`inputs_for` last set it)."""
    return _KEPT.shape == shape and len(_KEPT.entries) >= _KEPT.limit


def _entry_bytes(entry: KeptInputs) -> int:
    return entry.copy.nbytes + entry.space.nbytes + entry.targets.nbytes + entry.row_targets.nbytes


def key_of(known: np.ndarray, radius_m: float, margin_m: float, unseen_ok: bool, reach: int) -> Key:
    """The key of the map in ``known``'s buffer with these search parameters."""
    return known.__array_interface__["data"][0], known.shape, radius_m, margin_m, unseen_ok, reach


WHOLE_MAP = -1
"""A :func:`last_budget` hint: the map's last target search ended on the whole map."""
MAX_HINTS = 1 << 14
"""Maps whose last search's window is remembered (a few dozen bytes each; the oldest is forgotten first)."""


def last_budget(key: Key) -> int | None:
    """The budget (cells) of the window that decided the last target search on this map, ``WHOLE_MAP`` when
    that search ended on the whole map, None when there is no hint: where
    :func:`swarm.grid.nearest_reachable_unseen` starts the next one, since a robot's nearest unknown moves
    little between two of its searches. A hint only: every window gives the whole-map answer or none."""
    return _KEPT.budgets.get(key)


def note_budget(key: Key, budget: int) -> None:
    """Record for :func:`last_budget` which window (or ``WHOLE_MAP``) decided the search on this map."""
    budgets = _KEPT.budgets
    budgets[key] = budget
    budgets.move_to_end(key)
    while len(budgets) > MAX_HINTS:
        budgets.popitem(last=False)


def _new_inputs(h: int, w: int) -> KeptInputs:
    bits = ((h + 2) * (w + 2) + 7) // 8
    return KeptInputs(np.full(packed_size(h * w), _NEVER, np.uint8), np.zeros(bits, np.uint8),
                      np.zeros(bits, np.uint8), np.zeros(h, np.int64), np.zeros(1, np.int64))


def unpack_buffer(n: int) -> np.ndarray:
    """This thread's padded byte grid of ``n`` cells that a kept space is unpacked into for one search
    (its border stays 0). The search's distance array and touched list are
    :func:`swarm.grid.search`'s all-inf workspace, shared with :func:`swarm.grid.field_at`."""
    k = _KEPT
    if k.pad.shape[0] != n:
        k.pad = np.zeros(n, dtype=np.uint8)
    return k.pad


def forget_all() -> None:
    """Drop every kept entry of this thread, and the hints about them."""
    _KEPT.entries.clear()
    _KEPT.budgets.clear()
    _KEPT.shape = None


@njit(cache=True)
def refresh(known, copy, space, targets, row_targets, version, unseen_ok, row_offsets, half_widths,
            reach, margin):  # pragma: no cover - compiled
    """Bring the arrays of :class:`KeptInputs` up to date with ``known`` (a checked, C-contiguous map:
    values 0..2; ``version`` counts up when anything changed); ``margin`` >= the erosion depth and >=
    ``reach + 1``. Returns the number of targets."""
    h, w = known.shape
    cur = known.reshape(-1)
    words = cur.shape[0] // 8
    cur64, prev16 = cur[:8 * words].view(np.uint64), copy[:2 * words].view(np.uint16)
    dirty = np.zeros(h, np.bool_)
    cells = np.empty(8 * CHUNK_WORDS, np.int64)
    for k0 in range(0, words, CHUNK_WORDS):  # a map differs from its last search's in a few words
        k1 = min(k0 + CHUNK_WORDS, words)
        if differing_words(cur64, prev16, k0, k1):
            for j in range(sync_chunk(cur, copy, cur64, prev16, k0, k1, cells, 0)):
                dirty[cells[j] // w] = True
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
    wp = w + 2
    first = (a + 1) * wp  # the padded rows a + 1 .. b, borders included: bits first .. first + n - 1
    n = (b - a) * wp
    off = first & 7       # bytes laid out from bit 8 (first // 8), so eight of them make one byte of bits
    space_bytes = np.zeros(8 * ((off + n + 7) // 8), np.uint8)
    target_bytes = np.zeros(space_bytes.shape[0], np.uint8)
    for r in range(a, b):
        sp = part_space[r - lo]
        vw = seen[r - lo]
        q = off + (r - a) * wp + 1
        srow = space_bytes[q:q + w]  # row slices: indices the compiler knows are not negative (3x faster)
        trow = target_bytes[q:q + w]
        count = 0
        for c in range(w):
            s = sp[c] != 0
            t = vw[c] & s
            srow[c] = s
            trow[c] = t
            count += t
        row_targets[r] = count
    _write_bits(space, first, n, space_bytes)
    _write_bits(targets, first, n, target_bytes)


_GATHER_BITS = np.uint64(0x0102040810204080)
"""Times eight bytes of 0 or 1 (a little-endian uint64), the top byte holds them as bits, byte j in bit j."""


@njit(cache=True, inline="always")
def _write_bits(bits, first, n, values):  # pragma: no cover - compiled
    """Bits ``first .. first + n - 1`` of ``bits`` (little bit order) = ``values[first % 8 ..]`` (uint8 0/1,
    zero outside those places, a whole number of 8-byte words laid out from bit ``8 (first // 8)``); the
    bits around them are kept. A multiply gathers eight values into a byte: 4x faster than a bit at a time."""
    off = first & 7
    end = (first + n) & 7
    j0 = first >> 3
    words = values.view(np.uint64)
    m = words.shape[0]
    for j in range(m):
        v = (words[j] * _GATHER_BITS) >> np.uint64(56)
        keep = 0
        if j == 0 and off:
            keep |= (1 << off) - 1
        if j == m - 1 and end:
            keep |= 0xFF & ~((1 << end) - 1)
        bits[j0 + j] = (np.int64(bits[j0 + j]) & keep) | np.int64(v)


@njit(cache=True)
def map_target(known, exclude, reach, unseen_ok, row_offsets, half_widths, sr, sc, snap, dist, ring, touched,
               pad, copy, space, targets, row_targets, version, margin):  # pragma: no cover - compiled
    """The whole-map stage of :func:`swarm.grid.nearest_reachable_unseen` in one call: :func:`refresh` the
    kept inputs (``copy`` .. ``version``, see :class:`KeptInputs`), unpack the space into ``pad`` (the
    thread's padded grid of :func:`unpack_buffer`), then snap and search
    (:func:`swarm.grid.local.search_targets`, on the thread's all-inf ``dist`` and ``touched`` list of
    ``swarm.grid.search``, which it leaves all inf). With an exclusion mask (``exclude`` bool[H, W], or empty
    for none) the targets are computed afresh from the kept space. Returns what
    ``search_targets`` returns, with the path to the target (for :mod:`swarm.grid.memo`)."""
    h, w = known.shape
    total = refresh(known, copy, space, targets, row_targets, version, unseen_ok, row_offsets,
                    half_widths, reach, margin)
    if total == 0 and exclude.shape[0] != h:
        return NO_TARGET, -1, -1, np.inf, -1, -1, np.empty((0, 2), np.int64)
    unpack_bits(space, pad)
    grid = pad.reshape(h + 2, w + 2)
    marks = targets
    if exclude.shape[0] == h:
        seen = np.zeros((h, w), np.bool_)
        marks = np.zeros((h + 2) * (w + 2), np.uint8)  # a byte per cell, computed for this search only
        total = 0
        if grid_view_cells(known, exclude, reach, seen) > 0:
            total = mark_targets(seen, grid, exclude, marks.reshape(h + 2, w + 2))
    if total == 0:
        return NO_TARGET, -1, -1, np.inf, -1, -1, np.empty((0, 2), np.int64)
    return search_targets(grid[1:-1, 1:-1], grid, marks, sr, sc, snap, True, dist, ring, touched)


_BYTES_OF_BITS = np.array([sum(((x >> b) & 1) << (8 * b) for b in range(8)) for x in range(256)], dtype=np.uint64)
"""Eight bits of a byte spread to eight bytes of 0 or 1 (little-endian bit and byte order)."""


@njit(cache=True)
def unpack_bits(bits, out):  # pragma: no cover - compiled
    """``out`` (uint8[n]) = the first n bits of ``bits`` (np.packbits's little bit order), a byte each."""
    n = out.shape[0]
    whole = n // 8
    out64 = out[:8 * whole].view(np.uint64)
    for j in range(whole):
        out64[j] = _BYTES_OF_BITS[bits[j]]
    for i in range(8 * whole, n):
        out[i] = (bits[i >> 3] >> (i & 7)) & 1
