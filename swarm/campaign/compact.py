"""Compacting a results folder: its many small parts rewritten as one, for keeping or publishing.

A campaign commits a part every few runs, so a 7,000-run folder holds thousands of small Parquet files,
each compressed on its own (~50 KB a run with time series every 10 ticks). :func:`compact` writes every
run's latest row, time series and per-robot rows into one new part (zstd at a high level: a few KB a run)
and then removes the parts it replaces. Nothing is edited: rows and columns are copied as read.

Safety, as for every writer (:mod:`.store`): the new part is committed (its runs file renamed into place
last) before any old file goes, and an old part's runs file goes before its companions. A kill at any
moment leaves each run in at least one sound part, and where it is in two the new part is the later one,
whose row wins (:meth:`ResultsStore.runs_table`); a companion left without its runs file is a leftover that
the next ``swarm campaign run`` removes. The folder's start-up lock is held throughout, and a folder with a
live writer or a damaged part is refused: nothing else writes meanwhile, and nothing damaged is copied.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.parquet as pq

from swarm.base.errors import InvalidInput

from .parts import COMPANIONS, RUNS_SUFFIX
from .store import ResultsStore, _latest_per_key
from .writers import WRITERS, live_writers_locked, new_writer_id, registry_lock

LEVEL = 12
"""zstd level of the compacted part (pyarrow's default is 1): ~2x smaller time series, written once."""
MARK = b"swarm.compacted"
"""Runs-file metadata key of a part :func:`compact` wrote: a later compaction leaves it as it is."""


@dataclass(frozen=True)
class Compacted:
    """What :func:`compact` did: the runs it rewrote, the parts it replaced, the new part (None: nothing to
    do), the bytes of ``parts/`` before and after, and the parts of earlier compactions it left alone."""

    runs: int
    parts_before: int
    part: str | None
    bytes_before: int
    bytes_after: int
    kept: int = 0


def compact(folder: str | Path, level: int = LEVEL, everything: bool = False) -> Compacted:
    """Rewrite the sound parts of the results folder ``folder`` as one part (every run's latest row and its
    companions' rows) and remove them. Parts an earlier compaction wrote are left as they are (a folder kept
    in version control then grows by one file per compaction, and nothing kept is rewritten), unless
    ``everything``; fewer than two parts to merge is nothing to do. Raises
    :class:`InvalidInput` (field ``DIR``) for a folder that is not a campaign's, has a damaged part or is
    being written."""
    store = ResultsStore(folder)
    store.spec_source()  # a campaign results folder, or the one-line refusal
    try:
        (store.folder / WRITERS).mkdir(exist_ok=True)
        return _compact(store, level, everything)
    except OSError as exc:
        raise store.folder_error(exc) from None


def _compact(store: ResultsStore, level: int, everything: bool) -> Compacted:
    with registry_lock(store.folder, wait_s=5.0):
        live = live_writers_locked(store.folder)
        if live:
            raise InvalidInput("DIR", str(store.folder), "a results folder nobody is writing (a campaign is "
                                                         f"writing it now: {live[0].describe()})")
        store.require_sound()
        checks = store.check()  # (each part's verdict is kept: read once)
        before = _parts_bytes(store)
        kept = set() if everything else {c.part for c in checks if _is_compacted(store, c.part)}
        merged = [c.part for c in checks if c.part not in kept]
        if len(merged) < 2:
            n = sum(c.runs.num_rows for c in checks if c.runs is not None)
            return Compacted(n, len(checks), None, before, before, len(kept))
        latest = _latest_runs(store, [c.part for c in checks])  # over every part: a kept part may win a key
        mine = pc.is_in(latest.column("part"), value_set=pa.array(merged, pa.string()))
        runs = latest.filter(mine)
        winners = runs.column("part").to_pylist()
        keys = runs.column("key").to_pylist()
        companions = {suffix: _companion(store, suffix, keys, winners) for suffix in COMPANIONS}
        new = store.write_tables(runs.drop_columns(["part"]), *(companions[s] for s in COMPANIONS),
                                 writer=new_writer_id(), level=level, metadata={MARK: b"1"})
        for part in merged:  # the runs file first: its companions alone are a leftover, never a damaged part
            for suffix in (RUNS_SUFFIX, *COMPANIONS):
                (store.parts / f"{part}{suffix}").unlink(missing_ok=True)
        return Compacted(runs.num_rows, len(merged), new, before, _parts_bytes(store), len(kept))


def _is_compacted(store: ResultsStore, part: str) -> bool:
    """Whether ``part`` was written by :func:`compact` (its runs file's metadata says so)."""
    meta = pq.read_schema(store.parts / f"{part}{RUNS_SUFFIX}").metadata or {}
    return meta.get(MARK) == b"1"


def _latest_runs(store: ResultsStore, parts: list[str]) -> pa.Table:
    """Every run's latest row as written (all its columns), with the ``part`` it came from."""
    tables = []
    for part in parts:
        t = store.read_part(store.parts / f"{part}{RUNS_SUFFIX}")
        t = t.replace_schema_metadata(None)
        tables.append(t.append_column("part", pa.array([part] * t.num_rows, pa.string())))
    return _latest_per_key(pa.concat_tables(tables, promote_options="permissive"))


def _companion(store: ResultsStore, suffix: str, keys: list[str], parts: list[str]) -> pa.Table | None:
    """The ``suffix`` rows of each run in ``keys`` from the part in ``parts`` that holds its latest row."""
    by_part: dict[str, list[str]] = {}
    for key, part in zip(keys, parts):
        by_part.setdefault(part, []).append(key)
    tables = []
    for part in sorted(by_part):
        path = store.parts / f"{part}{suffix}"
        if not path.exists():
            continue
        t = store.read_part(path).replace_schema_metadata(None)
        tables.append(t.filter(pc.is_in(t.column("key"), value_set=pa.array(by_part[part], pa.string()))))
    return pa.concat_tables(tables, promote_options="permissive") if tables else None


def _parts_bytes(store: ResultsStore) -> int:
    try:
        return sum(e.stat().st_size for e in os.scandir(store.parts) if e.name.endswith(".parquet"))
    except FileNotFoundError:
        return 0


__all__ = ["LEVEL", "Compacted", "compact"]
