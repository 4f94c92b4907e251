"""Digests of fixed runs in the Minotaur paper's set-up, to prove an algorithm optimisation changed no result.

    python benchmarks/paper_digests.py > before.txt     # on the old code (PYTHONPATH=../old-checkout)
    python benchmarks/paper_digests.py > after.txt      # on the new code
    diff before.txt after.txt                           # must print nothing

``result_digests.py`` covers every built-in algorithm with their defaults; this covers the explorers whose
decisions issue 35 made cheaper (TNF, Minotaur, Greed) as examples/minotaur-paper.toml and
examples/minotaur-ablation.toml run them: the MAES motion preset, a 7 m lidar, TNF with alpha = 1 and
beta = 10, both ``variant`` values of TNF and Minotaur, buildings and caves, 16 robots spawned together on
150 tiles (the first ticks, where most decisions are), small teams to the end of exploration (98 %),
spawned at random, under line-of-sight and material-aware radio; and a few xBOA runs. Same line format
as result_digests.py. About a minute of CPU.
"""

from __future__ import annotations

import argparse
from typing import Any

from result_digests import MAES_MOTION, digest

from swarm.sim.loop import Simulation

PAPER_RUN = {"motion": MAES_MOTION, "lidar": {"range_m": 7.0}}
TNF = {"name": "tnf", "params": {"alpha": 1.0, "beta": 10.0}}
TNF_MAES = {"name": "tnf", "params": {"alpha": 1.0, "beta": 10.0, "variant": "maes"}}
MINOTAUR = {"name": "minotaur"}
MINOTAUR_MAES = {"name": "minotaur", "params": {"variant": "maes"}}


def paper(seed: int, kind: str, size: int, robots: int, spawn: str, algorithm: dict, ticks: int,
          radio: str = "global") -> dict[str, Any]:
    """A run of the paper's campaign grid with its [run] and [stop] set-up, cut at ``ticks``."""
    return {"seed": seed, "map": {"kind": kind, "size": size}, "robots": {"count": robots, "spawn": spawn},
            "algorithm": algorithm, "radio": {"model": radio}, **PAPER_RUN,
            "stop": {"explored": 0.98, "max_ticks": ticks}}


SPECS: dict[str, dict[str, Any]] = {
    "tnf16_b150": paper(21, "building", 150, 16, "together", TNF, 1500),
    "tnf16_c150": paper(22, "cave", 150, 16, "together", TNF, 1500),
    "tnf_maes16_b150": paper(23, "building", 150, 16, "together", TNF_MAES, 1500),
    "tnf_maes16_c150": paper(24, "cave", 150, 16, "together", TNF_MAES, 1500),
    "tnf4_b50_los_end": paper(25, "building", 50, 4, "random", TNF, 36000, "los"),
    "tnf_maes2_c50_end": paper(26, "cave", 50, 2, "random", TNF_MAES, 36000, "multiwall"),
    "minotaur16_b150": paper(31, "building", 150, 16, "together", MINOTAUR, 1500),
    "minotaur16_c150": paper(32, "cave", 150, 16, "together", MINOTAUR, 1500),
    "minotaur_maes16_b150": paper(33, "building", 150, 16, "together", MINOTAUR_MAES, 1500),
    "minotaur_maes16_c150": paper(34, "cave", 150, 16, "together", MINOTAUR_MAES, 1500),
    "minotaur4_c50_multiwall_end": paper(35, "cave", 50, 4, "random", MINOTAUR, 36000, "multiwall"),
    "minotaur_maes2_b50_los_end": paper(36, "building", 50, 2, "random", MINOTAUR_MAES, 36000, "los"),
    "greed16_b150": paper(41, "building", 150, 16, "together", {"name": "greed"}, 1500),
    "greed8_c100_end": paper(42, "cave", 100, 8, "random", {"name": "greed"}, 36000, "multiwall"),
    # xBOA is not in the paper's campaign; its decisions were made cheaper too: 1 m tiles, decisions on the
    # 0.5 m cells themselves, and a 180 degree fan with two goals per plan (headings count)
    "xboa4_b50": paper(51, "building", 50, 4, "together", {"name": "xboa"}, 600),
    "xboa4_b50_cells": paper(52, "building", 50, 4, "together", {"name": "xboa", "params": {"tile_cells": 1}}, 600),
    "xboa3_c50_fov180_goals2": paper(53, "cave", 50, 3, "random",
                                     {"name": "xboa", "params": {"fov_deg": 180.0, "n_goals": 2}}, 600),
}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("names", nargs="*", metavar="NAME", help=f"specs to run (default all): {', '.join(SPECS)}")
    args = ap.parse_args()
    for name in args.names:
        if name not in SPECS:
            ap.error(f"NAME: got {name!r}; allowed: {', '.join(SPECS)}")
    for name in args.names or SPECS:
        r = Simulation(SPECS[name]).run()
        s = r.summary
        print(name, digest(s, r.timeseries, r.events), s["ticks"], s["explored"], sum(s["plans"]), flush=True)


if __name__ == "__main__":
    main()
