"""Who takes a whole full map in a swarm: ``python benchmarks/speed/full_map_receivers.py --ticks 150``.

One run (1,000 robots on a 600-tile building spawned at random, frontier, the full stack, as
``bench_scale.py --robots 1000@600 --spawn random``) with :meth:`swarm.comm.sharing.MapSharing._merge_full`
wrapped: for every full map merged, how many of its receivers took only the cells since the sender's previous
update (``quick``), caught up on a few missed updates (``caught``) or took every known cell of the sender
(``rest``), the CPU time of those merges, and how often one receiver took the same map (by its payload's
hash) twice in one tick through the ``rest`` path (what merging each distinct map once per receiver and tick
would save). The wrapper costs a hash per full map; the run's own time is not the point.
"""

from __future__ import annotations

import argparse
import hashlib
import time
from collections import Counter
from typing import Any

import numpy as np

from swarm.comm import sharing
from swarm.sim.loop import Simulation


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ticks", type=int, default=150)
    ap.add_argument("--robots", type=int, default=1000)
    ap.add_argument("--size", type=int, default=600)
    ap.add_argument("--spawn", default="random", choices=["random", "together"])
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args(argv)

    stats: Counter = Counter()
    this_tick: set[tuple[int, bytes]] = set()
    merge_full = sharing.MapSharing._merge_full
    receive_tick = sharing.MapSharing.receive_tick

    def receive(self: Any, *a: Any, **k: Any) -> Any:
        this_tick.clear()
        return receive_tick(self, *a, **k)

    def merge(self: Any, msg: Any, ids: list[int], stack: np.ndarray, rows: np.ndarray) -> Any:
        t = time.process_time()
        quick, caught = merge_full(self, msg, ids, stack, rows)
        took = time.process_time() - t
        rest = ~quick
        for members, _ in caught:
            rest &= ~members
        key = hashlib.blake2b(msg.payload, digest_size=8).digest()
        stats["full maps"] += 1
        stats["receivers"] += len(ids)
        stats["quick"] += int(quick.sum())
        stats["caught"] += sum(int(m.sum()) for m, _ in caught)
        stats["rest"] += int(rest.sum())
        stats["merge CPU s"] += took
        stats["merge CPU s, maps with rest receivers"] += took if rest.any() else 0.0
        for k in np.flatnonzero(rest).tolist():
            stats["rest: same map twice in a tick"] += (ids[k], key) in this_tick
            this_tick.add((ids[k], key))
        return quick, caught

    sharing.MapSharing._merge_full = merge
    sharing.MapSharing.receive_tick = receive
    t0 = time.process_time()
    result = Simulation({"seed": args.seed, "map": {"kind": "building", "size": args.size},
                         "robots": {"count": args.robots, "spawn": args.spawn},
                         "algorithm": {"name": "frontier"}, "stop": {"max_ticks": args.ticks}}).run()
    print(f"{args.ticks} ticks, {time.process_time() - t0:.1f} s CPU, explored {result.summary['explored']:.3f}")
    for key, value in stats.items():
        print(f"  {key}: {value:.1f}" if isinstance(value, float) else f"  {key}: {value}")


if __name__ == "__main__":
    main()
