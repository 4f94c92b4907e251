"""A/B of the recorder's map diff: the knowledge journal (only the tiles a tick wrote) against whole-map
diffs, interleaved in one process, same spec.

    python benchmarks/speed/ab_record_journal.py --robots 256 --size 600 --ticks 100 --pairs 2

Prints, per run, the run's CPU time, the CPU time spent inside the recorder (per tick) and the recording's
size (identical by construction: tests/swarm/record/test_record_journal.py). CPU time, because the
machine is shared.
"""

from __future__ import annotations

import argparse
import time
from typing import Any

from swarm.record import Recorder
from swarm.sim.loop import Simulation


def one(spec: dict[str, Any], journal: bool, ticks: int) -> str:
    sim = Simulation(spec)
    recorder = Recorder(sim, journal=journal)
    inside = [0.0]

    def observe(view: Any) -> None:
        t = time.process_time()
        recorder(view)
        inside[0] += time.process_time() - t

    sim.observers = (observe,)
    t0 = time.process_time()
    result = sim.run()
    total = time.process_time() - t0
    recorder.finish(sim, result)
    return (f"journal={journal}: run {total:.1f} s CPU, inside the recorder {inside[0]:.2f} s = "
            f"{1000 * inside[0] / ticks:.1f} ms a tick, {len(recorder.to_bytes()) / 1e6:.1f} MB")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--robots", type=int, default=256)
    ap.add_argument("--size", type=int, default=600)
    ap.add_argument("--ticks", type=int, default=100)
    ap.add_argument("--pairs", type=int, default=2)
    args = ap.parse_args()
    spec = {"seed": 1, "map": {"kind": "building", "size": args.size}, "robots": {"count": args.robots},
            "algorithm": {"name": "frontier"}, "stop": {"max_ticks": args.ticks}}
    for _ in range(args.pairs):
        for journal in (True, False):
            print(one(spec, journal, args.ticks), flush=True)


if __name__ == "__main__":
    main()
