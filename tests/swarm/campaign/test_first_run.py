"""Issue 35's first run: numba compiles once before the workers start, progress on a terminal only,
reports rebuilt only when stale, the cost estimator samples the campaign's own first replicates, SLURM
job arrays shard whatever their numbering."""

from __future__ import annotations

import json
import os
import pty
import select
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from maps import InvalidInput
from swarm.campaign import deterministic_rows, parse_campaign, run_campaign
from swarm.campaign import warmup
from swarm.campaign.estimate import estimate, report_lines, strata
from swarm.campaign.executors import InlineExecutor, PoolExecutor
from swarm.campaign.runner import parse_shard
from swarm.campaign.store import ResultsStore
from swarm.cli import main

ROOT = Path(__file__).resolve().parents[3]

SMALL = """
[campaign]
name = "small"
seed = 11
replicates = 3

[grid]
map = ["building", "cave"]
size = [20]
robots = [1, 2]
spawn = ["together"]
algorithm = ["frontier", "greed"]
radio = ["global", "los"]

[stop]
explored = 0.6
max_ticks = 120
"""


@pytest.fixture(autouse=True)
def own_cache_folder(tmp_path, monkeypatch):
    """Warm-up stamps go to a folder of this test (no warm-up is skipped for another test's stamp)."""
    monkeypatch.setenv("SWARM_CACHE_DIR", str(tmp_path / "cache"))


def _env() -> dict[str, str]:
    return {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}


def run_with_terminal(argv: list[str], cwd: Path, stderr_tty: bool = True, timeout: float = 300) -> tuple[int, str, str]:
    """Run ``python -m swarm argv`` with stdout piped and stderr on a pseudo-terminal (or piped):
    (exit status, stdout, stderr)."""
    if not stderr_tty:
        p = subprocess.run([sys.executable, "-m", "swarm", *argv], cwd=cwd, env=_env(), capture_output=True,
                           text=True, timeout=timeout)
        return p.returncode, p.stdout, p.stderr
    import fcntl
    import struct
    import termios

    master, slave = pty.openpty()
    fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 40, 120, 0, 0))
    p = subprocess.Popen([sys.executable, "-m", "swarm", *argv], cwd=cwd, env=_env(), stdout=subprocess.PIPE,
                         stderr=slave, text=True)
    os.close(slave)
    err = b""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        ready, _, _ = select.select([master], [], [], 0.2)
        if ready:
            try:
                chunk = os.read(master, 65536)
            except OSError:
                break
            if not chunk:
                break
            err += chunk
        elif p.poll() is not None:
            break
    out = p.stdout.read()
    p.wait(timeout=30)
    os.close(master)
    return p.returncode, out, err.decode(errors="replace")


# --------------------------------------------------------------------------------- progress ----
def test_swarm_run_progress_goes_to_a_terminal_stderr_only(tmp_path):
    argv = ["run", "--size", "30", "--robots", "2", "--max-ticks", "400", "--json", "r.json"]
    status, out, err = run_with_terminal(argv, tmp_path)
    assert status == 0, err
    assert "run " in err and "tick " in err and "explored" in err, "a live progress line on the terminal"
    summary, wrote = out.splitlines()
    assert summary.startswith("frontier x2 on building 30") and wrote == "wrote r.json", "stdout: results only"
    result = json.loads((tmp_path / "r.json").read_text())
    assert result["summary"]["ticks"] <= 400 and "explored %" not in json.dumps(result)
    status, out_piped, err_piped = run_with_terminal(argv, tmp_path, stderr_tty=False)
    assert status == 0 and err_piped == "", "nothing on stderr when it is not a terminal"
    without_speed = lambda line: line.rsplit(", ", 1)[0]  # noqa: E731  (the last field is ticks per second)
    assert without_speed(out_piped.splitlines()[0]) == without_speed(summary)


