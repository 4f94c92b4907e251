"""The one check of a results folder's parts, shared by ``status``, resume, ``report`` and ``load``.

A part is a runs file (``<id>.runs.parquet``) and the companions committed before it (time series, per-robot
rows; :mod:`.store`). Before this check each reader trusted what it happened to read: ``status`` read two
columns of the runs files and passed a part whose other columns were damaged or of another type, which
``report`` then died on (``ArrowTypeError: Unable to merge``). Now every reader goes through
:func:`check_part`, and a part is either *sound*, and read, or *damaged*, and never merged:

- its runs file reads whole (every column; Parquet page checksums are verified where the file has them)
  and has the runs table's types (:data:`swarm.results.schema.RUNS`; a column null in every row may have
  the null type, as older versions wrote it); ``key`` is a non-null string unique in the part, ``status`` is
  ``ok`` or ``failed``, the grid labels and axes are non-null strings;
- its rows equal what was written: the runs file records the CRC-32 of its own column names, types and
  values (in its Parquet metadata since issue 48), so a flip in the footer that renames or retypes a column
  is seen (one in the footer's statistics changes nothing read and passes);
- every companion the runs file records (size and CRC-32) is there with that size and CRC-32: a bit flip,
  a truncation or a rewrite anywhere in it is seen without decoding it. A part of an older version records nothing: it needs a time-series file when one of its runs is ok,
  and each companion must open and have the schema's types.

What a damaged part means is documented in docs/campaigns.md ("Damaged parts"): status lists it and counts
its runs as pending, report and load refuse the folder naming it, and a campaign run (resume) moves its
files to ``DIR/quarantine/`` (nothing is deleted) and runs its runs again.
"""

from __future__ import annotations

import json
import zlib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.parquet as pq

from swarm.results.schema import (
    COMM_ROBOT_SERIES,
    COMM_SERIES,
    RUNS,
    TIMESERIES,
    arrow_type,
)

from .spec import is_axis
from .text import clip

RUNS_SUFFIX = ".runs.parquet"
TS_SUFFIX = ".timeseries.parquet"
ROBOTS_SUFFIX = ".robots.parquet"
COMPANIONS = (TS_SUFFIX, ROBOTS_SUFFIX)
RECORD_KEY = b"swarm.companions"
"""Runs-file metadata key: JSON ``{suffix: [size, crc32]}`` of the companions committed with the part."""
LABEL_COLUMNS = ("key", "map", "size", "spawn", "algorithm", "radio", "comm", "transport", "status")
"""Runs columns that must hold a string in every row (the report groups and sorts by them)."""
STATUSES = ("ok", "failed")
COMPANION_TYPES: dict[str, dict[str, str]] = {
    TS_SUFFIX: {"key": "string", **{c: t for c, (t, _) in TIMESERIES.items()},
                **{c: t for c, (t, _) in COMM_SERIES.items()}},
    ROBOTS_SUFFIX: {"key": "string", "tick": "int64", "robot": "int64",
                    **{c: t for c, (t, _) in COMM_ROBOT_SERIES.items()}},
}
"""Known columns of each companion and their types; ``key`` and ``tick`` (and ``robot``) are required."""
REQUIRED = {TS_SUFFIX: ("key", "tick"), ROBOTS_SUFFIX: ("key", "tick", "robot")}
_STEP = 1 << 20


class Damaged(Exception):
    """Why a part cannot be used (one short phrase), raised inside :func:`check_part`."""


@dataclass(frozen=True)
class PartCheck:
    """The verdict on one part: ``runs`` (normalised, see :func:`normalise_runs`) when sound, else ``problem``.
    ``keys``: the runs it holds, when its runs file could be read (a damaged part's runs are redone)."""

    part: str
    runs: pa.Table | None
    problem: str = ""
    keys: tuple[str, ...] = ()

    @property
    def sound(self) -> bool:
        return self.runs is not None

    def describe(self) -> str:
        """``<part id> (<problem>)``, short."""
        runs = f", {len(self.keys)} run{'s' if len(self.keys) != 1 else ''}" if self.keys else ""
        return f"{clip(self.part, 60)} ({self.problem}{runs})"


