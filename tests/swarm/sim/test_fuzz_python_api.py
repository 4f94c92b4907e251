"""Fuzzing the Python API (issue 48): ``swarm.run`` and the spec builders (``swarm.resolve_spec``,
``RunSpec.from_mapping``), ``swarm.campaign.run``, ``load`` and ``load_timeseries``, with arguments of every
type and shape. Every case must end in a result or one short :class:`~swarm.base.errors.InvalidInput` line:
never another exception, a hang (each case is timed) or more than 1 GB of memory (the process's peak RSS may
grow by less than that over the whole file).

Runs are kept small by construction (plausible sizes 20-40 tiles, at most 6 robots, ``max_ticks`` at most 30
or an invalid value), so that a case that is accepted runs in a fraction of a second.

Cases per run (``max_examples``): 300 (spec builders) + 200 (``swarm.run``) + 100 (``campaign.run``) + 150
(``load`` / ``load_timeseries``) = 750 (~20 s on a 2-core machine).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

import swarm
from swarm.base.errors import InvalidInput
from tests.fuzz_bounds import bounded_memory, check_refusal, timed  # noqa: F401 (bounded_memory: a fixture)
from swarm.results.result import RunResult
from swarm.sim.spec import RunSpec

FUZZ = settings(deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
                database=None)

ODD = [None, True, False, 0, -1, 2**63, -(2**70), 10**400, 0.5, float("nan"), float("inf"), "", "x" * 500, b"bytes",
       "\x00\n\u2028", [], [1, 2], (1,), {}, {"a": 1}, {1: 2}, set(), object(), print, np.int64(3), np.float32(2.5),
       np.array([1, 2]), np.zeros((2, 2)), Path("nowhere.npz"), Path("/"), Ellipsis, type, 1j]
"""Values of every type and shape a caller might pass by mistake."""
odd = st.sampled_from(ODD)


def mostly(good: st.SearchStrategy, in_ten: int = 9) -> st.SearchStrategy:
    """``good`` in ``in_ten`` draws of ten, else an odd value."""
    return st.integers(0, 9).flatmap(lambda k: good if k < in_ten else odd)


# ----------------------------------------------------------------------------------- run specs ----
sizes = st.one_of(st.integers(20, 40), st.sampled_from(["20", "24x20", [20, 30], 19, 0, "big", "20x", 20.0]))
sections = st.fixed_dictionaries({}, optional={
    "map": st.fixed_dictionaries({}, optional={"kind": mostly(st.sampled_from(["building", "cave", "file", "maze"])),
                                               "size": sizes, "seed": mostly(st.integers(0, 9)),
                                               "params": mostly(st.dictionaries(st.sampled_from(
                                                   ["fill_percent", "door_width", "bogus"]), odd | st.integers(0, 80),
                                                   max_size=2)),
                                               "path": odd}),
    "robots": mostly(st.fixed_dictionaries({}, optional={"count": mostly(st.integers(1, 6)),
                                                         "spawn": mostly(st.sampled_from(["together", "random"]))})),
    "algorithm": mostly(st.fixed_dictionaries({}, optional={
        "name": mostly(st.sampled_from(["frontier", "greed", "tnf", "minotaur", "xboa", "nope", "os:path", "a:b:c"])),
        "params": mostly(st.dictionaries(st.sampled_from(["recheck_ticks", "alpha", "variant", "bogus"]),
                                         odd | st.integers(1, 50), max_size=2))})),
    "lidar": mostly(st.dictionaries(st.sampled_from(["range_m", "noise_std", "mode", "bogus"]), odd | st.floats(0, 8),
                                    max_size=2)),
    "motion": mostly(st.dictionaries(st.sampled_from(["max_speed", "radius", "substeps"]), odd | st.floats(0.1, 3),
                                     max_size=2)),
    "radio": mostly(st.one_of(st.sampled_from(["los", "global", "multiwall", "wifi"]),
                              st.dictionaries(st.sampled_from(["model", "per", "shadowing_sigma_db", "materials",
                                                               "tx_power_overrides"]), odd, max_size=2))),
    "comm": mostly(st.dictionaries(st.sampled_from(["loss", "relay", "relay_hops", "bandwidth", "map_zlib_level"]),
                                   odd, max_size=2)),
    "navigation": mostly(st.dictionaries(st.sampled_from(["planner", "margin_m", "unseen"]), odd, max_size=2)),
    "stop": mostly(st.dictionaries(st.sampled_from(["explored", "stall_ticks"]), odd, max_size=2)),
    "seed": mostly(st.integers(0, 2**63 - 1)),
    "transport": mostly(st.sampled_from(["inprocess", "inprocess", "inprocess", "zenoh"])),
    "record_every": mostly(st.integers(1, 20)),
})
spec_args = st.integers(0, 9).flatmap(lambda k: st.none() if k < 2 else sections if k < 7 else odd if k < 8 else
                                      st.sampled_from(["seed = 3\n", "[map]\nsize = 20\n", "=\n", "nowhere.toml",
                                                       "[stop]\nmax_ticks = 'x'\n"]))
keywords = st.fixed_dictionaries({"max_ticks": mostly(st.integers(1, 30))}, optional={
    "map": mostly(st.sampled_from(["building", "building", "cave", "cave", "cavee", "nowhere.npz", "x.png"])),
    "size": sizes,
    "map_seed": mostly(st.integers(0, 9)), "robots": mostly(st.integers(1, 6)),
    "spawn": mostly(st.sampled_from(["together", "random", "apart"])),
    "algorithm": mostly(st.sampled_from(["frontier", "greed", "tnf", "nope"])), "seed": mostly(st.integers(0, 99)),
    "explored": mostly(st.floats(0.01, 1.0)), "transport": mostly(st.just("inprocess")),
    "params": mostly(st.dictionaries(st.sampled_from(["recheck_ticks", "bogus"]), odd, max_size=1)),
    "map_params": mostly(st.dictionaries(st.sampled_from(["door_width", "bogus"]), odd, max_size=1)),
    "lidar": mostly(st.fixed_dictionaries({"range_m": st.floats(1, 8)})),
    "radio": mostly(st.sampled_from(["los", "global", "wifi"])),
    "stop": mostly(st.fixed_dictionaries({"stall_ticks": st.integers(1, 100)}))}).flatmap(
    lambda kw: st.sampled_from([False] * 9 + [True]).map(lambda typo: {**kw, "robts": 2} if typo else kw))
"""swarm.run's keywords, each given or not: mostly valid values, an odd one in ten; an unknown one in ten cases."""


