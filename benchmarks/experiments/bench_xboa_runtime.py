"""xBOA and the IBOA planner inside the runtime (issue 8): decision cost, planner quality, parameter sweeps.

    python benchmarks/experiments/bench_xboa_runtime.py decisions --size 50 --robots 1 4 --seeds 3 [--ticks N] [--param k=v]
    python benchmarks/experiments/bench_xboa_runtime.py planner --size 50 --seeds 3
    python benchmarks/experiments/bench_xboa_runtime.py navrun --size 50 --seeds 3
    python benchmarks/experiments/bench_xboa_runtime.py sweep --robots 4 --param overlap_penalty=false

``decisions``: xBOA runs; per-decision wall time from ``Action.debug["decision_ms"]`` (mean, p95, max) and
the modes. ``planner``: every plan request the navigator makes in frontier runs (first 4000 ticks) is
replayed with A* and with the IBOA plug-in; lengths after the navigator's own line-of-sight shortcutting,
and IBOA's polyline against the optimal 8-connected length. ``navrun``: ticks to 99 % with each planner.
``sweep``: ticks to 99 % per seed for one parameter set.
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from swarm import grid
from swarm.cli.options import parse_params
from swarm.sim.loop import Simulation
from swarm.sim.spec import derive_seed


def spec(size: int, robots: int, seed: int, algorithm: str = "xboa", params: dict | None = None,
         max_ticks: int = 36000, **extra) -> dict:
    """The same maps and spawns as benchmarks/experiments/compare.py."""
    return {"seed": derive_seed(seed, "run"),
            "map": {"kind": "building", "size": size, "seed": derive_seed(seed, "building", size)},
            "robots": {"count": robots, "spawn": "together",
                       "spawn_seed": derive_seed(seed, "building", size, "spawn")},
            "algorithm": {"name": algorithm, "params": params or {}}, "stop": {"max_ticks": max_ticks}, **extra}


def _cpu_timed() -> list[float]:
    """Wrap XBOA._decide to record its CPU time (ms): the machine is shared, so wall time per decision is
    inflated by other processes; CPU time is the decision's own cost."""
    from algorithms import xboa

    cpu: list[float] = []
    inner = xboa.XBOA._decide

    def timed(self, obs, left):
        t0 = time.process_time()
        out = inner(self, obs, left)
        cpu.append(1000 * (time.process_time() - t0))
        return out

    xboa.XBOA._decide = timed
    return cpu


def decisions(args: argparse.Namespace) -> None:
    params = parse_params(tuple(args.param))
    cpu = _cpu_timed()
    for robots in args.robots:
        cpu.clear()
        ms: list[float] = []
        modes: dict[str, int] = {}
        lines = []
        for seed in range(args.seeds):
            def observe(view, ms=ms, modes=modes):
                for a in view.actions:
                    if a is not None and a.debug and "decision_ms" in a.debug:
                        ms.append(a.debug["decision_ms"])
                        modes[a.debug["mode"]] = modes.get(a.debug["mode"], 0) + 1
            t0 = time.perf_counter()
            r = Simulation(spec(args.size, robots, seed, params=params, max_ticks=args.ticks),
                           observers=[observe]).run()
            lines.append(f"  seed {seed}: {r.one_line()} ({time.perf_counter() - t0:.0f} s)")
        a, c = np.array(ms), np.array(cpu)
        print(f"building {args.size}, {robots} robot(s), params {params}: {len(a)} decisions; wall mean "
              f"{a.mean():.1f} ms, p95 {np.percentile(a, 95):.1f} ms, max {a.max():.1f} ms; CPU mean {c.mean():.1f} ms, "
              f"p95 {np.percentile(c, 95):.1f} ms, max {c.max():.1f} ms; {modes}")
        print("\n".join(lines))


class _Recorder:
    name = "recorder"

    def __init__(self) -> None:
        self.requests: list[tuple[np.ndarray, tuple[int, int], tuple[int, int]]] = []

    def plan(self, space, start, goal, rng):
        self.requests.append((space.copy(), start, goal))
        return grid.plan(space, start, goal)


