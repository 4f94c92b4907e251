"""Compare algorithms over seeded maps: mean ticks to an explored target per grid cell.

    python benchmarks/experiments/compare.py --algorithms greed tnf --kinds building cave --sizes 50 100 \\
        --robots 2 8 --radios global los multiwall --seeds 10 --workers 2 [--target 0.99] [--out table.md]

Every (kind, size, seed) uses the same map and spawn for every algorithm and radio (paired comparisons).
Runs that do not reach the target count at ``--max-ticks`` and are reported as timeouts. This is a small
stand-in for ``swarm campaign`` (issue 9) used for the algorithm issues' notes.
"""

from __future__ import annotations

import argparse
import itertools
import statistics
import time
from multiprocessing import Pool

from swarm.sim.loop import Simulation
from swarm.sim.spec import derive_seed


def run_one(cell: tuple) -> tuple:
    algorithm, kind, size, robots, radio, seed, target, max_ticks, extra = cell
    spec = {"seed": derive_seed(seed, "run"), "map": {"kind": kind, "size": size, "seed": derive_seed(seed, kind, size)},
            "robots": {"count": robots, "spawn": "together", "spawn_seed": derive_seed(seed, kind, size, "spawn")},
            "algorithm": {"name": algorithm}, "radio": {"model": radio},
            "stop": {"explored": target, "max_ticks": max_ticks}, **extra}
    t0 = time.perf_counter()
    r = Simulation(spec).run()
    return (algorithm, kind, size, robots, radio, seed, r.summary["ticks"], r.summary["stop_reason"],
            time.perf_counter() - t0)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--algorithms", nargs="+", default=["greed", "tnf"])
    ap.add_argument("--kinds", nargs="+", default=["building", "cave"])
    ap.add_argument("--sizes", nargs="+", type=int, default=[50, 100])
    ap.add_argument("--robots", nargs="+", type=int, default=[2, 8])
    ap.add_argument("--radios", nargs="+", default=["multiwall"])
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--target", type=float, default=0.99)
    ap.add_argument("--max-ticks", type=int, default=36000)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--out", default=None)
    args = ap.parse_args()
    cells = [(a, k, s, r, rad, seed, args.target, args.max_ticks, {})
             for k, s, r, rad, seed, a in itertools.product(args.kinds, args.sizes, args.robots, args.radios,
                                                            range(args.seeds), args.algorithms)]
    t0 = time.perf_counter()
    with Pool(args.workers) as pool:
        rows = pool.map(run_one, cells, chunksize=1)
    lines = [f"{len(rows)} runs in {time.perf_counter() - t0:.0f} s on {args.workers} workers; "
             f"mean ticks to {args.target:.0%} (timeouts count as {args.max_ticks}; n timed out)", "",
             "| kind | size | robots | radio | " + " | ".join(args.algorithms) + " |",
             "|---|---|---|---|" + "---|" * len(args.algorithms)]
    for k, s, r, rad in itertools.product(args.kinds, args.sizes, args.robots, args.radios):
        cols = []
        for a in args.algorithms:
            sel = [row for row in rows if row[:5] == (a, k, s, r, rad)]
            ticks = [row[6] if row[7] == "explored" else args.max_ticks for row in sel]
            fails = sum(row[7] != "explored" for row in sel)
            cols.append(f"{statistics.mean(ticks):.0f}" + (f" ({fails} t/o)" if fails else ""))
        lines.append(f"| {k} | {s} | {r} | {rad} | " + " | ".join(cols) + " |")
    text = "\n".join(lines)
    print(text)
    if args.out:
        with open(args.out, "w") as f:
            f.write(text + "\n")


if __name__ == "__main__":
    main()
