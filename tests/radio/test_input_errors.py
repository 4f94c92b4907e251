"""Issue #31 on the radio side: per-robot overrides, config files and flags give one short error line."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from maps import InvalidInput
from maps.io import save_npz
from radio import RadioConfig
from swarm.cli import main
from swarm.sim.spec import RunSpec

from .plans import vertical_wall


def cli_error(capfd, *args: str) -> str:
    code = main([str(a) for a in args])
    out, err = capfd.readouterr()
    assert code == 2, (code, out[-500:], err[-2000:])
    assert err.startswith("swarm: error: ") and len(err.splitlines()) == 1, err[-2000:]
    assert len(err) < 600, err[:600]
    return err.rstrip("\n")


@pytest.fixture
def wall_npz(tmp_path):
    return str(save_npz(vertical_wall("concrete"), tmp_path / "wall.npz"))


@pytest.mark.parametrize("section", ["tx_power_overrides", "sensitivity_overrides"])
def test_override_for_a_robot_that_does_not_exist_is_refused(section):
    with pytest.raises(InvalidInput) as info:
        RunSpec.from_mapping({"robots": {"count": 4}, "radio": {section: {"999": 10.0}}})
    assert info.value.field == f"radio.{section}.999"
    assert "0..3" in info.value.allowed
    spec = RunSpec.from_mapping({"robots": {"count": 4}, "radio": {section: {"3": 10.0}}})
    assert getattr(spec.radio, section) == {3: 10.0} and spec.canonical()["radio"][section] == {"3": 10.0}


def test_cli_run_with_an_override_for_robot_999(capfd):
    err = cli_error(capfd, "run", "--robots", "4", "--set", "radio.tx_power_overrides.999=10", "--print-spec")
    assert "radio.tx_power_overrides.999" in err and "0..3" in err


@pytest.mark.parametrize("key", ["1.5", "-1", "x", "\u00b3", "\u0663", "9" * 5000, " 1", ""])
def test_override_keys_must_be_plain_robot_ids(key):
    with pytest.raises(InvalidInput) as info:
        RadioConfig(tx_power_overrides={key: 10.0})
    assert info.value.field.startswith("tx_power_overrides")
    assert len(str(info.value)) < 400


@pytest.mark.parametrize("power", [float("inf"), float("-inf"), float("nan"), "10", None, 10**400])
def test_override_powers_must_be_finite_numbers(power):
    with pytest.raises(InvalidInput) as info:
        RadioConfig(tx_power_overrides={"1": power})
    assert info.value.field == "tx_power_overrides.1"


def test_radio_config_file_problems(tmp_path, capfd, wall_npz):
    for i, text in enumerate(["radio = 5", "x = " + "9" * 5000, "x = " + "[" * 5000 + "]" * 5000,
                              "[radio]\nmaterials = 3", '[radio]\n"' + "k" * 20_000 + '" = 1']):
        path = tmp_path / f"c{i}.toml"
        path.write_text(text)
        err = cli_error(capfd, "radio", "link", wall_npz, "--from", "10,20", "--to", "30,20", "--config", path)
        assert "k" * 200 not in err
    path = tmp_path / "bytes.toml"
    path.write_bytes(bytes(range(256)))
    cli_error(capfd, "radio", "link", wall_npz, "--from", "10,20", "--to", "30,20", "--config", path)


def test_radio_flags_with_huge_values_stay_short(capfd, wall_npz):
    huge = "7" * 20_000
    for args in (["--freq", huge + "x"], ["--from", huge + ",1"], ["--model", huge],
                 ["--param", f"materials.{huge}=1"], ["--param", f"alpha={huge}"],
                 ["--param", f"tx_power_overrides.{huge}=1"]):
        base = ["radio", "link", wall_npz, "--from", "10,20", "--to", "30,20"]
        err = cli_error(capfd, *base, *args)
        assert huge[:200] not in err


def test_heatmap_picture_size_is_bounded(tmp_path, capfd, wall_npz, monkeypatch):
    import maps.render

    monkeypatch.setattr(maps.render, "MAX_PICTURE_PIXELS", 100_000)
    err = cli_error(capfd, "radio", "heatmap", wall_npz, "--tx", "10,20", "--scale", "32", "-o", tmp_path / "h.png")
    assert err.startswith("swarm: error: --scale: got 32")
    assert not (tmp_path / "h.png").exists()


@pytest.mark.parametrize("freqs", [0, 2.4, "2.4", {"a": 1}, None])
def test_material_frequencies_that_are_not_a_list(freqs):
    """Found by the fuzz suite: ``freq_ghz = 0`` used to raise TypeError ('int' object is not iterable)."""
    from radio import material_from_value

    with pytest.raises(InvalidInput) as info:
        material_from_value("concrete", {"db": [1, 2], "freq_ghz": freqs})
    assert info.value.field == "materials.concrete.freq_ghz"


VALUES = st.recursive(st.none() | st.booleans() | st.integers(-10**30, 10**30) | st.floats() | st.text(max_size=8)
                      | st.sampled_from(["9" * 5000, "x" * 20_000, "\u00b3", "los", "per_metre"]),
                      lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=6), inner, max_size=3),
                      max_leaves=10)
OVERRIDES = st.dictionaries(st.one_of(st.integers(0, 12).map(str), st.text(max_size=3)),
                            st.one_of(st.floats(), st.integers(-10**400, 10**400), st.text(max_size=3)), max_size=3)
KEYS = st.sampled_from(["model", "frequency_ghz", "tx_power_dbm", "sensitivity_dbm", "alpha", "beta", "gamma",
                        "wall_mode", "max_range_m", "graze_tolerance_m", "materials", "tx_power_overrides",
                        "sensitivity_overrides", "unknown"])


@settings(max_examples=400, deadline=None, database=None)
@given(config=st.dictionaries(KEYS, VALUES, max_size=4), overrides=OVERRIDES, robots=st.integers(1, 8),
       section=st.sampled_from(["tx_power_overrides", "sensitivity_overrides"]))
def test_fuzz_radio_sections_of_a_run_spec(config, overrides, robots, section):
    """Any [radio] table gives a spec or one short InvalidInput line, never another exception; a spec
    never keeps an override for a robot the run does not have."""
    config = {**config, section: overrides}
    try:
        spec = RunSpec.from_mapping({"robots": {"count": robots}, "radio": config})
    except InvalidInput as exc:
        assert len(str(exc).splitlines()) == 1 and len(str(exc)) < 600
    else:
        assert all(int(k) < robots for k in getattr(spec.radio, section))
