"""The Minotaur paper's findings tested under full MAES parity and with each departure switched to swarm's
(issue 33; reads the ablation report, ``examples/minotaur-ablation.toml``).

    python benchmarks/experiments/maes_parity_findings.py docs/results/maes-parity/report/tables/runs.csv \
        -o docs/results/maes-parity/findings.md

For every finding (a paired contrast in a scope of cells: "Greed is faster than TNF with 2 robots on
150 x 150 buildings") and every condition (full parity, then one departure switched to swarm's), the
contrast's paired statistics from :func:`swarm.campaign.report.effects.compare_runs`: pairs share map,
size, robots, spawn and replicate; each map counts once with the mean log ratio of its pairs (spawns
pooled); median ratio a/b with a 95 % bootstrap interval, rank-biserial r, two-sided Wilcoxon p. Holm's
correction runs over the conditions of one finding (the family: "does this finding hold, and under which
set-up"); with 10 maps the smallest p is 0.002, so a family of all ~60 rows (threshold 0.05 / 60) could
never reject anything on a per-cell finding (the campaign now runs 20 maps per cell).

Conditions: full parity (MAES's radio, comm, algorithms and, where the runs table has a ``motion.model``
column, MAES's motion), then one departure at a time: swarm's radio, links judged at send, swarm's map
sharing, swarm's continuous motion, swarm's TNF, Minotaur and Greed. A runs table from before the motion
axis (issue 49) has no MAES motion: its parity is the continuous motion and the motion condition is left out.

Verdict: *holds* when the paired test leans the paper's way (rank-biserial r < 0: a ahead) with Holm's
p < 0.05, *reversed* when it leans the other way with Holm's p < 0.05, else *not established*. The side is
the test's, not the median ratio's: where most maps tie (Greed's 2-robot cells under MAES's merge, identical
under every radio) the median ratio is exactly 1 while the test is decided by the maps that differ.

Second table, **what each departure does to the contrast**: per map, the change of the log ratio
(departure minus parity), its median as a ratio of ratios with a 95 % bootstrap interval, and a Wilcoxon
test of the changes (Holm over the departures of one finding). A ratio of ratios below 1 moves a/b down
(a gains on b) when the departure is switched to swarm's.
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from swarm.campaign.report import effects
from swarm.campaign.report.tables import Table, markdown, p_value

PARITY = {"radio": "materials", "comm": "MAES"}
PARITY_ALGS = {"Greed": "Greed", "TNF": "TNF", "Minotaur": "Minotaur"}


@dataclass(frozen=True)
class Condition:
    """Full parity, or parity with one departure switched to swarm's."""

    name: str
    radio: str = "materials"
    comm: str = "MAES"
    algs: dict[str, str] = field(default_factory=lambda: dict(PARITY_ALGS))
    motion: str = "maes"


CONDITIONS = (
    Condition("full MAES parity"),
    Condition("swarm's radio (multiwall)", radio="materials (swarm)"),
    Condition("links judged at send", comm="MAES merge, links at send"),
    Condition("swarm's map sharing", comm="swarm sharing, links at receipt"),
    Condition("swarm's motion (continuous)", motion="continuous"),
    Condition("swarm's TNF", algs={**PARITY_ALGS, "TNF": "TNF (swarm)"}),
    Condition("swarm's Minotaur", algs={**PARITY_ALGS, "Minotaur": "Minotaur (swarm)"}),
    Condition("swarm's Greed", algs={**PARITY_ALGS, "Greed": "Greed (swarm)"}),
)
MOTION = "motion.model"


@dataclass(frozen=True)
class Finding:
    """A paper claim as a paired contrast: ``a`` is faster than ``b`` (ratio a/b < 1) in ``scope``."""

    key: str
    claim: str
    scope: dict[str, Any]
    a: str
    b: str
    dim: str = "algorithm"
    """``algorithm``: a and b are algorithm names; ``radio``: radio labels (the algorithm in ``scope``)."""


