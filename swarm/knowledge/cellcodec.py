"""Compiled byte layouts of map-update payloads (before zlib), see :class:`swarm.comm.messages.MapUpdate`.

* full map: every cell as 2 bits, four cells per byte, first cell in the low bits;
* delta: ``n`` little-endian uint32 gaps between ascending flat indices (the first from 0), then the
  ``n`` cell values packed as above.

Map sharing encodes and decodes updates every tick of a many-robot run; done with numpy these are ten
array passes and temporaries each, here one pass (figures: docs/performance-history.md).
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, inline="always")
def put_u32(buf: np.ndarray, at: int, v: int) -> None:  # pragma: no cover - compiled
    """Write ``v`` (0 <= v < 2**32) as a little-endian uint32 at ``buf[at:at + 4]``: the byte order of every
    gap in the map-update and obs-packet layouts."""
    buf[at] = v & 0xFF
    buf[at + 1] = (v >> 8) & 0xFF
    buf[at + 2] = (v >> 16) & 0xFF
    buf[at + 3] = (v >> 24) & 0xFF


@njit(cache=True, inline="always")
def put_raw_cells(buf: np.ndarray, p: int, cells: np.ndarray, first: int, last: int,
                  row: np.ndarray) -> int:  # pragma: no cover - compiled
    """Write the changed cells ``cells[first:last]`` (ascending flat indices) of the map ``row`` (flat) as an
    obs packet carries them: their uint32 gaps (the first from 0), then one raw byte per cell. Returns the
    position after them; ``buf`` needs ``5 * (last - first)`` bytes from ``p``."""
    prev = 0
    for k in range(first, last):
        put_u32(buf, p, cells[k] - prev)
        prev = cells[k]
        p += 4
    for k in range(first, last):
        buf[p] = row[cells[k]]
        p += 1
    return p


@njit(cache=True, inline="always")
def get_u32(raw: np.ndarray, at: int) -> np.int64:  # pragma: no cover - compiled
    """The little-endian uint32 at ``raw[at:at + 4]`` as an int64."""
    return (np.int64(raw[at]) | (np.int64(raw[at + 1]) << 8) | (np.int64(raw[at + 2]) << 16)
            | (np.int64(raw[at + 3]) << 24))


@njit(cache=True)
def pack2(values: np.ndarray) -> np.ndarray:  # pragma: no cover - compiled
    """``values`` (uint8, each 0..3) packed four to a byte. Each byte is written once from its four cells: a
    read-modify-write per cell was 5x slower (34 against 6.6 us for a 300 x 300 map)."""
    n = values.shape[0]
    out = np.empty((n + 3) // 4, dtype=np.uint8)
    whole = n // 4
    for j in range(whole):
        i = 4 * j
        out[j] = np.uint8((values[i] & 3) | ((values[i + 1] & 3) << 2) | ((values[i + 2] & 3) << 4)
                          | ((values[i + 3] & 3) << 6))
    if n > 4 * whole:
        last = 0
        for i in range(4 * whole, n):
            last |= (values[i] & 3) << (2 * (i & 3))
        out[whole] = np.uint8(last)
    return out


@njit(cache=True)
def fingerprint(data: np.ndarray) -> tuple[np.uint64, np.uint64]:  # pragma: no cover - compiled
    """Two 64-bit hashes of ``data`` (uint8, any length; multiply-rotate lanes of 8-byte words, the tail
    bytewise): a cheap key under which equal byte strings meet (a few tens of microseconds for a 360 KB
    packed map, against ~0.4 ms for blake2b). Not collision-proof: callers compare the bytes on a match."""
    n = data.shape[0]
    words = n // 8
    w = data[: 8 * words].view(np.uint64)
    h1 = np.uint64(0x9E3779B97F4A7C15) ^ np.uint64(n)
    h2 = np.uint64(0xC2B2AE3D27D4EB4F)
    p1, p2 = np.uint64(0x87C37B91114253D5), np.uint64(0x4CF5AD432745937F)
    for i in range(words):
        v = w[i]
        h1 = (h1 ^ (v * p1)) * p2
        h1 = (h1 << np.uint64(31)) | (h1 >> np.uint64(33))
        h2 = (h2 + v) * p1
        h2 = (h2 << np.uint64(27)) | (h2 >> np.uint64(37))
    for i in range(8 * words, n):
        h1 = (h1 ^ np.uint64(data[i])) * p2
        h2 = (h2 + np.uint64(data[i])) * p1
    return h1, h2


@njit(cache=True)
def pack_delta(idx: np.ndarray, values: np.ndarray) -> np.ndarray:  # pragma: no cover - compiled
    """The delta layout of the cells ``idx`` (ascending flat indices) whose values are ``values`` (``values[i]``
    for ``idx[i]``: a map's values gathered by the caller, whatever order the map is stored in)."""
    n = idx.shape[0]
    out = np.zeros(4 * n + (n + 3) // 4, dtype=np.uint8)
    prev = 0
    for i in range(n):
        put_u32(out, 4 * i, idx[i] - prev)
        prev = idx[i]
        out[4 * n + (i >> 2)] |= np.uint8((values[i] & 3) << (2 * (i & 3)))
    return out


@njit(cache=True)
def unpack2(packed: np.ndarray, n: int, out: np.ndarray) -> int:  # pragma: no cover - compiled
    """Unpack ``n`` 2-bit values of ``packed`` into ``out``; returns the largest value (3 is invalid). Whole
    bytes are split at once and the largest value read off or-ed bit masks, not compared per cell: 4x
    faster (32 against 8 us for a 300 x 300 map, every full MapUpdate received)."""
    whole = n // 4
    low = high = three = 0  # or of every value's bit 0, of its bit 1, of both together (fields aligned)
    for j in range(whole):
        b = np.int64(packed[j])
        out[4 * j] = b & 3
        out[4 * j + 1] = (b >> 2) & 3
        out[4 * j + 2] = (b >> 4) & 3
        out[4 * j + 3] = b >> 6
        low |= b
        high |= b >> 1
        three |= b & (b >> 1)
    for i in range(4 * whole, n):
        v = (np.int64(packed[i >> 2]) >> (2 * (i & 3))) & 3
        out[i] = v
        low |= v
        high |= v >> 1
        three |= v & (v >> 1)
    if three & 0x55:
        return 3
    if high & 0x55:
        return 2
    return 1 if low & 0x55 else 0


@njit(cache=True)
def values_at2(packed: np.ndarray, idx: np.ndarray) -> np.ndarray:  # pragma: no cover - compiled
    """The 2-bit values of ``packed`` (:func:`pack2`'s layout) at the flat indices ``idx`` (each below the
    packed cell count), as uint8: a few cells of a full map without unpacking all of it."""
    out = np.empty(idx.shape[0], dtype=np.uint8)
    for k in range(idx.shape[0]):
        i = idx[k]
        out[k] = (packed[i >> 2] >> (2 * (i & 3))) & 3
    return out


DELTA_OK, DELTA_REPEATED, DELTA_OUTSIDE = 0, 1, 2


@njit(cache=True)
def unpack_delta(raw: np.ndarray, n: int, size: int, idx: np.ndarray, values: np.ndarray) -> int:  # pragma: no cover
    """Decode the delta layout (``raw`` has exactly ``4 n + ceil(n / 4)`` bytes) into ``idx`` (int64)
    and ``values`` (uint8). Returns DELTA_OK, DELTA_REPEATED (a zero gap after the first: the same cell
    twice) or DELTA_OUTSIDE (an index >= ``size`` or a value above 2)."""
    at = 0
    for i in range(n):
        gap = get_u32(raw, 4 * i)
        if i > 0 and gap == 0:
            return DELTA_REPEATED
        at += gap
        idx[i] = at
    if n and at >= size:
        return DELTA_OUTSIDE
    if unpack2(raw[4 * n:], n, values) > 2:
        return DELTA_OUTSIDE
    return DELTA_OK


@njit(cache=True)
def known2(packed: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray, int]:  # pragma: no cover - compiled
    """The cells of a 2-bit packed map (``n`` cells) that are not 0: (ascending flat indices, values, the
    largest value; 3 is invalid). A byte of four unseen cells is skipped at once: a full map of a swarm's
    early run is mostly unseen, and its known cells are all a merge needs."""
    count = 0
    for j in range(packed.shape[0]):
        b = packed[j]
        if b:
            count += (b & 3 != 0) + ((b >> 2) & 3 != 0) + ((b >> 4) & 3 != 0) + ((b >> 6) & 3 != 0)
    idx = np.empty(count, np.int64)
    values = np.empty(count, np.uint8)
    top = 0
    m = 0
    for j in range(packed.shape[0]):
        b = np.int64(packed[j])
        if b == 0:
            continue
        for s in range(4):
            v = (b >> (2 * s)) & 3
            i = 4 * j + s
            if v and i < n:
                idx[m] = i
                values[m] = v
                m += 1
                top = max(top, v)
    return idx[:m], values[:m], top
