"""Progress display: a live tqdm bar on stderr when stderr is a terminal, plain lines now and then otherwise.

Progress never goes to stdout: a command's results, its ``--json`` output and anything piped stay exactly
what they were. On a terminal a bar redraws in place (a background thread keeps its clock moving while the
work in the foreground holds the interpreter, e.g. numba compiling); in a log (not a terminal) a
:class:`Bar` writes one plain line every ``every_s`` seconds and at the end, or nothing at all
(``plain=False``, for short steps whose end is reported anyway).

ETAs are smoothed: tqdm's exponential moving average of the recent rate on a terminal, the same average in
plain lines, so a slow first item (a compile, a pool starting) does not set the estimate for the rest.
"""

from __future__ import annotations

import os
import sys
import threading
import time
from typing import Any, TextIO

SMOOTHING = 0.1
"""Weight of the latest interval in the moving average of the rate (tqdm's ``smoothing``)."""


def is_terminal(stream: Any) -> bool:
    """``stream.isatty()``, False for anything without it (a StringIO, a closed stream)."""
    isatty = getattr(stream, "isatty", None)
    try:
        return bool(isatty()) if callable(isatty) else False
    except (ValueError, OSError):
        return False


def bar_width(stream: Any) -> dict[str, Any]:
    """tqdm's size arguments for ``stream``: follow the terminal's size, or 100 x 40 when the terminal reports
    none (a pseudo-terminal nobody sized, e.g. under ``script``: tqdm would draw nothing)."""
    try:
        columns, lines = os.get_terminal_size(stream.fileno())
    except (AttributeError, OSError, ValueError):
        columns = lines = 0
    return {"dynamic_ncols": True} if columns > 0 and lines > 0 else {"ncols": columns or 100, "nrows": lines or 40}


def clock(seconds: float) -> str:
    """``H:MM:SS`` (or ``M:SS`` under an hour); ``?`` for an unknown (NaN or infinite) duration."""
    if seconds != seconds or seconds in (float("inf"), float("-inf")):
        return "?"
    s = int(round(max(seconds, 0.0)))
    h, rest = divmod(s, 3600)
    m, s = divmod(rest, 60)
    return f"{h}:{m:02d}:{s:02d}" if h else f"{m}:{s:02d}"


class _Rate:
    """Items per second: an exponential moving average over update intervals (as tqdm's ``smoothing``),
    bias-corrected so its first values are plain means. The first update only starts the clock: what came
    before it (a pool starting its workers, a first compile) is not work at the campaign's pace."""

    def __init__(self, alpha: float = SMOOTHING) -> None:
        self.beta = 1.0 - alpha
        self.dn = self.dt = 0.0
        self.calls = 0
        self.last: float | None = None

    def add(self, n: float) -> None:
        now = time.monotonic()
        if self.last is None:
            self.last = now
            return
        dt, self.last = now - self.last, now
        self.dn = self.beta * self.dn + (1.0 - self.beta) * n
        self.dt = self.beta * self.dt + (1.0 - self.beta) * dt
        self.calls += 1

    @property
    def per_second(self) -> float:
        """NaN until two intervals are known (results of a pool's first runs often arrive together)."""
        return self.dn / self.dt if self.calls >= 2 and self.dt > 0 else float("nan")


