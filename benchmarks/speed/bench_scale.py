r"""Swarm scale: ``python benchmarks/speed/bench_scale.py [--robots 16 64 256 1000] [--ticks 300] [--cave]``.

For each robot count, one run in a fresh process: building maps sized to keep the density of the 16-robot,
150-tile case (``--density``), robots spawned together (``--spawn``), the frontier explorer
(``--algorithm``), the full stack (lidar, own maps, multiwall radio, delta map sharing, metrics). Each row
prints simulated ticks per second of the run loop (CPU time of the process, so other load on the machine
counts less), microseconds per robot-tick, peak RSS and the loop's biggest costs (each step's share of the
loop's CPU time).

A row is ``R`` (robots; the map sized for the density) or ``R@S`` (robots on an S-tile map: ``1000@600``);
``--cave`` adds a cave row for every count. ``--ticks T`` runs T ticks; ``--explored F`` runs until a
fraction F of the map is explored (capped by ``--max-ticks``). Each child first runs a tiny warm-up (8
robots, 20 ticks) so that the timed run does not pay numba's kernel loads; a row whose kernels had to be
compiled says so (run the script once more). Pin to one core for reference figures: ``taskset -c 0``.
A row whose resident memory passes ``--limit-gb`` (default 80 % of the machine's) is stopped and reported
with the tick it reached (``--limit-gb 8``: the issue-47 bound for 10,000 robots).

``--comm KEY=VALUE`` sets a ``[comm]`` setting of every row (``map_zlib_level=1``: map updates
compressed faster into more bytes). ``--json FILE`` writes every row's figures. The issue-47 figures:

    python benchmarks/speed/bench_scale.py --robots 16 64 256 1000 --ticks 300 --cave
    python benchmarks/speed/bench_scale.py --robots 1000@600 --ticks 1000 --algorithm greed
    python benchmarks/speed/bench_scale.py --robots 1000@600 --explored 0.5 --max-ticks 20000 --progress 60
    python benchmarks/speed/bench_scale.py --robots 1000@600 --explored 0.5 --max-ticks 400 --spawn random
    python benchmarks/speed/bench_scale.py --robots 1000@600 --explored 0.5 --max-ticks 400 --spawn random \
        --comm map_zlib_level=1
    python benchmarks/speed/bench_scale.py --robots 10000@2000 --ticks 200 --limit-gb 8
    python benchmarks/speed/bench_scale.py --robots 16@150 1000@600 --ticks 1000 --pairs 3   # the 2x ratio
"""

from __future__ import annotations

import argparse
import json
import math
import resource
import subprocess
import sys
import time
from pathlib import Path

REFERENCE = (16, 150)
"""The density every unsized row keeps: 16 robots on a 150-tile map."""

PHASES = (("swarm.transport.inprocess:InProcessHost.act", "algorithms"),
          ("swarm.sim.loop:Simulation._receive", "map merges"),
          ("swarm.sim.loop:Simulation._send", "updates + delivery"),
          ("swarm.sim.loop:Simulation._commands", "navigation"),
          ("swarm.sim.loop:World.step", "physics"),
          ("swarm.sim.loop:Lidar.scan", "lidar"),
          ("swarm.sim.loop:ExplorationTracker.update_coverage", "coverage"),
          ("swarm.sim.loop:Simulation._record", "metrics"),
          ("swarm.sim.loop:Simulation.observe", "observations"),
          ("swarm.grid.targets:_TargetSearch.run", "whole-map target searches"))
"""The loop's steps timed in each row (module:Owner.method as the loop module sees it, label)."""


def sized(robots: int, density: float) -> int:
    """The map size (tiles per side) that holds ``robots`` at ``density`` robots per square tile."""
    return max(20, int(round(math.sqrt(robots / density))))


def parse_row(text: str, density: float) -> tuple[int, int]:
    robots, _, size = text.partition("@")
    try:
        r = int(robots)
        s = int(size) if size else sized(r, density)
    except ValueError:
        raise SystemExit(f"bench_scale.py: error: row {text!r}: give R or R@S (robots, map tiles)") from None
    if r < 1 or s < 20:
        raise SystemExit(f"bench_scale.py: error: row {text!r}: robots >= 1 and a map of >= 20 tiles")
    return r, s


