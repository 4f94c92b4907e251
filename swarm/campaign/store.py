"""The results folder of a campaign: Parquet parts written atomically, readable by pandas/DuckDB/Polars.

Layout::

    DIR/campaign.toml          the spec as given (written once; a different spec in the same folder is an error)
    DIR/parts/<id>.timeseries.parquet   rows (key, tick, explored, coverage, ..., comm metrics)
    DIR/parts/<id>.robots.parquet       per robot and row (key, tick, robot, comm metrics); optional
    DIR/parts/<id>.runs.parquet         one row per run: spec columns, seeds, summary metrics, status
    DIR/writers/<writer>.lock           one per live writer (see :mod:`.writers`)
    DIR/quarantine/                     damaged parts moved aside by a campaign run (:mod:`.parts`)

A part is committed by renaming its runs file into place *after* its time-series and robots files: a run
counts as done only when its runs row exists, and a time-series or robots file without its runs file (a
crash in between) is ignored and removed by a later start-up once its writer is dead. Temporary files never have a ``.parquet``
suffix, so a kill -9 at any moment leaves either a whole part or nothing. Parts are named
``<time ns>-<seq>.<writer>`` so that later parts sort later and every part and temporary file names the
writer that made it (parts of older versions have no writer: ``<time ns>-<random>``); a key that appears
twice (a failed run retried) resolves to its latest row. The runs file records the size and CRC-32 of its
companions, and every reader goes through one check of each part (:mod:`.parts`): a damaged part is never
merged.
"""

from __future__ import annotations

import contextlib
import itertools
import os
import re
import time
import uuid
from pathlib import Path
from typing import Any, Iterable

import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.parquet as pq

from swarm.base.errors import InvalidInput

from swarm.results.schema import THRESHOLD_COLUMNS, robots_table, runs_table, timeseries_table  # noqa: F401  (re-export)
from .identity import difference
from .parts import (
    COMPANIONS,
    ROBOTS_SUFFIX,
    RUNS_SUFFIX,
    TS_SUFFIX,
    PartCheck,
    check_part,
    companion_record,
    normalise_companion,
)
from .text import clip

PARTS = "parts"
QUARANTINE = "quarantine"
"""Where a campaign run moves damaged parts (never deleted: the bytes stay for whoever wants to look)."""
SPEC_FILE = "campaign.toml"
WRITER_ID = r"[A-Za-z0-9_-]{1,40}-[0-9]{1,10}-[0-9a-f]{8}"
"""``<host>-<pid>-<nonce>`` (see :func:`swarm.campaign.writers.new_writer_id`)."""
_OWNED = re.compile(rf"^\.?[0-9]{{20}}-[0-9]{{6}}\.(?P<writer>{WRITER_ID})\.")
_PROBE = re.compile(rf"^\.probe\.(?P<writer>{WRITER_ID})\.tmp$")


def writer_of(name: str) -> str | None:
    """The writer id in a part or temporary file name; None for names of older versions (no writer)."""
    m = _OWNED.match(name) or _PROBE.match(name)
    return m.group("writer") if m else None


class CommitError(InvalidInput):
    """A part could not be written (disk full, quota, I/O error): the campaign stops, parts committed before
    stay, and running the same command again resumes. One line, exit status 2 like any bad folder."""

    def __init__(self, folder: Path, exc: OSError, runs: int) -> None:
        reason = exc.strerror or clip(str(exc), 120) or type(exc).__name__
        super().__init__("-o", str(folder), f"a results folder that can take more parts: writing one failed "
                                            f"({reason}); earlier parts are kept, the {runs} runs of this part "
                                            "were not saved; free space and run the same command to resume")
        self.errno = exc.errno


