"""How the runtime scales with the team: ``python benchmarks/speed/bench_scaling.py [--pairs 4] [--size 150]``.

The issue-3 workload (robots spawned together on a seeded building, the frontier explorer) with 32 and with
64 robots, the same number of ticks each, run alternately in this one process (the machine's speed drifts
within minutes, so only neighbouring runs compare; the order flips every pair). Prints each pair's CPU
seconds per tick of the run loop (this thread's, so other processes on the machine do not count) and the
64/32 ratio, then the median and range of the ratios: 2.0 is linear.

``--phases`` also times the loop's steps (algorithms, map-sharing merges, outgoing updates and delivery,
navigation, physics, lidar, metrics) and prints each one's 64/32 ratio and its cost above linear: where the
pairwise terms are.

``--memory`` instead runs 64 robots (``--robots``) on a 300-tile building (``--size``) for ``--ticks`` ticks in
a fresh process and prints its peak RSS (``ru_maxrss``), with the process's size after the imports and after
the set-up, how much of it is file-backed shared code (libllvmlite, pyarrow: ``RssFile``) at the end of
the run, and the peak of the process's own memory (``RssAnon``, sampled every 50 ticks).
"""

from __future__ import annotations

import argparse
import json
import resource
import statistics
import subprocess
import sys
import time

PHASES = (("swarm.transport.inprocess:InProcessHost.act", "algorithms (host.act)"),
          ("swarm.sim.loop:Simulation._receive", "map merges (_receive)"),
          ("swarm.sim.loop:Simulation._send", "updates + delivery (_send)"),
          ("swarm.sim.loop:Simulation._commands", "navigation (_commands)"),
          ("swarm.sim.loop:World.step", "physics (world.step)"),
          ("swarm.sim.loop:Lidar.scan", "lidar (scan)"),
          ("swarm.sim.loop:Simulation._record", "metrics (_record)"))


def spec(args: argparse.Namespace, robots: int) -> dict:
    return {"seed": args.seed, "map": {"kind": args.kind, "size": args.size},
            "robots": {"count": robots, "spawn": "together"}, "algorithm": {"name": args.algorithm},
            "stop": {"max_ticks": args.ticks}}


def time_phases(totals: dict[str, float]) -> None:
    """Wrap each of PHASES so that its thread CPU time adds up in ``totals`` (one clock read per call)."""
    import importlib

    for path, label in PHASES:
        module, qual = path.split(":")
        owner_name, method = qual.split(".")
        owner = getattr(importlib.import_module(module), owner_name)
        fn = getattr(owner, method)

        def timed(*a, _fn=fn, _label=label, **k):
            t0 = time.thread_time()
            try:
                return _fn(*a, **k)
            finally:
                totals[_label] = totals.get(_label, 0.0) + time.thread_time() - t0

        setattr(owner, method, timed)


def scaling(args: argparse.Namespace) -> None:
    from swarm.sim.loop import Simulation

    totals: dict[str, float] = {}
    if args.phases:
        time_phases(totals)
    Simulation({**spec(args, 8), "seed": args.seed + 1, "stop": {"max_ticks": 30}}).run()  # load every kernel
    per_tick: dict[int, list[dict[str, float]]] = {32: [], 64: []}
    for k in range(args.pairs):
        for robots in (32, 64) if k % 2 == 0 else (64, 32):
            totals.clear()
            sim = Simulation(spec(args, robots))
            t0 = time.thread_time()
            ticks = sim.run().summary["ticks"]
            row = {label: seconds / ticks for label, seconds in totals.items()}
            row["total"] = (time.thread_time() - t0) / ticks
            per_tick[robots].append(row)
        a, b = per_tick[32][-1]["total"], per_tick[64][-1]["total"]
        print(f"pair {k + 1}: 32 robots {1e3 * a:.3f} ms/tick, 64 robots {1e3 * b:.3f} ms/tick (CPU): "
              f"ratio {b / a:.2f}", flush=True)
    ratios = sorted(b["total"] / a["total"] for a, b in zip(per_tick[32], per_tick[64]))
    q = statistics.quantiles(ratios, n=4) if len(ratios) > 1 else [ratios[0]] * 3
    print(f"64/32 cost per tick over {len(ratios)} pairs: median {statistics.median(ratios):.2f} "
          f"(quartiles {q[0]:.2f}-{q[2]:.2f}, range {ratios[0]:.2f}-{ratios[-1]:.2f}; 2.00 is linear)")
    if args.phases:
        print(f"{'ms per tick (median)':30s} {'32':>7s} {'64':>7s} {'ratio':>6s} {'above linear':>13s}")
        for label in [label for _, label in PHASES] + ["total"]:
            a = statistics.median(r.get(label, 0.0) for r in per_tick[32])
            b = statistics.median(r.get(label, 0.0) for r in per_tick[64])
            print(f"  {label:28s} {1e3 * a:7.3f} {1e3 * b:7.3f} {b / max(a, 1e-12):6.2f} {1e3 * (b - 2 * a):+13.3f}")


