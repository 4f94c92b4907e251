"""How Greed, TNF and Minotaur degrade with localisation error, with and without avoidance (issue 50; reads
the report of ``examples/localization-study.toml``).

    python benchmarks/experiments/localization_study_findings.py \
        docs/results/localization-study/report/tables/runs.csv -o docs/results/localization-study/findings.md

Three tables:

1. **Time cost of each error model**, per algorithm: the paired ratio of ticks to the target under the error
   model over ticks with perfect localisation (pairs share map, robots, spawn, avoidance and replicate; each
   map counts once; median ratio with a 95 % bootstrap interval, Wilcoxon p, Holm over all rows). DNF runs
   count at the tick limit (``ttt_or_max``), so a ratio near ``max_ticks / perfect`` says runs stopped short.
2. **Map quality**, per algorithm and error model: share of runs reaching the target, medians of the final
   pose error, false free and false occupied shares, wall offset and the explored fraction counting only
   correctly known cells (``explored_correct``; docs/localization.md).
3. **Avoidance**: per algorithm and robot count, the paired ratio of ticks with ORCA over ticks without, and
   the median robot-robot and robot-wall contacts per robot-hour with and without.

The robustness ranking orders algorithms by the largest median time ratio over the error models, then by
the lowest median ``explored_correct`` under any error model.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import pandas as pd

from swarm.campaign.report import effects, units
from swarm.campaign.report.tables import Table, markdown, p_value

MODEL = "localization.model"
LOC_AXES = (MODEL, "localization.drift_per_m", "localization.turn_drift_per_rad", "localization.sigma_m")
AVOID = "navigation.avoidance"


def conditions(runs: pd.DataFrame) -> list[tuple[str, dict[str, str]]]:
    """(label, the localisation axes' labels) of every error model in the runs, perfect first."""
    axes = [a for a in LOC_AXES if a in runs]
    cells = runs[axes].astype(str).drop_duplicates()
    out = []
    for _, c in cells.iterrows():
        model = c[MODEL]
        if model == "perfect":
            label = "perfect"
        elif model == "odometry":
            label = f"odometry {100 * float(c['localization.drift_per_m']):g} %/m"
        else:
            label = f"bounded sigma {float(c['localization.sigma_m']):g} m"
        out.append((label, dict(c)))
    order = {"perfect": 0, "odometry": 1, "bounded": 2}
    return sorted(out, key=lambda lc: (order.get(lc[1][MODEL], 3), lc[0]))


def select(runs: pd.DataFrame, flt: dict[str, str]) -> pd.DataFrame:
    mask = np.ones(len(runs), dtype=bool)
    for col, value in flt.items():
        mask &= (runs[col].astype(str) == value).to_numpy()
    return runs[mask]


def time_costs(runs: pd.DataFrame, conds: list[tuple[str, dict[str, str]]]) -> pd.DataFrame:
    perfect = dict(conds[0][1])
    cells = [(alg, label, c) for alg in sorted(runs["algorithm"].astype(str).unique()) for label, c in conds[1:]]
    out = effects.compare_runs(runs, [(f"{alg} | {label}", {"algorithm": alg, **c}, {"algorithm": alg, **perfect})
                                      for alg, label, c in cells])
    out["algorithm"] = [alg for alg, _, _ in cells]
    out["condition"] = [label for _, label, _ in cells]
    return out


def quality(runs: pd.DataFrame, conds: list[tuple[str, dict[str, str]]]) -> pd.DataFrame:
    rows = []
    ok = runs[runs["status"] == "ok"]
    for alg in sorted(ok["algorithm"].astype(str).unique()):
        for label, c in conds:
            sel = select(ok, {"algorithm": alg, **c})
            rows.append({"algorithm": alg, "condition": label, "runs": len(sel),
                         "success": float(sel["success"].astype(bool).mean()) if len(sel) else np.nan,
                         **{col: float(pd.to_numeric(sel[col]).median()) if col in sel and sel[col].notna().any()
                            else np.nan
                            for col in ("explored", "pose_error_m", "false_free_share", "false_occupied_share", "wall_offset_m",
                                        "explored_correct")}})
    return pd.DataFrame(rows)


def avoidance(runs: pd.DataFrame) -> pd.DataFrame | None:
    if AVOID not in runs or runs[AVOID].nunique() < 2:
        return None
    labels = sorted(runs[AVOID].astype(str).unique())
    off, on = ("none", next(v for v in labels if v != "none")) if "none" in labels else labels[:2]
    comparisons = [(f"{alg} | {n}", {"algorithm": alg, "robots": n, AVOID: on},
                    {"algorithm": alg, "robots": n, AVOID: off})
                   for alg in sorted(runs["algorithm"].astype(str).unique())
                   for n in sorted(runs["robots"].astype(str).unique(), key=int)]
    out = effects.compare_runs(runs, comparisons)
    ok = runs[runs["status"] == "ok"].copy()
    hours = pd.to_numeric(ok["robots"]) * units.seconds(pd.to_numeric(ok["ticks"])) / 3600
    for kind in ("robot", "wall"):
        if f"collisions_{kind}" in ok:
            ok[f"{kind}_rh"] = pd.to_numeric(ok[f"collisions_{kind}"]) / hours
    for side, label in (("off", off), ("on", on)):
        for kind in ("robot", "wall"):
            col = f"{kind}_rh"
            out[f"{kind}_{side}"] = [float(select(ok, {"algorithm": a, "robots": n, AVOID: label})[col].median())
                                     if col in ok else np.nan
                                     for a, n in (name.split(" | ") for name in out["name"])]
    out.attrs["labels"] = (off, on)
    return out


def fmt(v: float, pct: bool = False, digits: int = 2) -> str:
    if pd.isna(v):
        return "–"
    return f"{100 * v:.1f}" if pct else f"{v:.{digits}f}"


def ranking(costs: pd.DataFrame, qual: pd.DataFrame) -> list[tuple[str, float, float, bool]]:
    """(algorithm, mean over the error models of the median share explored correctly, worst median time
    ratio, whether that ratio is capped), best first. Map quality leads: when no run under an error model
    reaches the target, its time ratio is the tick limit over the perfect run's time, which says how fast
    the algorithm is without error, not how it bears the error."""
    out = []
    for alg, grp in costs.groupby("algorithm"):
        q = qual[(qual["algorithm"] == alg) & (qual["condition"] != "perfect")]
        mean_correct = float(q["explored_correct"].mean()) if q["explored_correct"].notna().any() else np.nan
        capped = bool((q["success"] == 0).any())
        out.append((str(alg), mean_correct, float(grp["ratio"].max()), capped))
    return sorted(out, key=lambda t: (-t[1] if pd.notna(t[1]) else 0.0, t[2]))


def figure(runs: pd.DataFrame, conds: list[tuple[str, dict[str, str]]], path: Path) -> list[Path]:
    """The share explored correctly per error model and algorithm (median and interquartile range over
    runs), as PNG (300 dpi) and PDF beside ``path``."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from swarm.campaign.report.figures import DPI, STYLE, colour
    ok = runs[runs["status"] == "ok"]
    algs = list(dict.fromkeys(ok["algorithm"].astype(str)))  # the campaign's order: the report's colours
    labels = [label for label, _ in conds[1:]]
    plt.rcParams.update(STYLE)
    fig, ax = plt.subplots(figsize=(7.16, 2.8), constrained_layout=True)
    width = 0.8 / max(len(algs), 1)
    for k, alg in enumerate(algs):
        xs, med, lo, hi = [], [], [], []
        for i, (_, c) in enumerate(conds[1:]):
            v = pd.to_numeric(select(ok, {"algorithm": alg, **c})["explored_correct"]).dropna() * 100
            if len(v):
                xs.append(i - 0.4 + width * (k + 0.5))
                q1, q2, q3 = np.percentile(v, [25, 50, 75])
                med.append(q2)
                lo.append(q2 - q1)
                hi.append(q3 - q2)
        ax.errorbar(xs, med, yerr=[lo, hi], fmt="o", capsize=2, color=colour(k), label=alg)
    ax.set_xticks(range(len(labels)), labels)
    ax.set_ylabel("explored correctly (%)")
    ax.set_ylim(0, 100)
    ax.set_title("Map explored correctly after 10,000 ticks (1,000 s): median, interquartile range over runs")
    ax.legend(frameon=False, ncols=len(algs))
    ax.grid(axis="y", alpha=0.3)
    out = [path.with_suffix(".png"), path.with_suffix(".pdf")]
    for p in out:
        fig.savefig(p, dpi=DPI)
    plt.close(fig)
    return out


def render(costs: pd.DataFrame, qual: pd.DataFrame, avoid: pd.DataFrame | None, source: Path) -> str:
    lines = ["# Localisation error and avoidance: findings", "",
             f"Generated by `python benchmarks/experiments/localization_study_findings.py {source}` from the "
             "campaign report's runs table; do not edit by hand.", "",
             "## 1. Time to the target under each error model (ratio over perfect localisation)", "",
             "Paired by map, robots, spawn, avoidance and replicate; each map counts once; DNF at the tick limit. "
             "A ratio above 1 means slower with the error.", ""]
    t = Table(["Algorithm", "Error model", "Pairs", "Maps", "Ratio [95 % CI]", "p (Holm)"],
              [[r["algorithm"], r["condition"], str(int(r["pairs"])), str(int(r["maps"])), effects.ratio_text(r),
                p_value(r["p_holm"])] for _, r in costs.iterrows()], [False, False, True, True, True, True])
    lines += [markdown(t), "", "## 2. Map quality (medians over runs)", ""]
    t = Table(["Algorithm", "Error model", "Runs", "Reached target (%)", "Explored (%)", "Pose error (m)",
               "False free (%)", "False occupied (%)", "Wall offset (m)", "Explored correctly (%)"],
              [[r["algorithm"], r["condition"], str(int(r["runs"])), fmt(r["success"], True), fmt(r["explored"], True),
                fmt(r["pose_error_m"]),
                fmt(r["false_free_share"], True), fmt(r["false_occupied_share"], True), fmt(r["wall_offset_m"]),
                fmt(r["explored_correct"], True)] for _, r in qual.iterrows()],
              [False, False] + [True] * 8)
    lines += [markdown(t), "",
              "*Explored* is the report's explored fraction at the end of the run: for runs with a localisation "
              "model that recorded it over time, the correctly known cells (as *explored correctly*), else the "
              "cells the lidars have seen. Perfect runs carry no map-quality columns: their maps hold what was "
              "seen where it is.", ""]
    if avoid is not None:
        off, on = avoid.attrs["labels"]
        lines += [f"## 3. Avoidance: `{on}` against `{off}`", "",
                  "Time ratio paired as above (pooled over error models); contacts per robot-hour, medians over "
                  "runs (a robot-robot contact counts for both robots).", ""]
        t = Table(["Algorithm", "Robots", "Pairs", "Time ratio [95 % CI]", "p (Holm)", f"Robot-robot ({off})",
                   f"Robot-robot ({on})", f"Robot-wall ({off})", f"Robot-wall ({on})"],
                  [[*r["name"].split(" | "), str(int(r["pairs"])), effects.ratio_text(r), p_value(r["p_holm"]),
                    fmt(r["robot_off"], digits=0), fmt(r["robot_on"], digits=0), fmt(r["wall_off"], digits=0),
                    fmt(r["wall_on"], digits=0)] for _, r in avoid.iterrows()], [False, True] + [True] * 7)
        lines += [markdown(t), ""]
    lines += ["## Robustness ranking", "",
              "Ordered by the mean over the error models of the median share of the map explored correctly "
              "(what the error damages), then by the worst median time ratio. A time ratio marked *capped* comes "
              "from an error model under which no run reached the target: it is the tick limit over the time "
              "with perfect localisation, so it measures speed without error, not robustness.", ""]
    for i, (alg, correct, worst, capped) in enumerate(ranking(costs, qual), 1):
        lines.append(f"{i}. **{alg}**: explored correctly {fmt(correct, True)} % on average over the error models; "
                     f"worst time ratio {worst:.2f}{' (capped)' if capped else ''}")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs_csv", type=Path, help="the study report's tables/runs.csv")
    ap.add_argument("-o", "--output", type=Path, help="Markdown file to write (default: print)")
    ap.add_argument("--figure", type=Path, help="also draw the explored-correctly figure here (.png and .pdf)")
    args = ap.parse_args(argv)
    runs = effects.read_runs_csv(args.runs_csv)
    if MODEL not in runs:
        print(f"error: {args.runs_csv}: no {MODEL} column; not a localisation study", file=sys.stderr)
        return 2
    conds = conditions(runs)
    text = render(time_costs(runs, conds), quality(runs, conds), avoidance(runs), args.runs_csv)
    if args.figure:
        figure(runs, conds, args.figure)
    if args.output:
        args.output.write_text(text)
    else:
        print(text, end="")
    return 0


if __name__ == "__main__":
    sys.exit(main())
