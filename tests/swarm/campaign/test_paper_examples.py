"""The example campaigns (issue 11): the Minotaur paper's full grid, its small version, and a real run of
the small spec cut to one replicate of the 50-tile maps, every run finishing and its report building."""

from __future__ import annotations

import re
from pathlib import Path

import pandas as pd
import pytest

from swarm.campaign import load_campaign, make_executor, parse_campaign, run_campaign, status
from swarm.campaign.report import build_report
from swarm.campaign.report.load import expected_runs
from swarm.comm.medium import CommSpec

ROOT = Path(__file__).resolve().parents[3]
FULL = ROOT / "examples" / "minotaur-paper.toml"
SMALL = ROOT / "examples" / "minotaur-paper-small.toml"


def test_examples_quick_is_the_built_in_quick_campaign() -> None:
    builtin = ROOT / "swarm" / "campaign" / "examples" / "quick.toml"
    assert (ROOT / "examples" / "quick.toml").read_text() == builtin.read_text()


@pytest.fixture(scope="module")
def full():
    return load_campaign(FULL)  # validates all 54,000 run specs: ~25 s, so once per module


def test_full_paper_campaign_is_table_2(full) -> None:
    spec = full
    assert spec.seed == 123456 and spec.stop["explored"] == 0.98
    labels = {dim: [o.label for o in opts] for dim, opts in spec.grid.items()}
    assert labels == {"map": ["building", "cave"], "size": ["50", "100", "150"], "robots": ["1", "2", "4", "8", "16"],
                      "spawn": ["together", "random"], "algorithm": ["TNF", "Minotaur", "Greed"],
                      "radio": ["global", "LOS", "materials"]}
    assert expected_runs(spec) == 54_000


def test_small_campaign_is_the_full_grid_with_fewer_replicates(full) -> None:
    small = load_campaign(SMALL)
    assert small.replicates < full.replicates
    assert small.grid == full.grid and small.run == full.run and small.stop == full.stop
    # seeds depend on (campaign seed, kind, size, replicate) only: the small runs are the full's first ones
    for cell in small.cells()[::97]:
        for rep in range(small.replicates):
            assert small.run_for(cell, rep).key == full.run_for(cell, rep).key


def small_50_one_replicate() -> str:
    text = SMALL.read_text()
    text, n_rep = re.subn(r"(?m)^replicates = \d+$", "replicates = 1", text)
    text, n_size = re.subn(r"(?m)^size = \[.*\]$", "size = [50]", text)
    assert n_rep == 1 and n_size == 1
    return text


def test_small_spec_on_50_tile_maps_finishes_every_run_and_reports(tmp_path: Path) -> None:
    spec = parse_campaign(small_50_one_replicate())
    assert expected_runs(spec) == 180
    results = tmp_path / "results"
    run_campaign(spec, results, executor=make_executor(workers=2), progress=False)
    counts = status(results)
    assert (counts["done"], counts["failed"], counts["pending"]) == (180, 0, 0)
    report = build_report(results, tmp_path / "report")
    folder = report.parent
    runs = pd.read_csv(folder / "tables" / "runs.csv")
    assert len(runs) == 180 and set(runs["stop_reason"]) == {"explored"}
    assert (runs["explored"] >= 0.98).all()
    readme = (folder / "README.md").read_text()
    assert "minotaur-paper-small" in readme
    for link in re.findall(r"\]\(([^)#]+)\)", readme):
        assert (folder / link).exists(), link
    assert list((folder / "curves").glob("algorithms__building_50_16_*_materials.png"))
    summary = (folder / "tables" / "summary.md").read_text()
    assert "Minotaur" in summary and "TNF" in summary and "Greed" in summary


def test_frontier_recheck_example_pairs_the_two_recheck_periods_on_the_same_maps() -> None:
    spec = load_campaign(ROOT / "examples" / "frontier-recheck.toml")
    assert [o.label for o in spec.grid["algorithm"]] == ["frontier-recheck-20", "frontier-recheck-40"]
    assert expected_runs(spec) == 96
    runs: dict[tuple, dict[str, object]] = {}
    for cell in spec.cells():
        for rep in range(spec.replicates):
            run = spec.run_for(cell, rep).spec
            where = (cell["map"].label, cell["size"].label, cell["robots"].label, rep)
            runs.setdefault(where, {})[cell["algorithm"].label] = run
    assert len(runs) == 48
    for pair in runs.values():
        a, b = pair["frontier-recheck-20"], pair["frontier-recheck-40"]
        # the same map and start poses; only the re-check period differs (20 is the explorer's default)
        assert a.map == b.map and a.robots == b.robots and a.seed == b.seed
        assert a.algorithm.params == {**b.algorithm.params, "recheck_ticks": 20}
        assert b.algorithm.params["recheck_ticks"] == 40


