"""Campaigns: one TOML spec -> many runs, executed inline, on a process pool or on Dask, into a
resumable folder of Parquet parts; see :mod:`swarm.campaign.spec` for the spec format."""

from .executors import make_executor
from .runner import deterministic_rows, run_campaign, status
from .spec import CampaignSpec, load_campaign, parse_campaign
from .store import ResultsStore

__all__ = ["CampaignSpec", "ResultsStore", "deterministic_rows", "load_campaign", "make_executor", "parse_campaign",
           "run_campaign", "status"]
