"""Several processes on one results folder (issue 31): shards side by side, a second writer of the same runs
refused, a writer killed by SIGKILL recognised as dead, unwritable folders and full disks as one-line
errors. Every writer here is a real ``python -m swarm campaign run`` process."""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pyarrow.parquet as pq
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from swarm.campaign import parse_campaign, status
from swarm.campaign.store import RUNS_SUFFIX, TS_SUFFIX, ResultsStore
from swarm.campaign.writers import WRITERS, overlaps

from ... import full_disk
from .test_campaign import TINY

ROOT = Path(__file__).resolve().parents[3]


def spec_file(tmp_path: Path, replicates: int = 4) -> Path:
    path = tmp_path / "tiny.toml"
    path.write_text(TINY.replace("replicates = 2", f"replicates = {replicates}"))
    return path


def run_cmd(spec: Path, out: Path, *extra: str) -> list[str]:
    return [sys.executable, "-m", "swarm", "campaign", "run", str(spec), "-o", str(out), "--inline", "--quiet",
            *extra]


def start(cmd: list[str]) -> subprocess.Popen:
    return subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True,
                            cwd=ROOT)


def wait_for(predicate, what: str, timeout: float = 120.0, proc: subprocess.Popen | None = None) -> None:
    deadline = time.monotonic() + timeout
    while not predicate():
        if proc is not None and proc.poll() is not None:
            raise AssertionError(f"the writer ended before {what}: {proc.stderr.read()}")
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out waiting for {what}")
        time.sleep(0.02)


def lock_files(out: Path) -> list[Path]:
    folder = out / WRITERS
    return sorted(p for p in folder.glob("*.lock") if not p.name.startswith(".")) if folder.exists() else []


def run_files(out: Path) -> list[Path]:
    return sorted((out / "parts").glob(f"*{RUNS_SUFFIX}")) if (out / "parts").exists() else []


def raw_keys(out: Path) -> list[str]:
    """Every runs row of every part (not the latest-per-key view): a run written twice shows twice."""
    return [k for f in run_files(out) for k in pq.read_table(f, columns=["key"]).column("key").to_pylist()]


def assert_complete(out: Path, spec: Path) -> None:
    keys = raw_keys(out)
    expected = {k for _, k in parse_campaign(spec.read_text()).iter_keys()}
    assert len(keys) == len(set(keys)) == len(expected), "every run exactly once"
    assert set(keys) == expected
    ts = ResultsStore(out).timeseries_table()
    assert set(ts.column("key").to_pylist()) == expected, "no time-series file lost"
    assert not [p.name for p in (out / "parts").iterdir() if p.name.startswith(".")], "no temporary file left"
    assert not lock_files(out), "every writer removed its lock file"


def writer_id(lock: Path) -> str:
    return lock.name[: -len(".lock")]


def plant(out: Path, writer: str | None) -> list[Path]:
    """What a writer leaves when it dies mid-commit: a temporary file, and a time-series file whose runs
    file was never renamed into place (named like that writer's, or like an older version's)."""
    stamp = f"{time.time_ns():020d}"
    if writer is None:
        names = [f".{stamp}-abcdef12{RUNS_SUFFIX}.0badf00d.tmp", f"{stamp}-abcdef12{TS_SUFFIX}"]
    else:
        names = [f".{stamp}-999999.{writer}{TS_SUFFIX}.tmp", f"{stamp}-999998.{writer}{TS_SUFFIX}"]
    paths = [out / "parts" / n for n in names]
    for p in paths:
        p.write_bytes(b"in flight")
    return paths


# ------------------------------------------------------------------------------------------ overlap ----
@settings(max_examples=300, deadline=None)
@given(st.integers(1, 12), st.integers(1, 12), st.data(), st.integers(0, 200))
def test_shard_overlap_is_exactly_a_shared_run_index(n, m, data, total):
    i, j = data.draw(st.integers(0, n - 1)), data.draw(st.integers(0, m - 1))
    shared = any(x % n == i and x % m == j for x in range(total))
    assert overlaps((i, n), (j, m), total) is shared
    assert overlaps((i, n), (j, m)) is ((i - j) % __import__("math").gcd(n, m) == 0)
    assert overlaps(None, (j, m), total) is (total > 0) and overlaps((i, n), None) is True


# ----------------------------------------------------------------------------------- concurrency ----
@pytest.mark.timeout(300)
def test_two_shards_into_one_folder_at_once_write_every_run_exactly_once(tmp_path):
    spec = spec_file(tmp_path)
    out = tmp_path / "out"
    procs = [start(run_cmd(spec, out, "--shard", f"{i}/2", "--part-size", "3")) for i in (0, 1)]
    for p in procs:
        _, err = p.communicate(timeout=240)
        assert p.returncode == 0, err
    assert_complete(out, spec)
    assert status(out)["done"] == 48


