"""Log-normal shadowing: a seeded, spatially correlated field over a map, read by every link.

Shadowing is the slow, place-dependent part of the received power that the path-loss and wall terms do
not model (furniture, people, the real structure of walls). It is log-normal, i.e. Gaussian in dB, and
here it belongs to places, not to ticks: a link's margin changes only as its robots move, so its fate
does not flicker from tick to tick (docs/radio.md, "Shadowing").

**The field.** ``F(x)`` is a zero-mean, unit-variance Gaussian random field over the map with
Gudmundson's exponential correlation ``corr(F(x), F(y)) = exp(-|x - y| / d_c)`` (M. Gudmundson,
"Correlation model for shadow fading in mobile radio systems", Electronics Letters 27(23), 1991), where
``d_c`` is ``RadioConfig.shadowing_corr_m`` (default 10 m: 3GPP TR 38.901 Table 7.5-6, indoor office,
line of sight). It is drawn once per map from a seed by circulant embedding (white noise on a periodic
grid of ``d_c / 16`` cells, filtered in Fourier space by the square root of the covariance's spectrum;
C. R. Dietrich and G. N. Newsam, SIAM J. Sci. Comput. 18(4), 1997), so grid nodes have exactly this
covariance. The grid extends ``4 d_c`` beyond the map, so its wrap-around correlates opposite edges by at
most ``exp(-4)``. A point is read by bilinear interpolation of its cell's four corners divided by the
interpolation's own standard deviation: continuous, unit variance everywhere, correlation within a few
hundredths of ``exp(-d / d_c)`` (tests/radio/test_shadowing.py measures it).

**A link.** Robots at ``p`` and ``q`` see the shadowing

    ``S(p, q) = sigma * (F(p) + F(q)) / sqrt(2 (1 + exp(-|p - q| / d_c)))``   dB

subtracted from the received power in both directions. It is symmetric by construction (the sum does
not care which end transmits), exactly ``N(0, sigma^2)`` for every pair (the denominator is the standard
deviation of ``F(p) + F(q)``), continuous as either robot moves (so correlated along their paths), and
independent for links whose ends are all far apart. Links sharing an end share half their variance:
a robot in a shadowed spot is badly heard by everyone, as a robot behind a cabinet is.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

SHADOWING_SPAWN_KEY = 0x5AD0
"""The field's generator is ``SeedSequence(seed, spawn_key=(SHADOWING_SPAWN_KEY,))``: independent of
every other stream drawn from the same seed (a map's seed also generates the map)."""
CELLS_PER_CORRELATION = 16
"""Grid cells per correlation distance: fine enough that reading between nodes changes the correlation little
(the normalised interpolation raises it by at most ~5 % of its value)."""
PAD_CORRELATIONS = 4.0
"""The periodic grid extends this many correlation distances beyond the map on each axis."""
MAX_GRID_CELLS = 2048
"""Cells per grid axis at most: a tiny correlation distance on a huge map coarsens the grid instead."""


class ShadowingField:
    """``F``: the unit-variance field of one map (see the module docstring); built once per run."""

    def __init__(self, width_m: float, height_m: float, corr_m: float, seed: int) -> None:
        self.corr_m = float(corr_m)
        cell = self.corr_m / CELLS_PER_CORRELATION
        pad = PAD_CORRELATIONS * self.corr_m
        cell = max(cell, (max(width_m, height_m) + pad) / (MAX_GRID_CELLS - 1))
        nx = int(math.ceil((width_m + pad) / cell)) + 1
        ny = int(math.ceil((height_m + pad) / cell)) + 1
        self.cell_m = cell
        rng = np.random.default_rng(np.random.SeedSequence(int(seed), spawn_key=(SHADOWING_SPAWN_KEY,)))
        white = rng.standard_normal((ny, nx))
        # Circulant embedding: the covariance exp(-lag / d_c) over the periodic grid's (shortest) lags; its
        # Fourier transform is its spectrum (non-negative up to rounding, clipped), so filtering white noise
        # by the spectrum's square root gives exactly this covariance between grid nodes.
        lag_x = np.minimum(np.arange(nx), nx - np.arange(nx)) * cell
        lag_y = np.minimum(np.arange(ny), ny - np.arange(ny)) * cell
        cov = np.exp(-np.hypot(lag_y[:, None], lag_x[None, :]) / self.corr_m)
        spectrum = np.maximum(np.fft.rfft2(cov).real, 0.0)
        self.grid = np.ascontiguousarray(np.fft.irfft2(np.fft.rfft2(white) * np.sqrt(spectrum), s=(ny, nx)))
        cov = np.fft.irfft2(spectrum, s=(ny, nx))  # the grid's covariance by lag (the clipping's effect included)
        # Covariance of a cell's corners at lags 0, x+1, y+1, (+1, +1) and (-1, +1).
        self._lags = np.array([cov[0, 0], cov[0, 1], cov[1, 0], cov[1, 1], cov[1, nx - 1]], dtype=np.float64)
        self._inv_cell = 1.0 / cell

    def at(self, xy: np.ndarray) -> np.ndarray:
        """``F`` at points ``xy`` (float64[N, 2], metres): float64[N]."""
        xy = np.ascontiguousarray(xy, dtype=np.float64).reshape(-1, 2)
        out = np.empty(xy.shape[0])
        _radio_field_at(self.grid, self._inv_cell, self._lags, xy, out)
        return out


@njit(cache=True)
def _radio_field_at(grid, inv_cell, lags, xy, out):  # pragma: no cover - compiled
    """Bilinear interpolation of ``grid`` at each point, divided by the interpolation's standard
    deviation under the grid's covariance (``lags``: the corners' variance and covariances along x, y, the
    diagonal and the anti-diagonal), so every point reads a unit-variance value. Indices wrap (the grid is
    periodic)."""
    ny, nx = grid.shape
    c0, cx, cy, cd, ca = lags[0], lags[1], lags[2], lags[3], lags[4]
    for k in range(xy.shape[0]):
        gx = xy[k, 0] * inv_cell
        gy = xy[k, 1] * inv_cell
        fx = math.floor(gx)
        fy = math.floor(gy)
        a = gx - fx
        b = gy - fy
        i0 = int(fx) % nx
        j0 = int(fy) % ny
        i1 = (i0 + 1) % nx
        j1 = (j0 + 1) % ny
        wa = (1.0 - a) * (1.0 - b)
        wb = a * (1.0 - b)
        wc = (1.0 - a) * b
        wd = a * b
        value = wa * grid[j0, i0] + wb * grid[j0, i1] + wc * grid[j1, i0] + wd * grid[j1, i1]
        var = (c0 * (wa * wa + wb * wb + wc * wc + wd * wd)
               + 2.0 * (cx * (wa * wb + wc * wd) + cy * (wa * wc + wb * wd) + cd * wa * wd + ca * wb * wc))
        out[k] = value / math.sqrt(var)


@njit(cache=True)
def _radio_shadow_links(values_rx, values_tx, tx_robot, distance, sigma, corr, sens, rssi, link,
                        shadow):  # pragma: no cover - compiled
    """Apply ``S`` to a link picture in place: for receiver ``i`` (row) and transmitter column ``k``,
    ``shadow[i, k] = S``, ``rssi[i, k] -= S`` and ``link[i, k] = rssi[i, k] >= sens[i]`` (eq. 2 judged again).
    ``values_rx`` / ``values_tx``: the field at the receivers and the transmitters; a pair where
    ``i == tx_robot[k]`` (a robot and itself) is left alone with ``shadow = 0``. One kernel for every path
    (all pairs, the senders' columns, one-to-many), so they agree bit for bit; the sum ``values_rx[i] +
    values_tx[k]`` is the same either way round, so ``S`` is symmetric bit for bit."""
    for i in range(rssi.shape[0]):
        for k in range(rssi.shape[1]):
            if i == tx_robot[k]:
                shadow[i, k] = 0.0
                continue
            s = sigma * (values_rx[i] + values_tx[k]) / math.sqrt(2.0 * (1.0 + math.exp(-distance[i, k] / corr)))
            shadow[i, k] = s
            r = rssi[i, k] - s
            rssi[i, k] = r
            link[i, k] = r >= sens[i]
