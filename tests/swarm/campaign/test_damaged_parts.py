"""Damaged parts (issue 48, item 6): one check for status, resume, report and load.

Each case damages one part of a real results folder the way a crafted or corrupted folder does (a column of
another type, a null label, a bit flip, a truncated or missing time series); then ``report`` and ``load``
must refuse in one line naming the part (no traceback), ``status`` must list it and count its runs as
pending, and a campaign run (resume) must move it to ``quarantine/`` unchanged and run its runs again, giving
the rows of an undamaged folder.
"""

from __future__ import annotations

import shutil
from collections.abc import Callable
from pathlib import Path

import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.parquet as pq
import pytest

from maps import InvalidInput
from swarm.campaign import (
    deterministic_rows,
    load,
    make_executor,
    parse_campaign,
    run_campaign,
    status,
)
from swarm.campaign.api import load_timeseries
from swarm.campaign.store import ResultsStore
from swarm.cli import main

SPEC = """
[campaign]
name = "damage"
seed = 7
replicates = 2

[grid]
map = ["building"]
size = [20]
robots = [1]
spawn = ["together"]
algorithm = ["frontier", "greed"]
radio = ["global"]

[stop]
explored = 0.6
max_ticks = 30
"""


def _run(folder: Path) -> None:
    run_campaign(parse_campaign(SPEC), folder, executor=make_executor(inline=True), progress=False, flush_runs=1,
                 warmup=False)


@pytest.fixture(scope="module")
def pristine(tmp_path_factory) -> Path:
    """4 runs, one part each."""
    folder = tmp_path_factory.mktemp("damage") / "pristine"
    _run(folder)
    assert len(list((folder / "parts").glob("*.runs.parquet"))) == 4
    return folder


def first(folder: Path, suffix: str) -> Path:
    return min((folder / "parts").glob(f"*{suffix}"))


def rewrite(suffix: str, column: str, make: Callable[[pa.Table], pa.Array]) -> Callable[[Path], None]:
    """Rewrite the first part's file with ``column`` replaced (what a crafted folder or another tool does)."""
    def edit(folder: Path) -> None:
        path = first(folder, suffix)
        table = pq.read_table(path)
        i = table.schema.get_field_index(column)
        pq.write_table(table.set_column(i, column, make(table)), path)
    return edit


def flip_in_data(suffix: str) -> Callable[[Path], None]:
    """Flip one bit in the middle of the first column chunk holding more than 64 bytes of page data."""
    def edit(folder: Path) -> None:
        path = first(folder, suffix)
        meta = pq.ParquetFile(path).metadata.row_group(0)
        chunks = [meta.column(i) for i in range(meta.num_columns)]
        chunk = max(chunks, key=lambda c: c.total_compressed_size)
        start = chunk.dictionary_page_offset or chunk.data_page_offset
        data = bytearray(path.read_bytes())
        data[start + chunk.total_compressed_size - 8] ^= 0x04
        path.write_bytes(bytes(data))
    return edit