class ResultsStore:
    def __init__(self, folder: str | Path) -> None:
        self.folder = Path(folder)
        self.parts = self.folder / PARTS
        self._seq = itertools.count()
        self._checked: dict[str, tuple[tuple[Any, ...], PartCheck]] = {}

    # ------------------------------------------------------------------------------------ set-up ----
    def prepare(self, source: str) -> None:
        """Create the folder, or check an existing one belongs to the same spec (:mod:`.identity`: the
        parsed TOML must be equal; comments and formatting may differ). Deletes nothing."""
        spec_file = self.folder / SPEC_FILE
        try:
            self.refuse_foreign()
            self.parts.mkdir(parents=True, exist_ok=True)
            if spec_file.exists():
                stored = spec_file.read_text(encoding="utf-8", errors="replace")
            else:
                stored = None
                _atomic_write(spec_file, source.encode())
        except OSError as exc:
            raise self.folder_error(exc) from None
        if stored is not None:
            changed = difference(stored, source)
            if changed:
                raise InvalidInput("-o", str(self.folder), "an empty folder or one holding results of this same "
                                                           f"spec (campaign.toml differs: {changed})")

    def refuse_foreign(self) -> None:
        """A one-line refusal if the folder holds files but no ``campaign.toml``: a campaign is never scattered
        among someone else's files (``-o .``, ``-o ~``). Call before writing anything into it."""
        if not (self.folder / SPEC_FILE).exists() and self.folder.is_dir():
            others = sorted(p.name for p in self.folder.iterdir()  # (a writer starting beside us may be
                            if p.name not in (PARTS, "writers", SPEC_FILE)  # writing campaign.toml right now,
                            and not p.name.startswith(f".{SPEC_FILE}."))     # or have just renamed it in)
            if others:
                raise InvalidInput("-o", str(self.folder), "an empty folder or one holding results of this same "
                                                           f"spec (it holds {clip(others[0])} and no {SPEC_FILE})")

    open_for = prepare  # the name of earlier versions (a single writer: nothing is cleaned any more)

    def folder_error(self, exc: OSError) -> InvalidInput:
        where = Path(exc.filename).name if exc.filename else self.folder.name
        return InvalidInput("-o", str(self.folder), f"a writable results folder ({exc.strerror or exc}: {clip(where)})")

    def probe(self, writer: str) -> None:
        """Create and remove a small file in ``parts/``: a folder we cannot write fails here, before any run
        is computed, not when the first part is committed."""
        path = self.parts / f".probe.{writer}.tmp"
        try:
            fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o644)
            try:
                os.write(fd, b"probe")
                os.fsync(fd)
            finally:
                os.close(fd)
                path.unlink(missing_ok=True)
        except OSError as exc:
            raise self.folder_error(exc) from None

    def spec_source(self) -> str:
        path = self.folder / SPEC_FILE
        try:
            return path.read_text(encoding="utf-8")
        except FileNotFoundError:
            raise InvalidInput("DIR", str(self.folder), "a campaign results folder (no campaign.toml in it)") from None
        except OSError as exc:
            raise InvalidInput("DIR", str(self.folder), f"a readable campaign results folder ({exc.strerror})") from None
        except UnicodeDecodeError:
            raise InvalidInput("DIR", str(self.folder), "a campaign results folder (its campaign.toml is not "
                                                        "UTF-8 text)") from None

    def leftovers(self) -> list[tuple[Path, str | None]]:
        """Temporary files and time-series files without their runs file, with the writer that made each
        (None: a name of an older version). Only files whose writer is dead may be removed."""
        out: list[tuple[Path, str | None]] = []
        try:
            names = os.listdir(self.parts)
        except FileNotFoundError:
            return out
        present = set(names)
        for name in names:
            if name.startswith(".") and name.endswith(".tmp"):
                out.append((self.parts / name, writer_of(name)))
            else:
                for suffix in COMPANIONS:
                    if name.endswith(suffix) and name[: -len(suffix)] + RUNS_SUFFIX not in present:
                        out.append((self.parts / name, writer_of(name)))
        return out

    # ----------------------------------------------------------------------------------- writing ----
    def new_part_id(self, writer: str | None) -> str:
        if writer is None:
            return f"{time.time_ns():020d}-{uuid.uuid4().hex[:8]}"
        return f"{time.time_ns():020d}-{next(self._seq) % 1_000_000:06d}.{writer}"

    def write_part(self, runs: list[dict[str, Any]], timeseries: list[dict[str, Any]],
                   writer: str | None = None, robots: list[dict[str, Any]] | None = None) -> str:
        """Commit a batch of finished runs (``robots``: their per-robot rows, if any); returns the part id. On
        an OSError nothing of the part is left (no temporary file, no time-series or robots file without its
        runs) and :class:`CommitError` is raised."""
        return self.write_tables(runs_table(runs), timeseries_table(timeseries) if timeseries else None,
                                 robots_table(robots) if robots else None, writer)

    def write_tables(self, runs: pa.Table, timeseries: pa.Table | None, robots: pa.Table | None,
                     writer: str | None = None, level: int | None = None,
                     metadata: dict[bytes, bytes] | None = None) -> str:
        """:meth:`write_part` for rows already in tables (``level``: the zstd level, default pyarrow's; a
        compacted folder is written once and kept, so it is worth a higher one; ``metadata``: more keys for
        the runs file's metadata)."""
        part = self.new_part_id(writer)
        ts_path = self.parts / f"{part}{TS_SUFFIX}"
        robots_path = self.parts / f"{part}{ROBOTS_SUFFIX}"
        runs_path = self.parts / f"{part}{RUNS_SUFFIX}"
        owned = writer is not None
        try:
            written = {}
            if timeseries is not None and timeseries.num_rows:
                _write_table(ts_path, timeseries, owned=owned, level=level)
                written[TS_SUFFIX] = ts_path
            if robots is not None and robots.num_rows:
                _write_table(robots_path, robots, owned=owned, level=level)
                written[ROBOTS_SUFFIX] = robots_path
            table = runs.replace_schema_metadata({**(runs.schema.metadata or {}), **(metadata or {}),
                                                  **companion_record(written, runs)})  # companions' size, CRC-32
            _write_table(runs_path, table, owned=owned, level=level)
        except OSError as exc:
            if not runs_path.exists():
                for path in (ts_path, robots_path):
                    with contextlib.suppress(OSError):
                        path.unlink(missing_ok=True)
            raise CommitError(self.folder, exc, runs.num_rows) from None
        return part

    # ----------------------------------------------------------------------------------- reading ----
    def run_files(self) -> list[Path]:
        return sorted(self.parts.glob(f"*{RUNS_SUFFIX}")) if self.parts.exists() else []

    def check(self) -> list[PartCheck]:
        """Every committed part checked (:func:`swarm.campaign.parts.check_part`), in part order. A part's
        verdict is kept while its runs file is unchanged (parts are never rewritten)."""
        out = []
        for path in self.run_files():
            part = path.name[: -len(RUNS_SUFFIX)]
            try:
                st = path.stat()
            except OSError:  # gone meanwhile (moved to quarantine by another process)
                continue
            stamp = (st.st_size, st.st_mtime_ns, *(_stamp(self.parts / f"{part}{s}") for s in COMPANIONS))
            cached = self._checked.get(part)
            if cached is None or cached[0] != stamp:
                cached = self._checked[part] = (stamp, check_part(self.parts, part))
            out.append(cached[1])
        return out

    def damaged(self) -> list[PartCheck]:
        """The parts that must not be read (:mod:`.parts`)."""
        return [c for c in self.check() if not c.sound]

    def require_sound(self) -> None:
        """Raise the one-line :class:`InvalidInput` naming a damaged part, if there is one (report, load)."""
        bad = self.damaged()
        if bad:
            more = f" and {len(bad) - 1} more" if len(bad) > 1 else ""
            raise InvalidInput("DIR", str(self.folder), f"a results folder whose parts are sound (part "
                                                        f"{bad[0].describe()}{more}; 'swarm campaign run' on it "
                                                        f"moves damaged parts to {QUARANTINE}/ and runs their "
                                                        "runs again)")

    def quarantine(self, parts: Iterable[PartCheck]) -> list[str]:
        """Move the files of ``parts`` to ``DIR/quarantine/`` (companions first, the runs file last: a kill
        in between leaves a runs file without its companions, damaged too, moved by the next run). Returns the
        part ids moved; a file already gone (another process moved it) is skipped."""
        target = self.folder / QUARANTINE
        moved = []
        for check in parts:
            try:
                target.mkdir(exist_ok=True)
                for suffix in (*COMPANIONS, RUNS_SUFFIX):
                    src = self.parts / f"{check.part}{suffix}"
                    dst = target / src.name
                    n = 0
                    while dst.exists():  # never replace what an earlier quarantine kept
                        n += 1
                        dst = target / f"{src.name}.{n}"
                    with contextlib.suppress(FileNotFoundError):
                        os.rename(src, dst)
            except OSError as exc:
                raise self.folder_error(exc) from None
            self._checked.pop(check.part, None)
            moved.append(check.part)
        return moved

    def runs_table(self, columns: Iterable[str] | None = None) -> pa.Table | None:
        """All runs rows of the sound parts, the latest row per key (``columns``: only these, plus ``part``)."""
        wanted = None if columns is None else list(columns)
        tables = []
        for check in self.check():
            if check.runs is None:
                continue
            t = check.runs
            if wanted is not None:
                t = t.select([c for c in wanted if c in t.column_names])
            tables.append(t.append_column("part", pa.array([check.part] * t.num_rows, pa.string())))
        if not tables:
            return None
        table = pa.concat_tables(tables, promote_options="permissive")
        return _latest_per_key(table)

    def timeseries_table(self, keys: Iterable[str] | None = None) -> pa.Table | None:
        """The time-series rows of every run (or of ``keys``), from the part holding each run's latest row."""
        return self._companion_table(TS_SUFFIX, keys)

    def robots_table(self, keys: Iterable[str] | None = None) -> pa.Table | None:
        """The per-robot rows (key, tick, robot, comm metrics) of every run (or of ``keys``); None when no
        part has any (a campaign with ``output.robot_series_every = 0``, or of an older version)."""
        return self._companion_table(ROBOTS_SUFFIX, keys)

    def _companion_table(self, suffix: str, keys: Iterable[str] | None) -> pa.Table | None:
        runs = self.runs_table(columns=("key",))
        if runs is None:
            return None
        wanted = dict(zip(runs.column("key").to_pylist(), runs.column("part").to_pylist()))
        if keys is not None:
            keys = set(keys)
            wanted = {k: p for k, p in wanted.items() if k in keys}
        tables = []
        for part in sorted(set(wanted.values())):
            path = self.parts / f"{part}{suffix}"
            if path.exists():
                t = normalise_companion(self.read_part(path), suffix)
                mask = pc.is_in(t.column("key"), value_set=pa.array([k for k, p in wanted.items() if p == part],
                                                                    pa.string()))
                tables.append(t.filter(mask))
        return pa.concat_tables(tables, promote_options="permissive") if tables else None

    def read_part(self, path: Path, columns: list[str] | None = None) -> pa.Table:
        """A part file; a damaged one (parts are written atomically, so only something outside the campaign
        damages them) is a one-line error naming it."""
        try:
            return pq.read_table(path, columns=columns)
        except (OSError, pa.ArrowException) as exc:
            raise InvalidInput("DIR", str(self.folder), f"readable Parquet parts ({clip(path.name)} cannot be "
                                                        f"read: {clip(str(exc), 80)}; move it out of parts/ and "
                                                        "run the campaign again to redo its runs)") from None

    def done_keys(self) -> dict[str, str]:
        """key -> status ('ok' or 'failed') of every committed run of a sound part; a run also held by a
        damaged part is not done (it is run again: its latest result is the damaged one)."""
        table = self.runs_table(columns=("key", "status"))
        if table is None:
            return {}
        redo = {k for c in self.damaged() for k in c.keys}
        return {k: st for k, st in zip(table.column("key").to_pylist(), table.column("status").to_pylist())
                if k not in redo}


