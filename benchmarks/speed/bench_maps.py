"""Map generation time: ``python benchmarks/speed/bench_maps.py [--size 150] [--seeds 20]``.

Prints mean / min / max milliseconds per map for cave and building at the given size.
"""

from __future__ import annotations

import argparse
import statistics
import time

from maps import generate


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--size", type=int, default=150)
    ap.add_argument("--seeds", type=int, default=20)
    args = ap.parse_args()
    generate("cave", 30, 0)  # warm imports
    for kind in ("cave", "building"):
        times = []
        for seed in range(args.seeds):
            t0 = time.perf_counter()
            generate(kind, args.size, seed)
            times.append((time.perf_counter() - t0) * 1000)
        print(f"{kind:8s} {args.size}x{args.size}: mean {statistics.mean(times):6.1f} ms  "
              f"min {min(times):6.1f}  max {max(times):6.1f}  ({args.seeds} seeds)")


if __name__ == "__main__":
    main()