def small(spec: RunSpec) -> bool:
    """A run this file may afford: a small map (50 tiles, the default, or less), few robots, few ticks."""
    size = spec.map.size if isinstance(spec.map.size, list) else [spec.map.size, spec.map.size]
    return spec.stop.max_ticks <= 30 and spec.robots.count <= 6 and max(size) <= 50


@settings(FUZZ, max_examples=300)
@given(spec=spec_args, overrides=keywords)
def test_spec_builders_give_a_spec_or_one_line(spec, overrides):
    with timed():
        try:
            resolved = swarm.resolve_spec(spec, **overrides)
        except InvalidInput as exc:
            check_refusal(exc)
        else:
            event("accepted")
            assert isinstance(resolved, RunSpec) and RunSpec.from_mapping(resolved.canonical()).key == resolved.key
        try:
            RunSpec.from_mapping(spec)
        except InvalidInput as exc:
            check_refusal(exc)


def _noop(view: object) -> None:
    pass


observers = st.sampled_from([(), (), (), [_noop], [_noop], [_noop], (_noop,), (_noop,), 5, "print", [5], print, None,
                             [None], {"a": print}])


@settings(FUZZ, max_examples=200)
@given(spec=spec_args, overrides=keywords, watch=observers)
def test_run_gives_a_result_or_one_line(spec, overrides, watch):
    with timed():
        try:
            resolved = swarm.resolve_spec(spec, **overrides)
        except InvalidInput:
            resolved = None
        if resolved is not None and not small(resolved):
            event("too large to run here")
            return
        try:
            result = swarm.run(spec, observers=watch, **overrides)
        except InvalidInput as exc:
            check_refusal(exc)
            return
        event("ran")
        assert isinstance(result, RunResult) and result.summary["ticks"] <= 30
        assert len(repr(result)) < 400