class Bar:
    """A counter toward ``total`` (None: open-ended, shows the count and the clock).

    ``unit`` names the items ("run", "file"; "" with no total: a clock only); ``postfix`` values (e.g.
    ``failed=2``) are shown after the rate and the ETA. ``initial``: items done before this bar started (counted, but not in its rate)."""

    def __init__(self, total: int | None, desc: str, unit: str = "it", stream: TextIO | None = None,
                 every_s: float = 30.0, plain: bool = True, initial: int = 0, live: bool = False) -> None:
        self.stream = sys.stderr if stream is None else stream
        self.total, self.desc, self.unit = total, desc, unit
        self.tty = is_terminal(self.stream)
        self.every_s, self.plain = every_s, plain
        self.n = initial
        self.t0 = time.monotonic()
        self.last_line = self.t0
        self.rate = _Rate()
        self.postfix: dict[str, Any] = {}
        self._bar: Any = None
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        if self.tty:
            from tqdm import tqdm

            fmt = ("{desc} [{elapsed}]" if total is None and not unit else
                   "{desc}: {n} " + unit + "s [{elapsed}]" if total is None else
                   "{desc}: {percentage:3.0f}%|{bar}| {n_fmt}/{total_fmt} " + unit + "s [{elapsed}{postfix}]")
            self._bar = tqdm(total=total, desc=desc, unit=" " + unit + "s", file=self.stream, initial=initial,
                             smoothing=SMOOTHING, mininterval=0.2, leave=True, bar_format=fmt,
                             **bar_width(self.stream))
            if total is not None:
                self._bar.set_postfix_str(self._status())
            if live:  # redraw every half second although the foreground may not call update for a while
                self._thread = threading.Thread(target=self._refresh, name="progress", daemon=True)
                self._thread.start()

    def _refresh(self) -> None:
        while not self._stop.wait(0.5):
            bar = self._bar
            if bar is not None:
                bar.refresh()

    def update(self, n: int = 1, **postfix: Any) -> None:
        self.n += n
        self.rate.add(n)
        if postfix:
            self.postfix.update(postfix)
        if self._bar is not None:
            if self.total is not None:
                self._bar.set_postfix_str(self._status(), refresh=False)
            self._bar.update(n)
        elif self.plain:
            now = time.monotonic()
            if now - self.last_line >= self.every_s or (self.total is not None and self.n >= self.total):
                self.last_line = now
                self._line(now)

    def describe(self, desc: str) -> None:
        """Change the text before the bar (e.g. the step running now)."""
        self.desc = desc
        if self._bar is not None:
            self._bar.set_description_str(desc)

    def eta_s(self) -> float:
        """Seconds left at the smoothed rate (NaN without a total or a rate yet)."""
        if self.total is None:
            return float("nan")
        return (self.total - self.n) / self.rate.per_second

    def _status(self) -> str:
        """``1.5 runs/min, ETA 0:35, 0 failed``: the smoothed rate, the ETA and the postfix values."""
        if self.rate.last is None:
            return "starting"
        rate = self.rate.per_second
        per_min = f"{60 * rate:.1f} {self.unit}s/min" if rate == rate else f"? {self.unit}s/min"
        return ", ".join([per_min, f"ETA {clock(self.eta_s())}", *(f"{v} {k}" for k, v in self.postfix.items())])

    def _line(self, now: float) -> None:
        extra = "".join(f", {v} {k}" for k, v in self.postfix.items())
        if self.total is None:
            count = f": {self.n} {self.unit}s" if self.unit else ""
            text = f"{self.desc}{count}{extra}, {clock(now - self.t0)} elapsed"
        else:
            text = f"{self.desc}: {self.n}/{self.total} {self.unit}s done, {self._status()}"
        self.stream.write(text + "\n")
        self.stream.flush()

    def close(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join()
            self._thread = None
        if self._bar is not None:
            self._bar.close()
            self._bar = None

    def __enter__(self) -> "Bar":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()


def note(text: str, stream: TextIO | None = None) -> None:
    """One line on stderr (above a live bar on a terminal, without breaking it)."""
    out = sys.stderr if stream is None else stream
    if is_terminal(out):
        from tqdm import tqdm

        tqdm.write(text, file=out)
    else:
        out.write(text + "\n")
        out.flush()


__all__ = ["Bar", "clock", "is_terminal", "note"]


COMPILE_NOTE = ("compiling numba kernels on first use (about a minute on one core after an install or an "
                "update; cached for later runs)")


class CompileProgress:
    """Within the block, show numba compiling: on the first compilation, one line (``note``) and then a live
    counter of functions compiled with its clock; when the block ends, the counter stays as the record.
    Nothing at all when nothing compiles (a warm cache). Not on a terminal: the note and one closing line
    ``compiled N functions in S s`` when ``plain``, else nothing.

    ``watch`` (a :class:`swarm.util.jit.JitWatch`) holds the counts and times afterwards."""

    def __init__(self, stream: TextIO | None = None, note_text: str = COMPILE_NOTE, plain: bool = False,
                 desc: str = "compiling") -> None:
        from .jit import JitWatch

        self.stream = sys.stderr if stream is None else stream
        self.note_text, self.plain, self.desc = note_text, plain, desc
        self.tty = is_terminal(self.stream)
        self.bar: Bar | None = None
        self.started: float | None = None
        self.watch = JitWatch(on_compile=self._compiled)

    def _compiled(self, watch: Any) -> None:
        if self.started is None:
            self.started = time.monotonic()
            if self.tty or self.plain:
                note(self.note_text, self.stream)
            if self.tty:
                self.bar = Bar(None, self.desc, unit="function", stream=self.stream, plain=False, live=True)
        if self.bar is not None:
            self.bar.update(1)

    def step(self, desc: str) -> None:
        """Say which step is compiling now (e.g. 'warm-up run 2/3')."""
        self.desc = desc
        if self.bar is not None:
            self.bar.describe(desc)

    def __enter__(self) -> "CompileProgress":
        self.watch.__enter__()
        return self

    def __exit__(self, *exc: Any) -> None:
        self.watch.__exit__(*exc)
        if self.bar is not None:
            self.bar.close()
        elif self.plain and self.started is not None:
            note(f"compiled {self.watch.compiled} functions in {self.watch.seconds:.0f} s", self.stream)
