"""Log-normal shadowing: the field is seeded, unit-variance and exponentially correlated; a link reads it
symmetrically; every path (all pairs, senders' columns, one link, heatmap) gives the same numbers."""

from __future__ import annotations

import numpy as np
import pytest

from maps import Map, generate
from radio import RadioConfig, build_link_model
from radio.shadowing import ShadowingField
from swarm.base.errors import InvalidInput


def open_box(width_m: float = 60.0, height_m: float = 40.0) -> Map:
    cols, rows = int(width_m / 0.5), int(height_m / 0.5)
    solid = np.zeros((rows, cols), dtype=bool)
    solid[0, :] = solid[-1, :] = solid[:, 0] = solid[:, -1] = True
    return Map(solid=solid, material=solid.astype(np.uint8), materials=("air", "concrete"), seed=5)


def test_the_field_is_a_function_of_its_seed():
    a, b, c = (ShadowingField(50.0, 30.0, 5.0, seed) for seed in (7, 7, 8))
    points = np.random.default_rng(0).uniform([0, 0], [50, 30], (200, 2))
    assert np.array_equal(a.at(points), b.at(points))
    assert not np.allclose(a.at(points), c.at(points))


def test_the_field_has_unit_variance_and_gudmundson_correlation():
    """exp(-d / d_c) between points d apart, estimated over 40 fields x 300 point pairs each, at random
    (off-grid) positions: unit variance, correlation e^-0.2, e^-1 (within 0.05: sampling error and the
    interpolation's few hundredths), and none at 6 d_c."""
    corr = 5.0
    rng = np.random.default_rng(1)
    estimates: dict[float, list[np.ndarray]] = {0.0: [], 1.0: [], 5.0: [], 30.0: []}
    for seed in range(40):
        field = ShadowingField(80.0, 80.0, corr, seed)
        p = rng.uniform(0, 40, (300, 2))
        angle = rng.uniform(0, 2 * np.pi, 300)
        base = field.at(p)
        for d in estimates:
            q = p + d * np.column_stack((np.cos(angle), np.sin(angle)))
            estimates[d].append(np.column_stack((base, field.at(q))))
    pairs = {d: np.concatenate(v) for d, v in estimates.items()}
    assert abs(pairs[0.0][:, 0].var() - 1.0) < 0.1 and abs(pairs[0.0][:, 0].mean()) < 0.1
    for d in (1.0, 5.0, 30.0):
        rho = np.corrcoef(pairs[d].T)[0, 1]
        assert abs(rho - np.exp(-d / corr)) < 0.05, (d, rho, np.exp(-d / corr))


def test_the_field_is_continuous_along_a_path():
    """A robot driving at 1 m/s moves 0.1 m a tick: its field value moves by a small fraction of a sigma,
    so a link's shadowing does not flicker from tick to tick."""
    field = ShadowingField(60.0, 40.0, 10.0, 3)
    path = np.column_stack((np.arange(1.0, 59.0, 0.1), np.full(580, 20.0)))
    steps = np.abs(np.diff(field.at(path)))
    assert steps.max() < 0.15 and steps.mean() < 0.05
    assert np.ptp(field.at(path)) > 1.0  # but it does vary over the map


def state(config: RadioConfig, xy: np.ndarray, truth: Map | None = None):
    return build_link_model(truth or open_box(), config, field_seed=11).evaluate(xy)


XY = np.array([[5.0, 5.0], [20.0, 10.0], [35.0, 30.0], [50.0, 12.0], [12.0, 33.0], [45.0, 35.0]])


def test_link_shadowing_is_symmetric_and_moves_rssi_and_links_by_the_same_amount():
    plain = state(RadioConfig(), XY)
    shadowed = state(RadioConfig(shadowing_sigma_db=8.0, sensitivity_dbm=-55.0), XY)
    base = state(RadioConfig(sensitivity_dbm=-55.0), XY)
    s = shadowed.shadowing_db
    assert plain.shadowing_db is None and s is not None
    assert np.array_equal(s, s.T) and np.all(np.diag(s) == 0.0) and np.abs(s).max() > 1.0
    np.testing.assert_allclose(shadowed.rssi, base.rssi - s, rtol=0, atol=1e-12)
    off = ~np.eye(len(XY), dtype=bool)
    assert np.array_equal(shadowed.link[off], (shadowed.rssi >= -55.0)[off]) and not shadowed.link.diagonal().any()
    assert not np.array_equal(shadowed.link, base.link), "sigma 8 dB near the sensitivity changes some links"


