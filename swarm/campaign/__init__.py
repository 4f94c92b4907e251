"""Campaigns: one TOML spec -> many runs, executed inline, on a process pool or on Dask, into a
resumable folder of Parquet parts; see :mod:`swarm.campaign.spec` for the spec format. From Python:
``run(spec, out, workers=..., dask=...)``, ``load(dir)`` (runs, a DataFrame), ``load_timeseries(dir)``
(:mod:`.api`).

Names are imported on first use, so ``swarm --help`` (which reads :mod:`.limits`) loads no pyarrow. May import:
``swarm.sim`` and every package below it."""

from __future__ import annotations

from importlib import import_module
from typing import Any

_WHERE = {"CampaignSpec": "spec", "load_campaign": "spec", "parse_campaign": "spec", "make_executor": "executors",
          "deterministic_rows": "runner", "run_campaign": "runner", "status": "runner", "ResultsStore": "store",
          "run": "api", "load": "api", "load_timeseries": "api", "CampaignResults": "api"}

__all__ = ["CampaignResults", "CampaignSpec", "ResultsStore", "deterministic_rows", "load", "load_campaign",
           "load_timeseries", "make_executor", "parse_campaign", "run", "run_campaign", "status"]


def __getattr__(name: str) -> Any:
    if name in _WHERE:
        value = getattr(import_module(f".{_WHERE[name]}", __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
