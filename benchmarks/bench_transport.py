"""Transport and map-sharing costs on the issue-3 workload (16 robots, 150 x 150 building, frontier).

    python benchmarks/bench_transport.py [--ticks 3000] [--robots 16]

Prints, for the same spec: ticks per wall and CPU second with the in-process and the zenoh transport
(agents in the runtime's process, so every observation and action goes through a real zenoh session),
and map-sharing bytes per tick with delta updates versus full maps (every 10 ticks). Each configuration
runs twice and the faster run is reported (the machine may be shared).
"""

from __future__ import annotations

import argparse
import time

from swarm.simulation import Simulation


def measure(spec: dict) -> tuple[float, float, dict]:
    best = None
    for _ in range(2):
        sim = Simulation(spec)
        cpu0 = time.process_time()
        r = sim.run()
        cpu = time.process_time() - cpu0
        row = (r.summary["ticks"] / r.summary["wall_time_s"], r.summary["ticks"] / cpu, r.summary)
        best = row if best is None or row[0] > best[0] else best
    return best  # type: ignore[return-value]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--ticks", type=int, default=3000)
    ap.add_argument("--robots", type=int, default=16)
    ap.add_argument("--size", type=int, default=150)
    args = ap.parse_args()
    base = {"seed": 1, "map": {"kind": "building", "size": args.size}, "robots": {"count": args.robots},
            "stop": {"max_ticks": args.ticks}}
    results = {}
    for transport in ("inprocess", "zenoh"):
        wall, cpu, summary = measure({**base, "transport": transport})
        results[transport] = summary
        print(f"{transport:9s}: {wall:7.0f} ticks/s wall, {cpu:7.0f} ticks per CPU-second")
    print(f"identical results: {results['inprocess']['final_poses'] == results['zenoh']['final_poses']}")
    for mode in ("delta", "full"):
        _, _, s = measure({**base, "comm": {"map_sharing": mode}})
        m = s["messages"]
        print(f"map sharing {mode:5s}: {m['map_bytes_sent'] / s['ticks']:9.0f} bytes/tick sent "
              f"({m['map_bytes_sent'] / 1e6:.1f} MB over {s['ticks']} ticks), all messages "
              f"{m['bytes_sent'] / s['ticks']:.0f} bytes/tick, explored {100 * s['explored']:.1f}%")


if __name__ == "__main__":
    main()
