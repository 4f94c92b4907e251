"""Runtime throughput: ``python benchmarks/speed/bench_runtime.py [--robots 16 --size 150 --seed 1 --profile]``.

The issue-3 workload: 16 robots spawned together on a seeded 150 x 150 building, the frontier explorer,
until 99 % explored (or ``--max-ticks``). Prints simulated ticks per wall second (run loop only, set-up
reported separately), peak RSS, and with ``--profile`` where the time goes (cProfile, top functions).
Pin to one core for the reference figure: ``taskset -c 0 python benchmarks/speed/bench_runtime.py``.

``--repeat N`` runs the workload N times, each in a fresh process (so every run pays the same imports and
kernel loads), and reports each run, the best and the median: the project's shared virtual machine
changes speed by up to 2x within seconds (a fixed pure-Python loop took 37-80 us over one minute), so one
run says little and the best of several is the closest to what the code itself costs.

``--warm-process`` first runs the workload once, untimed, on the next seed (another map) and then times
the run: the steady state of a campaign worker, which runs many specs in one process and loads numba's
compiled kernels from their cache only during its first run (each kernel on its first call: ~0.2 s of
this workload's loop in a fresh process). Without it the timed run pays those loads, as a one-off
``swarm run`` does. Peak RSS then covers both runs.

A run that had to compile numba kernels (no cache yet: the first run after an install, or after a kernel
was edited) says so, with the kernels' compile time: compiling takes most of a minute and LLVM lifts the
process's peak RSS to ~450 MB, so such a run measures the compiler, not the simulation. ``--repeat N``
leaves compiling runs out of its best, median and peak RSS and runs another in their place, so the
summary covers N runs on a warm cache.
"""

from __future__ import annotations

import argparse
import cProfile
import json
import pstats
import resource
import statistics
import subprocess
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager

from numba.core import event

from swarm.sim.loop import Simulation


def workload(args: argparse.Namespace, seed: int) -> dict:
    """The benchmark's spec with this seed."""
    spec = {"seed": seed, "map": {"kind": args.kind, "size": args.size},
            "robots": {"count": args.robots, "spawn": "together"}, "algorithm": {"name": args.algorithm},
            "stop": {"max_ticks": args.max_ticks}, "transport": args.transport}
    if args.set:
        from swarm.cli.options import parse_params
        from swarm.sim.spec_input import merge

        spec = merge(spec, parse_params(tuple(args.set), "--set"))
    return spec


@contextmanager
def compiles_counted(tally: dict) -> Iterator[None]:
    """Count into ``tally`` (``kernels``, ``seconds``) the numba compilations started inside the block:
    numba raises its ``numba:compile`` event only when a kernel is not in its cache. Kernels compiled
    while compiling another (inlined callees) count once, with their caller's time."""
    with event.install_recorder("numba:compile") as recorder:
        yield
    depth, started = 0, 0.0
    for stamp, ev in recorder.buffer:
        if ev.is_start:
            if depth == 0:
                started = stamp
                tally["kernels"] += 1
            depth += 1
        else:
            depth -= 1
            if depth == 0:
                tally["seconds"] += stamp - started


def run_once(args: argparse.Namespace) -> dict:
    """Build and run the workload once in this process (after an untimed run on the next seed with
    ``--warm-process``); its figures (run loop timed apart from set-up), and the numba kernels compiled
    on the way (none once numba's cache holds them)."""
    tally = {"kernels": 0, "seconds": 0.0}
    with compiles_counted(tally):
        if args.warm_process:
            Simulation(workload(args, args.seed + 1)).run()
        spec = workload(args, args.seed)
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
            pstats.Stats(profiler).sort_stats("tottime").print_stats(25)
    s = result.summary
    return {"line": result.one_line(), "ticks": s["ticks"], "wall": s["wall_time_s"], "cpu": cpu, "setup": setup,
            "rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, "plans": sum(s["plans"]),
            "compiled": tally["kernels"], "compile_s": tally["seconds"]}


def report(r: dict) -> str:
    """One run's figures on one line."""
    line = (f"ticks {r['ticks']}  run {r['wall']:.2f} s wall, {r['cpu']:.2f} s CPU -> "
            f"{r['ticks'] / r['wall']:.0f} ticks/s wall, {r['ticks'] / r['cpu']:.0f} ticks per CPU-second"
            f"  (set-up {r['setup']:.2f} s)  peak RSS {r['rss_mb']:.0f} MB  plans {r['plans']}")
    if r["compiled"]:
        line += (f"  COMPILED {r['compiled']} numba kernels ({r['compile_s']:.1f} s; the cache was cold, so"
                 " this run measures the compiler)")
    return line


def repeat(n: int, argv: list[str]) -> None:
    """Run this script in fresh processes with ``argv`` (which asks for one run) until ``n`` runs compiled
    nothing (a run that compiled, on a cold cache, is replaced once: at most ``2 n`` runs); summarise."""
    runs: list[dict] = []
    while sum(not r["compiled"] for r in runs) < n and len(runs) < 2 * n:
        child = subprocess.run([sys.executable, __file__, *argv, "--emit-json"], capture_output=True, text=True)
        if child.returncode != 0:  # a bad --set, say: the run's own error, not a traceback of this one
            sys.stderr.write(child.stderr)
            raise SystemExit(child.returncode)
        r = json.loads(child.stdout.strip().splitlines()[-1])
        runs.append(r)
        if len(runs) == 1:
            print(r["line"])
        print(f"run {len(runs)}: {report(r)}", flush=True)
    print(summary(runs))


def summary(runs: list[dict]) -> str:
    """Best, median and worst ticks/s and the peak RSS of the runs that compiled nothing, saying how many
    were left out; of all runs if every one compiled, saying so."""
    warm = [r for r in runs if not r["compiled"]] or runs
    left_out = len(runs) - len(warm)
    rates = sorted(r["ticks"] / r["wall"] for r in warm)
    note = (f" (left out: {left_out} run(s) that compiled numba kernels)" if left_out else
            " (every run compiled numba kernels: these figures include the compiler)" if runs[0]["compiled"] else "")
    return (f"{len(warm)} runs: best {rates[-1]:.0f} ticks/s, median {statistics.median(rates):.0f}, "
            f"worst {rates[0]:.0f}; peak RSS up to {max(r['rss_mb'] for r in warm):.0f} MB{note}")


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
    ap.add_argument("--warm-process", action="store_true",
                    help="time the run after an untimed one on the next seed in the same process (kernels loaded)")
    ap.add_argument("--repeat", type=int, default=1, metavar="N",
                    help="run N times, each in a fresh process, and report the best and the median")
    ap.add_argument("--emit-json", action="store_true", help=argparse.SUPPRESS)  # one run for --repeat
    args = ap.parse_args()
    if args.repeat < 1:
        ap.error(f"--repeat: {args.repeat} is not allowed; give a whole number >= 1")
    if args.repeat > 1:
        if args.profile:
            ap.error("--repeat: profile one run at a time (drop --repeat or --profile)")
        repeat(args.repeat, [*sys.argv[1:], "--repeat", "1"])  # the last --repeat wins: each child runs once
        return
    r = run_once(args)
    if args.emit_json:
        print(json.dumps(r))
        return
    print(r["line"])
    print(report(r))


if __name__ == "__main__":
    main()
