"""Predict a campaign's wall time from a stratified sample of its own runs (``swarm campaign estimate``).

**Strata.** The campaign's cells grouped by the dimensions that drive a run's cost (default: map, size,
robots, algorithm and transport, those the grid has). From each stratum, ``per_cell`` runs: run j is
replicate j (a different map each, the campaign's first replicates 0..k-1) of the stratum's j-th cell in a
seeded random order (from the campaign seed, so radio and spawn are sampled without bias). The sample is
therefore made of runs of the campaign itself (same specs, same keys): written into the campaign's results
folder, they are kept when the campaign runs.

**Cost of a run.** Its wall time in a worker less the time numba spent compiling or loading kernels
(``jit_time_s``: a worker's start-up, not the run's pace). The sample runs on as many local workers as the
prediction is for (at most one per core), so the measured times include the slowdown of workers sharing
the machine (memory bandwidth, and any other load at the time).

**Prediction.** ``T = startup + sum_s N_s * mean_s(cost + gap) / W + tail`` with ``N_s`` the campaign's
runs in stratum ``s``, ``W`` workers, ``gap`` the pool's measured overhead per run (idle time between two
consecutive runs of one worker: sending a spec, returning a result, committing parts), ``startup`` the
measured time for a worker to start and run its first run's kernel loading, and ``tail`` the wait for the
last runs once fewer than ``W`` remain, ``(W - 1) / W`` times the mean cost of the campaign's last ``W``
runs. The 95 % interval is a percentile bootstrap: runs resampled with replacement within each stratum
(2,000 resamples, rescaled so that 2 runs per stratum do not halve their variance), everything else held at
its measured value. With 2 runs per stratum the within-stratum spread is known poorly; the interval is the
sampling uncertainty of this design, not of the machine's future load (a shared machine whose other work
changes between the sample and the campaign moves the real time by as much as that work changes).
"""

from __future__ import annotations

import os
import tempfile
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from swarm.base.errors import InvalidInput

from swarm.sim.spec import derive_seed
from .spec import DIMENSIONS, CampaignSpec

COST_DIMS = ("map", "size", "robots", "algorithm", "transport")
"""Default strata: what changes a run's cost most (radio, spawn and comm change it little)."""
BOOTSTRAP = 2000
CONFIDENCE = 0.95


@dataclass
class Stratum:
    """Cells sharing the values of the stratifying dimensions, and the sample drawn from them."""

    labels: tuple[str, ...]
    cells: list[int]
    """Cell positions (run index = position * replicates + replicate)."""
    runs: int
    """Runs of the campaign (or shard) in this stratum."""
    sample: list[int] = field(default_factory=list)
    """Run indices sampled."""


@dataclass
class SampleRun:
    index: int
    labels: dict[str, str]
    cost_s: float
    cpu_s: float
    status: str


@dataclass
class Estimate:
    """A campaign's predicted wall time on ``workers`` workers, and what it is made of."""

    name: str
    total_runs: int
    workers: int
    sample_workers: int
    by: tuple[str, ...]
    strata: list[Stratum]
    runs: list[SampleRun]
    weights: np.ndarray
    """Per sample run: campaign runs it stands for (N_s / k_s)."""
    gap_s: float
    startup_s: float
    tail_s: float
    predicted_s: float
    low_s: float
    high_s: float
    run_seconds: float
    """Sum of the campaign's predicted run costs (worker-seconds)."""
    gap_seconds: float
    """Sum of the pool's overhead between runs over the campaign (worker-seconds)."""
    cpu_seconds: float
    sample_wall_s: float
    new_runs: int
    notes: list[str] = field(default_factory=list)

    def by_dimension(self) -> dict[str, list[tuple[str, float]]]:
        """Per grid dimension, each value's share of the campaign's run time, in grid order."""
        cost = np.array([r.cost_s for r in self.runs]) * self.weights
        total = float(cost.sum()) or 1.0
        out: dict[str, list[tuple[str, float]]] = {}
        for dim in self.runs[0].labels if self.runs else ():
            shares: dict[str, float] = {}
            for r, c in zip(self.runs, cost):
                shares[r.labels[dim]] = shares.get(r.labels[dim], 0.0) + float(c) / total
            out[dim] = list(shares.items())
        return out

    def slowest(self, n: int = 10) -> list[tuple[Stratum, float, float]]:
        """The ``n`` strata of highest mean cost per run: (stratum, mean seconds per run, share of the total)."""
        by_index = {r.index: r for r in self.runs}
        rows = []
        for s in self.strata:
            costs = [by_index[i].cost_s for i in s.sample if i in by_index]
            if costs:
                mean = float(np.mean(costs))
                rows.append((s, mean, mean * s.runs / max(self.run_seconds, 1e-9)))
        return sorted(rows, key=lambda r: -r[1])[:n]

    def to_dict(self) -> dict[str, Any]:
        return {"campaign": self.name, "runs": self.total_runs, "workers": self.workers,
                "sample_workers": self.sample_workers, "by": list(self.by), "strata": len(self.strata),
                "sample_runs": len(self.runs), "new_runs": self.new_runs, "sample_wall_s": self.sample_wall_s,
                "predicted_s": self.predicted_s, "ci95_s": [self.low_s, self.high_s],
                "run_worker_hours": self.run_seconds / 3600, "gap_worker_hours": self.gap_seconds / 3600,
                "cpu_core_hours": self.cpu_seconds / 3600, "idle_machine_lower_bound_s": self.cpu_seconds / self.workers,
                "gap_s": self.gap_s, "startup_s": self.startup_s, "tail_s": self.tail_s,
                "by_dimension": {d: dict(v) for d, v in self.by_dimension().items()},
                "slowest": [{"stratum": dict(zip(self.by, s.labels)), "mean_s": m, "share": sh}
                            for s, m, sh in self.slowest()],
                "notes": self.notes}


