"""``swarm campaign compact``: a results folder's parts rewritten as one, every run's latest rows unchanged,
safe when killed between its steps, refused while a real writer process holds the folder or when a part is
damaged."""

from __future__ import annotations

import os
import signal
import subprocess
import sys

import pyarrow.compute as pc
import pytest

from swarm.base.errors import InvalidInput
from swarm.campaign import make_executor, parse_campaign, run_campaign, status
from swarm.campaign.compact import compact
from swarm.campaign.parts import RUNS_SUFFIX, TS_SUFFIX
from swarm.campaign.report.load import load
from swarm.campaign.store import ResultsStore
from swarm.cli import main

from .test_campaign import TINY
from .test_damaged_parts import flip_in_data
from .test_writers import ROOT, lock_files, run_cmd, run_files, spec_file, start, wait_for


def folder_of_parts(tmp_path):
    """A finished tiny campaign (one part per run) plus a later part that retries its first run with other
    numbers, as a retried run leaves it: the later row must win, before and after compacting."""
    spec = parse_campaign(TINY)
    out = tmp_path / "out"
    run_campaign(spec, out, executor=make_executor(inline=True), progress=False, flush_runs=1)
    store = ResultsStore(out)
    first = store.run_files()[0]
    runs = store.read_part(first)
    retried = runs.set_column(runs.schema.get_field_index("ticks"), "ticks",
                              pc.add(runs.column("ticks"), 1000))
    ts = store.read_part(first.with_name(first.name.replace(RUNS_SUFFIX, TS_SUFFIX)))
    store.write_tables(retried.replace_schema_metadata(None), ts.slice(0, 3), None, writer=None)
    return spec, out, runs.column("key")[0].as_py()


def snapshot(folder):
    store = ResultsStore(folder)
    runs = store.runs_table().drop_columns(["part"]).sort_by("key")
    ts = store.timeseries_table().sort_by([("key", "ascending"), ("tick", "ascending")])
    robots = store.robots_table()
    robots = None if robots is None else robots.sort_by([("key", "ascending"), ("tick", "ascending"),
                                                         ("robot", "ascending")])
    return runs, ts, robots


def assert_same(a, b):
    for x, y in zip(a, b):
        assert (x is None) == (y is None)
        if x is not None:
            assert x.equals(y)


def test_compacting_keeps_every_runs_latest_rows_and_a_resume_runs_nothing(tmp_path):
    spec, out, retried_key = folder_of_parts(tmp_path)
    before = snapshot(out)
    parts_before = len(ResultsStore(out).run_files())
    assert parts_before > 2
    done = compact(out)
    assert (done.runs, done.parts_before) == (before[0].num_rows, parts_before)
    assert len(ResultsStore(out).run_files()) == 1 and len(list((out / "parts").iterdir())) <= 3
    after = snapshot(out)
    assert_same(before, after)
    row = after[0].filter(pc.equal(after[0].column("key"), retried_key))
    assert row.column("ticks")[0].as_py() >= 1000, "the retried (later) row won"
    assert len(after[1].filter(pc.equal(after[1].column("key"), retried_key))) == 3
    assert status(out)["done"] == before[0].num_rows and status(out)["pending"] == 0
    resumed = run_campaign(spec, out, executor=make_executor(inline=True), progress=False)
    assert resumed.ran == 0
    assert len(load(out).runs) == before[0].num_rows
    again = compact(out)
    assert again.part is None and again.kept == 1 and again.bytes_after == again.bytes_before


def retry_of(store, runs, key, extra):
    """A new part holding ``key``'s row of ``runs`` with ``extra`` ticks more (a retried run's later row)."""
    row = runs.filter(pc.equal(runs.column("key"), key))
    row = row.set_column(row.schema.get_field_index("ticks"), "ticks", pc.add(row.column("ticks"), extra))
    return store.write_tables(row, None, None, writer=None)


