"""Every built-in explorer meets the plugin contract: registered with its parameters, and passes every check
of ``swarm.testing.check_explorer`` (typed parameters, well-formed actions, determinism, its own messages
registered and round-tripping the codec, observations left alone, robustness, in-process == zenoh)."""

from __future__ import annotations

import dataclasses

import pytest

from swarm.plugins import explorers as registry
from swarm.testing import CHECKS, check_explorer

BUILT_INS = {
    "frontier": "algorithms.frontier:FrontierExplorer",
    "greed": "algorithms.greed:Greed",
    "tnf": "algorithms.tnf:TNF",
    "minotaur": "algorithms.minotaur:Minotaur",
    "xboa": "algorithms.xboa:XBOA",
    "rbw": "algorithms.random_ballistic_walk:RandomBallisticWalk",
    "wall_follower": "algorithms.wall_follower:WallFollower",
    "brick_and_mortar": "algorithms.brick_and_mortar:BrickAndMortar",
    "ssb": "algorithms.ssb:SSB",
    "voronoi": "algorithms.voronoi:Voronoi",
    "market": "algorithms.market:Market",
    "mmpf": "algorithms.mmpf:MMPF",
    "rrt_exploration": "algorithms.rrt_exploration:RRTExploration",
}
OWN_MESSAGES = {"tnf": "tnf.destination", "minotaur": "minotaur.", "xboa": "xboa.target",
                "brick_and_mortar": "brick_and_mortar.", "ssb": "ssb.", "voronoi": "voronoi.explored",
                "market": "market.pose", "mmpf": "mmpf.pose",
                "rrt_exploration": "rrt.goal"}
"""A message type of its own each of these must send in the check's run, so the messages check saw it."""
SETTINGS = {"xboa": {"params": {"pop_size": 8, "max_gen": 8, "preset": "defaults"}}}
"""xBOA's optimiser at its smallest useful budget (the check's run still decides and announces)."""


def test_built_ins_are_registered_with_their_parameters():
    assert {name: registry.available().get(name) for name in BUILT_INS} == BUILT_INS
    for name in BUILT_INS:
        fields = [f.name for f in dataclasses.fields(registry.params_class(name))]
        assert [row[0] for row in registry.describe(name)] == fields and fields, name
        assert registry.load(name).name == name


@pytest.mark.parametrize("name", list(BUILT_INS))
def test_built_in_passes_the_explorer_checker(name):
    report = check_explorer(name, **SETTINGS.get(name, {}))
    assert report.checks == CHECKS, str(report)
    messages = next(r.detail for r in report.results if r.check == "messages")
    if name in OWN_MESSAGES:
        assert OWN_MESSAGES[name] in messages, messages
    else:
        assert messages.startswith("sends no messages of its own"), messages
    assert "a full inbox" in next(r.detail for r in report.results if r.check == "robustness")
