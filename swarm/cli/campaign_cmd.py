"""``swarm campaign``: run a campaign spec, check its progress, build its report."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import click

from swarm.base.errors import InvalidInput

from swarm.campaign.limits import DASK_CONNECT_TIMEOUT_S, MAX_RUNS
from .group import cli

QUICK_OUTPUT = Path("swarm-results") / "quick"


@cli.group("campaign")
def campaign_group() -> None:
    """Many runs from one TOML spec: process pool or Dask, resumable Parquet results, reports."""


def _quick_spec_path() -> Path:
    from importlib.resources import files

    return Path(str(files("swarm.campaign") / "examples" / "quick.toml"))


@campaign_group.command("run")
@click.argument("spec_path", metavar="SPEC.toml", required=False,
                type=click.Path(exists=True, dir_okay=False, path_type=Path))
@click.option("-o", "--output", type=click.Path(file_okay=False, path_type=Path), default=None,
              help=f"Results folder (created; re-running resumes). [default with no SPEC: {QUICK_OUTPUT}]")
@click.option("--workers", type=click.IntRange(1, 1024), default=None,
              help="Worker processes (default: one per core).")
@click.option("--dask", default=None, metavar="local|tcp://HOST:PORT",
              help="Run on Dask: 'local' starts a LocalCluster of --workers processes; an address joins a cluster "
                   f"(given up after {DASK_CONNECT_TIMEOUT_S} s without an answer).")
@click.option("--inline", is_flag=True, help="Run in this process, one after another (debugging).")
@click.option("--shard", default=None, metavar="i/N|slurm",
              help="Run only every N-th run starting at i (0 <= i < N), or 'slurm': this task's share of a SLURM "
                   "job array, whatever its first index (--array=1-8 and --array=0-7 both work).")
@click.option("--retry-failed", is_flag=True, help="Run again the runs that failed before.")
@click.option("--report/--no-report", "make_report", default=None,
              help="Build the report when done, unless it is up to date [default: only for the built-in quick "
                   "campaign].")
@click.option("--part-size", type=click.IntRange(1, 100_000), default=20, show_default=True,
              help="Runs per committed Parquet part (a crash loses at most the runs of one part in progress).")
@click.option("--max-runs", type=click.IntRange(1), default=MAX_RUNS, show_default=True,
              help="Refuse a campaign of more runs than this (counted from the grid before anything is built).")
@click.option("--warmup/--no-warmup", default=True, show_default=True,
              help="Compile numba's kernels here, in the campaign's first runs, before the workers start "
                   "(skipped when the cache is known to be warm, and for a remote Dask cluster).")
@click.option("--quiet", is_flag=True, help="No progress output.")
def run_cmd(spec_path: Path | None, output: Path | None, workers: int | None, dask: str | None, inline: bool,
            shard: str | None, retry_failed: bool, make_report: bool | None, part_size: int, max_runs: int,
            warmup: bool, quiet: bool) -> None:
    """Run every run of SPEC.toml that OUTPUT does not hold yet.

    With no SPEC: the built-in quick campaign (48 short runs) into ./swarm-results/quick, then its report.
    Several processes may write into one OUTPUT at once when their --shard selections do not overlap; a
    process whose runs another live one is writing is refused (exit status 2). Progress goes to stderr: a
    bar on a terminal, a line every 30 s otherwise.
    """
    import time

    from swarm.campaign import load_campaign, run_campaign
    from swarm.campaign.executors import check_dask_address
    from swarm.campaign.runner import parse_shard

    t_command = time.monotonic()
    quick = spec_path is None
    if quick:
        spec_path = _quick_spec_path()
        output = output or QUICK_OUTPUT
        make_report = True if make_report is None else make_report
    if output is None:
        raise InvalidInput("-o", None, "a results folder for this campaign")
    if inline and (dask or workers):
        raise InvalidInput("--inline", True, "not together with --workers or --dask")
    shard_t = parse_shard(shard)
    if dask is not None:
        check_dask_address(dask)
    spec = load_campaign(spec_path, max_runs=max_runs)
    n_runs = spec.run_count()
    in_shard = f" ({len(spec.indices(shard_t))} in shard {shard_t[0]}/{shard_t[1]})" if shard_t else ""
    say = (lambda text: click.echo(text, err=True)) if quiet else _note
    say(f"campaign {spec.name}: {n_runs} runs{in_shard} -> {output}")
    remote = dask is not None and dask != "local"
    outcome = run_campaign(spec, output, executor=lambda: _start_executor(workers, dask, inline, quiet),
                           shard=shard_t, retry_failed=retry_failed, progress=not quiet, flush_runs=part_size,
                           log=None if quiet else say, warmup=warmup and not remote)
    timing = outcome.timing()
    click.echo(f"{outcome.ran} ran ({outcome.failed} failed), {outcome.skipped} already done, "
               f"in {time.monotonic() - t_command:.0f} s" + (f" ({timing})" if timing else ""))
    if make_report:
        report_dir = output / "report"
        readme, built = _report(output, report_dir, quiet=quiet)
        click.echo(f"report: {readme}" + ("" if built else " (up to date: no new runs)"))


def _note(text: str) -> None:
    """An information line on stdout (above a live bar on a terminal, without breaking it)."""
    import sys

    from swarm.util.progress import note

    note(text, sys.stdout)


def _start_executor(workers: int | None, dask: str | None, inline: bool, quiet: bool) -> Any:
    """The executor, a Dask cluster's start-up shown with its clock (on a terminal) and its time said."""
    import time

    from swarm.campaign import make_executor
    from swarm.util.progress import Bar

    if dask is None:
        return make_executor(workers=workers, dask=dask, inline=inline)
    what = "starting a local Dask cluster" if dask == "local" else f"connecting to the Dask scheduler {dask}"
    t0 = time.monotonic()
    if quiet:
        return make_executor(workers=workers, dask=dask, inline=inline)
    with Bar(None, what, unit="", plain=False, live=True):
        executor = make_executor(workers=workers, dask=dask, inline=inline)
    _note(f"Dask ready in {time.monotonic() - t0:.1f} s: {executor.describe()}")
    return executor


