"""Campaigns from Python: ``swarm.campaign.run``, ``swarm.campaign.load``, ``swarm.campaign.load_timeseries``.

::

    import swarm
    out = swarm.campaign.run("grid.toml", "results/grid", workers=2)   # or dask="tcp://host:8786"
    runs = swarm.campaign.load("results/grid")                         # one row per run (pandas)
    series = swarm.campaign.load_timeseries("results/grid")            # one row per recorded tick

The same code paths as ``swarm campaign run`` (the spec is read and validated by
:func:`~swarm.campaign.spec.load_campaign`, executors come from :func:`~swarm.campaign.executors.make_executor`,
results go through :func:`~swarm.campaign.runner.run_campaign`), so a bad spec, folder, worker count or
Dask address is the same one-line :class:`~swarm.base.errors.InvalidInput`; docs/python-api.md is the guide.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping

import numpy as np
import pandas as pd

from swarm.base.errors import InvalidInput, shorten

from swarm.results.schema import RUNS
from .executors import DaskExecutor
from .limits import MAX_RUNS
from .spec import CampaignSpec, load_campaign, parse_campaign

LABELS = ("index", "replicate", "map", "size", "robots", "spawn", "algorithm", "radio", "comm", "transport")
"""Runs-table columns :func:`load_timeseries` joins onto every time-series row (the run's grid cell)."""


@dataclass(frozen=True)
class CampaignResults:
    """What :func:`run` did, and its results folder to read from."""

    folder: Path
    total: int
    """Runs selected (the whole campaign, or the shard)."""
    skipped: int
    """Already in the folder before this call."""
    ran: int
    failed: int
    wall_s: float

    def runs(self) -> pd.DataFrame:
        """Every run in the folder (:func:`load`)."""
        return load(self.folder)

    def timeseries(self) -> pd.DataFrame:
        """Every run's time series (:func:`load_timeseries`)."""
        return load_timeseries(self.folder)

    def report(self, output: str | Path | None = None, **options: Any) -> Path:
        """Build the campaign report (``swarm campaign report``) into ``output`` (default: ``folder/report``);
        returns its README.md."""
        from .report import build_report

        return build_report(self.folder, Path(output) if output is not None else self.folder / "report", **options)


def campaign_spec(spec: Any, max_runs: int | None = MAX_RUNS) -> CampaignSpec:
    """A campaign spec from a :class:`CampaignSpec`, a path to its TOML, TOML text or a mapping of its
    tables (written back as TOML: the results folder keeps the spec as ``campaign.toml``)."""
    if isinstance(spec, CampaignSpec):
        if not spec.source:
            raise InvalidInput("spec", spec.name, "a CampaignSpec read from TOML (load_campaign / parse_campaign)")
        return spec
    if isinstance(spec, Mapping):
        import tomli_w

        try:
            text = tomli_w.dumps(dict(spec))
        except (TypeError, ValueError) as exc:
            raise InvalidInput("spec", shorten(repr(spec), 60), f"tables of TOML values ({shorten(str(exc), 80)})") from None
        return parse_campaign(text, "<mapping>", max_runs=max_runs)
    if isinstance(spec, str) and ("\n" in spec or "=" in spec):
        return parse_campaign(spec, "<string>", max_runs=max_runs)
    if isinstance(spec, (str, os.PathLike)):
        return load_campaign(spec, max_runs=max_runs)
    raise InvalidInput("spec", spec, "a campaign TOML path, TOML text, a mapping of its tables or a CampaignSpec")


def quick_spec_path() -> Path:
    """The built-in quick campaign (``swarm campaign run`` with no SPEC)."""
    from importlib.resources import files

    return Path(str(files("swarm.campaign") / "examples" / "quick.toml"))


def run(spec: Any, out: str | os.PathLike[str], *, workers: int | None = None, dask: Any = None,
        inline: bool = False, shard: str | None = None, retry_failed: bool = False, max_runs: int = MAX_RUNS,
        flush_runs: int = 20, progress: bool = False) -> CampaignResults:
    """Run every run of ``spec`` that ``out`` does not hold yet, as ``swarm campaign run SPEC -o OUT``.

    ``spec``: a campaign TOML path, TOML text, a mapping of its tables, a :class:`CampaignSpec`, or
    ``"quick"`` for the built-in quick campaign. ``workers``: processes (default one per core); ``dask``:
    ``"local"``, a scheduler address (``tls://host:8786``, secured by Dask's ``distributed.comm.tls``
    settings) or a live ``distributed.Client`` or cluster object (e.g. dask-jobqueue's ``SLURMCluster``,
    whose own security then applies); ``inline``: in this process; ``shard``:
    ``"i/N"``; ``retry_failed``: run failed runs again; ``flush_runs``: runs per Parquet part. Re-running
    resumes, and every executor gives the same rows (but ``swarm.results.schema.NONDETERMINISTIC_COLUMNS``).
    """
    from .executors import check_dask_address, make_executor
    from .runner import parse_shard, run_campaign

    for flag, value in (("--retry-failed", retry_failed), ("--inline", inline), ("progress", progress)):
        if not isinstance(value, bool):  # a set or a string would reach the results folder's JSON
            raise InvalidInput(flag, value, "True or False")
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int) or not 1 <= workers <= 1024):
        raise InvalidInput("--workers", workers, "an integer from 1 to 1024")
    if inline and (dask is not None or workers):
        raise InvalidInput("--inline", True, "not together with --workers or --dask")
    if isinstance(flush_runs, bool) or not isinstance(flush_runs, int) or not 1 <= flush_runs <= 100_000:
        raise InvalidInput("--part-size", flush_runs, "an integer from 1 to 100000")
    if not isinstance(out, (str, os.PathLike)) or not str(out):
        raise InvalidInput("-o", out, "a results folder for this campaign (a path)")
    if shard is not None and not isinstance(shard, str):
        raise InvalidInput("--shard", shard, "a string 'i/N' with 0 <= i < N, e.g. '3/10', or 'slurm'")
    shard_t = parse_shard(shard)
    if isinstance(dask, str):
        check_dask_address(dask)
        make = lambda: make_executor(workers=workers, dask=dask, inline=inline)  # noqa: E731
    elif dask is not None:
        make = lambda: ClientExecutor(dask, workers)  # noqa: E731
    else:
        make = lambda: make_executor(workers=workers, inline=inline)  # noqa: E731
    campaign = campaign_spec(quick_spec_path() if isinstance(spec, str) and spec == "quick" else spec,
                             max_runs=max_runs)
    outcome = run_campaign(campaign, out, executor=make, shard=shard_t, retry_failed=retry_failed, progress=progress,
                           flush_runs=flush_runs)
    return CampaignResults(folder=Path(out), total=outcome.total, skipped=outcome.skipped, ran=outcome.ran,
                           failed=outcome.failed, wall_s=outcome.wall_s)


