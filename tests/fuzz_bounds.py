"""What every fuzz case of the Python API and the RL envs must respect (issue 48): a refusal is one short
line, no case hangs, and a whole fuzz file grows the process by less than 1 GB."""

from __future__ import annotations

import resource
import time
from collections.abc import Iterator

import pytest
from hypothesis import event

from swarm.base.errors import InvalidInput

MAX_MESSAGE = 500
"""A refusal's message is one line shorter than this."""
MAX_CASE_S = 60.0
"""No case may take longer (a hang)."""
MAX_GROWTH_KB = 1024 * 1024
"""Peak RSS may grow by less than this over a whole fuzz file (ru_maxrss is in KB on Linux)."""


def check_refusal(exc: InvalidInput) -> None:
    """``exc`` is one short line; hypothesis counts the refusals by field."""
    msg = str(exc)
    assert "\n" not in msg and "\r" not in msg and len(msg) < MAX_MESSAGE, msg
    event(f"refused: {str(exc.field).split('.')[0].split('[')[0][:20]}")


@pytest.fixture(scope="module", autouse=True)
def bounded_memory() -> Iterator[None]:
    """The whole module stays within 1 GB more than the process had (import it into a fuzz module)."""
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    yield
    grown = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before
    assert grown < MAX_GROWTH_KB, f"peak RSS grew by {grown / 1024:.0f} MB"


class timed:
    """A case must not hang: it runs in less than :data:`MAX_CASE_S`."""

    def __enter__(self) -> None:
        self.t0 = time.monotonic()

    def __exit__(self, *exc: object) -> None:
        took = time.monotonic() - self.t0
        assert took < MAX_CASE_S, f"a case took {took:.0f} s"
