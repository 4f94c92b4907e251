"""IBOA path planning quality (IBOA (Kent) grid planner, IBOA (Lévy) continuous planner; docs/papers.md).

Grid planner: on N seeded maps (half ``building``, half ``cave``, 50 x 50 tiles: a tile is blocked when any
of its 0.5 m cells is solid), one random start/goal pair per map in the largest 4-connected free region
(at least 20 tiles apart). For each map: the optimal 8-connected A* length, the any-angle optimum (the
physical limit), and the IBOA (and plain BOA) planner's grid path, paper-simplified path and
line-of-sight-pulled path, as ratios to the any-angle optimum; milliseconds and evaluations per plan.

Continuous planner: random scenes of circular obstacles, IBOA-Levy (and BOA, xBOA) with the sign-fixed
penalty at w = 10 (paper), 100 and 1000: mean length, fraction of collision-free results, min clearance.

    python benchmarks/experiments/bench_boa_pathplan.py            # 20 maps, ~1 min
    python benchmarks/experiments/bench_boa_pathplan.py --quick    # 6 maps
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np
from scipy.ndimage import label

from algorithms.boa.pathplan import IBOAPlannerParams, plan_iboa, simplify_los
from algorithms.boa.pathplan_levy import LevyPlannerParams, plan_levy
from algorithms.boa.shortest import any_angle_length, astar_length, path_length
from maps import generate


def tile_grid(kind: str, seed: int, size: int) -> np.ndarray:
    s = generate(kind, size, seed=seed).solid
    return s.reshape(size, 2, size, 2).any(axis=(1, 3))


def pair(g: np.ndarray, rng: np.random.Generator) -> tuple[tuple[int, int], tuple[int, int]]:
    lab, _ = label(~g)
    big = np.argmax(np.bincount(lab.ravel())[1:]) + 1
    free = np.argwhere(lab == big)
    while True:
        a, b = free[rng.choice(len(free), 2, replace=False)]
        if abs(a[0] - b[0]) + abs(a[1] - b[1]) >= 20:
            return (int(a[0]), int(a[1])), (int(b[0]), int(b[1]))


def grid_bench(n_maps: int, size: int) -> None:
    print(f"\n### Grid planner, {n_maps} maps of {size} x {size} tiles (ratios to the any-angle optimum)\n")
    print("| map | A* | any-angle | IBOA grid | IBOA simplified | IBOA + LOS | BOA simplified | IBOA ms | IBOA evals |")
    print("|---|---|---|---|---|---|---|---|---|")
    rows = []
    for i in range(n_maps):
        kind = "building" if i % 2 == 0 else "cave"
        seed = i // 2
        g = tile_grid(kind, seed, size)
        a, b = pair(g, np.random.default_rng(1000 + i))
        A = astar_length(g, a, b)
        AA = any_angle_length(g, a, b)
        t0 = time.perf_counter()
        p = plan_iboa(g, a, b, np.random.default_rng(i))
        ms = (time.perf_counter() - t0) * 1000
        los = path_length(simplify_los(g, list(p.waypoints)))
        q = plan_iboa(g, a, b, np.random.default_rng(i), IBOAPlannerParams(variant="BOA"))
        r = (A / AA, p.grid_length / AA, p.length / AA, los / AA, q.length / AA, ms, p.nfev)
        rows.append(r)
        print(f"| {kind} {seed} | {r[0]:.3f} | {AA:.1f} | {r[1]:.3f} | {r[2]:.3f} | {r[3]:.3f} | {r[4]:.3f} "
              f"| {ms:.0f} | {p.nfev} |", flush=True)
    m = np.mean(rows, axis=0)
    print(f"| **mean** | {m[0]:.3f} | | {m[1]:.3f} | {m[2]:.3f} | {m[3]:.3f} | {m[4]:.3f} | {m[5]:.0f} | {m[6]:.0f} |")


def continuous_bench(n_scenes: int) -> None:
    print(f"\n### Continuous planner, {n_scenes} random scenes of 6 circles in a 230 x 150 box\n")
    print("| optimiser | w | mean length / straight line | collision-free | min clearance | evals | ms |")
    print("|---|---|---|---|---|---|---|")
    scenes = []
    for s in range(n_scenes):
        rng = np.random.default_rng(s)
        obs = np.c_[rng.uniform(40, 190, 6), rng.uniform(20, 130, 6), rng.uniform(8, 20, 6)]
        scenes.append(obs)
    for variant in ("IBOA-Levy", "BOA", "xBOA"):
        for w in (10.0, 100.0, 1000.0):
            res = []
            for s, obs in enumerate(scenes):
                t0 = time.perf_counter()
                p = plan_levy(obs, (5, 5), (225, 145), ((0, 230), (0, 150)), np.random.default_rng(s),
                              LevyPlannerParams(variant=variant, penalty_weight=w))
                res.append((p.length / np.hypot(220, 140), p.clearance, p.nfev, (time.perf_counter() - t0) * 1000))
            a = np.array(res)
            print(f"| {variant} | {w:g} | {a[:, 0].mean():.3f} | {(a[:, 1] >= 0).mean() * 100:.0f} % "
                  f"| {a[:, 1].min():.2f} | {a[:, 2].mean():.0f} | {statistics.mean(a[:, 3]):.0f} |", flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--maps", type=int, default=None)
    ap.add_argument("--size", type=int, default=50)
    args = ap.parse_args()
    t = time.perf_counter()
    g = tile_grid("cave", 0, 30)
    plan_iboa(g, *pair(g, np.random.default_rng(0)), np.random.default_rng(0), IBOAPlannerParams(max_gen=2))  # warm-up
    grid_bench(args.maps or (6 if args.quick else 20), args.size)
    continuous_bench(3 if args.quick else 10)
    print(f"\ntotal {time.perf_counter() - t:.0f} s")


if __name__ == "__main__":
    main()
