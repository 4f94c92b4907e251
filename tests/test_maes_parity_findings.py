"""benchmarks/experiments/maes_parity_findings.py: the MAES-parity findings are a pure function of a runs
table. On the committed ablation report's runs table it writes the committed findings unchanged; every
departure the campaign ran is a condition, and a runs table from before the motion axis leaves that one out."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

_ROOT = Path(__file__).resolve().parents[1]
_SPEC = importlib.util.spec_from_file_location("maes_parity_findings",
                                               _ROOT / "benchmarks" / "experiments" / "maes_parity_findings.py")
findings = importlib.util.module_from_spec(_SPEC)
sys.modules["maes_parity_findings"] = findings   # its dataclasses look their module up
_SPEC.loader.exec_module(findings)  # type: ignore[union-attr]
REPORT = _ROOT / "docs" / "results" / "maes-parity"


def test_the_committed_findings_are_rewritten_byte_for_byte(tmp_path):
    out = tmp_path / "findings.md"
    assert findings.main([str(REPORT / "report" / "tables" / "runs.csv"), "-o", str(out)]) == 0
    written = out.read_text().splitlines()
    committed = (REPORT / "findings.md").read_text().splitlines()
    assert written[3:] == committed[3:]          # all but the header naming the runs table's path
    assert (tmp_path / "findings.csv").read_text() == (REPORT / "findings.csv").read_text()


def test_every_departure_the_campaign_ran_is_a_condition_and_a_table_without_the_motion_axis_drops_it():
    runs = findings.effects.read_runs_csv(REPORT / "report" / "tables" / "runs.csv")
    res, shifts = findings.analyse(runs)
    assert set(res["name"]) == {c.name for c in findings.CONDITIONS}
    assert set(shifts["condition"]) == {c.name for c in findings.CONDITIONS[1:]}
    before = runs[runs[findings.MOTION] == "continuous"].drop(columns=findings.MOTION)   # the first version's
    res, shifts = findings.analyse(before[before["algorithm"] != "Greed (swarm)"])
    names = set(res["name"]) | set(shifts["condition"])
    assert "full MAES parity" in names and "swarm's Minotaur" not in names   # run under MAES motion only
    assert "swarm's motion (continuous)" not in names and "swarm's Greed" not in names
    # global and LOS were run under MAES's motion only: the radio findings have no parity runs left
    assert set(res["finding"]) == {f.key for f in findings.FINDINGS} - {"R1", "R2", "R3", "R4"}
    assert "Not tested (the runs table has no full-parity runs for them): R1, R2, R3, R4." in \
        findings.render(res, shifts, "runs.csv")


def test_the_kept_ablation_results_folder_is_sound_and_resumes_the_example_campaign():
    """docs/results/maes-parity/campaign/ holds the ablation's runs so far (compacted): its parts pass the
    results check, its spec is examples/minotaur-ablation.toml's (so `swarm campaign run` resumes it), and
    every run it holds is one of that campaign's and was computed by one clean commit."""
    from swarm.campaign import load_campaign, status
    from swarm.campaign.identity import difference
    from swarm.campaign.store import ResultsStore

    folder = REPORT / "campaign"
    example = _ROOT / "examples" / "minotaur-ablation.toml"
    assert difference((folder / "campaign.toml").read_text(), example.read_text()) is None
    s = status(folder)
    assert not s.get("damaged") and s["done"] > 0 and s["done"] + s["failed"] + s["pending"] == s["total"] == 7040
    runs = ResultsStore(folder).runs_table(columns=("key", "swarm_version")).to_pydict()
    keys = {key for _, key in load_campaign(example).iter_keys()}
    assert set(runs["key"]) <= keys
    versions = set(runs["swarm_version"])
    assert len(versions) == 1 and "+git." in next(iter(versions)) and not next(iter(versions)).endswith("-dirty")


def test_a_verdict_takes_its_side_from_the_paired_test():
    """Greed's 2-robot cells tie under every radio (MAES's merge never merges), so R2's median ratio is
    exactly 1 while the maps that differ favour global: the finding holds, it is not reversed."""
    import pandas as pd

    row = {"ratio": 1.0, "rank_biserial": -0.63, "p_holm": 0.001}
    assert findings.verdict(pd.Series(row)) == "**holds**"
    assert findings.verdict(pd.Series({**row, "rank_biserial": 0.63})) == "**reversed**"
    assert findings.verdict(pd.Series({**row, "p_holm": 0.2})) == "not established"
