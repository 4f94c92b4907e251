"""Where Minotaur's robot-ticks go, by state/mode, for variant swarm and maes under full MAES parity (issue 33).

    python benchmarks/experiments/minotaur_modes.py --seeds 5 --cells building:50:16 cave:50:16 building:50:2

Each run is the ablation campaign's full-parity set-up (MAES's motion model, ``--motion continuous`` for
swarm's navigator with MAES's speeds; robots facing +y; 7 m lidar, radio "maes", MAES map merge with links
judged at receipt, 98 % explored; spawn together; maps and spawns of ``derive_seed`` as in
``bench_minotaur_doors.py``). The share of robot-ticks in each mode of the explorer's ``debug`` shows the
overhead the paper blames for Minotaur's slowness (section 5.2, Figs. 10-11): ``room/check-door`` is driving
to a candidate doorway to verify it, ``door/door-nearest`` MAES's nearest-doorway rule, ``room/corner``
corner coverage (variant maes only). The last column is the share of ``check-door`` robot-ticks spent on a
candidate cell another robot had started to check earlier (MAES pools tried candidates through its
heartbeats, issue 49 row 2, so this counts what that pooling leaves); the one before it the share
of ``door-nearest`` robot-ticks in which another robot drives through the same doorway by the same rule
(MAES's nearest-doorway rule has no claim: robots that finish rooms near each other pick the same one).
"""

from __future__ import annotations

import argparse
from collections import Counter

from swarm.sim.loop import Simulation
from swarm.sim.spec import derive_seed

MAES_MOTION = {"max_speed": 3.0, "max_turn_rate": 4.0, "max_accel": 60.0, "max_turn_accel": 120.0, "substeps": 8}


def run(kind: str, size: int, robots: int, variant: str, seed: int,
        motion: str = "maes") -> tuple[int, Counter, int, int]:
    spec = {"seed": derive_seed(seed, "run"), "map": {"kind": kind, "size": size, "seed": derive_seed(seed, kind, size)},
            "robots": {"count": robots, "spawn": "together", "spawn_seed": derive_seed(seed, kind, size, "spawn"),
                       "heading": "maes"},
            "algorithm": {"name": "minotaur", "params": {"variant": variant}}, "radio": {"model": "maes"},
            "comm": {"map_sharing": "maes", "link_at": "receive"}, "motion": {**MAES_MOTION, "model": motion}, "lidar": {"range_m": 7.0},
            "stop": {"explored": 0.98, "max_ticks": 36000}}
    modes: Counter = Counter()
    first_checker: dict = {}
    repeated = [0]
    herded = [0]

    def watch(view) -> None:
        nearest = Counter(repr(a.debug["door"]) for a in view.actions
                          if a is not None and a.debug and a.debug["mode"] == "door-nearest")
        herded[0] += sum(n for n in nearest.values() if n > 1)
        for robot, a in enumerate(view.actions):
            if a is not None and a.debug:
                modes[f"{a.debug['state']}/{a.debug['mode']}"] += 1
                check = a.debug.get("check")
                if check is not None and a.debug["mode"] == "check-door":
                    key = tuple(check[1])
                    if first_checker.setdefault(key, robot) != robot:
                        repeated[0] += 1

    result = Simulation(spec, observers=[watch]).run()
    return int(result.summary["ticks"]), modes, repeated[0], herded[0]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--cells", nargs="+", default=["building:50:16", "cave:50:16", "building:50:2"],
                    help="kind:size:robots")
    ap.add_argument("--motion", choices=("maes", "continuous"), default="maes",
                    help="motion.model: MAES's (full parity, the default) or swarm's navigator")
    args = ap.parse_args()
    print("| cell | variant | runs | ticks (mean) | top modes (share of robot-ticks) | door-nearest ticks on a doorway "
          "another robot takes too | check-door ticks on a candidate another robot tried first |\n"
          "|---|---|---:|---:|---|---:|---:|")
    for cell in args.cells:
        kind, size, robots = cell.split(":")
        for variant in ("swarm", "maes"):
            ticks, total, repeated, herded = [], Counter(), 0, 0
            for seed in range(args.seeds):
                t, m, r, h = run(kind, int(size), int(robots), variant, seed, args.motion)
                herded += h
                ticks.append(t)
                total.update(m)
                repeated += r
            n = sum(total.values())
            top = ", ".join(f"{k} {v / n:.0%}" for k, v in total.most_common(5))
            checks = total["room/check-door"]
            repeated_share = f"{repeated / checks:.0%}" if checks else "–"
            nearest = total["door/door-nearest"]
            herded_share = f"{herded / nearest:.0%}" if nearest else "–"
            print(f"| {kind} {size}, {robots} robots | {variant} | {args.seeds} | {sum(ticks) / len(ticks):.0f} | "
                  f"{top} | {herded_share} | {repeated_share} |", flush=True)


if __name__ == "__main__":
    main()