FINDINGS = (
    Finding("R1", "LOS is slower than materials (Greed, every cell)", {"algorithm": "Greed"}, "materials", "LOS",
            "radio"),
    Finding("R2", "materials is slower than global (Greed, every cell)", {"algorithm": "Greed"}, "global",
            "materials", "radio"),
    Finding("R3", "LOS is slower than materials (TNF and Minotaur, 50 x 50)",
            {"algorithm": ["TNF", "Minotaur"], "size": 50}, "materials", "LOS", "radio"),
    Finding("R4", "materials is slower than global (TNF and Minotaur, 50 x 50)",
            {"algorithm": ["TNF", "Minotaur"], "size": 50}, "global", "materials", "radio"),
    Finding("B2a", "Greed is faster than TNF (2 robots, 150 x 150 buildings; Fig. 7 right)",
            {"map": "building", "size": 150, "robots": 2}, "Greed", "TNF"),
    Finding("B2b", "Minotaur is faster than TNF (2 robots, 150 x 150 buildings; Fig. 7 right)",
            {"map": "building", "size": 150, "robots": 2}, "Minotaur", "TNF"),
    Finding("B2c", "Greed is slightly faster than Minotaur (2 robots, 150 x 150 buildings; Fig. 7 right)",
            {"map": "building", "size": 150, "robots": 2}, "Greed", "Minotaur"),
    Finding("B16a", "Minotaur is faster than Greed (16 robots, buildings; Fig. 8)",
            {"map": "building", "robots": 16}, "Minotaur", "Greed"),
    Finding("B16b", "Minotaur is faster than TNF (16 robots, buildings; Fig. 8)",
            {"map": "building", "robots": 16}, "Minotaur", "TNF"),
    Finding("C1", "Minotaur is slower than Greed on caves (every cave cell)", {"map": "cave"}, "Greed",
            "Minotaur"),
    Finding("C2", "Minotaur is slower than TNF on caves (every cave cell)", {"map": "cave"}, "TNF", "Minotaur"),
    Finding("C3", "TNF is faster than Greed (2 robots, 50 x 50 caves; Fig. 9 left)",
            {"map": "cave", "size": 50, "robots": 2}, "TNF", "Greed"),
    Finding("C4", "Greed is faster than TNF (16 robots, 150 x 150 caves; Fig. 9 right)",
            {"map": "cave", "size": 150, "robots": 16}, "Greed", "TNF"),
)


def filters(f: Finding, c: Condition, motion: bool = True) -> tuple[dict[str, Any], dict[str, Any]] | None:
    """The (A, B) filters of finding ``f`` under condition ``c``, or None when the campaign has no such runs.
    ``motion``: the runs table has a ``motion.model`` column; a table from before the axis (swarm's continuous
    motion everywhere) has none, its parity is that motion and the motion condition is left out."""
    if not motion and c.motion != "maes":
        return None
    pick = {MOTION: c.motion} if motion else {}
    if f.dim == "radio":
        if c.comm != PARITY["comm"] or any(c.algs[k] != k for k in PARITY_ALGS) or c.motion != "maes":
            return None                                   # global and LOS were run under MAES comm only
        radio = {"materials": c.radio}
        base = {**f.scope, "comm": c.comm, **pick}
        return {**base, "radio": radio.get(f.a, f.a)}, {**base, "radio": radio.get(f.b, f.b)}
    base = {**f.scope, "radio": c.radio, "comm": c.comm, **pick}
    return {**base, "algorithm": c.algs[f.a]}, {**base, "algorithm": c.algs[f.b]}


def verdict(r: pd.Series) -> str:
    if pd.isna(r["p_holm"]) or r["p_holm"] >= 0.05:
        return "not established"
    return "**holds**" if effects.a_faster(r) else "**reversed**"


def shift_row(f: Finding, c: Condition, parity: pd.Series, other: pd.Series) -> dict[str, Any]:
    """The change of the contrast's per-map log ratio from parity to condition ``c``."""
    both = pd.concat([parity.rename("p"), other.rename("o")], axis=1, join="inner")
    d = (both["o"] - both["p"]).to_numpy(float)
    test = effects.signed_rank(d)
    lo = hi = float("nan")
    if len(d) >= effects.MIN_UNITS:
        lo, hi = effects.bootstrap_median_ci(d, effects.row_rng((f.key, c.name)))
    return {"finding": f.key, "condition": c.name, "maps": len(d), "ratio": float(np.exp(np.median(d))),
            "ratio_low": float(np.exp(lo)), "ratio_high": float(np.exp(hi)), "rank_biserial": test.r,
            "p_value": test.p}


