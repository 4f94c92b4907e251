"""Checks the commands run on their flags before any work starts: finite numbers, writable output paths.

A flag that cannot be honoured must fail before a run is computed, not after (a result that cannot be
written is a run wasted), and with the one-line error of :class:`~swarm.base.errors.InvalidInput`.
"""

from __future__ import annotations

import math
import os
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import click

from swarm.base.errors import InvalidInput


class FiniteSeconds(click.ParamType):
    """A duration in seconds: a finite number in (0, ``most``]; ``nan``, ``inf`` and ``1e300`` are refused
    (a timeout that never ends, or one too large for the OS's waits)."""

    name = "seconds"

    def __init__(self, most: float = 86_400.0) -> None:
        self.most = most

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None) -> float:
        if isinstance(value, float) and math.isfinite(value) and 0 < value <= self.most:
            return value
        try:
            seconds = float(value)
        except (TypeError, ValueError):
            seconds = math.nan
        if not (math.isfinite(seconds) and 0 < seconds <= self.most):
            self.fail(f"got {str(value)[:40]!r}; allowed: a finite number of seconds > 0 and <= {self.most:g}",
                      param, ctx)
        return seconds


def check_output_path(flag: str, path: Path) -> Path:
    """``path`` can be written: its folder exists and takes a new file, and it is not a folder or a file
    that cannot be written (``/proc/version``). Probed by opening: permission bits do not bind root."""
    folder = path.parent if str(path.parent) else Path(".")
    if path.is_dir():
        raise InvalidInput(flag, str(path), "a file path, not a folder")
    if not folder.is_dir():
        raise InvalidInput(flag, str(path), "a path in an existing folder")
    try:
        if path.exists():
            if not path.is_file():
                raise InvalidInput(flag, str(path), "a regular file or a new file")
            with open(path, "ab"):  # appends nothing: the file is unchanged
                pass
        fd, probe = tempfile.mkstemp(prefix=".swarm-probe-", dir=folder)
        os.close(fd)
        os.unlink(probe)
    except OSError as exc:
        raise InvalidInput(flag, str(path), f"a path this user can write ({exc.strerror or type(exc).__name__})") from None
    return path


@contextmanager
def writing(flag: str, path: Path) -> Iterator[None]:
    """Write the output of ``flag`` at ``path`` inside this block: an OSError (a full disk, a quota, a vanished
    folder) becomes a one-line :class:`InvalidInput` naming the flag (exit 2, not a traceback), and the checks of
    :func:`maps.io.atomic_write_bytes` (field ``output``) name the flag. Atomic writers leave no partial file."""
    try:
        yield
    except OSError as exc:
        raise InvalidInput(flag, str(path), f"a path that can be written ({exc.strerror or type(exc).__name__})") from None
    except InvalidInput as exc:
        if exc.field != "output":
            raise
        raise InvalidInput(flag, exc.value, exc.allowed) from None
