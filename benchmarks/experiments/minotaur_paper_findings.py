"""Every number of the "Finding by finding" section of docs/results/minotaur-paper/README.md (findings 1-4),
recomputed from the report's runs table.

    python benchmarks/experiments/minotaur_paper_findings.py \
        [docs/results/minotaur-paper/report/tables/runs.csv]

Definitions (as the README states them):

- **ticks**: ticks to 98 % explored (``ticks_to_target``; a run that never got there would count at its
  ``max_ticks``, as in the report). A *cell* is one map kind, size, robot count, spawn mode, algorithm and
  radio (3 runs, one per map); a *per-cell statement* of findings 2-4 pools both spawns (6 runs per line).
- **Finding 1** (radio): means over all algorithms, spawns and maps with 2-16 robots (1-robot runs are the
  same run under every radio). "LOS slowest" counts the 144 multi-robot cells (kind x size x robots x spawn
  x algorithm) where LOS's mean is strictly above both others; "order holds" where global <= materials <=
  LOS. Paired comparisons with :func:`swarm.campaign.report.effects.compare_runs` (1-robot runs dropped,
  every map once with the mean log ratio of its pairs), Holm over the six radio comparisons of the two map
  kinds. The LOS penalty by robot count is mean LOS ticks over mean global ticks, all kinds, sizes,
  algorithms and spawns pooled. Fig. 7 left: Greed, 16 robots spawned together, 150 x 150 buildings.
- **Findings 2-4** (algorithms): materials radio. Per cell (size x robots, both spawns pooled): the mean
  ticks per algorithm; pairs of runs on the same map and spawn; "A wins k of 6" counts pairs where A needed
  fewer ticks; p is the two-sided Wilcoxon signed-rank test on the 6 pairs' log ratios (treating the two
  spawns of a map as independent; 0.031 is the smallest it can give); "mean ratio" is the mean over pairs
  of t_A / t_B. Pooled per map kind: ``compare_runs`` over all 15 cells (90 pairs, 1-robot runs included),
  Holm over the six algorithm comparisons (3 pairs x 2 kinds).
"""

from __future__ import annotations

import argparse
import itertools
import sys
from pathlib import Path

import numpy as np
import pandas as pd

from swarm.campaign.report import effects

DEFAULT = Path("docs/results/minotaur-paper/report/tables/runs.csv")
KINDS = ("building", "cave")
SIZES = (50, 100, 150)
ROBOTS = (1, 2, 4, 8, 16)
RADIOS = ("global", "materials", "LOS")
ALGS = ("TNF", "Minotaur", "Greed")


def load(path: Path) -> tuple[pd.DataFrame, pd.DataFrame]:
    """The runs as ``compare_runs`` reads them, and a frame with numeric size/robots and ``t`` (ticks)."""
    runs = effects.read_runs_csv(path)
    df = runs[runs["status"] == "ok"].copy()
    df["size"] = df["size"].astype(int)
    df["robots"] = df["robots"].astype(int)
    df["t"] = df["ttt_or_max"].astype(float)
    return runs, df


def pct(a: float, b: float) -> str:
    return f"{100 * (a / b - 1):+.1f} %"


def stat_text(r: pd.Series, maps_faster: int) -> str:
    return (f"pairs {r['pairs']}, a faster in {r['a_wins']} (b in {r['b_wins']}, ties {r['ties']}); "
            f"ratio {r['ratio']:.2f} [{r['ratio_low']:.2f}, {r['ratio_high']:.2f}] over {r['maps']} maps, "
            f"a faster on {maps_faster} of {r['maps']} maps; p = {r['p_value']:.3f}, Holm {r['p_holm']:.3f}")


def maps_faster(runs: pd.DataFrame, fa: dict, fb: dict) -> int:
    """Maps whose mean log ratio a/b is below 0 (a faster on that map), as ``compare_runs`` counts units."""
    return int((effects.unit_log_ratios(runs, fa, fb) < 0).sum())


def name(kind: str, a: str, b: str) -> str:
    """A comparison's name. It seeds the row's bootstrap (:func:`effects.row_rng`), so with 9 maps the
    interval's ends can move by an order statistic with the name; these names give the README's intervals."""
    return f"{kind.capitalize()}s: {a} vs. {b}"


