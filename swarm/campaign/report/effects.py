"""Paired tests, effect sizes and multiple-comparison correction for every comparison the report makes, and
the hook an ablation script calls with its own list of comparisons.

Hook
----
::

    compare_cells(data, comparisons, *, target=0.98, runs_t=None, single_robot=None,
                  resamples=RESAMPLES, seed=SEED) -> pandas.DataFrame

- ``data``: :class:`.load.CampaignData` (``load.load(results_dir)``).
- ``comparisons``: ``[(name, filter_a, filter_b), ...]``. A filter maps grid dimensions (``map``, ``size``,
  ``robots``, ``spawn``, ``algorithm``, ``radio``, ``comm``, ``transport``, and radio/comm parameter axes
  such as ``radio.sensitivity_dbm``) to a label or a list of labels
  (numbers are accepted for numeric labels: ``{"robots": 16}``); a dimension a filter leaves out takes any
  value. The dimensions where the two filters differ are the *contrast*; runs of A and B pair when they
  agree on every other dimension and on the replicate (the same map and start poses), e.g.
  ``("TNF: MAES radio vs ours", {"algorithm": "TNF", "radio": "maes"}, {"algorithm": "TNF", "radio":
  "materials"})`` pairs every TNF run under ``maes`` with the TNF run of the same map, size, robots, spawn,
  comm and replicate under ``materials``, pooled over all of those cells. A filter that selects several runs
  per pairing key (a contrasted dimension given two values) or a contrast on ``map`` or ``size`` (different
  maps never pair) raises ``ValueError``.
- ``target``: explored fraction for ticks to target (as ``--target``); ``runs_t``: a frame from
  :func:`time_to_target` to reuse instead of recomputing it. Without the results folder,
  ``compare_runs(read_runs_csv("report/tables/runs.csv"), comparisons)`` does the same from a report.
- ``single_robot``: keep 1-robot cells; default: dropped when the contrast is only radio/comm/transport
  (a lone robot talks to no one, so those runs are the same run).
- Returns one row per comparison, in the order given, with the columns of :func:`summarise` (``name``,
  ``a``, ``b`` describe the filters); Holm's correction runs across the rows: the family is the list given.
  :func:`effects_table` formats it for :func:`.tables.markdown` / :func:`.tables.latex`.

Statistics (choices stated in the report's Method section and in docs/campaigns.md)
-------------------------------------------------------------------------------------
- **Pairs** share everything but the compared dimension, replicate included: the same map and start poses.
  Each pair gives the log ratio ``log(t_a / t_b)`` of ticks to target; a DNF run counts at its
  ``max_ticks`` (a lower bound on its time, so the ratio understates a DNF's loss; such pairs are counted in
  ``dnf_pairs``), and a pair where both runs are DNF is a tie (log ratio 0). Log ratios, not tick
  differences, because ticks grow ~40-fold from small to large maps and few to many robots: a ratio is
  comparable across cells and its distribution is closer to symmetric, as the signed-rank test assumes.
- **Unit** of the test and the interval: the map (map, size, replicate). Within a cell every pair is its
  own map. Pooled over cells, one map appears in many cells (every robot count and spawn), so its pairs are
  not independent: each map contributes the mean of its pairs' log ratios.
- **Test**: Wilcoxon signed-rank, two-sided, on the units' values; zero values (ties) are dropped
  (Wilcoxon's original convention, scipy's default) and counted in ``ties``. The p-value is the exact
  permutation distribution of the signed ranks with mid-ranks for tied magnitudes (up to ``EXACT_MAX``
  units, the normal approximation with tie correction above), so it does not depend on the scipy version.
  No test below ``MIN_UNITS`` units that differ; with n units the smallest possible p is ``2 ** (1 - n)``
  (0.031 for 6), given in ``p_min``.
- **Holm** step-down correction across the tested rows of one table (the family named in its caption).
- **Effect size**: the median over units of the ratio t_a / t_b (``ratio``; 0.8: a needs 20 % fewer
  ticks) with a 95 % percentile bootstrap interval (``RESAMPLES`` resamples of the units from a
  ``numpy.random.Generator`` seeded from ``SEED`` and the row's labels, so every row is reproducible on
  its own), and the matched-pairs rank-biserial correlation ``r = (W+ - W-) / (W+ + W-)`` of the same signed
  ranks the test uses (+1: a slower on every map, -1: faster on every map). No interval below
  ``MIN_UNITS`` units.
"""

