"""Minotaur's doorway detection scored against the true doors of generated maps (issues 7 and 33).

    python benchmarks/experiments/bench_minotaur_doors.py --seeds 20 --sizes 50 100 --robots 1 4 --workers 2
    python benchmarks/experiments/bench_minotaur_doors.py --kinds building cave --seeds 10 --sizes 50 100 \
        --robots 2 8 --motion maes --workers 2                      # issue 33: false doorways on caves
    python benchmarks/experiments/bench_minotaur_doors.py ... --params '{"variant": "maes"}'

Every run explores a seeded map to ``--explored`` (99 %) with Minotaur; the doorways all robots
know at the end (their ``debug["doorways"]``, merged by position) are matched to the map's true doors
(a building generator's ``Map.graph`` edges: centre, axis; a cave has none, so every doorway found in a
cave is a false positive): a detection is a true positive when a true door of the same axis has its
centre within ``--match-m`` (1.5 m) and is not matched yet (nearest first). Precision = matched
detections / detections; recall = matched doors / true doors; "false / run" = unmatched detections per
run. The rows "detector on the true map" run the detector alone on each fully known map: what the
robots could find at best (and, on caves, how many cave wall gaps pass the test at all); not for
``variant = "maes"``, whose doorways are checked where the robot stands, not found in a map.

``--motion maes`` runs MAES's robots (3 m/s, docs/maes.md section 5; the paper's campaign); ``--params``
passes Minotaur parameters (JSON). Maps and spawns are those of ``benchmarks/experiments/compare.py``
for the same seed (``derive_seed``).
"""

from __future__ import annotations

import argparse
import itertools
import json
import math
import sys
import time
from multiprocessing import Pool

import numpy as np

from algorithms.minotaur.detection import detect
from algorithms.minotaur.doorways import MATCH_M
from algorithms.minotaur.params import MinotaurParams
from maps import generate
from swarm.api import FREE, SOLID
from swarm.sim.loop import Simulation
from swarm.sim.spec import derive_seed

Door = tuple[float, float, int]
MAES_MOTION = {"max_speed": 3.0, "max_turn_rate": 4.0, "max_accel": 60.0, "max_turn_accel": 120.0, "substeps": 8}


def true_doors(m) -> list[Door]:
    """A building's doors (centre, axis); a cave has none."""
    if m.graph is None:
        return []
    return [(float(d["x"]), float(d["y"]), 0 if d["axis"] == "x" else 1) for _, _, d in m.graph.edges(data=True)]


def merge(found: list[Door]) -> list[Door]:
    """One entry per doorway (robots' records of one doorway differ by a cell or two)."""
    out: list[Door] = []
    for x, y, a in found:
        if not any(b == a and math.hypot(x - u, y - v) < MATCH_M for u, v, b in out):
            out.append((x, y, a))
    return out


def score(found: list[Door], truth: list[Door], match_m: float) -> tuple[int, int, int]:
    """(true positives, detections, true doors), matching nearest pairs first."""
    pairs = sorted((math.hypot(x - u, y - v), i, j) for i, (x, y, a) in enumerate(found)
                   for j, (u, v, b) in enumerate(truth) if a == b and math.hypot(x - u, y - v) <= match_m)
    used_f: set[int] = set()
    used_t: set[int] = set()
    for _, i, j in pairs:
        if i not in used_f and j not in used_t:
            used_f.add(i)
            used_t.add(j)
    return len(used_f), len(found), len(truth)


def run_one(cell: tuple) -> tuple:
    kind, size, robots, seed, explored, max_ticks, match_m, motion, params = cell
    spec = {"seed": derive_seed(seed, "run"),
            "map": {"kind": kind, "size": size, "seed": derive_seed(seed, kind, size)},
            "robots": {"count": robots, "spawn": "together", "spawn_seed": derive_seed(seed, kind, size, "spawn")},
            "algorithm": {"name": "minotaur", "params": dict(params)}, "radio": {"model": "multiwall"},
            "stop": {"explored": explored, "max_ticks": max_ticks}}
    if motion == "maes":
        spec["motion"] = MAES_MOTION
    last: dict[int, list] = {}

    def watch(view) -> None:
        for i, a in enumerate(view.actions):
            if a is not None and a.debug:
                last[i] = a.debug["doorways"]

    t0 = time.perf_counter()
    sim = Simulation(spec, observers=[watch])
    result = sim.run()
    found = merge([(x, y, axis) for doors in last.values() for x, y, axis, _, _ in doors])
    tp, n_found, n_true = score(found, true_doors(sim.truth), match_m)
    return (kind, size, robots, seed, tp, n_found, n_true, result.summary["explored"], result.summary["ticks"],
            time.perf_counter() - t0)


