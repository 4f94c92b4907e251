"""The explorer benchmark's campaign mode measures the campaign's own runs, and only the cells asked for."""

from __future__ import annotations

import importlib.util
from pathlib import Path

from swarm.campaign import load_campaign

_ROOT = Path(__file__).resolve().parents[1]
_SPEC = importlib.util.spec_from_file_location("bench_algorithms", _ROOT / "benchmarks" / "speed" / "bench_algorithms.py")
assert _SPEC is not None and _SPEC.loader is not None
bench = importlib.util.module_from_spec(_SPEC)
_SPEC.loader.exec_module(bench)

_PAPER = str(_ROOT / "examples" / "minotaur-paper.toml")


def test_campaign_cells_are_the_matching_cells_runs_as_the_campaign_runs_them():
    campaign = load_campaign(_PAPER, max_runs=None)
    reps = campaign.replicates
    expected = []
    for pos in range(campaign.run_count() // reps):
        run = campaign.run_at(pos * reps + 1)
        cell = {k: str(v) for k, v in run.cell.items()}
        if cell["size"] == "150" and cell["robots"] == "16" and cell["algorithm"] == "TNF":
            expected.append(run.canonical())
    got = bench.campaign_cells(_PAPER, ["size=150", "robots=16"], "tnf", replicate=1)
    assert [spec for _, spec in got] == expected
    assert len(got) == 2 * 2 * 3  # map kinds x spawns x radios
    labels = [text for text, _ in got]
    assert all("size=" not in text and "robots=" not in text for text in labels)  # the fixed labels are left out
    assert len(set(labels)) == len(labels)
    assert {spec["robots"]["count"] for _, spec in got} == {16}


def test_campaign_cells_of_an_algorithm_not_in_the_cells_is_empty():
    assert bench.campaign_cells(_PAPER, ["size=150", "algorithm=Greed"], "tnf", replicate=0) == []
    assert len(bench.campaign_cells(_PAPER, ["size=50", "robots=1", "map=cave"], "greed", replicate=0)) == 2 * 3
