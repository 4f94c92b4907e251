"""benchmarks/experiments/rerun_sample.py: repeats a sample of a results folder's runs and compares rows;
identical on the same code, and a changed result is reported (exit 1)."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import swarm
from swarm.campaign import executors

_ROOT = Path(__file__).resolve().parents[1]
_SPEC = importlib.util.spec_from_file_location("rerun_sample", _ROOT / "benchmarks" / "experiments" / "rerun_sample.py")
rerun = importlib.util.module_from_spec(_SPEC)
_SPEC.loader.exec_module(rerun)  # type: ignore[union-attr]

CAMPAIGN = """
[campaign]
name = "rerun"
seed = 7
replicates = 2
[grid]
map = ["building"]
size = [20]
robots = [2]
spawn = ["together"]
algorithm = ["frontier"]
radio = ["global"]
[stop]
max_ticks = 60
"""


def test_a_sample_is_identical_on_the_same_code_and_a_changed_result_is_reported(tmp_path, capsys, monkeypatch):
    spec = tmp_path / "c.toml"
    spec.write_text(CAMPAIGN)
    swarm.campaign.run(str(spec), tmp_path / "out", inline=True)
    assert rerun.main([str(tmp_path / "out"), str(spec), "--runs", "2"]) == 0
    out = capsys.readouterr().out
    assert out.count("SAME run") == 2 and "2 of 2 rows identical" in out

    real = executors.execute

    def one_tick_more(task):
        result = real(task)
        result["summary"]["ticks"] += 1
        return result

    monkeypatch.setattr(executors, "execute", one_tick_more)
    assert rerun.main([str(tmp_path / "out"), str(spec), "--runs", "1"]) == 1
    assert "differs in ticks" in capsys.readouterr().out
