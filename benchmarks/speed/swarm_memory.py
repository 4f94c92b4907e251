"""Where a swarm's memory goes: ``python benchmarks/speed/swarm_memory.py --robots 10000 --size 2000 --ticks 3``.

One run (building map of ``--size`` tiles, robots spawned together, frontier, the full stack) built from its
spec in this process. Prints the set-up's CPU time and RSS, then for each of the first ``--ticks`` ticks the
CPU time and resident memory (from ``/proc/self/status``) before and after each loop step, so a step that
makes memory resident shows itself. bench_scale.py's watchdog ends the process (exit 3, a JSON line with
the tick reached) once RSS passes ``--limit-gb``: a 10,000-robot run can otherwise take the machine's memory.

``--tiles`` then measures what the robots' maps hold against what they would hold stored by tiles: for each
robot, the 4 KB pages its map's rows touch (what the dense ``uint8[R, H, W]`` stack makes resident) and the
32 x 32 and 64 x 64-cell tiles holding a known cell. (It scans every map: use it on runs that fit in memory,
e.g. ``--robots 2500 --size 1000 --ticks 15``.)
"""

from __future__ import annotations

import argparse
import resource
import time

import numpy as np
from bench_scale import memory_watchdog, rss_gb  # this script's folder is on sys.path
from numba import njit

STEPS = ("move_and_scan", "_receive", "_send", "_deliver", "observe", "apply", "_record", "_commands")
"""The loop's steps (methods of :class:`swarm.sim.loop.Simulation`) reported per tick."""


def peak_gb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20


def report_steps(sim_type: type, ticks: int, tick: list[int]) -> None:
    """Wrap each of STEPS to print its CPU time and RSS change while the tick is below ``ticks``; ``tick[0]``
    follows the tick being run."""
    for name in STEPS:
        fn = getattr(sim_type, name)

        def wrapped(self, *a, _fn=fn, _name=name, **k):
            if tick[0] >= ticks:
                return _fn(self, *a, **k)
            t0, r0 = time.process_time(), rss_gb()
            try:
                return _fn(self, *a, **k)
            finally:
                print(f"    {_name}: {time.process_time() - t0:.1f} s CPU, RSS {r0:.2f} -> {rss_gb():.2f} GB",
                      flush=True)
        setattr(sim_type, name, wrapped)
    from swarm.transport.inprocess import InProcessHost

    act = InProcessHost.act

    def act_and_report(self, batch, _act=act):
        if tick[0] >= ticks:
            return _act(self, batch)
        t0, r0 = time.process_time(), rss_gb()
        try:
            return _act(self, batch)
        finally:
            print(f"    algorithms: {time.process_time() - t0:.1f} s CPU, RSS {r0:.2f} -> {rss_gb():.2f} GB",
                  flush=True)
    InProcessHost.act = act_and_report
    sense = sim_type.sense
    last = [time.process_time()]

    def sense_and_report(self, loop_state, _sense=sense):
        tick[0] = loop_state.tick
        now = time.process_time()
        print(f"  tick {loop_state.tick}: {now - last[0]:.1f} s CPU since the last, RSS {rss_gb():.2f} GB, "
              f"peak {peak_gb():.2f} GB, explored {100 * self.tracker.explored:.2f} %", flush=True)
        last[0] = now
        return _sense(self, loop_state)
    sim_type.sense = sense_and_report


@njit(cache=True)
def pages_and_tiles(known: np.ndarray, tile: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per robot of ``known`` (uint8[R, H, W], C-contiguous): known cells, 4 KB pages of its rows holding
    one, and ``tile`` x ``tile``-cell tiles holding one."""
    n, h, w = known.shape
    cells = np.zeros(n, np.int64)
    pages = np.zeros(n, np.int64)
    tiles = np.zeros(n, np.int64)
    tiles_w = (w + tile - 1) // tile
    used = np.zeros(((h + tile - 1) // tile) * tiles_w, np.bool_)
    for r in range(n):
        flat = known[r].reshape(-1)
        used[:] = False
        last_page = -1
        for i in range(flat.shape[0]):
            if flat[i] != 0:
                cells[r] += 1
                if i // 4096 != last_page:
                    last_page = i // 4096
                    pages[r] += 1
                y = i // w
                used[(y // tile) * tiles_w + (i - y * w) // tile] = True
        tiles[r] = used.sum()
    return cells, pages, tiles


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--robots", type=int, default=10_000)
    ap.add_argument("--size", type=int, default=2_000, help="building size in tiles (default 2000)")
    ap.add_argument("--ticks", type=int, default=3, help="ticks to run (default 3)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--limit-gb", type=float, default=12.0, help="stop once RSS passes this (default 12)")
    ap.add_argument("--tiles", action="store_true", help="after the run, compare row pages with tiles")
    ap.add_argument("--tiled", action="store_true", help="keep the maps by tiles (Simulation(tiled=True))")
    args = ap.parse_args()
    tick = [-1]
    memory_watchdog(args.limit_gb, tick)
    from swarm.sim.loop import Simulation

    report_steps(Simulation, args.ticks, tick)
    t0 = time.process_time()
    sim = Simulation({"seed": args.seed, "map": {"kind": "building", "size": args.size},
                      "robots": {"count": args.robots}, "algorithm": {"name": "frontier"},
                      "stop": {"max_ticks": args.ticks}}, tiled=args.tiled)
    print(f"set-up: {time.process_time() - t0:.1f} s CPU, RSS {rss_gb():.2f} GB, peak {peak_gb():.2f} GB, "
          f"map {sim.truth.shape[0]} x {sim.truth.shape[1]} cells", flush=True)
    t1 = time.process_time()
    result = sim.run()
    print(f"run: {result.summary['ticks']} ticks, {time.process_time() - t1:.1f} s CPU, peak {peak_gb():.2f} GB",
          flush=True)
    if args.tiles and not args.tiled:
        known = np.ascontiguousarray(sim.known)
        for tile in (32, 64):
            cells, pages, tiles = pages_and_tiles(known, tile)
            print(f"maps: median {np.median(cells):.0f} known cells a robot; rows {pages.sum() * 4096 / 2**20:.0f} MB "
                  f"(median {np.median(pages) * 4:.0f} KB a robot); {tile} x {tile} tiles "
                  f"{tiles.sum() * tile * tile / 2**20:.0f} MB (median {np.median(tiles) * tile * tile / 1024:.0f} KB)",
                  flush=True)


if __name__ == "__main__":
    main()
