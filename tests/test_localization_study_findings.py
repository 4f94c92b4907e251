"""benchmarks/experiments/localization_study_findings.py: on a hand-built runs table the time ratios, the
map-quality medians, the avoidance contacts and the ranking come out as computed by hand."""

from __future__ import annotations

import csv
import importlib.util
import sys
from pathlib import Path

_ROOT = Path(__file__).resolve().parents[1]
_SPEC = importlib.util.spec_from_file_location(
    "localization_study_findings", _ROOT / "benchmarks" / "experiments" / "localization_study_findings.py")
findings = importlib.util.module_from_spec(_SPEC)
sys.modules["localization_study_findings"] = findings
_SPEC.loader.exec_module(findings)  # type: ignore[union-attr]

CONDITIONS = [("perfect", "0.02", "0.1", 1.0), ("odometry", "0.05", "0.1", 1.5), ("bounded", "0.02", "0.2", 1.1)]
SLOWER = {"greed": 1.0, "tnf": 2.0}   # tnf's error models cost twice greed's extra time


def write_runs(path: Path) -> None:
    rows = []
    for alg in SLOWER:
        for model, drift, sigma, factor in CONDITIONS:
            for avoid in ("none", "orca"):
                for rep in range(6):
                    ticks = round(1000 * (1 + (factor - 1) * SLOWER[alg]) * (1.2 if avoid == "orca" else 1.0))
                    rows.append({"key": f"{alg}{model}{avoid}{rep}", "map": "building", "size": "75", "robots": "16",
                                 "spawn": "together", "algorithm": alg, "radio": "multiwall", "comm": "default",
                                 "transport": "inprocess", "localization.model": model,
                                 "localization.drift_per_m": drift, "localization.turn_drift_per_rad": drift,
                                 "localization.sigma_m": sigma, "navigation.avoidance": avoid, "replicate": rep,
                                 "status": "ok", "stop_reason": "explored", "ticks": ticks, "max_ticks": 10000,
                                 "explored": 0.95, "map_seed": 100 + rep,
                                 "collisions_wall": 10, "collisions_robot": 80 if avoid == "none" else 40,
                                 "pose_error_m": "" if model == "perfect" else 0.5 * factor,
                                 "explored_correct": "" if model == "perfect" else 0.9 - 0.1 * SLOWER[alg],
                                 "ticks_to_target": ticks, "success": "True"})
    with path.open("w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)


def test_findings_on_a_hand_built_table(tmp_path):
    write_runs(tmp_path / "runs.csv")
    runs = findings.effects.read_runs_csv(tmp_path / "runs.csv")
    conds = findings.conditions(runs)
    assert [label for label, _ in conds] == ["perfect", "odometry 5 %/m", "bounded sigma 0.2 m"]
    costs = findings.time_costs(runs, conds).set_index(["algorithm", "condition"])
    assert costs.loc[("greed", "odometry 5 %/m"), "ratio"] == 1.5
    assert costs.loc[("tnf", "odometry 5 %/m"), "ratio"] == 2.0
    assert abs(costs.loc[("tnf", "bounded sigma 0.2 m"), "ratio"] - 1.2) < 1e-9
    qual = findings.quality(runs, conds).set_index(["algorithm", "condition"])
    assert qual.loc[("greed", "odometry 5 %/m"), "pose_error_m"] == 0.75
    avoid = findings.avoidance(runs).set_index("name")
    assert abs(avoid.loc["greed | 16", "ratio"] - 1.2) < 1e-9
    assert avoid.loc["greed | 16", "robot_off"] > avoid.loc["greed | 16", "robot_on"]
    assert abs(avoid.loc["greed | 16", "wall_off"] - findings.np.median(
        [10 / (16 * t * 0.1 / 3600) for t in (1000, 1500, 1100)])) < 1e-6   # 10 wall contacts, 3 error models
    ranked = findings.ranking(findings.time_costs(runs, conds), findings.quality(runs, conds))
    assert [alg for alg, *_ in ranked] == ["greed", "tnf"]                    # 0.8 explored correctly against 0.7
    assert abs(ranked[0][1] - 0.8) < 1e-9 and ranked[1][2] == 2.0 and not ranked[0][3]  # every run reached it
    out = tmp_path / "findings.md"
    assert findings.main([str(tmp_path / "runs.csv"), "-o", str(out)]) == 0
    assert "1. **greed**" in out.read_text()
    assert findings.main([str(tmp_path / "runs.csv"), "-o", str(out), "--figure", str(tmp_path / "fig.png")]) == 0
    assert (tmp_path / "fig.png").stat().st_size > 10_000 and (tmp_path / "fig.pdf").exists()
