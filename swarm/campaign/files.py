"""Reading a small text file the user names (a campaign TOML, a figure layout), every failure one line."""

from __future__ import annotations

import stat
from pathlib import Path

from swarm.base.errors import InvalidInput

MAX_BYTES = 16 * 2**20
"""A file larger than this is refused before it is read (a spec is a few KB; /dev/zero is endless)."""


def read_user_file(path: str | Path, field_name: str, what: str, max_bytes: int = MAX_BYTES) -> str:
    """The UTF-8 text of the regular file ``path``; a missing, unreadable, special, huge or non-UTF-8 file is
    an :class:`InvalidInput` naming ``field_name``."""
    path = Path(path)
    try:
        info = path.stat()
        if not stat.S_ISREG(info.st_mode):
            raise InvalidInput(field_name, str(path), f"a {what} file (this is not a regular file)")
        if info.st_size > max_bytes:
            raise InvalidInput(field_name, str(path), f"a {what} of at most {max_bytes // 2**20} MiB "
                                                      f"(this one has {info.st_size:,} bytes)")
        data = path.read_bytes()
    except OSError as exc:
        raise InvalidInput(field_name, str(path), f"a readable {what} ({exc.strerror or exc})") from None
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise InvalidInput(field_name, str(path), f"a {what} in UTF-8 (byte {exc.start} is not UTF-8)") from None
