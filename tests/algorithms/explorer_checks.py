"""Checks every explorer's tests make: the shipped checker passes and names the explorer's messages, and
one seed gives one run."""

from __future__ import annotations

from typing import Any

from swarm.sim.loop import Simulation

TIMINGS = ("wall_time_s", "setup_time_s")


def assert_passes_checker(name: str, *message_types: str, params: dict[str, Any] | None = None) -> None:
    """``swarm algorithms check`` passes for ``name`` and its message check lists each of ``message_types``."""
    from swarm.testing import CHECKS, check_explorer

    report = check_explorer(name, params=params) if params is not None else check_explorer(name)
    assert report.checks == CHECKS, str(report)
    messages = next(r.detail for r in report.results if r.check == "messages")
    assert all(t in messages for t in message_types), messages


def assert_seed_reproducible(name: str) -> None:
    """Two runs of one spec (2 robots, 600 ticks) have the same summary, timings aside, and explore."""
    spec = {"seed": 3, "map": {"kind": "building", "size": 30}, "robots": {"count": 2},
            "algorithm": {"name": name}, "stop": {"max_ticks": 600}}
    a, b = (Simulation(spec).run().summary for _ in range(2))
    assert {k: v for k, v in a.items() if k not in TIMINGS} == {k: v for k, v in b.items() if k not in TIMINGS}
    assert a["explored"] > 0