def paired(runs: pd.DataFrame, family: list[tuple[str, dict, dict]], title: str) -> None:
    print(f"\n{title}")
    out = effects.compare_runs(runs, family)
    for (name, fa, fb), (_, r) in zip(family, out.iterrows()):
        print(f"  {name}: {stat_text(r, maps_faster(runs, fa, fb))}")


# ------------------------------------------------------------------------------------ finding 1 ----
def finding1(runs: pd.DataFrame, df: pd.DataFrame) -> None:
    print("=" * 100)
    print("1. Communication (mean ticks to 98 %, 2-16 robots, all algorithms, spawns and maps)")
    multi = df[df["robots"] > 1]
    means = multi.groupby(["map", "size", "radio"])["t"].mean().unstack("radio")
    print("\n| map | size | global | materials | LOS |\n|---|---|---:|---:|---:|")
    for (kind, size), r in means.iterrows():
        g, m, los = r["global"], r["materials"], r["LOS"]
        print(f"| {kind} | {size} | {g:.0f} | {m:.0f} ({pct(m, g)}) | {los:.0f} ({pct(los, g)}) |")
    los_pen = (means["LOS"] / means["global"] - 1) * 100
    big = los_pen[los_pen.index.get_level_values("size") >= 100]
    mat = (means["materials"] / means["global"] - 1) * 100
    print(f"\nLOS cost on 100 and 150 maps: {big.min():.1f} % to {big.max():.1f} %;"
          f" materials vs global over all rows: {mat.min():+.1f} % to {mat.max():+.1f} %")

    cells = multi.groupby(["map", "size", "robots", "spawn", "algorithm", "radio"])["t"].mean().unstack("radio")
    slowest = (cells["LOS"] > cells["global"]) & (cells["LOS"] > cells["materials"])
    order = (cells["global"] <= cells["materials"]) & (cells["materials"] <= cells["LOS"])
    kind = cells.index.get_level_values("map")
    print(f"\nmulti-robot cells: {len(cells)}; LOS slowest (strictly) in {int(slowest.sum())}"
          + "".join(f"; {k}: {int(slowest[kind == k].sum())} of {int((kind == k).sum())}" for k in KINDS))
    print(f"global <= materials <= LOS in {int(order.sum())} of {len(cells)}"
          + "".join(f"; {k}: {int(order[kind == k].sum())}" for k in KINDS))

    family = []
    for k in KINDS:
        for a, b in (("global", "LOS"), ("materials", "LOS"), ("global", "materials")):
            family.append((name(k, a, b), {"map": k, "radio": a}, {"map": k, "radio": b}))
    paired(runs, family, "Paired over maps, multi-robot cells (Holm over these six):")

    by_n = multi.groupby(["robots", "radio"])["t"].mean().unstack("radio")
    print("\nLOS penalty by robot count (mean LOS / mean global - 1; all kinds, sizes, algorithms, spawns):")
    for n, r in by_n.iterrows():
        print(f"  {n:2d} robots: LOS {pct(r['LOS'], r['global'])}, materials {pct(r['materials'], r['global'])}")

    f7 = df[(df["map"] == "building") & (df["size"] == 150) & (df["robots"] == 16) & (df["spawn"] == "together")
            & (df["algorithm"] == "Greed")]
    f7m = f7.groupby("radio")["t"].mean()
    print("\nFig. 7 left (Greed, 16 robots together, 150 x 150 buildings), mean ticks over 3 maps: "
          + ", ".join(f"{r} {f7m[r]:.0f}" for r in RADIOS))
    per_map = f7.pivot_table(index="replicate", columns="radio", values="t")
    print("  per map:\n" + "\n".join("    " + line for line in per_map[list(RADIOS)].to_string().splitlines()))


# ------------------------------------------------------------------------------------ findings 2-4 ----
def cell_pairs(mat: pd.DataFrame, kind: str, size: int, robots: int, a: str, b: str) -> dict:
    """The 6 pairs of one cell (both spawns) of algorithm a against b under materials."""
    sel = mat[(mat["map"] == kind) & (mat["size"] == size) & (mat["robots"] == robots)]
    keys = ["spawn", "replicate"]
    m = sel[sel["algorithm"] == a][[*keys, "t"]].merge(sel[sel["algorithm"] == b][[*keys, "t"]], on=keys,
                                                         suffixes=("_a", "_b"))
    lr = np.log(m["t_a"] / m["t_b"]).to_numpy()
    test = effects.signed_rank(lr)
    return {"n": len(m), "a_wins": int((m["t_a"] < m["t_b"]).sum()), "b_wins": int((m["t_b"] < m["t_a"]).sum()),
            "mean_ratio": float((m["t_a"] / m["t_b"]).mean()), "p": test.p,
            "mean_a": float(sel[sel["algorithm"] == a]["t"].mean()),
            "mean_b": float(sel[sel["algorithm"] == b]["t"].mean())}


