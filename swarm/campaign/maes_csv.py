"""Export runs as MAES statistics CSVs, so MAES's own tools (maes-csv-reader's cactus plots and tables,
``sort-files.sh``) read swarm campaigns unchanged.

The format is MAES's ``ExplorationStatisticsCSVWriter`` (docs/maes.md section 8.5):

- header, verbatim, with its space before "Biggest":
  ``Tick,Covered,Explored,Average Agent Distance,Agents Interconnected, Biggest Cluster %``
- one row per snapshot: the tick, coverage % and explored % as C# ``float`` (percentages are
  ``proportion * 100`` computed in single precision), the average pairwise robot distance, ``1``/``0`` for
  "every robot in one communication group" and the biggest group's share of the robots in %. MAES writes
  the two communication cells blank at tick 0 (its tracker skips tick 0), and so do we.
- floats as ``Single.ToString()`` under InvariantCulture: .NET Framework / Mono (Unity) general format,
  7 significant digits, ``E-05`` style exponents.
- file name ``[cave-]{alg}-seed-{mapSeed}-mapConfig.HeightInTiles-{H}-comms-{Global|LOS|Material}-robots-{n}-``
  ``{SpawnTogether|SpawnApart}_e{int explored %}-c{int covered %}.csv`` where the suffix truncates the last
  row's values, as MAES's ``(int)`` cast does.

What cannot match is listed by :func:`fidelity_notes` and printed in the report.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from .report.output import ReportWriter, slug
from .report.series import iter_parts
from .store import ResultsStore

if TYPE_CHECKING:
    from .report.load import CampaignData

HEADER = "Tick,Covered,Explored,Average Agent Distance,Agents Interconnected, Biggest Cluster %"
COMMS = {"global": "Global", "los": "LOS", "multiwall": "Material", "maes": "Material"}
SPAWNS = {"together": "SpawnTogether", "random": "SpawnApart"}
DISTANCE_COLUMN = "mean_pair_distance_m"
"""A time-series column the runtime does not record yet (see the report note); used when present."""
MAES_MAX_TICKS = 36000
"""maes-csv-reader counts a run whose last tick is 36000 as a timeout."""
SERIES_COLUMNS = ("tick", "explored", "coverage", "comm_groups", "biggest_group", "all_connected", DISTANCE_COLUMN)


# ------------------------------------------------------------------------------------ formatting ----
def dotnet_float(x: float) -> str:
    """``((float)x).ToString(CultureInfo.InvariantCulture)`` as .NET Framework / Unity's Mono prints it."""
    v = float(np.float32(x)) + 0.0  # single precision, and no "-0"
    if math.isnan(v):
        return "NaN"
    if math.isinf(v):
        return "Infinity" if v > 0 else "-Infinity"
    return f"{v:.7g}".replace("e", "E")


def format_floats(values: np.ndarray) -> list[str]:
    """:func:`dotnet_float` of every element (vectorised for the common case)."""
    a = np.asarray(values, dtype=np.float32).astype(np.float64) + 0.0
    if not np.all(np.isfinite(a)):
        return [dotnet_float(v) for v in a.tolist()]
    return [s.replace("e", "E") if "e" in s else s for s in (f"{v:.7g}" for v in a.tolist())]


def percent32(proportion: np.ndarray) -> np.ndarray:
    """``proportion * 100`` in single precision, as MAES's ``ExploredProportion * 100`` (both floats)."""
    return np.asarray(proportion, dtype=np.float64).astype(np.float32) * np.float32(100)


def biggest_cluster32(comm_groups: np.ndarray, biggest_group: np.ndarray, robots: int) -> np.ndarray:
    """MAES's ``CreateClusterSizeSnapShot``: 100 with one group, else ``(float)biggest / (float)total * 100f``."""
    count = np.rint(np.asarray(biggest_group, dtype=np.float64) * robots).astype(np.float32)
    share = count / np.float32(robots) * np.float32(100)
    return np.where(np.asarray(comm_groups) == 1, np.float32(100), share).astype(np.float32)