def test_campaign_progress_bar_on_a_terminal_plain_lines_otherwise(tmp_path):
    (tmp_path / "small.toml").write_text(SMALL.replace("replicates = 3", "replicates = 1"))
    status, out, err = run_with_terminal(["campaign", "run", "small.toml", "-o", "a", "--inline"], tmp_path)
    assert status == 0, err
    assert "runs:" in err and "|" in err and "ETA" in err and "\r" in err, "a redrawn bar on the terminal"
    assert "|" not in out and "ETA" not in out and "\r" not in out, "stdout has no bar"
    assert out.splitlines()[0] == "campaign small: 16 runs -> a" and "16 ran (0 failed)" in out
    status, out2, err2 = run_with_terminal(["campaign", "run", "small.toml", "-o", "b", "--inline"], tmp_path,
                                           stderr_tty=False)
    assert status == 0
    assert "\r" not in err2 and err2.strip().splitlines()[-1].startswith("runs: 16/16 runs done"), err2


def test_the_eta_ignores_the_time_before_the_first_result(monkeypatch):
    """A pool's start-up (or a compile) before the first result does not set the pace of the rest."""
    from swarm.util import progress

    now = [0.0]
    monkeypatch.setattr(progress.time, "monotonic", lambda: now[0])
    bar = progress.Bar(100, "runs", unit="run", stream=open(os.devnull, "w"))
    now[0] = 60.0  # a minute before the first run comes back
    bar.update(1)
    for _ in range(9):
        now[0] += 2.0
        bar.update(1)
    assert bar.rate.per_second == pytest.approx(0.5)
    assert bar.eta_s() == pytest.approx(180.0)


# ----------------------------------------------------------------------------------- warm-up ----
JIT_PLUGIN = '''
import numpy as np
from numba import njit
from swarm.api import Action


@njit(cache=True)
def unknown_cells(known):
    return int((known == 0).sum())


class JitExplorer:
    """Drives ahead; asks a kernel of its own (cached, new to this machine) every tick."""

    name = "jit-explorer"

    def reset(self, robot, params, rng):
        pass

    def act(self, obs):
        unknown_cells(np.asarray(obs.known))
        return Action(velocity=(0.4, 0.2))
'''


def test_workers_find_the_kernels_compiled_before_they_start(tmp_path, monkeypatch):
    """A kernel no process has compiled yet (a plugin's) is compiled by the warm-up run here, once; the
    pool's workers then load it and compile nothing."""
    plugin = tmp_path / "plugin"
    plugin.mkdir()
    (plugin / "jitplug.py").write_text(JIT_PLUGIN)
    monkeypatch.syspath_prepend(str(plugin))
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join([str(plugin), str(ROOT), os.environ.get("PYTHONPATH", "")]))
    spec = parse_campaign(SMALL.replace('algorithm = ["frontier", "greed"]', 'algorithm = ["jitplug:JitExplorer"]')
                          .replace("replicates = 3", "replicates = 2"))
    results = []
    outcome = run_campaign(spec, tmp_path / "out", executor=PoolExecutor(2), progress=False,
                           on_result=results.append)
    here = [r for r in results if r["worker_pid"] == os.getpid()]
    pool = [r for r in results if r["worker_pid"] != os.getpid()]
    assert outcome.warmup_runs == len(here) >= 1 and results[:len(here)] == here, "warm-up runs come first"
    assert sum(r["jit_compiled"] for r in here) >= 1, "the plugin's kernel compiled here"
    assert pool and all(r["jit_compiled"] == 0 for r in pool), [r["jit_compiled"] for r in pool]
    assert {r["status"] for r in results} == {"ok"} and len(results) == spec.run_count()


