"""The results schema is the one the code writes: a run's summary and time series, and a campaign's runs
table, column for column and type for type."""

from __future__ import annotations

import typing

import pyarrow as pa

from swarm.campaign import make_executor, parse_campaign, run_campaign
from swarm.campaign.runner import runs_row
from swarm.campaign.store import ResultsStore
from swarm.results.schema import (OPTIONAL_TIMESERIES, RUNS, THRESHOLD_COLUMNS, TIMESERIES, MessageCounts, Summary,
                                  dropped, summary_columns)
from swarm.sim.loop import Simulation
from swarm.util.source import source_commit, version_label

from tests.swarm.campaign.test_campaign import TINY

SPEC = {"map": {"kind": "building", "size": 20}, "robots": {"count": 2}, "seed": 3, "stop": {"max_ticks": 60},
        "comm": {"loss": 0.5}}


def test_a_runs_summary_and_time_series_have_the_schemas_fields():
    r = Simulation(SPEC).run()
    assert set(r.summary) == set(typing.get_type_hints(Summary))
    assert set(r.summary["messages"]) == MessageCounts.__required_keys__
    relaying = Simulation({**SPEC, "comm": {"relay": "flood"}}).run()  # the relaying counts come with relaying
    assert set(relaying.summary["messages"]) == set(typing.get_type_hints(MessageCounts))
    assert list(r.timeseries) == [c for c in TIMESERIES if c not in OPTIONAL_TIMESERIES]
    located = Simulation({**SPEC, "localization": {"model": "bounded"}}).run()   # the optional columns come with it
    assert list(located.timeseries) == list(TIMESERIES)
    assert r.timeseries["msgs_dropped"][-1] == dropped(r.summary["messages"]) > 0, "one definition of dropped"


def test_runs_rows_fill_exactly_the_runs_columns_with_their_types(tmp_path):
    spec = parse_campaign(TINY)
    run_campaign(spec, tmp_path, executor=make_executor(inline=True), progress=False, shard=(0, 12))
    row = runs_row(spec, spec.runs()[0], {"key": "k", "status": "failed", "error": "x", "summary": None,
                                          "wall_time_s": 0.1, "worker_pid": 1, "worker_rss_mb": 1.0})
    assert set(row) == set(RUNS)
    assert set(summary_columns(None)) == set(summary_columns(Simulation(SPEC).run().summary))
    (part,) = ResultsStore(tmp_path).run_files()
    table = pa.parquet.read_table(part)
    assert {f.name: f.type for f in table.schema} == RUNS
    for col in THRESHOLD_COLUMNS.values():  # typed even where no run of the part reached the threshold
        assert table.schema.field(col).type == pa.int64()


def test_results_record_the_algorithms_distribution(tmp_path):
    """A run says which installed distribution and version computed it; a module loaded by path from a
    folder outside any distribution says None."""
    r = Simulation(SPEC).run()
    assert r.provenance["algorithm"] == {"name": "frontier", "distribution": "swarm-sim",
                                         "version": r.provenance["swarm"]}
    local = Simulation({**SPEC, "algorithm": {"name": "tests.swarm.agents:Talker"}}).run()
    assert local.provenance["algorithm"]["distribution"] is None
    spec = parse_campaign(TINY)
    run_campaign(spec, tmp_path, executor=make_executor(inline=True), progress=False, shard=(0, 24))
    table = ResultsStore(tmp_path).runs_table()
    assert table.column("algorithm_dist").to_pylist() == ["swarm-sim"]
    # and which source: the package version, with the commit when it runs from a git checkout
    assert r.provenance["source"] == source_commit()
    assert table.column("swarm_version").to_pylist() == [version_label()]