from __future__ import annotations

import zlib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from scipy import stats as sps

from ..spec import is_axis
from ..store import ResultsStore
from . import stats
from .load import DIMS, CampaignData
from .series import sample
from .tables import Table, header, p_value, ticks

MIN_UNITS = 6
"""Units (maps) that differ needed for a test, and units needed for an interval."""
EXACT_MAX = 200
"""Exact signed-rank p-values up to this many units; the normal approximation above."""
RESAMPLES = 2000
"""Bootstrap resamples per interval: bounded, so a 54,000-run report stays in seconds."""
SEED = 33
LEVEL = 0.95
UNITS = ("map", "size", "replicate")
"""A map: the same world and start poses in every cell that shares it."""
COMM_DIMS = ("radio", "comm", "transport")
"""Dimensions that only change how robots talk: 1-robot cells tie on them by construction (and so do the
radio and comm parameter axes: :func:`talk_only`)."""
PAIRED_DIMS = ("algorithm", "radio", "comm", "transport", "robots", "spawn")
"""Dimensions compared pairwise; map kind and size change the map itself, so their runs share nothing."""
COLUMNS = ("cells", "pairs", "maps", "a_wins", "b_wins", "ties", "dnf_pairs", "median_a", "median_b", "mean_diff",
           "median_diff", "ratio", "ratio_low", "ratio_high", "rank_biserial", "tested", "p_min", "p_value",
           "p_holm")


# ------------------------------------------------------------------------------------ statistics ----
@dataclass(frozen=True)
class SignedRank:
    """Wilcoxon signed-rank on one sample of paired values (zeros dropped)."""

    n: int
    """Values that differ from zero: the test's sample size."""
    zeros: int
    w_plus: float
    w_minus: float
    p: float
    """Two-sided p-value; NaN below ``MIN_UNITS`` values that differ."""
    r: float
    """Matched-pairs rank-biserial correlation; NaN without a nonzero value."""


def log_ratios(t_a: np.ndarray, t_b: np.ndarray, ok_a: np.ndarray | None = None,
               ok_b: np.ndarray | None = None) -> np.ndarray:
    """``log(t_a / t_b)`` per pair (ticks floored at 1); 0 where both runs are DNF (``ok_*`` False)."""
    a = np.maximum(np.asarray(t_a, dtype=float), 1.0)
    b = np.maximum(np.asarray(t_b, dtype=float), 1.0)
    out = np.log(a / b)
    if ok_a is not None and ok_b is not None:
        out[~np.asarray(ok_a, dtype=bool) & ~np.asarray(ok_b, dtype=bool)] = 0.0
    return out


def signed_rank(values: np.ndarray, min_n: int = MIN_UNITS) -> SignedRank:
    """Two-sided Wilcoxon signed-rank test of ``values`` (differences or log ratios) against 0.

    Zeros are dropped; tied magnitudes get mid-ranks (magnitudes equal to 12 decimals tie); the p-value is
    exact (the permutation distribution of the observed ranks) up to ``EXACT_MAX`` values.
    """
    v = np.round(np.asarray(values, dtype=float), 12)
    v = v[np.isfinite(v)]
    nz = v[v != 0]
    n, zeros = len(nz), len(v) - len(nz)
    if n == 0:
        return SignedRank(0, zeros, 0.0, 0.0, float("nan"), float("nan"))
    ranks = sps.rankdata(np.abs(nz))
    w_plus, w_minus = float(ranks[nz > 0].sum()), float(ranks[nz < 0].sum())
    r = (w_plus - w_minus) / (w_plus + w_minus)
    p = signed_rank_p(ranks, w_plus) if n >= min_n else float("nan")
    return SignedRank(n, zeros, w_plus, w_minus, p, r)