def truth_map_row(kind: str, size: int, seeds: int, match_m: float, params: dict) -> tuple[int, int, int]:
    p = MinotaurParams(**params)
    tot = [0, 0, 0]
    for seed in range(seeds):
        m = generate(kind, size, derive_seed(seed, kind, size))
        known = np.where(m.solid, SOLID, FREE).astype(np.uint8)
        doors = [(d.x, d.y, d.axis) for d in detect(known, p.min_door_width_m, p.max_door_width_m, p.wall_continue_m)]
        for k, v in enumerate(score(doors, true_doors(m), match_m)):
            tot[k] += v
    return tot[0], tot[1], tot[2]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--kinds", nargs="+", default=["building"], choices=["building", "cave"])
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--sizes", nargs="+", type=int, default=[50, 100])
    ap.add_argument("--robots", nargs="+", type=int, default=[1, 4])
    ap.add_argument("--explored", type=float, default=0.99)
    ap.add_argument("--max-ticks", type=int, default=100_000)
    ap.add_argument("--match-m", type=float, default=1.5)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--motion", default="default", choices=["default", "maes"])
    ap.add_argument("--params", default="{}", help="Minotaur parameters, JSON (e.g. '{\"variant\": \"maes\"}')")
    args = ap.parse_args()
    params = json.loads(args.params)
    MinotaurParams(**params)                                       # refuse bad parameters before the runs
    cells = [(k, s, r, seed, args.explored, args.max_ticks, args.match_m, args.motion, tuple(sorted(params.items())))
             for k, s, r, seed in itertools.product(args.kinds, args.sizes, args.robots, range(args.seeds))]
    t0 = time.perf_counter()
    with Pool(args.workers) as pool:
        rows = pool.map(run_one, cells, chunksize=1)
    print("command: python " + " ".join(sys.argv))
    print(f"{len(rows)} runs in {time.perf_counter() - t0:.0f} s; doorways matched to true doors within "
          f"{args.match_m} m (same axis)\n")
    print("| map | size | robots | runs | explored (min) | ticks (mean) | true doors | detected | correct | "
          "false / run | precision | recall |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for k in args.kinds:
        total = [0, 0, 0]
        n_runs = 0
        for s, r in itertools.product(args.sizes, args.robots):
            sel = [row for row in rows if row[:3] == (k, s, r)]
            tp, nf, nt = (sum(row[i] for row in sel) for i in (4, 5, 6))
            total = [total[0] + tp, total[1] + nf, total[2] + nt]
            n_runs += len(sel)
            print(f"| {k} | {s} | {r} | {len(sel)} | {min(row[7] for row in sel):.3f} | "
                  f"{sum(row[8] for row in sel) / len(sel):.0f} | {nt} | {nf} | {tp} | {(nf - tp) / len(sel):.2f} | "
                  f"{_ratio(tp, nf)} | {_ratio(tp, nt)} |")
        tp, nf, nt = total
        print(f"| {k} | all | | {n_runs} | | | {nt} | {nf} | {tp} | {(nf - tp) / max(n_runs, 1):.2f} | "
              f"{_ratio(tp, nf)} | {_ratio(tp, nt)} |")
        for s in args.sizes if params.get("variant", "swarm") == "swarm" else ():   # maes checks on arrival
            tp, nf, nt = truth_map_row(k, s, args.seeds, args.match_m, params)
            print(f"| {k} | {s} | detector on the true map | {args.seeds} | 1.000 | | {nt} | {nf} | {tp} | "
                  f"{(nf - tp) / args.seeds:.2f} | {_ratio(tp, nf)} | {_ratio(tp, nt)} |")


def _ratio(a: int, b: int) -> str:
    return f"{a / b:.3f}" if b else "-"


if __name__ == "__main__":
    main()
