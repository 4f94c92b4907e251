"""Short, one-line renderings of user input for error messages (a 20,000-character label or key must not
become a 20,000-character message)."""

from __future__ import annotations

from typing import Any

LIMIT = 60


def clip(text: str, limit: int = LIMIT) -> str:
    """``text`` on one line (non-printable characters escaped), cut to ``limit`` characters with ``...``."""
    text = text[: 4 * limit]
    if not text.isprintable():
        text = "".join(c if c.isprintable() else c.encode("unicode_escape").decode("ascii") for c in text)
    return text if len(text) <= limit else text[: limit - 3] + "..."


def clip_repr(value: Any, limit: int = LIMIT) -> str:
    """``repr(value)`` through :func:`clip`; never raises (huge ints, odd objects)."""
    if isinstance(value, str):
        return clip(repr(value[: 4 * limit]), limit)
    try:
        return clip(repr(value), limit)
    except Exception:  # e.g. an int of more than 4300 digits
        return f"<{type(value).__name__}>"


def clip_list(items: Any, limit: int = 200) -> str:
    """``a, b, c`` of ``items`` (each clipped), cut to ``limit`` characters."""
    out = ", ".join(clip(str(i), 40) for i in list(items)[:50])
    return out if len(out) <= limit else out[: limit - 3] + "..."
