"""Per-decision cost of the xBOA exploration fitness: wall time, fitness evaluations and peak memory.

Workloads:
* the paper's house map (24 x 24, 1 m cells) at the start pose and at mid-mission beliefs;
* a 150 x 150-tile building (``maps.generate("building", 150, seed)``) as a 300 x 300 belief of 0.5 m
  cells (the runtime's knowledge map) with 0 %, ~15 % and ~50 % of it known, and the same map as a
  150 x 150 belief of 1 m tiles.
For each: gain-table construction alone, then whole decisions (xBOA pop 20 / pop 5, short-term; xBOA pop
20 long-term K = 3) in table and lazy modes. Peak memory is what ``tracemalloc`` sees during one decision
(every work array is allocated in Python, so the kernels' memory is included); times are taken without
tracing.

    python benchmarks/speed/bench_boa_fitness.py            # ~1 min
    python benchmarks/speed/bench_boa_fitness.py --reps 5
"""

from __future__ import annotations

import argparse
import statistics
import time
import tracemalloc

import numpy as np

from algorithms.boa.beams import NORTH, Lidar
from algorithms.boa.decision import DecisionParams, decide
from algorithms.boa.fitness import Belief, ExplorationProblem
from algorithms.boa.gridworld import load_xboa_csv, paper_map_path, scan
from maps import generate


def measure(fn, reps: int) -> tuple[float, float, float]:
    """(median ms, min ms, peak MB): timed over ``reps`` calls after a warm-up call, then one more call
    under ``tracemalloc`` for the peak (tracing slows allocation down, so it is not timed)."""
    fn(0)
    times = []
    for r in range(reps):
        t0 = time.perf_counter()
        fn(r + 1)
        times.append((time.perf_counter() - t0) * 1000)
    tracemalloc.start()
    fn(reps + 1)
    peak = tracemalloc.get_traced_memory()[1] / 2**20
    tracemalloc.stop()
    return statistics.median(times), min(times), peak


def bench_belief(label: str, belief: Belief, cell: tuple[int, int], battery: int, reps: int) -> None:
    H, W = belief.shape
    for mode in ("table", "lazy"):
        ms, lo, mb = measure(lambda r: ExplorationProblem(belief, cell, NORTH, battery, mode=mode).gain_table(), reps)
        print(f"| {label} | gain table for all {H * W} goals ({mode}) | {ms:.1f} ({lo:.1f}) | {H * W} | {mb:.1f} |")
    for variant, pop, k, mode in (("xBOA", 20, 1, "table"), ("xBOA", 20, 1, "lazy"), ("xBOA", 5, 1, "lazy"),
                                  ("BOA", 20, 1, "lazy"), ("xBOA", 20, 3, "lazy")):
        prm = DecisionParams(variant=variant, pop_size=pop, n_goals=k, fitness_mode=mode, retries=0)
        nfev = []

        def one(r: int) -> None:
            nfev.append(decide(belief, cell, NORTH, battery, prm, np.random.default_rng(r)).nfev)

        ms, lo, mb = measure(one, reps)
        what = f"decision {variant} pop {pop} {'short' if k == 1 else f'long K={k}'} ({mode})"
        print(f"| {label} | {what} | {ms:.1f} ({lo:.1f}) | {statistics.mean(nfev):.0f} | {mb:.1f} |", flush=True)


def house_beliefs() -> list[tuple[str, Belief, tuple[int, int]]]:
    path = paper_map_path("house")
    if path is None:
        return []
    truth = load_xboa_csv(path)
    tables = Lidar().tables(1.0)
    out = []
    L = np.zeros(truth.shape)
    scan(truth, L, 1, 1, NORTH, tables, np.random.default_rng(0), 0.05)
    out.append(("house 24x24, start", Belief.from_logodds(L), (1, 1)))
    for (r, c, h) in [(3, 3, 1), (6, 5, 2), (9, 6, 2), (12, 8, 0), (12, 12, 0), (14, 13, 2)]:
        scan(truth, L, r, c, h, tables, np.random.default_rng(r), 0.05)
    out.append(("house 24x24, mid-mission", Belief.from_logodds(L), (14, 13)))
    return out


def big_beliefs(seed: int) -> list[tuple[str, Belief, tuple[int, int]]]:
    solid = generate("building", 150, seed=seed).solid                 # 300 x 300 cells of 0.5 m
    H, W = solid.shape
    free = np.argwhere(~solid)
    start = tuple(int(v) for v in free[np.argmin(np.abs(free - np.array([H // 2, W // 2])).sum(1))])
    yy, xx = np.mgrid[0:H, 0:W]
    out = []
    for radius, name in ((0, "0 % known"), (65, "~15 % known"), (120, "~50 % known")):
        known = (yy - start[0]) ** 2 + (xx - start[1]) ** 2 <= radius ** 2
        out.append((f"building 300x300 @0.5 m, {name}", Belief(~known, known & solid, 0.5), start))
    tiles = solid.reshape(150, 2, 150, 2).any(axis=(1, 3))
    tstart = (start[0] // 2, start[1] // 2)
    tiles[tstart] = False
    known = (np.mgrid[0:150, 0:150][0] - tstart[0]) ** 2 + (np.mgrid[0:150, 0:150][1] - tstart[1]) ** 2 <= 60 ** 2
    out.append(("building 150x150 @1 m, ~50 % known", Belief(~known, known & tiles, 1.0), tstart))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--seed", type=int, default=3)
    args = ap.parse_args()
    print("| belief | work | ms median (min) | fitness evaluations | peak MB |\n|---|---|---|---|---|")
    for label, belief, cell in house_beliefs():
        bench_belief(label, belief, cell, 300, args.reps)
    for label, belief, cell in big_beliefs(args.seed):
        bench_belief(label, belief, cell, 100_000, args.reps)


if __name__ == "__main__":
    main()
