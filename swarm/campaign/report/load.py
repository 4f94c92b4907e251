"""Read a results folder into what the report needs: one row per committed run with its grid labels, the
campaign's own order of every grid dimension, and how many runs the spec defines.

Tables and figures follow the order the spec lists values in (the author chose it: e.g. global, multiwall,
los), not the alphabet. The spec is parsed *without* building its run specs: validating 54,000 run specs
takes most of a minute and the report only needs labels and a count.
"""

from __future__ import annotations

import json
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pandas as pd

from swarm.base.errors import InvalidInput

from swarm.results.schema import (BENCHMARK_RUN_COLUMNS, COMM_RUN_COLUMNS, LOCALIZATION_RUN_COLUMNS, RUNS,
                                  THRESHOLD_COLUMNS)
from ..spec import CampaignSpec, campaign_from_mapping, folder_of, is_axis
from ..store import ResultsStore

DIMS = ("map", "size", "robots", "spawn", "algorithm", "radio", "comm", "transport")
"""Grid dimensions as the runs table names them; a campaign may add radio and comm parameter axes
(``radio.sensitivity_dbm``: :attr:`CampaignData.axes`), after these."""
ALWAYS_SHOWN = ("map", "size", "robots", "spawn", "algorithm", "radio")
"""Shown in names and tables even when constant, so a figure name says which world it shows."""
RUN_COLUMNS = ("key", *DIMS, "replicate", "map_kind", "radio_model", "map_seed", "status", "error", "stop_reason",
               "ticks", "max_ticks", "explored_target", "explored", "coverage", *THRESHOLD_COLUMNS.values(), "part",
               "msgs_sent", "bytes_sent", "msgs_delivered", "bytes_delivered", "msgs_dropped", "collisions_wall",
               "collisions_robot", "swarm_version", *BENCHMARK_RUN_COLUMNS, *COMM_RUN_COLUMNS, *LOCALIZATION_RUN_COLUMNS)
"""The runs-table columns the report reads (:data:`swarm.results.schema.RUNS`, plus the store's ``part``); results of
older versions lack the communication, localisation, collision-split, benchmark-metric and code-version columns
(they read as missing)."""
assert set(RUN_COLUMNS) <= {*RUNS, "part"}


@dataclass
class CampaignData:
    """A results folder as the report sees it."""

    folder: Path
    name: str
    description: str
    source: str
    spec: CampaignSpec | None
    runs: pd.DataFrame
    """Every committed run (ok and failed), sorted in spec order; dimension columns are ordered categoricals
    (so ``groupby(..., observed=True)`` lists groups in spec order)."""
    orders: dict[str, list[str]]
    dims: tuple[str, ...]
    """Dimensions shown: ``ALWAYS_SHOWN`` plus comm/transport and axes when they take several values."""
    total: int | None
    """Runs the spec defines (None when the spec could not be read)."""
    every: int
    spec_error: str = ""
    axes: tuple[str, ...] = ()
    """Radio and comm parameter axes of the grid (``radio.sensitivity_dbm``), after :data:`DIMS`."""
    foreign: int = 0
    """Runs in the folder whose keys the spec does not define, left out of every table and statistic."""

    @property
    def all_dims(self) -> tuple[str, ...]:
        """Every grid dimension, the axes included, in grid order."""
        return (*DIMS, *self.axes)

    @property
    def ok(self) -> pd.DataFrame:
        return self.runs[self.runs["status"] == "ok"]

    @property
    def failed(self) -> pd.DataFrame:
        return self.runs[self.runs["status"] != "ok"]

    @property
    def pending(self) -> int | None:
        return None if self.total is None else max(self.total - len(self.runs), 0)

    def varies(self, dim: str) -> bool:
        return self.runs[dim].nunique() > 1 if len(self.runs) else len(self.orders.get(dim, [])) > 1


