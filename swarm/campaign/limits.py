"""Limits of the campaign command line, in a module light enough for ``swarm --help``."""

MAX_RUNS = 1_000_000
"""A campaign of more runs is refused unless the caller raises the limit (``--max-runs``): a typo in a grid
(``replicates = 100000``) should not start a month of work."""
DASK_CONNECT_TIMEOUT_S = 10
"""How long ``--dask ADDRESS`` waits for the scheduler before giving up with a one-line error."""