def signed_rank_p(ranks: np.ndarray, w_plus: float) -> float:
    """Two-sided p of the signed-rank sum ``w_plus`` given the (mid-)ranks of the nonzero values:
    2 x the smaller tail of its distribution when every sign is equally likely (exact up to ``EXACT_MAX``)."""
    ranks = np.asarray(ranks, dtype=float)
    n = len(ranks)
    if n > EXACT_MAX:
        _, counts = np.unique(ranks, return_counts=True)
        mean = n * (n + 1) / 4
        var = n * (n + 1) * (2 * n + 1) / 24 - float((counts ** 3 - counts).sum()) / 48
        z = (w_plus - mean) / np.sqrt(var)
        return float(min(1.0, 2 * sps.norm.sf(abs(z))))
    doubled = np.rint(2 * ranks).astype(np.int64)  # mid-ranks are k or k + 1/2: integers when doubled
    pmf = np.zeros(int(doubled.sum()) + 1)
    pmf[0] = 1.0
    top = 0
    for w in np.sort(doubled):
        nxt = pmf.copy()
        nxt[w:top + w + 1] += pmf[:top + 1]
        pmf = nxt * 0.5
        top += int(w)
    t = int(round(2 * w_plus))
    return float(min(1.0, 2 * min(pmf[:t + 1].sum(), pmf[t:].sum())))


def holm(p_values: Sequence[float] | np.ndarray) -> np.ndarray:
    """Holm's step-down adjusted p-values (family-wise error), in input order; NaN entries are not tests
    (they stay NaN and do not count in the family size)."""
    p = np.asarray(p_values, dtype=float)
    out = np.full(len(p), np.nan)
    tested = np.flatnonzero(~np.isnan(p))
    m = len(tested)
    if m == 0:
        return out
    order = tested[np.argsort(p[tested], kind="stable")]
    adjusted = np.minimum(1.0, np.maximum.accumulate((m - np.arange(m)) * p[order]))
    out[order] = adjusted
    return out


def bootstrap_median_ci(values: np.ndarray, rng: np.random.Generator, resamples: int = RESAMPLES,
                        level: float = LEVEL) -> tuple[float, float]:
    """Percentile bootstrap interval of the median of ``values`` (resampled with replacement)."""
    v = np.asarray(values, dtype=float)
    if len(v) == 0:
        return float("nan"), float("nan")
    idx = rng.integers(0, len(v), size=(int(resamples), len(v)))
    medians = np.median(v[idx], axis=1)
    lo, hi = np.quantile(medians, [(1 - level) / 2, (1 + level) / 2])
    return float(lo), float(hi)


def row_rng(labels: Sequence[Any], seed: int = SEED) -> np.random.Generator:
    """A generator seeded from ``seed`` and a row's labels: a row's interval does not depend on other rows."""
    text = "\x1f".join(str(x) for x in labels)
    return np.random.default_rng([int(seed), zlib.crc32(text.encode("utf-8"))])


