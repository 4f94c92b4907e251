"""Minotaur (MAES variant) against Greed under full MAES parity: ticks to 98 % and their ratio per map.

    python benchmarks/experiments/minotaur_greed_ratio.py --seeds 6

16 robots spawned together on 50-tile buildings (the cell of finding B16a), MAES motion, 7 m lidar, MAES's
radio and heartbeat merge, links judged at receipt. Seeds 1..N are not the ablation's maps: a quick,
indicative check of what a change to the MAES variants does (docs/maes.md section 11.1), not a study.
"""

from __future__ import annotations

import argparse
import statistics
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from result_digests import MAES_MOTION  # noqa: E402

from swarm.sim.loop import Simulation  # noqa: E402

ALGORITHMS = {"minotaur": {"name": "minotaur", "params": {"variant": "maes"}}, "greed": {"name": "greed"}}


def ticks(seed: int, algorithm: dict) -> int:
    """Ticks to 98 % explored (or the 36,000-tick limit) of one full-parity run."""
    spec = {"map": {"kind": "building", "size": 50}, "robots": {"count": 16, "spawn": "together"},
            "algorithm": algorithm, "seed": seed, "motion": MAES_MOTION, "lidar": {"range_m": 7.0},
            "radio": {"model": "maes"}, "comm": {"map_sharing": "maes", "link_at": "receive"},
            "stop": {"max_ticks": 36000, "explored": 0.98}}
    return int(Simulation(spec).run().summary["ticks"])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seeds", type=int, default=6, help="maps (seeds 1..N)")
    args = ap.parse_args()
    ratios = []
    print("seed minotaur greed ratio")
    for seed in range(1, args.seeds + 1):
        m, g = ticks(seed, ALGORITHMS["minotaur"]), ticks(seed, ALGORITHMS["greed"])
        ratios.append(m / g)
        print(seed, m, g, round(m / g, 2), flush=True)
    print("median ratio", round(statistics.median(ratios), 2))


if __name__ == "__main__":
    main()
