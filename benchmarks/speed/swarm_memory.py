"""Where a swarm's memory goes: ``python benchmarks/speed/swarm_memory.py --robots 10000 --size 2000 --ticks 3``.

One run (building map of ``--size`` tiles, robots spawned together, frontier, the full stack) built from its
spec in this process. Prints the set-up's CPU time and RSS, then for each of the first ``--ticks`` ticks the
CPU time and resident memory (from ``/proc/self/status``) before and after each loop step, so a step that
makes memory resident shows itself. bench_scale.py's watchdog ends the process (exit 3, a JSON line with
the tick reached) once RSS passes ``--limit-gb``: a 10,000-robot run can otherwise take the machine's memory.

``--breakdown 2,11,13`` prints, before each of those ticks, what holds the memory: the Simulation's objects
walked attribute by attribute (numpy arrays and bytes summed per attribute path, list and dict indices
folded to ``[*]``; an array in a lazily resident mapping counts its resident pages, from
``/proc/self/smaps``), and glibc's heap (in use and free, ``mallinfo2``) where there is one.

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


def _mappings() -> list[tuple[int, int, int]]:
    """This process's memory mappings: (start, end, resident bytes), from /proc/self/smaps."""
    out: list[list[int]] = []
    with open("/proc/self/smaps") as f:
        for line in f:
            head = line.split(" ", 1)[0]
            if "-" in head and not line[0].isupper():
                a, b = head.split("-")
                out.append([int(a, 16), int(b, 16), 0])
            elif line.startswith("Rss:") and out:
                out[-1][2] = int(line.split()[1]) * 1024
    return [(a, b, r) for a, b, r in out]


def _lazy_mapping(arr: np.ndarray, maps: list[tuple[int, int, int]]) -> tuple[int, int, int] | None:
    """The mapping holding ``arr`` when its memory is an mmap of its own (swarm.util.memory.lazy_zeros); the
    kernel merges adjacent such mappings, so several arrays may share one."""
    import mmap

    base = arr
    while isinstance(base, np.ndarray) and base.base is not None:
        base = base.base
    if isinstance(base, memoryview):
        base = base.obj
    if not isinstance(base, mmap.mmap):
        return None
    addr = arr.__array_interface__["data"][0]
    return next(((a, b, resident) for a, b, resident in maps if a <= addr < b), None)


def memory_breakdown(root: object, top: int = 25) -> list[tuple[str, int, int]]:
    """The ``top`` attribute paths under ``root`` (swarm's, algorithms' and radio's objects, their lists, tuples,
    deques and dicts) by bytes of numpy arrays and bytes objects: (path, bytes, count). Each array is counted
    once (the first path that reaches its memory); lazily resident arrays count the resident pages of their
    mapping, listed once for all the arrays that share it (path "a + b")."""
    import re
    from collections import deque

    maps = _mappings()
    totals: dict[str, list[int]] = {}
    lazy: dict[tuple[int, int], tuple[int, list[str]]] = {}
    seen: set[int] = set()
    buffers: set[tuple[int, int]] = set()
    stack: list[tuple[object, str]] = [(root, "sim")]
    while stack:
        obj, path = stack.pop()
        if id(obj) in seen:
            continue
        seen.add(id(obj))
        key = re.sub(r"\[[^\]]*\]", "[*]", path)
        if isinstance(obj, np.ndarray):
            addr = obj.__array_interface__["data"][0]
            if (addr, obj.nbytes) in buffers:
                continue
            buffers.add((addr, obj.nbytes))
            mapping = _lazy_mapping(obj, maps) if obj.nbytes >= 1 << 22 else None
            if mapping is not None:
                names = lazy.setdefault(mapping[:2], (mapping[2], []))[1]
                if key not in names:
                    names.append(key)
                continue
            entry = totals.setdefault(key, [0, 0])
            entry[0] += obj.nbytes
            entry[1] += 1
            continue
        if isinstance(obj, (bytes, bytearray)):
            entry = totals.setdefault(key, [0, 0])
            entry[0] += len(obj)
            entry[1] += 1
            continue
        if isinstance(obj, dict):
            stack.extend((v, f"{path}[*]") for v in obj.values())
            continue
        if isinstance(obj, (list, tuple, deque, set, frozenset)):
            stack.extend((v, f"{path}[*]") for v in obj)
            continue
        if not (type(obj).__module__ or "").startswith(("swarm", "algorithms", "radio")):
            continue
        fields = dict(getattr(obj, "__dict__", {}))
        for cls in type(obj).__mro__:
            for name in getattr(cls, "__slots__", ()):
                if hasattr(obj, name):
                    fields[name] = getattr(obj, name)
        stack.extend((v, f"{path}.{k}") for k, v in fields.items())
    for resident, names in lazy.values():
        totals[" + ".join(sorted(names)) + " (resident)"] = [resident, len(names)]
    ranked = sorted(totals.items(), key=lambda kv: -kv[1][0])[:top]
    return [(path, size, count) for path, (size, count) in ranked]


def heap_gb() -> tuple[float, float] | None:
    """glibc's heap: (in use, free) GB (``mallinfo2``), or None without it."""
    import ctypes

    class MallInfo2(ctypes.Structure):
        _fields_ = [(name, ctypes.c_size_t) for name in ("arena", "ordblks", "smblks", "hblks", "hblkhd",
                                                           "usmblks", "fsmblks", "uordblks", "fordblks", "keepcost")]
    try:
        info = ctypes.CDLL("libc.so.6").mallinfo2
    except (OSError, AttributeError):
        return None
    info.restype = MallInfo2
    m = info()
    return m.uordblks / 2**30, m.fordblks / 2**30


def print_breakdown(sim: object, tick: int) -> None:
    heap = heap_gb()
    print(f"  memory before tick {tick}: RSS {rss_gb():.2f} GB"
          + (f"; heap in use {heap[0]:.2f} GB, free {heap[1]:.2f} GB" if heap else ""), flush=True)
    for path, size, count in memory_breakdown(sim):
        print(f"    {size / 2**20:9.1f} MB  x{count:<6d} {path}", flush=True)


def peak_gb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20


def report_steps(sim_type: type, ticks: int, tick: list[int], breakdown: frozenset[int] = frozenset()) -> None:
    """Wrap each of STEPS to print its CPU time and RSS change while the tick is below ``ticks``; ``tick[0]``
    follows the tick being run; before each tick in ``breakdown``, print what holds the memory."""
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
        if loop_state.tick in breakdown:
            print_breakdown(self, loop_state.tick)
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
    ap.add_argument("--breakdown", default="", metavar="TICKS",
                    help="comma-separated ticks before which to print what holds the memory")
    args = ap.parse_args()
    tick = [-1]
    memory_watchdog(args.limit_gb, tick)
    from swarm.sim.loop import Simulation

    try:
        breakdown = frozenset(int(t) for t in args.breakdown.split(",") if t.strip())
    except ValueError:
        ap.error(f"--breakdown: {args.breakdown[:40]!r} is not a comma-separated list of ticks")
    report_steps(Simulation, args.ticks, tick, breakdown)
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
