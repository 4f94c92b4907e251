"""Campaigns: one TOML spec -> many runs, executed inline, on a process pool or on Dask, into a
resumable folder of Parquet parts; see :mod:`swarm.campaign.spec` for the spec format.

Names are imported on first use, so ``swarm --help`` (which reads :mod:`.limits`) loads no pyarrow."""

from __future__ import annotations

from importlib import import_module
from typing import Any

_WHERE = {"CampaignSpec": "spec", "load_campaign": "spec", "parse_campaign": "spec", "make_executor": "executors",
          "deterministic_rows": "runner", "run_campaign": "runner", "status": "runner", "ResultsStore": "store"}

__all__ = ["CampaignSpec", "ResultsStore", "deterministic_rows", "load_campaign", "make_executor", "parse_campaign",
           "run_campaign", "status"]


def __getattr__(name: str) -> Any:
    if name in _WHERE:
        value = getattr(import_module(f".{_WHERE[name]}", __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
