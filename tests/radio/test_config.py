"""RadioConfig: defaults from the paper, TOML-like construction, round trip, and clear errors."""

from __future__ import annotations

import json
import math
import tomllib

import pytest

from radio import RadioConfig, config_from_mapping
from swarm.base.errors import InvalidInput


def test_defaults_are_the_papers():
    c = RadioConfig()
    # Minotaur paper section 4.1 (802.11ax) and 3GPP TR 38.901 InH-office LOS
    assert (c.model, c.frequency_ghz, c.tx_power_dbm, c.sensitivity_dbm) == ("multiwall", 2.4, 15.0, -82.0)
    assert (c.alpha, c.beta, c.gamma, c.wall_mode, c.max_range_m) == (1.73, 32.4, 2.0, "crossing", None)


def test_from_toml_and_round_trip():
    text = """
    model = "multiwall"
    frequency_ghz = 5.2
    wall_mode = "per_metre"
    tx_power_overrides = { "3" = 10.0 }
    [materials]
    glass = [2.26, 2.48, 3.04]
    plaster = { db = 4.0, thickness_m = 0.5 }
    """
    c = config_from_mapping(tomllib.loads(text))
    assert c.frequency_ghz == 5.2 and dict(c.tx_power_overrides) == {3: 10.0}
    assert c.material_table()["plaster"].per_metre_db(5.2) == 8.0  # 4 dB over 0.5 m
    # tx powers for a 5-robot run: robot 3 overridden, ids beyond the run unused
    assert c.tx_power_array(5).tolist() == [15.0, 15.0, 15.0, 10.0, 15.0]
    plain = c.to_mapping()
    assert json.loads(json.dumps(plain)) == plain
    again = config_from_mapping(plain)
    assert again == c and hash(again) == hash(c)


@pytest.mark.parametrize("data, field", [
    ({"frequency_ghz": -2.4}, "frequency_ghz"),
    ({"frequency_ghz": 0}, "frequency_ghz"),
    ({"tx_power_dbm": math.nan}, "tx_power_dbm"),
    ({"sensitivity_dbm": math.inf}, "sensitivity_dbm"),
    ({"alpha": -1}, "alpha"),
    ({"model": "rayleigh"}, "model"),
    ({"wall_mode": "per_wall"}, "wall_mode"),
    ({"max_range_m": 15}, "max_range_m"),                    # only meaningful for LOS
    ({"model": "los", "max_range_m": -1}, "max_range_m"),
    ({"model": "maes", "wall_mode": "per_metre"}, "wall_mode"),
    ({"graze_tolerance_m": 0.5}, "graze_tolerance_m"),
    ({"materials": {"glass": -3}}, "materials.glass"),
    ({"materials": "glass"}, "materials"),
    ({"tx_power_overrides": {"x": 3}}, "tx_power_overrides.x"),
    ({"sensitivity_overrides": {"2": "loud"}}, "sensitivity_overrides.2"),
    ({"frequency": 2.4}, "frequency"),                       # unknown key
])
def test_invalid_configs_name_the_field(data, field):
    with pytest.raises(InvalidInput) as err:
        config_from_mapping(data)
    assert err.value.field == field
    assert str(err.value).count("\n") == 0 and "allowed:" in str(err.value)


def test_unknown_key_lists_the_parameters():
    with pytest.raises(InvalidInput) as err:
        config_from_mapping({"freq": 2.4}, prefix="radio.")
    assert err.value.field == "radio.freq" and "frequency_ghz" in err.value.allowed