@pytest.mark.timeout(300)
def test_a_start_up_keeps_a_live_writers_files_and_removes_a_dead_ones(tmp_path):
    spec = spec_file(tmp_path)
    out = tmp_path / "out"
    first = start(run_cmd(spec, out, "--shard", "0/2", "--part-size", "1"))
    try:
        wait_for(lambda: lock_files(out) and run_files(out), "the first part", proc=first)
        os.killpg(first.pid, signal.SIGSTOP)  # alive (it holds its lock) but not moving
        (lock,) = lock_files(out)
        info = json.loads(lock.read_text())
        assert info["pid"] == first.pid and info["shard"] == [0, 2]
        theirs = plant(out, writer_id(lock))
        old_format = plant(out, None)
        second = subprocess.run(run_cmd(spec, out, "--shard", "1/2", "--part-size", "3"), capture_output=True,
                                text=True, timeout=240, cwd=ROOT)
        assert second.returncode == 0, second.stderr
        assert all(p.exists() for p in theirs), "a live writer's in-flight files were deleted"
        assert all(p.exists() for p in old_format), "old-format files are removed only when no writer is alive"
        assert [w.pid for w in status(out)["writers"]] == [first.pid]
    finally:
        os.killpg(first.pid, signal.SIGCONT)
    _, err = first.communicate(timeout=240)
    assert first.returncode == 0, err
    # the first writer has ended: a new start-up (nothing left to run) removes what it and the old version left
    again = subprocess.run(run_cmd(spec, out), capture_output=True, text=True, timeout=240, cwd=ROOT)
    assert again.returncode == 0, again.stderr
    assert not any(p.exists() for p in theirs + old_format)
    assert_complete(out, spec)


@pytest.mark.timeout(300)
def test_the_same_campaign_twice_at_once_never_runs_a_run_twice(tmp_path):
    spec = spec_file(tmp_path, replicates=6)
    out = tmp_path / "out"
    procs = [start(run_cmd(spec, out, "--part-size", "3")) for _ in range(2)]
    results = [(p.pid, *p.communicate(timeout=240), p.returncode) for p in procs]
    codes = sorted(r[3] for r in results)
    assert codes in ([0, 2], [0, 0]), results  # [0, 0] only if one ended before the other started
    for pid, _, err, code in results:
        if code == 2:
            other = next(r[0] for r in results if r[0] != pid)
            last = err.splitlines()[-1]
            assert last.startswith("swarm: error: -o:") and "Traceback" not in err, err
            assert f"pid {other} on " in last and "(all runs, no --shard)" in last
    assert_complete(out, spec)


@pytest.mark.timeout(300)
def test_a_second_writer_of_overlapping_runs_is_refused_while_the_first_runs(tmp_path):
    spec = spec_file(tmp_path)
    out = tmp_path / "out"
    first = start(run_cmd(spec, out, "--shard", "1/2", "--part-size", "1"))
    try:
        wait_for(lambda: run_files(out), "the first part", proc=first)
        os.killpg(first.pid, signal.SIGSTOP)
        files_before = sorted(p.name for p in (out / "parts").iterdir())
        for shard in ("1/4", "3/6", None):  # 1/4 and 3/6 share runs with 1/2; no --shard shares every run
            extra = ["--shard", shard] if shard else []
            t0 = time.monotonic()
            refused = subprocess.run(run_cmd(spec, out, *extra), capture_output=True, text=True, timeout=120, cwd=ROOT)
            assert refused.returncode == 2, refused.stderr
            assert time.monotonic() - t0 < 60
            assert "Traceback" not in refused.stderr
            line = refused.stderr.splitlines()[-1]
            assert line.startswith("swarm: error: -o:")
            assert f"pid {first.pid} on " in line and "(shard 1/2)" in line, line
        assert sorted(p.name for p in (out / "parts").iterdir()) == files_before, "a refused writer touched parts/"
        apart = subprocess.run(run_cmd(spec, out, "--shard", "0/4"), capture_output=True, text=True, timeout=240,
                               cwd=ROOT)
        assert apart.returncode == 0, apart.stderr  # 0/4 shares no run with 1/2
    finally:
        os.killpg(first.pid, signal.SIGCONT)
    _, err = first.communicate(timeout=240)
    assert first.returncode == 0, err
    rows = raw_keys(out)
    assert len(rows) == len(set(rows)) == 24 + 12


