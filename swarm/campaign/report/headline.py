"""The report's finding: one sentence on its first page saying how much the radio model and the algorithm
changed the time to target, from the runs' means (the paired tests further down say which differences are
established)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
import pandas as pd

from .units import seconds


def _pct(x: float) -> str:
    return f"{100 * x:g} %"


def _change(ratio: float) -> str:
    """A ratio as a signed percentage: 1.43 -> '+43 %'."""
    return f"{100 * (ratio - 1):+.0f} %"


def _means(df: pd.DataFrame, by: str, order: Sequence[str]) -> dict[str, float]:
    """Mean simulated seconds to target (DNF at max_ticks) per value of ``by``, in ``order``."""
    got = df.groupby(df[by].astype(str), observed=True)["ttt_or_max"].mean()
    return {v: float(seconds(got[v])) for v in order if v in got.index and np.isfinite(got[v])}


def _matched(df: pd.DataFrame, by: str, values: Sequence[str], orders: Mapping[str, Sequence[str]]) -> pd.DataFrame:
    """The runs of ``df`` whose set-up (every other dimension, map, size and replicate) was run with every one
    of ``values`` of ``by``: means over them compare like with like. A campaign that runs some values on some
    cells only (an ``[[include]]``: global radio on the small maps alone) would otherwise compare a mean over
    small maps with one over all."""
    keys = list(dict.fromkeys(c for c in (*orders, "map", "size", "replicate") if c in df.columns and c != by))
    df = df[df[by].astype(str).isin(list(values))]
    if df.empty or not keys:
        return df
    have = df.groupby(keys, observed=True)[by].transform("nunique")  # as build._against_figure's complete cells
    return df[have.to_numpy() == len(set(values))]


def finding(runs: pd.DataFrame, orders: Mapping[str, Sequence[str]], target: float) -> str | None:
    """One sentence: per algorithm, how far the radio model moved its mean time to ``target`` from the first
    radio model (the most and the least affected algorithm), and how far apart the algorithms were under
    that radio model. None when neither the radio model nor the algorithm varies, or no run is done.
    ``runs``: the report's runs with ``ttt_or_max`` (ticks), ``status``, ``algorithm`` and ``radio``. Each
    mean compares like with like: a radio model against the first on the set-ups run with both (per
    algorithm), the algorithms on the set-ups run with all of them."""
    ok = runs[runs["status"] == "ok"]
    algorithms = [a for a in orders.get("algorithm", []) if (ok["algorithm"].astype(str) == a).any()]
    radios = ([r for r in orders.get("radio", []) if (ok["radio"].astype(str) == r).any()]
              if "radio" in ok.columns else [])
    if ok.empty or (len(algorithms) < 2 and len(radios) < 2):
        return None
    maps = ok[[c for c in ("map", "size", "replicate") if c in ok.columns]].drop_duplicates()
    if not ok["success"].any():
        return f"No run reached {_pct(target)} explored within its time limit ({len(maps)} maps)."
    head = f"Over {len(maps)} maps (mean time to {_pct(target)} explored"
    head += ", runs that never reached it counted at their time limit)" if (~ok["success"]).any() else ")"
    parts = []
    ref = radios[0] if radios else None
    if len(radios) >= 2:
        effects = []
        for alg in algorithms or [None]:
            runs_a = ok if alg is None else ok[ok["algorithm"].astype(str) == alg]
            pairs = {}
            for other in radios[1:]:
                means = _means(_matched(runs_a, "radio", [ref, other], orders), "radio", [ref, other])
                if len(means) == 2:
                    pairs[other] = (means[ref], means[other])
            if not pairs:
                continue
            worst = max(pairs, key=lambda r: abs(pairs[r][1] / pairs[r][0] - 1))
            a, b = pairs[worst]
            effects.append((abs(b / a - 1), alg, worst, a, b))
        if effects:
            effects.sort(key=lambda e: (-e[0], str(e[1])))
            _, alg, worst, a, b = effects[0]
            who = f"{alg}'s" if alg is not None else "the"
            if round(100 * abs(b / a - 1)) == 0:
                parts.append(f"the radio model did not change the time ({a:.0f} s under {ref})")
            else:
                parts.append(f"the radio model moved {who} time from {a:.0f} s under {ref} to {b:.0f} s under "
                             f"{worst} ({_change(b / a)})")
            if len(effects) > 1 and round(100 * effects[0][0]) != 0:
                _, alg2, worst2, a2, b2 = effects[-1]
                parts[-1] += f" but {alg2}'s only by {_change(b2 / a2)} ({worst2})"
    if len(algorithms) >= 2:
        under = ok if ref is None else ok[ok["radio"].astype(str) == ref]
        present = [a for a in algorithms if (under["algorithm"].astype(str) == a).any()]
        means = _means(_matched(under, "algorithm", present, orders), "algorithm", present)
        if len(means) >= 2:
            fast, slow = min(means, key=means.get), max(means, key=means.get)
            where = f" under {ref} radio" if ref is not None and len(radios) >= 2 else ""
            if round(means[fast]) == round(means[slow]):
                parts.append(f"the algorithms all took {means[fast]:.0f} s{where}")
            else:
                parts.append(f"the algorithms ranged from {fast} ({means[fast]:.0f} s) to {slow} "
                             f"({means[slow]:.0f} s){where}")
    if not parts:
        return None
    return f"{head}, " + ", and ".join(parts) + "."
