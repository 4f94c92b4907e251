"""The one error type for bad user input, shared by every layer.

It lives in :mod:`swarm.base`, the floor under ``maps``, ``radio`` and every swarm package; users reach it as
``swarm.InvalidInput``, ``swarm.api.InvalidInput`` or ``maps.InvalidInput``. The CLI turns it into a
one-line message and exit status 2.

The message is always one short line, whatever the input: the value is cut to 80 characters, a field name
built from user keys to 100 and the ``allowed`` text to 300, and every character that could break the line
or confuse a terminal (newlines, ``\\v``, ``\\f``, U+2028, escape codes...) is written as an escape.
"""

from __future__ import annotations

import math
from typing import Any

MAX_VALUE_CHARS = 80
"""A user-provided value in a message is cut to this many characters (with ``...``)."""
MAX_FIELD_CHARS = 100
"""A field name (which may embed user keys, e.g. ``legend.colours.<key>``) is cut to this many characters."""
MAX_ALLOWED_CHARS = 300
"""The ``allowed`` text is cut to this many characters (a safety net: sources keep it short themselves)."""


def one_line(text: str) -> str:
    """``text`` with every non-printable character (line breaks, tabs, controls) written as an escape."""
    if text.isprintable():
        return text
    return "".join(ch if ch.isprintable() else ch.encode("unicode_escape").decode("ascii") for ch in text)


def shorten(text: Any, limit: int = MAX_VALUE_CHARS) -> str:
    """``str(text)`` on one line, cut to ``limit`` characters with ``...`` when longer."""
    if not isinstance(text, str):
        text = short_repr(text, limit) if not isinstance(text, (int, float)) else _safe_str(text)
    if len(text) > 4 * limit:  # escaping cannot shrink a text: cut first so a huge value costs little
        text = text[: 4 * limit]
    text = one_line(text)
    if len(text) > limit:
        text = text[: limit - 3] + "..."
    return text


def short_repr(value: Any, limit: int = MAX_VALUE_CHARS) -> str:
    """``repr(value)`` on one line and at most ``limit`` characters; never raises."""
    if isinstance(value, str) and len(value) > 4 * limit:
        value = value[: 4 * limit]  # repr of a cut string: same first characters, far cheaper
        text = repr(value)[:-1] + "..."
    else:
        try:
            text = repr(value)
        except Exception:  # e.g. an int of more than 4300 digits, or an object whose repr fails
            text = _safe_str(value)
    text = one_line(text)
    if len(text) > limit:
        text = text[: limit - 3] + "..."
    return text


def _safe_str(value: Any) -> str:
    if isinstance(value, int) and not isinstance(value, bool):
        digits = value.bit_length() * math.log10(2)
        if digits > 1000:  # str() refuses past 4300 digits, and a shorter huge one is no use in a message
            return f"<an integer of {int(digits) + 1} digits>"
    try:
        return str(value)
    except Exception:
        return f"<{type(value).__name__}>"


def field_name(prefix: str, key: Any) -> str:
    """``prefix.key`` for a key taken from user input; never raises (a non-string key is shown by its
    shortened repr) and :class:`InvalidInput` cuts the result to ``MAX_FIELD_CHARS``."""
    return f"{prefix}.{key if isinstance(key, str) else short_repr(key)}"


class InvalidInput(ValueError):
    """A config value, file, flag or message that cannot be used.

    The message always names the field, the offending value and what is allowed, on one line, e.g.
    ``size: got 10; allowed: an integer >= 20 (tiles per side)``. The attributes keep what was passed
    (callers re-raise with another field name); only the message is shortened.
    """

    def __init__(self, field: str, value: Any, allowed: str) -> None:
        self.field = field
        self.value = value
        self.allowed = allowed
        super().__init__(f"{shorten(field, MAX_FIELD_CHARS)}: got {short_repr(value)}; "
                         f"allowed: {shorten(allowed, MAX_ALLOWED_CHARS)}")


def require(condition: bool, field: str, value: Any, allowed: str) -> None:
    """Raise :class:`InvalidInput` unless ``condition`` holds."""
    if not condition:
        raise InvalidInput(field, value, allowed)
