"""Where map sharing's time goes: ``python benchmarks/profiling/profile_sharing.py [--robots 16 --size 150 --seed 1]``.

Runs the issue-3 workload (as ``benchmarks/speed/bench_runtime.py``) with the map-sharing steps wrapped
in timers and prints, per step, the calls, the time per call and the share of the run: finding each robot's changed
cells for its delta (``sync_box``, or ``sync_changes`` after a full map was merged), building deltas and
full maps (most of it zlib), encoding envelopes, delivering, decoding (zlib, cells, dense maps) and
merging. The timers add about 1 us per call, so the run itself is a little slower than in
``benchmarks/speed/bench_runtime.py``; the shares are what matters.
"""

from __future__ import annotations

import argparse
from collections import Counter
from typing import Any

from workload import add_workload_arguments, workload_spec, wrap

import swarm.comm.medium as medium
import swarm.comm.messages as messages
import swarm.comm.sharing as sharing
from swarm.sim.loop import Simulation

TIMED: list[tuple[Any, str, str]] = [
    (sharing, "sync_box_packed", "changed cells for a delta (sync_box_packed)"),
    (sharing, "sync_changes_packed", "  the same after a full map (sync_changes_packed)"),
    (sharing, "delta_update", "build a delta (pack + zlib)"),
    (sharing, "full_update", "build a full map (pack + zlib)"),
    (messages.zlib, "compress", "  of which zlib.compress"),
    (medium.Medium, "envelope", "encode an envelope"),
    (medium.Medium, "deliver", "deliver a tick's envelopes"),
    (messages.zlib, "decompress", "zlib.decompress (updates that came as bytes)"),
    (messages.MapUpdate, "cells", "a delta's cells (decoded on the first call)"),
    (messages.MapUpdate, "dense", "a full map's cells (decoded on the first call)"),
    (sharing, "merge_cells_many", "merge a delta into all its receivers"),
    (sharing, "merge_cells_many_counted", "  the same, counting free cells (the runtime's)"),
]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_workload_arguments(parser)
    args = parser.parse_args()
    spent: Counter = Counter()
    calls: Counter = Counter()
    for owner, name, label in TIMED:
        wrap(owner, name, label, spent, calls)
    result = Simulation(workload_spec(args)).run()
    wall = result.summary["wall_time_s"]
    print(result.one_line())
    print(f"run {wall:.2f} s wall")
    for _, _, label in TIMED:
        if calls[label]:
            print(f"{label:48s} {calls[label]:7d} calls {1e6 * spent[label] / calls[label]:8.1f} us "
                  f"{spent[label]:7.3f} s {100 * spent[label] / wall:5.1f} %")


if __name__ == "__main__":
    main()
