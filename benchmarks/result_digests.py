"""Digests of a fixed set of runs, to prove an optimisation changed no result bit.

    python benchmarks/result_digests.py > before.txt     # on the old code
    python benchmarks/result_digests.py > after.txt      # on the new code
    diff before.txt after.txt                            # must print nothing
    python benchmarks/result_digests.py --transport zenoh frontier16_b150   # same digests over zenoh

Each line: spec name, SHA-256 prefix of the summary (without wall/set-up times), time series and events,
ticks, explored fraction, plans. The specs cover every built-in algorithm, packet loss with a bandwidth
cap, full-map sharing, optimistic planning with a noisy log-odds lidar and the MAES motion preset.
About 25 s in all on one core.
"""

from __future__ import annotations

import argparse
import hashlib
import json
from typing import Any

from swarm.sim.loop import Simulation

MAES_MOTION = {"max_speed": 3.0, "max_turn_rate": 4.0, "max_accel": 60.0, "max_turn_accel": 120.0, "substeps": 8}

SPECS: dict[str, dict[str, Any]] = {
    "frontier16_b150": {"seed": 1, "map": {"kind": "building", "size": 150}, "robots": {"count": 16, "spawn": "together"},
                        "algorithm": {"name": "frontier"}, "stop": {"max_ticks": 2500}},
    "frontier4_c100": {"seed": 3, "map": {"kind": "cave", "size": 100}, "robots": {"count": 4, "spawn": "random"},
                       "algorithm": {"name": "frontier"}, "stop": {"max_ticks": 4000}},
    "greed8_b100_loss": {"seed": 5, "map": {"kind": "building", "size": 100}, "robots": {"count": 8, "spawn": "together"},
                         "algorithm": {"name": "greed"}, "stop": {"max_ticks": 2500},
                         "comm": {"loss": 0.3, "bandwidth": 3000}},
    "tnf6_c100_full": {"seed": 7, "map": {"kind": "cave", "size": 100}, "robots": {"count": 6, "spawn": "together"},
                       "algorithm": {"name": "tnf"}, "stop": {"max_ticks": 2500},
                       "comm": {"map_sharing": "full", "share_every": 7}},
    "minotaur8_b100": {"seed": 9, "map": {"kind": "building", "size": 100}, "robots": {"count": 8, "spawn": "together"},
                       "algorithm": {"name": "minotaur"}, "stop": {"max_ticks": 2500}},
    "xboa4_c50": {"seed": 11, "map": {"kind": "cave", "size": 50}, "robots": {"count": 4, "spawn": "together"},
                  "algorithm": {"name": "xboa"}, "stop": {"max_ticks": 600}},
    "frontier3_b50_opt_noise": {"seed": 13, "map": {"kind": "building", "size": 50}, "robots": {"count": 3, "spawn": "random"},
                                "algorithm": {"name": "frontier"}, "stop": {"max_ticks": 3000},
                                "navigation": {"unseen": "traversable"}, "lidar": {"noise_std": 0.05, "mode": "logodds"}},
    "greed16_c150_maes": {"seed": 2, "map": {"kind": "cave", "size": 150}, "robots": {"count": 16, "spawn": "random"},
                          "algorithm": {"name": "greed"}, "stop": {"max_ticks": 1500}, "motion": MAES_MOTION},
}


def digest(summary: dict[str, Any], timeseries: Any, events: Any) -> str:
    s = {k: v for k, v in summary.items() if k not in ("wall_time_s", "setup_time_s")}
    blob = json.dumps({"s": s, "ts": timeseries, "ev": events}, sort_keys=True, default=str)
    return hashlib.sha256(blob.encode()).hexdigest()[:16]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("names", nargs="*", metavar="NAME", help=f"specs to run (default all): {', '.join(SPECS)}")
    ap.add_argument("--transport", default="inprocess", choices=("inprocess", "zenoh"))
    args = ap.parse_args()
    for name in args.names:
        if name not in SPECS:
            ap.error(f"NAME: got {name!r}; allowed: {', '.join(SPECS)}")
    for name in args.names or SPECS:
        r = Simulation({**SPECS[name], "transport": args.transport}).run()
        s = r.summary
        print(name, digest(s, r.timeseries, r.events), s["ticks"], s["explored"], sum(s["plans"]), flush=True)


if __name__ == "__main__":
    main()