def file_crc(path: Path) -> tuple[int, int]:
    """Size and CRC-32 of a file, read a MiB at a time."""
    crc = size = 0
    with open(path, "rb") as f:
        while block := f.read(_STEP):
            crc = zlib.crc32(block, crc)
            size += len(block)
    return size, crc


def table_crc(table: pa.Table) -> int:
    """CRC-32 of a table's column names, types and values (not of its file: a flip in the footer's statistics
    changes nothing read, a flip in a column name or type changes this). For runs files: a row per run."""
    names = [(f.name, str(f.type)) for f in table.schema]
    text = json.dumps([names, table.to_pydict()], default=repr, allow_nan=True)
    return zlib.crc32(text.encode())


def companion_record(paths: dict[str, Path], runs: pa.Table) -> dict[bytes, bytes]:
    """The runs-file metadata recording the size and CRC-32 of each companion in ``paths`` (suffix -> path)
    and the CRC-32 of the runs table itself (:func:`table_crc`)."""
    record: dict[str, Any] = {suffix: list(file_crc(path)) for suffix, path in paths.items()}
    record["runs"] = table_crc(runs)
    return {RECORD_KEY: json.dumps(record).encode()}


def _types_ok(schema: pa.Schema, types: dict[str, str], what: str) -> None:
    for field in schema:
        expected = types.get(field.name)
        if expected is None or pa.types.is_null(field.type):
            continue
        want = arrow_type(expected)  # type: ignore[arg-type]
        if field.type != want and not (want == pa.float64() and pa.types.is_integer(field.type)):
            raise Damaged(f"{what} column {clip(field.name, 40)} is {clip(str(field.type), 40)}, not {want}")


def normalise_runs(table: pa.Table) -> pa.Table:
    """The runs columns readers use (:data:`RUNS` and grid axes), each of its :data:`RUNS` type: parts of
    different versions then always concatenate."""
    keep = [f for f in table.schema if f.name in RUNS or is_axis(f.name)]
    arrays = []
    for f in keep:
        col = table.column(f.name)
        if f.name in RUNS:
            want = arrow_type(RUNS[f.name])
            if col.type != want:
                col = col.cast(want)
        elif not pa.types.is_string(col.type):
            col = col.cast(pa.string())
        arrays.append(col)
    return pa.Table.from_arrays(arrays, names=[f.name for f in keep])


def _check_runs(table: pa.Table) -> None:
    _types_ok(table.schema, dict(RUNS), "runs")
    names = set(table.column_names)
    for name in ("key", "status"):
        if name not in names:
            raise Damaged(f"runs file has no {name!r} column")
    for name in [*LABEL_COLUMNS, *(n for n in names if is_axis(n))]:
        if name not in names:
            continue
        col = table.column(name)
        if table.num_rows and (pa.types.is_null(col.type) or col.null_count):
            raise Damaged(f"runs column {clip(name, 40)} is empty in a row")
        if not pa.types.is_string(col.type) and not pa.types.is_null(col.type):
            raise Damaged(f"runs column {clip(name, 40)} is {clip(str(col.type), 40)}, not string")
    if table.num_rows == 0:
        raise Damaged("runs file has no rows")
    keys = table.column("key")
    if pc.count_distinct(keys).as_py() != table.num_rows:
        raise Damaged("a run key appears twice in the runs file")
    bad = pc.invert(pc.is_in(table.column("status"), value_set=pa.array(STATUSES)))
    if pc.any(bad).as_py():
        raise Damaged("a status is neither ok nor failed")


