"""Campaigns: expansion, stable keys, paired worlds, resumable atomic results, executors agree."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from maps import InvalidInput
from swarm.campaign import deterministic_rows, load_campaign, make_executor, parse_campaign, run_campaign, status
from swarm.campaign.store import ResultsStore

TINY = """
[campaign]
name = "tiny"
seed = 7
replicates = 2

[grid]
map = ["building", "cave"]
size = [20]
robots = [1, 2]
spawn = ["together"]
algorithm = ["frontier", {name = "frontier", params = {recheck_ticks = 5}, label = "frontier-eager"}]
radio = ["global", "los"]

[stop]
explored = 0.6
max_ticks = 250

[[exclude]]
robots = 2
radio = "los"
"""


def tiny(extra: str = "") -> object:
    return parse_campaign(TINY + extra)


def test_expansion_exclusion_and_counts():
    spec = tiny()
    runs = spec.runs()
    # 2 maps x 1 size x 2 robot counts x 1 spawn x 2 algorithms x 2 radios = 16 cells, minus the 4 cells with
    # 2 robots and LOS = 12 cells, x 2 replicates = 24 runs.
    assert len(runs) == 24
    assert not any(r.cell["robots"] == "2" and r.cell["radio"] == "los" for r in runs)
    assert len({r.key for r in runs}) == 24
    assert [r.index for r in runs] == list(range(24))


def test_include_adds_a_cell_and_duplicates_collapse():
    extra = """
[[include]]
map = "building"
size = 25
robots = 3
spawn = "random"
algorithm = "frontier"
radio = "global"