# ------------------------------------------------------------------------------------ summarise ----
def summarise(pairs: pd.DataFrame, by: Sequence[str], *, units: Sequence[str] = UNITS,
              cell: Sequence[str] = (), sort: bool = True, resamples: int = RESAMPLES,
              seed: int = SEED) -> pd.DataFrame:
    """One row per group of ``pairs`` (``by``), Holm-adjusted across the rows (the rows are the family).

    ``pairs`` needs ``t_a``, ``t_b`` (ticks, DNF at max_ticks), ``ok_a``, ``ok_b``, ``winner`` and the
    ``units`` columns; ``cell``: columns naming a pair's cell, to count cells (0 when not given).

    Columns: ``by``, ``cells``, ``pairs``, ``maps`` (units), ``a_wins``/``b_wins`` (pairs where that run
    reached the target and the other did not or later), ``ties`` (pairs with equal ticks or both DNF),
    ``dnf_pairs`` (pairs with at least one DNF), ``median_a``/``median_b`` (median ticks over pairs, DNF at
    max), ``mean_diff``/``median_diff`` (a - b, ticks), ``ratio`` with ``ratio_low``/``ratio_high`` (median
    over units of t_a / t_b and its bootstrap interval), ``rank_biserial``, ``tested`` (units that differ),
    ``p_min`` (the smallest p possible with them), ``p_value`` and ``p_holm``.
    """
    by = list(by)
    if pairs.empty:
        return pd.DataFrame(columns=[*by, *COLUMNS])
    lr = log_ratios(pairs["t_a"].to_numpy(float), pairs["t_b"].to_numpy(float),
                    pairs["ok_a"].to_numpy(bool), pairs["ok_b"].to_numpy(bool))
    unit_id = pairs.groupby([*by, *units], observed=True, sort=False).ngroup().to_numpy()
    cell_id = (pairs.groupby(list(cell), observed=True, sort=False).ngroup().to_numpy() if cell
               else np.zeros(len(pairs), dtype=np.int64))
    t_a, t_b = pairs["t_a"].to_numpy(float), pairs["t_b"].to_numpy(float)
    ok_a, ok_b = pairs["ok_a"].to_numpy(bool), pairs["ok_b"].to_numpy(bool)
    winner = pairs["winner"].to_numpy(dtype=object)
    rows = []
    for keys, idx in pairs.groupby(by, observed=True, sort=sort).indices.items():
        keys = keys if isinstance(keys, tuple) else (keys,)
        _, inv = np.unique(unit_id[idx], return_inverse=True)
        values = np.bincount(inv, weights=lr[idx]) / np.bincount(inv)
        test = signed_rank(values)
        if len(values) >= MIN_UNITS:
            lo, hi = bootstrap_median_ci(values, row_rng(keys, seed), resamples)
        else:
            lo = hi = float("nan")
        d = t_a[idx] - t_b[idx]
        rows.append({**dict(zip(by, keys)), "cells": len(np.unique(cell_id[idx])) if cell else 0,
                     "pairs": len(idx), "maps": len(values), "a_wins": int((winner[idx] == "a").sum()),
                     "b_wins": int((winner[idx] == "b").sum()), "ties": int((winner[idx] == "tie").sum()),
                     "dnf_pairs": int((~ok_a[idx] | ~ok_b[idx]).sum()), "median_a": float(np.median(t_a[idx])),
                     "median_b": float(np.median(t_b[idx])), "mean_diff": float(d.mean()),
                     "median_diff": float(np.median(d)), "ratio": float(np.exp(np.median(values))),
                     "ratio_low": float(np.exp(lo)), "ratio_high": float(np.exp(hi)),
                     "rank_biserial": test.r, "tested": test.n,
                     "p_min": 2.0 ** (1 - test.n) if test.n else float("nan"), "p_value": test.p})
    out = pd.DataFrame(rows, columns=[*by, *COLUMNS])
    out["p_holm"] = holm(out["p_value"].to_numpy(float))
    return out


def talk_only(dim: str) -> bool:
    """A dimension that only changes how robots talk (:data:`COMM_DIMS` or a radio/comm parameter axis)."""
    return dim in COMM_DIMS or (is_axis(dim) and dim.partition(".")[0] in ("radio", "comm"))


def dims_of(frame: pd.DataFrame) -> list[str]:
    """The grid dimensions a frame of runs has: :data:`.load.DIMS` and any parameter axes (radio, comm,
    motion, robots.heading)."""
    return [*DIMS, *(c for c in frame.columns if is_axis(c))]


def single_robot(frame: pd.DataFrame) -> np.ndarray:
    """Rows whose ``robots`` label is the number 1."""
    return (pd.to_numeric(frame["robots"].astype(str), errors="coerce") == 1).to_numpy()