def test_link_shadowing_is_normal_with_the_configured_sigma_whatever_the_distance():
    """Over many maps' fields, S(p, q) has standard deviation sigma for near and far pairs alike."""
    sigma = 4.0
    near, far = [], []
    xy = np.array([[10.0, 10.0], [10.5, 10.0], [50.0, 30.0]])
    for seed in range(400):
        s = build_link_model(open_box(), RadioConfig(shadowing_sigma_db=sigma), field_seed=seed).evaluate(xy).shadowing_db
        near.append(s[0, 1])
        far.append(s[0, 2])
    for values in (np.array(near), np.array(far)):
        assert abs(values.std() - sigma) < 0.15 * sigma and abs(values.mean()) < 0.2 * sigma


def test_every_path_gives_the_same_shadowed_numbers():
    truth = generate("building", 40, 2)
    rows, cols = np.nonzero(truth.free)
    pick = np.random.default_rng(4).choice(len(rows), 7, replace=False)
    xy = np.column_stack(((cols[pick] + 0.5) * 0.5, (rows[pick] + 0.5) * 0.5))
    config = RadioConfig(shadowing_sigma_db=6.0, sensitivity_dbm=-70.0)
    full = build_link_model(truth, config, field_seed=9).evaluate(xy)
    fresh = build_link_model(truth, config, field_seed=9)  # no cached state: the senders' columns are walked
    link, margin = fresh.margin_columns(xy, [0, 3, 6])
    assert np.array_equal(link, full.link[:, [0, 3, 6]])
    assert np.array_equal(margin, full.rssi[:, [0, 3, 6]] + 70.0, equal_nan=True)
    assert np.array_equal(build_link_model(truth, config, field_seed=9).link_columns(xy, [2, 5]), full.link[:, [2, 5]])
    b = fresh.budget(xy[1], xy[4])
    assert b.rssi_dbm == full.rssi[4, 1] and b.shadowing_db == full.shadowing_db[4, 1] and b.link == full.link[4, 1]
    rssi, _ = fresh.field(xy[2], xy[[0, 5]])
    assert np.array_equal(rssi, full.rssi[[0, 5], 2])


def test_the_field_seed_defaults_to_the_maps_seed():
    config = RadioConfig(shadowing_sigma_db=5.0)
    truth = open_box()  # seed 5
    default = build_link_model(truth, config).evaluate(XY).shadowing_db
    assert np.array_equal(default, build_link_model(truth, config, field_seed=5).evaluate(XY).shadowing_db)
    assert not np.array_equal(default, build_link_model(truth, config, field_seed=6).evaluate(XY).shadowing_db)


@pytest.mark.parametrize("settings, name", [
    ({"shadowing_sigma_db": -1.0}, "shadowing_sigma_db"), ({"shadowing_sigma_db": float("nan")}, "shadowing_sigma_db"),
    ({"shadowing_sigma_db": 51.0}, "shadowing_sigma_db"), ({"shadowing_corr_m": 0.0}, "shadowing_corr_m"),
    ({"model": "los", "shadowing_sigma_db": 2.0}, "shadowing_sigma_db"),
    ({"model": "global", "shadowing_sigma_db": 2.0}, "shadowing_sigma_db"),
])
def test_bad_shadowing_settings_are_one_line_errors(settings, name):
    with pytest.raises(InvalidInput, match=name) as info:
        RadioConfig(**settings)
    assert "\n" not in str(info.value)


def test_shadowing_settings_at_their_defaults_leave_the_canonical_form_alone():
    assert RadioConfig(shadowing_sigma_db=0.0, shadowing_corr_m=10.0).to_mapping() == RadioConfig().to_mapping()
    assert "shadowing_sigma_db" in RadioConfig(shadowing_sigma_db=3.0).to_mapping()
    # a setting of a feature that is off is allowed (a sigma sweep may include 0) and unused
    sweep_zero = RadioConfig(shadowing_corr_m=5.0)
    assert build_link_model(open_box(), sweep_zero).shadowing is None
