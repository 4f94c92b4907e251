"""How often two robots can talk under each radio model, on the ablation campaign's own maps (issue 33).

    python benchmarks/experiments/link_budget.py docs/results/maes-parity/report/tables/runs.csv --positions 150

For every map of the runs table (kind, size, replicate: its ``map_seed``), ``--positions`` free points are drawn
uniformly from the free cells (a generator seeded by the map seed), and every pair is judged by the four radio
models of ``examples/minotaur-ablation.toml``: global, LOS, MAES's material model (``maes``: no distance term,
attenuation per 0.25 m of wall) and swarm's (``multiwall``: log-distance path loss plus one attenuation per wall
crossed). The table gives the share of pairs linked per model, by map kind, size and the number of walls the
straight line crosses. It tests the explanation first offered for finding R2 (materials indistinguishable from
global because the material model links nearly every pair global links): it does not (see
docs/results/maes-parity/README.md).
"""

from __future__ import annotations

import argparse
import numpy as np
import pandas as pd

from maps import CELL_M, generate
from radio import build_link_model, config_from_mapping

MODELS = ("global", "los", "maes", "multiwall")
WALL_BINS = ("0", "1", "2", "3+")


def link_shares(kind: str, size: int, map_seed: int, positions: int) -> list[dict]:
    """Per pair of ``positions`` random free points: walls crossed and which models link it."""
    truth = generate(kind, size, map_seed)
    rng = np.random.default_rng(map_seed)
    free = np.argwhere(~truth.solid)
    cells = free[rng.choice(len(free), size=positions, replace=False)]
    xy = (cells[:, ::-1].astype(np.float64) + 0.5) * CELL_M  # (col, row) -> (x, y), cell centres
    off = ~np.eye(positions, dtype=bool)
    states = {m: build_link_model(truth, config_from_mapping({"model": m})).evaluate(xy) for m in MODELS}
    walls = np.minimum(states["multiwall"].walls[off], 3)
    links = {m: states[m].link[off] for m in MODELS}
    out = []
    for w in range(4):
        sel = walls == w
        if sel.any():
            out.append({"map": kind, "size": size, "walls": WALL_BINS[w], "pairs": int(sel.sum()),
                        **{m: float(links[m][sel].mean()) for m in MODELS}})
    out.append({"map": kind, "size": size, "walls": "all", "pairs": int(off.sum()),
                **{m: float(links[m].mean()) for m in MODELS}})
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs_csv")
    ap.add_argument("--positions", type=int, default=150)
    args = ap.parse_args()
    runs = pd.read_csv(args.runs_csv)
    maps = runs[["map", "size", "replicate", "map_seed"]].drop_duplicates().sort_values(["map", "size", "replicate"])
    rows = [row for m in maps.itertuples()
            for row in link_shares(m.map, int(m.size), int(m.map_seed), args.positions)]
    table = pd.DataFrame(rows)
    print(f"Share of pairs of random free points linked ({args.positions} points per map, every ordered pair), "
          "by walls crossed on the straight line; mean over maps\n")
    print("| map | size | walls crossed | pairs per map | global | LOS | materials (MAES) | materials (swarm) |")
    print("|---|---:|---|---:|---:|---:|---:|---:|")
    order = {w: i for i, w in enumerate((*WALL_BINS, "all"))}
    for (kind, size, walls), sub in sorted(table.groupby(["map", "size", "walls"]), key=lambda kv: (*kv[0][:2], order[kv[0][2]])):
        cells = " | ".join(f"{sub[m].mean():.2f}" for m in MODELS)
        print(f"| {kind} | {size} | {walls} | {sub['pairs'].mean():.0f} | {cells} |")


if __name__ == "__main__":
    main()
