"""Option types and parsers shared by the subcommands."""

from __future__ import annotations

import tomllib
from typing import Any

import click

from maps.errors import InvalidInput


def parse_value(text: str) -> Any:
    """A TOML value (``45``, ``true``, ``"x"``, ``{concrete = 1}``, ``[1, 2]``); bare words stay strings."""
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        return text


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
                raise InvalidInput(flag, pair, f"a key that does not also set {part!r} to a value")
        node[parts[-1]] = parse_value(value.strip())
    return out


class PointType(click.ParamType):
    """A point ``x,y`` in metres."""

    name = "x,y"

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None) -> tuple[float, float]:
        if isinstance(value, tuple):
            return value
        try:
            x, y = (float(v) for v in str(value).split(","))
        except ValueError:
            self.fail(f"{value!r} is not a point; allowed: x,y in metres, e.g. 10.5,3", param, ctx)
        if not (x == x and y == y) or abs(x) == float("inf") or abs(y) == float("inf"):
            self.fail(f"{value!r} is not a finite point; allowed: x,y in metres", param, ctx)
        return x, y


POINT = PointType()
