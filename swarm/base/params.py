"""Frozen-dataclass parameter sets: build from a mapping, reject unknown keys, check types and ranges.

Every configurable thing in swarm (generators, radio, algorithms) declares its parameters as a frozen
dataclass and validates them in ``__post_init__`` with the checkers below, so one bad value gives one
clear line naming the field. :func:`from_mapping` also checks each given value against its field's
annotation when that is a simple one (:func:`annotation_allows`), so a parameter set without checkers of
its own still refuses ``patience = "abc"`` for ``patience: int``.
"""

from __future__ import annotations

import dataclasses
import math
import sys
import types
import typing
from collections.abc import Mapping
from functools import lru_cache
from typing import Any, TypeVar

from .errors import InvalidInput, short_repr

T = TypeVar("T")


def from_mapping(cls: type[T], data: Mapping[str, Any] | None, prefix: str = "") -> T:
    """Instantiate the dataclass ``cls`` from ``data``; unknown keys are an error naming them, and so is a
    value that does not fit its field's simple annotation (see :func:`annotation_allows`: ``int``,
    ``float``, ``bool``, ``str``, lists of those, ``Mapping``, ``X | None``). Values are passed on as
    given, never converted. The class's own ``__post_init__`` checks run first, so their (more precise)
    message wins when both refuse a value; a field they name is given the full name (``prefix`` + field,
    ``motion.max_speed``) unless they named it so already."""
    data = dict(data or {})
    names = [f.name for f in dataclasses.fields(cls) if f.init]  # type: ignore[arg-type]
    for key in data:
        if key not in names:
            shown = key if isinstance(key, str) else short_repr(key)  # str() of a 5000-digit int raises
            raise InvalidInput(f"{prefix}{shown}", data[key], f"a parameter of {cls.__name__}: {', '.join(names)}")
    try:
        obj = cls(**data)
    except InvalidInput as exc:
        if not prefix or exc.field.startswith(prefix):
            raise
        raise InvalidInput(f"{prefix}{exc.field}", exc.value, exc.allowed) from None
    except Exception:  # e.g. a TypeError comparing "abc" with 1 in __post_init__: say which value is wrong
        problem = type_problem(cls, data, prefix)
        if problem is not None:
            raise problem from None
        raise
    problem = type_problem(cls, data, prefix)
    if problem is not None:
        raise problem
    return obj


def type_problem(cls: type, data: Mapping[str, Any], prefix: str = "") -> InvalidInput | None:
    """The error for the first value in ``data`` that its field's annotation in dataclass ``cls`` does not
    allow (``InvalidInput(prefix + field, value, "an integer")``), or None when every one fits."""
    hints = field_annotations(cls)
    for key, value in data.items():
        annotation = hints.get(key, Any)
        if annotation_allows(annotation, value) is False:
            return InvalidInput(f"{prefix}{key}", value, describe_annotation(annotation) or "another type")
    return None


@lru_cache(maxsize=None)
def field_annotations(cls: type) -> dict[str, Any]:
    """Each field's annotation, resolved (``from __future__ import annotations`` makes them strings, which
    :func:`typing.get_type_hints` evaluates); a field whose annotation does not resolve maps to ``Any``."""
    try:
        hints = typing.get_type_hints(cls)
    except Exception:  # one unresolvable name (e.g. imported under TYPE_CHECKING): resolve field by field
        hints = {}
        module = vars(sys.modules[cls.__module__]) if cls.__module__ in sys.modules else {}
        for f in dataclasses.fields(cls):
            if not isinstance(f.type, str):
                hints[f.name] = f.type
                continue
            try:
                hints[f.name] = eval(f.type, dict(module))  # what get_type_hints does, one field at a time
            except Exception:
                hints[f.name] = Any
    return {f.name: hints.get(f.name, Any) for f in dataclasses.fields(cls)}


_NONE = type(None)


def _unwrap(tp: Any) -> Any:
    while True:
        if typing.get_origin(tp) is typing.Annotated:
            tp = typing.get_args(tp)[0]
        elif hasattr(tp, "__supertype__"):  # typing.NewType
            tp = tp.__supertype__
        else:
            return tp


def _members(tp: Any) -> tuple[Any, ...] | None:
    """The members of a union annotation (``X | Y``, ``Optional[X]``), None for anything else."""
    origin = typing.get_origin(tp)
    if origin is typing.Union or isinstance(tp, types.UnionType):
        return typing.get_args(tp)
    return None