def finish_pairs(m: pd.DataFrame) -> pd.DataFrame:
    """Merged runs (``ttt_or_max_a`` ...) renamed to ``t_a``, ``t_b``, ``ok_a``, ``ok_b`` plus ``diff`` and
    ``winner`` ('a' when a reached the target and b did not or later, 'b' likewise, else 'tie')."""
    p = m.rename(columns={"ttt_or_max_a": "t_a", "ttt_or_max_b": "t_b", "success_a": "ok_a", "success_b": "ok_b"})
    p["ok_a"], p["ok_b"] = p["ok_a"].astype(bool), p["ok_b"].astype(bool)
    p["diff"] = p["t_a"] - p["t_b"]
    a_wins = p["ok_a"] & (~p["ok_b"] | (p["t_a"] < p["t_b"]))
    b_wins = p["ok_b"] & (~p["ok_a"] | (p["t_b"] < p["t_a"]))
    p["winner"] = np.where(a_wins, "a", np.where(b_wins, "b", "tie"))
    return p


# ------------------------------------------------------------------------------------------ hook ----
def time_to_target(data: CampaignData, target: float) -> pd.DataFrame:
    """The ok runs of ``data`` with ``ttt``, ``success`` and ``ttt_or_max`` (:func:`.stats.add_time_to_target`),
    from the threshold column or, for other targets, from the time series."""
    ok = data.ok.reset_index(drop=True)
    if stats.threshold_column(target) is not None or ok.empty:
        return stats.add_time_to_target(ok, target, np.full(len(ok), -1))
    cell_id = ok.groupby(list(data.dims), observed=True, sort=True).ngroup().to_numpy()
    sampled = sample(ResultsStore(data.folder), ok, cell_id, data.every, target)
    return stats.add_time_to_target(ok, target, sampled.first_at_target)


def read_runs_csv(path: str | Path) -> pd.DataFrame:
    """A report's ``tables/runs.csv`` read back as :func:`compare_runs` needs it (labels as text, ``ttt_or_max``
    = ticks to target or ``max_ticks`` for a DNF), so published results can be re-analysed without the
    results folder."""
    df = pd.read_csv(path, dtype=str, keep_default_na=False)
    for col in ("replicate", "ticks", "max_ticks", "explored", "map_seed", "ticks_to_target"):
        if col in df:
            df[col] = pd.to_numeric(df[col].replace("", np.nan), errors="coerce")
    df["success"] = df["success"].str.lower() == "true"
    df["ttt_or_max"] = df["ticks_to_target"].fillna(df["max_ticks"]).where(df["status"] == "ok")
    return df


def _label(value: Any) -> str:
    if isinstance(value, float) and value.is_integer():
        return str(int(value))
    return str(value)


def _selection(name: str, side: str, flt: Mapping[str, Any], runs: pd.DataFrame) -> dict[str, frozenset[str]]:
    out = {}
    for dim, value in flt.items():
        if dim not in dims_of(runs):
            raise ValueError(f"{name}: filter {side} names {dim!r}, not a grid dimension "
                             f"({', '.join(dims_of(runs))})")
        values = value if isinstance(value, (list, tuple, set, frozenset)) else [value]
        labels = frozenset(_label(v) for v in values)
        known = set(runs[dim].astype(str))
        missing = sorted(labels - known)
        if missing:
            raise ValueError(f"{name}: filter {side} has {dim} = {missing[0]!r}, which no run has "
                             f"(values: {', '.join(sorted(known))})")
        out[dim] = labels
    return out


def _describe(sel: Mapping[str, frozenset[str]]) -> str:
    return ", ".join(f"{d}={'|'.join(sorted(v))}" for d, v in sel.items()) or "all"