def csv_text(tick: np.ndarray, explored: np.ndarray, coverage: np.ndarray, robots: int,
             comm_groups: np.ndarray | None = None, biggest_group: np.ndarray | None = None,
             all_connected: np.ndarray | None = None, distance: np.ndarray | None = None) -> tuple[str, int, int]:
    """One run's CSV text, and the integer explored % and covered % of its last row (the file-name suffix)."""
    tick = np.asarray(tick, dtype=np.int64)
    n = len(tick)
    exp32, cov32 = percent32(explored), percent32(coverage)
    ticks = [str(t) for t in tick.tolist()]
    cov_s, exp_s = format_floats(cov32), format_floats(exp32)
    if distance is not None:
        dist_s = format_floats(distance)
    else:
        dist_s = ["0" if robots == 1 else ""] * n  # one robot: MAES's mean over the self-pair is 0
    if all_connected is not None and comm_groups is not None and biggest_group is not None:
        ic_s = ["1" if c else "0" for c in np.asarray(all_connected, dtype=bool).tolist()]
        bc_s = format_floats(biggest_cluster32(comm_groups, biggest_group, robots))
        zero = tick == 0
        if zero.any():  # MAES's CommunicationTracker takes no snapshot at tick 0
            for i in np.flatnonzero(zero).tolist():
                ic_s[i] = bc_s[i] = ""
    else:
        ic_s = bc_s = [""] * n
    lines = [HEADER, *(",".join(row) for row in zip(ticks, cov_s, exp_s, dist_s, ic_s, bc_s))]
    last_e = int(exp32[-1]) if n else 0
    last_c = int(cov32[-1]) if n else 0
    return "\n".join(lines) + "\n", last_e, last_c


# -------------------------------------------------------------------------------------- naming ----
def height_tiles(size_label: str) -> str:
    """MAES names files by ``HeightInTiles``: the H of a W x H size."""
    return size_label.lower().split("x")[-1]


def map_prefix(map_kind: str, map_label: str) -> str:
    """Buildings have none, caves ``cave-`` (MAES's ``{mapType}-``); other kinds their label."""
    if map_kind == "building":
        return ""
    return "cave-" if map_kind == "cave" else f"{slug(map_label)}-"


def file_stem(algorithm: str, map_kind: str, map_label: str, map_seed: Any, size_label: str, radio_model: str,
              robots: Any, spawn: str) -> str:
    """MAES's ``statisticsFileName`` for one run."""
    seed = "na" if pd.isna(map_seed) else str(int(map_seed))
    comms = COMMS.get(radio_model, slug(radio_model))
    return (f"{map_prefix(map_kind, map_label)}{slug(algorithm)}-seed-{seed}-mapConfig.HeightInTiles-"
            f"{height_tiles(size_label)}-comms-{comms}-robots-{int(robots)}-{SPAWNS.get(spawn, slug(spawn))}")


def file_name(stem: str, explored_pct: int, covered_pct: int) -> str:
    return f"{stem}_e{explored_pct}-c{covered_pct}.csv"


def subfolder_dims(runs: pd.DataFrame) -> list[str]:
    """Grid dimensions whose labels the MAES name cannot tell apart (two map labels of one kind, two radio
    labels of one model, comm or transport settings, ...): files go into one subfolder per such label."""
    tokens = {
        "map": runs["map_kind"].astype(str).str.cat(runs["map"].astype(str).map(slug), sep="|").where(
            ~runs["map_kind"].isin(["building", "cave"]), runs["map_kind"].astype(str)),
        "size": runs["size"].astype(str).map(height_tiles),
        "algorithm": runs["algorithm"].astype(str).map(slug),
        "radio": runs["radio_model"].astype(str).map(lambda m: COMMS.get(m, m)),
        "spawn": runs["spawn"].astype(str),
        "robots": runs["robots"].astype(str),
    }
    out: list[str] = []
    for dim in ("map", "size", "robots", "spawn", "algorithm", "radio", "comm", "transport"):
        labels = runs[dim].astype(str)
        if dim in tokens:
            per_token = pd.DataFrame({"t": tokens[dim].to_numpy(), "l": labels.to_numpy()}).groupby("t")["l"].nunique()
            if (per_token > 1).any():
                out.append(dim)
        elif labels.nunique() > 1:
            out.append(dim)
    return out


