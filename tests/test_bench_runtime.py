"""The runtime benchmark tells runs that compiled numba kernels from runs that measure the simulation."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
from numba import njit

_PATH = Path(__file__).resolve().parents[1] / "benchmarks" / "speed" / "bench_runtime.py"
_SPEC = importlib.util.spec_from_file_location("bench_runtime", _PATH)
assert _SPEC is not None and _SPEC.loader is not None
bench = importlib.util.module_from_spec(_SPEC)
_SPEC.loader.exec_module(bench)


def _run(ticks: int, wall: float, rss: float, compiled: int) -> dict:
    return {"ticks": ticks, "wall": wall, "cpu": wall, "setup": 0.3, "rss_mb": rss, "plans": 5,
            "compiled": compiled, "compile_s": 40.0 if compiled else 0.0}


def test_compiles_counted_counts_a_fresh_kernel_once_with_its_inlined_callee_and_nothing_once_compiled():
    @njit  # no cache: compiled on first call in every process
    def inner(x):
        return x * 2.0

    @njit
    def outer(a):
        return inner(a.sum())

    first = {"kernels": 0, "seconds": 0.0}
    with bench.compiles_counted(first):
        assert outer(np.ones(3)) == 6.0
    assert first["kernels"] == 1 and first["seconds"] > 0.0
    again = {"kernels": 0, "seconds": 0.0}
    with bench.compiles_counted(again):
        assert outer(np.ones(4)) == 8.0  # same types: the compiled version
    assert again == {"kernels": 0, "seconds": 0.0}


def test_report_flags_a_compiling_run_and_summary_leaves_it_out():
    cold, warm_a, warm_b = _run(1000, 50.0, 450.0, 26), _run(1000, 0.8, 200.0, 0), _run(1000, 1.0, 210.0, 0)
    assert "COMPILED 26 numba kernels" in bench.report(cold)
    assert "COMPILED" not in bench.report(warm_a)
    line = bench.summary([cold, warm_a, warm_b])
    assert line.startswith("2 runs: best 1250 ticks/s, median 1125, worst 1000; peak RSS up to 210 MB")
    assert "left out: 1 run(s)" in line
    assert bench.summary([cold]).startswith("1 runs: best 20 ticks/s")  # nothing else to show
    assert "every run compiled" in bench.summary([cold])
    assert "compiled" not in bench.summary([warm_a, warm_b])
