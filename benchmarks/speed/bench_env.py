"""RL step cost: ``python benchmarks/speed/bench_env.py [--robots 8] [--size 50] [--pairs 7]``.

How much one ``step()`` of the PettingZoo environment (:class:`swarm.env.SwarmParallelEnv`, one agent per
robot, one tick per step) costs against one tick of the runtime on the same run (goal: at most 1.5x).

- ``same run``: the env with every agent delegating to its explorer (the spec's ``algorithm``) steps the
  very run ``Simulation.run`` runs, tick for tick (tested bit for bit), so the ratio is the environment's
  own overhead: building every agent's observation (crop, goal choices, neighbours with the all-pairs
  radio picture, inbox), rewards, and PettingZoo's dicts.
- ``random goals``: agents pick uniformly among the goal choices instead (another trajectory, so another
  workload; shown for what training costs).

Each pair runs the runtime and the env alternately in this process on the same seed (CPU time,
``time.process_time``, so time descheduled by other jobs does not count); the ratio is taken per pair.
Prints every pair, then the median and range of the ratios.
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

import swarm.env as senv
from swarm.simulation import Simulation


def spec(args: argparse.Namespace) -> dict:
    return {"map": {"kind": args.kind, "size": args.size}, "robots": {"count": args.robots},
            "algorithm": {"name": args.algorithm}, "stop": {"max_ticks": args.max_ticks}}


def runtime_tick(args: argparse.Namespace, seed: int) -> tuple[float, int]:
    """CPU seconds per tick of ``Simulation.run`` (set-up excluded) and its ticks."""
    sim = Simulation({**spec(args), "seed": seed})
    t0 = time.process_time()
    result = sim.run()
    return (time.process_time() - t0) / result.summary["ticks"], result.summary["ticks"]


def env_step(args: argparse.Namespace, seed: int, policy: str) -> tuple[float, int]:
    """CPU seconds per ``step()`` of the ParallelEnv (reset excluded) and the steps of the episode."""
    env = senv.SwarmParallelEnv(spec(args), delegate=True, crop_cells=args.crop)
    env.reset(seed=seed)
    delegate = env.core.config.n_actions - 1
    rng = np.random.default_rng(seed)
    steps = 0
    t0 = time.process_time()
    while env.agents:
        if policy == "same run":
            actions = {a: delegate for a in env.agents}
        else:
            actions = {a: int(rng.integers(1, delegate)) for a in env.agents}
        env.step(actions)
        steps += 1
    return (time.process_time() - t0) / steps, steps


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--robots", type=int, default=8)
    ap.add_argument("--size", type=int, default=50)
    ap.add_argument("--kind", default="building", choices=("building", "cave"))
    ap.add_argument("--algorithm", default="frontier")
    ap.add_argument("--max-ticks", type=int, default=3000)
    ap.add_argument("--crop", type=int, default=32, help="crop_cells of the observation")
    ap.add_argument("--pairs", type=int, default=7)
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()
    runtime_tick(args, args.seed)  # compile and warm every kernel first
    env_step(args, args.seed, "same run")
    for policy in ("same run", "random goals"):
        ratios = []
        for k in range(args.pairs):
            seed = args.seed + k
            order = ("runtime", "env") if k % 2 == 0 else ("env", "runtime")
            out = {}
            for what in order:
                out[what] = runtime_tick(args, seed) if what == "runtime" else env_step(args, seed, policy)
            ratio = out["env"][0] / out["runtime"][0]
            ratios.append(ratio)
            print(f"{policy:12s} seed {seed}: runtime {1e6 * out['runtime'][0]:7.1f} us/tick ({out['runtime'][1]} ticks), "
                  f"env {1e6 * out['env'][0]:7.1f} us/step ({out['env'][1]} steps), ratio {ratio:.3f}")
        print(f"{policy}: step / tick median {statistics.median(ratios):.3f}, range {min(ratios):.3f}-{max(ratios):.3f} "
              f"over {len(ratios)} pairs ({args.robots} robots, {args.kind} {args.size})")


if __name__ == "__main__":
    main()
