"""A run spec round-trips through TOML: ``swarm run --print-spec`` writes what ``--spec`` reads back to the
same run (the same key), for every kind of section."""

from __future__ import annotations

import tomllib

import pytest

from swarm.cli import main
from swarm.sim.spec import RunSpec

SPECS = [
    {},
    {"seed": 7, "map": {"kind": "cave", "size": [40, 30], "seed": 3, "params": {"fill_percent": 45}},
     "robots": {"count": 8, "spawn": "random", "spawn_seed": 11}},
    {"algorithm": {"name": "tnf", "params": {"alpha": 8.0, "beta": 8.0}}, "comm": {"loss": 0.25, "bandwidth": 4000}},
    {"algorithm": {"name": "minotaur"}, "navigation": {"unseen": "traversable", "margin_m": 0.1}},
    {"algorithm": {"name": "xboa"}, "lidar": {"noise_std": 0.05, "mode": "logodds", "range_m": 5.0}},
    {"radio": {"model": "multiwall", "frequency_ghz": 5.2, "wall_mode": "per_metre",
               "tx_power_overrides": {"3": 10.0}, "materials": {"plaster": {"db": 4.0, "thickness_m": 0.5},
                                                                "glass": [2.26, 2.48, 3.04]}}},
    {"radio": {"model": "los"}, "motion": {"max_speed": 3.0, "max_turn_rate": 4.0, "substeps": 8}, "stop": {"explored": 0.9}},
    {"map": {"kind": "file", "path": "house.npz"}, "robots": {"count": 1}, "transport": "zenoh", "record_every": 5},
]


@pytest.mark.parametrize("data", SPECS, ids=range(len(SPECS)))
def test_toml_reads_back_to_the_same_run(data):
    spec = RunSpec.from_mapping(data)
    again = RunSpec.from_mapping(tomllib.loads(spec.to_toml()))
    assert again.key == spec.key and again.to_toml() == spec.to_toml()


def test_print_spec_output_is_a_spec_file(tmp_path, capsys):
    assert main(["run", "--print-spec", "--map", "cave", "--robots", "3", "--set", "comm.loss=0.1"]) == 0
    printed = capsys.readouterr().out
    path = tmp_path / "run.toml"
    path.write_text(printed)
    assert main(["run", "--spec", str(path), "--print-spec"]) == 0
    assert capsys.readouterr().out == printed
    assert RunSpec.from_mapping(tomllib.loads(printed)).robots.count == 3


def test_print_spec_shows_every_default_and_reads_back_to_the_same_run(tmp_path, capsys):
    """Settings the canonical form omits at their default (so older specs keep their key) are printed too."""
    assert main(["run", "--print-spec", "--algorithm", "tnf"]) == 0
    printed = capsys.readouterr().out
    data = tomllib.loads(printed)
    assert (data["comm"]["relay"], data["comm"]["relay_hops"], data["comm"]["map_zlib_level"]) == ("none", 4, 6)
    assert (data["radio"]["shadowing_sigma_db"], data["radio"]["per"]) == (0.0, "off")
    assert {"shadowing_corr_m", "per_ref"} <= set(data["radio"]) and "variant" in data["algorithm"]["params"]
    path = tmp_path / "run.toml"
    path.write_text(printed)
    assert main(["run", "--spec", str(path), "--print-spec"]) == 0
    assert capsys.readouterr().out == printed
    assert RunSpec.from_mapping(data).key == RunSpec.from_mapping({"algorithm": {"name": "tnf"}}).key