def _report(folder: Path, report_dir: Path, quiet: bool = False, force: bool = False,
            **options: Any) -> tuple[Path, bool]:
    """The report of ``folder`` in ``report_dir``, built unless up to date, with its progress on stderr; a
    file-system error (an unwritable -o, a full disk) is one line."""
    from swarm.campaign.report.fingerprint import update_report

    progress = None if quiet else _ReportBar()
    try:
        return update_report(folder, report_dir, force=force, progress=progress, **options)
    except OSError as exc:
        where = exc.filename or report_dir
        raise InvalidInput("-o", str(report_dir), f"a writable report folder ({exc.strerror or exc}: "
                                                  f"{Path(str(where)).name[:60]})") from None
    finally:
        if progress is not None:
            progress.close()


class _ReportBar:
    """The report's stages and files written, as a live counter on a terminal (a line every 30 s otherwise)."""

    def __init__(self) -> None:
        self.bar: Any = None

    def stage(self, name: str) -> None:
        from swarm.util.progress import Bar

        if self.bar is None:
            self.bar = Bar(None, f"report: {name}", unit="file", live=True)
        else:
            self.bar.describe(f"report: {name}")

    def wrote(self, relative: str) -> None:
        if self.bar is not None:
            self.bar.update(1)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


@campaign_group.command("estimate")
@click.argument("spec_path", metavar="SPEC.toml", type=click.Path(exists=True, dir_okay=False, path_type=Path))
@click.option("--per-cell", type=click.IntRange(1, 1000), default=2, show_default=True,
              help="Sample runs per stratum (the campaign's first replicates of its cells).")
@click.option("--workers", type=click.IntRange(1, 100_000), default=None,
              help="Workers to predict for (default: one per core); the sample runs on min(this, cores).")
@click.option("--by", default=None, metavar="DIM,DIM,...",
              help="Dimensions whose combinations form the strata [default: map,size,robots,algorithm,transport "
                   "where the grid has them].")
@click.option("-o", "--output", type=click.Path(file_okay=False, path_type=Path), default=None,
              help="Write the sample runs into this results folder (the campaign's own -o: it then resumes from "
                   "them). Default: a temporary folder, deleted.")
@click.option("--shard", default=None, metavar="i/N|slurm", help="Predict for one shard of the campaign.")
@click.option("--json", "json_out", type=click.Path(dir_okay=False, path_type=Path), default=None,
              help="Also write the estimate as JSON.")
@click.option("--max-runs", type=click.IntRange(1), default=MAX_RUNS, show_default=True,
              help="Refuse a campaign of more runs than this.")
@click.option("--quiet", is_flag=True, help="No progress output.")
def estimate_cmd(spec_path: Path, per_cell: int, workers: int | None, by: str | None, output: Path | None,
                 shard: str | None, json_out: Path | None, max_runs: int, quiet: bool) -> None:
    """Predict the wall time of SPEC.toml from a stratified sample of its runs.

    Runs PER-CELL runs of every stratum (cells grouped by --by), the campaign's own first replicates, and
    prints the predicted wall time on --workers workers with a 95 % bootstrap interval, the cost by
    dimension and the slowest strata. See swarm/campaign/estimate.py for the model.
    """
    import json

    from swarm.campaign import load_campaign
    from swarm.campaign.estimate import estimate, report_lines
    from swarm.campaign.runner import parse_shard
    from .checks import check_output_path, writing

    shard_t = parse_shard(shard)
    dims = None if by is None else [d.strip() for d in by.split(",") if d.strip()]
    if json_out is not None:
        check_output_path("--json", json_out)
    spec = load_campaign(spec_path, max_runs=max_runs)
    say = (lambda text: None) if quiet else _note
    est = estimate(spec, per_cell=per_cell, workers=workers, by=dims, output=output, shard=shard_t,
                   progress=not quiet, log=say)
    for line in report_lines(est):
        click.echo(line)
    if json_out is not None:
        from maps.io import atomic_write_bytes

        with writing("--json", json_out):
            atomic_write_bytes(json_out, json.dumps(est.to_dict(), indent=1).encode())
        click.echo(f"wrote {json_out}")


