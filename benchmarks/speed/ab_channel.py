"""What the stochastic channel costs: ``python benchmarks/speed/ab_channel.py [--rounds 6] [-- ARGS]``.

Runs ``benchmarks/speed/bench_runtime.py`` (16 robots, 150 x 150 building, frontier) in fresh processes,
round after round, once per variant: the default channel, shadowing with packet errors, flood relaying,
and all of them; reports each round and, per variant, the median and the range of its run-time ratio to
the default run of the same round (interleaved, so the machine's drifting speed cancels). Arguments after
``--`` go to every run (``-- --max-ticks 3000``). Run once with ``--rounds 1`` first if the numba caches
are cold.
"""

from __future__ import annotations

import argparse
import statistics
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from ab_runtime import HERE, run  # noqa: E402

VARIANTS: dict[str, list[str]] = {
    "default": [],
    "shadowing+per": ["--set", "radio.shadowing_sigma_db=4", "--set", "radio.per=bpsk"],
    "flood": ["--set", "comm.relay=flood"],
    "all": ["--set", "radio.shadowing_sigma_db=4", "--set", "radio.per=bpsk", "--set", "comm.relay=flood"],
}


def main() -> None:
    argv = sys.argv[1:]
    extra = argv[argv.index("--") + 1:] if "--" in argv else []
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--rounds", type=int, default=6)
    args = ap.parse_args(argv[:argv.index("--")] if "--" in argv else argv)
    if args.rounds < 1:
        ap.error(f"--rounds: {args.rounds} is not allowed; give a whole number >= 1")
    ratios: dict[str, list[float]] = {name: [] for name in VARIANTS if name != "default"}
    for k in range(args.rounds):
        times = {name: run(HERE, [*extra, *flags]) for name, flags in VARIANTS.items()}
        base = times["default"]
        for name in ratios:
            ratios[name].append(times[name] / base)
        print(f"round {k + 1}: " + ", ".join(f"{name} {t:.2f} s" for name, t in times.items()), flush=True)
    for name, values in ratios.items():
        print(f"{name}: median ratio to default {statistics.median(values):.3f} "
              f"(range {min(values):.3f}-{max(values):.3f} over {len(values)} rounds)")


if __name__ == "__main__":
    main()
