"""The report's statistics, as pure functions of the per-run frame (testable on hand-made numbers).

Choices, each stated in the report's Method section:

- **Time to target** is the first tick with explored >= target. When the target is one of the thresholds
  the simulator checks every tick (0.5 ... 0.99) the exact column (t50 ... t99) is used; otherwise the first
  recorded time-series row, so it is late by less than the recording interval.
- A run that never reaches the target is **DNF** (MAES's word); *timeouts* are the DNF runs that stopped at
  ``max_ticks`` (the others stalled, lost every robot, or stopped at a lower ``stop.explored``).
  Means and medians of ticks cover successes only; "mean, DNF = max" counts a DNF as ``max_ticks``
  (a lower bound on its real time).
- **Bands**: a two-sided Student-t interval of the mean across replicates (maps) at each time, n - 1
  degrees of freedom; none with fewer than two runs.
- **Paired comparisons**: runs pair when everything but the compared dimension is equal, replicate included
  (same map, same start poses): :func:`pair_runs`. The tests, effect sizes and Holm's correction on those
  pairs are in :mod:`.effects`.
- **Radio ordering** (:func:`comm_effect`): not judged in 1-robot cells, where every radio model gives the
  same run (a lone robot talks to no one).
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping, Sequence

import numpy as np
import pandas as pd
from scipy import stats as sps

from swarm.results.schema import THRESHOLD_COLUMNS

EXPECTED_RANK = {"global": 0, "multiwall": 1, "maes": 1, "los": 2}
"""Radio models from most to least permissive: the ordering of mean times the paper reports."""


def threshold_column(target: float) -> str | None:
    """``t98`` for 0.98 etc.: the exact per-tick crossing the runs table records, if the target is one."""
    for key, col in THRESHOLD_COLUMNS.items():
        if abs(float(key) - target) < 1e-12:
            return col
    return None


def add_time_to_target(runs: pd.DataFrame, target: float, first_at_series: np.ndarray | None = None) -> pd.DataFrame:
    """``runs`` plus ``ttt`` (ticks to target, NaN for DNF and failed runs), ``success`` and ``ttt_or_max``.

    ``first_at_series`` (per row of ``runs``: first recorded tick at the target, -1 if none) is used when the
    target has no threshold column.
    """
    out = runs.copy()
    col = threshold_column(target)
    if col is not None:
        ttt = pd.to_numeric(out[col], errors="coerce").astype(float)
    elif first_at_series is not None:
        ttt = pd.Series(np.where(np.asarray(first_at_series) >= 0, first_at_series, np.nan), index=out.index,
                        dtype=float)
    else:
        raise ValueError(f"target {target} has no threshold column; pass first_at_series")
    ok = (out["status"] == "ok").to_numpy()
    ttt = ttt.where(ok)
    out["ttt"] = ttt
    out["success"] = ttt.notna()
    out["ttt_or_max"] = ttt.fillna(pd.to_numeric(out["max_ticks"], errors="coerce")).where(ok)
    out["timeout"] = ok & ~out["success"].to_numpy() & (out["stop_reason"] == "max_ticks").to_numpy()
    return out


# ----------------------------------------------------------------------------------------- curves ----
def mean_band(values: np.ndarray, level: float = 0.95) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Per column of ``values`` [runs, times]: mean, lower, upper (t-interval) and the number of runs.

    NaN entries (runs without data) are left out; the band is NaN where fewer than two runs remain.
    """
    v = np.asarray(values, dtype=np.float64)
    have = ~np.isnan(v)
    n = have.sum(axis=0)
    filled = np.where(have, v, 0.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = filled.sum(axis=0) / n
        dev = np.where(have, v - mean, 0.0)
        std = np.sqrt((dev ** 2).sum(axis=0) / (n - 1))
        half = sps.t.ppf(0.5 + level / 2, np.maximum(n - 1, 1)) * std / np.sqrt(n)
    half = np.where(n >= 2, half, np.nan)
    return mean, mean - half, mean + half, n


# ---------------------------------------------------------------------------------------- summary ----
def summary(runs_t: pd.DataFrame, dims: Sequence[str]) -> pd.DataFrame:
    """One row per cell (every dimension in ``dims``), over ok runs: counts and ticks to target (mean, median
    and quartiles over the successes)."""
    ok = runs_t[runs_t["status"] == "ok"]
    g = ok.groupby(list(dims), observed=True, sort=True)
    out = g.agg(runs=("key", "size"), successes=("success", "sum"), timeouts=("timeout", "sum"),
                mean_ticks=("ttt", "mean"), median_ticks=("ttt", "median"), mean_ticks_dnf_max=("ttt_or_max", "mean"),
                fastest=("ttt", "min"), slowest=("ttt", "max"), q1_ticks=("ttt", lambda t: t.quantile(0.25)),
                q3_ticks=("ttt", lambda t: t.quantile(0.75))).reset_index()
    out["successes"] = out["successes"].astype(int)
    out["timeouts"] = out["timeouts"].astype(int)
    out["dnf"] = out["runs"] - out["successes"]
    out["success_rate"] = out["successes"] / out["runs"]
    return out[[*dims, "runs", "successes", "success_rate", "dnf", "timeouts", "mean_ticks", "median_ticks",
                "q1_ticks", "q3_ticks", "mean_ticks_dnf_max", "fastest", "slowest"]]


# ---------------------------------------------------------------------------------------- paired ----
def pair_runs(runs_t: pd.DataFrame, dims: Sequence[str], compare: str = "algorithm") -> pd.DataFrame:
    """Every pair of ok runs that differ only in ``compare`` (same cell otherwise, same replicate).

    One row per (cell, replicate, a, b) with a before b in spec order: ``t_a``, ``t_b`` (DNF at max_ticks),
    ``ok_a``, ``ok_b``, ``diff`` = t_a - t_b and ``winner`` ('a', 'b' or 'tie').
    """
    cell = [d for d in dims if d != compare]
    ok = runs_t[runs_t["status"] == "ok"]
    labels = [lab for lab in ok[compare].cat.categories if (ok[compare] == lab).any()]
    cols = [*cell, "replicate", "ttt_or_max", "success", "key"]
    frames = []
    for a, b in itertools.combinations(labels, 2):
        left = ok.loc[ok[compare] == a, cols]
        right = ok.loc[ok[compare] == b, cols]
        m = left.merge(right, on=[*cell, "replicate"], suffixes=("_a", "_b"))
        if m.empty:
            continue
        m.insert(len(cell) + 1, "a", a)
        m.insert(len(cell) + 2, "b", b)
        frames.append(m)
    if not frames:
        return pd.DataFrame(columns=[*cell, "replicate", "a", "b", "t_a", "t_b", "ok_a", "ok_b", "diff", "winner",
                                     "key_a", "key_b"])
    p = pd.concat(frames, ignore_index=True)
    p = p.rename(columns={"ttt_or_max_a": "t_a", "ttt_or_max_b": "t_b", "success_a": "ok_a", "success_b": "ok_b"})
    p["diff"] = p["t_a"] - p["t_b"]
    a_wins = p["ok_a"] & (~p["ok_b"] | (p["t_a"] < p["t_b"]))
    b_wins = p["ok_b"] & (~p["ok_a"] | (p["t_b"] < p["t_a"]))
    p["winner"] = np.where(a_wins, "a", np.where(b_wins, "b", "tie"))
    for col in ("a", "b"):
        p[col] = pd.Categorical(p[col], categories=list(runs_t[compare].cat.categories), ordered=True)
    return p.sort_values([*cell, "a", "b", "replicate"], kind="stable").reset_index(drop=True)


# ---------------------------------------------------------------------------------- radio effect ----
def comm_effect(runs_t: pd.DataFrame, dims: Sequence[str], models: Mapping[str, str],
                compare: str = "radio") -> pd.DataFrame:
    """Per cell (everything but the radio): mean ticks to target per radio label (DNF at max_ticks),
    the observed ordering and whether it follows global <= material-aware <= LOS.

    Columns: the cell's dimensions, then ``mean:<label>``, ``ok:<label>``, ``n:<label>`` per radio label,
    ``ordering`` and ``as_expected`` (True/False; None when fewer than two labels have a known model, and in
    1-robot cells).
    """
    cell = [d for d in dims if d != compare]
    ok = runs_t[runs_t["status"] == "ok"]
    labels = [lab for lab in runs_t[compare].cat.categories if (ok[compare] == lab).any()]
    g = ok.groupby([*cell, compare], observed=True, sort=True).agg(
        mean=("ttt_or_max", "mean"), ok=("success", "sum"), n=("key", "size"))
    wide = g.unstack(compare)
    wide.columns = [f"{stat}:{lab}" for stat, lab in wide.columns]
    wide = wide.reset_index()
    for lab in labels:
        for stat in ("mean", "ok", "n"):
            if f"{stat}:{lab}" not in wide:
                wide[f"{stat}:{lab}"] = np.nan
    wide = wide[[*cell, *[f"{s}:{lab}" for lab in labels for s in ("mean", "ok", "n")]]]
    orderings, expected = [], []
    lone = (pd.to_numeric(wide["robots"].astype(str), errors="coerce") == 1).to_numpy() if "robots" in wide else (
        np.zeros(len(wide), dtype=bool))
    for (_, row), single in zip(wide.iterrows(), lone):
        means = {lab: row[f"mean:{lab}"] for lab in labels if pd.notna(row[f"mean:{lab}"])}
        orderings.append(_ordering(means, labels))
        expected.append(None if single else _as_expected(means, models))
    wide["ordering"] = orderings
    wide["as_expected"] = expected
    return wide


def _ordering(means: Mapping[str, float], labels: Sequence[str]) -> str:
    ranked = sorted(means, key=lambda lab: (means[lab], labels.index(lab)))
    text = ranked[0] if ranked else ""
    for prev, lab in itertools.pairwise(ranked):
        text += (" = " if abs(means[lab] - means[prev]) < 1e-9 else " < ") + lab
    return text


def _as_expected(means: Mapping[str, float], models: Mapping[str, str]) -> bool | None:
    known = [(EXPECTED_RANK[models[lab]], m) for lab, m in means.items() if models.get(lab) in EXPECTED_RANK]
    if len({r for r, _ in known}) < 2:
        return None
    return all(ma <= mb + 1e-9 for (ra, ma), (rb, mb) in itertools.product(known, known) if ra < rb)