@campaign_group.command("status")
@click.argument("folder", metavar="DIR", type=click.Path(exists=True, file_okay=False, path_type=Path))
def status_cmd(folder: Path) -> None:
    """Done, failed and pending runs of a results folder, and the processes writing it now."""
    from swarm.campaign import status

    s = status(folder)
    click.echo(f"{s['campaign']}: {s['done']} done, {s['failed']} failed, {s['pending']} pending "
               f"of {s['total']} runs ({s['parts']} parts)")
    for error, count in sorted(s["errors"].items(), key=lambda kv: -kv[1])[:10]:
        click.echo(f"  {count} x {error[:200]}")
    for part in s.get("damaged", [])[:10]:
        click.echo(f"  damaged part, its runs count as pending: {part}")
    if s.get("damaged"):
        click.echo(f"  {len(s['damaged'])} damaged part(s): report and load refuse the folder; 'swarm campaign run' "
                   "moves them to quarantine/ and runs their runs again")
    for writer in s["writers"] or ():
        click.echo(f"  writing now: {writer.describe()}")


@campaign_group.command("compact")
@click.argument("folder", metavar="DIR", type=click.Path(exists=True, file_okay=False, path_type=Path))
@click.option("--all", "everything", is_flag=True,
              help="Also merge the parts of earlier compactions (by default they are left as they are).")
def compact_cmd(folder: Path, everything: bool) -> None:
    """Rewrite a results folder's parts as one part, to keep or publish it.

    Every run's latest row, time series and per-robot rows, copied unedited into one zstd-compressed part;
    the old parts are removed once it is committed (safe under kill -9; refused while a campaign writes the
    folder or when a part is damaged). Parts of earlier compactions are left alone unless --all, so a folder
    kept in version control grows by one file per compaction. A resumed campaign and a report read the
    folder as before.
    """
    from swarm.campaign.compact import compact

    done = compact(folder, everything=everything)
    kept = f" ({done.kept} part(s) of earlier compactions left as they are)" if done.kept else ""
    if done.part is None:
        click.echo(f"{folder}: {done.runs} runs; nothing to compact{kept}")
        return
    click.echo(f"{folder}: {done.runs} runs from {done.parts_before} parts into part {done.part}; "
               f"{done.bytes_before / 1e6:.1f} MB -> {done.bytes_after / 1e6:.1f} MB{kept}")


@campaign_group.command("report")
@click.argument("folder", metavar="DIR", type=click.Path(path_type=Path))
@click.option("-o", "--output", type=click.Path(path_type=Path), default=None,
              help="Report folder (created; files of an earlier report there are replaced). [default: DIR/report]")
@click.option("--target", type=float, default=0.98, show_default=True,
              help="Explored fraction that counts as done: time to target, DNF, success rate.")
@click.option("--maes-csv", "maes_csv", is_flag=True,
              help="Also write one MAES statistics CSV per run (MAES's header and file naming) into maes-csv/.")
@click.option("--format", "fmt", type=click.Choice(["png", "svg", "pdf"]), default="png", show_default=True,
              help="Figure file format (a PDF copy of every figure is written too).")
@click.option("--figure-width", "figure_width", type=click.Choice(["page", "column"]), default="page",
              show_default=True, help="Figure width: a journal page (7.16 in, two columns) or one column (3.5 in).")
@click.option("--figures", "figures_file", type=click.Path(path_type=Path), default=None,
              help="A figure layout TOML: multi-panel figures drawn first (e.g. examples/minotaur-paper-figures.toml).")
@click.option("--cell-figures/--no-cell-figures", "cell_figures", default=True, show_default=True,
              help="Per-cell curves, cactus and paired figures (a big campaign has over a thousand).")
@click.option("--force", is_flag=True,
              help="Rebuild even if the report is up to date (same results, options and swarm version).")
@click.option("--quiet", is_flag=True, help="No progress output.")
def report_cmd(folder: Path, output: Path | None, target: float, maes_csv: bool, fmt: str, figure_width: str,
               figures_file: Path | None, cell_figures: bool, force: bool, quiet: bool) -> None:
    """Curves, cactus/ECDF plots, paired comparisons and tables of the results in DIR.

    A report that is up to date (built from the same results with the same options by the same swarm) is
    left as it is; --force rebuilds it."""
    from swarm.campaign.report.build import check_target

    check_target(target)
    readme, built = _report(folder, output or folder / "report", quiet=quiet, force=force, target=target,
                            maes_csv=maes_csv, fmt=fmt, figure_width=figure_width, figures_file=figures_file,
                            cell_figures=cell_figures)
    click.echo(f"report: {readme}" + ("" if built else " (up to date; --force rebuilds it)"))
