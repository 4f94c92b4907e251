"""Whole runs every MAES-style explorer (Greed, TNF) must survive: one robot explores a 50 x 50 map,
determinism, in-process == zenoh, and every link model with the sharing modes that matter for it.

Minotaur and xBOA have their own whole-run tests (their runs need other maps, batteries or motion).
"""

from __future__ import annotations

import pytest

from swarm.sim.loop import Simulation

EXPLORERS = ["greed", "tnf"]


def small(algorithm: str) -> dict:
    return {"seed": 4, "map": {"kind": "building", "size": 30}, "robots": {"count": 3},
            "algorithm": {"name": algorithm}, "radio": {"model": "multiwall"}, "stop": {"max_ticks": 500}}


@pytest.mark.parametrize("algorithm", EXPLORERS)
@pytest.mark.parametrize("kind", ["building", "cave"])
def test_one_robot_explores_a_50_map(algorithm, kind):
    r = Simulation({"seed": 1, "map": {"kind": kind, "size": 50}, "robots": {"count": 1},
                    "algorithm": {"name": algorithm}}).run()
    assert r.summary["stop_reason"] == "explored", r.one_line()
    assert r.summary["ticks_to"]["0.99"] is not None


@pytest.mark.parametrize("algorithm", EXPLORERS)
def test_same_spec_twice_is_identical(algorithm):
    a = Simulation(small(algorithm)).run()
    b = Simulation(small(algorithm)).run()
    assert a.deterministic_view() == b.deterministic_view()
    assert a.summary["messages"]["delivered"] > 0


@pytest.mark.parametrize("algorithm", EXPLORERS)
def test_inprocess_and_zenoh_transports_agree(algorithm):
    a = Simulation({**small(algorithm), "transport": "inprocess"}).run()
    b = Simulation({**small(algorithm), "transport": "zenoh"}).run()
    strip = lambda r: {k: v for k, v in r.deterministic_view().items() if k not in ("spec", "key")}
    assert strip(a) == strip(b)


@pytest.mark.parametrize("radio", ["global", "los", "multiwall", "maes"])
@pytest.mark.parametrize("algorithm, sharing", [("greed", "delta"), ("greed", "full"), ("tnf", "delta"), ("tnf", "off")])
def test_runs_with_every_link_model_and_sharing_mode(algorithm, sharing, radio):
    r = Simulation({**small(algorithm), "radio": {"model": radio}, "comm": {"map_sharing": sharing},
                    "stop": {"max_ticks": 300}}).run()
    assert r.summary["explored"] > 0.2, r.one_line()
    assert r.summary["messages"]["malformed"] == 0
    if algorithm == "tnf" and sharing == "off":
        assert r.summary["messages"]["sent"] > 0 and r.summary["messages"]["map_bytes_sent"] == 0, \
            "destinations are TNF's own messages"
