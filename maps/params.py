"""Frozen-dataclass parameter sets: build from a mapping, reject unknown keys, check types and ranges.

Every configurable thing in swarm (generators, radio, algorithms) declares its parameters as a frozen
dataclass and validates them in ``__post_init__`` with the checkers below, so one bad value gives one
clear line naming the field.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from typing import Any, TypeVar

from .errors import InvalidInput, field_name, short_repr

T = TypeVar("T")


def from_mapping(cls: type[T], data: Mapping[str, Any] | None, prefix: str = "") -> T:
    """Instantiate the dataclass ``cls`` from ``data``; unknown keys are an error naming them."""
    data = dict(data or {})
    names = [f.name for f in dataclasses.fields(cls) if f.init]  # type: ignore[arg-type]
    for key in data:
        if key not in names:
            shown = key if isinstance(key, str) else short_repr(key)  # str() of a 5000-digit int raises
            raise InvalidInput(f"{prefix}{shown}", data[key], f"a parameter of {cls.__name__}: {', '.join(names)}")
    return cls(**data)


def to_mapping(obj: Any) -> dict[str, Any]:
    """JSON-able dict of a parameter dataclass (tuples become lists, nested mappings become dicts)."""
    return {f.name: _plain(getattr(obj, f.name)) for f in dataclasses.fields(obj)}


def _plain(v: Any) -> Any:
    if isinstance(v, Mapping):
        return {str(k): _plain(x) for k, x in v.items()}
    if isinstance(v, (tuple, list)):
        return [_plain(x) for x in v]
    return v


def check_int(name: str, value: Any, lo: int | None = None, hi: int | None = None) -> int:
    """An integer (bools refused) within ``[lo, hi]``."""
    ok = isinstance(value, int) and not isinstance(value, bool)
    if ok and lo is not None and value < lo:
        ok = False
    if ok and hi is not None and value > hi:
        ok = False
    if not ok:
        raise InvalidInput(name, value, f"an integer{_range_text(lo, hi)}")
    return value


def check_float(name: str, value: Any, lo: float | None = None, hi: float | None = None, *,
                lo_open: bool = False, hi_open: bool = False) -> float:
    """A finite number within the given bounds (open or closed); NaN and inf are refused."""
    ok = isinstance(value, (int, float)) and not isinstance(value, bool)
    try:
        ok = ok and math.isfinite(value)
    except OverflowError:  # an int beyond the float range (TOML integers are unbounded)
        ok = False
    if ok and lo is not None and (value < lo or (lo_open and value == lo)):
        ok = False
    if ok and hi is not None and (value > hi or (hi_open and value == hi)):
        ok = False
    if not ok:
        lo_s = "" if lo is None else (f" > {lo:g}" if lo_open else f" >= {lo:g}")
        hi_s = "" if hi is None else (f" < {hi:g}" if hi_open else f" <= {hi:g}")
        joiner = " and" if lo_s and hi_s else ""
        raise InvalidInput(name, value, f"a finite number{lo_s}{joiner}{hi_s}")
    return float(value)


def check_choice(name: str, value: Any, choices: tuple[str, ...]) -> str:
    if value not in choices:
        raise InvalidInput(name, value, " | ".join(repr(c) for c in choices))
    return value


def check_bool(name: str, value: Any) -> bool:
    if not isinstance(value, bool):
        raise InvalidInput(name, value, "true or false")
    return value


def check_weights(name: str, value: Any) -> tuple[tuple[str, float], ...]:
    """A non-empty mapping known wall material -> non-negative weight with a positive, finite sum, as sorted
    pairs (see :func:`maps.materials.check_known_material`)."""
    from .materials import check_known_material

    if not isinstance(value, Mapping) or not value:
        raise InvalidInput(name, value, "a non-empty table of material = weight")
    pairs = []
    for key, w in value.items():
        check_known_material(key, field_name(name, key))
        check_float(field_name(name, key), w, 0.0)
        pairs.append((key, float(w)))
    total = sum(w for _, w in pairs)
    if not 0 < total < math.inf:
        raise InvalidInput(name, dict(value), "weights with a positive, finite sum")
    return tuple(sorted(pairs))


def _range_text(lo: int | None, hi: int | None) -> str:
    if lo is not None and hi is not None:
        return f" in {lo}..{hi}"
    if lo is not None:
        return f" >= {lo}"
    if hi is not None:
        return f" <= {hi}"
    return ""