# ------------------------------------------------------------------------------------- sampling ----
def check_by(spec: CampaignSpec, by: Sequence[str] | None) -> tuple[str, ...]:
    if by is None:
        return tuple(d for d in COST_DIMS if d in spec.grid)
    for d in by:
        if d not in spec.grid:
            raise InvalidInput("--by", d, f"dimensions of this campaign's grid: {', '.join(spec.grid)}")
    return tuple(dict.fromkeys(by))


def strata(spec: CampaignSpec, by: Sequence[str], per_cell: int,
           shard: tuple[int, int] | None = None) -> list[Stratum]:
    """The campaign's cells grouped by ``by``, and the sample of each (see the module docstring)."""
    reps = spec.replicates
    n_cells = spec.run_count() // reps
    in_shard = set(spec.indices(shard)) if shard is not None else None
    groups: dict[tuple[str, ...], Stratum] = {}
    for pos in range(n_cells):
        labels = spec.run_at(pos * reps).cell
        key = tuple(str(labels[d]) for d in by)
        s = groups.setdefault(key, Stratum(key, [], 0))
        s.cells.append(pos)
        s.runs += reps if in_shard is None else sum(pos * reps + r in in_shard for r in range(reps))
    for s in groups.values():
        rng = np.random.default_rng(derive_seed(spec.seed, "estimate", *s.labels))
        order = [s.cells[i] for i in rng.permutation(len(s.cells))]
        s.sample = [pos * reps + rep for pos, rep in _pairs(order, reps, per_cell)]
    return [s for s in groups.values() if s.runs > 0]


