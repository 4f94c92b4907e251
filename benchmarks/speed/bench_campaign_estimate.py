"""``swarm campaign estimate`` on the Minotaur paper's campaign, and a check of the estimate against a real run.

    python benchmarks/speed/bench_campaign_estimate.py                      # examples/minotaur-paper.toml
    python benchmarks/speed/bench_campaign_estimate.py --check benchmarks/speed/estimate-check.toml

The first prints the estimate of the paper's 54,000 runs on 2 workers from 2 runs of each of its 90
map x size x robots x algorithm strata (the issue-35 figure; ~180 runs, minutes on 2 cores). ``--check
SPEC`` estimates SPEC from its sample (in a temporary folder), then runs all of SPEC from scratch in
another folder on the same number of workers and prints the predicted and the real wall time, the error
and whether the real time falls in the 95 % interval; with ``--reuse`` the real run resumes from the
sample instead (what a user who passed -o would get; the comparison is then against the remaining runs).
Run it niced, on an otherwise steady machine: the estimate measures the machine as it is while sampling.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))


def load() -> str:
    return " ".join(Path("/proc/loadavg").read_text().split()[:3]) if Path("/proc/loadavg").exists() else "?"


def main() -> None:
    from swarm.campaign import load_campaign, make_executor, run_campaign
    from swarm.campaign.estimate import estimate, hours, report_lines

    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--spec", default=str(ROOT / "examples" / "minotaur-paper.toml"))
    ap.add_argument("--check", default=None, metavar="SPEC", help="estimate SPEC, then run it in full and compare")
    ap.add_argument("--per-cell", type=int, default=2)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--json", default=None, help="write the figures as JSON")
    args = ap.parse_args()
    spec = load_campaign(args.check or args.spec, max_runs=None)
    print(f"load average before: {load()}")
    with tempfile.TemporaryDirectory(prefix="swarm-estimate-bench-") as tmp:
        t0 = time.monotonic()
        est = estimate(spec, per_cell=args.per_cell, workers=args.workers, output=Path(tmp) / "sample",
                       progress=False, log=print)
        print(f"estimate took {time.monotonic() - t0:.0f} s")
        for line in report_lines(est):
            print(line)
        out = {"estimate": est.to_dict(), "load_before": load()}
        if args.check:
            print(f"running all {spec.run_count()} runs of {spec.name} on {args.workers} workers ...")
            t0 = time.monotonic()
            outcome = run_campaign(spec, Path(tmp) / "full", executor=make_executor(workers=args.workers),
                                   progress=False)
            real = time.monotonic() - t0
            err = (est.predicted_s - real) / real
            inside = est.low_s <= real <= est.high_s
            print(f"predicted {hours(est.predicted_s)} (95 % CI {hours(est.low_s)} - {hours(est.high_s)}), "
                  f"real {hours(real)} ({real:.0f} s, {outcome.ran} runs, {outcome.failed} failed): "
                  f"error {100 * err:+.1f} %, {'inside' if inside else 'outside'} the interval")
            from swarm.campaign.store import ResultsStore

            t = ResultsStore(Path(tmp) / "full").runs_table(columns=("key", "wall_time_s", "cpu_time_s", "jit_time_s"))
            cost = sum(w - (j or 0.0) for w, j in zip(t.column("wall_time_s").to_pylist(),
                                                     t.column("jit_time_s").to_pylist()))
            cpu = sum(t.column("cpu_time_s").to_pylist())
            print(f"  sum of run costs (wall - numba) predicted {hours(est.run_seconds)}, real {hours(cost)} "
                  f"({100 * (est.run_seconds - cost) / cost:+.1f} %); CPU predicted {hours(est.cpu_seconds)}, "
                  f"real {hours(cpu)} ({100 * (est.cpu_seconds - cpu) / cpu:+.1f} %)")
            out["check"] = {"real_s": real, "error": err, "inside": inside, "runs": outcome.ran,
                            "real_run_seconds": cost, "real_cpu_seconds": cpu}
        print(f"load average after: {load()}")
        if args.json:
            Path(args.json).write_text(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
