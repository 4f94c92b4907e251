"""The results folder of a campaign: Parquet parts written atomically, readable by pandas/DuckDB/Polars.

Layout::

    DIR/campaign.toml          the spec as given (written once; a different spec in the same folder is an error)
    DIR/parts/<id>.timeseries.parquet   rows (key, tick, explored, coverage, ..., comm metrics)
    DIR/parts/<id>.runs.parquet         one row per run: spec columns, seeds, summary metrics, status

A part is committed by renaming its runs file into place *after* its time-series file: a run counts as
done only when its runs row exists, and a time-series file without its runs file (a crash in between) is
ignored and removed on the next start. Temporary files never have a ``.parquet`` suffix, so a kill -9 at
any moment leaves either a whole part or nothing. Parts are named so that later parts sort later; a key
that appears twice (a failed run retried) resolves to its latest row.
"""

from __future__ import annotations

import os
import time
import uuid
from pathlib import Path
from typing import Any, Iterable

import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.parquet as pq

from maps.errors import InvalidInput
from maps.io import atomic_write_bytes

PARTS = "parts"
RUNS_SUFFIX = ".runs.parquet"
TS_SUFFIX = ".timeseries.parquet"
THRESHOLD_COLUMNS = {"0.5": "t50", "0.75": "t75", "0.9": "t90", "0.95": "t95", "0.98": "t98", "0.99": "t99"}


class ResultsStore:
    def __init__(self, folder: str | Path) -> None:
        self.folder = Path(folder)
        self.parts = self.folder / PARTS

    # ------------------------------------------------------------------------------------ set-up ----
    def open_for(self, source: str) -> None:
        """Create the folder, or check an existing one belongs to the same spec; drop orphan parts."""
        self.parts.mkdir(parents=True, exist_ok=True)
        spec_file = self.folder / "campaign.toml"
        if spec_file.exists():
            if spec_file.read_text(encoding="utf-8") != source:
                raise InvalidInput("-o", str(self.folder), "an empty folder or one holding results of this same spec "
                                                          "(campaign.toml differs)")
        else:
            atomic_write_bytes(spec_file, source.encode())
        for ts in self.parts.glob(f"*{TS_SUFFIX}"):
            if not (self.parts / ts.name.replace(TS_SUFFIX, RUNS_SUFFIX)).exists():
                ts.unlink()
        for tmp in self.parts.glob(".*"):
            tmp.unlink()

    def spec_source(self) -> str:
        path = self.folder / "campaign.toml"
        if not path.exists():
            raise InvalidInput("DIR", str(self.folder), "a campaign results folder (no campaign.toml in it)")
        return path.read_text(encoding="utf-8")

    # ----------------------------------------------------------------------------------- writing ----
    def write_part(self, runs: list[dict[str, Any]], timeseries: list[dict[str, Any]]) -> str:
        """Commit a batch of finished runs; returns the part id."""
        part = f"{time.time_ns():020d}-{uuid.uuid4().hex[:8]}"
        if timeseries:
            _write_table(self.parts / f"{part}{TS_SUFFIX}", pa.Table.from_pylist(timeseries))
        _write_table(self.parts / f"{part}{RUNS_SUFFIX}", pa.Table.from_pylist(runs))
        return part

    # ----------------------------------------------------------------------------------- reading ----
    def run_files(self) -> list[Path]:
        return sorted(self.parts.glob(f"*{RUNS_SUFFIX}")) if self.parts.exists() else []

    def runs_table(self) -> pa.Table | None:
        """All runs rows, the latest row per key."""
        files = self.run_files()
        if not files:
            return None
        tables = []
        for f in files:
            t = pq.read_table(f)
            tables.append(t.append_column("part", pa.array([f.name[: -len(RUNS_SUFFIX)]] * t.num_rows, pa.string())))
        table = pa.concat_tables(tables, promote_options="permissive")
        return _latest_per_key(table)

    def timeseries_table(self, keys: Iterable[str] | None = None) -> pa.Table | None:
        runs = self.runs_table()
        if runs is None:
            return None
        wanted = dict(zip(runs.column("key").to_pylist(), runs.column("part").to_pylist()))
        if keys is not None:
            keys = set(keys)
            wanted = {k: p for k, p in wanted.items() if k in keys}
        tables = []
        for part in sorted(set(wanted.values())):
            path = self.parts / f"{part}{TS_SUFFIX}"
            if path.exists():
                t = pq.read_table(path)
                mask = pc.is_in(t.column("key"), value_set=pa.array([k for k, p in wanted.items() if p == part]))
                tables.append(t.filter(mask))
        return pa.concat_tables(tables, promote_options="permissive") if tables else None

    def done_keys(self) -> dict[str, str]:
        """key -> status ('ok' or 'failed') of every committed run."""
        table = self.runs_table()
        if table is None:
            return {}
        return dict(zip(table.column("key").to_pylist(), table.column("status").to_pylist()))


def _write_table(path: Path, table: pa.Table) -> None:
    tmp = path.with_name(f".{path.name}.{uuid.uuid4().hex[:8]}.tmp")
    try:
        pq.write_table(table, tmp, compression="zstd")
        with open(tmp, "rb") as f:
            os.fsync(f.fileno())
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()


def _latest_per_key(table: pa.Table) -> pa.Table:
    keys = table.column("key").to_pylist()
    parts = table.column("part").to_pylist()
    latest: dict[str, int] = {}
    for i, (k, p) in enumerate(zip(keys, parts)):
        if k not in latest or parts[latest[k]] <= p:
            latest[k] = i
    return table.take(sorted(latest.values()))
