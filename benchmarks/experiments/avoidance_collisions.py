"""Robot-robot and robot-wall collisions with and without local avoidance (issue 50), on the 16-robot
workload: 16 robots spawned together on 50-tile buildings, the frontier explorer, to 95 % explored.

    python benchmarks/experiments/avoidance_collisions.py [--seeds 3] [--robots 16] [--size 50]

Per run and avoidance setting: contacts begun with another robot and with a wall, per robot-hour of simulated
time (the run summary's ``collisions_robot`` and ``collisions_wall``: a robot starting to touch another robot
or a wall, counted per robot, so a robot-robot contact counts for both); ticks to the stop; CPU seconds per
tick.
"""

from __future__ import annotations

import argparse
import statistics
import time

from swarm.sim.loop import Simulation
from swarm.world.motion import TICK_S


def one(kind: str, seed: int, robots: int, size: int, algorithm: str) -> dict[str, float]:
    spec = {"map": {"kind": "building", "size": size, "seed": seed}, "robots": {"count": robots, "spawn": "together",
                                                                                 "spawn_seed": seed},
            "seed": seed, "algorithm": {"name": algorithm}, "stop": {"explored": 0.95, "max_ticks": 6000},
            "navigation": {"avoidance": kind}}
    sim = Simulation(spec)
    t0 = time.process_time()
    result = sim.run()
    cpu = time.process_time() - t0
    ticks = result.summary["ticks"]
    hours = robots * ticks * TICK_S / 3600
    s = result.summary
    return {"robot_per_rh": s["collisions_robot"] / hours, "wall_per_rh": s["collisions_wall"] / hours, "ticks": ticks,
            "ms_per_tick": 1000 * cpu / ticks, "explored": s["explored"]}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--robots", type=int, default=16)
    ap.add_argument("--size", type=int, default=50)
    ap.add_argument("--algorithm", default="frontier")
    ap.add_argument("--kinds", nargs="+", default=["none", "orca", "hrvo"])
    args = ap.parse_args()
    print("| avoidance | robot-robot contacts per robot-hour | robot-wall per robot-hour | ticks to 95 % | ms per tick |")
    print("|---|---|---|---|---|")
    rows = {k: [] for k in args.kinds}
    for seed in range(1, args.seeds + 1):
        for kind in args.kinds:   # interleaved: the machine's load falls on every setting alike
            rows[kind].append(one(kind, seed, args.robots, args.size, args.algorithm))
    for kind, rs in rows.items():
        def med(key: str) -> str:
            vals = [r[key] for r in rs]
            return f"{statistics.median(vals):.1f} ({min(vals):.1f}-{max(vals):.1f})"
        print(f"| {kind} | {med('robot_per_rh')} | {med('wall_per_rh')} | {med('ticks')} | {med('ms_per_tick')} |")


if __name__ == "__main__":
    main()
