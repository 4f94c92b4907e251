"""One line on a terminal when numba starts compiling swarm's kernels.

numba compiles each kernel on its first call and caches it on disk, so the first ``swarm run`` after an
install (or after a kernel is edited) spends about a minute compiling before the simulation starts, and
says nothing while it does. On a terminal this prints one line when the first compilation starts; output
that is not a terminal (pipes, logs, tests) gets nothing, so it stays exactly the run's results.
"""

from __future__ import annotations

import sys
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any, TextIO

NOTE = ("swarm: compiling numba kernels on first use (about a minute after an install; "
        "cached for later runs)")


def _is_terminal(stream: TextIO) -> bool:
    isatty = getattr(stream, "isatty", None)
    return bool(isatty()) if callable(isatty) else False


@contextmanager
def compile_notice(stream: TextIO | None = None) -> Iterator[None]:
    """Within the block, print :data:`NOTE` to ``stream`` (default stderr) when numba starts its first
    compilation, once; nothing when ``stream`` is not a terminal or nothing is compiled (warm cache)."""
    out = sys.stderr if stream is None else stream
    if not _is_terminal(out):
        yield
        return
    from numba.core import event

    class _FirstCompile(event.Listener):  # numba's listener base: on_start / on_end per event
        said = False

        def on_start(self, ev: Any) -> None:
            if not self.said:
                self.said = True
                out.write(NOTE + "\n")
                out.flush()

        def on_end(self, ev: Any) -> None:
            pass

    with event.install_listener("numba:compile", _FirstCompile()):
        yield