def time_phases(totals: dict[str, float]) -> None:
    """Wrap each of PHASES so that its CPU time adds up in ``totals`` (nested calls count in both)."""
    import importlib

    for path, label in PHASES:
        module, qual = path.split(":")
        owner_name, method = qual.split(".")
        owner = getattr(importlib.import_module(module), owner_name)
        fn = getattr(owner, method)

        def timed(*a, _fn=fn, _label=label, **k):
            t0 = time.process_time()
            try:
                return _fn(*a, **k)
            finally:
                totals[_label] = totals.get(_label, 0.0) + time.process_time() - t0

        setattr(owner, method, timed)


def child(args: argparse.Namespace) -> None:
    from numba.core import event

    from swarm.sim.loop import Simulation

    compiled = [0]

    class Compiles(event.Listener):
        def on_start(self, ev):  # noqa: D401 - numba's listener interface
            compiled[0] += 1

        def on_end(self, ev):
            pass

    event.register("numba:compile", Compiles())
    Simulation({"seed": args.seed + 1, "map": {"kind": args.kind, "size": 30}, "robots": {"count": 8},
                "algorithm": {"name": args.algorithm}, "stop": {"max_ticks": 20}}).run()
    totals: dict[str, float] = {}
    time_phases(totals)
    stop = {"max_ticks": args.ticks} if args.explored is None else {"explored": args.explored,
                                                                     "max_ticks": args.max_ticks}
    tick = [-1]  # the tick being run, for the memory watchdog's report
    sense = Simulation.sense

    def sense_and_note(self, state, _sense=sense):
        tick[0] = state.tick
        return _sense(self, state)
    Simulation.sense = sense_and_note
    memory_watchdog(args.limit_gb, tick)
    t0 = time.process_time()
    sim = Simulation({"seed": args.seed, "map": {"kind": args.kind, "size": args.size},
                      "robots": {"count": args.robots, "spawn": args.spawn},
                      "algorithm": {"name": args.algorithm, "params": params_of(args.param)},
                      "comm": params_of(args.comm, "--comm"), "stop": stop})
    setup_cpu = time.process_time() - t0
    totals.clear()
    if args.progress > 0:
        report_progress(sim, args.progress)
    t1 = time.process_time()
    wall0 = time.perf_counter()
    result = sim.run()
    cpu = time.process_time() - t1
    wall = time.perf_counter() - wall0
    s = result.summary
    print(json.dumps({"robots": args.robots, "size": args.size, "kind": args.kind, "spawn": args.spawn,
                      "algorithm": args.algorithm,
                      "params": params_of(args.param), "comm": params_of(args.comm, "--comm"),
                      "ticks": s["ticks"], "explored": s["explored"], "stop_reason": s["stop_reason"],
                      "cpu_s": cpu, "wall_s": wall, "setup_cpu_s": setup_cpu,
                      "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
                      "phases": totals, "compiled": compiled[0]}))


def memory_limit_gb(text: str | None) -> float:
    """``--limit-gb``: the value given, else 80 % of the machine's memory."""
    if text is not None:
        return float(text)
    with open("/proc/meminfo") as f:
        total_kb = next(int(line.split()[1]) for line in f if line.startswith("MemTotal"))
    return 0.8 * total_kb / 2**20


def rss_gb() -> float:
    """This process's resident memory now, GB (``/proc/self/status``)."""
    with open("/proc/self/status") as f:
        return next(int(line.split()[1]) for line in f if line.startswith("VmRSS")) / 2**20


def memory_watchdog(limit_gb: float, tick: list[int]) -> None:
    """End this process (exit 3) once its resident memory passes ``limit_gb``, printing a JSON line with the
    tick it was at (``tick[0]``, kept up to date by the caller): a 10,000-robot row can otherwise take the
    machine's memory (and the other rows with it). Also used by swarm_memory.py."""
    import os
    import threading

    def watch() -> None:
        while True:
            now = rss_gb()
            if now > limit_gb:
                print(json.dumps({"stopped": "memory", "rss_gb": now, "limit_gb": limit_gb, "tick": tick[0],
                                  "cpu_s": time.process_time()}), flush=True)
                os._exit(3)
            time.sleep(0.5)

    threading.Thread(target=watch, daemon=True).start()