def cell_text(c: dict, a: str, b: str) -> str:
    return (f"{a} faster in {c['a_wins']} of {c['n']} pairs ({b} in {c['b_wins']}), p = {c['p']:.3f}, "
            f"mean pair ratio {a}/{b} {c['mean_ratio']:.2f}, ratio of means {c['mean_a'] / c['mean_b']:.2f} "
            f"({pct(c['mean_a'], c['mean_b'])})")


def cell_means(mat: pd.DataFrame, kind: str) -> pd.DataFrame:
    m = mat[mat["map"] == kind].groupby(["size", "robots", "algorithm"])["t"].mean().unstack("algorithm")
    return m[list(ALGS)]


def per_cell_table(mat: pd.DataFrame, kind: str) -> None:
    means = cell_means(mat, kind)
    print(f"\nPer cell, {kind}s, materials, mean ticks (both spawns, 6 runs) and pair counts (x/6: row faster):")
    print("| size | robots | TNF | Minotaur | Greed | lowest | M vs G | M vs T | T vs G |")
    print("|---|---|---:|---:|---:|---|---|---|---|")
    for (size, n), r in means.iterrows():
        counts = []
        for a, b in (("Minotaur", "Greed"), ("Minotaur", "TNF"), ("TNF", "Greed")):
            c = cell_pairs(mat, kind, size, n, a, b)
            counts.append(f"{c['a_wins']}/6 p={c['p']:.3f}")
        print(f"| {size} | {n} | {r['TNF']:.0f} | {r['Minotaur']:.0f} | {r['Greed']:.0f} | {r.idxmin()} | "
              + " | ".join(counts) + " |")


def count_cells(mat: pd.DataFrame, kind: str, a: str, b: str) -> dict[int, list[tuple[int, int]]]:
    """Cells (size, robots) of a kind grouped by how many of 6 pairs a wins against b."""
    out: dict[int, list[tuple[int, int]]] = {}
    for size, n in itertools.product(SIZES, ROBOTS):
        out.setdefault(cell_pairs(mat, kind, size, n, a, b)["a_wins"], []).append((size, n))
    return dict(sorted(out.items(), reverse=True))


def pooled_algorithms(runs: pd.DataFrame) -> None:
    family = []
    for k in KINDS:
        for a, b in (("Minotaur", "Greed"), ("Minotaur", "TNF"), ("TNF", "Greed")):
            family.append((name(k, a, b), {"map": k, "radio": "materials", "algorithm": a},
                           {"map": k, "radio": "materials", "algorithm": b}))
    paired(runs, family, "Pooled per map kind, materials, all 15 cells (Holm over these six algorithm comparisons):")
    mat = runs[(runs["status"] == "ok") & (runs["radio"] == "materials")]
    for k in KINDS:
        for a, b in (("Minotaur", "Greed"), ("Minotaur", "TNF"), ("TNF", "Greed")):
            p = effects.contrast_pairs(mat, {"map": k, "algorithm": a}, {"map": k, "algorithm": b})
            print(f"  {k}: mean pair ratio {a}/{b} {(p['t_a'] / p['t_b']).mean():.2f}, "
                  f"{b}/{a} {(p['t_b'] / p['t_a']).mean():.2f}")


def finding2(mat: pd.DataFrame) -> None:
    print("=" * 100)
    print("2. Buildings, 2 robots (materials, both spawns)")
    means = cell_means(mat, "building")
    for n in (2, 1):
        r = means.loc[(150, n)]
        print(f"  150 x 150, {n} robot(s): " + ", ".join(f"{a} {r[a]:.0f}" for a in ALGS))
    for b in ("Greed", "Minotaur"):
        print(f"  150 x 150, 2 robots: {cell_text(cell_pairs(mat, 'building', 150, 2, 'TNF', b), 'TNF', b)}")
    for size in (50, 100):
        r = means.loc[(size, 2)]
        others = [a for a in ALGS if a != "Minotaur"]
        below = [100 * (1 - r["Minotaur"] / r[a]) for a in others]
        print(f"  {size} x {size}, 2 robots: " + ", ".join(f"{a} {r[a]:.0f}" for a in ALGS)
              + f"; lowest {r.idxmin()}; Minotaur below "
              + ", ".join(f"{a} by {x:.1f} %" for a, x in zip(others, below)))
        for b in others:
            print(f"    {cell_text(cell_pairs(mat, 'building', size, 2, 'Minotaur', b), 'Minotaur', b)}")
        print(f"    {cell_text(cell_pairs(mat, 'building', size, 2, 'TNF', 'Greed'), 'TNF', 'Greed')}")
    print("  (pooled building TNF/Greed: see the pooled table below)")