def truncate(suffix: str) -> Callable[[Path], None]:
    def edit(folder: Path) -> None:
        path = first(folder, suffix)
        path.write_bytes(path.read_bytes()[: path.stat().st_size // 2])
    return edit


def remove(suffix: str) -> Callable[[Path], None]:
    return lambda folder: first(folder, suffix).unlink()


CASES = {
    "runs column of another type": (rewrite(".runs.parquet", "ticks", lambda t: pc.cast(t["ticks"], pa.string())),
                                    "ticks is string"),
    "grid label of another type": (rewrite(".runs.parquet", "spawn", lambda t: pa.array([5] * t.num_rows)),
                                   "spawn is int64"),
    "null grid label": (rewrite(".runs.parquet", "map", lambda t: pa.nulls(t.num_rows, pa.string())),
                        "map is empty"),
    "dictionary-encoded null label": (rewrite(".runs.parquet", "map",
                                              lambda t: pa.nulls(t.num_rows, pa.string()).dictionary_encode()),
                                      "map is dictionary"),
    "unknown status": (rewrite(".runs.parquet", "status", lambda t: pa.array(["done"] * t.num_rows)),
                       "neither ok nor failed"),
    "bit flip in the runs file": (flip_in_data(".runs.parquet"), "runs file cannot be read"),
    "time-series column of another type": (rewrite(".timeseries.parquet", "tick",
                                                   lambda t: pc.cast(t["tick"], pa.string())), "time-series file"),
    "bit flip in the time series": (flip_in_data(".timeseries.parquet"), "time-series file was changed"),
    "truncated time series": (truncate(".timeseries.parquet"), "time-series file was changed"),
    "missing time series": (remove(".timeseries.parquet"), "time-series file is missing"),
    "truncated per-robot rows": (truncate(".robots.parquet"), "per-robot file was changed"),
}


@pytest.mark.parametrize("case", list(CASES))
def test_a_damaged_part_is_refused_by_all_and_redone_by_resume(pristine, tmp_path, capsys, case):
    damage, needle = CASES[case]
    folder = tmp_path / "results"
    shutil.copytree(pristine, folder)
    part = first(folder, ".runs.parquet").name[: -len(".runs.parquet")]
    damage(folder)
    damaged_files = {p.name: p.read_bytes() for p in (folder / "parts").glob(f"{part}.*")}

    # report and load: one line naming the part and the problem
    assert main(["campaign", "report", str(folder), "-o", str(tmp_path / "report"), "--no-cell-figures"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("swarm: error: DIR:") and "Traceback" not in err, err
    assert part[:20] in err and needle in err, err
    for reader in (load, load_timeseries):
        with pytest.raises(InvalidInput, match=needle):
            reader(folder)

    # status: the same verdict, the part's run pending
    s = status(folder)
    assert len(s["damaged"]) == 1 and part[:20] in s["damaged"][0] and needle in s["damaged"][0], s
    assert s["done"] == 3 and s["pending"] == 1, s
    assert main(["campaign", "status", str(folder)]) == 0
    assert "damaged part" in capsys.readouterr().out

    # resume: the part is moved aside unchanged, its run redone; nothing else changes
    logged: list[str] = []
    outcome = run_campaign(parse_campaign(SPEC), folder, executor=make_executor(inline=True), progress=False,
                           warmup=False, log=logged.append)
    assert outcome.ran == 1 and any("quarantine/" in line and part[:20] in line for line in logged), logged
    kept = {p.name: p.read_bytes() for p in (folder / "quarantine").iterdir()}
    assert kept == damaged_files
    assert not list((folder / "parts").glob(f"{part}.*"))
    s = status(folder)
    assert (s["done"], s["pending"], s["damaged"]) == (4, 0, []), s
    assert deterministic_rows(folder) == deterministic_rows(pristine)
    assert len(load_timeseries(folder)) == len(load_timeseries(pristine))


def test_the_pristine_folder_is_sound(pristine):
    store = ResultsStore(pristine)
    assert store.damaged() == [] and len(store.check()) == 4
    assert len(load(pristine)) == 4


def test_a_part_of_an_older_version_without_its_time_series_is_damaged(pristine, tmp_path):
    """Parts written before issue 48 record no companions: a missing time series is still noticed."""
    folder = tmp_path / "old"
    shutil.copytree(pristine, folder)
    for path in (folder / "parts").glob("*.runs.parquet"):
        table = pq.read_table(path)
        pq.write_table(table.replace_schema_metadata(None), path)  # as older versions wrote it
    assert ResultsStore(folder).damaged() == [] and len(load(folder)) == 4
    first(folder, ".timeseries.parquet").unlink()
    (bad,) = ResultsStore(folder).damaged()
    assert "time-series file is missing" in bad.problem and len(bad.keys) == 1


def test_a_part_of_failed_runs_needs_no_time_series(tmp_path):
    spec = SPEC.replace('algorithm = ["frontier", "greed"]',
                        'algorithm = [{name = "tests.swarm.campaign.broken:Boom", label = "boom"}]')
    run_campaign(parse_campaign(spec), tmp_path, executor=make_executor(inline=True), progress=False, warmup=False)
    assert not list((tmp_path / "parts").glob("*.timeseries.parquet"))
    assert ResultsStore(tmp_path).damaged() == []
    assert status(tmp_path)["failed"] == 2