def _stamp(path: Path) -> tuple[int, int] | None:
    """Size and modification time of a file, None if it is not there (a part's verdict is redone when any
    of its files changes)."""
    try:
        st = path.stat()
    except OSError:
        return None
    return st.st_size, st.st_mtime_ns


def _write_table(path: Path, table: pa.Table, owned: bool = False, level: int | None = None) -> None:
    """Write ``table`` to a temporary file, fsync it and rename it into place (``owned``: the final name
    carries the writer id, so the temporary name needs no extra randomness; ``level``: zstd level)."""
    tmp = path.with_name(f".{path.name}.tmp" if owned else f".{path.name}.{uuid.uuid4().hex[:8]}.tmp")
    try:
        pq.write_table(table, tmp, compression="zstd", compression_level=level, write_page_checksum=True)
        with open(tmp, "rb") as f:
            os.fsync(f.fileno())
        os.replace(tmp, path)
    finally:
        with contextlib.suppress(OSError):
            tmp.unlink(missing_ok=True)


def _atomic_write(path: Path, data: bytes) -> None:
    tmp = path.with_name(f".{path.name}.{uuid.uuid4().hex[:8]}.tmp")
    try:
        with open(tmp, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    finally:
        with contextlib.suppress(OSError):
            tmp.unlink(missing_ok=True)


def _latest_per_key(table: pa.Table) -> pa.Table:
    keys = table.column("key").to_pylist()
    parts = table.column("part").to_pylist()
    latest: dict[str, int] = {}
    for i, (k, p) in enumerate(zip(keys, parts)):
        if k not in latest or parts[latest[k]] <= p:
            latest[k] = i
    return table.take(sorted(latest.values()))
