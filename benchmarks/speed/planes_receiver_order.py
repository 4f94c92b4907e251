"""How a merge through the knowledge planes costs with its receivers' bits spread or consecutive.

``python benchmarks/speed/planes_receiver_order.py [--receivers 5 10 20 40] [--reps 5]``

A relayed delta of a spread-out swarm (~26,000 cells in a 200 x 200-cell square, 65 % of it) is merged
into k receivers of 1,000 robots on a 1,200 x 1,200-cell map, each of which already holds 90 % of the
delta, through :func:`swarm.knowledge.planes.merge_into_many`. The receivers are drawn at random (the bits
of a delta's receivers in a run: robot ids) or as k consecutive robots (what an order of the planes' bits
by place would approach, since a delta reaches its sender's radio neighbours). Prints ms per merge,
alternating the two, for each k. The planes' cost per cell grows with the 64-robot words its receivers
touch; this measures how much a spatial order could save before building one (docs/performance.md).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from swarm.knowledge.planes import KnowledgePlanes, merge_into_many, note_map


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--receivers", type=int, nargs="+", default=[5, 10, 20, 40])
    ap.add_argument("--reps", type=int, default=5, help="merges per way and count (after one warm-up each)")
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()
    if args.reps < 1 or any(k < 1 or k > 1000 for k in args.receivers):
        ap.error("--reps must be >= 1 and each --receivers count in 1..1000")
    rng = np.random.default_rng(args.seed)
    n, h, w = 1000, 1200, 1200
    known = np.zeros((n, h, w), np.uint8)  # resident only where written
    planes = KnowledgePlanes(n, h * w)
    counts = np.zeros(n, np.int64)
    dirty = np.zeros((n, -(-h // 32), -(-w // 32)), np.uint8)

    def delta() -> tuple[np.ndarray, np.ndarray]:
        r0, c0 = rng.integers(0, h - 200), rng.integers(0, w - 200)
        rows, cols = np.meshgrid(np.arange(r0, r0 + 200), np.arange(c0, c0 + 200), indexing="ij")
        cells = (rows * w + cols).reshape(-1)
        idx = np.sort(cells[rng.random(cells.size) < 0.65]).astype(np.int64)
        return idx, np.where(rng.random(idx.size) < 0.8, 1, 2).astype(np.uint8)

    print(f"{'receivers':>9}  {'random ms':>24}  {'consecutive ms':>24}")
    for k in args.receivers:
        times: dict[str, list[float]] = {"random": [], "consecutive": []}
        for rep in range(2 * (args.reps + 1)):
            way = "random" if rep % 2 == 0 else "consecutive"
            idx, values = delta()
            if way == "random":
                robots = np.sort(rng.choice(n, k, replace=False)).astype(np.int64)
            else:
                start = int(rng.integers(0, n - k + 1))
                robots = np.arange(start, start + k, dtype=np.int64)
            for r in robots:  # each receiver holds 90 % of the delta already
                part = idx[rng.random(idx.size) < 0.9]
                known[r].reshape(-1)[part] = values[np.searchsorted(idx, part)]
                note_map(planes.free, planes.solid, known[r].reshape(-1), r)
            t = time.perf_counter()
            merge_into_many(known, planes.free, planes.solid, planes.mask(robots), idx, values, counts, dirty, 32)
            times[way].append(time.perf_counter() - t)
        cols = ["  ".join(f"{1e3 * x:5.2f}" for x in times[way][1:]) for way in ("random", "consecutive")]
        print(f"{k:>9}  {cols[0]:>24}  {cols[1]:>24}", flush=True)


if __name__ == "__main__":
    main()
