"""Explorer speed per tick, this checkout against another, interleaved:
``python benchmarks/speed/bench_algorithms.py BASE [--algorithms tnf minotaur greed] [--pairs 3] [--warm]``.

The workload is the Minotaur paper's set-up (examples/minotaur-paper.toml [run]: the MAES motion preset,
a 7 m lidar, TNF with alpha = 1 and beta = 10) on the case issue 35 measured: 16 robots spawned together
on a seeded 150-tile building, until 98 % explored (``--kind``, ``--size``, ``--robots``, ``--seed``,
``--max-ticks`` and ``--variant maes`` vary it). Each run is a fresh process with one checkout first on
``PYTHONPATH``; the two checkouts alternate (which goes first alternates too) and each run reports the
CPU seconds of its run loop (``time.process_time`` around ``Simulation.run``, so other processes on the
shared machine cost it little) and the digest of its results (``benchmarks/result_digests.py``'s).

Prints, per algorithm, every pair, then ticks per CPU-second of each side (median and range), the median
speed-up (base CPU / this CPU, per pair) with its range, and whether the two checkouts gave the same
digest in every run: an optimisation must not change a result. Run each side once first after editing a
kernel (``--warm``): the first run of a checkout compiles its numba kernels. A fresh process also loads
the kernels it uses from numba's cache inside its run loop (0.1-0.3 s, 2-5 % of these runs), which a
campaign worker pays once for all its runs: ``--warm-process`` times a second run in each process, after an
untimed one, which is the pace of a worker's later runs.

``--campaign SPEC --cell size=150 robots=16`` measures a campaign's own cells instead: every cell of SPEC
whose labels match (for each algorithm asked, its cells), one replicate's spec (``--replicate``, 0: the
first) as the campaign runs it (map, spawn, radio and seeds included), one pair per cell (``--pairs`` is
not used). It prints each cell's speed-up and, per
algorithm, the speed-up of the whole set (base CPU over this CPU, summed over the cells: what a campaign
of those cells gains) and the median over cells.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parents[2]
MAES_MOTION = {"max_speed": 3.0, "max_turn_rate": 4.0, "max_accel": 60.0, "max_turn_accel": 120.0, "substeps": 8}
ALGORITHMS = ("tnf", "minotaur", "greed", "xboa", "frontier")


def spec(args: argparse.Namespace, algorithm: str) -> dict:
    """The paper's [run] set-up on the chosen map, for ``algorithm``."""
    params: dict = {"alpha": 1.0, "beta": 10.0} if algorithm == "tnf" else {}
    if args.variant != "swarm" and algorithm in ("tnf", "minotaur"):
        params["variant"] = args.variant
    return {"seed": args.seed, "map": {"kind": args.kind, "size": args.size},
            "robots": {"count": args.robots, "spawn": "together"}, "algorithm": {"name": algorithm, "params": params},
            "motion": MAES_MOTION, "lidar": {"range_m": 7.0},
            "stop": {"explored": 0.98, "max_ticks": args.max_ticks}}


def child(spec_json: str, warm_process: bool = False) -> None:
    """Run one spec in this process and print its ticks, run-loop CPU seconds and result digest as JSON
    (``warm_process``: of a second run, after an untimed one)."""
    sys.path.insert(0, str(HERE / "benchmarks"))
    from result_digests import digest  # noqa: E402 - the checkout's own, found on PYTHONPATH's swarm

    from swarm.sim.loop import Simulation

    if warm_process:
        Simulation(json.loads(spec_json)).run()
    sim = Simulation(json.loads(spec_json))
    t0 = time.process_time()
    result = sim.run()
    cpu = time.process_time() - t0
    s = result.summary
    print(json.dumps({"ticks": s["ticks"], "cpu_s": cpu, "explored": s["explored"],
                      "digest": digest(s, result.timeseries, result.events)}))


