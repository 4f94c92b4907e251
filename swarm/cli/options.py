"""Option types and parsers shared by the subcommands.

Every message they produce is one short line: click's own messages quote the value in full, so the
types below (drop-in subclasses of click's) cut a long value to 80 characters in the message.
"""

from __future__ import annotations

import re
import tomllib
from typing import Any

import click

from swarm.base.errors import MAX_VALUE_CHARS, InvalidInput, short_repr, shorten

MAX_MESSAGE_WORD = MAX_VALUE_CHARS
_LONG_WORD = re.compile(r"\S{%d,}" % (MAX_MESSAGE_WORD + 1))


def parse_value(text: str, flag: str = "--param", pair: str | None = None) -> Any:
    """A TOML value (``45``, ``true``, ``"x"``, ``{concrete = 1}``, ``[1, 2]``); bare words stay strings.

    Text that is not one TOML value (``a b``, ``1\\nx = 2``) stays a string too. What TOML refuses beyond
    syntax (an integer of more than 4300 digits, brackets nested thousands deep) is an error naming
    ``flag`` and ``pair``.
    """
    try:
        parsed = tomllib.loads(f"v = {text}")
    except tomllib.TOMLDecodeError:
        return text
    except RecursionError:
        raise InvalidInput(flag, text if pair is None else pair, "a TOML value nested less deeply") from None
    except ValueError:  # int() past 4300 digits
        raise InvalidInput(flag, text if pair is None else pair,
                           "a TOML value (integers of at most 4300 digits)") from None
    if set(parsed) != {"v"}:
        return text
    return parsed["v"]


def parse_params(pairs: tuple[str, ...], flag: str = "--param") -> dict[str, Any]:
    """``("a=1", "b.c=x")`` -> ``{"a": 1, "b": {"c": "x"}}``; dotted keys nest."""
    out: dict[str, Any] = {}
    for pair in pairs:
        key, sep, value = pair.partition("=")
        key = key.strip()
        if not sep or not key:
            raise InvalidInput(flag, pair, "KEY=VALUE, VALUE in TOML syntax (e.g. fill_percent=45)")
        node = out
        parts = key.split(".")
        for part in parts[:-1]:
            node = node.setdefault(part, {})
            if not isinstance(node, dict):
                raise InvalidInput(flag, pair, f"a key that does not also set {short_repr(part)} to a value")
        node[parts[-1]] = parse_value(value.strip(), flag, pair)
    return out


def short_message(message: str, value: Any = None) -> str:
    """``message`` with ``value`` (and any other run of more than 80 non-blank characters) cut to 80."""
    if isinstance(value, str) and len(value) > MAX_MESSAGE_WORD:
        message = message.replace(repr(value), short_repr(value)).replace(value, shorten(value))
    message = _LONG_WORD.sub(lambda m: shorten(m.group()), message)
    return shorten(message, 400)


class ShortMessages:
    """Mixin for click parameter types: a failed conversion's message quotes a long value cut to 80 chars."""

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None) -> Any:
        try:
            return super().convert(value, param, ctx)  # type: ignore[misc]
        except click.BadParameter as exc:
            exc.message = short_message(exc.message, value)
            raise


class IntRange(ShortMessages, click.IntRange):
    """:class:`click.IntRange` with short messages."""


class Choice(ShortMessages, click.Choice):
    """:class:`click.Choice` with short messages."""


class Path(ShortMessages, click.Path):
    """:class:`click.Path` with short messages; a path with a NUL character is a usage error, not a
    ``ValueError`` from ``os.stat``."""

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None) -> Any:
        if isinstance(value, str) and "\x00" in value:
            self.fail(f"{short_repr(value)} contains a NUL character; allowed: a file path", param, ctx)
        return super().convert(value, param, ctx)


class FloatType(ShortMessages, click.types.FloatParamType):
    """``float`` with short messages."""


FLOAT = FloatType()


class PointType(click.ParamType):
    """A point ``x,y`` in metres."""

    name = "x,y"

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None) -> tuple[float, float]:
        if isinstance(value, tuple):
            return value
        try:
            x, y = (float(v) for v in str(value).split(","))
        except ValueError:
            self.fail(f"{short_repr(value)} is not a point; allowed: x,y in metres, e.g. 10.5,3", param, ctx)
        if not (x == x and y == y) or abs(x) == float("inf") or abs(y) == float("inf"):
            self.fail(f"{short_repr(value)} is not a finite point; allowed: x,y in metres", param, ctx)
        return x, y


POINT = PointType()

