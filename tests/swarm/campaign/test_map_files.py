"""A grid dimension over a folder of map files (issue 52): ``map = [{files = "plans/*.json", ...}]``, replicate r on
file r mod n, the same file for every algorithm, end to end through ``swarm campaign run`` and ``report``."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from maps import InvalidInput
from swarm.campaign import load_campaign, parse_campaign, status
from swarm.campaign.store import ResultsStore
from swarm.cli import main

PLANS = Path(__file__).resolve().parents[3] / "examples" / "plans"

SPEC = """
[campaign]
name = "plans"
seed = 11
replicates = 3

[grid]
map = [{files = "plans/*.json", label = "houseexpo", params = {scale = 2.5}}]
size = [50]
robots = [2]
spawn = ["together"]
algorithm = ["frontier", "greed"]
radio = ["global"]

[stop]
explored = 0.9
max_ticks = 120
"""


@pytest.fixture
def campaign(tmp_path: Path) -> Path:
    shutil.copytree(PLANS, tmp_path / "plans")
    (tmp_path / "spec.toml").write_text(SPEC)
    return tmp_path / "spec.toml"


def test_replicates_cycle_through_the_sorted_files_and_every_algorithm_meets_the_same_one(campaign):
    spec = load_campaign(campaign)
    files = sorted(str(p.resolve()) for p in (campaign.parent / "plans").glob("*.json"))
    runs = spec.runs()
    assert len(runs) == 2 * 3
    for run in runs:
        assert run.cell["map"] == "houseexpo"
        assert run.spec.map.path == files[run.replicate % 3] and run.spec.map.params == {"scale": 2.5}
    by_rep = {}
    for run in runs:
        by_rep.setdefault(run.replicate, set()).add((run.spec.map.path, json.dumps(run.seeds, sort_keys=True)))
    assert all(len(worlds) == 1 for worlds in by_rep.values()), "paired: one world per replicate"
    # the stored text records the folder, so a re-parse from anywhere gives the same keys
    again = parse_campaign(spec.source, "elsewhere.toml")
    assert [k for _, k in again.iter_keys()] == [k for _, k in spec.iter_keys()]


def test_run_and_report_end_to_end(campaign, tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["campaign", "run", str(campaign), "-o", str(out), "--inline", "--quiet", "--no-report"]) == 0
    st = status(out)
    assert st["done"] == 6 and st["failed"] == 0, st
    table = ResultsStore(out).runs_table().to_pylist()
    assert {row["map"] for row in table} == {"houseexpo"} and all(row["explored"] > 0 for row in table)
    assert main(["campaign", "run", str(campaign), "-o", str(out), "--inline", "--quiet", "--no-report"]) == 0
    assert len(ResultsStore(out).runs_table().to_pylist()) == 6, "a second run resumes: nothing run twice"
    assert main(["campaign", "report", str(out), "--quiet", "--no-cell-figures"]) == 0
    readme = (out / "report" / "README.md").read_text()
    assert "houseexpo" in readme
    # the plans are drawn as the runs met them: one panel per file, in metres
    from maps.io import load_map
    from swarm.campaign.report import mapfigs
    from swarm.campaign.report.load import load as load_results
    ((title, panels),) = mapfigs.campaign_maps(load_results(out))
    assert title.startswith("houseexpo") and len(panels) == len(list((campaign.parent / "plans").glob("*.json")))
    first = sorted((campaign.parent / "plans").glob("*.json"))[0]
    assert panels[0][0] == first.name
    assert (panels[0][1].solid == load_map(first, scale=2.5).solid).all()
    assert "## Maps" in readme and (out / "report" / "figures" / f"maps-{title.replace(' ', '-')}.png").stat().st_size > 10_000
    import csv

    with open(out / "report" / "tables" / "paired.csv", newline="") as f:
        (row,) = list(csv.DictReader(f))
    assert (row["map"], row["a"], row["b"], row["pairs"], row["maps"]) == ("houseexpo", "frontier", "greed", "3", "3")


def test_runs_the_spec_does_not_define_are_left_out_of_the_report(campaign, tmp_path):
    out = tmp_path / "out"
    assert main(["campaign", "run", str(campaign), "-o", str(out), "--inline", "--quiet", "--no-report"]) == 0
    stored = out / "campaign.toml"
    stored.write_text(stored.read_text().replace('algorithm = ["frontier", "greed"]', 'algorithm = ["frontier"]'))
    from swarm.campaign.report.load import load as load_results
    data = load_results(out)            # greed's 3 runs are no runs of the spec now
    assert data.foreign == 3 and len(data.runs) == 3 and set(data.runs["algorithm"]) == {"frontier"}
    assert main(["campaign", "report", str(out), "--quiet", "--no-cell-figures"]) == 0
    assert "3 runs in the folder are not runs of its spec" in (out / "report" / "README.md").read_text()


def test_resuming_from_a_copy_with_its_own_map_files_is_refused(campaign, tmp_path, capsys):
    """A run's key holds its map file's path: the same TOML beside another copy of the plans would run every
    file-map run again under new keys. It is refused in one line, and nothing is written."""
    out = tmp_path / "out"
    assert main(["campaign", "run", str(campaign), "-o", str(out), "--inline", "--quiet", "--no-report",
                 "--shard", "0/3"]) == 0
    copy = tmp_path / "copy"
    shutil.copytree(campaign.parent / "plans", copy / "plans")
    shutil.copy(campaign, copy / "spec.toml")
    before = sorted(p.name for p in (out / "parts").iterdir())
    capsys.readouterr()
    assert main(["campaign", "run", str(copy / "spec.toml"), "-o", str(out), "--inline", "--quiet",
                 "--no-report"]) == 2
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert err.startswith("swarm: error: -o:") and f"map files are in {campaign.parent}," in err and str(copy) in err
    assert sorted(p.name for p in (out / "parts").iterdir()) == before
    assert status(out)["done"] == 2


@pytest.mark.parametrize("change, needles", [
    ('files = "plans/*.json"', 'files = "none/*.json"', ),
])
def test_an_empty_glob_is_one_line(campaign, capsys, change, needles):
    campaign.write_text(SPEC.replace(change, needles))
    assert main(["campaign", "run", str(campaign), "-o", str(campaign.parent / "out"), "--inline"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "grid.map[0].files: got 'none/*.json'" in err
    assert "a glob matching at least one map file in" in err


@pytest.mark.parametrize("old, new, needle", [
    ("replicates = 3", "replicates = 2", "campaign.replicates: got 2; allowed: at least 3"),
    ("params = {scale = 2.5}", "params = {scale = 50}", "grid.map[0].params.scale: got 50"),
    ("params = {scale = 2.5}", "params = {door = 1}", "grid.map[0].params.door: got 1"),
    ('label = "houseexpo"', 'label = "houseexpo", size = 3', "files, label and params only"),
    ('"plans/*.json"', '"/abs/*.json"', "a glob relative to the campaign file's folder"),
])
def test_bad_file_entries_name_their_key(campaign, old, new, needle):
    campaign.write_text(SPEC.replace(old, new))
    with pytest.raises(InvalidInput, match=None) as info:
        load_campaign(campaign)
    assert needle in str(info.value), str(info.value)


def test_two_entries_may_share_a_file_only_with_other_params(campaign):
    two = ('map = [{files = "plans/*.json", label = "all"}, '
           '{files = "plans/handmade_[hs]*.json", label = "two"PARAMS}]')
    old = 'map = [{files = "plans/*.json", label = "houseexpo", params = {scale = 2.5}}]'
    campaign.write_text(SPEC.replace(old, two.replace("PARAMS", "")))
    with pytest.raises(InvalidInput, match="grid.map: got 'two'.*handmade_hall_three_rooms.json is also in all"):
        load_campaign(campaign)
    campaign.write_text(SPEC.replace(old, two.replace("PARAMS", ", params = {scale = 2.5}")))
    spec = load_campaign(campaign)
    assert spec.run_count() == 2 * 2 * 3 and len({k for _, k in spec.iter_keys()}) == 12
    paths = {(r.cell["map"], r.replicate): Path(r.spec.map.path).name for r in spec.runs()}
    assert paths[("all", 2)] == "handmade_two_rooms.json" and paths[("two", 2)] == "handmade_hall_three_rooms.json"
