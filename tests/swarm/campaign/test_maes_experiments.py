"""examples/maes-experiments.toml (issue 49): MAES's own 2024 experiment grid (DEIS-Tools/MAES 1bb0312,
``ExperimentBase.cs`` / ``SceneToExperiments.cs``, docs/maes.md section 8.2) as a campaign, and two of its
smallest runs end to end, exported under the file names MAES's scripts look for."""

from __future__ import annotations

import re
from pathlib import Path

import pandas as pd
import pytest

from swarm.campaign import load_campaign, make_executor, parse_campaign, run_campaign, status
from swarm.campaign.maes_csv import export_maes_csv
from swarm.campaign.report.load import expected_runs

ROOT = Path(__file__).resolve().parents[3]
SPEC = ROOT / "examples" / "maes-experiments.toml"

# What ExperimentBase.cs runs per scene: 100 map seeds, `for (amountOfRobots = 1; <= 9; += 2)`,
# SpawnTogether and SpawnApart; scenes {building|cave}_{alg}_{Global|LOS|Material}_{50|75|100} (Voronoi
# left out: not in swarm).
MAES_ROBOTS = list(range(1, 10, 2))
MAES_SIZES = ["50", "75", "100"]
MAES_COMMS = ["Global", "LOS", "Material"]
MAES_ALGORITHMS = ["greed", "tnf", "minotaur"]


@pytest.fixture(scope="module")
def full():
    return load_campaign(SPEC)  # validates all 54,000 run specs (~5 s)


def test_grid_is_maes_experiment_grid(full) -> None:
    labels = {dim: [o.label for o in opts] for dim, opts in full.grid.items()}
    assert labels == {"map": ["building", "cave"], "size": MAES_SIZES, "robots": [str(n) for n in MAES_ROBOTS],
                      "spawn": ["together", "random"], "algorithm": MAES_ALGORITHMS, "radio": MAES_COMMS,
                      "comm": ["MAES"]}
    assert full.seed == 1234 and full.replicates == 100
    assert expected_runs(full) == 2 * 3 * 5 * 2 * 3 * 3 * 100
    # SimulationScenario.cs's default end: explored > 0.99 or more than 36,000 ticks; a row every 10 ticks
    assert full.stop == {"explored": 0.99, "max_ticks": 36000} and full.timeseries_every == 10

    cells = {tuple(c[d].label for d in ("map", "algorithm", "radio")): c for c in full.cells()}
    run = {key: full.run_for(cell, 0).spec for key, cell in cells.items()}
    for (kind, alg, radio), spec in run.items():
        assert spec.algorithm.name == alg and spec.algorithm.params["variant"] == "maes"
        assert spec.radio.model == {"Global": "global", "LOS": "los", "Material": "maes"}[radio]
        assert (spec.comm.map_sharing, spec.comm.link_at) == ("maes", "receive")
        assert spec.lidar.range_m == 7.0  # slamRayTraceRange 7
        assert (spec.motion.model, spec.motion.max_speed) == ("maes", 3.0)  # MAES's controller and speed
        # the 2024 buildings: rooms between halls never split (docs/maes.md section 2 item 5)
        assert kind != "building" or spec.map.params["room_split_percent"] == 0
    tnf = run[("building", "tnf", "Global")].algorithm.params
    assert (tnf["alpha"], tnf["beta"]) == (1, 10)  # new TnfExplorationAlgorithm(1, 10, seed)


def two_smallest_runs() -> str:
    """The spec cut to replicate 0 of two 50-tile building cells: Greed, 1 robot, Global, together, and
    Minotaur, 3 robots, Material, apart (the MAES radio and merge with more than one robot)."""
    text = SPEC.read_text()
    text, n = re.subn(r"(?m)^replicates = 100$", "replicates = 1", text)
    assert n == 1
    return text + """
[[exclude]]
map = "cave"
[[exclude]]
size = ["75", "100"]
[[exclude]]
robots = [5, 7, 9]
[[exclude]]
algorithm = "tnf"
[[exclude]]
robots = 1
algorithm = "minotaur"
[[exclude]]
robots = 3
algorithm = "greed"
[[exclude]]
robots = 1
radio = ["LOS", "Material"]
[[exclude]]
robots = 3
radio = ["Global", "LOS"]
[[exclude]]
robots = 1
spawn = "random"
[[exclude]]
robots = 3
spawn = "together"
"""


def test_smallest_runs_finish_and_export_under_maes_names(full, tmp_path: Path) -> None:
    spec = parse_campaign(two_smallest_runs())
    cells = [{d: o.label for d, o in c.items()} for c in spec.cells()]
    assert [(c["algorithm"], c["robots"], c["radio"], c["spawn"]) for c in cells] == [
        ("greed", "1", "Global", "together"), ("minotaur", "3", "Material", "random")]
    # the slice's runs are the full campaign's own first replicates (seeds: campaign seed, kind, size, replicate)
    by_labels = {tuple(sorted((d, o.label) for d, o in c.items())): c for c in full.cells()}
    for cell in spec.cells():
        twin = by_labels[tuple(sorted((d, o.label) for d, o in cell.items()))]
        assert spec.run_for(cell, 0).key == full.run_for(twin, 0).key

    results = tmp_path / "results"
    run_campaign(spec, results, executor=make_executor(workers=1), progress=False)
    counts = status(results)
    assert (counts["done"], counts["failed"], counts["pending"]) == (2, 0, 0)
    runs = pd.concat(pd.read_parquet(p) for p in sorted((results / "parts").glob("*.runs.parquet")))
    assert set(runs["stop_reason"]) == {"explored"} and (runs["explored"] >= 0.99).all()
    assert (runs["ticks"] < 36000).all()

    # --maes-csv names: ExperimentBase.cs's statisticsFileName and its resume regex match them
    names = sorted(p.name for p in export_maes_csv(results, tmp_path / "csv"))
    assert len(names) == 2
    assert re.fullmatch(r"greed-seed-\d+-mapConfig\.HeightInTiles-50-comms-Global-robots-1-SpawnTogether_.*\.csv",
                        names[0]), names
    assert re.fullmatch(r"minotaur-seed-\d+-mapConfig\.HeightInTiles-50-comms-Material-robots-3-SpawnApart_.*\.csv",
                        names[1]), names