def test_comm_sweep_example_sweeps_sensitivity_and_loss_from_the_best_radio() -> None:
    spec = load_campaign(ROOT / "examples" / "comm-sweep.toml")
    labels = {dim: [o.label for o in opts] for dim, opts in spec.grid.items()}
    assert labels["algorithm"] == ["greed", "tnf", "minotaur"] and labels["map"] == ["building", "cave"]
    assert spec.axes == ("radio.sensitivity_dbm", "comm.loss", "comm.relay")
    assert labels["radio.sensitivity_dbm"] == ["-88", "-82", "-76", "-70"], "the reference (first) is the best radio"
    runs = spec.runs()
    assert {r.spec.radio.model for r in runs} == {"multiwall"} and spec.replicates >= 6
    flood = {(r.cell["map"], r.cell["size"], r.cell["algorithm"], r.cell["radio.sensitivity_dbm"], r.replicate)
             for r in runs if r.spec.comm.relay == "flood"}
    plain = {(r.cell["map"], r.cell["size"], r.cell["algorithm"], r.cell["radio.sensitivity_dbm"], r.replicate)
             for r in runs if r.spec.comm.relay == "none" and r.spec.comm.loss == 0}
    assert flood and flood < plain, "every relaying run has its pair without relaying"


def test_ablation_example_is_full_maes_parity_with_one_departure_per_slice() -> None:
    """examples/minotaur-ablation.toml (issue 49): at least 20 maps per cell, every algorithm's MAES variant,
    MAES's motion and heading under full parity, and each departure (swarm's motion among them) a slice
    that differs from parity in that one setting, on the same maps."""
    spec = load_campaign(ROOT / "examples" / "minotaur-ablation.toml")
    assert spec.replicates >= 20
    # the first two replicates of every cell (building all 7,040 specs takes half a minute; every replicate
    # of a cell is built from the same template)
    runs = [spec.run_at(i) for i in spec.indices() if i % spec.replicates < 2]
    assert len(runs) == 2 * len(spec.indices()) // spec.replicates
    parity = [r for r in runs if r.cell["radio"] == "materials" and r.cell["comm"] == "MAES"
              and r.cell["motion.model"] == "maes" and "(swarm)" not in r.cell["algorithm"]]
    assert {r.spec.algorithm.params["variant"] for r in parity} == {"maes"}
    assert {r.spec.robots.heading for r in runs} == {"maes"}
    assert {r.spec.motion.max_speed for r in runs} == {3.0}
    smooth = [r for r in runs if r.cell["motion.model"] == "continuous"]
    assert {r.cell["algorithm"] for r in smooth} == {"Greed", "TNF", "Minotaur"}
    assert {r.cell["radio"] for r in smooth} == {"materials"} and {r.cell["comm"] for r in smooth} == {"MAES"}
    def world(r):
        return (r.cell["map"], r.cell["size"], r.cell["robots"], r.cell["spawn"], r.cell["algorithm"], r.replicate)
    assert {world(r) for r in smooth} == {world(r) for r in parity}, "each departure run has its parity pair"
    assert {r.cell["algorithm"] for r in runs} >= {"Greed (swarm)", "TNF (swarm)", "Minotaur (swarm)"}


def test_localization_study_crosses_every_error_model_with_avoidance_on_the_same_maps() -> None:
    """examples/localization-study.toml (issue 50): perfect localisation, three odometry drifts and two
    bounded sigmas, each with and without ORCA, for Greed, TNF and Minotaur; perfect runs carry no
    localisation section (their keys are those of runs before the feature)."""
    spec = load_campaign(ROOT / "examples" / "localization-study.toml")
    runs = spec.runs()
    conditions = {(r.spec.localization.model, r.spec.localization.drift_per_m, r.spec.localization.sigma_m)
                  for r in runs}
    assert conditions == {("perfect", 0.02, 0.1), ("odometry", 0.01, 0.1), ("odometry", 0.02, 0.1),
                          ("odometry", 0.05, 0.1), ("bounded", 0.02, 0.05), ("bounded", 0.02, 0.2)}
    assert {r.spec.navigation.avoidance for r in runs} == {"none", "orca"}
    assert {r.cell["algorithm"] for r in runs} == {"greed", "tnf", "minotaur"}
    for r in runs:
        if r.spec.localization.model == "odometry":
            assert r.spec.localization.turn_drift_per_rad == r.spec.localization.drift_per_m
        if r.spec.localization.model == "perfect":
            assert "localization" not in r.spec_json
    worlds = {}
    for r in runs:
        worlds.setdefault((r.cell["map"], r.cell["robots"], r.replicate), set()).add(r.spec.map.seed)
    assert all(len(seeds) == 1 for seeds in worlds.values()), "every condition runs on the same maps"


def test_swarm_sizes_example_runs_16_to_1024_robots_and_reports(tmp_path: Path) -> None:
    """Issue 47: a campaign grid of 16 to 1,024 robots works end to end, report included (cut to 3 ticks a
    run and a 150-tile building here; the example's 100 ticks on 300 tiles take ~1.5 min)."""
    text = (ROOT / "examples" / "swarm-sizes.toml").read_text()
    assert "robots = [16, 64, 256, 1024]" in text
    spec = parse_campaign(text.replace("max_ticks = 100", "max_ticks = 3").replace("size = [300]", "size = [150]"))
    results = tmp_path / "results"
    run_campaign(spec, results, executor=make_executor(workers=1), progress=False)
    counts = status(results)
    assert (counts["done"], counts["failed"], counts["pending"]) == (4, 0, 0)
    folder = build_report(results, tmp_path / "report").parent
    runs = pd.read_csv(folder / "tables" / "runs.csv")
    assert sorted(runs["robots"]) == [16, 64, 256, 1024] and set(runs["stop_reason"]) == {"max_ticks"}
    assert "`1024`" in (folder / "README.md").read_text()


