"""On a terminal, say when numba starts compiling swarm's kernels and show it compiling.

numba compiles each kernel on its first call and caches it on disk, so the first command after an install
(or after a kernel is edited) spends about a minute compiling before it starts its real work. On a
terminal this prints one line when the first compilation starts and then a live counter of functions
compiled with its clock (:class:`swarm.util.progress.CompileProgress`); output that is not a terminal (pipes,
logs, tests) gets nothing, so it stays exactly the command's results.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from typing import TextIO

from swarm.util.progress import COMPILE_NOTE, CompileProgress

NOTE = COMPILE_NOTE


@contextmanager
def compile_notice(stream: TextIO | None = None) -> Iterator[CompileProgress]:
    """Within the block, show numba's first compilation on ``stream`` (default stderr) if it is a terminal;
    nothing when it is not or nothing compiles (warm cache). Yields the progress (its ``watch`` holds the
    compile count and time afterwards)."""
    with CompileProgress(stream) as progress:
        yield progress