def load(results_dir: str | Path) -> CampaignData:
    """Read ``results_dir``; bad folders raise :class:`InvalidInput` naming ``DIR``."""
    folder = Path(results_dir)
    if not folder.is_dir():
        raise InvalidInput("DIR", str(folder), "an existing campaign results folder")
    store = ResultsStore(folder)
    source = store.spec_source()
    spec, spec_error = _read_spec(source)
    store.require_sound()
    table = store.runs_table()
    frame = table.to_pandas() if table is not None else None
    columns = frame.columns if frame is not None else ()
    axes = spec.axes if spec is not None else tuple(c for c in columns if is_axis(c))
    runs = _runs_frame(frame, axes)
    foreign = 0
    if spec is not None and len(runs):  # e.g. file-map runs of a copy elsewhere, written before that was refused
        mine = runs["key"].astype(str).isin({key for _, key in spec.iter_keys()}).to_numpy()
        foreign = int((~mine).sum())
        runs = runs[mine].reset_index(drop=True)
    orders = _orders(spec, runs, axes)
    for dim in (*DIMS, *axes):
        runs[dim] = pd.Categorical(runs[dim], categories=orders[dim], ordered=True)
    runs = runs.sort_values([*DIMS, *axes, "replicate", "key"], kind="stable").reset_index(drop=True)
    dims = tuple(d for d in (*DIMS, *axes) if d in ALWAYS_SHOWN or runs[d].nunique() > 1)
    every = spec.timeseries_every if spec is not None else 10
    name = spec.name if spec is not None else (str(runs["campaign"].iloc[0]) if len(runs) else folder.name)
    return CampaignData(folder=folder, name=name, description=spec.description if spec else "", source=source,
                        spec=spec, runs=runs, orders=orders, dims=dims,
                        total=expected_runs(spec) if spec is not None else None, every=every, spec_error=spec_error,
                        axes=axes, foreign=foreign)


def _read_spec(source: str) -> tuple[CampaignSpec | None, str]:
    """The spec without validating its runs; a spec this installation cannot read still gets a report."""
    try:
        return campaign_from_mapping(tomllib.loads(source), folder_of(source) or ""), ""
    except (InvalidInput, tomllib.TOMLDecodeError) as exc:
        return None, str(exc)


def expected_runs(spec: CampaignSpec) -> int:
    """How many runs ``spec.runs()`` yields, building one run spec per cell instead of one per run.

    Two cells with identical run specs (e.g. a comm option that restates a default) share their keys and
    count once, as in :meth:`CampaignSpec.runs`. Seeds depend only on (map kind, size, replicate), so cells
    equal at replicate 0 are equal at every replicate.
    """
    cells = spec.cells()
    try:
        distinct = {spec.run_for(cell, 0).key for cell in cells}
    except InvalidInput:  # a spec this installation cannot build: count distinct option values instead
        distinct = {json.dumps({d: o.value for d, o in c.items()}, sort_keys=True, default=str) for c in cells}
    return len(distinct) * spec.replicates


def _runs_frame(df: pd.DataFrame | None, axes: tuple[str, ...] = ()) -> pd.DataFrame:
    columns = (*RUN_COLUMNS, *axes)
    if df is None:
        df = pd.DataFrame({c: pd.Series(dtype=object) for c in columns})
    for col in columns:
        if col not in df:
            df[col] = None
    df = df[[*columns, *([c for c in ("campaign",) if c in df])]].copy()
    for dim in (*DIMS, *axes):
        df[dim] = df[dim].astype(str)
    for col in ("ticks", "max_ticks", "explored_target", "explored", "coverage", "t50", "t75", "t90", "t95",
                "t98", "t99", "replicate", "map_seed", "msgs_sent", "bytes_sent", "msgs_delivered",
                "bytes_delivered", "msgs_dropped", "collisions_wall", "collisions_robot", *BENCHMARK_RUN_COLUMNS,
                *COMM_RUN_COLUMNS,
                *(c for c in LOCALIZATION_RUN_COLUMNS if c != "explored_measure")):
        df[col] = pd.to_numeric(df[col], errors="coerce")
    correct = (df["explored_measure"] == "correct").to_numpy()
    if correct.any():   # runs with a localisation model: explored counts correctly known cells (docs/localization.md)
        df.loc[correct, "explored"] = df.loc[correct, "explored_correct"]
        for col in THRESHOLD_COLUMNS.values():
            df.loc[correct, col] = df.loc[correct, f"{col}_correct"]
    df["error"] = df["error"].fillna("").astype(str)
    df["status"] = df["status"].fillna("failed").astype(str)
    df["stop_reason"] = df["stop_reason"].fillna("error").astype(str)
    return df


def _orders(spec: CampaignSpec | None, runs: pd.DataFrame, axes: tuple[str, ...] = ()) -> dict[str, list[str]]:
    """Per dimension: the spec's labels in spec order, then labels only the data has (from [[include]])."""
    orders: dict[str, list[str]] = {}
    for dim in (*DIMS, *axes):
        labels = [o.label for o in spec.grid.get(dim, ())] if spec is not None else []
        extra = sorted(set(runs[dim]) - set(labels), key=_natural)
        orders[dim] = [*labels, *extra] if labels or extra else []
    return orders


def _natural(label: str) -> tuple[Any, ...]:
    """Numbers in numeric order (2 < 16), everything else alphabetically after them."""
    try:
        return (0, float(label), label)
    except ValueError:
        return (1, 0.0, label)
