"""``swarm run``'s progress on a terminal: one live line with the tick, the explored share and the speed.

Shown on stderr only when stderr is a terminal; stdout (the one-line summary) and files written with
``--json`` never see it, nor does stderr when it is piped. The line is redrawn twice a second by a
background thread, so it keeps moving while numba compiles kernels on a first run (then it says so, with
the count of functions compiled, after one line explaining the wait).
"""

from __future__ import annotations

import sys
import threading
import time
from typing import Any, TextIO

from swarm.util.jit import JitWatch
from swarm.util.progress import COMPILE_NOTE, bar_width, clock, is_terminal, note

PERMILLE = 1000


class RunProgress:
    """A tick observer (``sim.observers``) and a context manager around building and running one simulation.

    The bar shows the larger of the explored share of the stop target and the share of ``max_ticks`` used,
    the run's two ways to end."""

    def __init__(self, max_ticks: int, target: float, stream: TextIO | None = None) -> None:
        self.stream = sys.stderr if stream is None else stream
        self.enabled = is_terminal(self.stream)
        self.max_ticks, self.target = max_ticks, target
        self.tick = 0
        self.explored = 0.0
        self.t_first: float | None = None
        self.tick_first = 0
        self.noted = False
        self.watch = JitWatch(on_compile=self._compiled)
        self._bar: Any = None
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    def __call__(self, view: Any) -> None:
        """Called after every tick: keep the numbers (the drawing thread shows them)."""
        self.tick = view.tick
        self.explored = view.tracker.explored
        if self.t_first is None:
            self.t_first, self.tick_first = time.monotonic(), view.tick

    def _compiled(self, watch: JitWatch) -> None:
        if not self.noted and self.enabled:
            self.noted = True
            note(COMPILE_NOTE, self.stream)

    def status(self) -> str:
        """The text after the bar, e.g. ``tick 1200/36000, explored 44.1 % of 99 %, 380 ticks/s``."""
        parts = [f"tick {self.tick}/{self.max_ticks}", f"explored {100 * self.explored:.1f} % of "
                                                        f"{100 * self.target:g} %"]
        if self.t_first is not None and self.tick > self.tick_first:
            parts.append(f"{(self.tick - self.tick_first) / max(time.monotonic() - self.t_first, 1e-9):.0f} ticks/s")
        if self.watch.compiling or (self.t_first is None and self.watch.compiled):
            parts.append(f"compiling numba kernels ({self.watch.compiled} functions)")
        return ", ".join(parts)

    def fraction(self) -> float:
        return min(1.0, max(self.explored / self.target if self.target > 0 else 0.0, self.tick / self.max_ticks))

    def _draw(self) -> None:
        bar = self._bar
        if bar is None:
            return
        bar.n = int(PERMILLE * self.fraction())
        bar.set_postfix_str(self.status(), refresh=False)
        bar.refresh()

    def _loop(self) -> None:
        while not self._stop.wait(0.5):
            self._draw()

    def __enter__(self) -> "RunProgress":
        self.watch.__enter__()
        if self.enabled:
            from tqdm import tqdm

            self._bar = tqdm(total=PERMILLE, file=self.stream, leave=True, **bar_width(self.stream),
                             bar_format="run {percentage:3.0f}%|{bar}| [{elapsed}{postfix}]")
            self._bar.set_postfix_str(self.status(), refresh=False)
            self._thread = threading.Thread(target=self._loop, name="run-progress", daemon=True)
            self._thread.start()
        return self

    def __exit__(self, *exc: Any) -> None:
        self.watch.__exit__(*exc)
        self._stop.set()
        if self._thread is not None:
            self._thread.join()
        if self._bar is not None:
            if exc[0] is None:
                self._draw()
            self._bar.close()
            self._bar = None


__all__ = ["RunProgress", "clock"]