[[include]]
map = "building"
size = 20
robots = 1
spawn = "together"
algorithm = "frontier"
radio = "global"
"""
    runs = tiny(extra).runs()
    assert len(runs) == 24 + 2, "one new cell (2 replicates); the second include repeats a grid cell"
    assert sum(r.cell["size"] == "25" for r in runs) == 2


def test_keys_are_stable_across_processes_and_key_order():
    keys = [r.key for r in tiny().runs()]
    shuffled = TINY.replace('robots = [1, 2]\nspawn = ["together"]', 'spawn = ["together"]\nrobots = [1, 2]')
    assert shuffled != TINY
    assert sorted(r.key for r in parse_campaign(shuffled).runs()) == sorted(keys)
    code = ("import sys, json; from swarm.campaign import parse_campaign; "
            "print(json.dumps([r.key for r in parse_campaign(sys.stdin.read()).runs()]))")
    out = subprocess.run([sys.executable, "-c", code], input=TINY, capture_output=True, text=True, timeout=120,
                         env={**os.environ, "PYTHONHASHSEED": "99"})
    assert json.loads(out.stdout) == keys


def test_paired_worlds():
    """Every algorithm and comm model meets the same map and start poses per (kind, size, replicate)."""
    from swarm.sim.loop import Simulation

    runs = tiny().runs()
    groups: dict = {}
    for r in runs:
        groups.setdefault((r.cell["map"], r.cell["size"], r.replicate), []).append(r)
    for members in groups.values():
        assert len({(m.seeds["map_seed"], m.seeds["spawn_seed"], m.seeds["run_seed"]) for m in members}) == 1
        one = [m for m in members if m.cell["robots"] == "1"]
        a, b = one[0], one[-1]
        assert a.cell["algorithm"] != b.cell["algorithm"] or a.cell["radio"] != b.cell["radio"]
        sa, sb = Simulation(a.spec), Simulation(b.spec)
        assert (sa.truth.solid == sb.truth.solid).all()
        assert (sa.start_poses == sb.start_poses).all()
    # different replicates meet different worlds
    reps = {r.replicate: r.seeds["map_seed"] for r in runs if r.cell["map"] == "cave"}
    assert reps[0] != reps[1]


def test_seeds_do_not_depend_on_the_grid():
    """Adding an algorithm or a robot count changes no existing run (no shared sequential RNG)."""
    before = {r.key for r in tiny().runs()}
    bigger = parse_campaign(TINY.replace("robots = [1, 2]", "robots = [1, 2, 3]").replace(
        'algorithm = ["frontier",', 'algorithm = ["greed", "frontier",'))
    assert before <= {r.key for r in bigger.runs()}


@pytest.mark.parametrize("mutation, field", [
    ("[campaign]\nname = 'x'\nseed = -1", "campaign.seed"),
    ("[grid]\nmap = ['building']", "grid.size"),
    ("[campaign]\nreplicates = 0\n[grid]", "campaign.replicates"),
])
def test_malformed_specs_are_rejected_before_any_run(mutation, field):
    with pytest.raises(InvalidInput) as info:
        parse_campaign(mutation)
    assert info.value.field.startswith(field)


@pytest.mark.parametrize("old, new, field", [
    ('robots = [1, 2]', 'robots = [1, -2]', "grid.robots[1]"),
    ('radio = ["global", "los"]', 'radio = ["global", "lox"]', "grid.radio[1]"),
    ('params = {recheck_ticks = 5}', 'params = {recheck = 5}', "grid.algorithm[1]"),
    ('size = [20]', 'size = [5]', "grid.size[0]"),
    ('max_ticks = 250', 'max_tick = 250', "stop.max_tick"),
    ('[[exclude]]\nrobots = 2', '[[exclude]]\nrobotz = 2', "exclude[0].robotz"),
    ('label = "frontier-eager"', 'label = "frontier"', "grid.algorithm"),
])
def test_bad_values_name_their_key(old, new, field):
    assert old in TINY
    with pytest.raises(InvalidInput) as info:
        parse_campaign(TINY.replace(old, new))
    assert info.value.field.startswith(field), str(info.value)
    assert "\n" not in str(info.value)


def test_broken_run_is_recorded_and_does_not_stop_the_campaign(tmp_path):
    text = TINY.replace('algorithm = ["frontier", {name = "frontier", params = {recheck_ticks = 5}, label = "frontier-eager"}]',
                        'algorithm = ["frontier", {name = "tests.swarm.campaign.broken:Boom", label = "boom"}]'
                        ).replace('map = ["building", "cave"]', 'map = ["building"]')
    spec = parse_campaign(text)
    out = run_campaign(spec, tmp_path, executor=make_executor(inline=True), progress=False)
    assert out.ran == 12 and out.failed == 6   # every "boom" run raises at tick 3, every frontier run is fine
    st = status(tmp_path)
    assert st["done"] == 6 and st["failed"] == 6 and st["pending"] == 0
    assert list(st["errors"]) == ["RuntimeError: boom at tick 3"]
    again = run_campaign(spec, tmp_path, executor=make_executor(inline=True), progress=False)
    assert again.ran == 0, "failed runs are retried only on request"
    retried = run_campaign(spec, tmp_path, executor=make_executor(inline=True), progress=False, retry_failed=True)
    assert retried.ran == 6 and retried.failed == 6
    assert len(ResultsStore(tmp_path).runs_table()) == 12, "each run appears once (its latest result)"


def test_executors_give_identical_results(tmp_path):
    spec = tiny()
    run_campaign(spec, tmp_path / "inline", executor=make_executor(inline=True), progress=False)
    pool = make_executor(workers=2)
    try:
        run_campaign(spec, tmp_path / "pool", executor=pool, progress=False)
    finally:
        pool.close()
    dask = make_executor(workers=2, dask="local")
    try:
        address = dask.cluster.scheduler_address
        assert address.startswith("tls://127.0.0.1:"), "the local cluster: loopback, TLS"
        from distributed import Client

        for stranger in (address, address.replace("tls://", "tcp://")):  # no certificate: cannot submit code
            with pytest.raises(Exception):
                Client(stranger, timeout="3s", set_as_default=False)
        run_campaign(spec, tmp_path / "dask", executor=dask, progress=False)
    finally:
        dask.close()
    reference = deterministic_rows(tmp_path / "inline")
    assert len(reference) == 24 and all(r["status"] == "ok" for r in reference)
    assert deterministic_rows(tmp_path / "pool") == reference
    assert deterministic_rows(tmp_path / "dask") == reference
    ts = {name: ResultsStore(tmp_path / name).timeseries_table().sort_by([("key", "ascending"), ("tick", "ascending")])
          for name in ("inline", "pool", "dask")}
    assert ts["pool"].equals(ts["inline"]) and ts["dask"].equals(ts["inline"])


def test_shards_partition_the_campaign(tmp_path):
    spec = tiny()
    for i in range(3):
        run_campaign(spec, tmp_path, executor=make_executor(inline=True), progress=False, shard=(i, 3))
    assert status(tmp_path)["done"] == 24


def test_a_different_spec_cannot_reuse_a_results_folder(tmp_path):
    run_campaign(tiny(), tmp_path, executor=make_executor(inline=True), progress=False, shard=(0, 8))
    with pytest.raises(InvalidInput, match="campaign.toml differs"):
        run_campaign(parse_campaign(TINY.replace("seed = 7", "seed = 8")), tmp_path,
                     executor=make_executor(inline=True), progress=False)


def test_a_folder_of_other_files_is_refused_and_left_alone(tmp_path):
    (tmp_path / "thesis.tex").write_text("mine")
    with pytest.raises(InvalidInput, match=r"-o: .*holds thesis.tex and no campaign.toml"):
        run_campaign(tiny(), tmp_path, executor=make_executor(inline=True), progress=False, shard=(0, 8))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["thesis.tex"]


def test_a_campaign_toml_renamed_in_by_a_writer_starting_beside_us_is_not_a_foreign_file(tmp_path, monkeypatch):
    """Two shards started at once: ours finds no campaign.toml, then the other renames its copy in before
    ours lists the folder. That file is the campaign's own, not someone else's (a race CI once hit)."""
    store = ResultsStore(tmp_path)
    real_exists = Path.exists

    def exists_then_appears(self: Path, *args, **kwargs) -> bool:
        if self.name == "campaign.toml" and not real_exists(self):
            self.write_text("[campaign]\n")  # the other writer's rename lands right after our check
            return False
        return real_exists(self, *args, **kwargs)

    monkeypatch.setattr(Path, "exists", exists_then_appears)
    store.refuse_foreign()  # no refusal
    (tmp_path / "thesis.tex").write_text("mine")
    (tmp_path / "campaign.toml").unlink()
    with pytest.raises(InvalidInput, match=r"holds thesis.tex and no campaign.toml"):
        store.refuse_foreign()


@pytest.mark.timeout(600)
def test_kill_9_then_resume_gives_every_run_once_and_identical_results(tmp_path):
    spec_file = tmp_path / "tiny.toml"
    spec_file.write_text(TINY.replace("replicates = 2", "replicates = 4"))
    killed = tmp_path / "killed"
    cmd = [sys.executable, "-m", "swarm", "campaign", "run", str(spec_file), "-o", str(killed), "--workers", "2",
           "--part-size", "3", "--quiet"]
    proc = subprocess.Popen(cmd, start_new_session=True, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    deadline = time.monotonic() + 300
    parts = killed / "parts"
    while time.monotonic() < deadline:
        done = len(list(parts.glob("*.runs.parquet"))) if parts.exists() else 0
        if done >= 2 or proc.poll() is not None:
            break
        time.sleep(0.05)
    assert proc.poll() is None, "the campaign finished before it could be killed; make it longer"
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait(30)
    interrupted = status(killed)
    assert 0 < interrupted["done"] < 48
    resumed = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert resumed.returncode == 0, resumed.stderr
    assert status(killed)["done"] == 48
    table = ResultsStore(killed).runs_table()
    keys = table.column("key").to_pylist()
    assert len(keys) == len(set(keys)) == 48
    reference = tmp_path / "reference"
    run_campaign(load_campaign(spec_file), reference, executor=make_executor(inline=True), progress=False)
    assert deterministic_rows(killed) == deterministic_rows(reference)
    assert not [p for p in (killed / "parts").iterdir() if p.name.startswith(".")], "no temporary files left"


SLOW = """
[campaign]
name = "slow"
seed = 3
replicates = 4