def _pairs(order: list[int], reps: int, k: int) -> list[tuple[int, int]]:
    """``k`` distinct (cell, replicate) pairs: sample j takes replicate j (another map each time, as long as
    the campaign has replicates) of the cell ``order[j]`` (cells in turn, in their seeded order)."""
    m = len(order)
    want = min(k, m * reps)
    out: list[tuple[int, int]] = []
    seen: set[tuple[int, int]] = set()
    for j in range(2 * m * reps):
        pair = (order[(j + j // reps) % m], j % reps)
        if pair not in seen:
            seen.add(pair)
            out.append(pair)
            if len(out) == want:
                return out
    for rep in range(reps):  # what the interleaving missed, in order
        for cell in order:
            if (cell, rep) not in seen and len(out) < want:
                seen.add((cell, rep))
                out.append((cell, rep))
    return out


# ------------------------------------------------------------------------------------ estimating ----
def estimate(spec: CampaignSpec, *, per_cell: int = 2, workers: int | None = None, by: Sequence[str] | None = None,
             output: str | Path | None = None, shard: tuple[int, int] | None = None, progress: bool = True,
             log: Callable[[str], None] | None = None, seed: int = 0, executor: Any = None) -> Estimate:
    """Run the stratified sample of ``spec`` (into ``output``, or a temporary folder) and predict the wall time
    of the whole campaign (or ``shard``) on ``workers`` workers (default: one per core)."""
    from .executors import make_executor
    from .runner import run_campaign
    from .store import ResultsStore

    if per_cell < 1:
        raise InvalidInput("--per-cell", per_cell, "an integer >= 1")
    workers = workers or os.cpu_count() or 1
    sample_workers = min(workers, os.cpu_count() or 1)
    by = check_by(spec, by)
    groups = strata(spec, by, per_cell, shard)
    sample = sorted(i for s in groups for i in s.sample)
    seen: dict[str, dict[str, Any]] = {}
    with tempfile.TemporaryDirectory(prefix="swarm-estimate-") as tmp:
        folder = Path(output) if output is not None else Path(tmp) / "sample"
        if log:
            log(f"sample: {len(sample)} runs ({per_cell} per stratum of {' x '.join(by)}, {len(groups)} strata) "
                f"on {sample_workers} worker{'s' if sample_workers != 1 else ''}")
        runner = executor if executor is not None else (lambda: make_executor(workers=sample_workers))
        outcome = run_campaign(spec, folder, executor=runner, progress=progress, log=log, indices=sample,
                               on_result=lambda r: seen.__setitem__(r["key"], r))
        table = ResultsStore(folder).runs_table(columns=("key", "index", "status", "wall_time_s", "cpu_time_s",
                                                         "jit_time_s"))
    rows = {} if table is None else {int(i): (st, w, c, j) for i, st, w, c, j in zip(
        *(table.column(n).to_pylist() for n in ("index", "status", "wall_time_s", "cpu_time_s", "jit_time_s")))}
    runs: list[SampleRun] = []
    weights: list[float] = []
    stratum_of: list[int] = []
    for k, s in enumerate(groups):
        got = [i for i in s.sample if i in rows]
        for i in got:
            status, wall, cpu, jit = rows[i]
            labels = {d: str(v) for d, v in spec.run_at(i).cell.items()}
            cost = max(float(wall) - float(jit or 0.0), 0.0)
            runs.append(SampleRun(i, labels, cost, float(cpu if cpu is not None else wall), status))
            weights.append(s.runs / len(got))
            stratum_of.append(k)
    if not runs:
        raise InvalidInput("spec", spec.name, "a campaign whose sample runs could be timed (none was)")
    w = np.asarray(weights)
    cost = np.array([r.cost_s for r in runs])
    notes: list[str] = []
    gap, startup = _pool_overheads(seen, outcome.executor_started, os.getpid())
    if gap is None:
        notes.append("no new runs on a pool to measure its overhead between runs: counted as 0")
        gap, startup = 0.0, 0.0
    if workers > sample_workers:
        notes.append(f"sampled on {sample_workers} workers (this machine's cores) for {workers}: the prediction "
                     "assumes each of them runs as fast as a worker here")
    tail = _tail(spec, groups, runs, stratum_of, workers, shard)
    run_seconds = float((w * cost).sum())
    gap_seconds = gap * float(w.sum())
    predicted = startup + (run_seconds + gap_seconds) / workers + tail
    low, high = _bootstrap(groups, runs, stratum_of, gap, workers, startup + tail, seed)
    failed = sum(r.status != "ok" for r in runs)
    if failed:
        notes.append(f"{failed} sample runs failed; their time counts as the time a failure costs")
    return Estimate(spec.name, sum(s.runs for s in groups), workers, sample_workers, by, groups, runs, w, gap,
                    startup, tail, predicted, low, high, run_seconds, gap_seconds,
                    float((w * np.array([r.cpu_s for r in runs])).sum()), outcome.wall_s, outcome.ran, notes)


def _pool_overheads(results: dict[str, dict[str, Any]], started: float | None,
                    main_pid: int) -> tuple[float | None, float]:
    """(mean idle time between consecutive runs of one worker, mean time from the pool's start to a
    worker's first run plus that run's kernel loading), from the runs the pool ran (not this process's)."""
    per_worker: dict[int, list[tuple[float, float, float]]] = {}
    for r in results.values():
        if r.get("worker_pid") != main_pid and "started" in r:
            per_worker.setdefault(r["worker_pid"], []).append((r["started"], r["ended"], r.get("jit_time_s", 0.0)))
    gaps: list[float] = []
    starts: list[float] = []
    for spans in per_worker.values():
        spans.sort()
        gaps += [b[0] - a[1] for a, b in zip(spans, spans[1:])]
        if started is not None:
            starts.append(spans[0][0] - started + spans[0][2])
    if not gaps:
        return None, 0.0
    return float(np.mean(gaps)), float(np.mean(starts)) if starts else 0.0


def _tail(spec: CampaignSpec, groups: list[Stratum], runs: list[SampleRun], stratum_of: list[int], workers: int,
          shard: tuple[int, int] | None) -> float:
    """``(W - 1) / W`` times the mean cost of the campaign's last ``W`` runs (their strata's mean costs)."""
    if workers <= 1:
        return 0.0
    reps = spec.replicates
    where = {pos: k for k, s in enumerate(groups) for pos in s.cells}
    means = {k: float(np.mean([r.cost_s for r, sk in zip(runs, stratum_of) if sk == k]))
             for k in set(stratum_of)}
    last = list(spec.indices(shard))[-workers:]
    costs = [means[where[i // reps]] for i in last if where.get(i // reps) in means]
    return (workers - 1) / workers * float(np.mean(costs)) if costs else 0.0


def _bootstrap(groups: list[Stratum], runs: list[SampleRun], stratum_of: list[int], gap: float, workers: int,
               fixed: float, seed: int) -> tuple[float, float]:
    """Percentile interval of the prediction: runs resampled with replacement within each stratum, the
    resampled means rescaled by sqrt(k / (k - 1)) (the plain bootstrap of k runs shrinks the variance of
    their mean by (k - 1) / k: half of it for k = 2). A stratum of one sampled run borrows the median
    coefficient of variation of the others (normal draws)."""
    rng = np.random.default_rng(seed)
    totals = np.zeros(BOOTSTRAP)
    cost = np.array([r.cost_s for r in runs])
    of = np.array(stratum_of)
    cvs = [float(np.std(cost[of == k], ddof=1) / max(np.mean(cost[of == k]), 1e-9))
           for k in range(len(groups)) if (of == k).sum() >= 2]
    cv = float(np.median(cvs)) if cvs else 0.0
    for k, s in enumerate(groups):
        c = cost[of == k]
        if len(c) == 0:
            continue
        mean = float(c.mean())
        if len(c) >= 2:
            draws = c[rng.integers(0, len(c), size=(BOOTSTRAP, len(c)))].mean(axis=1)
            draws = mean + np.sqrt(len(c) / (len(c) - 1)) * (draws - mean)
        else:
            draws = mean + cv * mean * rng.standard_normal(BOOTSTRAP)
        totals += s.runs * (np.maximum(draws, 0.0) + gap)
    pred = fixed + totals / workers
    alpha = (1 - CONFIDENCE) / 2
    lo, hi = np.quantile(pred, [alpha, 1 - alpha])
    return float(lo), float(hi)


# ------------------------------------------------------------------------------------- printing ----
def hours(seconds: float) -> str:
    """``11.8 h``, ``42 min`` or ``35 s``."""
    if seconds >= 3 * 3600:
        return f"{seconds / 3600:.1f} h"
    if seconds >= 120:
        return f"{seconds / 60:.0f} min"
    return f"{seconds:.0f} s"


def report_lines(e: Estimate) -> list[str]:
    """What ``swarm campaign estimate`` prints."""
    eff = e.run_seconds / max(e.run_seconds + e.gap_seconds, 1e-9)
    ratio = e.run_seconds / max(e.cpu_seconds, 1e-9)
    lines = [
        f"campaign {e.name}: {e.total_runs:,} runs; sample {len(e.runs)} runs ({e.new_runs} run now, in "
        f"{hours(e.sample_wall_s)}), {len(e.strata)} strata of {' x '.join(e.by)}",
        f"predicted wall time on {e.workers} worker{'s' if e.workers != 1 else ''}: {hours(e.predicted_s)} "
        f"(95 % CI {hours(e.low_s)} - {hours(e.high_s)})",
        f"  = {hours(e.run_seconds)} of runs / {e.workers} workers, pool efficiency {eff:.3f} "
        f"({1000 * e.gap_s:.0f} ms between runs), + start-up {e.startup_s:.0f} s + last runs {e.tail_s:.0f} s",
        f"  runs' CPU time {hours(e.cpu_seconds)}; their wall time is {ratio:.2f}x that on {e.sample_workers} busy "
        f"workers{' (other load on the machine, or workers waiting for memory)' if ratio > 1.15 else ''}",
        f"  with no other load on the machine, at least {hours(e.cpu_seconds / e.workers)} (CPU time over the "
        "workers)",
        "cost by dimension (share of the campaign's run time):",
    ]
    for dim, shares in e.by_dimension().items():
        if len(shares) > 1:
            lines.append(f"  {dim:10s} " + ", ".join(f"{v} {100 * sh:.0f} %" for v, sh in shares))
    lines.append("slowest strata (mean per run; runs; share of the campaign's run time):")
    for s, mean, share in e.slowest():
        lines.append(f"  {' '.join(s.labels):40s} {mean:8.1f} s  {s.runs:7,d}  {100 * share:5.1f} %")
    lines += [f"note: {n}" for n in e.notes]
    return lines


__all__ = ["COST_DIMS", "Estimate", "Stratum", "estimate", "report_lines", "strata"]
