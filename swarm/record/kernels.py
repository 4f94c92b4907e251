"""numba kernels for the recorder's per-tick diffs.

The recorder runs every tick on small arrays (an R x R link matrix) and one big one (the R x H x W
knowledge maps). With numpy, per-call overhead dominated: ~40 calls of a few microseconds each cost more
than the arithmetic (figures: docs/performance-history.md). One pass per stream in numba
does the compare, the mirror update and the output in a single loop.
"""

from __future__ import annotations

import numpy as np
from numba import njit

RSSI_NAN, RSSI_NEG_INF, RSSI_POS_INF = -32768, -32767, 32767
"""int16 codes for RSSI values that are not finite (the diagonal is NaN; ``los`` gives -inf)."""


@njit(cache=True)
def _record_quantise(value: float, quantum: float) -> int:
    """One RSSI value in units of ``quantum`` (round half to even), or its code when not finite."""
    if np.isnan(value):
        return RSSI_NAN
    if value == np.inf:
        return RSSI_POS_INF
    if value == -np.inf:
        return RSSI_NEG_INF
    q = np.rint(value / quantum)
    if q > RSSI_POS_INF - 1:
        return RSSI_POS_INF - 1
    if q < RSSI_NEG_INF + 1:
        return RSSI_NEG_INF + 1
    return int(q)


@njit(cache=True)
def _record_quantise_array(values: np.ndarray, quantum: float, out: np.ndarray) -> None:
    for k in range(values.size):
        out[k] = _record_quantise(values[k], quantum)


@njit(cache=True)
def _record_diff(current: np.ndarray, mirror: np.ndarray, words: np.ndarray) -> np.ndarray:
    """Sorted indices where the 1-D uint8 arrays differ; the mirror takes the new values. Compares 8
    cells per uint64 word first (``words``: int64 scratch, at least ``size // 8`` long)."""
    n = current.size
    n8 = n - n % 8
    a64 = current[:n8].view(np.uint64)
    b64 = mirror[:n8].view(np.uint64)
    m = 0
    for w in range(a64.size):
        if a64[w] != b64[w]:
            words[m] = w
            m += 1
    out = np.empty(8 * m + (n - n8), dtype=np.int64)
    k = 0
    for j in range(m):
        base = words[j] * 8
        for i in range(base, base + 8):
            if current[i] != mirror[i]:
                out[k] = i
                k += 1
                mirror[i] = current[i]
    for i in range(n8, n):
        if current[i] != mirror[i]:
            out[k] = i
            k += 1
            mirror[i] = current[i]
    return out[:k]


@njit(cache=True)
def _record_links(link: np.ndarray, rssi: np.ndarray, link_mirror: np.ndarray, rssi_mirror: np.ndarray,
                  quantum: float, units: int, toggled: np.ndarray, idx: np.ndarray, vals: np.ndarray) -> tuple:
    """One tick of the link streams (flat R*R arrays): indices whose link toggled, and RSSI entries to
    rewrite (drifted more than ``units`` quanta, became or stopped being non-finite, or their link
    toggled). Mirrors are updated. Returns (toggled count, rewritten count)."""
    nt = 0
    nr = 0
    for k in range(link.size):
        flip = link[k] != link_mirror[k]
        if flip:
            link_mirror[k] = link[k]
            toggled[nt] = k
            nt += 1
        q = _record_quantise(rssi[k], quantum)
        s = rssi_mirror[k]
        if q != s:
            special = q <= RSSI_NEG_INF or q >= RSSI_POS_INF or s <= RSSI_NEG_INF or s >= RSSI_POS_INF
            if flip or special or abs(q - s) > units:
                rssi_mirror[k] = q
                idx[nr] = k
                vals[nr] = q
                nr += 1
    return nt, nr


@njit(cache=True)
def _record_changes(current: np.ndarray, mirror: np.ndarray, idx: np.ndarray, vals: np.ndarray) -> int:
    """Flat int64 arrays: the indices where ``current`` differs from ``mirror`` and the new values into
    ``idx`` and ``vals``, the mirror updated; returns how many (the age-of-information matrix each tick)."""
    m = 0
    for k in range(current.size):
        if current[k] != mirror[k]:
            mirror[k] = current[k]
            idx[m] = k
            vals[m] = current[k]
            m += 1
    return m


def changed_cells(current: np.ndarray, mirror: np.ndarray, words: np.ndarray | None = None) -> np.ndarray:
    """Sorted flat indices where ``current`` differs from ``mirror`` (same shape, C-contiguous, 1-byte
    cells, bool or uint8); copies the new values into ``mirror``."""
    a = np.ascontiguousarray(current).reshape(-1).view(np.uint8)
    b = mirror.reshape(-1).view(np.uint8)
    if words is None or words.size < a.size // 8:
        words = np.empty(a.size // 8 + 1, dtype=np.int64)
    return _record_diff(a, b, words)


def quantise_rssi(rssi: np.ndarray, quantum_db: float) -> np.ndarray:
    """int16 RSSI in units of ``quantum_db`` (same shape), with codes for NaN and +-inf."""
    values = np.ascontiguousarray(rssi, dtype=np.float64)
    out = np.empty(values.shape, dtype=np.int16)
    _record_quantise_array(values.reshape(-1), float(quantum_db), out.reshape(-1))
    return out
