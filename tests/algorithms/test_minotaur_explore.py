"""Minotaur explores whole maps (issue 7): 99 % of seeded buildings with 1, 4 and 16 robots, and of a
cave (where the paper finds it slow, but it must finish). One seed per cell keeps CI affordable; the
many-seed comparison with Greed and TNF is ``benchmarks/experiments/compare.py`` (and, on the paper's grid,
docs/results/minotaur-paper/README.md)."""

from __future__ import annotations

import pytest

from swarm.sim.loop import Simulation

# MAES's robots (3 m/s, as in the paper's campaign) where one robot alone on 100 x 100 would need most of
# the tick limit at our default 1 m/s; examples/minotaur-paper-small.toml runs every cell of the paper.
MAES = {"max_speed": 3.0, "max_turn_rate": 4.0, "max_accel": 60.0, "max_turn_accel": 120.0, "substeps": 8}
CASES = [
    ("building", 50, 1, 1, None),
    ("building", 50, 4, 2, None),
    ("building", 50, 16, 6, None),
    ("building", 100, 1, 8, MAES),
    ("building", 100, 4, 7, None),
    ("building", 100, 16, 3, None),
    ("cave", 50, 2, 4, None),
    ("cave", 50, 4, 5, None),
    ("cave", 100, 4, 9, MAES),
]


@pytest.mark.parametrize("kind,size,robots,seed,motion", CASES)
def test_explores_99_percent(kind: str, size: int, robots: int, seed: int, motion: dict | None) -> None:
    spec = {"map": {"kind": kind, "size": size}, "robots": {"count": robots}, "algorithm": {"name": "minotaur"},
            "radio": {"model": "multiwall"}, "seed": seed, "stop": {"max_ticks": 36000}}
    if motion:
        spec["motion"] = motion
    summary = Simulation(spec).run().summary
    assert summary["stop_reason"] == "explored", summary["explored"]
    assert summary["explored"] >= 0.99