def analyse(runs: pd.DataFrame) -> tuple[pd.DataFrame, pd.DataFrame]:
    rows, shifts = [], []
    motion = MOTION in runs.columns
    for f in FINDINGS:
        comps, conds = [], []
        parity_filters = filters(f, CONDITIONS[0], motion)
        for c in CONDITIONS:
            fl = filters(f, c, motion)
            if fl is not None and not all(_matches(runs, x) for x in fl):
                fl = None                                                     # a departure this campaign did not run
            if fl is not None and (c is CONDITIONS[0] or fl != parity_filters):   # skip departures it does not touch
                comps.append((c.name, *fl))
                conds.append(c)
        if not conds or conds[0] is not CONDITIONS[0]:
            continue                                    # no parity runs for this finding: nothing to test
        df = effects.compare_runs(runs, comps)
        df.insert(0, "finding", f.key)
        df["verdict"] = [verdict(r) for _, r in df.iterrows()]
        rows.append(df)
        parity = effects.unit_log_ratios(runs, *filters(f, conds[0], motion))
        fs = [shift_row(f, c, parity, effects.unit_log_ratios(runs, *filters(f, c, motion))) for c in conds[1:]]
        if fs:
            sf = pd.DataFrame(fs)
            sf["p_holm"] = effects.holm(sf["p_value"].to_numpy(float))
            shifts.append(sf)
    shift_columns = ["finding", "condition", "maps", "ratio", "ratio_low", "ratio_high", "rank_biserial",
                     "p_value", "p_holm"]
    return (pd.concat(rows, ignore_index=True) if rows else pd.DataFrame(columns=["finding", "name", "verdict"]),
            pd.concat(shifts, ignore_index=True) if shifts else pd.DataFrame(columns=shift_columns))


def _matches(runs: pd.DataFrame, fl: dict[str, Any]) -> bool:
    """Whether any run matches filter ``fl`` (a value or a list of values per column)."""
    mask = np.ones(len(runs), dtype=bool)
    for col, value in fl.items():
        values = [str(v) for v in (value if isinstance(value, list) else [value])]
        mask &= runs[col].astype(str).isin(values).to_numpy()
    return bool(mask.any())


def _ratio(r: pd.Series) -> str:
    return effects.ratio_text(r)


def render(res: pd.DataFrame, shifts: pd.DataFrame, source: str) -> str:
    claims = {f.key: f for f in FINDINGS}
    out = ["# The Minotaur paper's findings under MAES parity, one departure at a time", "",
           f"Written by `python benchmarks/experiments/maes_parity_findings.py {source}` (not edited). The method is "
           "in the script's docstring: a/b is the median over maps of the ratio of ticks to 98 %, a to b (below 1: "
           "a faster, the paper's claim), with its 95 % bootstrap interval; r the rank-biserial correlation; p a "
           "two-sided Wilcoxon signed-rank test over maps; Holm over the conditions of one finding.", ""]
    untested = [f.key for f in FINDINGS if f.key not in set(res["finding"])]
    if untested:
        out += [f"Not tested (the runs table has no full-parity runs for them): {', '.join(untested)}.", ""]
    for key, grp in res.groupby("finding", sort=False):
        f = claims[key]
        out += [f"## {key}: {f.claim}", ""]
        head = ["Condition", "Pairs", "Maps", "a faster", "b faster", "Median a", "Median b", "a/b (95 % CI)",
                "r", "p", "p (Holm)", "Verdict"]
        body = [[r["name"], str(r["pairs"]), str(r["maps"]), str(r["a_wins"]), str(r["b_wins"]),
                 f"{r['median_a']:.0f}" if pd.notna(r["median_a"]) else "–",
                 f"{r['median_b']:.0f}" if pd.notna(r["median_b"]) else "–", _ratio(r),
                 "–" if pd.isna(r["rank_biserial"]) else f"{r['rank_biserial']:+.2f}", p_value(r["p_value"]),
                 p_value(r["p_holm"]), r["verdict"]] for _, r in grp.iterrows()]
        out += [f"a = {f.a}, b = {f.b}.", "", markdown(Table(head, body, [False] + [True] * 10 + [False]))]
        sg = shifts[shifts["finding"] == key]
        if len(sg):
            head = ["Departure switched to swarm's", "Maps", "change of a/b (95 % CI)", "r", "p", "p (Holm)"]
            body = [[r["condition"], str(r["maps"]), _ratio(r),
                     "–" if pd.isna(r["rank_biserial"]) else f"{r['rank_biserial']:+.2f}", p_value(r["p_value"]),
                     p_value(r["p_holm"])] for _, r in sg.iterrows()]
            out += ["What each departure does to a/b (per map: a/b under the departure divided by a/b under "
                    "parity; below 1: a gains on b):", "", markdown(Table(head, body, [False] + [True] * 5))]
    return "\n".join(out) + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs_csv", type=Path, help="the ablation report's tables/runs.csv")
    ap.add_argument("-o", "--output", type=Path, help="Markdown file to write (and a .csv beside it)")
    args = ap.parse_args(argv)
    runs = effects.read_runs_csv(args.runs_csv)
    res, shifts = analyse(runs)
    text = render(res, shifts, str(args.runs_csv))
    if args.output:
        args.output.write_text(text)
        res.to_csv(args.output.with_suffix(".csv"), index=False)
        shifts.to_csv(args.output.with_name(args.output.stem + "-departures.csv"), index=False)
    else:
        sys.stdout.write(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