def rss_parts() -> dict[str, int]:
    """This process's resident memory now (MB): all, its own (anonymous), file-backed (shared code)."""
    parts = {}
    with open("/proc/self/status") as f:
        for line in f:
            key = line.split(":")[0]
            if key in ("VmRSS", "RssAnon", "RssFile"):
                parts[key] = int(line.split()[1]) // 1024
    return parts


def memory_child(args: argparse.Namespace) -> None:
    from swarm.sim.loop import Simulation

    imported = rss_parts()["VmRSS"]
    own = [0]

    def sample(view) -> None:  # the process's own memory, every 50 ticks (a /proc read: no cost to speak of)
        if view.tick % 50 == 0:
            own[0] = max(own[0], rss_parts()["RssAnon"])

    sim = Simulation(spec(args, args.robots), observers=(sample,))
    set_up = rss_parts()["VmRSS"]
    summary = sim.run().summary
    end = rss_parts()
    print(json.dumps({"imported": imported, "set_up": set_up, "end": end, "ticks": summary["ticks"],
                      "peak": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss // 1024,
                      "own_peak": max(own[0], end["RssAnon"])}))


def memory(args: argparse.Namespace) -> None:
    child = subprocess.run([sys.executable, __file__, *sys.argv[1:], "--memory-child"], capture_output=True, text=True)
    if child.returncode != 0:
        sys.stderr.write(child.stderr)
        raise SystemExit(child.returncode)
    r = json.loads(child.stdout.strip().splitlines()[-1])
    print(f"{args.robots} robots, {args.kind} {args.size}, {r['ticks']} ticks: peak RSS {r['peak']} MB "
          f"(after the imports {r['imported']} MB, after the set-up {r['set_up']} MB; at the end "
          f"{r['end']['VmRSS']} MB, of which the process's own {r['end']['RssAnon']} MB and file-backed shared "
          f"code {r['end']['RssFile']} MB); the process's own memory peaked at {r['own_peak']} MB")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--pairs", type=int, default=4)
    ap.add_argument("--size", type=int, default=None, help="map size in tiles (150; 300 with --memory)")
    ap.add_argument("--kind", default="building")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--algorithm", default="frontier")
    ap.add_argument("--ticks", type=int, default=3000)
    ap.add_argument("--phases", action="store_true", help="also time the loop's steps")
    ap.add_argument("--memory", action="store_true", help="peak RSS of one run in a fresh process instead")
    ap.add_argument("--robots", type=int, default=64, help="robots of the --memory run")
    ap.add_argument("--memory-child", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.pairs < 1:
        ap.error(f"--pairs: {args.pairs} is not allowed; give a whole number >= 1")
    if args.size is None:
        args.size = 300 if args.memory or args.memory_child else 150
    if args.memory_child:
        memory_child(args)
    elif args.memory:
        memory(args)
    else:
        scaling(args)


if __name__ == "__main__":
    main()
