"""Materials: the paper's Table 1, log-frequency interpolation, config entries, and clear errors."""

from __future__ import annotations

import math

import pytest

from radio.materials import DEFAULT_MATERIALS, Material, material_from_value, resolve_table
from swarm.base.errors import InvalidInput


@pytest.mark.parametrize("name, expected", [
    ("air", (0.0, 0.0, 0.0)),
    ("concrete", (13.0, 15.0, 23.0)),
    ("wood", (5.1, 6.7, 14.0)),
    ("brick", (4.5, 5.5, 15.0)),
    ("wall", (0.0, 0.0, 0.0)),
])
def test_table_points_are_exact(name, expected):
    # Minotaur paper Table 1 (and MAES's generic wall): the table frequencies return the table values.
    m = DEFAULT_MATERIALS[name]
    assert tuple(m.crossing_db(f) for f in (1.3, 2.4, 5.2)) == pytest.approx(expected, abs=1e-12)


def test_interpolation_is_linear_in_log_frequency():
    concrete = DEFAULT_MATERIALS["concrete"]
    # 3.5 GHz: w = ln(3.5/2.4) / ln(5.2/2.4) = 0.377294 / 0.773190 = 0.487971; 15 + 8 * w = 18.903768 dB
    assert concrete.crossing_db(3.5) == pytest.approx(18.903768, abs=1e-6)
    # the geometric mean of 1.3 and 2.4 GHz (1.766352 GHz) is halfway in log f: (13 + 15) / 2 = 14 dB
    assert concrete.crossing_db(math.sqrt(1.3 * 2.4)) == pytest.approx(14.0, abs=1e-9)


def test_clamped_outside_the_table():
    wood = DEFAULT_MATERIALS["wood"]
    # below 1.3 GHz the 1.3 GHz value (5.1 dB), above 5.2 GHz the 5.2 GHz value (14 dB)
    assert wood.crossing_db(0.9) == 5.1
    assert wood.crossing_db(28.0) == 14.0


def test_per_metre_spreads_the_crossing_over_the_thickness():
    # 6.7 dB over a 0.25 m thick wall = 26.8 dB per metre
    m = Material("panel", (1.3, 2.4, 5.2), (5.1, 6.7, 14.0), thickness_m=0.25)
    assert m.per_metre_db(2.4) == pytest.approx(26.8)


def test_config_entry_forms():
    # a number: the same at every frequency
    assert material_from_value("glass", 2.0).crossing_db(5.0) == 2.0
    # a list: dB at 1.3 / 2.4 / 5.2 GHz
    assert material_from_value("glass", [1, 2, 3]).crossing_db(2.4) == 2.0
    # a table with its own frequencies and thickness: 4 dB at 2.4 GHz over 0.5 m = 8 dB/m
    m = material_from_value("plaster", {"db": [3.0, 4.0], "freq_ghz": [1.0, 2.4], "thickness_m": 0.5})
    assert m.crossing_db(2.4) == 4.0 and m.per_metre_db(2.4) == 8.0
    assert material_from_value("drywall", m.to_mapping() | {"db": [1.0, 2.0]}).db == (1.0, 2.0)


@pytest.mark.parametrize("name, value, field", [
    ("glass", -1.0, "materials.glass"),
    ("glass", [1, 2], "materials.glass"),
    ("glass", [1, float("nan"), 3], "materials.glass.db[1]"),
    ("glass", {"db": [1, 2], "freq_ghz": [2.4, 1.3]}, "materials.glass.freq_ghz"),
    ("glass", {"db": [1, 2], "freq_ghz": [-1, 1.3]}, "materials.glass.freq_ghz[0]"),
    ("glass", {"db": 1, "colour": "blue"}, "materials.glass.colour"),
    ("glass", {"db": 1, "thickness_m": 0}, "materials.glass.thickness_m"),
    ("glass", "thin", "materials.glass"),
    ("air", 3.0, "materials.air.db"),
    ("Glass!", 3.0, "materials"),
])
def test_bad_entries_name_the_field(name, value, field):
    with pytest.raises(InvalidInput) as err:
        material_from_value(name, value)
    assert err.value.field == field


def test_unknown_map_material_is_an_error_listing_the_known_ones():
    with pytest.raises(InvalidInput) as err:
        resolve_table(("air", "concrete", "plaster"), {})
    assert err.value.field == "material" and err.value.value == "plaster"
    assert "concrete" in err.value.allowed and "[radio.materials]" in err.value.allowed
    # defining it in the config resolves it, and config entries override the defaults
    table = resolve_table(("air", "plaster", "wood"),
                          {"plaster": material_from_value("plaster", 4.0), "wood": material_from_value("wood", 1.0)})
    assert [m.crossing_db(2.4) for m in table] == [0.0, 4.0, 1.0]