def test_warm_up_covers_every_feature_once_and_a_valid_stamp_skips_it(tmp_path):
    spec = parse_campaign(SMALL)
    stamp = tmp_path / "stamp.json"
    plan = warmup.plan(spec, range(spec.run_count()), stamp)
    chosen = [warmup.features(spec.run_at(i).canonical()) for i in plan.indices]
    assert frozenset().union(*chosen) == plan.needed, "every algorithm, map, radio, ... met"
    assert {f for f in plan.needed if f.startswith("algorithm=")} == {"algorithm=frontier", "algorithm=greed"}
    assert len(plan.indices) <= 3 and all(spec.run_at(i).replicate == 0 for i in plan.indices)
    assert all(spec.run_at(i).cell["size"] == "20" for i in plan.indices)
    from swarm.sim.loop import Simulation

    Simulation({"map": {"size": 20}, "stop": {"max_ticks": 5}}).run()  # kernels of this process in the cache
    assert warmup.record(stamp, plan.needed)
    assert warmup.plan(spec, range(spec.run_count()), stamp).indices == [], "a valid stamp: no warm-up"
    recorded = json.loads(stamp.read_text())["files"]
    assert recorded, "the kernels' cache files are recorded"
    index = Path(recorded[0][0])
    os.utime(index, ns=(index.stat().st_atime_ns, index.stat().st_mtime_ns + 1_000_000))
    assert warmup.plan(spec, range(spec.run_count()), stamp).indices == plan.indices, "a changed cache: warm up"
    more = parse_campaign(SMALL.replace('"greed"]', '"greed", "tnf"]'))
    assert warmup.record(stamp, plan.needed)
    extra = warmup.plan(more, range(more.run_count()), stamp)
    assert len(extra.indices) == 1 and more.run_at(extra.indices[0]).cell["algorithm"] == "tnf"


def test_warm_up_runs_give_the_rows_a_pool_gives(tmp_path):
    spec = parse_campaign(SMALL.replace("replicates = 3", "replicates = 1"))
    run_campaign(spec, tmp_path / "warm", executor=PoolExecutor(2), progress=False, warmup=True)
    run_campaign(spec, tmp_path / "cold", executor=InlineExecutor(), progress=False, warmup=False)
    assert deterministic_rows(tmp_path / "warm") == deterministic_rows(tmp_path / "cold")
    table = ResultsStore(tmp_path / "warm").runs_table(columns=("key", "cpu_time_s", "jit_time_s", "wall_time_s"))
    for col in ("cpu_time_s", "jit_time_s"):
        assert all(v is not None and v >= 0 for v in table.column(col).to_pylist())
    assert all(j <= w for j, w in zip(table.column("jit_time_s").to_pylist(), table.column("wall_time_s").to_pylist()))


# ------------------------------------------------------------------------------------ report ----
def test_a_report_is_rebuilt_only_when_it_is_stale(tmp_path, capsys):
    spec = parse_campaign(SMALL.replace("replicates = 3", "replicates = 1"))
    folder = tmp_path / "res"
    run_campaign(spec, folder, executor=InlineExecutor(), progress=False, shard=(0, 2))
    report = ["campaign", "report", str(folder), "--no-cell-figures", "--quiet"]
    assert main(report) == 0
    assert "up to date" not in capsys.readouterr().out
    readme = folder / "report" / "README.md"
    stamp = readme.stat().st_mtime_ns
    assert main(report) == 0
    assert "(up to date; --force rebuilds it)" in capsys.readouterr().out
    assert readme.stat().st_mtime_ns == stamp, "not rewritten"
    assert main([*report, "--target", "0.5"]) == 0, "another option: another report"
    assert "up to date" not in capsys.readouterr().out
    assert main([*report, "--target", "0.5"]) == 0 and "up to date" in capsys.readouterr().out
    (folder / "report" / "tables" / "summary.csv").unlink()
    assert main([*report, "--target", "0.5"]) == 0 and "up to date" not in capsys.readouterr().out
    assert (folder / "report" / "tables" / "summary.csv").exists(), "a deleted file is rebuilt"
    outcome = run_campaign(spec, folder, executor=InlineExecutor(), progress=False, shard=(1, 2))  # a new part
    assert outcome.ran == 8
    assert main([*report, "--target", "0.5"]) == 0 and "up to date" not in capsys.readouterr().out
    assert "16 runs" in readme.read_text() or "16" in readme.read_text()
    assert main([*report, "--target", "0.5", "--force"]) == 0 and "up to date" not in capsys.readouterr().out


