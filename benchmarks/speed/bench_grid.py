"""Grid helper speed: ``python benchmarks/speed/bench_grid.py [--size 150] [--seed 1] [--repeats 50]``.

Builds a knowledge map from ``maps.generate("building", size, seed)`` (0.5 m cells, so 300 x 300 for
size 150) in two variants -- fully known (truth: FREE where free, SOLID where solid) and half known (the
right half of the map UNSEEN) -- and prints the mean and best milliseconds per call of each helper. The
plan is the long one: between the two drivable cells nearest opposite corners of the map. numba kernels
are compiled (or loaded from cache) before timing.
"""

from __future__ import annotations

import argparse
import statistics
import time
from typing import Any, Callable

import numpy as np

from maps import generate
from swarm.api import FREE, SOLID, UNSEEN
from swarm import grid


def knowledge_maps(size: int, seed: int) -> dict[str, np.ndarray]:
    truth = generate("building", size, seed).solid
    full = np.where(truth, SOLID, FREE).astype(np.uint8)
    half = full.copy()
    half[:, half.shape[1] // 2:] = UNSEEN
    return {"full": full, "half": half}


def timed(fn: Callable[[], Any], repeats: int) -> tuple[float, float]:
    fn()  # warm (compile / cache load, first-touch allocations)
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append((time.perf_counter() - t0) * 1000.0)
    return statistics.mean(times), min(times)


def corner_cells(space: np.ndarray) -> tuple[tuple[int, int], tuple[int, int]]:
    h, w = space.shape
    a = grid.nearest_in(space, (0, 0))
    b = grid.nearest_in(space, (h - 1, w - 1))
    assert a is not None and b is not None, "no drivable cell"
    return a, b


def bench(name: str, known: np.ndarray, repeats: int) -> None:
    space = grid.configuration_space(known)
    start, goal = corner_cells(space)
    if name == "half":  # keep the goal on the known side
        cols = np.nonzero(space.any(axis=0))[0]
        goal = grid.nearest_in(space, (known.shape[0] - 1, int(cols.max()))) or goal
    path = grid.plan(space, start, goal)
    rows: list[tuple[str, Callable[[], Any]]] = [
        ("configuration_space", lambda: grid.configuration_space(known)),
        ("plan (corner to corner)", lambda: grid.plan(space, start, goal)),
        ("C-space + plan", lambda: grid.plan(grid.configuration_space(known), start, goal)),
    ]
    if path is not None:
        rows.append(("simplify", lambda: grid.simplify(space, path)))
    rows += [
        ("distance_field (1 source)", lambda: grid.distance_field(space, start)),
        ("distance_field (max 10 m)", lambda: grid.distance_field(space, start, max_dist_m=10.0)),
        ("frontier_clusters", lambda: grid.frontier_clusters(known)),
        ("nearest_reachable_unseen", lambda: grid.nearest_reachable_unseen(known, start)),
    ]
    plen = "none" if path is None else f"{len(path)} cells, {grid.path_length_m(grid.simplify(space, path)):.1f} m"
    print(f"\n{name} ({known.shape[0]}x{known.shape[1]}, {int(space.sum())} drivable cells, path {plen}, "
          f"{len(grid.frontier_clusters(known))} frontier clusters)")
    for label, fn in rows:
        mean, best = timed(fn, repeats)
        print(f"  {label:28s} mean {mean:7.3f} ms   best {best:7.3f} ms")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--size", type=int, default=150, help="map size in tiles (1 m); cells = 2 x size")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--repeats", type=int, default=50)
    args = ap.parse_args()
    for name, known in knowledge_maps(args.size, args.seed).items():
        bench(name, known, args.repeats)


if __name__ == "__main__":
    main()