def annotation_allows(annotation: Any, value: Any) -> bool | None:
    """Whether ``value`` fits a simple annotation: True or False, or None when the annotation is not one
    this checks (anything but ``int`` (bools refused), ``float`` (ints too, bools refused), ``bool``,
    ``str``, ``tuple[...]``/``list[...]``/``tuple``/``list`` of those (a list or a tuple), ``Mapping``/``dict``
    (any mapping; keys and values unchecked) and unions of those, ``None`` included)."""
    tp = _unwrap(annotation)
    members = _members(tp)
    if members is not None:
        verdicts = [annotation_allows(m, value) for m in members]
        if True in verdicts:
            return True
        return None if None in verdicts else False
    if tp is _NONE or tp is None:
        return value is None
    if tp is bool:
        return isinstance(value, bool)
    if tp is int:
        return isinstance(value, int) and not isinstance(value, bool)
    if tp is float:
        return isinstance(value, (int, float)) and not isinstance(value, bool)
    if tp is str:
        return isinstance(value, str)
    origin = typing.get_origin(tp) or tp
    if origin in (tuple, list):
        if not isinstance(value, (tuple, list)):
            return False
        args = typing.get_args(tp)
        if not args:
            return True
        if origin is tuple and not (len(args) == 2 and args[1] is Ellipsis):
            if args == ((),):  # tuple[()]
                return len(value) == 0
            if len(value) != len(args):
                return False
            verdicts = [annotation_allows(a, v) for a, v in zip(args, value)]
        else:
            verdicts = [annotation_allows(args[0], v) for v in value]
        return False if False in verdicts else True
    if origin in (dict, Mapping):  # typing.Mapping[...] and dict[...] have these origins
        return isinstance(value, Mapping)
    return None


def describe_annotation(annotation: Any) -> str | None:
    """What a simple annotation allows, in words (``"an integer"``, ``"a list of numbers"``); None for an
    annotation :func:`annotation_allows` does not check."""
    words = _describe(_unwrap(annotation))
    return None if words is None else words[0]


def _describe(tp: Any) -> tuple[str, str] | None:
    """(singular, plural) description, or None if unchecked."""
    members = _members(tp)
    if members is not None:
        parts = [_describe(_unwrap(m)) for m in members]
        if any(p is None for p in parts):
            return None
        return " or ".join(p[0] for p in parts), " or ".join(p[1] for p in parts)  # type: ignore[index]
    simple = {_NONE: ("none", "nones"), bool: ("true or false", "true or false values"),
              int: ("an integer", "integers"), float: ("a number", "numbers"), str: ("a string", "strings")}
    if tp is None:
        return simple[_NONE]
    if isinstance(tp, type) and tp in simple:
        return simple[tp]
    origin = typing.get_origin(tp) or tp
    if origin in (tuple, list):
        args = typing.get_args(tp)
        if not args:
            return "a list", "lists"
        if origin is tuple and not (len(args) == 2 and args[1] is Ellipsis):
            parts = [_describe(_unwrap(a)) for a in args]
            if parts[0] is not None and all(p == parts[0] for p in parts):
                return f"a list of {len(args)} {parts[0][1]}", f"lists of {len(args)} {parts[0][1]}"
            inner = ", ".join("anything" if p is None else p[0] for p in parts)
            return f"a list of {len(args)} ({inner})", f"lists of {len(args)}"
        part = _describe(_unwrap(args[0]))
        return (f"a list of {part[1]}", f"lists of {part[1]}") if part else ("a list", "lists")
    if origin in (dict, Mapping):
        return "a table", "tables"
    return None


OMIT_DEFAULT = "omit_default"
"""Field metadata key: ``field(default=..., metadata={OMIT_DEFAULT: True})`` leaves the field out of
:func:`to_mapping` while it holds its default. A setting added to an existing section carries it, so every
spec written before it existed keeps its canonical form and its run key (campaign folders resume)."""


def to_mapping(obj: Any, omit_defaults: bool = True) -> dict[str, Any]:
    """JSON-able dict of a parameter dataclass (tuples become lists, nested mappings become dicts); fields
    marked :data:`OMIT_DEFAULT` are left out while they hold their default, unless ``omit_defaults`` is
    False (every setting shown, as ``swarm run --print-spec`` shows them)."""
    out = {}
    for f in dataclasses.fields(obj):
        value = getattr(obj, f.name)
        if (omit_defaults and f.metadata.get(OMIT_DEFAULT) and f.default is not dataclasses.MISSING
                and value == f.default):
            continue
        out[f.name] = _plain(value)
    return out


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
    """``value`` if it is one of the strings ``choices``; anything else (an array, a list, a number) is a
    one-line InvalidInput, never the error its own comparison would raise."""
    if not isinstance(value, str) or value not in choices:
        raise InvalidInput(name, value, " | ".join(repr(c) for c in choices))
    return value


def check_bool(name: str, value: Any) -> bool:
    """``value`` if it is a bool (not 0/1, not a string); else :class:`InvalidInput` naming ``name``."""
    if not isinstance(value, bool):
        raise InvalidInput(name, value, "true or false")
    return value


def _range_text(lo: int | None, hi: int | None) -> str:
    if lo is not None and hi is not None:
        return f" in {lo}..{hi}"
    if lo is not None:
        return f" >= {lo}"
    if hi is not None:
        return f" <= {hi}"
    return ""
