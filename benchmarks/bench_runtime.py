"""Runtime throughput: ``python benchmarks/bench_runtime.py [--robots 16 --size 150 --seed 1 --profile]``.

The issue-3 workload: 16 robots spawned together on a seeded 150 x 150 building, the frontier explorer,
until 99 % explored (or ``--max-ticks``). Prints simulated ticks per wall second (run loop only, set-up
reported separately), peak RSS, and with ``--profile`` where the time goes (cProfile, top functions).
Pin to one core for the reference figure: ``taskset -c 0 python benchmarks/bench_runtime.py``.
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import resource
import time

from swarm.simulation import Simulation


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--robots", type=int, default=16)
    ap.add_argument("--size", type=int, default=150)
    ap.add_argument("--kind", default="building")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--algorithm", default="frontier")
    ap.add_argument("--max-ticks", type=int, default=36000)
    ap.add_argument("--transport", default="inprocess")
    ap.add_argument("--set", action="append", default=[], metavar="SECTION.KEY=VALUE")
    ap.add_argument("--profile", action="store_true")
    args = ap.parse_args()
    spec = {"seed": args.seed, "map": {"kind": args.kind, "size": args.size},
            "robots": {"count": args.robots, "spawn": "together"}, "algorithm": {"name": args.algorithm},
            "stop": {"max_ticks": args.max_ticks}, "transport": args.transport}
    if args.set:
        from swarm.cli.options import parse_params
        from swarm.cli.run_cmd import _merge

        spec = _merge(spec, parse_params(tuple(args.set), "--set"))
    t0 = time.perf_counter()
    sim = Simulation(spec)
    setup = time.perf_counter() - t0
    profiler = cProfile.Profile() if args.profile else None
    if profiler:
        profiler.enable()
    cpu0 = time.process_time()
    result = sim.run()
    cpu = time.process_time() - cpu0
    if profiler:
        profiler.disable()
    s = result.summary
    rss_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(result.one_line())
    print(f"ticks {s['ticks']}  run {s['wall_time_s']:.2f} s wall, {cpu:.2f} s CPU -> "
          f"{s['ticks'] / s['wall_time_s']:.0f} ticks/s wall, {s['ticks'] / cpu:.0f} ticks per CPU-second"
          f"  (set-up {setup:.2f} s)  peak RSS {rss_mb:.0f} MB  plans {sum(s['plans'])}")
    if profiler:
        pstats.Stats(profiler).sort_stats("tottime").print_stats(25)


if __name__ == "__main__":
    main()