# ------------------------------------------------------------------------------------ campaigns ----
CAMPAIGN = """
[campaign]
name = "fuzz"
seed = 1
replicates = 1

[grid]
map = ["building"]
size = [20]
robots = [1]
spawn = ["together"]
algorithm = ["frontier"]
radio = ["global"]

[stop]
max_ticks = 10
"""


@pytest.fixture(scope="module")
def results(tmp_path_factory) -> Path:
    """A results folder of the one-run campaign above."""
    folder = tmp_path_factory.mktemp("fuzz-campaign") / "out"
    swarm.campaign.run(CAMPAIGN, folder, inline=True)
    return folder


campaign_specs = st.one_of(st.just(CAMPAIGN), st.just(CAMPAIGN), odd, st.sampled_from([
    {"campaign": {"name": "m", "replicates": 1}, "grid": {"map": ["building"], "size": [20], "robots": [1],
                                                          "spawn": ["together"], "algorithm": ["frontier"],
                                                          "radio": [5]}},
    "[campaign]\nname = 3\n", "nowhere.toml", "quick?", {"campaign": object()}]))
campaign_options = st.fixed_dictionaries({}, optional={
    "workers": mostly(st.none(), 5), "dask": st.sampled_from([None, "nowhere", "tcp://127.0.0.1:1", "udp://x:1", 5]),
    "inline": st.sampled_from([True, True, "yes", 1, None]), "shard": mostly(st.sampled_from(["0/1", "0/2", "2/1"])),
    "retry_failed": mostly(st.booleans()), "max_runs": mostly(st.integers(1, 10)),
    "flush_runs": mostly(st.integers(1, 5)), "progress": st.sampled_from([False, None, 0])})


@settings(FUZZ, max_examples=100)
@given(spec=campaign_specs, out=st.sampled_from(["folder", "folder", "folder", None, 5, "", b"x",
                                                 Path("/proc/version"), "/", "."]),
       options=campaign_options)
def test_campaign_run_gives_a_result_or_one_line(spec, out, options, results):
    if options.get("inline") is None and options.get("workers") is None and options.get("dask") is None:
        options["inline"] = True  # no process pool: a pool's start-up is tested elsewhere and costs seconds
    folder = results if out == "folder" else out
    with timed():
        try:
            outcome = swarm.campaign.run(spec, folder, **options)
        except InvalidInput as exc:
            check_refusal(exc)
            return
        event("ran")
        assert outcome.total >= 0 and outcome.failed == 0


@settings(FUZZ, max_examples=150)
@given(which=st.sampled_from(["load", "load_timeseries"]),
       folder=st.sampled_from(["results", "parent", "file", None, 5, "", b"x", Path("/proc"), "/nowhere", [1]]),
       keys=st.sampled_from([None, [], ["nope"], "abc", 5, [None], {"a": 1}, np.array(["x"])]),
       labels=st.sampled_from([True, False, None, "yes", 0]))
def test_campaign_load_gives_a_table_or_one_line(which, folder, keys, labels, results):
    named = {"results": results, "parent": results.parent, "file": results / "campaign.toml"}
    where = named[folder] if isinstance(folder, str) and folder in named else folder
    args = {} if which == "load" else {"keys": keys, "labels": labels}
    with timed():
        try:
            table = getattr(swarm.campaign, which)(where, **args)
        except InvalidInput as exc:
            check_refusal(exc)
            return
        event(f"{which} read")
        assert len(table) >= 0