# its one-tick communication figures once warned of an empty x range
@pytest.mark.filterwarnings("error::UserWarning")
def test_a_resumed_campaign_with_nothing_new_keeps_its_report(tmp_path, capsys):
    spec_file = tmp_path / "small.toml"
    spec_file.write_text(SMALL.replace("replicates = 3", "replicates = 1").replace('["building", "cave"]', '["cave"]')
                         .replace("[1, 2]", "[2]").replace('["global", "los"]', '["global"]'))
    argv = ["campaign", "run", str(spec_file), "-o", str(tmp_path / "r"), "--inline", "--report", "--quiet"]
    assert main(argv) == 0
    first = capsys.readouterr().out
    assert "report:" in first and "up to date" not in first
    assert main(argv) == 0
    assert "(up to date: no new runs)" in capsys.readouterr().out


def test_report_progress_is_told_every_stage_and_file(tmp_path):
    from swarm.campaign.report.build import ReportProgress, build_report

    spec = parse_campaign(SMALL.replace("replicates = 3", "replicates = 1"))
    run_campaign(spec, tmp_path / "res", executor=InlineExecutor(), progress=False)

    class Seen(ReportProgress):
        def __init__(self):
            self.stages, self.files = [], []

        def stage(self, name):
            self.stages.append(name)

        def wrote(self, relative):
            self.files.append(relative)

    seen = Seen()
    build_report(tmp_path / "res", tmp_path / "rep", cell_figures=False, progress=seen)
    assert seen.stages[:2] == ["loading results", "reading time series"] and "figures" in seen.stages
    listed = [n for n in (tmp_path / "rep" / "files.txt").read_text().splitlines() if n and not n.startswith("#")]
    assert sorted(set(seen.files)) == sorted(listed)


# ---------------------------------------------------------------------------------- estimate ----
def test_the_estimate_samples_the_campaigns_first_replicates_and_they_are_kept(tmp_path, capsys):
    spec = parse_campaign(SMALL.replace("replicates = 3", "replicates = 2").replace("max_ticks = 120", "max_ticks = 60"))
    groups = strata(spec, ("map", "size", "robots", "algorithm"), 2)
    assert len(groups) == 8 and all(len(s.sample) == 2 for s in groups)
    keys = dict(spec.iter_keys())
    for s in groups:
        runs = [spec.run_at(i) for i in s.sample]
        assert [r.replicate for r in runs] == [0, 1], "the campaign's first replicates: two maps"
        assert len({r.cell["radio"] for r in runs}) == 2, "of two different cells of the stratum"
        assert all(r.key == keys[r.index] for r in runs), "the campaign's own runs"
    radios = [spec.run_at(s.sample[0]).cell["radio"] for s in groups]
    assert set(radios) == {"global", "los"}, "a seeded order of the cells, not always the first"
    est = estimate(spec, per_cell=2, workers=2, output=tmp_path / "out", progress=False,
                   by=("map", "size", "robots", "algorithm"))
    sample = sorted(i for s in groups for i in s.sample)
    assert sorted(r.index for r in est.runs) == sample
    stored = ResultsStore(tmp_path / "out").done_keys()
    assert set(stored) == {keys[i] for i in sample}
    assert est.total_runs == spec.run_count() == 32
    assert float(est.weights.sum()) == pytest.approx(32), "each sample run stands for its stratum's share"
    assert est.low_s <= est.predicted_s <= est.high_s
    assert est.predicted_s == pytest.approx(est.startup_s + (est.run_seconds + est.gap_seconds) / 2 + est.tail_s)
    shares = est.by_dimension()
    assert set(shares) == set(spec.grid) and all(abs(sum(v for _, v in s) - 1) < 1e-9 for s in shares.values())
    lines = report_lines(est)
    assert lines[1].startswith("predicted wall time on 2 workers:") and "95 % CI" in lines[1]
    outcome = run_campaign(spec, tmp_path / "out", executor=InlineExecutor(), progress=False)
    assert (outcome.skipped, outcome.ran) == (16, 16), "the campaign resumes from the estimate's sample"


