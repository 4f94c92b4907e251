"""The report's communication section: from a real sweep campaign (tables, figures, findings that quote
the tables' numbers), its sentences on hand-made rows (each clause follows the numbers), and results
without comm metrics."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest

from swarm.campaign import make_executor, parse_campaign, run_campaign
from swarm.campaign.report import build_report
from swarm.campaign.report import comm

from .synthetic_results import FakeRun, write

SWEEP = """
[campaign]
name = "comm-report-test"
seed = 5
replicates = 2

[grid]
map = ["building"]
size = [20]
robots = [1, 3]
spawn = ["random"]
algorithm = ["greed", "frontier"]
radio.sensitivity_dbm = [-90, -35]

[stop]
explored = 0.9
max_ticks = 400
"""


@pytest.fixture(scope="module")
def sweep(tmp_path_factory) -> tuple[Path, Path]:
    root = tmp_path_factory.mktemp("sweep")
    results = root / "results"
    run_campaign(parse_campaign(SWEEP), results, executor=make_executor(inline=True), progress=False)
    return results, build_report(results, root / "report").parent


def test_the_section_has_its_tables_figures_and_a_finding_per_comparison(sweep):
    _, report = sweep
    text = (report / "README.md").read_text()
    section = text.split("## Communication\n", 1)[1].split("\n## ", 1)[0]
    for name in ("comm", "comm_pooled", "comm_effects"):
        for ext in ("md", "tex", "csv"):
            assert (report / "tables" / f"{name}.{ext}").exists(), (name, ext)
    assert (report / "comm/against_radio.sensitivity-dbm.png").stat().st_size > 5000
    against = pd.read_csv(report / "comm/against_radio.sensitivity-dbm.csv")
    assert set(against["metric"]) == {"ttt_or_max", "missing_pct", "aoi_age_s", "delivered_pct"}
    assert set(against["value"].astype(str)) == {"-90", "-35"}
    for alg in ("greed", "frontier"):
        assert (report / f"comm/radio.sensitivity-dbm__building_20_3_random_{alg}_multiwall.png").exists()
    effects = pd.read_csv(report / "tables/comm_effects.csv")
    assert list(zip(effects["algorithm"], effects["a"].astype(str), effects["b"].astype(str))) == [
        ("greed", "-90", "-35"), ("frontier", "-90", "-35")]
    for _, row in effects.iterrows():
        line = next(ln for ln in section.splitlines() if ln.startswith(f"- **{row['algorithm']}, "))
        assert (f"a message reached {row['delivered_pct:b']:.1f} % of the other robots under -35 against "
                f"{row['delivered_pct:a']:.1f} %") in line
        assert f"{row['missing_pct:b']:.1f} %" in line
    assert effects["delivered_pct:b"].max() < effects["delivered_pct:a"].min(), \
        "a -35 dBm receiver hears less than a -90 dBm one: the sweep shows in the numbers"
    cells = pd.read_csv(report / "tables/comm.csv")
    assert len(cells) == 2 * 2 * 2 and (cells.loc[cells["robots"] == 1, "missing_pct"] == 0).all()


@pytest.mark.parametrize("numbers, verdict, expect, absent", [
    ({"delivered_pct": (99.5, 99.0)}, "identical", ["made no difference to what was carried"], ["lost"]),
    ({"delivered_pct": (100.0, 60.0), "missing_pct": (2.0, 2.5), "biggest_pct": (100.0, 90.0)},
     "no established difference", ["Messages were lost", "no knowledge was", "stayed in groups", "90.0 %"], []),
    ({"delivered_pct": (100.0, 60.0), "missing_pct": (2.0, 2.5), "biggest_pct": (100.0, 40.0),
      "aoi_age_s": (1.0, 1.1)}, "not tested", ["kept each robot up to date"], ["groups"]),
    ({"delivered_pct": (100.0, 60.0), "missing_pct": (2.0, 2.5), "biggest_pct": (100.0, 40.0),
      "aoi_age_s": (1.0, 9.0)}, "not tested", ["was older (9.0 s against 1.0 s)"], ["groups"]),
    ({"delivered_pct": (100.0, 60.0), "missing_pct": (2.0, 30.0)}, "no established difference",
     ["Messages reached fewer robots", "robots knew less", "30.0 %",
      "no difference in exploration time was established"],
     ["no knowledge"]),
    ({"delivered_pct": (100.0, 60.0), "missing_pct": (2.0, 30.0)}, "not tested",
     ["robots knew less", "too few maps to tell"], ["established"]),
    ({"delivered_pct": (60.0, 100.0), "missing_pct": (10.0, 2.0)}, "identical",
     ["Messages reached more robots", "robots knew more", "did not change"], ["lost"]),
    ({"delivered_pct": (60.0, 100.0), "missing_pct": (2.0, 2.2)}, "no established difference",
     ["Messages reached more robots", "knew no more"], ["lost"]),
    ({"delivered_pct": (100.0, 60.0), "missing_pct": (2.0, 30.0)}, "slower",
     ["was slower than under ref (ticks b/a 1.25", "30.0 %"], ["did not show"]),
])
def test_a_finding_says_what_its_numbers_say(numbers, verdict, expect, absent):
    values = {"delivered_pct": (100.0, 100.0), "missing_pct": (1.0, 1.0), "aoi_age_s": (2.0, 2.0),
              "biggest_pct": (100.0, 100.0), **numbers}
    row = {"dimension": "radio", "algorithm": "greed", "a": "ref", "b": "bad", "pairs": 10, "maps": 10,
           "tested": 10, "ratio": 0.8, "p_value": 0.01, "p_holm": 0.02 if verdict == "slower" else 0.4,
           "verdict": verdict}
    for metric, (a, b) in values.items():
        row[f"{metric}:a"], row[f"{metric}:b"] = a, b
    text = comm.sentence(pd.Series(row))
    for needle in expect:
        assert needle in text, (needle, text)
    for needle in absent:
        assert needle not in text, (needle, text)


def test_the_verdict_follows_the_paired_test():
    base = {"ties_all": False, "p_holm": 0.01, "p_value": 0.001, "ratio": 0.8, "rank_biserial": -0.9}
    assert comm.verdict(pd.Series(base)) == "slower"
    assert comm.verdict(pd.Series({**base, "ratio": 1.2, "rank_biserial": 0.9})) == "faster"
    # most maps tie (median ratio exactly 1): the side is the test's, decided by the maps that differ
    assert comm.verdict(pd.Series({**base, "ratio": 1.0, "rank_biserial": -0.6})) == "slower"
    assert comm.verdict(pd.Series({**base, "ratio": 1.0, "rank_biserial": 0.6})) == "faster"
    assert comm.verdict(pd.Series({**base, "p_holm": 0.3})) == "no established difference"
    assert comm.verdict(pd.Series({**base, "p_holm": float("nan"), "p_value": float("nan")})) == "not tested"
    assert comm.verdict(pd.Series({**base, "ties_all": True})) == "identical"


def test_results_without_comm_metrics_get_a_note(tmp_path):
    runs = [FakeRun(alg, radio, rep, 100 + rep) for alg in ("greed", "frontier") for radio in ("global", "los")
            for rep in range(2)]
    report = build_report(write(tmp_path / "results", runs, replicates=2), tmp_path / "report")
    text = report.read_text()
    assert "## Communication\n\nThese results hold no communication metrics" in text
    assert not (tmp_path / "report/tables/comm.csv").exists()
