"""MAES CSV export: the header, row format, float printing and file naming of MAES's
StatisticsCSVWriter (docs/maes.md section 8.5), exactly."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from swarm.campaign import ResultsStore
from swarm.campaign.maes_csv import (
    HEADER,
    csv_text,
    dotnet_float,
    export_maes_csv,
    file_name,
    file_stem,
    subfolder_dims,
)

from .synthetic_results import FakeRun, write


def test_header_is_maes_verbatim():
    assert HEADER == "Tick,Covered,Explored,Average Agent Distance,Agents Interconnected, Biggest Cluster %"


@pytest.mark.parametrize("value, text", [
    (0.0, "0"), (-0.0, "0"), (100.0, "100"), (0.1, "0.1"), (98.00001, "98.00001"), (1 / 3, "0.3333333"),
    (0.00012345678, "0.0001234568"), (1e-5, "1E-05"), (12345678.0, "1.234568E+07"), (float("nan"), "NaN"),
])
def test_floats_print_as_single_tostring(value, text):
    assert dotnet_float(value) == text


def test_rows_follow_maes_snapshots():
    text, e, c = csv_text(tick=[0, 10, 20, 25], explored=[0.1, 0.25, 0.5, 0.98999], coverage=[0.0, 0.01, 1 / 3, 0.5],
                          robots=3, comm_groups=[1, 2, 1, 3], biggest_group=[1.0, 2 / 3, 1.0, 1 / 3],
                          all_connected=[True, False, True, False])
    assert text == (HEADER + "\n"
                    "0,0,10,,,\n"                  # tick 0: MAES's communication tracker writes nothing
                    "10,1,25,,0,66.66667\n"        # 2 of 3 robots in the biggest group: 2f / 3f * 100f
                    "20,33.33334,50,,1,100\n"      # one group: exactly 100
                    "25,50,98.999,,0,33.33334\n")  # distance blank: not recorded for several robots
    assert (e, c) == (98, 50), "the file-name suffix truncates the last row, as (int) does"


def test_one_robot_has_zero_average_distance():
    text, _, _ = csv_text([0, 10], [0.2, 0.3], [0.01, 0.02], 1, [1, 1], [1.0, 1.0], [True, True])
    assert text.splitlines()[1:] == ["0,1,20,0,,", "10,2,30,0,1,100"]


def test_file_names_follow_the_2024_campaign():
    stem = file_stem("greed", "building", "building", 4450073834181740416, "150", "multiwall", 16, "together")
    assert stem == "greed-seed-4450073834181740416-mapConfig.HeightInTiles-150-comms-Material-robots-16-SpawnTogether"
    assert file_name(stem, 98, 36) == stem + "_e98-c36.csv"
    cave = file_stem("tnf", "cave", "cave", 7, "120x80", "los", 2, "random")
    assert cave == "cave-tnf-seed-7-mapConfig.HeightInTiles-80-comms-LOS-robots-2-SpawnApart"
    assert "-comms-Global-" in file_stem("greed", "building", "b", 1, "50", "global", 1, "together")
    assert "-comms-Material-" in file_stem("greed", "building", "b", 1, "50", "maes", 1, "together")


def test_labels_the_name_cannot_tell_apart_get_subfolders():
    runs = pd.DataFrame({"map": ["building"] * 3, "map_kind": ["building"] * 3, "size": ["50"] * 3,
                         "robots": [2] * 3, "spawn": ["together"] * 3, "algorithm": ["greed"] * 3,
                         "radio": ["mw24", "mw5", "los"], "radio_model": ["multiwall", "multiwall", "los"],
                         "comm": ["default"] * 3, "transport": ["inprocess"] * 3})
    assert subfolder_dims(runs) == ["radio"]
    runs["radio"], runs["radio_model"] = ["global", "multiwall", "los"], ["global", "multiwall", "los"]
    assert subfolder_dims(runs) == []


def test_export_writes_one_file_per_done_run(tmp_path):
    fakes = [FakeRun("greed", "global", 0, 120), FakeRun("frontier", "los", 1, None, stop_reason="max_ticks"),
             FakeRun("greed", "los", 0, None, failed="RuntimeError: x")]
    results = write(tmp_path / "results", fakes)
    paths = export_maes_csv(results, tmp_path / "out")
    runs = ResultsStore(results).runs_table().to_pandas()
    seeds = runs[runs["status"] == "ok"].set_index("algorithm")["map_seed"]
    assert len(paths) == 2, "the failed run has no statistics, as in MAES"
    assert {p.name for p in paths} == {
        f"greed-seed-{seeds['greed']}-mapConfig.HeightInTiles-20-comms-Global-robots-2-SpawnTogether_e98-c32.csv",
        f"frontier-seed-{seeds['frontier']}-mapConfig.HeightInTiles-20-comms-LOS-robots-2-SpawnTogether_e90-c30.csv"}
    greed = next(p for p in paths if p.name.startswith("greed"))
    lines = greed.read_text().split("\n")
    assert lines[0] == HEADER and lines[-1] == ""
    assert lines[1] == "0,0,0,,,"
    # explored 0.081667 (the fake's 0.98 * 10 / 120): (float)0.081667 * 100f is 8.166699 in single precision
    assert lines[2] == "10,2.722233,8.166699,,0,50"
    assert lines[-2] == "120,32.66666,98,,1,100"  # (float)(0.98 / 3) * 100f = 32.666665: 7 digits "32.66666"
    frame = pd.read_csv(greed)
    assert list(frame["Tick"]) == [*range(0, 121, 10)]
    assert frame["Explored"].iloc[-1] == pytest.approx(98.0)
    index = pd.read_csv(tmp_path / "out/maes-csv-index.csv")
    assert sorted(index["stop_reason"]) == ["explored", "max_ticks"]
    assert all((tmp_path / "out" / f).exists() for f in index["file"])
    before = {p: p.read_bytes() for p in paths}
    again = export_maes_csv(results, tmp_path / "out")
    assert {p: p.read_bytes() for p in again} == before


def test_percentages_are_single_precision_products():
    explored = np.array([0.29])  # 0.29 * 100 is 28.999999999999996 in double; MAES multiplies floats
    text, e, _ = csv_text([0], explored, [0.0], 1)
    assert text.splitlines()[1] == "0,0,29,0,,"
    assert e == 29