class ClientExecutor(DaskExecutor):
    """A :class:`DaskExecutor` on a Dask client or cluster the caller holds (``dask=client`` or
    ``dask=SLURMCluster(...)``): runs are submitted through it, and only a client made here is closed."""

    def __init__(self, target: Any, workers: int | None = None) -> None:  # noqa: D107 (not DaskExecutor's)
        try:
            from distributed import Client
        except ImportError:
            raise InvalidInput("dask", type(target).__name__, "an installed Dask (pip install distributed)") from None
        self.cluster = None
        self._own = not isinstance(target, Client)
        if self._own:
            if not hasattr(target, "scheduler_address"):
                raise InvalidInput("dask", type(target).__name__, "'local', a scheduler address, a distributed.Client "
                                                                 "or a Dask cluster object")
            target = Client(target, set_as_default=False)
        self.client = target
        self.name = f"dask:{self.client.scheduler.address}"
        self.window = max(2 * (workers or 0), 2 * len(self.client.scheduler_info().get("workers", {})) or 2)

    def close(self) -> None:
        if self._own:
            self.client.close()


def _store(folder: str | os.PathLike[str]) -> Any:
    """The folder's :class:`~swarm.campaign.store.ResultsStore`, once it is known to be a results folder."""
    from .store import ResultsStore

    if not isinstance(folder, (str, os.PathLike)) or not str(folder):
        raise InvalidInput("DIR", folder, "a campaign results folder (a path)")
    path = Path(folder)
    if not path.is_dir():
        raise InvalidInput("DIR", str(path), "an existing campaign results folder")
    store = ResultsStore(path)
    store.spec_source()  # no campaign.toml: not a results folder (one-line error)
    store.require_sound()  # a damaged part is named, never merged (swarm.campaign.parts)
    return store


def load(folder: str | os.PathLike[str]) -> pd.DataFrame:
    """Every committed run of a results folder, one row each (the latest row of a retried run), in the
    campaign's run order: the grid cell (``map``, ``size``, ``robots``, ``spawn``, ``algorithm``, ``radio``,
    ``comm``), seeds, ``status``, the summary metrics (``ticks``, ``explored``, ``t50`` ... ``t99`` ticks to
    each explored fraction, messages, ...) and ``spec_json``; :data:`swarm.results.schema.RUNS` lists them."""
    table = _store(folder).runs_table()
    if table is None:
        return pd.DataFrame({name: pd.Series(dtype=object) for name in (*RUNS, "part")})
    return table.to_pandas().sort_values(["index", "key"], kind="stable").reset_index(drop=True)


def _keys(keys: Any) -> list[str] | None:
    """``keys`` of :func:`load_timeseries` as a list of run keys (strings), or a one-line error."""
    allowed = "None or a list of run keys (strings), e.g. runs['key']"
    if keys is None:
        return None
    if isinstance(keys, (str, bytes, Mapping)):
        raise InvalidInput("keys", keys, allowed)
    try:
        listed = list(keys)
    except TypeError:
        raise InvalidInput("keys", keys, allowed) from None
    if not all(isinstance(key, str) for key in listed):
        raise InvalidInput("keys", keys, allowed)
    return listed


def load_timeseries(folder: str | os.PathLike[str], keys: Any = None, labels: bool = True) -> pd.DataFrame:
    """The time series of the runs of a results folder (those of ``keys`` only, if given): one row per
    recorded tick with the run's ``key``, ``tick``, ``explored``, ``coverage`` and the comm metrics
    (:data:`swarm.results.schema.TIMESERIES`; ``explored_correct`` is NaN for runs without a localisation
    model); ``labels`` joins each run's grid cell (:data:`LABELS`), so
    ``df.groupby(["algorithm", "tick"]).explored.mean()`` is a curve."""
    from swarm.results.schema import OPTIONAL_TIMESERIES

    store = _store(folder)
    table = store.timeseries_table(_keys(keys))
    frame = table.to_pandas() if table is not None else pd.DataFrame({"key": pd.Series(dtype=object),
                                                                       "tick": pd.Series(dtype="int64")})
    for col in OPTIONAL_TIMESERIES:
        if col not in frame:
            frame[col] = np.nan
    if labels:
        runs = load(folder)
        frame = frame.merge(runs[["key", *LABELS]], on="key", how="left")
        return frame.sort_values(["index", "tick"], kind="stable").reset_index(drop=True)
    return frame.sort_values(["key", "tick"], kind="stable").reset_index(drop=True)


__all__ = ["CampaignResults", "ClientExecutor", "LABELS", "campaign_spec", "load", "load_timeseries", "run"]
