"""Lidar cost per tick: ``python benchmarks/speed/bench_sensing.py [--kind building] [--size 150] [--calls 1000]
[--repeats 3]``.

16 robots at random free positions and headings (50 such swarms, cycled) on ``maps.generate(kind, size, 1)``.
Prints milliseconds per ``Lidar.scan`` call for R = 1 and R = 16, in ternary, noise-free log-odds and
noisy log-odds mode (mean over ``--calls`` calls after warm-up; best and worst of ``--repeats``
repetitions), plus the coverage update. Times are this process's CPU time (``time.process_time``): the
kernels are single-threaded, so on an idle machine that equals wall time, and on a shared machine it is
much less noisy. Goal: about 0.3 ms per tick for 16 robots (the numba DDA of docs/measurements.md C1).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from maps import generate
from swarm.knowledge.maps import ExplorationTracker, empty_knowledge
from swarm.world.sensing import Lidar, LidarParams, warm_up


def random_poses(free: np.ndarray, n: int, rng: np.random.Generator) -> np.ndarray:
    """``n`` poses uniformly inside random free cells, random headings."""
    cells = np.argwhere(free)
    pick = cells[rng.choice(len(cells), size=n, replace=False)]
    xy = (pick[:, ::-1] + rng.random((n, 2))) * 0.5
    return np.column_stack([xy, rng.uniform(-np.pi, np.pi, n)])


def time_scans(lidar: Lidar, pose_sets: list[np.ndarray], calls: int, rng: np.random.Generator) -> float:
    """Mean ms per scan, cycling through ``pose_sets`` so the swarm is somewhere else every call (a
    pessimistic case for the CPU caches compared with robots that move 0.1 m per tick)."""
    known = empty_knowledge(lidar.shape, len(pose_sets[0]))
    lidar.scan(pose_sets[0], known, rng)
    t0 = time.process_time()
    for k in range(calls):
        lidar.scan(pose_sets[k % len(pose_sets)], known, rng)
    return (time.process_time() - t0) * 1000.0 / calls


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--kind", choices=("building", "cave"), default="building")
    ap.add_argument("--size", type=int, default=150)
    ap.add_argument("--calls", type=int, default=1000)
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    t0 = time.process_time()
    warm_up()
    print(f"warm_up: {1000 * (time.process_time() - t0):.0f} ms (includes loading numba's cache)")
    truth = generate(args.kind, args.size, 1)
    rng = np.random.default_rng(1)
    pose_sets = [random_poses(truth.free, 16, rng) for _ in range(50)]
    configs = [("ternary", LidarParams()),
               ("logodds", LidarParams(mode="logodds")),
               ("logodds+noise", LidarParams(mode="logodds", noise_std=0.05))]
    print(f"{args.kind} {args.size}x{args.size} ({truth.shape[1]}x{truth.shape[0]} cells), "
          f"range {LidarParams().range_m:g} m, auto rays {LidarParams().n_rays}")
    for name, params in configs:
        for n in (1, 16):
            times = []
            for _ in range(args.repeats):
                lidar = Lidar(truth, params)
                times.append(time_scans(lidar, [p[:n] for p in pose_sets], args.calls, np.random.default_rng(2)))
            print(f"  {name:14s} R={n:2d}: {min(times):.3f} ms/scan best, {max(times):.3f} worst "
                  f"({args.calls} calls x {args.repeats})")
    tracker = ExplorationTracker(truth)
    xy = np.ascontiguousarray(pose_sets[0][:, :2])
    tracker.update_coverage(xy)
    t0 = time.process_time()
    for _ in range(args.calls):
        tracker.update_coverage(xy)
    print(f"  coverage update R=16: {1000 * (time.process_time() - t0) / args.calls:.4f} ms/call")


if __name__ == "__main__":
    main()
