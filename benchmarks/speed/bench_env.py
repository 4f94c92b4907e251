"""RL step cost: ``python benchmarks/speed/bench_env.py [--robots 8] [--size 50] [--pairs 7]``.

How much one ``step()`` of the PettingZoo environment (:class:`swarm.env.SwarmParallelEnv`, one agent per
robot, one tick per step) costs against one tick of the runtime on the same run (goal: at most 1.5x).

- ``same run``: the env with every agent delegating to its explorer (the spec's ``algorithm``) steps the
  very run ``Simulation.run`` runs, tick for tick (tested bit for bit), so the ratio is the environment's
  own overhead: building every agent's observation (crop, goal choices, neighbours with the all-pairs
  radio picture, inbox), rewards, and PettingZoo's dicts.
- ``random goals``: agents pick uniformly among the goal choices instead (another trajectory, so another
  workload; shown for what training costs).

Each pair runs the runtime (``Simulation.run``'s own loop steps) and the env on the same seed in this
process, alternating blocks of ``--block`` ticks, so both meet the machine in the same state (CPU time,
``time.process_time``, so time descheduled by other jobs does not count); the ratio is taken per pair.
Prints every pair, then the median and range of the ratios.
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

import swarm.env as senv
from swarm.sim.loop import Simulation
from swarm.transport import make_host


def spec(args: argparse.Namespace) -> dict:
    return {"map": {"kind": args.kind, "size": args.size}, "robots": {"count": args.robots},
            "algorithm": {"name": args.algorithm}, "stop": {"max_ticks": args.max_ticks}}


class RuntimeRun:
    """``Simulation.run``'s loop, a block of ticks at a time (the same steps ``_loop`` takes)."""

    def __init__(self, args: argparse.Namespace, seed: int) -> None:
        self.sim = Simulation({**spec(args), "seed": seed})
        self.host = make_host("inprocess", self.sim.spec.key)
        self.host.start(self.sim.resets())
        self.state = self.sim.start_state()
        self.done = self.sim.sense(self.state)
        self.count = 0

    def block(self, n: int) -> None:
        sim, state, host = self.sim, self.state, self.host
        for _ in range(n):
            if self.done:
                return
            sim.apply(state, host.act(sim.observe(state)))
            self.done = sim.sense(state)
            self.count += 1


class EnvRun:
    """The ParallelEnv on the same spec and seed, a block of steps at a time."""

    def __init__(self, args: argparse.Namespace, seed: int, policy: str) -> None:
        self.env = senv.SwarmParallelEnv(spec(args), delegate=True, crop_cells=args.crop)
        self.env.reset(seed=seed)
        self.delegate = self.env.core.config.n_actions - 1
        self.policy = policy
        self.rng = np.random.default_rng(seed)
        self.done = False
        self.count = 0

    def block(self, n: int) -> None:
        env = self.env
        for _ in range(n):
            if not env.agents:
                self.done = True
                return
            if self.policy == "same run":
                actions = {a: self.delegate for a in env.agents}
            else:
                actions = {a: int(self.rng.integers(1, self.delegate)) for a in env.agents}
            env.step(actions)
            self.count += 1
        self.done = not env.agents


def pair(args: argparse.Namespace, seed: int, policy: str) -> tuple[float, float, int, int]:
    """CPU seconds per runtime tick and per env step, the two advanced in alternating blocks of
    ``args.block`` ticks (so both meet the same machine), and their tick / step counts."""
    runtime, env = RuntimeRun(args, seed), EnvRun(args, seed, policy)
    spent = {"runtime": 0.0, "env": 0.0}
    while not (runtime.done and env.done):
        for name, side in (("runtime", runtime), ("env", env)):
            t0 = time.process_time()
            side.block(args.block)
            spent[name] += time.process_time() - t0
    return spent["runtime"] / runtime.count, spent["env"] / env.count, runtime.count, env.count


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
    ap.add_argument("--block", type=int, default=50, help="ticks each side runs before the other's turn")
    args = ap.parse_args()
    pair(args, args.seed, "same run")  # compile and warm every kernel first
    for policy in ("same run", "random goals"):
        ratios = []
        for k in range(args.pairs):
            seed = args.seed + k
            tick, step, ticks, steps = pair(args, seed, policy)
            ratio = step / tick
            ratios.append(ratio)
            print(f"{policy:12s} seed {seed}: runtime {1e6 * tick:7.1f} us/tick ({ticks} ticks), "
                  f"env {1e6 * step:7.1f} us/step ({steps} steps), ratio {ratio:.3f}")
        print(f"{policy}: step / tick median {statistics.median(ratios):.3f}, range {min(ratios):.3f}-{max(ratios):.3f} "
              f"over {len(ratios)} pairs ({args.robots} robots, {args.kind} {args.size})")


if __name__ == "__main__":
    main()
