"""A small comparison from Python: three explorers on the same small buildings, two radio models, plotted.

    python examples/compare.py --out compare-results        # about a minute on 2 cores

Runs a campaign with ``swarm.campaign.run`` (re-running resumes: finished runs are kept), reads the runs
and the time series back as pandas DataFrames, and draws OUT/compare.png: the mean explored fraction over
time per algorithm and radio model, with a 95 % band over the maps, and prints the median time to 90 %
explored per cell.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

import swarm

CAMPAIGN = {
    "campaign": {"name": "compare", "seed": 3, "replicates": 6},
    "grid": {"map": ["building"], "size": [40], "robots": [4], "spawn": ["together"],
             "algorithm": ["frontier", "greed", "tnf"], "radio": ["global", "multiwall"]},
    "stop": {"explored": 0.95, "max_ticks": 6000},
}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", type=Path, default=Path("compare-results"))
    ap.add_argument("--workers", type=int, default=None, help="worker processes (default: one per core)")
    args = ap.parse_args()

    done = swarm.campaign.run(CAMPAIGN, args.out, workers=args.workers, progress=True)
    print(f"{done.ran} runs ran, {done.skipped} were already done, {done.failed} failed")
    runs = done.runs()
    series = done.timeseries()

    print(runs.groupby(["algorithm", "radio"], observed=True)["t90"].median().unstack().to_string())

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    grid = np.arange(0, int(runs["ticks"].max()) + 1, 10)  # to the longest run
    fig, axes = plt.subplots(1, 2, figsize=(9, 3.6), dpi=120, sharey=True)
    for ax, (radio, by_radio) in zip(axes, series.groupby("radio", sort=False)):
        for algorithm, cell in by_radio.groupby("algorithm", sort=False):
            # each run's curve on a common time grid; a run that stopped early holds its last value
            curves = np.array([np.interp(grid, run["tick"], run["explored"]) for _, run in cell.groupby("key")])
            mean = curves.mean(axis=0)
            half = 1.96 * curves.std(axis=0, ddof=1) / np.sqrt(len(curves))
            ax.plot(grid / 10, mean, label=f"{algorithm} ({len(curves)} maps)")
            ax.fill_between(grid / 10, mean - half, mean + half, alpha=0.2)
        ax.set_title(f"radio: {radio}")
        ax.set_xlabel("time (s)")
    axes[0].set_ylabel("explored fraction")
    axes[1].legend(loc="lower right")
    fig.suptitle("4 robots, 40 x 40 m buildings")
    fig.tight_layout()
    path = args.out / "compare.png"
    fig.savefig(path)
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
