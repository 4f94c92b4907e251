"""Campaign throughput, scaling, results size and worker memory (issue 9).

    python benchmarks/speed/bench_campaign.py                  # quick campaign with 1 and 2 workers + leak check
    python benchmarks/speed/bench_campaign.py --leak-runs 1000 # longer leak check (runs per campaign, all workers)

1. Throughput: the built-in quick campaign (48 runs) into a fresh folder with 1 worker, then with 2; runs
   per minute of wall time (pool start-up included) and the speed-up.
2. Results size: bytes of the results folder per 1000 runs (time series every 10 ticks).
3. Worker memory: a uniform campaign (every run the same size of world: 20 x 20 buildings, 2 robots,
   Greed, --leak-runs replicates) on 2 workers; each run row carries its worker's peak RSS
   (``ru_maxrss``) after the run. A leak shows as a peak that keeps growing; the goal is flat within
   10 % from a worker's 50th run to its 500th.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

from swarm.campaign import ResultsStore, make_executor, parse_campaign, run_campaign
from swarm.campaign.spec import load_campaign

QUICK = Path(__file__).resolve().parents[1] / "swarm" / "campaign" / "examples" / "quick.toml"
LEAK = """
[campaign]
name = "leak-check"
seed = 5
replicates = {n}
[grid]
map = ["building"]
size = [20]
robots = [2]
spawn = ["random"]
algorithm = ["greed"]
radio = ["multiwall"]
[stop]
explored = 0.98
max_ticks = 6000
"""


def folder_bytes(folder: Path) -> int:
    return sum(p.stat().st_size for p in folder.rglob("*") if p.is_file())


def timed_campaign(spec, folder: Path, workers: int) -> float:
    t0 = time.perf_counter()
    run_campaign(spec, folder, executor=make_executor(workers=workers), progress=False)
    return time.perf_counter() - t0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--leak-runs", type=int, default=1100, help="runs of the uniform leak-check campaign")
    ap.add_argument("--skip-quick", action="store_true")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        if not args.skip_quick:
            quick = load_campaign(QUICK)
            n = len(quick.runs())
            rates = {}
            for workers in (1, 2):
                secs = timed_campaign(quick, tmp / f"quick{workers}", workers)
                rates[workers] = 60 * n / secs
                print(f"quick campaign, {workers} worker(s): {n} runs in {secs:.1f} s = {rates[workers]:.1f} runs/min",
                      flush=True)
            print(f"speed-up 2 vs 1 workers: {rates[2] / rates[1]:.2f}x")
            size = folder_bytes(tmp / "quick2")
            print(f"results folder: {size / 1e6:.2f} MB for {n} runs = {size / n * 1000 / 1e6:.1f} MB per 1000 runs")
        spec = parse_campaign(LEAK.format(n=args.leak_runs))
        secs = timed_campaign(spec, tmp / "leak", 2)
        runs = ResultsStore(tmp / "leak").runs_table().to_pandas().sort_values("index")
        print(f"leak check: {len(runs)} runs in {secs:.0f} s on 2 workers; "
              f"{folder_bytes(tmp / 'leak') / len(runs) * 1000 / 1e6:.1f} MB per 1000 runs")
        for pid, g in runs.groupby("worker_pid"):
            rss = g["worker_rss_mb"].to_numpy()
            marks = {k: float(rss[k - 1]) for k in (1, 50, 100, 250, 500, len(rss)) if k <= len(rss)}
            line = ", ".join(f"run {k}: {v:.1f}" for k, v in marks.items())
            growth = (marks[500] / marks[50] - 1) * 100 if 500 in marks else float("nan")
            print(f"  worker {pid}: {len(rss)} runs; peak RSS MB {line}; run 50 -> 500: {growth:+.1f} %")


if __name__ == "__main__":
    os.environ.setdefault("PYTHONHASHSEED", "0")
    main()