[grid]
map = ["building"]
size = [150]
robots = [8]
spawn = ["together"]
algorithm = ["greed"]
radio = ["multiwall"]

[stop]
max_ticks = 36000
"""


def _children(pid: int) -> list[int]:
    """Live child processes of ``pid`` (read from /proc: every pool worker of a campaign process)."""
    out = subprocess.run(["ps", "-o", "pid=", "--ppid", str(pid)], capture_output=True, text=True).stdout
    return [int(p) for p in out.split()]


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    return not Path(f"/proc/{pid}/stat").read_text().split(") ")[-1].startswith("Z")


def _start_slow_campaign(tmp_path: Path) -> tuple[subprocess.Popen, list[int]]:
    """A campaign of long runs on 2 pool workers, and its workers' pids once both are busy."""
    spec_file = tmp_path / "slow.toml"
    spec_file.write_text(SLOW)
    cmd = [sys.executable, "-m", "swarm", "campaign", "run", str(spec_file), "-o", str(tmp_path / "out"),
           "--workers", "2", "--no-warmup", "--quiet"]
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 120
    workers: list[int] = []
    while time.monotonic() < deadline and proc.poll() is None:
        workers = [p for p in _children(proc.pid) if "spawn_main" in Path(f"/proc/{p}/cmdline").read_text()]
        if len(workers) >= 2:
            break
        time.sleep(0.2)
    assert proc.poll() is None and len(workers) >= 2, "the pool did not start"
    time.sleep(3)  # the workers are inside their first runs (minutes each)
    return proc, workers


@pytest.mark.timeout(300)
def test_sigterm_stops_a_campaign_and_its_workers_at_once(tmp_path):
    proc, workers = _start_slow_campaign(tmp_path)
    t0 = time.monotonic()
    proc.send_signal(signal.SIGTERM)
    proc.wait(60)
    assert proc.returncode == 143, proc.stderr.read()
    assert time.monotonic() - t0 < 30, "a terminated campaign must not wait for its runs in flight"
    deadline = time.monotonic() + 10
    while any(_alive(w) for w in workers) and time.monotonic() < deadline:
        time.sleep(0.2)
    assert not any(_alive(w) for w in workers), "pool workers outlived the campaign"
    assert "Traceback" not in proc.stderr.read()


@pytest.mark.timeout(300)
def test_pool_workers_exit_when_the_campaign_is_killed(tmp_path):
    proc, workers = _start_slow_campaign(tmp_path)
    proc.kill()  # SIGKILL: the campaign gets no chance to stop its pool
    proc.wait(30)
    deadline = time.monotonic() + 15
    while any(_alive(w) for w in workers) and time.monotonic() < deadline:
        time.sleep(0.2)
    assert not any(_alive(w) for w in workers), "orphaned pool workers kept running"
