"""2-bit copies of knowledge maps, and the cells a map changed since its copy was taken.

The map-sharing service keeps, per robot, the map as of its last update and builds each delta from the
cells that differ (:class:`swarm.comm.sharing.MapSharing`). A knowledge map holds three values (UNSEEN = 0,
FREE = 1, SOLID = 2), so that copy needs 2 bits a cell, not a byte: 90 KB instead of 360 KB per robot on
a 300-tile map, 17 MB less for 64 robots (docs/performance-history.md). The layout is the wire's
(:func:`swarm.knowledge.cellcodec.pack2`): flat cell ``i`` in bits ``2 (i mod 4)`` of byte ``i // 4``.

:func:`sync_box_packed` and :func:`sync_changes_packed` are :func:`swarm.knowledge.maps.sync_box` and
:func:`swarm.knowledge.maps.sync_changes` against such a copy: the same cells in the same order, bit for bit
(tests/swarm/knowledge/test_packed.py compares them on random maps). Like those, they skip 8 cells at a time
where nothing changed: 8 map bytes packed into 16 bits with three shifts and masks, compared with two bytes
of the copy.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .cellcodec import pack2

__all__ = ["CHUNK_WORDS", "copy_cell_if_changed", "differing_words", "pack8", "packed_copy", "packed_size",
           "same_as_packed", "sync_box_packed", "sync_box_tiles_packed", "sync_changes_packed", "sync_chunk", "unpacked"]

_M1 = np.uint64(0x000F000F000F000F)
_M2 = np.uint64(0x000000FF000000FF)
_M3 = np.uint64(0xFFFF)


def packed_size(cells: int) -> int:
    """Bytes of the 2-bit copy of a map of ``cells`` cells."""
    return (cells + 3) // 4


def packed_copy(known: np.ndarray) -> np.ndarray:
    """The 2-bit copy of ``known`` (uint8, values 0..2): uint8[packed_size(known.size)]."""
    return pack2(np.ascontiguousarray(known).reshape(-1))


def unpacked(packed: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """The map a 2-bit copy holds, uint8[shape] (for tests and inspection)."""
    n = shape[0] * shape[1]
    bits = np.unpackbits(packed, bitorder="little")[: 2 * n].reshape(n, 2)
    return (bits[:, 0] | (bits[:, 1] << 1)).astype(np.uint8).reshape(shape)


@njit(cache=True, inline="always")
def pack8(x: np.uint64) -> np.uint64:  # pragma: no cover - compiled
    """Eight cells (one little-endian byte each, 0..3) packed into the low 16 bits, cell j in bits 2j."""
    x = (x | (x >> np.uint64(6))) & _M1
    x = (x | (x >> np.uint64(12))) & _M2
    return (x | (x >> np.uint64(24))) & _M3


CHUNK_WORDS = 64
"""Words (8 cells each) a whole-map comparison checks at once, branch-free (:func:`differing_words`),
before it looks at the words of a chunk one by one."""


@njit(cache=True, inline="always")
def differing_words(cur64: np.ndarray, prev16: np.ndarray, k0: int, k1: int) -> int:  # pragma: no cover
    """How many of the 8-cell words ``k0..k1-1`` differ between a map (``cur64``) and its copy (``prev16``).
    A count without stores and with unsigned indices, so the compiler vectorises it: 9 us for a 600 x 600
    map, against 39 us for a word-by-word loop that writes where it finds a difference."""
    n = 0
    for k in range(k0, k1):
        ku = np.uint64(k)
        n += pack8(cur64[ku]) != np.uint64(prev16[ku])
    return n


@njit(cache=True, inline="always")
def sync_chunk(cur: np.ndarray, prev: np.ndarray, cur64: np.ndarray, prev16: np.ndarray, k0: int, k1: int,
               out: np.ndarray, m: int) -> int:  # pragma: no cover - compiled
    """Write into the 2-bit copy ``prev`` the cells of words ``k0..k1-1`` of the map ``cur`` that differ,
    listing them in ``out`` from ``m`` (ascending); returns the new end. The whole-map comparisons'
    body (:func:`sync_changes_packed`, :func:`swarm.grid.kept.refresh`), for chunks of :data:`CHUNK_WORDS`
    where :func:`differing_words` found a difference (the callers ask it first: asked in here, the
    count loop is no longer vectorised, 3x slower)."""
    for k in range(k0, k1):
        if pack8(cur64[k]) != np.uint64(prev16[k]):
            for i in range(8 * k, 8 * k + 8):
                if copy_cell_if_changed(cur, prev, i):
                    out[m] = i
                    m += 1
    return m


@njit(cache=True, inline="always")
def copy_cell_if_changed(cur: np.ndarray, prev: np.ndarray, i: int) -> bool:  # pragma: no cover - compiled
    """Write flat cell ``i`` of ``cur`` into the 2-bit copy ``prev`` if it differs there; True if it did."""
    j = i >> 2
    s = (i & 3) << 1
    old = np.int64(prev[j])
    v = np.int64(cur[i])
    if (old >> s) & 3 != v:
        prev[j] = np.uint8((old & ~(3 << s)) | (v << s))
        return True
    return False


@njit(cache=True, inline="always")
def _same_words2(cur64: np.ndarray, prev16: np.ndarray, a: int, b: int) -> bool:  # pragma: no cover - compiled
    """True if the 8-cell words covering cells ``a..b-1`` hold the same values in the map and the copy;
    False if one differs or the span reaches past the last whole word."""
    last = (b - 1) >> 3
    if last >= cur64.shape[0]:
        return False
    for w in range(a >> 3, last + 1):
        if pack8(cur64[w]) != np.uint64(prev16[w]):
            return False
    return True


@njit(cache=True)
def _sync_box_packed_kernel(current: np.ndarray, prev: np.ndarray, box: np.ndarray,
                            extra: np.ndarray) -> np.ndarray:  # pragma: no cover - compiled
    h, w = current.shape
    cur = current.reshape(-1)
    words = cur.shape[0] // 8
    cur64, prev16 = cur[:8 * words].view(np.uint64), prev[:2 * words].view(np.uint16)
    r0, r1, c0, c1 = max(box[0], 0), min(box[1], h), max(box[2], 0), min(box[3], w)
    out = np.empty(max(r1 - r0, 0) * max(c1 - c0, 0) + extra.shape[0], dtype=np.int64)
    m = 0
    if c1 > c0:
        for r in range(r0, r1):
            a, b = r * w + c0, r * w + c1
            if _same_words2(cur64, prev16, a, b):
                continue
            for i in range(a, b):
                if copy_cell_if_changed(cur, prev, i):
                    out[m] = i
                    m += 1
    for j in range(extra.shape[0]):
        if copy_cell_if_changed(cur, prev, extra[j]):
            out[m] = extra[j]
            m += 1
    if extra.shape[0]:
        out[:m].sort()
    return out[:m].copy()


@njit(cache=True)
def _sync_changes_packed_kernel(cur: np.ndarray, prev: np.ndarray) -> np.ndarray:  # pragma: no cover - compiled
    words = cur.shape[0] // 8
    cur64, prev16 = cur[:8 * words].view(np.uint64), prev[:2 * words].view(np.uint16)
    out = np.empty(cur.shape[0], dtype=np.int64)
    m = 0
    for k0 in range(0, words, CHUNK_WORDS):
        k1 = min(k0 + CHUNK_WORDS, words)
        if differing_words(cur64, prev16, k0, k1):
            m = sync_chunk(cur, prev, cur64, prev16, k0, k1, out, m)
    for i in range(8 * words, cur.shape[0]):
        if copy_cell_if_changed(cur, prev, i):
            out[m] = i
            m += 1
    return out[:m].copy()


def sync_box_packed(current: np.ndarray, prev: np.ndarray, box: np.ndarray, extra: np.ndarray) -> np.ndarray:
    """:func:`swarm.knowledge.maps.sync_box_unchecked` against the 2-bit copy ``prev`` of ``current`` (a
    C-contiguous uint8 map, values 0..2; ``box`` int64 (r0, r1, c0, c1), clipped here; ``extra`` int64 flat
    cells in range): the changed cells in the box and among ``extra``, ascending, written into ``prev``."""
    return _sync_box_packed_kernel(current, prev, box, extra)


def sync_changes_packed(current: np.ndarray, prev: np.ndarray) -> np.ndarray:
    """:func:`swarm.knowledge.maps.sync_changes` against the 2-bit copy ``prev``: every cell of ``current`` that
    differs, ascending, written into ``prev`` (after the call ``prev`` is ``current``'s copy)."""
    return _sync_changes_packed_kernel(np.ascontiguousarray(current).reshape(-1), prev)


@njit(cache=True)
def _same_kernel(cur: np.ndarray, prev: np.ndarray) -> bool:  # pragma: no cover - compiled
    words = cur.shape[0] // 8
    cur64, prev16 = cur[:8 * words].view(np.uint64), prev[:2 * words].view(np.uint16)
    if differing_words(cur64, prev16, 0, words):
        return False
    for i in range(8 * words, cur.shape[0]):
        if (np.int64(prev[i >> 2]) >> ((i & 3) << 1)) & 3 != cur[i]:
            return False
    return True


def same_as_packed(current: np.ndarray, prev: np.ndarray) -> bool:
    """Whether ``current`` (uint8, values 0..3) holds exactly what its 2-bit copy ``prev`` holds (a copy of
    another size never does)."""
    if prev.shape[0] != packed_size(current.size):
        return False
    return bool(_same_kernel(np.ascontiguousarray(current).reshape(-1), prev))


def sync_box_tiles_packed(current: np.ndarray, prev: np.ndarray, box: np.ndarray, dirty: np.ndarray,
                          tile: int) -> np.ndarray:
    """:func:`sync_box_packed` over the cells of ``box`` and of the tiles marked in ``dirty``
    (uint8[ceil(H / tile), ceil(W / tile)], ``tile`` x ``tile`` cells each): the changed cells there,
    ascending, written into ``prev``. The cost follows the box and the marked tiles, not the map."""
    return _sync_box_tiles_kernel(current, prev, box, dirty, tile)


@njit(cache=True)
def _sync_box_tiles_kernel(current: np.ndarray, prev: np.ndarray, box: np.ndarray, dirty: np.ndarray,
                           tile: int) -> np.ndarray:  # pragma: no cover - compiled
    h, w = current.shape
    cur = current.reshape(-1)
    words = cur.shape[0] // 8
    cur64, prev16 = cur[:8 * words].view(np.uint64), prev[:2 * words].view(np.uint16)
    r0, r1, c0, c1 = max(box[0], 0), min(box[1], h), max(box[2], 0), min(box[3], w)
    has_box = r1 > r0 and c1 > c0
    tr_n, tc_n = dirty.shape
    marked = 0
    for tr in range(tr_n):
        for tc in range(tc_n):
            marked += dirty[tr, tc] != 0
    cap = marked * tile * tile + (max(r1 - r0, 0) * max(c1 - c0, 0) if has_box else 0)
    out = np.empty(cap, dtype=np.int64)
    m = 0
    plain_a = np.empty(tc_n + 1, np.int64)  # a tile row's column intervals, without and with the box's
    plain_b = np.empty(tc_n + 1, np.int64)
    boxed_a = np.empty(tc_n + 2, np.int64)
    boxed_b = np.empty(tc_n + 2, np.int64)
    work_a = np.empty(tc_n + 2, np.int64)
    work_b = np.empty(tc_n + 2, np.int64)
    for tr in range(tr_n):
        ra, rb = tr * tile, min((tr + 1) * tile, h)
        n_plain = 0
        tc = 0
        while tc < tc_n:
            if dirty[tr, tc]:
                a = tc
                while tc < tc_n and dirty[tr, tc]:
                    tc += 1
                plain_a[n_plain] = a * tile
                plain_b[n_plain] = min(tc * tile, w)
                n_plain += 1
            else:
                tc += 1
        in_box = has_box and ra < r1 and r0 < rb
        if n_plain == 0 and not in_box:
            continue
        n_boxed = 0
        if in_box:  # the box's columns put in order among the sorted, disjoint tile intervals, then merged
            n = 0
            inserted = False
            for j in range(n_plain):
                if not inserted and c0 < plain_a[j]:
                    work_a[n], work_b[n] = c0, c1
                    n += 1
                    inserted = True
                work_a[n], work_b[n] = plain_a[j], plain_b[j]
                n += 1
            if not inserted:
                work_a[n], work_b[n] = c0, c1
                n += 1
            for j in range(n):
                a, b = work_a[j], work_b[j]
                if n_boxed and a <= boxed_b[n_boxed - 1]:
                    boxed_b[n_boxed - 1] = max(boxed_b[n_boxed - 1], b)
                else:
                    boxed_a[n_boxed], boxed_b[n_boxed] = a, b
                    n_boxed += 1
        for r in range(ra, rb):
            boxed = in_box and r0 <= r < r1
            n_iv = n_boxed if boxed else n_plain
            for j in range(n_iv):
                a = (boxed_a[j] if boxed else plain_a[j]) + r * w
                b = (boxed_b[j] if boxed else plain_b[j]) + r * w
                if _same_words2(cur64, prev16, a, b):
                    continue
                for i in range(a, b):
                    if copy_cell_if_changed(cur, prev, i):
                        out[m] = i
                        m += 1
    return out[:m].copy()


@njit(cache=True)
def rising_cells(theirs: np.ndarray, mine: np.ndarray, cells: np.ndarray,
                 values: np.ndarray) -> int:  # pragma: no cover - compiled
    """The cells where 2-bit copy ``theirs`` holds more than 2-bit copy ``mine`` (both :func:`packed_copy`'s
    layout, the same length), ascending into ``cells`` with ``theirs``'s values into ``values``; returns how
    many. Merging a map into one that holds at least ``mine`` can raise only these cells, so a merge of a full
    map into a robot that never heard its sender reads two bytes per four cells instead of every known cell
    (equal bytes, most of a converged swarm's map, are skipped at once, and empty or equal runs of 32 cells
    as one word). ``cells`` must have room for every cell ``theirs`` knows."""
    words = theirs.shape[0] // 8
    t64 = theirs[:8 * words].view(np.uint64)
    m64 = mine[:8 * words].view(np.uint64)
    n = 0
    for i in range(words):
        if t64[i] != 0 and t64[i] != m64[i]:
            n = _rising_bytes(theirs, mine, 8 * i, 8 * i + 8, cells, values, n)
    return _rising_bytes(theirs, mine, 8 * words, theirs.shape[0], cells, values, n)


@njit(cache=True, inline="always")
def _rising_bytes(theirs: np.ndarray, mine: np.ndarray, first: int, end: int, cells: np.ndarray, values: np.ndarray,
                  n: int) -> int:  # pragma: no cover - compiled
    """:func:`rising_cells` over bytes ``first:end``, appending after the ``n`` cells found so far."""
    for b in range(first, end):
        t = theirs[b]
        m = mine[b]
        if t == m or t == 0:
            continue
        for k in range(4):
            tv = (t >> (2 * k)) & 3
            if tv > ((m >> (2 * k)) & 3):
                cells[n] = 4 * b + k
                values[n] = tv
                n += 1
    return n