def report_progress(sim, every_s: float) -> None:
    """Print the tick, explored fraction, CPU time and RSS to stderr every ``every_s`` CPU-seconds of the run
    (a long ``--explored`` run can then be judged, or stopped, before it ends)."""
    sense = type(sim).sense
    start = time.process_time()
    due = [start + every_s]

    def sense_and_report(self, state, _sense=sense):
        now = time.process_time()
        if now >= due[0]:
            due[0] = now + every_s
            rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
            print(f"  tick {state.tick}: explored {100 * self.tracker.explored:.1f} %, {now - start:.0f} s CPU, "
                  f"peak RSS {rss:.0f} MB", file=sys.stderr, flush=True)
        return _sense(self, state)

    type(sim).sense = sense_and_report


def params_of(items: list[str], flag: str = "--param") -> dict:
    """``--param KEY=VALUE`` items as the algorithm's params, or ``--comm`` items as the [comm] settings
    (each VALUE read as JSON, else kept as text)."""
    out = {}
    for item in items:
        key, sep, value = item.partition("=")
        if not sep or not key:
            raise SystemExit(f"bench_scale.py: error: {flag}: got {item[:60]!r}; allowed: KEY=VALUE")
        try:
            out[key] = json.loads(value)
        except json.JSONDecodeError:
            out[key] = value
    return out


def run_row(args: argparse.Namespace, robots: int, size: int, kind: str) -> dict | None:
    argv = [sys.executable, __file__, "--child", "--kind", kind, "--robots-n", str(robots), "--size", str(size),
            "--algorithm", args.algorithm, "--seed", str(args.seed), "--ticks", str(args.ticks),
            "--max-ticks", str(args.max_ticks), "--spawn", args.spawn]
    if args.explored is not None:
        argv += ["--explored", str(args.explored)]
    for item in args.param:
        argv += ["--param", item]
    for item in args.comm:
        argv += ["--comm", item]
    argv += ["--progress", str(args.progress), "--limit-gb", str(args.limit_gb)]
    proc = subprocess.run(argv, stdout=subprocess.PIPE, stderr=None if args.progress > 0 else subprocess.PIPE,
                          text=True)
    lines = proc.stdout.strip().splitlines()
    if proc.returncode == 3 and lines and '"stopped"' in lines[-1]:
        stop = json.loads(lines[-1])
        where = "in set-up" if stop["tick"] < 0 else f"at tick {stop['tick']}"
        print(f"{robots:>6} {kind} {size}: stopped {where}: RSS passed {stop['limit_gb']:g} GB "
              f"({stop['rss_gb']:.1f} GB after {stop['cpu_s']:.0f} s CPU)", flush=True)
        return None
    if proc.returncode != 0:
        tail = (proc.stderr or "").strip().splitlines()[-1:] or [f"exit status {proc.returncode}"]
        print(f"{robots:>6} {kind} {size}: failed ({tail[0][:120]})", flush=True)
        return None
    return json.loads(lines[-1])


