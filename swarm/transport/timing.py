"""Where a transport's ticks go, measured only when asked (``benchmarks/speed/bench_transport.py --split``).

A :class:`PhaseTimes` accumulates wall seconds per named phase. Code that supports it wraps a callable once,
at set-up, with :func:`timed`, which returns the callable itself when no ``PhaseTimes`` is given: runs that do
not ask pay nothing per tick. A wrapped call costs a clock read more, so measured runs are a
little slower than plain ones; the benchmark reports both.

Phases nest where calls nest: over zenoh an agent in the runtime's session answers inside the obs ``put``,
so ``zenoh: obs put`` includes ``agent: handle``; zenoh's own share is the difference (:meth:`PhaseTimes.own`).
"""

from __future__ import annotations

import time
from typing import Any, Callable, TypeVar

F = TypeVar("F", bound=Callable[..., Any])


class PhaseTimes:
    """Seconds and calls per phase name, summed over a run."""

    def __init__(self) -> None:
        self.seconds: dict[str, float] = {}
        self.calls: dict[str, int] = {}

    def wrap(self, phase: str, fn: F) -> F:
        """``fn`` with every call's wall time added to ``phase``."""
        seconds, calls, clock = self.seconds, self.calls, time.perf_counter
        seconds.setdefault(phase, 0.0)
        calls.setdefault(phase, 0)

        def timed(*args: Any, **kwargs: Any) -> Any:
            t0 = clock()
            try:
                return fn(*args, **kwargs)
            finally:
                seconds[phase] += clock() - t0
                calls[phase] += 1

        return timed  # type: ignore[return-value]

    def add(self, phase: str, seconds: float) -> None:
        """Add a span measured by the caller (for waits that are not one call)."""
        self.seconds[phase] = self.seconds.get(phase, 0.0) + seconds
        self.calls[phase] = self.calls.get(phase, 0) + 1

    def get(self, phase: str) -> float:
        return self.seconds.get(phase, 0.0)

    def own(self, phase: str, *inner: str) -> float:
        """``phase``'s seconds minus those of the phases nested in it."""
        return self.get(phase) - sum(self.get(p) for p in inner)


def timed(times: PhaseTimes | None, phase: str, fn: F) -> F:
    """``fn`` timed into ``times``, or ``fn`` itself when ``times`` is None (the normal, unmeasured run)."""
    return fn if times is None else times.wrap(phase, fn)
