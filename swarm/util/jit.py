"""Watching numba's just-in-time compiler: how many functions it compiled, and how long that took.

numba compiles a kernel on its first call with new argument types, or loads it from its on-disk cache
(``cache=True``). Both happen under numba's global compiler lock, and the first run after an install spends
about a minute there. :class:`JitWatch` listens to numba's own events while a block runs:

- ``seconds``: time spent holding the compiler lock (compiling, or loading compiled code from the cache);
  only the outermost acquisition counts, so a kernel compiling its callees is counted once;
- ``compiled``: functions compiled (cache loads are not compilations), and ``compile_seconds`` their time.

numba fires these events only around compilations and cache loads, so a watch costs nothing while compiled
kernels run. Used for the per-run ``jit_time_s`` column, the compile progress of the CLI and ``swarm plan``.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from contextlib import ExitStack
from typing import Any


class JitWatch:
    """Context manager: counts numba compilations and times the compiler inside the block.

    ``on_compile(watch)`` is called after each function compiled (for a progress display)."""

    def __init__(self, on_compile: Callable[["JitWatch"], None] | None = None) -> None:
        self.on_compile = on_compile
        self.seconds = 0.0
        self.compile_seconds = 0.0
        self.compiled = 0
        self.compiling = False
        """True while numba compiles (for a display refreshed from another thread)."""
        self._stack: ExitStack | None = None

    def __enter__(self) -> "JitWatch":
        from numba.core import event

        watch = self

        class _Outermost(event.Listener):
            """Times the outermost of nested start/end pairs of one event kind."""

            def __init__(self, done: Callable[[float], None], each: Callable[[], None] | None = None) -> None:
                self.depth = 0
                self.t0 = 0.0
                self.done = done
                self.each = each

            def on_start(self, ev: Any) -> None:
                if self.depth == 0:
                    self.t0 = time.perf_counter()
                    if self.each is not None:
                        watch.compiling = True
                self.depth += 1

            def on_end(self, ev: Any) -> None:
                self.depth -= 1
                if self.each is not None:
                    self.each()
                if self.depth == 0:
                    if self.each is not None:
                        watch.compiling = False
                    self.done(time.perf_counter() - self.t0)

        def lock_done(dt: float) -> None:
            watch.seconds += dt

        def compile_done(dt: float) -> None:
            watch.compile_seconds += dt

        def one_compiled() -> None:
            watch.compiled += 1
            if watch.on_compile is not None:
                watch.on_compile(watch)

        self._stack = ExitStack()
        self._stack.enter_context(event.install_listener("numba:compiler_lock", _Outermost(lock_done)))
        self._stack.enter_context(event.install_listener("numba:compile", _Outermost(compile_done, one_compiled)))
        return self

    def __exit__(self, *exc: Any) -> None:
        if self._stack is not None:
            self._stack.close()
            self._stack = None


__all__ = ["JitWatch"]
