"""The one error type for bad user input, shared by every layer.

It lives in ``maps`` because ``maps`` is the bottom of the dependency stack (``maps <- radio <- swarm``);
``swarm.errors`` re-exports it. The CLI turns it into a one-line message and exit status 2.
"""

from __future__ import annotations

from typing import Any

_MAX_VALUE_CHARS = 80


def _short_repr(value: Any) -> str:
    text = repr(value).replace("\n", "\\n")
    if len(text) > _MAX_VALUE_CHARS:
        text = text[: _MAX_VALUE_CHARS - 3] + "..."
    return text


class InvalidInput(ValueError):
    """A config value, file, flag or message that cannot be used.

    The message always names the field, the offending value and what is allowed, on one line, e.g.
    ``size: got 10; allowed: an integer >= 20 (tiles per side)``.
    """

    def __init__(self, field: str, value: Any, allowed: str) -> None:
        self.field = field
        self.value = value
        self.allowed = allowed
        one_line = f"{field}: got {_short_repr(value)}; allowed: {allowed}"
        super().__init__(one_line.replace("\r", "\\r").replace("\n", "\\n"))  # field names may come from the input


def require(condition: bool, field: str, value: Any, allowed: str) -> None:
    """Raise :class:`InvalidInput` unless ``condition`` holds."""
    if not condition:
        raise InvalidInput(field, value, allowed)