def contrast_pairs(runs_t: pd.DataFrame, filter_a: Mapping[str, Any], filter_b: Mapping[str, Any], *,
                   name: str = "comparison", single_robot_cells: bool | None = None) -> pd.DataFrame:
    """The pairs of one comparison of :func:`compare_cells`: ok runs of A and B that agree on every
    dimension outside the contrast and on the replicate. Columns: the pairing keys, ``t_a``, ``t_b``,
    ``ok_a``, ``ok_b``, ``diff``, ``winner``, ``key_a``, ``key_b`` and the contrasted dimensions' labels
    (``<dim>_a``, ``<dim>_b``)."""
    ok = runs_t[runs_t["status"] == "ok"]
    sel_a, sel_b = _selection(name, "A", filter_a, ok), _selection(name, "B", filter_b, ok)
    dims = dims_of(ok)
    contrast = [d for d in dims if sel_a.get(d) != sel_b.get(d)]
    if not contrast:
        raise ValueError(f"{name}: filters A and B select the same cells")
    if {"map", "size"} & set(contrast):
        raise ValueError(f"{name}: A and B differ in map or size; runs on different maps do not pair")
    keys = [d for d in dims if d not in contrast] + ["replicate", "map_seed"]
    drop_single = all(talk_only(d) for d in contrast) if single_robot_cells is None else not single_robot_cells
    sides = []
    for side, sel in (("A", sel_a), ("B", sel_b)):
        mask = np.ones(len(ok), dtype=bool)
        for dim, labels in sel.items():
            mask &= ok[dim].astype(str).isin(labels).to_numpy()
        if drop_single:
            mask &= ~single_robot(ok)
        part = ok.loc[mask, [*dims, "replicate", "map_seed", "ttt_or_max", "success", "key"]].copy()
        for dim in dims:
            part[dim] = part[dim].astype(str)
        dup = part.duplicated(keys)
        if dup.any():
            several = [d for d in contrast if part[d].nunique() > 1]
            raise ValueError(f"{name}: filter {side} selects several runs per cell and replicate "
                             f"({', '.join(several) or 'a contrasted dimension'} takes several values); give one "
                             f"value per contrasted dimension")
        sides.append(part)
    left, right = sides
    m = left.merge(right, on=keys, suffixes=("_a", "_b"))  # contrasted dimensions get _a and _b
    return finish_pairs(m)


def unit_log_ratios(runs_t: pd.DataFrame, filter_a: Mapping[str, Any], filter_b: Mapping[str, Any]) -> pd.Series:
    """The values :func:`compare_runs` tests for one contrast: per unit (map, size, replicate, as strings), the
    mean log ratio t_a / t_b of its pairs (:func:`log_ratios`: a DNF at its limit). Below 0: a faster on that
    map. For findings scripts that ask per map what a comparison's summary pools."""
    p = contrast_pairs(runs_t, filter_a, filter_b)
    lr = log_ratios(p["t_a"].to_numpy(float), p["t_b"].to_numpy(float), p["ok_a"].to_numpy(bool),
                    p["ok_b"].to_numpy(bool))
    index = pd.MultiIndex.from_frame(p[list(UNITS)].astype(str))
    return pd.Series(lr, index=index).groupby(level=list(range(len(UNITS)))).mean()


def compare_cells(data: CampaignData, comparisons: Sequence[tuple[str, Mapping[str, Any], Mapping[str, Any]]], *,
                  target: float = 0.98, runs_t: pd.DataFrame | None = None, single_robot: bool | None = None,
                  resamples: int = RESAMPLES, seed: int = SEED) -> pd.DataFrame:
    """Paired statistics of each (name, filter A, filter B) comparison, Holm across the list (module doc)."""
    if runs_t is None:
        runs_t = time_to_target(data, target)
    return compare_runs(runs_t, comparisons, single_robot=single_robot, resamples=resamples, seed=seed)


