"""Time series of many runs, streamed part by part and resampled onto a per-cell grid with numpy.

A 54,000-run campaign holds ~10^8 time-series rows; loading them at once (key strings included) would need
gigabytes. Instead each Parquet part is read alone (only the needed columns), its rows are mapped to run
indices and scattered into one float32 buffer holding, for every run, its explored fraction on its cell's
time grid (at most ``MAX_POINTS`` points). No Python loop touches individual runs or ticks.

Sampling rule: the value at grid tick g is the last recorded value at a tick <= g. A run stops when it
reaches its target (or times out or stalls); after its final tick it keeps its last value: it is done,
and dropping it would make the average jump as the fast runs leave.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.parquet as pq

from ..store import TS_SUFFIX, ResultsStore

MAX_POINTS = 400
"""Grid points per curve: enough for a smooth line, small enough for 54,000 runs in ~90 MB."""


def iter_parts(store: ResultsStore, runs: pd.DataFrame, columns: Sequence[str]) -> Iterator[tuple[np.ndarray, pa.Table]]:
    """Yield ``(run_index, table)`` per time-series part: rows of the runs in ``runs`` (its positional index
    is the run index) from the part holding each run's latest row, with only ``columns`` (plus ``key``).
    Within a part, rows come sorted by (run, tick)."""
    if runs.empty:
        return
    keys = runs["key"].to_numpy(dtype=object)
    by_part = pd.Series(np.arange(len(runs)), index=runs["part"].to_numpy(dtype=object)).groupby(level=0, sort=True)
    for part, positions in by_part:
        path = store.parts / f"{part}{TS_SUFFIX}"
        if not path.exists():
            continue
        try:
            available = set(pq.read_schema(path).names)
        except (OSError, pa.ArrowException):
            store.read_part(path)  # raises the one-line error naming the damaged part
            raise
        cols = ["key", *[c for c in columns if c in available and c != "key"]]
        table = store.read_part(path, columns=cols)
        pos = positions.to_numpy()
        idx = pc.index_in(table.column("key"), value_set=pa.array(keys[pos].tolist(), pa.string()))
        keep = pc.is_valid(idx)
        table = table.filter(keep)
        if table.num_rows == 0:
            continue
        run_index = pos[idx.filter(keep).to_numpy(zero_copy_only=False).astype(np.int64)]
        order = np.lexsort((table.column("tick").to_numpy(), run_index))
        yield run_index[order], table.take(pa.array(order))


def explored_values(table: pa.Table) -> np.ndarray:
    """The explored fraction of each row: counting only correctly known cells where the run recorded that
    (a localisation model: ``explored_correct``), else the cells the lidars have seen."""
    value = table.column("explored").to_numpy(zero_copy_only=False).astype(np.float64)
    if "explored_correct" in table.column_names:
        correct = table.column("explored_correct").to_numpy(zero_copy_only=False).astype(np.float64)
        value = np.where(np.isnan(correct), value, correct)
    return value


@dataclass
class Sampled:
    """Explored fraction of every run on its cell's grid, and each run's first recorded tick at the target."""

    cell_ticks: list[np.ndarray]
    """Per cell: grid ticks (0, step, 2 step, ...)."""
    cell_values: list[np.ndarray]
    """Per cell: float32 [runs in cell, grid points], NaN for a run without any time series."""
    cell_rows: list[np.ndarray]
    """Per cell: the run indices of the rows of ``cell_values``."""
    first_at_target: np.ndarray
    """Per run: first recorded tick with explored >= target, -1 if none (NaN-free int64)."""


def grid_step(max_tick: int, every: int) -> int:
    """A multiple of the recording interval giving at most ``MAX_POINTS`` points up to ``max_tick``."""
    every = max(int(every), 1)
    return every * max(1, -(-int(max_tick) // (every * (MAX_POINTS - 1))))


@dataclass
class _Layout:
    """Where each run's grid points sit in one flat buffer: runs of a cell contiguous, ``points[c]`` each."""

    cell_id: np.ndarray
    steps: np.ndarray
    points: np.ndarray
    offset: np.ndarray
    by_cell: np.ndarray
    size: int

    @classmethod
    def of(cls, runs: pd.DataFrame, cell_id: np.ndarray, every: int) -> "_Layout":
        """A cell's grid ends at the latest final tick among its runs."""
        n_runs = len(runs)
        cell_id = np.asarray(cell_id, dtype=np.int64)
        n_cells = int(cell_id.max()) + 1 if n_runs else 0
        final = runs["ticks"].fillna(0).to_numpy(dtype=np.int64)
        cell_max = np.zeros(n_cells, dtype=np.int64)
        np.maximum.at(cell_max, cell_id, final)
        steps = np.array([grid_step(int(m), every) for m in cell_max], dtype=np.int64)
        points = cell_max // np.maximum(steps, 1) + 1 + (cell_max % np.maximum(steps, 1) > 0)
        by_cell = np.argsort(cell_id, kind="stable")
        row_len = points[cell_id[by_cell]]
        starts_sorted = np.concatenate([[0], np.cumsum(row_len)[:-1]]).astype(np.int64)
        offset = np.empty(n_runs, dtype=np.int64)
        offset[by_cell] = starts_sorted
        return cls(cell_id, steps, points, offset, by_cell, int(row_len.sum()))

    def slots(self, ridx: np.ndarray, tick: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Buffer positions of rows (run index, tick) and a mask of the last row of each slot."""
        run_step, run_points = self.steps[self.cell_id[ridx]], self.points[self.cell_id[ridx]]
        slot = np.minimum(-(-tick // run_step), run_points - 1)
        flat = self.offset[ridx] + slot
        last = np.ones(len(flat), dtype=bool)
        last[:-1] = flat[1:] != flat[:-1]
        return flat, last

    def cells(self, buffer: np.ndarray) -> tuple[list[np.ndarray], list[np.ndarray], list[np.ndarray]]:
        """Per cell: grid ticks, values [runs, points] (carried forward) and run indices."""
        cell_ticks, cell_values, cell_rows = [], [], []
        n_cells = len(self.points)
        bounds = np.searchsorted(self.cell_id[self.by_cell], np.arange(n_cells + 1))
        for c in range(n_cells):
            members = self.by_cell[bounds[c]:bounds[c + 1]]
            start = int(self.offset[members[0]]) if len(members) else 0
            block = buffer[start:start + len(members) * int(self.points[c])].reshape(len(members), int(self.points[c]))
            cell_values.append(_ffill(block))
            cell_ticks.append(np.arange(int(self.points[c]), dtype=np.int64) * int(self.steps[c]))
            cell_rows.append(members)
        return cell_ticks, cell_values, cell_rows


def sample(store: ResultsStore, runs: pd.DataFrame, cell_id: np.ndarray, every: int, target: float) -> Sampled:
    """Resample the explored series of ``runs`` (positional index = run index) cell by cell.

    ``cell_id[i]`` is run i's cell; a cell's grid ends at the latest final tick among its runs.
    """
    layout = _Layout.of(runs, cell_id, every)
    buffer = np.full(layout.size, np.nan, dtype=np.float32)
    first_at = np.full(len(runs), -1, dtype=np.int64)
    for ridx, table in iter_parts(store, runs, ("tick", "explored", "explored_correct")):
        tick = table.column("tick").to_numpy().astype(np.int64)
        value = explored_values(table)
        flat, last = layout.slots(ridx, tick)
        buffer[flat[last]] = value[last]
        reached = value >= target
        r_runs, r_ticks = ridx[reached], tick[reached]
        first = np.ones(len(r_runs), dtype=bool)
        first[1:] = r_runs[1:] != r_runs[:-1]
        first_at[r_runs[first]] = r_ticks[first]
    cell_ticks, cell_values, cell_rows = layout.cells(buffer)
    return Sampled(cell_ticks=cell_ticks, cell_values=cell_values, cell_rows=cell_rows, first_at_target=first_at)


def sample_columns(store: ResultsStore, runs: pd.DataFrame, cell_id: np.ndarray, every: int,
                   columns: Sequence[str]) -> dict[str, Sampled]:
    """:func:`sample` for other time-series columns (one pass over the parts for all of them): per column, its
    values on each cell's grid (NaN for runs whose parts lack the column, as parts of older versions do);
    ``first_at_target`` is left at -1."""
    layout = _Layout.of(runs, cell_id, every)
    buffers = {c: np.full(layout.size, np.nan, dtype=np.float32) for c in columns}
    for ridx, table in iter_parts(store, runs, ("tick", *columns)):
        tick = table.column("tick").to_numpy().astype(np.int64)
        flat, last = layout.slots(ridx, tick)
        for c in columns:
            if c in table.column_names:
                value = table.column(c).to_numpy(zero_copy_only=False).astype(np.float64)
                buffers[c][flat[last]] = value[last]
    out = {}
    for c in columns:
        cell_ticks, cell_values, cell_rows = layout.cells(buffers[c])
        out[c] = Sampled(cell_ticks, cell_values, cell_rows, np.full(len(runs), -1, dtype=np.int64))
    return out


def _ffill(block: np.ndarray) -> np.ndarray:
    """Carry each row's last value forward over NaN (grid slots with no row, and the time after the end)."""
    if block.size == 0:
        return block
    have = ~np.isnan(block)
    idx = np.where(have, np.arange(block.shape[1]), 0)
    np.maximum.accumulate(idx, axis=1, out=idx)
    return block[np.arange(block.shape[0])[:, None], idx]  # a row that starts with NaN stays NaN until data
