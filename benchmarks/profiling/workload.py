"""The issue-3 workload as the profiling scripts take it, and the timer they wrap functions in.

16 robots spawned together on a seeded building map, the frontier explorer, until 99 % explored (as
``benchmarks/speed/bench_runtime.py`` runs it), with ``--robots``, ``--size``, ``--seed`` and
``--max-ticks`` to vary it. The profiling scripts beside it import it (``from workload import ...``: run
them as ``python benchmarks/profiling/SCRIPT.py``, which puts this folder on ``sys.path``).
"""

from __future__ import annotations

import argparse
import time
from collections import Counter
from typing import Any, Callable


def add_workload_arguments(parser: argparse.ArgumentParser) -> None:
    """The workload's command-line options."""
    parser.add_argument("--robots", type=int, default=16)
    parser.add_argument("--size", type=int, default=150)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--max-ticks", type=int, default=36000)


def workload_spec(args: argparse.Namespace) -> dict[str, Any]:
    """The run spec of the parsed options."""
    return {"seed": args.seed, "map": {"kind": "building", "size": args.size},
            "robots": {"count": args.robots, "spawn": "together"}, "algorithm": {"name": "frontier"},
            "stop": {"max_ticks": args.max_ticks}}


def wrap(owner: Any, name: str, label: str, spent: Counter, calls: Counter) -> None:
    """Replace ``owner.name`` by a version that adds its wall time to ``spent[label]``."""
    inner: Callable[..., Any] = getattr(owner, name)

    def timed(*args: Any, **kwargs: Any) -> Any:
        t0 = time.perf_counter()
        try:
            return inner(*args, **kwargs)
        finally:
            spent[label] += time.perf_counter() - t0
            calls[label] += 1

    setattr(owner, name, timed)