def planner(args: argparse.Namespace) -> None:
    from algorithms.boa.pathplan import IBOAPlannerParams
    from algorithms.boa.planner_plugin import IBOAPlanner, IBOAPlannerSettings, path_length_cells

    requests = []
    for seed in range(args.seeds):
        sim = Simulation(spec(args.size, 1, seed, "frontier", max_ticks=4000))
        rec = _Recorder()
        sim.navigators[0].planner = rec
        sim.run()
        requests += rec.requests
    base = [(grid.path_length_m(grid.simplify(s, grid.plan(s, a, b))), 0.5 * path_length_cells(grid.plan(s, a, b)))
            for s, a, b in requests]
    print(f"{len(requests)} plan requests from frontier runs on {args.seeds} building(s) of {args.size} m")
    for name, settings in (("runtime default (pop 30 x 30 gen)", IBOAPlannerSettings()),
                           ("paper-size budget (pop 60 x 50 gen)", IBOAPlannerSettings(iboa=IBOAPlannerParams()))):
        pl = IBOAPlanner(settings)
        rng = np.random.default_rng(0)
        after, raw, times = [], [], []
        for (s, a, b), (nav_astar, grid_astar) in zip(requests, base):
            t0 = time.perf_counter()
            path = pl.plan(s, a, b, rng)
            times.append(1000 * (time.perf_counter() - t0))
            if nav_astar > 0:
                after.append(grid.path_length_m(grid.simplify(s, path)) / nav_astar)
                if pl.last_waypoints is not None:
                    raw.append(0.5 * path_length_cells(np.array(pl.last_waypoints)) / grid_astar)
        t = np.array(times)
        print(f"{name}: after the navigator's shortcutting IBOA/A* mean {np.mean(after):.3f}, "
              f"max {np.max(after):.3f}, share > 1.01: {np.mean(np.array(after) > 1.01):.1%}; "
              f"IBOA's simplified polyline / optimal 8-connected length mean {np.mean(raw):.3f}, max {np.max(raw):.3f}; "
              f"ms per plan mean {t.mean():.0f}, p95 {np.percentile(t, 95):.0f}, max {t.max():.0f}; {pl.stats}")


def navrun(args: argparse.Namespace) -> None:
    for algorithm in ("frontier", "xboa"):
        for planner_name in ("astar", "iboa"):
            ticks, walls = [], []
            for seed in range(args.seeds):
                t0 = time.perf_counter()
                r = Simulation(spec(args.size, 1, seed, algorithm, navigation={"planner": planner_name})).run()
                walls.append(time.perf_counter() - t0)
                ticks.append(r.summary["ticks_to"]["0.99"] or 36000)
            print(f"{algorithm} + {planner_name}: ticks to 99 % mean {statistics.mean(ticks):.0f} {ticks}, "
                  f"wall {statistics.mean(walls):.1f} s per run")


def sweep(args: argparse.Namespace) -> None:
    """Ticks to 99 % per seed with benchmarks/experiments/compare.py's run_one (same maps and spawns), 2 workers."""
    import sys
    from multiprocessing import Pool
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parent))  # compare.py sits beside this script
    from compare import run_one

    params = parse_params(tuple(args.param))
    cells = [(args.algorithm, "building", args.size, args.robots, "multiwall", seed, 0.99, 36000,
              {"algorithm": {"name": args.algorithm, "params": params}}) for seed in range(args.seeds)]
    with Pool(2) as pool:
        rows = pool.map(run_one, cells, chunksize=1)
    ticks = [r[6] if r[7] == "explored" else 36000 for r in rows]
    print(f"{args.algorithm} {params}, {args.robots} robot(s): mean {statistics.mean(ticks):.0f} {ticks}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    d = sub.add_parser("decisions")
    d.add_argument("--size", type=int, default=50)
    d.add_argument("--robots", type=int, nargs="+", default=[1, 4])
    d.add_argument("--seeds", type=int, default=3)
    d.add_argument("--ticks", type=int, default=36000)
    d.add_argument("--param", action="append", default=[])
    for name in ("planner", "navrun"):
        p = sub.add_parser(name)
        p.add_argument("--size", type=int, default=50)
        p.add_argument("--seeds", type=int, default=3)
    w = sub.add_parser("sweep")
    w.add_argument("--algorithm", default="xboa")
    w.add_argument("--size", type=int, default=50)
    w.add_argument("--robots", type=int, default=1)
    w.add_argument("--seeds", type=int, default=5)
    w.add_argument("--param", action="append", default=[])
    args = ap.parse_args()
    {"decisions": decisions, "planner": planner, "navrun": navrun, "sweep": sweep}[args.cmd](args)


if __name__ == "__main__":
    main()
