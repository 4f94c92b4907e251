"""The report's communication section, as pure functions of the per-run frame: what the radio carried and
lost, how the robots stayed in touch, how complete and how fresh their knowledge was (docs/comm-metrics.md),
per cell, pooled per compared value, and paired against a reference value with the statistics of
:mod:`.effects`; and the sentences that say, from those numbers, whether a comm setting changed exploration
time and which metric shows why.

Quantities per run (from the runs table):

- *delivered %*: the share of the other robots each message reached: deliveries over ``(msgs_sent -
  msgs_relayed) x (robots - 1)`` (with relaying a robot gets each message once, whichever copy brings it);
- *lost %* (per cause): failed deliveries over ``msgs_sent x (robots - 1)``, every transmission counted
  (relayed copies included; without relaying the two shares add up to 100 %);
- *biggest group %*, *all connected %*: mean over the recorded rows;
- *contact gap (s)*: ticks since a robot last received anything, mean over robots and rows, in seconds;
- *missing %*: share of the team's known free cells a robot does not know, mean over robots and rows;
- *AoI age (s)*: mean age of a robot's information about the others, in seconds.

Paired effects compare each value of a talk-only dimension (radio, comm, a radio/comm parameter axis) with
the dimension's first value in spec order (the reference), per algorithm, every other dimension pooled: time
to target as :func:`.effects.summarise` does (ratio, interval, Wilcoxon, Holm over the table's rows), each
comm metric by the per-map mean of its paired differences (Wilcoxon, Holm per metric over the rows). 1-robot
runs are left out (a lone robot talks to no one).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd

from swarm.results.schema import DROP_CAUSES
from . import effects
from .tables import Table, header, p_value
from .units import seconds

METRICS = {
    "delivered_pct": "Delivered %",
    "missing_pct": "Missing %",
    "aoi_age_s": "AoI age (s)",
    "contact_s": "Contact gap (s)",
    "biggest_pct": "Biggest group %",
    "connected_pct": "All connected %",
}
"""The comm metrics compared in pairs, with their headers."""
SAME_DELIVERED_PP = 1.0
"""Delivered shares within this many percentage points count as 'as many messages arrived'."""
SAME_MISSING_PP = 1.0
"""Missing shares within this many percentage points count as 'no knowledge lost'."""
GROUPED_PCT = 75.0
"""A mean biggest group of at least this share of the robots counts as 'robots stayed in groups'."""
SAME_AGE = 0.2
"""AoI ages within this relative difference count as 'about as fresh'."""


def has_comm(runs: pd.DataFrame) -> bool:
    """Do the ok runs carry communication metrics (results of versions that recorded them)?"""
    ok = runs[runs["status"] == "ok"]
    return bool(len(ok)) and bool(ok["aoi_age_mean"].notna().any())


def robots_of(frame: pd.DataFrame) -> np.ndarray:
    return pd.to_numeric(frame["robots"].astype(str), errors="coerce").to_numpy(float)


def derive(runs_t: pd.DataFrame) -> pd.DataFrame:
    """``runs_t`` plus the per-run quantities of the module docstring (percentages and seconds)."""
    out = runs_t.copy()
    n = robots_of(out)
    others = np.maximum(n - 1, 0)
    sent = out["msgs_sent"].to_numpy(float)
    messages = (sent - out["msgs_relayed"].fillna(0).to_numpy(float)) * others  # (message, robot) pairs
    transmissions = sent * others
    with np.errstate(invalid="ignore", divide="ignore"):
        out["delivered_pct"] = np.where(messages > 0, 100 * out["msgs_delivered"].to_numpy(float) / messages, np.nan)
        share = lambda col: np.where(transmissions > 0, 100 * out[col].to_numpy(float) / transmissions,  # noqa: E731
                                     np.nan)
        out["lost_pct"] = share("msgs_dropped")
        for cause in DROP_CAUSES:
            out[f"lost_{cause}_pct"] = share(f"msgs_{cause}")
    out["kb_sent"] = out["bytes_sent"].to_numpy(float) / 1000
    out["missing_pct"] = 100 * out["missing_free_mean"].to_numpy(float)
    out["aoi_age_s"] = seconds(out["aoi_age_mean"].to_numpy(float))
    out["contact_s"] = seconds(out["since_contact_mean"].to_numpy(float))
    out["biggest_pct"] = 100 * out["biggest_group_mean"].to_numpy(float)
    out["connected_pct"] = 100 * out["all_connected_share"].to_numpy(float)
    return out


def causes_seen(frame: pd.DataFrame) -> list[str]:
    """The drop causes with a loss in some run (a table shows only those)."""
    return [c for c in DROP_CAUSES if (frame[f"msgs_{c}"].fillna(0) > 0).any()]


COLUMNS = ("kb_sent", "delivered_pct", "lost_pct", *(f"lost_{c}_pct" for c in DROP_CAUSES), "biggest_pct",
           "connected_pct", "contact_s", "missing_pct", "aoi_age_s", "ttt_or_max")


def cell_means(frame: pd.DataFrame, by: Sequence[str]) -> pd.DataFrame:
    """Mean of every quantity over the ok runs of each group of ``by`` (and the group's run count)."""
    ok = frame[frame["status"] == "ok"]
    g = ok.groupby(list(by), observed=True, sort=True)
    out = g[list(COLUMNS)].mean().reset_index()
    out.insert(len(by), "runs", g.size().to_numpy())
    return out


def means_table(df: pd.DataFrame, by: Sequence[str], causes: Sequence[str]) -> Table:
    """A :func:`cell_means` frame as a table (lost deliveries per cause seen, or their total)."""
    lost = [(f"lost_{c}_pct", f"Lost: {c.removeprefix('dropped_')} %") for c in causes] or [("lost_pct", "Lost %")]
    cols = [("kb_sent", "kB sent"), ("delivered_pct", "Delivered %"), *lost, ("biggest_pct", "Biggest group %"),
            ("connected_pct", "All connected %"), ("contact_s", "Contact gap (s)"), ("missing_pct", "Missing %"),
            ("aoi_age_s", "AoI age (s)"), ("ttt_or_max", "Ticks to target (DNF = max)")]
    rows = [[str(r[d]) for d in by] + [str(int(r["runs"]))] + [_number(r[c]) for c, _ in cols]
            for _, r in df.iterrows()]
    return Table([header(d) if d != "dimension" else "Dimension" for d in by] + ["Runs"] + [h for _, h in cols],
                 rows, [False] * len(by) + [True] * (len(cols) + 1))


def _number(x: float) -> str:
    if pd.isna(x):
        return "–"
    return f"{x:.0f}" if abs(x) >= 100 else f"{x:.1f}"


# --------------------------------------------------------------------------------------- paired ----
def talk_dims(dims: Sequence[str], varies: dict[str, bool]) -> list[str]:
    """The shown dimensions that only change how robots talk and take several values (not transport: it
    changes no result by design)."""
    return [d for d in dims if effects.talk_only(d) and d != "transport" and varies.get(d)]


def paired_effects(frame: pd.DataFrame, dims: Sequence[str], talk: Sequence[str],
                   orders: dict[str, list[str]]) -> pd.DataFrame:
    """Per talk-only dimension, algorithm and value b: value b against the reference (the first value) with
    every other dimension pooled, units = maps. Columns: ``dimension``, ``algorithm``, ``a``, ``b``, the
    :func:`.effects.summarise` columns for ticks to target, and per metric of :data:`METRICS`: ``<m>:a``,
    ``<m>:b`` (means over the paired runs), ``<m>:diff`` (median over maps of b - a), ``<m>:p`` and
    ``<m>:p_holm`` (Holm per metric over the rows)."""
    multi = frame[(frame["status"] == "ok") & (robots_of(frame) > 1)]
    rows = []
    for dim in talk:
        labels = [lab for lab in orders[dim] if (multi[dim].astype(str) == lab).any()]
        if len(labels) < 2:
            continue
        ref = labels[0]
        keys = [d for d in dims if d != dim] + ["replicate"]
        left = multi[multi[dim].astype(str) == ref]
        for b in labels[1:]:
            right = multi[multi[dim].astype(str) == b]
            m = left.merge(right, on=keys, suffixes=("_a", "_b"))
            if m.empty:
                continue
            m = effects.finish_pairs(m)
            for alg, grp in m.groupby("algorithm", observed=True, sort=True):
                rows.append((dim, str(alg), ref, b, grp))
    if not rows:
        return pd.DataFrame()
    frames = []
    for k, (dim, alg, a, b, grp) in enumerate(rows):
        frames.append(grp.assign(dimension=dim, algorithm=alg, a=a, b=b, _order=k))
    pairs = pd.concat(frames, ignore_index=True)
    cell = [d for d in ("map", "size", "robots", "spawn") if d in pairs]
    out = effects.summarise(pairs, ["_order", "dimension", "algorithm", "a", "b"], cell=cell, sort=True)
    for metric in METRICS:
        stats = []
        for k, (_, _, _, _, grp) in enumerate(rows):
            va, vb = grp[f"{metric}_a"].to_numpy(float), grp[f"{metric}_b"].to_numpy(float)
            keep = np.isfinite(va) & np.isfinite(vb)
            unit = grp.loc[keep, list(effects.UNITS)].astype(str).agg("|".join, axis=1).to_numpy()
            diffs = pd.Series(vb[keep] - va[keep]).groupby(unit).mean().to_numpy() if keep.any() else np.zeros(0)
            test = effects.signed_rank(diffs)
            stats.append((float(np.mean(va[keep])) if keep.any() else np.nan,
                          float(np.mean(vb[keep])) if keep.any() else np.nan,
                          float(np.median(diffs)) if len(diffs) else np.nan, test.p))
        arr = np.array(stats, dtype=float).reshape(len(rows), 4)
        out[f"{metric}:a"], out[f"{metric}:b"], out[f"{metric}:diff"], out[f"{metric}:p"] = arr.T
        out[f"{metric}:p_holm"] = effects.holm(arr[:, 3])
    out["ties_all"] = out["ties"] == out["pairs"]
    out["verdict"] = [verdict(r) for _, r in out.iterrows()]
    return out.drop(columns="_order")


def effects_table(df: pd.DataFrame) -> Table:
    """The paired comm effects as a table: ticks ratio with its interval and Holm p, then each metric a -> b."""
    head = ["Dimension", "Algorithm", "a (reference)", "b", "Maps", "Ticks b/a (95 % CI)", "p (Holm)",
            "Delivered % a → b", "Missing % a → b", "AoI age (s) a → b", "Biggest group % b", "Time"]
    rows = []
    for _, r in df.iterrows():
        rows.append([str(r["dimension"]), str(r["algorithm"]), str(r["a"]), str(r["b"]), str(int(r["maps"])),
                     _ratio_b_a(r), p_value(r["p_holm"]),
                     _arrow(r, "delivered_pct"), _arrow(r, "missing_pct"), _arrow(r, "aoi_age_s"),
                     _number(r["biggest_pct:b"]), r["verdict"]])
    return Table(head, rows, [False] * 4 + [True] * 7 + [False])


def _ratio_b_a(r: pd.Series) -> str:
    """Ticks b/a (the inverse of :func:`.effects.summarise`'s a/b) with its interval."""
    if pd.isna(r["ratio"]):
        return "–"
    text = f"{1 / r['ratio']:.2f}"
    return text + (f" [{1 / r['ratio_high']:.2f}, {1 / r['ratio_low']:.2f}]" if pd.notna(r["ratio_low"]) else "")


def _arrow(r: pd.Series, metric: str) -> str:
    return f"{_number(r[f'{metric}:a'])} → {_number(r[f'{metric}:b'])}"


def verdict(r: pd.Series) -> str:
    """What the paired test says of b's exploration time against a's: identical, slower, faster, not
    established, or not tested."""
    if r["ties_all"]:
        return "identical"
    if pd.notna(r["p_holm"]) and r["p_holm"] < 0.05:
        return "slower" if effects.a_faster(r) else "faster"  # b against a
    if pd.isna(r["p_value"]):
        return "not tested"
    return "no established difference"


# -------------------------------------------------------------------------------------- findings ----
@dataclass
class Finding:
    """One sentence of the section's text, about b against a for one algorithm."""

    dimension: str
    algorithm: str
    a: str
    b: str
    verdict: str
    text: str


def findings(df: pd.DataFrame) -> list[Finding]:
    """A sentence per row of :func:`paired_effects`: b's exploration time against a's and the metric that
    shows why (thresholds :data:`SAME_DELIVERED_PP`, :data:`SAME_MISSING_PP`, :data:`GROUPED_PCT`,
    :data:`SAME_AGE`)."""
    return [Finding(str(r["dimension"]), str(r["algorithm"]), str(r["a"]), str(r["b"]), r["verdict"], sentence(r))
            for _, r in df.iterrows()]


def sentence(r: pd.Series) -> str:
    """The finding of one row, every clause computed from its numbers."""
    a, b, alg = r["a"], r["b"], r["algorithm"]
    maps = int(r["maps"])
    d_a, d_b = r["delivered_pct:a"], r["delivered_pct:b"]
    m_a, m_b = r["missing_pct:a"], r["missing_pct:b"]
    g_a, g_b = r["aoi_age_s:a"], r["aoi_age_s:b"]
    big = r["biggest_pct:b"]
    delivered = f"a message reached {_pct(d_b)} of the other robots under {b} against {_pct(d_a)} under {a}"
    missing = f"robots missed {_pct(m_b)} of the team's known free cells under {b} against {_pct(m_a)}"
    age = f"their information about the others was {_secs(g_b)} old on average against {_secs(g_a)}"
    ratio = 1 / r["ratio"]  # b / a
    how = {"identical": f"took exactly as long as under {a} in every pair ({int(r['pairs'])})",
           "slower": f"was slower than under {a} (ticks b/a {ratio:.2f}, p (Holm) {p_value(r['p_holm'])})",
           "faster": f"was faster than under {a} (ticks b/a {ratio:.2f}, p (Holm) {p_value(r['p_holm'])})",
           "no established difference": f"time was not shown to differ from {a}'s (ticks b/a {ratio:.2f}, "
                                        f"p (Holm) {p_value(r['p_holm'])})",
           "not tested": f"time against {a}'s: ticks b/a {ratio:.2f}, not tested (runs differ on "
                         f"{int(r['tested'])} of {maps} maps, {effects.MIN_UNITS} needed)"}[r["verdict"]]
    head = f"**{alg}, {r['dimension']} = {b}**: exploration {how}"
    if r["verdict"] in ("slower", "faster"):
        return f"{head}; {delivered}, {missing}, and {age}."
    carried = _direction(d_a, d_b, SAME_DELIVERED_PP)  # more or fewer deliveries under b
    knew = _direction(m_b, m_a, SAME_MISSING_PP)       # more or less knowledge under b (less missing)
    if carried == 0:
        return f"{head}. The comm setting made no difference to what was carried: {delivered}, and {missing}."
    if knew == 0 and carried < 0:
        why = (f"because the robots stayed in groups (the biggest group held {_pct(big)} of them on average)"
               if big >= GROUPED_PCT else
               "as the map updates that did arrive kept each robot up to date" if _close_rel(g_a, g_b, SAME_AGE)
               else f"although their information about the others was older ({_secs(g_b)} against {_secs(g_a)})")
        return f"{head}. Messages were lost ({delivered}) but no knowledge was: {missing}, {why}."
    if knew == 0:
        return f"{head}. Messages reached more robots ({delivered}) but the robots knew no more: {missing}."
    ending = {"identical": "yet exploration time did not change",
              "no established difference": "yet no difference in exploration time was established",
              "not tested": "too few maps to tell whether exploration time followed"}[r["verdict"]]
    return (f"{head}. Messages reached {'fewer' if carried < 0 else 'more'} robots ({delivered}) and the robots knew "
            f"{'less' if knew < 0 else 'more'} ({missing}; {age}); {ending}.")


def _direction(before: float, after: float, tol: float) -> int:
    """+1 when ``after`` exceeds ``before`` by ``tol`` or more, -1 when it falls short by as much, else 0."""
    if pd.isna(before) or pd.isna(after) or abs(after - before) < tol:
        return 0
    return 1 if after > before else -1


def _close_rel(x: float, y: float, tol: float) -> bool:
    return bool(pd.notna(x) and pd.notna(y) and abs(x - y) <= tol * max(abs(x), abs(y), 1e-9))


def _pct(x: float) -> str:
    return "–" if pd.isna(x) else f"{x:.1f} %"


def _secs(x: float) -> str:
    return "–" if pd.isna(x) else f"{x:.1f} s"