def test_explorer_comparison_runs_every_registered_explorer_on_the_same_maps() -> None:
    """examples/explorer-comparison.toml (issue 52): every built-in explorer, buildings, caves and the example
    plans, 4 and 16 robots; each explorer of a cell meets the same maps; its figure layout names only values
    the grid has."""
    from swarm.campaign.report.layout import check_layout, load_layout
    from swarm.plugins import explorers

    spec = load_campaign(ROOT / "examples" / "explorer-comparison.toml")
    runs = spec.runs()
    assert len(runs) == 234
    names = {r.spec.algorithm.name for r in runs}
    built_in = {name for name, target in explorers.available().items() if target.startswith("algorithms.")}
    assert names == built_in, "a built-in explorer is missing from the comparison"
    worlds: dict[tuple[str, int, int], set[str]] = {}
    for r in runs:
        world = r.spec.map.path if r.spec.map.kind == "file" else str(r.spec.map.seed)
        worlds.setdefault((r.cell["map"], r.cell["robots"], r.replicate), set()).add(str(world))
    assert all(len(w) == 1 for w in worlds.values()), "every explorer meets the same maps"
    orders = {dim: [o.label for o in opts] for dim, opts in spec.grid.items()}
    check_layout(load_layout(ROOT / "examples" / "explorer-comparison-figures.toml"), orders)


def test_the_maes_experiments_slice_is_the_full_campaigns_first_two_maps():
    """examples/maes-experiments-slice.toml (issue 49, published in docs/results/maes-experiments) runs
    exactly the first two replicates of examples/maes-experiments.toml: every cell, the same run specs
    (maps, spawns, seeds), and its figure layout names only what the grid has."""
    from swarm.campaign.report.layout import check_layout, load_layout

    full = {(tuple(sorted(r.cell.items())), r.replicate): r for r in
            load_campaign(ROOT / "examples" / "maes-experiments.toml").runs() if r.replicate < 2}
    slice_spec = load_campaign(ROOT / "examples" / "maes-experiments-slice.toml")
    runs = slice_spec.runs()
    assert len(runs) == len(full) == 1080
    for r in runs:
        assert full[(tuple(sorted(r.cell.items())), r.replicate)].spec == r.spec
    orders = {dim: [o.label for o in opts] for dim, opts in slice_spec.grid.items()}
    check_layout(load_layout(ROOT / "examples" / "maes-experiments-figures.toml"), orders)


@pytest.mark.parametrize("name, robots, spawns, periods", [
    ("share_every_swarm.toml", 1000, {"random"}, [10, 200]),
    ("share_every_team.toml", 16, {"together", "random"}, [10, 50, 200])])
def test_share_every_campaigns_pair_the_sharing_periods_on_the_same_maps(name, robots, spawns, periods) -> None:
    """The issue-47 measurements of `comm.share_every`: each period meets the same maps and start poses, and
    the first period is the runtime's default (the reference of every paired comparison)."""
    spec = load_campaign(ROOT / "benchmarks" / "experiments" / name)
    assert [o.label for o in spec.grid["comm"]] == [f"every {k}" for k in periods]
    runs: dict[tuple, dict[int, object]] = {}
    for run in spec.runs():
        assert run.spec.robots.count == robots
        where = (run.cell["spawn"], run.cell["algorithm"], run.replicate)
        runs.setdefault(where, {})[run.spec.comm.share_every] = run.spec
    assert {w[0] for w in runs} == spawns
    assert len(runs) == len(spawns) * len(spec.grid["algorithm"]) * spec.replicates
    assert periods[0] == CommSpec().share_every
    for pair in runs.values():
        assert sorted(pair) == periods
        first = pair[periods[0]]
        for other in pair.values():  # only the sharing period differs
            assert other.map == first.map and other.robots == first.robots and other.seed == first.seed
            assert other.algorithm == first.algorithm and other.radio == first.radio


def _campaign_files() -> list[Path]:
    files = sorted((ROOT / "examples").glob("*.toml")) + sorted((ROOT / "benchmarks" / "experiments").glob("*.toml"))
    return [f for f in files if "\n[campaign]" in "\n" + f.read_text()]


@pytest.mark.parametrize("path", _campaign_files(), ids=lambda p: f"{p.parent.name}/{p.name}")
def test_every_shipped_campaign_spec_validates(path: Path) -> None:
    """Every campaign TOML the project ships parses and builds a run spec per cell, so its documented command
    does not fail on a typo (figure layouts, which have no [campaign] table, are checked by their own tests)."""
    spec = load_campaign(path, max_runs=None)
    assert spec.run_bound() > 0
