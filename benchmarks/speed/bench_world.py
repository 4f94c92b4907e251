"""Physics cost per logic tick: ``python benchmarks/speed/bench_world.py [--size 150] [--robots 16] [--ticks 5000]``.

Spawns the robots on free cells of ``generate("building", size, seed)`` and drives them with random-ish
commands (each robot holds a random (v, omega) for 5-30 ticks, mostly forward, so robots keep running
into walls and each other). Prints the number of wall rectangles, microseconds per ``World.step`` for
the default and the MAES drive (best and median of ``--repeats`` runs), the share of robot-ticks in
contact, and the cost of one ``Follower.command``. The simulation targets >= 1500 ticks/s in total, so
physics should stay well under 100 us per tick for 16 robots.
"""

from __future__ import annotations

import argparse
import math
import statistics
import time

import numpy as np

from maps import generate
from maps.raster import robot_space
from swarm.world.motion import Follower, MotionParams
from swarm.world.physics import World


def spawn_poses(free: np.ndarray, count: int, rng: np.random.Generator, spacing: float = 0.7) -> np.ndarray:
    """``count`` poses on robot-space cell centres, at least ``spacing`` apart, random headings."""
    cells = np.argwhere(robot_space(free))
    poses: list[tuple[float, float, float]] = []
    for idx in rng.permutation(len(cells)):
        r, c = cells[idx]
        x, y = (c + 0.5) * 0.5, (r + 0.5) * 0.5
        if all(math.hypot(x - px, y - py) >= spacing for px, py, _ in poses):
            poses.append((x, y, float(rng.uniform(-math.pi, math.pi))))
            if len(poses) == count:
                return np.array(poses)
    raise SystemExit("not enough free space for the robots")


def command_schedule(n: int, ticks: int, params: MotionParams, rng: np.random.Generator) -> np.ndarray:
    """``float64[ticks, n, 2]``: piecewise-constant random commands."""
    out = np.empty((ticks, n, 2))
    for i in range(n):
        t = 0
        while t < ticks:
            hold = int(rng.integers(5, 31))
            v = params.max_speed * rng.uniform(-0.2, 1.0)
            w = params.max_turn_rate * rng.uniform(-1.0, 1.0) * (rng.random() < 0.5)
            out[t:t + hold, i] = (v, w)
            t += hold
    return out


def run_once(world: World, schedule: np.ndarray) -> tuple[float, float, float]:
    """Wall-clock and CPU seconds for all steps, and the share of robot-ticks with a contact. CPU time is
    the steadier figure on a shared machine; wall-clock is what a run sees."""
    contacts = 0
    t0, c0 = time.perf_counter(), time.process_time()
    for cmd in schedule:
        world.step(cmd)
        contacts += int(world.collided.sum())
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    return wall, cpu, contacts / (schedule.shape[0] * schedule.shape[1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--size", type=int, default=150)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--robots", type=int, default=16)
    ap.add_argument("--ticks", type=int, default=5000)
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args()

    truth = generate("building", args.size, args.seed)
    rng = np.random.default_rng(args.seed)
    poses = spawn_poses(truth.free, args.robots, rng)
    print(f"map: {truth.summary()}")
    print(f"wall rectangles: {len(truth.wall_rectangles)}")
    for name, params in (("default", MotionParams()), ("maes", MotionParams.maes())):
        schedule = command_schedule(args.robots, args.ticks, params, np.random.default_rng(args.seed + 1))
        t0 = time.perf_counter()
        warm = World(truth, poses, params)
        build_ms = (time.perf_counter() - t0) * 1e3
        warm.step(schedule[0])                       # loads the numba kernels outside the timing
        walls, cpus = [], []
        share = 0.0
        for _ in range(args.repeats):
            world = World(truth, poses, params)
            wall, cpu, share = run_once(world, schedule)
            walls.append(wall / args.ticks * 1e6)
            cpus.append(cpu / args.ticks * 1e6)
        print(f"{name:8s} {params.substeps:2d} sub-steps: step {min(walls):6.1f} us best / "
              f"{statistics.median(walls):6.1f} us median wall-clock, {min(cpus):6.1f} us best CPU "
              f"({args.robots} robots, {args.ticks} ticks, {args.repeats} runs); "
              f"{100 * share:4.1f} % robot-ticks in contact; build {build_ms:.0f} ms")

    follower = Follower(MotionParams())
    path = np.array([[1.0, 1.0], [5.0, 1.0], [5.0, 6.0], [9.0, 9.0]])
    follower.set_path(path)
    pose = (0.5, 0.8, 0.3)
    n = 20000
    t0 = time.perf_counter()
    for _ in range(n):
        follower.command(pose)
    print(f"Follower.command: {(time.perf_counter() - t0) / n * 1e6:.1f} us per call")


if __name__ == "__main__":
    main()
