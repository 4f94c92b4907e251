"""The xBOA paper's exploration experiment, Tables 3-6 style (its section 5; docs/boa.md sections 8-9).

For every BOA-family variant, short-term (1 goal) and long-term (K = 3 goals) strategies, population 5
and 20, N repetitions (seeds 0..N-1) on the paper's maps: exploration rate after 100, 200 and 300 steps
(battery 300), wall milliseconds per decision, fitness evaluations (rows) and distinct goals per decision.
Baselines: the exhaustive per-decision optimum (argmax of the gain table) and best-of-5 random goals. Then
the multi-robot runs (3 robots on one shared central map, with and without the overlap penalty).

    python benchmarks/experiments/bench_boa_paper.py --quick            # ~20 s: house map, 3 repetitions, pop 5 & 20 short-term
    python benchmarks/experiments/bench_boa_paper.py                    # full: both maps, all variants, 10 repetitions
    python benchmarks/experiments/bench_boa_paper.py --json out.json    # also write every row as JSON

The maps are read from $XBOA_MAPS or ../shared/data/xboa-maps (not part of this repository).
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from dataclasses import replace

import numpy as np

from algorithms.boa.decision import DecisionParams
from algorithms.boa.gridworld import load_xboa_csv, paper_map_path
from algorithms.boa.scenario import PaperSetup, run_mission
from algorithms.boa.variants import FAMILY

STEPS = (100, 200, 300)


def run_config(truth: np.ndarray, setup: PaperSetup, params: DecisionParams, reps: int) -> dict:
    rates, ms, nfev, distinct, n_dec, ends = [], [], [], [], [], []
    for seed in range(reps):
        r = run_mission(truth, setup, params, seed)
        rates.append([r.rate_at(s) * 100 for s in STEPS])
        ms += [d.time_ms for d in r.decisions]
        nfev += [d.nfev for d in r.decisions]
        distinct += [d.n_distinct for d in r.decisions]
        n_dec.append(len(r.decisions))
        ends.append(r.ticks)
    a = np.array(rates)
    return {
        "rate_mean": a.mean(axis=0).round(2).tolist(), "rate300_min": round(float(a[:, -1].min()), 2),
        "rate300_max": round(float(a[:, -1].max()), 2),
        "ms_mean": round(statistics.mean(ms), 2), "ms_median": round(statistics.median(ms), 2),
        "ms_p90": round(float(np.percentile(ms, 90)), 2), "nfev": round(statistics.mean(nfev), 1),
        "distinct": round(statistics.mean(distinct), 1), "decisions": round(statistics.mean(n_dec), 1),
        "ticks_median": statistics.median(ends),
    }


def row(label: str, res: dict) -> str:
    r = res["rate_mean"]
    return (f"| {label} | {r[0]:.1f} | {r[1]:.1f} | {r[2]:.1f} ({res['rate300_min']:.1f}-{res['rate300_max']:.1f}) "
            f"| {res['ms_mean']:.1f} / {res['ms_median']:.1f} ({res['ms_p90']:.1f}) | {res['nfev']:.0f} "
            f"| {res['distinct']:.0f} | {res['decisions']:.1f} |")


HEADER = ("| configuration | @100 % | @200 % | @300 % (min-max) | ms/decision mean / median (p90) | evals/decision "
          "| distinct goals | decisions |\n|---|---|---|---|---|---|---|---|")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="house map, 3 repetitions, short-term, xBOA/BOA only")
    ap.add_argument("--reps", type=int, default=None)
    ap.add_argument("--maps", default=None, help="comma-separated: house,empty")
    ap.add_argument("--variants", default=None, help="comma-separated variant names")
    ap.add_argument("--json", default=None)
    args = ap.parse_args()
    reps = args.reps or (3 if args.quick else 10)
    maps = (args.maps or ("house" if args.quick else "house,empty")).split(",")
    variants = args.variants.split(",") if args.variants else (["BOA", "xBOA"] if args.quick else list(FAMILY))
    horizons = (1,) if args.quick else (1, 3)
    out: list[dict] = []
    t_start = time.perf_counter()
    for name in maps:
        path = paper_map_path(name)
        if path is None:
            print(f"map-{name}.csv not found (set XBOA_MAPS); skipped", file=sys.stderr)
            continue
        truth = load_xboa_csv(path)
        run_mission(truth, PaperSetup(battery=5), DecisionParams(pop_size=5), 0)     # compile / warm caches
        setup = PaperSetup(battery=300)
        print(f"\n### {name} map, 1 robot, battery 300, {reps} repetitions\n\n{HEADER}")
        for k in horizons:
            for v in variants:
                for pop in (5, 20):
                    params = DecisionParams(variant=v, pop_size=pop, n_goals=k)
                    res = run_config(truth, setup, params, reps)
                    label = f"{v} pop {pop} {'short' if k == 1 else f'long K={k}'}"
                    print(row(label, res), flush=True)
                    out.append({"map": name, "robots": 1, "variant": v, "pop": pop, "goals": k, **res})
        for label, params in (("exhaustive argmax (oracle)", DecisionParams(search="exhaustive")),
                              ("best of 5 random goals", DecisionParams(variant="BOA", pop_size=5, max_gen=0,
                                                                        retries=0))):
            res = run_config(truth, setup, params, reps)
            print(row(label, res), flush=True)
            out.append({"map": name, "robots": 1, "variant": label, "pop": params.pop_size, "goals": 1, **res})
        print(f"\n### {name} map, 3 robots (shared central map, round-robin), battery 300 each\n\n{HEADER}")
        for overlap in (False, True):
            for v, pop in (("xBOA", 5), ("xBOA", 20), ("BOA", 5)):
                if args.quick and pop == 20:
                    continue
                res = run_config(truth, replace(setup, n_robots=3, overlap_penalty=overlap),
                                 DecisionParams(variant=v, pop_size=pop), reps)
                label = f"{v} pop {pop}, 3 robots{', overlap penalty' if overlap else ''}"
                print(row(label, res), flush=True)
                out.append({"map": name, "robots": 3, "overlap": overlap, "variant": v, "pop": pop, "goals": 1, **res})
    print(f"\ntotal {time.perf_counter() - t_start:.0f} s")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(out, fh, indent=1)


if __name__ == "__main__":
    main()
