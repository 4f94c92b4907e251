"""Eq. 1 path loss with the 3GPP TR 38.901 indoor-office LOS defaults."""

from __future__ import annotations

import numpy as np
import pytest

from radio.pathloss import path_loss_db

ALPHA, BETA, GAMMA = 1.73, 32.4, 2.0


@pytest.mark.parametrize("d, expected", [
    (1.0, 40.004225),    # 17.3 * 0 + 32.4 + 20 * log10(2.4) (= 7.604225)
    (10.0, 57.304225),   # + 17.3 * 1
    (100.0, 74.604225),  # + 17.3 * 2
    (50.0, 69.396406),   # 17.3 * log10(50) = 29.392181; + 40.004225
    (0.3, 40.004225),    # clamped to 1 m
    (0.0, 40.004225),    # clamped to 1 m: no log10(0)
])
def test_eq1_at_2_4_ghz(d, expected):
    assert path_loss_db(d, 2.4, ALPHA, BETA, GAMMA) == pytest.approx(expected, abs=1e-6)


def test_frequency_term():
    # 20 * log10(f): 1.3 GHz -> 2.278867, 5.2 GHz -> 14.320067; at 10 m add 17.3 + 32.4
    assert path_loss_db(10.0, 1.3, ALPHA, BETA, GAMMA) == pytest.approx(51.978867, abs=1e-6)
    assert path_loss_db(10.0, 5.2, ALPHA, BETA, GAMMA) == pytest.approx(64.020067, abs=1e-6)


def test_vectorised_and_non_decreasing():
    d = np.linspace(0.0, 200.0, 2001)
    loss = path_loss_db(d, 2.4, ALPHA, BETA, GAMMA)
    assert loss.shape == d.shape and np.all(np.diff(loss) >= 0)


def test_the_models_kernel_agrees_with_eq1():
    from radio import build_link_model

    from .plans import open_floor

    rng = np.random.default_rng(0)
    xy = np.column_stack((rng.uniform(1, 119, 30), rng.uniform(1, 19, 30)))
    state = build_link_model(open_floor()).evaluate(xy)
    expected = path_loss_db(state.distance, 2.4, ALPHA, BETA, GAMMA)
    assert np.allclose(state.path_loss_db, expected, rtol=0, atol=1e-9)
    # open space: rssi = 15 dBm - L (diagonal excluded)
    off = ~np.eye(30, dtype=bool)
    assert np.allclose(state.rssi[off], 15.0 - expected[off], rtol=0, atol=1e-9)