def _check_companion(path: Path, suffix: str) -> None:
    try:
        schema = pq.read_schema(path)
    except (OSError, pa.ArrowException) as exc:
        raise Damaged(f"its {suffix[1:]} file cannot be read: {clip(str(exc), 60)}") from None
    for name in REQUIRED[suffix]:
        if name not in schema.names:
            raise Damaged(f"its {suffix[1:]} file has no {name!r} column")
    _types_ok(schema, COMPANION_TYPES[suffix], suffix[1:].split(".")[0])
    if pa.types.is_null(schema.field("key").type):
        raise Damaged(f"its {suffix[1:]} file has no run keys")


def check_part(parts: Path, part: str) -> PartCheck:
    """Check the part ``part`` (an id) in the folder ``parts``: sound (its normalised runs table) or damaged
    (the problem, and its run keys when readable). Reads the runs file whole and each companion's footer
    (and, when recorded, every byte of it for its CRC-32); never raises for what is in the files."""
    keys: tuple[str, ...] = ()
    try:
        try:
            table = pq.read_table(parts / f"{part}{RUNS_SUFFIX}", page_checksum_verification=True)
        except FileNotFoundError:
            raise Damaged("its runs file is gone") from None
        except (OSError, pa.ArrowException) as exc:
            raise Damaged(f"its runs file cannot be read: {clip(str(exc), 60)}") from None
        if "key" in table.column_names and pa.types.is_string(table.schema.field("key").type):
            keys = tuple(k for k in table.column("key").to_pylist() if isinstance(k, str))
        _check_runs(table)
        meta = table.schema.metadata or {}
        if RECORD_KEY in meta:
            _check_record(parts, part, meta[RECORD_KEY], table)
        else:  # an older part: what its files say must hold together
            if "ok" in table.column("status").to_pylist() and not (parts / f"{part}{TS_SUFFIX}").exists():
                raise Damaged("its time-series file is missing")
        for suffix in COMPANIONS:
            path = parts / f"{part}{suffix}"
            if path.exists():
                _check_companion(path, suffix)
        return PartCheck(part, normalise_runs(table), keys=keys)
    except Damaged as exc:
        return PartCheck(part, None, str(exc), keys)
    except (OSError, pa.ArrowException, ValueError, TypeError) as exc:  # anything else a crafted file provokes
        return PartCheck(part, None, f"unreadable ({clip(type(exc).__name__ + ': ' + str(exc), 60)})", keys)


def _check_record(parts: Path, part: str, raw: bytes, table: pa.Table) -> None:
    try:
        record: Any = json.loads(raw)
        runs_crc = int(record.pop("runs"))
        items = [(s, int(v[0]), int(v[1])) for s, v in record.items()]
    except (ValueError, TypeError, AttributeError, IndexError, KeyError):
        raise Damaged("its runs file's companion record is damaged") from None
    if table_crc(table.replace_schema_metadata(None)) != runs_crc:
        raise Damaged("its runs file was changed or damaged after it was written (CRC-32 of its rows differs)")
    for suffix, size, crc in items:
        if suffix not in COMPANIONS:
            raise Damaged("its runs file's companion record is damaged")
        path = parts / f"{part}{suffix}"
        what = "time-series" if suffix == TS_SUFFIX else "per-robot"
        if not path.exists():
            raise Damaged(f"its {what} file is missing")
        if file_crc(path) != (size, crc):
            raise Damaged(f"its {what} file was changed or damaged after it was written (size or CRC-32 differs)")
    if TS_SUFFIX not in record and (parts / f"{part}{TS_SUFFIX}").exists():
        raise Damaged("it has a time-series file its runs file does not record")


def normalise_companion(table: pa.Table, suffix: str) -> pa.Table:
    """A companion table with its known columns only, each of the schema's type."""
    types = COMPANION_TYPES[suffix]
    keep = [f for f in table.schema if f.name in types]
    arrays = []
    for f in keep:
        col, want = table.column(f.name), arrow_type(types[f.name])  # type: ignore[arg-type]
        arrays.append(col if col.type == want else col.cast(want))
    return pa.Table.from_arrays(arrays, names=[f.name for f in keep])
