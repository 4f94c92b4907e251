"""The explorer meets swarm's plugin contract, and explores."""

from __future__ import annotations

import pytest

from swarm.api import InvalidInput
from swarm import Simulation
from swarm.testing import check_explorer

from swarm_example_explorer import Claimer, ClaimerParams

NAME = "swarm_example_explorer:Claimer"   # by path: works installed or not ("claimer" once installed)


def test_meets_the_plugin_contract():
    report = check_explorer(NAME)
    assert report.checks[0] == "contract" and "transports" in report.checks


def test_explores_a_small_building():
    result = Simulation({"seed": 1, "map": {"kind": "building", "size": 20}, "robots": {"count": 2},
                         "algorithm": {"name": NAME}, "stop": {"max_ticks": 1500}}).run()
    assert result.summary["explored"] > 0.9, result.one_line()
    assert result.summary["messages"]["malformed"] == 0


def test_bad_parameters_are_one_line_errors():
    with pytest.raises(InvalidInput, match="claim_radius_m"):
        ClaimerParams(claim_radius_m=-1.0)
    assert Claimer.Params is ClaimerParams
