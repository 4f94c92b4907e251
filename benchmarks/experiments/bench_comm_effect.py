"""Communication effect: ticks to 99 % for one algorithm under global, los, multiwall radio and no communication.

    python benchmarks/experiments/bench_comm_effect.py ALGORITHMS SEEDS RADIOS [KIND SIZE ROBOTS]
    python benchmarks/experiments/bench_comm_effect.py greed 10 global,los,multiwall,none building 100 8

"none" = no links (LOS with a 1 mm range) and map sharing off. Seeds are the run seeds 0..SEEDS-1; 2 workers.
"""
import sys, time, itertools, statistics
from multiprocessing import Pool
from swarm.sim.loop import Simulation

COMMS = {
    "global": {"radio": {"model": "global"}},
    "los": {"radio": {"model": "los"}},
    "multiwall": {"radio": {"model": "multiwall"}},
    "none": {"radio": {"model": "los", "max_range_m": 0.001}, "comm": {"map_sharing": "off"}},
}

def one(args):
    alg, comm, seed, kind, size, n = args
    spec = {"seed": seed, "map": {"kind": kind, "size": size}, "robots": {"count": n},
            "algorithm": {"name": alg}, **COMMS[comm]}
    t = time.perf_counter()
    r = Simulation(spec).run()
    return alg, comm, seed, r.summary["ticks_to"]["0.99"], r.summary["stop_reason"], time.perf_counter() - t

if __name__ == "__main__":
    algs = sys.argv[1].split(","); seeds = range(int(sys.argv[2])); comms = sys.argv[3].split(",")
    kind = sys.argv[4] if len(sys.argv) > 4 else "building"; size = int(sys.argv[5]) if len(sys.argv) > 5 else 100
    n = int(sys.argv[6]) if len(sys.argv) > 6 else 8
    cells = [(a, c, s, kind, size, n) for a, s, c in itertools.product(algs, seeds, comms)]
    with Pool(2) as p:
        rows = p.map(one, cells, chunksize=1)
    for r in rows:
        print(*r[:5], round(r[5], 1))
    for a, c in itertools.product(algs, comms):
        v = [r[3] if r[3] is not None else 36000 for r in rows if r[0] == a and r[1] == c]
        print(a, c, "mean", round(statistics.mean(v)), v)
