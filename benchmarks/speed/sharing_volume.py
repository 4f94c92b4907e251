"""What a swarm's map sharing moves, against what a tile-by-tile "send what the receiver lacks" would move.

``python benchmarks/speed/sharing_volume.py [--robots 1000] [--size 600] [--ticks 150] [--tile 64]``

Runs ``robots`` frontier robots spawned at random on a seeded ``size``-tile building (map updates at zlib
level 1, the rest as ``bench_scale.py --spawn random``). At the tick each sharing round's deltas arrive, it
prints the (cell, receiver) pairs the delta merges read (the cells of each delta times its receivers) and,
before they are merged, the tiles of ``tile`` x ``tile`` cells in which at least one robot whose delta
reaches a receiver knows more cells than that receiver: what a receiver-driven protocol exchanging whole
tiles would send (in cells: tiles x tile^2). It measures whether such a protocol could cut the volume that
keeps a spread-out swarm from real time (docs/performance.md, "Swarm scale").
"""

from __future__ import annotations

import argparse

import numpy as np
from numba import njit

from swarm.comm import sharing
from swarm.comm.messages import MapUpdate
from swarm.sim.loop import Simulation


@njit(cache=True)
def tile_counts(stack: np.ndarray, tile: int) -> np.ndarray:  # pragma: no cover - compiled
    """Known cells of each robot's dense map (``uint8[R, H, W]``) per ``tile`` x ``tile`` tile."""
    n, h, w = stack.shape
    out = np.zeros((n, -(-h // tile), -(-w // tile)), np.int32)
    for r in range(n):
        for i in range(h):
            for j in range(w):
                if stack[r, i, j]:
                    out[r, i // tile, j // tile] += 1
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--robots", type=int, default=1000)
    ap.add_argument("--size", type=int, default=600, help="building size in tiles")
    ap.add_argument("--ticks", type=int, default=150)
    ap.add_argument("--tile", type=int, default=64, help="side of the tiles a receiver would ask for, in cells")
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()
    if args.robots < 2 or args.size < 10 or args.ticks < 1 or args.tile < 1:
        ap.error("--robots must be >= 2, --size >= 10, --ticks and --tile >= 1")
    spec = {"seed": args.seed, "map": {"kind": "building", "size": args.size},
            "robots": {"count": args.robots, "spawn": "random"}, "algorithm": {"name": "frontier"},
            "comm": {"map_zlib_level": 1}, "stop": {"max_ticks": args.ticks}}
    sim = Simulation(spec, tiled=False)
    every = sim.comm.share_every
    totals = [0, 0]
    original = sharing.MapSharing.receive_tick

    def counted(self, deliveries, known, live, cells=True, tick=0):
        deltas = [(m, np.asarray(rs)) for m, rs in deliveries if isinstance(m, MapUpdate) and not m.full]
        if tick % every == 1 and deltas:  # a round's deltas, sent the tick before
            counts = tile_counts(known, args.tile)
            pairs = sum(m.count * len(rs) for m, rs in deltas)
            wanted = np.zeros(counts.shape, np.bool_)
            for m, rs in deltas:
                wanted[rs] |= counts[m.sender][None] > counts[rs]
            cells_moved = int(wanted.sum()) * args.tile * args.tile
            totals[0] += pairs
            totals[1] += cells_moved
            print(f"tick {tick:5d}: {len(deltas)} deltas, {pairs:.3g} (cell, receiver) pairs; whole tiles a "
                  f"receiver lacks: {int(wanted.sum())} = {cells_moved:.3g} cells", flush=True)
        return original(self, deliveries, known, live, cells=cells, tick=tick)

    sharing.MapSharing.receive_tick = counted
    sim.run()
    print(f"all rounds: {totals[0]:.3g} pairs; tiles: {totals[1]:.3g} cells ({totals[1] / max(1, totals[0]):.2f}x)")


if __name__ == "__main__":
    main()
