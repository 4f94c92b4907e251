"""What the stochastic channel costs: ``python benchmarks/speed/ab_channel.py [--rounds 6] [-- ARGS]``.

Runs ``benchmarks/speed/bench_runtime.py`` (16 robots, 150 x 150 building, frontier) in fresh processes,
round after round, once per variant: the default channel, shadowing with packet errors, flood relaying,
and all of them (in a rotated order each round); reports each round and, per variant, the median and the
range of its ratio of run-loop CPU seconds to the default run of the same round (interleaved, so the
machine's drifting speed mostly cancels; CPU rather than wall time because a shared machine stretches wall
time most). Arguments after ``--`` go to every run (``-- --max-ticks 3000``). Run once with ``--rounds 1``
first if the numba caches are cold.
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
LINE = re.compile(r"ticks (\d+)  run ([0-9.]+) s wall, ([0-9.]+) s CPU")

VARIANTS: dict[str, list[str]] = {
    "default": [],
    "shadowing+per": ["--set", "radio.shadowing_sigma_db=4", "--set", "radio.per=bpsk"],
    "flood": ["--set", "comm.relay=flood"],
    "all": ["--set", "radio.shadowing_sigma_db=4", "--set", "radio.per=bpsk", "--set", "comm.relay=flood"],
}


def run(args: list[str]) -> tuple[int, float, float]:
    """(ticks, wall s, CPU s) of one bench_runtime.py run of this checkout."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [str(HERE), os.environ.get("PYTHONPATH")])))
    child = subprocess.run([sys.executable, str(HERE / "benchmarks" / "speed" / "bench_runtime.py"), *args], cwd=HERE,
                           env=env, capture_output=True, text=True)
    if child.returncode != 0:
        sys.stderr.write(child.stderr)
        raise SystemExit(child.returncode)
    m = LINE.search(child.stdout)
    if m is None:
        raise SystemExit(f"bench_runtime.py printed no run time:\n{child.stdout}")
    return int(m.group(1)), float(m.group(2)), float(m.group(3))


def main() -> None:
    argv = sys.argv[1:]
    extra = argv[argv.index("--") + 1:] if "--" in argv else []
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--rounds", type=int, default=6)
    args = ap.parse_args(argv[:argv.index("--")] if "--" in argv else argv)
    if args.rounds < 1:
        ap.error(f"--rounds: {args.rounds} is not allowed; give a whole number >= 1")
    names = list(VARIANTS)
    ratios: dict[str, list[float]] = {name: [] for name in names if name != "default"}
    for k in range(args.rounds):
        order = names[k % len(names):] + names[:k % len(names)]
        runs = {name: run([*extra, *VARIANTS[name]]) for name in order}
        ticks, _, base = runs["default"]
        for name in ratios:
            if runs[name][0] != ticks:
                raise SystemExit(f"{name} ran {runs[name][0]} ticks, default {ticks}: set --max-ticks below the end")
            ratios[name].append(runs[name][2] / base)
        print(f"round {k + 1}: " + ", ".join(f"{name} {cpu:.2f} s CPU ({wall:.2f} s wall)"
                                             for name, (_, wall, cpu) in runs.items()), flush=True)
    for name, values in ratios.items():
        print(f"{name}: median CPU ratio to default {statistics.median(values):.3f} "
              f"(range {min(values):.3f}-{max(values):.3f} over {len(values)} rounds)")


if __name__ == "__main__":
    main()
