"""Run a random sample of a results folder's runs again with this code and compare their rows.

    python benchmarks/experiments/rerun_sample.py docs/results/maes-parity/campaign \
        examples/minotaur-ablation.toml --runs 12 --seed 1

A campaign computed by one commit stays comparable with later code only where the later code is exact for
its runs. This picks ``--runs`` of the folder's runs at random (seeded; ok runs only), runs each in this
process exactly as a campaign worker does (``swarm.campaign.executors.execute``), builds its runs-table row
(``swarm.campaign.runner.runs_row``) and compares every column but those that legitimately differ between
executions (``swarm.results.schema.NONDETERMINISTIC_COLUMNS``: times, worker, commit). Prints one line a
run and exits 1 if any row differs (issue 49: the ablation kept across sessions, checked on the final code).
"""

from __future__ import annotations

import argparse
import math
import sys
import time

import numpy as np


def same(a: object, b: object) -> bool:
    """Equal, with NaN equal to NaN (a run that never reached a fraction has NaN crossings)."""
    if isinstance(a, float) and isinstance(b, float):
        return a == b or (math.isnan(a) and math.isnan(b))
    return a == b


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folder", help="a campaign results folder")
    ap.add_argument("spec", help="the campaign's TOML spec")
    ap.add_argument("--runs", type=int, default=12, help="how many runs to repeat (default 12)")
    ap.add_argument("--seed", type=int, default=1, help="seed of the sample")
    args = ap.parse_args(argv)

    from swarm.campaign.executors import execute
    from swarm.campaign.runner import runs_row
    from swarm.campaign.spec import load_campaign
    from swarm.campaign.store import ResultsStore
    from swarm.results.schema import NONDETERMINISTIC_COLUMNS

    campaign = load_campaign(args.spec)
    table = ResultsStore(args.folder).runs_table()
    if table is None:
        print(f"rerun_sample.py: error: folder: {args.folder[:80]!r} holds no runs", file=sys.stderr)
        return 2
    stored = {row["key"]: row for row in table.to_pylist() if row["status"] == "ok"}
    keys = sorted(stored)
    picked = set(np.random.default_rng(args.seed).choice(len(keys), size=min(args.runs, len(keys)),
                                                          replace=False).tolist())
    wanted = {keys[i] for i in picked}
    differ = 0
    for index, key in campaign.iter_keys():
        if key not in wanted:
            continue
        run = campaign.run_at(index)
        t0 = time.perf_counter()
        row = runs_row(campaign, run, execute((key, run.canonical())))
        old = stored[key]
        changed = sorted(c for c in row if c not in NONDETERMINISTIC_COLUMNS and c in old
                         and not same(row[c], old[c]))
        differ += bool(changed)
        label = " / ".join(str(v) for v in run.cell.values())
        print(f"{'SAME' if not changed else 'DIFFERENT'} run {index} ({label}, replicate {run.replicate}): "
              f"{row['ticks']} ticks, {time.perf_counter() - t0:.0f} s"
              + (f"; differs in {', '.join(changed[:8])}" if changed else ""), flush=True)
    versions = sorted({str(stored[k]["swarm_version"]) for k in wanted})
    print(f"{len(wanted) - differ} of {len(wanted)} rows identical (stored by {', '.join(versions)})")
    return 1 if differ else 0


if __name__ == "__main__":
    sys.exit(main())
