"""Log-distance path loss (Minotaur paper, section 4.1, eq. 1) and the link budget (eq. 2).

``L(d, f) = 10 * alpha * log10(d) + beta + 10 * gamma * log10(f)``, d in metres, f in GHz.

The defaults alpha = 1.73, beta = 32.4, gamma = 2.0 are the 3GPP TR 38.901 (v16, Table 7.4.1-1)
indoor-office line-of-sight model ``PL = 32.4 + 17.3 log10(d) + 20 log10(f)``. We use the line-of-sight
fit on purpose: walls are charged explicitly (eq. 2), so a non-line-of-sight fit would count them twice.
Distances below 1 m are clamped to 1 m, where the 3GPP fit starts (and so ``log10(0)`` never happens).

Link budget (eq. 2): a message from j reaches i iff ``Ptx_j - L(d_ij, f) - sum(A_wall) >= S_i``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

MIN_DISTANCE_M = 1.0
"""Distances are clamped to at least this before eq. 1 (the near-field start of the 3GPP fit)."""


def path_loss_db(distance_m: np.ndarray | float, frequency_ghz: float, alpha: float, beta: float,
                 gamma: float) -> np.ndarray:
    """Eq. 1 for one distance or an array of distances (metres), elementwise."""
    d = np.maximum(np.asarray(distance_m, dtype=np.float64), MIN_DISTANCE_M)
    return 10.0 * alpha * np.log10(d) + beta + 10.0 * gamma * np.log10(frequency_ghz)


MULTIWALL, MAES, LOS, GLOBAL = 0, 1, 2, 3
"""Model codes for :func:`_radio_link_budget`."""


@njit(cache=True)
def _radio_link_budget(code, distance, walls, wall_db, tx, sens, alpha, beta, freq_term, max_range, symmetric,
                       path_loss, charged, rssi, link):  # pragma: no cover
    """Eqs. 1-2 for every (receiver i, transmitter j): fills ``path_loss``, ``charged``, ``rssi``, ``link``.

    ``distance`` etc. are [Ri, Rj]; ``tx`` is per transmitter (column), ``sens`` per receiver (row);
    ``freq_term`` is ``10 * gamma * log10(f)``; ``symmetric``: the distances are a symmetric all-pairs
    matrix, so eq. 1 is evaluated once per pair. One kernel serves every model (``code``) and both the
    all-pairs matrices and one-transmitter fields, so the numbers cannot drift apart.
    """
    n_rx, n_tx = distance.shape
    for i in range(n_rx):
        for j in range(n_tx):
            d = distance[i, j]
            pl = 0.0
            w = 0.0
            if code == MULTIWALL:
                if symmetric and j < i:
                    pl = path_loss[j, i]
                else:
                    pl = 10.0 * alpha * math.log10(max(d, MIN_DISTANCE_M)) + beta + freq_term
                w = wall_db[i, j]
                r = tx[j] - pl - w
                ok = r >= sens[i]
            elif code == MAES:
                w = wall_db[i, j]
                r = tx[j] - w
                ok = r >= sens[i]
            elif code == LOS:
                ok = walls[i, j] == 0 and d <= max_range
                r = tx[j] if ok else -np.inf
            else:
                ok = True
                r = tx[j]
            path_loss[i, j] = pl
            charged[i, j] = w
            rssi[i, j] = r
            link[i, j] = ok