def fidelity_notes(runs: pd.DataFrame, every: int, has_distance: bool, subdirs: Sequence[str]) -> list[str]:
    """Every way these files differ from what MAES would write for the same runs."""
    notes = []
    if not has_distance:
        notes.append("*Average Agent Distance* is blank for runs with more than one robot: the time series does "
                     "not record robot positions (one robot: 0, MAES's mean over the self-pair).")
    cadence = "every 10 ticks, as MAES" if every == 10 else f"every {every} ticks (MAES: every 10)"
    notes.append(f"A row per recorded tick, {cadence}, plus the run's final tick, which MAES omits when it is "
                 "not a multiple of 10; so the last *Tick* is the exact stop tick.")
    max_ticks = sorted(set(pd.to_numeric(runs["max_ticks"], errors="coerce").dropna().astype(int)))
    if max_ticks and max_ticks != [MAES_MAX_TICKS]:
        notes.append(f"maes-csv-reader counts a run as a timeout when its last tick is {MAES_MAX_TICKS}; this "
                     f"campaign's `max_ticks` is {', '.join(map(str, max_ticks))}.")
    stopped_early = int(((runs["stop_reason"] != "explored") & (runs["stop_reason"] != "max_ticks")).sum())
    if stopped_early:
        notes.append(f"{stopped_early} runs stopped before their target for another reason (stalled, every robot "
                     "failed): maes-csv-reader would count them as successes. Their `_e` suffix and the index's "
                     "`stop_reason` tell them apart.")
    notes.append("Map seeds are this campaign's 63-bit derived seeds (MAES draws 0..999999), and the algorithm "
                 "part is the campaign's algorithm label.")
    if subdirs:
        notes.append(f"The MAES name cannot tell apart some labels of {', '.join(subdirs)}: files are in one "
                     f"subfolder per label (`{'_'.join(f'{d}-LABEL' for d in subdirs)}/`).")
    notes.append("Lines end with `\\n` (MAES on Windows writes `\\r\\n`); floats have 7 significant digits as "
                 "`Single.ToString()` on .NET Framework / Unity's Mono (.NET Core 3+ would print up to 9).")
    return notes


# --------------------------------------------------------------------------------------- export ----
def write_runs(store: ResultsStore, data: CampaignData, out: ReportWriter, folder: str = "maes-csv",
               index: str = "maes-csv-index.csv") -> dict[str, Any]:
    """Write one CSV per done run under ``out.folder / folder`` and an index next to that folder (not in it:
    MAES tools read every CSV of a folder). Returns what the report README needs."""
    runs = data.ok.reset_index(drop=True)
    subdirs = subfolder_dims(runs) if len(runs) else []
    rows: list[dict[str, Any]] = []
    has_distance = False
    written: dict[str, str] = {}
    for ridx, table in iter_parts(store, runs, SERIES_COLUMNS):
        cols = {name: table.column(name).to_numpy(zero_copy_only=False) for name in table.column_names}
        has_distance = has_distance or DISTANCE_COLUMN in cols
        bounds = np.flatnonzero(np.r_[True, ridx[1:] != ridx[:-1], True])
        for start, stop in itertools.pairwise(bounds):
            run = runs.iloc[int(ridx[start])]
            s = slice(int(start), int(stop))
            text, e, c = csv_text(cols["tick"][s], cols["explored"][s], cols["coverage"][s], int(run["robots"]),
                                  *(cols[k][s] if k in cols else None
                                    for k in ("comm_groups", "biggest_group", "all_connected", DISTANCE_COLUMN)))
            stem = file_stem(str(run["algorithm"]), str(run["map_kind"]), str(run["map"]), run["map_seed"],
                             str(run["size"]), str(run["radio_model"]), run["robots"], str(run["spawn"]))
            sub = "_".join(f"{d}-{slug(str(run[d]))}" for d in subdirs)
            relative = "/".join(p for p in (folder, sub, file_name(stem, e, c)) if p)
            if relative in written:
                raise RuntimeError(f"two runs map to the MAES file {relative}: {written[relative]} and {run['key']}")
            written[relative] = str(run["key"])
            out.write(relative, text)
            rows.append({"file": relative, "key": run["key"], **{d: str(run[d]) for d in data.dims},
                         "replicate": int(run["replicate"]), "stop_reason": run["stop_reason"]})
    rows.sort(key=lambda r: r["file"])
    index_frame = pd.DataFrame(rows, columns=["file", "key", *data.dims, "replicate", "stop_reason"])
    out.write(index, index_frame.to_csv(index=False, lineterminator="\n"))
    return {"files": len(rows), "folder": folder, "index": index,
            "notes": fidelity_notes(runs, data.every, has_distance, subdirs)}


def export_maes_csv(results_dir: str | Path, out_dir: str | Path) -> list[Path]:
    """Write the MAES CSV of every done run of ``results_dir`` into ``out_dir/maes-csv/`` (their index:
    ``out_dir/maes-csv-index.csv``); returns the CSV paths."""
    from .report.load import load

    data = load(results_dir)
    out = ReportWriter(Path(out_dir))
    write_runs(ResultsStore(data.folder), data, out)
    return [out.folder / f for f in out.written if f.endswith(".csv") and f != "maes-csv-index.csv"]
