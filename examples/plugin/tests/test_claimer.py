"""The explorer meets swarm's plugin contract, and explores.

Uses only the documented contract: ``swarm.api``, ``swarm.run`` and ``swarm.testing``."""

from __future__ import annotations

import pytest

import swarm
from swarm.api import InvalidInput
from swarm.testing import check_explorer

from swarm_example_explorer import Claimer, ClaimerParams

NAME = "swarm_example_explorer:Claimer"   # by path: works installed or not ("claimer" once installed)


def test_meets_the_plugin_contract():
    report = check_explorer(NAME)
    assert report.checks[0] == "contract" and "transports" in report.checks


def test_explores_a_small_building():
    result = swarm.run({"seed": 1, "map": {"kind": "building", "size": 20}}, robots=2, algorithm=NAME,
                       max_ticks=1500)
    assert result.summary["explored"] > 0.9, result.one_line()
    assert result.summary["messages"]["malformed"] == 0


def test_bad_parameters_are_one_line_errors():
    with pytest.raises(InvalidInput, match="claim_radius_m"):
        ClaimerParams(claim_radius_m=-1.0)
    assert Claimer.Params is ClaimerParams
