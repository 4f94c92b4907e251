"""Time per compiled kernel: ``python benchmarks/profiling/profile_kernels.py [--robots 16 --size 150 --seed 1] [--top 30]``.

Runs the issue-3 workload (as ``benchmarks/speed/bench_runtime.py``) with every numba kernel that Python
code calls wrapped in a timer, and prints per kernel the share of the run, the time per call and the calls. A sampling
profiler cannot name compiled code (py-spy shows it as one anonymous block); this can, and it sees a kernel
regress inside the run, where its inputs, its calls and the caches are the run's own (it caught a corridor
kernel that took 24.6 us per plan against 9.2 before, which the whole run's noise hid).

Kernels are looked up as module attributes in ``swarm``, ``radio`` and ``algorithms`` after a first run of
the same workload, so every kernel is compiled or loaded before it is wrapped (the script takes two runs'
time); calls from one kernel to another stay compiled and are counted in the caller. The timer adds about
1 us per call (a kernel called 170,000 times carries ~0.2 s of it), so compare shares and per-call times
between versions, not with ``benchmarks/speed/bench_runtime.py``.
"""

from __future__ import annotations

import argparse
import importlib
import pkgutil
from collections import Counter
from types import ModuleType

from numba.core.registry import CPUDispatcher
from workload import add_workload_arguments, workload_spec, wrap

import algorithms
import radio
import swarm
from swarm.sim.loop import Simulation

SKIP = ("__main__", ".cli", ".viewer")  # command-line entry points and the browser viewer: not kernels


def project_modules() -> list[ModuleType]:
    """Every importable module of the three packages, except entry points."""
    out = []
    for package in (swarm, radio, algorithms):
        for info in pkgutil.walk_packages(package.__path__, package.__name__ + "."):
            if not any(part in info.name for part in SKIP):
                out.append(importlib.import_module(info.name))
    return out


def wrap_kernels(modules: list[ModuleType], spent: Counter, calls: Counter) -> int:
    """Wrap each numba dispatcher found as a module attribute (once per module that holds it); returns how
    many were wrapped."""
    wrapped = 0
    for module in modules:
        for name, value in list(vars(module).items()):
            if isinstance(value, CPUDispatcher):
                wrap(module, name, f"{value.py_func.__module__}.{value.py_func.__name__}", spent, calls)
                wrapped += 1
    return wrapped


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_workload_arguments(parser)
    parser.add_argument("--top", type=int, default=30, help="kernels to list (by time)")
    args = parser.parse_args()
    # Every kernel the run uses must be compiled before any is wrapped: a kernel compiled later would see
    # a wrapper, not a kernel, where it calls another by name. The same spec runs the same code paths.
    Simulation(workload_spec(args)).run()
    spent: Counter = Counter()
    calls: Counter = Counter()
    sim = Simulation(workload_spec(args))
    wrapped = wrap_kernels(project_modules(), spent, calls)  # after set-up: only the run's calls count
    result = sim.run()
    wall = result.summary["wall_time_s"]
    total = sum(spent.values())
    print(result.one_line())
    print(f"run {wall:.2f} s wall; {wrapped} kernel references wrapped, {total:.2f} s ({100 * total / wall:.1f} %) "
          "inside them")
    for label, seconds in spent.most_common(args.top):
        print(f"{100 * seconds / wall:5.1f} %  {1e6 * seconds / calls[label]:8.1f} us  {calls[label]:8d}  {label}")


if __name__ == "__main__":
    main()