def test_estimate_cli_prints_and_writes_json(tmp_path, capsys):
    spec_file = tmp_path / "small.toml"
    spec_file.write_text(SMALL.replace("replicates = 3", "replicates = 1"))
    assert main(["campaign", "estimate", str(spec_file), "--per-cell", "1", "--workers", "4", "--by", "map,algorithm",
                 "--json", str(tmp_path / "e.json"), "--quiet"]) == 0
    out = capsys.readouterr().out
    assert "predicted wall time on 4 workers" in out and "slowest strata" in out
    data = json.loads((tmp_path / "e.json").read_text())
    assert data["strata"] == 4 and data["sample_runs"] == 4 and data["runs"] == 16
    assert data["ci95_s"][0] <= data["predicted_s"] <= data["ci95_s"][1]
    assert main(["campaign", "estimate", str(spec_file), "--by", "colour"]) == 2
    assert "--by: got 'colour'" in capsys.readouterr().err


# ------------------------------------------------------------------------------------ shards ----
def _slurm(task: int, lo: int, hi: int, count: int) -> dict[str, str]:
    return {"SLURM_ARRAY_TASK_ID": str(task), "SLURM_ARRAY_TASK_MIN": str(lo), "SLURM_ARRAY_TASK_MAX": str(hi),
            "SLURM_ARRAY_TASK_COUNT": str(count)}


@pytest.mark.parametrize("lo, hi, step", [(1, 4, 1), (0, 3, 1), (0, 6, 2), (10, 13, 1)])
def test_slurm_arrays_shard_whatever_their_numbering(lo, hi, step):
    shards = [parse_shard("slurm", _slurm(t, lo, hi, 4)) for t in range(lo, hi + 1, step)]
    assert shards == [(0, 4), (1, 4), (2, 4), (3, 4)]


@pytest.mark.parametrize("env, why", [({}, "SLURM_ARRAY_TASK_ID is not set"),
                                      (_slurm(2, 1, 7, 3), "evenly spaced"),
                                      ({**_slurm(1, 1, 4, 4), "SLURM_ARRAY_TASK_ID": "x"}, "not integers")])
def test_slurm_shard_outside_a_proper_array_is_one_line(env, why):
    with pytest.raises(InvalidInput) as err:
        parse_shard("slurm", env)
    assert err.value.field == "--shard" and why in err.value.allowed


def test_a_one_based_slurm_array_runs_every_run_once(tmp_path, monkeypatch, capsys):
    spec_file = tmp_path / "small.toml"
    spec_file.write_text(SMALL.replace("replicates = 3", "replicates = 1"))
    for task in (1, 2, 3):
        for name, value in _slurm(task, 1, 3, 3).items():
            monkeypatch.setenv(name, value)
        assert main(["campaign", "run", str(spec_file), "-o", str(tmp_path / "r"), "--shard", "slurm", "--inline",
                     "--quiet"]) == 0
    out = capsys.readouterr().out
    assert [line.split(" ran")[0] for line in out.splitlines() if " ran (" in line] == ["6", "5", "5"]
    assert len(ResultsStore(tmp_path / "r").done_keys()) == 16


# ------------------------------------------------------------------------------------- dask ----
def test_dask_start_up_is_timed_and_said(tmp_path, capsys):
    pytest.importorskip("distributed")
    spec_file = tmp_path / "small.toml"
    spec_file.write_text(SMALL.replace("replicates = 3", "replicates = 1").replace('"greed"]', '"greed"]\n')
                         .replace("max_ticks = 120", "max_ticks = 40"))
    t0 = time.monotonic()
    assert main(["campaign", "run", str(spec_file), "-o", str(tmp_path / "r"), "--dask", "local", "--workers", "2",
                 "--no-warmup"]) == 0
    wall = time.monotonic() - t0
    out = capsys.readouterr().out
    ready = next(line for line in out.splitlines() if line.startswith("Dask ready in "))
    start = float(ready.split("Dask ready in ")[1].split(" s")[0])
    assert "2 workers on a local cluster" in ready and 0 < start < wall
    total = float(out.split(" already done, in ")[1].split(" s")[0])
    assert total >= start - 1, "the total includes the cluster's start-up"