def finding3(mat: pd.DataFrame) -> None:
    print("=" * 100)
    print("3. Buildings, 16 robots (materials, both spawns)")
    means = cell_means(mat, "building")
    for size in (50, 150):
        r = means.loc[(size, 16)]
        print(f"  {size} x {size}, 16 robots: Minotaur {r['Minotaur']:.0f}, Greed {r['Greed']:.0f} "
              f"({pct(r['Greed'], r['Minotaur'])}), TNF {r['TNF']:.0f} ({pct(r['TNF'], r['Minotaur'])})")
    lowest = means.idxmin(axis=1)
    print(f"  Minotaur lowest mean in {int((lowest == 'Minotaur').sum())} of {len(means)} building cells"
          f" (others: {', '.join(f'{s}/{n}: {a}' for (s, n), a in lowest.items() if a != 'Minotaur')})")
    groups = count_cells(mat, "building", "Minotaur", "Greed")
    print("  Minotaur vs Greed per cell, pairs won: "
          + "; ".join(f"{k}/6 in {len(v)} cells {v}" for k, v in groups.items()))
    for size, n in itertools.product((50, 100), (4, 8)):
        c = cell_pairs(mat, "building", size, n, "Minotaur", "Greed")
        print(f"  {size} x {size}, {n} robots: Minotaur {100 * (1 - c['mean_a'] / c['mean_b']):.1f} % fewer ticks "
              f"than Greed; {cell_text(c, 'Minotaur', 'Greed')}")
    c = cell_pairs(mat, "building", 150, 16, "Minotaur", "Greed")
    print(f"  150 x 150, 16 robots: {cell_text(c, 'Minotaur', 'Greed')}")


def finding4(mat: pd.DataFrame) -> None:
    print("=" * 100)
    print("4. Caves (materials, both spawns)")
    means = cell_means(mat, "cave")
    lowest = means.idxmin(axis=1)
    print(f"  Minotaur lowest mean in {int((lowest == 'Minotaur').sum())} of {len(means)} cave cells")
    for size, n in ((50, 2), (150, 16)):
        r = means.loc[(size, n)]
        print(f"  {size} x {size}, {n} robots: " + ", ".join(f"{a} {r[a]:.0f}" for a in ("Minotaur", "TNF", "Greed")))
        for a, b in (("Minotaur", "TNF"), ("TNF", "Greed")):
            print(f"    {cell_text(cell_pairs(mat, 'cave', size, n, a, b), a, b)}")
    for a, b in (("Minotaur", "TNF"), ("TNF", "Greed")):
        groups = count_cells(mat, "cave", a, b)
        print(f"  {a} vs {b} per cell, pairs won: " + "; ".join(f"{k}/6 in {len(v)} cells {v}"
                                                             for k, v in groups.items()))
    tnf_lower = (means["TNF"] < means["Greed"]).sum()
    print(f"  TNF mean below Greed's in {int(tnf_lower)} of {len(means)} cave cells")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs_csv", type=Path, nargs="?", default=DEFAULT,
                    help=f"a report's tables/runs.csv (default {DEFAULT})")
    args = ap.parse_args(argv)
    runs, df = load(args.runs_csv)
    n_dnf = int((~df["success"]).sum())
    print(f"{args.runs_csv}: {len(runs)} runs, {len(df)} ok, {n_dnf} did not reach 98 %")
    finding1(runs, df)
    mat = df[df["radio"] == "materials"]
    finding2(mat)
    finding3(mat)
    finding4(mat)
    print("=" * 100)
    for k in KINDS:
        per_cell_table(mat, k)
    print()
    pooled_algorithms(runs)
    return 0


if __name__ == "__main__":
    sys.exit(main())