def show(row: dict, top: int) -> None:
    ticks, robots, cpu = row["ticks"], row["robots"], row["cpu_s"]
    rate = ticks / cpu if cpu > 0 else float("inf")
    per = 1e6 * cpu / max(ticks * robots, 1)
    costs = sorted(row["phases"].items(), key=lambda kv: -kv[1])[:top]
    shares = ", ".join(f"{label} {100 * sec / cpu:.0f}%" for label, sec in costs if cpu > 0)
    note = " (compiled kernels: run again)" if row["compiled"] else ""
    print(f"{robots:>6} {row['kind']:>8} {row['size']:>5} {ticks:>6} {rate:>9.1f} {per:>9.1f} "
          f"{row['peak_rss_mb']:>8.0f} {100 * row['explored']:>6.1f}%  {shares}{note}", flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--robots", nargs="+", default=["16", "64", "256", "1000"],
                    help="rows: R (map sized for the density) or R@S (robots on an S-tile map)")
    ap.add_argument("--density", type=float, default=REFERENCE[0] / REFERENCE[1] ** 2,
                    help="robots per square tile of an unsized row (default: 16 on 150 tiles)")
    ap.add_argument("--kind", default="building", choices=["building", "cave"])
    ap.add_argument("--cave", action="store_true", help="add a cave row for every count")
    ap.add_argument("--algorithm", default="frontier")
    ap.add_argument("--param", action="append", default=[], metavar="KEY=VALUE",
                    help="an algorithm parameter (repeatable; VALUE read as JSON, else text), e.g. recheck_ticks=100")
    ap.add_argument("--comm", action="append", default=[], metavar="KEY=VALUE",
                    help="a [comm] setting (repeatable), e.g. map_zlib_level=1")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--spawn", default="together", choices=["together", "random"],
                    help="robots spawned together (default) or at random over the map")
    ap.add_argument("--ticks", type=int, default=300)
    ap.add_argument("--explored", type=float, default=None, help="run to this explored fraction instead")
    ap.add_argument("--max-ticks", type=int, default=20_000, help="the cap of an --explored run")
    ap.add_argument("--top", type=int, default=4, help="how many of the loop's costs to show")
    ap.add_argument("--pairs", type=int, default=1, help="repeat the rows, alternating their order, and print each "
                    "row's median us per robot-tick and its ratio to the first row's")
    ap.add_argument("--json", type=Path, default=None, help="write every row's figures here")
    ap.add_argument("--progress", type=float, default=0.0, metavar="SECONDS",
                    help="each child prints its tick, explored fraction and RSS to stderr every SECONDS of CPU")
    ap.add_argument("--limit-gb", type=float, default=None,
                    help="stop a row whose resident memory passes this many GB (default: 80 %% of the machine's)")
    ap.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--robots-n", type=int, default=16, help=argparse.SUPPRESS)
    ap.add_argument("--size", type=int, default=150, help=argparse.SUPPRESS)
    args = ap.parse_args()
    args.limit_gb = memory_limit_gb(None if args.limit_gb is None else str(args.limit_gb))
    if args.child:
        args.robots = args.robots_n
        child(args)
        return
    if args.ticks < 1 or args.max_ticks < 1 or args.density <= 0 or args.pairs < 1 or args.limit_gb <= 0:
        ap.error("--ticks, --max-ticks and --pairs must be >= 1, --density and --limit-gb > 0")
    params_of(args.param)  # a malformed item: one line now, not one per row
    params_of(args.comm, "--comm")
    rows = [parse_row(text, args.density) for text in args.robots]
    kinds = [args.kind] + (["cave"] if args.cave and args.kind != "cave" else [])
    print(f"{'robots':>6} {'map':>8} {'tiles':>5} {'ticks':>6} {'ticks/s':>9} {'us/r-t':>9} {'RSS MB':>8} "
          f"{'explored':>7}  biggest costs (share of the loop's CPU)", flush=True)
    out = []
    for k in range(args.pairs):
        order = rows if k % 2 == 0 else rows[::-1]  # alternate, so drift in the machine's speed cancels
        for kind in kinds:
            for robots, size in order:
                row = run_row(args, robots, size, kind)
                if row is not None:
                    show(row, args.top)
                    out.append(row)
    if args.pairs > 1:
        ratios(out, rows[0])
    if args.json is not None:
        args.json.write_text(json.dumps(out, indent=1))


def ratios(out: list[dict], first: tuple[int, int]) -> None:
    """Per row, the median us per robot-tick over the repeats and its ratio to the first row's, pair by pair
    (the runs of one repeat were taken back to back)."""
    import statistics

    def per(row: dict) -> float:
        return 1e6 * row["cpu_s"] / max(row["ticks"] * row["robots"], 1)

    keys = sorted({(r["robots"], r["size"], r["kind"]) for r in out}, key=lambda k: (k[2], k[0], k[1]))
    for key in keys:
        base_key = (first[0], first[1], key[2])
        mine = [per(r) for r in out if (r["robots"], r["size"], r["kind"]) == key]
        base = [per(r) for r in out if (r["robots"], r["size"], r["kind"]) == base_key]
        pairs = sorted(a / b for a, b in zip(mine, base))
        print(f"{key[0]:>6} {key[2]:>8} {key[1]:>5}: {statistics.median(mine):.1f} us per robot-tick (median of "
              f"{len(mine)}), {statistics.median(pairs):.2f}x the {first[0]}-robot row (range "
              f"{pairs[0]:.2f}-{pairs[-1]:.2f})", flush=True)


if __name__ == "__main__":
    main()