@pytest.mark.timeout(300)
def test_a_writer_killed_by_sigkill_is_recognised_dead_cleaned_up_and_resumed(tmp_path):
    spec = spec_file(tmp_path)
    out = tmp_path / "out"
    victim = start(run_cmd(spec, out, "--part-size", "2"))
    wait_for(lambda: len(run_files(out)) >= 2, "two parts", proc=victim)
    os.killpg(victim.pid, signal.SIGKILL)
    victim.wait(30)
    (lock,) = lock_files(out)  # the kernel dropped its flock; the file stays
    assert json.loads(lock.read_text())["pid"] == victim.pid
    assert status(out)["writers"] == [], "status sees the writer is dead"
    left = plant(out, writer_id(lock)) + plant(out, None)
    resumed = subprocess.run(run_cmd(spec, out), capture_output=True, text=True, timeout=240, cwd=ROOT)
    assert resumed.returncode == 0, resumed.stderr
    assert not lock.exists() and not any(p.exists() for p in left)
    assert_complete(out, spec)


# ------------------------------------------------------------------------------- unwritable / full ----
def _without_root_powers() -> list[str]:
    """A command prefix under which file permissions apply (root ignores them unless its powers go)."""
    if os.geteuid() != 0:
        return []
    if shutil.which("setpriv") is None:
        pytest.skip("running as root without setpriv: cannot make a folder read-only for the test")
    return ["setpriv", "--bounding-set", "-dac_override,-dac_read_search,-fowner"]


@pytest.mark.parametrize("read_only", ["folder", "parts"])
def test_a_read_only_results_folder_fails_before_any_run_with_one_line(tmp_path, read_only):
    spec = spec_file(tmp_path, replicates=1)
    out = tmp_path / "out"
    if read_only == "parts":  # an existing results folder whose parts/ became read-only: the probe finds it
        (out / "parts").mkdir(parents=True)
        (out / WRITERS).mkdir()
        shutil.copy(spec, out / "campaign.toml")
        ro = out / "parts"
    else:
        out.mkdir()
        ro = out
    ro.chmod(0o555)
    try:
        cmd = [*_without_root_powers(), *run_cmd(spec, out)]
        cmd.remove("--quiet")
        t0 = time.monotonic()
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=120, cwd=ROOT)
    finally:
        ro.chmod(0o755)
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.startswith("swarm: error: -o:") and proc.stderr.count("\n") == 1, proc.stderr
    assert "writable" in proc.stderr and "Permission denied" in proc.stderr
    assert "runs done" not in proc.stdout + proc.stderr and time.monotonic() - t0 < 60, "no run was computed"
    assert not run_files(out)


@pytest.mark.skipif(not full_disk.SUPPORTED, reason="needs /proc")
@pytest.mark.parametrize("fail_at, what", [(4, "time-series file of part 2"), (5, "robots file of part 2"),
                                           (6, "runs file of part 2")])
def test_a_full_disk_stops_with_one_line_keeping_committed_parts_and_no_temp_file(tmp_path, fail_at, what):
    spec = spec_file(tmp_path, replicates=1)
    out = tmp_path / "out"
    args = ["campaign", "run", str(spec), "-o", str(out), "--inline", "--part-size", "3"]
    proc = full_disk.run_on_full_disk(args, ".parquet", fail_at)
    assert proc.returncode == 2, proc.stderr
    err = proc.stderr.splitlines()
    assert "Traceback" not in proc.stderr
    assert err[-1].startswith("swarm: error: -o:") and "No space left on device" in err[-1], err
    names = sorted(p.name for p in (out / "parts").iterdir())
    assert sorted(n.split(".", 2)[2] for n in names) == ["robots.parquet", "runs.parquet", "timeseries.parquet"], \
        names
    assert status(out)["done"] == 3, "part 1 is intact"
    assert not lock_files(out)
    resumed = subprocess.run(run_cmd(spec, out), capture_output=True, text=True, timeout=240, cwd=ROOT)
    assert resumed.returncode == 0, resumed.stderr
    assert_complete(out, spec)


def test_a_folder_written_by_an_earlier_version_resumes(tmp_path):
    """Parts named without a writer id (``<time>-<random>``, as before writers registered) count as done;
    their leftovers are removed when no writer is alive."""
    from swarm.campaign import make_executor, run_campaign
    from swarm.campaign.runner import runs_row, timeseries_rows
    from swarm.campaign.executors import execute

    spec = parse_campaign(TINY)
    store = ResultsStore(tmp_path)
    store.prepare(spec.source)
    first = [spec.run_at(i) for i in range(5)]
    results = [execute((r.key, r.canonical())) for r in first]
    part = store.write_part([runs_row(spec, r, x) for r, x in zip(first, results)],
                            [row for r, x in zip(first, results) for row in timeseries_rows(r.key, x["timeseries"])])
    assert "." not in part, "named as earlier versions named parts"
    left = plant(tmp_path, None)
    out = run_campaign(spec, tmp_path, executor=make_executor(inline=True), progress=False)
    assert (out.skipped, out.ran) == (5, 19)
    assert not any(p.exists() for p in left)
    keys = raw_keys(tmp_path)
    assert len(keys) == len(set(keys)) == 24