def compare_runs(runs_t: pd.DataFrame, comparisons: Sequence[tuple[str, Mapping[str, Any], Mapping[str, Any]]], *,
                 single_robot: bool | None = None, resamples: int = RESAMPLES, seed: int = SEED) -> pd.DataFrame:
    """:func:`compare_cells` on a frame of runs with ticks to target (``ttt_or_max``, ``success``, the grid
    dimensions, ``replicate``, ``map_seed``, ``status``), e.g. a report's ``tables/runs.csv`` read back."""
    names = [c[0] for c in comparisons]
    if len(set(names)) != len(names):
        raise ValueError("comparison names must be unique")
    frames, described = [], {}
    for order, (name, flt_a, flt_b) in enumerate(comparisons):
        p = contrast_pairs(runs_t, flt_a, flt_b, name=name, single_robot_cells=single_robot)
        ok = runs_t[runs_t["status"] == "ok"]
        described[name] = (_describe(_selection(name, "A", flt_a, ok)), _describe(_selection(name, "B", flt_b, ok)))
        if len(p):
            keys = [d for d in dims_of(runs_t) if f"{d}_a" not in p.columns and d in p.columns]
            p = p.assign(name=name, order=order, cell=p.groupby(keys, sort=False).ngroup())
            frames.append(p[["name", "order", "cell", *UNITS, "t_a", "t_b", "ok_a", "ok_b", "winner"]])
    pairs = pd.concat(frames, ignore_index=True).sort_values("order", kind="stable") if frames else pd.DataFrame(
        columns=["name", "cell", *UNITS, "t_a", "t_b", "ok_a", "ok_b", "winner"])
    out = summarise(pairs, ["name"], cell=["cell"], sort=False, resamples=resamples, seed=seed)
    out = out.set_index("name").reindex(names).reset_index()
    for col in ("cells", "pairs", "maps", "a_wins", "b_wins", "ties", "dnf_pairs", "tested"):
        out[col] = out[col].fillna(0).astype(int)
    out.insert(1, "a", [described[n][0] for n in names])
    out.insert(2, "b", [described[n][1] for n in names])
    return out


# ---------------------------------------------------------------------------------------- tables ----
def ratio_text(r: pd.Series) -> str:
    if pd.isna(r["ratio"]):
        return "–"
    text = f"{r['ratio']:.2f}"
    return text + (f" [{r['ratio_low']:.2f}, {r['ratio_high']:.2f}]" if pd.notna(r["ratio_low"]) else "")


def effects_table(df: pd.DataFrame, labels: Sequence[str], *, cells: bool = False, maps: bool = False) -> Table:
    """A :func:`summarise` / :func:`compare_cells` frame as a table: ``labels`` first (grid dimensions get
    their usual headers), then counts, medians, the ratio with its interval, r, p and Holm's p."""
    head = [{"name": "Comparison", "dimension": "Dimension"}.get(c) or (header(c) if c in DIMS or is_axis(c) else c)
            for c in labels]
    head += (["Cells"] if cells else []) + ["Pairs"] + (["Maps"] if maps else [])
    head += ["a faster", "b faster", "Ties", "DNF", "Median a ticks", "Median b ticks", "a/b (95 % CI)", "r", "p",
             "p (Holm)"]
    rows = []
    for _, r in df.iterrows():
        row = [str(r[c]) for c in labels] + ([str(int(r["cells"]))] if cells else []) + [str(int(r["pairs"]))]
        row += [str(int(r["maps"]))] if maps else []
        row += [str(int(r["a_wins"])), str(int(r["b_wins"])), str(int(r["ties"])), str(int(r["dnf_pairs"])),
                ticks(r["median_a"], "–"), ticks(r["median_b"], "–"), ratio_text(r),
                "–" if pd.isna(r["rank_biserial"]) else f"{r['rank_biserial']:+.2f}", p_value(r["p_value"]),
                p_value(r["p_holm"])]
        rows.append(row)
    n_num = len(head) - len(labels)
    return Table(head, rows, [False] * len(labels) + [True] * n_num)


def a_faster(row: Mapping[str, Any]) -> bool:
    """Whether a row's paired test puts a ahead of b: the side of its signed-rank statistic (rank-biserial
    below 0: the log ratios a/b lean negative). Not the median ratio, which is exactly 1 when most maps tie
    (a cell where a radio cannot matter) however clear the test is on the rest."""
    return bool(row["rank_biserial"] < 0)


def tally(df: pd.DataFrame, alpha: float = 0.05) -> tuple[int, int, int]:
    """(tested rows, rows with p < alpha, rows with Holm p < alpha)."""
    p, h = df["p_value"].to_numpy(float), df["p_holm"].to_numpy(float)
    return int(np.isfinite(p).sum()), int((p < alpha).sum()), int((h < alpha).sum())