def test_a_second_compaction_leaves_the_first_ones_part_and_loses_no_later_row(tmp_path):
    _, out, _ = folder_of_parts(tmp_path)
    first = compact(out)
    store = ResultsStore(out)
    runs = store.read_part(out / "parts" / f"{first.part}{RUNS_SUFFIX}").replace_schema_metadata(None)
    keys = runs.column("key").to_pylist()
    stale = retry_of(store, runs, keys[2], 5)  # an older row than the compacted part's: renamed to sort first
    for path in (out / "parts").glob(f"{stale}*"):
        path.rename(path.with_name("0" * 20 + path.name[20:]))
    retry_of(store, runs, keys[0], 2000)
    retry_of(store, runs, keys[1], 3000)
    before = snapshot(out)
    second = compact(out)
    assert second.kept == 1 and second.parts_before == 3 and second.runs == 2
    assert {p.name for p in ResultsStore(out).run_files()} == {f"{first.part}{RUNS_SUFFIX}",
                                                               f"{second.part}{RUNS_SUFFIX}"}
    assert_same(before, snapshot(out))  # keys 0 and 1 from the new part, key 2 still from the first
    everything = compact(out, everything=True)
    assert everything.parts_before == 2 and len(ResultsStore(out).run_files()) == 1
    assert_same(before, snapshot(out))


def test_a_kill_between_commit_and_clean_up_loses_and_doubles_nothing(tmp_path, monkeypatch):
    _, out, _ = folder_of_parts(tmp_path)
    before = snapshot(out)
    real_unlink = type(out).unlink
    calls = []

    def dies_on_fifth_file(self, missing_ok=False):  # the new part is in; the second old part half gone
        if self.name.endswith(".tmp"):  # the commit's own clean-up of its temporary files
            return real_unlink(self, missing_ok=missing_ok)
        calls.append(self.name)
        if len(calls) == 5:
            raise KeyboardInterrupt("killed")
        return real_unlink(self, missing_ok=missing_ok)

    monkeypatch.setattr(type(out), "unlink", dies_on_fifth_file)
    with pytest.raises(KeyboardInterrupt):
        compact(out)
    monkeypatch.setattr(type(out), "unlink", real_unlink)
    assert calls[0].endswith(RUNS_SUFFIX), "an old part's runs file goes before its companions"
    assert_same(before, snapshot(out))  # every run once, from the new part where it is in two
    assert not ResultsStore(out).damaged()
    again = compact(out)  # the killed one's part stays; the rest of the old parts become one more
    assert again.kept == 1 and len(ResultsStore(out).run_files()) == 2
    assert_same(before, snapshot(out))


def test_a_damaged_part_is_refused_and_nothing_is_written(tmp_path):
    _, out, _ = folder_of_parts(tmp_path)
    flip_in_data(TS_SUFFIX)(out)
    names = sorted(p.name for p in (out / "parts").iterdir())
    with pytest.raises(InvalidInput, match="damaged parts to quarantine"):
        compact(out)
    assert sorted(p.name for p in (out / "parts").iterdir()) == names


@pytest.mark.timeout(300)
def test_a_folder_a_live_writer_process_holds_is_refused(tmp_path):
    spec = spec_file(tmp_path, replicates=6)
    out = tmp_path / "out"
    writer = start(run_cmd(spec, out, "--part-size", "1"))
    try:
        wait_for(lambda: lock_files(out) and len(run_files(out)) >= 2, "two parts", proc=writer)
        os.killpg(writer.pid, signal.SIGSTOP)  # alive, holding its lock
        names = sorted(p.name for p in (out / "parts").iterdir())
        refused = subprocess.run([sys.executable, "-m", "swarm", "campaign", "compact", str(out)],
                                 capture_output=True, text=True, timeout=120, cwd=ROOT)
        assert refused.returncode == 2 and "Traceback" not in refused.stderr
        line = refused.stderr.strip().splitlines()[-1]
        assert line.startswith("swarm: error: DIR:") and f"pid {writer.pid}" in line, line
        assert sorted(p.name for p in (out / "parts").iterdir()) == names
    finally:
        os.killpg(writer.pid, signal.SIGCONT)
    _, err = writer.communicate(timeout=240)
    assert writer.returncode == 0, err
    done = subprocess.run([sys.executable, "-m", "swarm", "campaign", "compact", str(out)],
                          capture_output=True, text=True, timeout=120, cwd=ROOT)
    assert done.returncode == 0, done.stderr
    assert len(run_files(out)) == 1 and status(out)["pending"] == 0


def test_the_cli_refuses_a_folder_that_is_not_a_campaigns_in_one_line(tmp_path, capsys):
    (tmp_path / "x.txt").write_text("not results")
    assert main(["campaign", "compact", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("swarm: error: DIR:") and "campaign.toml" in err[0]