def campaign_cells(path: str, where: list[str], algorithm: str, replicate: int) -> list[tuple[str, dict]]:
    """(labels, canonical run spec) of replicate ``replicate`` of each cell of the campaign at ``path`` whose
    labels match every ``dim=label`` of ``where`` and whose algorithm is ``algorithm``."""
    from swarm.campaign import load_campaign

    spec = load_campaign(path, max_runs=None)
    want = dict(w.split("=", 1) for w in where)
    reps = spec.replicates
    out = []
    for pos in range(spec.run_count() // reps):
        run_ = spec.run_at(pos * reps + replicate)
        labels = {k: str(v) for k, v in run_.cell.items()}
        if not all(labels.get(k) == v for k, v in want.items()):
            continue
        canonical = run_.canonical()
        if canonical["algorithm"]["name"] == algorithm:
            out.append((" ".join(f"{k}={v}" for k, v in labels.items() if k not in want), canonical))
    return out


def campaign_mode(args: argparse.Namespace, base: Path) -> None:
    """One interleaved pair per matching cell of ``args.campaign`` (see the module docstring)."""
    for algorithm in args.algorithms:
        cells = campaign_cells(args.campaign, args.cell, algorithm, args.replicate)
        if not cells:
            raise SystemExit(f"--cell: no cell of {args.campaign} matches {' '.join(args.cell)} for {algorithm}")
        if args.warm:
            run(base, cells[0][1])
            run(HERE, cells[0][1])
        cpu = {"base": 0.0, "this": 0.0}
        ratios, same = [], True
        for i, (labels, s) in enumerate(cells):
            b, t = pair(base, s, i, args.warm_process)
            same &= b["digest"] == t["digest"]
            cpu["base"] += b["cpu_s"]
            cpu["this"] += t["cpu_s"]
            ratios.append(b["cpu_s"] / t["cpu_s"])
            print(f"{algorithm} {labels}: {b['ticks']} ticks; base {b['ticks'] / b['cpu_s']:.0f}, this "
                  f"{t['ticks'] / t['cpu_s']:.0f} ticks/CPU-s, speed-up {ratios[-1]:.2f}x; digests "
                  f"{'equal' if b['digest'] == t['digest'] else 'DIFFER'}", flush=True)
        print(f"{algorithm}: {len(cells)} cells, CPU base {cpu['base']:.1f} s, this {cpu['this']:.1f} s: speed-up "
              f"{cpu['base'] / cpu['this']:.2f}x over the set, per cell {span(ratios, '.2f')}x; results "
              f"{'identical' if same else 'DIFFERENT'}", flush=True)


def run(checkout: Path, spec_: dict, warm_process: bool = False) -> dict:
    """One run of ``spec_`` in a fresh process with ``checkout`` first on the path (``warm_process``: timed
    after an untimed one in that process)."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [str(checkout), os.environ.get("PYTHONPATH")])))
    flags = ["--warm-process"] if warm_process else []
    out = subprocess.run([sys.executable, __file__, "--child", json.dumps(spec_), *flags], cwd=checkout,
                         env=env, capture_output=True, text=True)
    if out.returncode != 0:
        sys.stderr.write(out.stderr)
        raise SystemExit(f"{checkout}: the run failed")
    return json.loads(out.stdout.strip().splitlines()[-1])


def pair(base: Path, spec_: dict, i: int, warm_process: bool) -> tuple[dict, dict]:
    """Pair ``i``: ``spec_`` run on the base and on this checkout (which goes first alternates with ``i``);
    their results, base first."""
    order = [("base", base), ("this", HERE)] if i % 2 == 0 else [("this", HERE), ("base", base)]
    got = {name: run(where, spec_, warm_process) for name, where in order}
    return got["base"], got["this"]


def span(values: list[float], fmt: str) -> str:
    return f"{format(statistics.median(values), fmt)} ({format(min(values), fmt)}-{format(max(values), fmt)})"


def main() -> None:
    if len(sys.argv) in (3, 4) and sys.argv[1] == "--child":
        child(sys.argv[2], warm_process=sys.argv[3:] == ["--warm-process"])
        return
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("base", type=Path, help="the other checkout (a git worktree of main, say)")
    ap.add_argument("--algorithms", nargs="+", default=["tnf", "minotaur", "greed"], choices=ALGORITHMS)
    ap.add_argument("--pairs", type=int, default=3)
    ap.add_argument("--warm", action="store_true", help="one unmeasured run of each side first (compiles kernels)")
    ap.add_argument("--kind", default="building", choices=("building", "cave"))
    ap.add_argument("--size", type=int, default=150)
    ap.add_argument("--robots", type=int, default=16)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--max-ticks", type=int, default=36000)
    ap.add_argument("--variant", default="swarm", choices=("swarm", "maes"), help="for tnf and minotaur")
    ap.add_argument("--warm-process", action="store_true",
                    help="time a second run in each process, after an untimed one (a campaign worker's pace)")
    ap.add_argument("--campaign", default=None, metavar="SPEC", help="measure this campaign's cells (see above)")
    ap.add_argument("--cell", nargs="*", default=[], metavar="DIM=LABEL", help="with --campaign: the cells to take")
    ap.add_argument("--replicate", type=int, default=0, help="with --campaign: the replicate of each cell")
    args = ap.parse_args()
    base = args.base.resolve()
    if not (base / "swarm").is_dir():
        ap.error(f"base: {base} is not allowed; give a checkout of this project")
    if args.pairs < 1:
        ap.error(f"--pairs: {args.pairs} is not allowed; give a whole number >= 1")
    bad = [w for w in args.cell if "=" not in w]
    if bad:
        ap.error(f"--cell: {bad[0]!r} is not allowed; give DIM=LABEL, e.g. size=150")
    if args.campaign is not None:
        campaign_mode(args, base)
        return
    for algorithm in args.algorithms:
        s = spec(args, algorithm)
        if args.warm:
            run(base, s)
            run(HERE, s)
        rates: dict[str, list[float]] = {"base": [], "this": []}
        ratios, same = [], True
        for i in range(args.pairs):
            b, t = pair(base, s, i, args.warm_process)
            same &= b["digest"] == t["digest"]
            rates["base"].append(b["ticks"] / b["cpu_s"])
            rates["this"].append(t["ticks"] / t["cpu_s"])
            ratios.append(b["cpu_s"] / t["cpu_s"])
            print(f"{algorithm} pair {i + 1}: {b['ticks']} ticks; base {b['cpu_s']:.2f} CPU-s, this {t['cpu_s']:.2f} "
                  f"CPU-s, speed-up {ratios[-1]:.2f}x; digests {'equal' if b['digest'] == t['digest'] else 'DIFFER'}",
                  flush=True)
        print(f"{algorithm}: ticks per CPU-second base {span(rates['base'], '.0f')}, this {span(rates['this'], '.0f')}; "
              f"speed-up {span(ratios, '.2f')}x over {args.pairs} pairs; results "
              f"{'identical' if same else 'DIFFERENT'}", flush=True)


if __name__ == "__main__":
    main()
