"""Interleaved A/B of the runtime benchmark: ``python benchmarks/speed/ab_runtime.py BASE [--pairs 6] [-- ARGS]``.

Runs ``benchmarks/speed/bench_runtime.py`` alternately from another checkout ``BASE`` (say a ``git worktree`` of
the previous release) and from this one, each run in a fresh process with that checkout first on
``PYTHONPATH``, and reports every pair, the median of the run-time ratios (this / base) and the best run
of each side. On a machine whose speed drifts by +-15 % within minutes (and by up to 2x on a bad day)
only pairs taken back to back say whether a change made the code faster. Arguments after ``--`` go to
both runs (``-- --max-ticks 3000``). The first run of a checkout whose numba caches are cold compiles
every kernel; run each side once before measuring (``--warm``).
"""

from __future__ import annotations

import argparse
import os
import re
import statistics
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parents[2]
LINE = re.compile(r"run ([0-9.]+) s wall")


def bench_script(checkout: Path) -> Path:
    """The runtime benchmark of ``checkout``: ``benchmarks/speed/`` now, ``benchmarks/`` in older releases."""
    moved = checkout / "benchmarks" / "speed" / "bench_runtime.py"
    return moved if moved.is_file() else checkout / "benchmarks" / "bench_runtime.py"


def run(checkout: Path, args: list[str]) -> float:
    """Run-loop wall seconds of one bench_runtime.py run from ``checkout``."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [str(checkout), os.environ.get("PYTHONPATH")])))
    child = subprocess.run([sys.executable, str(bench_script(checkout)), *args], cwd=checkout,
                           env=env, capture_output=True, text=True)
    if child.returncode != 0:  # the run's own error (a bad argument, say), as bench_runtime.py --repeat shows it
        sys.stderr.write(child.stderr)
        raise SystemExit(child.returncode)
    out = child.stdout
    m = LINE.search(out)
    if m is None:
        raise SystemExit(f"{checkout}: bench_runtime.py printed no run time:\n{out}")
    return float(m.group(1))


def main() -> None:
    argv = sys.argv[1:]
    extra = argv[argv.index("--") + 1:] if "--" in argv else []
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("base", type=Path, help="the other checkout (its benchmarks/speed/bench_runtime.py is run; "
                    "benchmarks/bench_runtime.py in older releases)")
    ap.add_argument("--pairs", type=int, default=6)
    ap.add_argument("--warm", action="store_true", help="one unmeasured run of each side first (compiles kernels)")
    args = ap.parse_args(argv[:argv.index("--")] if "--" in argv else argv)
    base = args.base.resolve()
    if not bench_script(base).is_file():
        ap.error(f"base: {base} is not allowed; give a checkout of this project "
                 "(with benchmarks/speed/bench_runtime.py or benchmarks/bench_runtime.py)")
    if args.pairs < 1:
        ap.error(f"--pairs: {args.pairs} is not allowed; give a whole number >= 1")
    if args.warm:
        run(base, extra)
        run(HERE, extra)
    ratios, base_s, this_s = [], [], []
    for i in range(args.pairs):
        b = run(base, extra)
        t = run(HERE, extra)
        base_s.append(b)
        this_s.append(t)
        ratios.append(t / b)
        print(f"pair {i + 1}: base {b:.2f} s, this {t:.2f} s, ratio {t / b:.3f}", flush=True)
    print(f"median ratio {statistics.median(ratios):.3f} over {args.pairs} pairs (below 1: this checkout is faster); "
          f"best runs: base {min(base_s):.2f} s, this {min(this_s):.2f} s")


if __name__ == "__main__":
    main()
