"""The RSSI field over a map and its picture."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

from radio import RadioConfig, build_link_model
from radio.heatmap import CONTOUR_RGB, contour_mask, render_heatmap, rssi_field, save_heatmap

from .plans import vertical_wall


def test_field_values_at_cell_centres():
    m = vertical_wall("concrete")
    f = rssi_field(build_link_model(m), (10.0, 20.25))
    # cell centre (15.25, 20.25), row 40, col 30: d = 5.25 m, L = 17.3 log10(5.25) + 40.004225 = 52.462981
    assert f.rssi[40, 30] == pytest.approx(15 - 52.462981, abs=1e-6)
    # cell centre (30.25, 20.25), col 60, behind the wall: L(20.25) = 22.601153 + 40.004225 = 62.605378; - 15 dB
    assert f.rssi[40, 60] == pytest.approx(15 - 62.605378 - 15, abs=1e-6)
    assert np.isnan(f.rssi[40, 40]) and not f.link[40, 40]  # inside the wall (col 40 = x in [20, 20.5))
    assert np.isnan(f.rssi[m.solid]).all() and np.isfinite(f.rssi[m.free]).all()


def test_contour_is_the_edge_of_the_linked_region():
    link = np.zeros((5, 6), dtype=bool)
    link[1:4, 1:3] = True
    free = np.ones_like(link)
    free[[0, -1], :] = free[:, [0, -1]] = False
    # linked cells with an unlinked free 4-neighbour: column 2 borders column 3 (unlinked, free)
    expected = np.zeros_like(link)
    expected[1:4, 2] = True
    assert np.array_equal(contour_mask(link, free), expected)


def test_picture(tmp_path):
    m = vertical_wall("concrete")
    model = build_link_model(m, RadioConfig(tx_power_dbm=-20.0))  # weak: the linked region ends in the room
    field = rssi_field(model, (10.0, 20.25))
    assert 0.0 < field.linked_share < 1.0
    image = render_heatmap(m, field, scale=2, title="t")
    # 80 x 80 cells at 2 px per cell, plus the legend strip
    assert image.width == 160 and image.height > 160
    pixels = np.asarray(image)[:160]
    assert (pixels == CONTOUR_RGB).all(axis=2).any()
    path = save_heatmap(m, field, tmp_path / "rssi.png", scale=2, title="t")
    assert Image.open(path).size == image.size


def test_line_of_sight_field_and_trace():
    m = vertical_wall("concrete")
    model = build_link_model(m, RadioConfig(model="los"))
    field = rssi_field(model, (10.0, 20.25))
    # left of the wall (x < 20): line of sight, rssi = tx power; right of it: blocked, -inf
    assert field.rssi[40, 30] == 15.0 and field.link[40, 30]
    assert field.rssi[40, 60] == -np.inf and not field.link[40, 60]
    assert render_heatmap(m, field, scale=1).width == 80
    # LOS counts the wall but charges no dB for it
    (wall,) = model.trace((10.0, 20.25), (30.0, 20.25))
    assert wall.db == 0.0 and wall.charged == ("concrete",)


@pytest.mark.parametrize("tx_power, sensitivity", [(1e308, -1e308), (-1e308, 1e308), (-1e308, -1e308)])
def test_picture_of_a_field_whose_range_overflows_floats(tmp_path, tx_power, sensitivity):
    """``--tx-power 1e308 --sensitivity -1e308`` made the colour range inf - (-inf) and every ramp position NaN
    (an IndexError, found by tests/maps/test_fuzz_inputs.py); any finite setting now draws."""
    import warnings

    from radio.heatmap import colour_ramp

    m = vertical_wall("concrete")
    field = rssi_field(build_link_model(m, RadioConfig(tx_power_dbm=tx_power, sensitivity_dbm=sensitivity)),
                       (10.0, 20.25))
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no overflow warnings on the way either
        image = render_heatmap(m, field)
        ends = colour_ramp(np.array([-1e308, 0.0, 1e308]), -1e308, 1e308)
    assert image.size[0] > 0
    assert np.array_equal(ends[0], colour_ramp(np.array([0.0]), 0.0, 1.0)[0])   # the ramp's dark end
    assert np.array_equal(ends[2], colour_ramp(np.array([1.0]), 0.0, 1.0)[0])   # its bright end
    assert np.array_equal(ends[1], colour_ramp(np.array([0.5]), 0.0, 1.0)[0])   # the middle stays the middle
