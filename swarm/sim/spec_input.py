"""A run spec from what a user gives: a spec file or TOML text, flags or keyword overrides, ``--set`` pairs.

Shared by ``swarm run`` (:mod:`swarm.cli.run_cmd`) and the Python API (:func:`swarm.run`), so both read
the same files, apply overrides in the same order (file, then flags, then ``--set``) and fail with the same
one-line :class:`~swarm.base.errors.InvalidInput`; the spec itself is validated by :class:`~swarm.sim.spec.RunSpec`.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any, Mapping

from swarm.base.errors import InvalidInput, shorten

from .spec import RunSpec

FLAG_FIELDS: dict[str, tuple[str, str]] = {
    "size": ("map", "size"), "map_seed": ("map", "seed"), "robots": ("robots", "count"),
    "spawn": ("robots", "spawn"), "algorithm": ("algorithm", "name"), "max_ticks": ("stop", "max_ticks"),
    "explored": ("stop", "explored"),
}
"""Flags (``swarm run --robots 8``, ``swarm.run(robots=8)``) that set one key of a spec section."""
TOP_FLAGS = ("seed", "transport")
"""Flags that set a top-level key of the spec."""
SECTIONS = ("map", "robots", "algorithm", "lidar", "motion", "navigation", "radio", "comm", "stop")
"""Spec sections an override may give as a table, merged into the spec's (``lidar={"range_m": 4}``)."""
GENERATED_KINDS = ("building", "cave")
MAP_FILE_SUFFIXES = (".npz", ".pgm", ".csv", ".yaml", ".yml")
"""Map files a run reads (:func:`maps.io.load_map` without a legend)."""


def load_spec_file(path: str | os.PathLike[str], field: str = "--spec") -> dict[str, Any]:
    """A run spec TOML file, read with a size cap; any unreadable or invalid file is an InvalidInput naming
    ``field``."""
    from maps.io import parse_toml, read_file_bytes

    data = read_file_bytes(path, field)
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        raise InvalidInput(field, str(path), "a UTF-8 TOML file") from None
    return parse_toml(text, field, str(path))


def merge(base: Mapping[str, Any], overrides: Mapping[str, Any]) -> dict[str, Any]:
    """``base`` with ``overrides`` applied: tables merge key by key, anything else replaces."""
    out = dict(base)
    for k, v in overrides.items():
        if isinstance(v, Mapping) and isinstance(out.get(k), Mapping):
            out[k] = merge(out[k], v)
        else:
            out[k] = v
    return out


def map_override(value: str, field: str = "map") -> dict[str, Any]:
    """``--map`` / ``map=``: a generated kind, or a map file (size 50 is only the file's placeholder). A
    value that is neither (a misspelt kind, ``cavee``) is refused naming the kinds, not opened as a file."""
    if value in GENERATED_KINDS:
        return {"kind": value}
    if Path(value).suffix.lower() not in MAP_FILE_SUFFIXES:
        raise InvalidInput(field, value, f"a map kind ({' | '.join(GENERATED_KINDS)}) or a map file "
                                         f"({', '.join(MAP_FILE_SUFFIXES)}): this is neither")
    return {"kind": "file", "path": str(value), "size": 50}


def flag_overrides(flags: Mapping[str, Any], prefix: str = "") -> dict[str, Any]:
    """The spec tables the flags that were given (not None) set, as ``swarm run``'s flags set them; errors
    name the flag as ``prefix + name`` (``--map`` on the command line, ``map`` in Python)."""
    over: dict[str, Any] = {}
    if flags.get("map") is not None:
        over["map"] = map_override(flags["map"], f"{prefix}map")
    for flag, (section, key) in FLAG_FIELDS.items():
        if flags.get(flag) is not None:
            over.setdefault(section, {})[key] = flags[flag]
    for flag in TOP_FLAGS:
        if flags.get(flag) is not None:
            over[flag] = flags[flag]
    return over


def check_size_flag(data: Mapping[str, Any], flags: Mapping[str, Any], prefix: str = "") -> None:
    """A size flag is refused on a map file (given by the map flag or the spec): the file sets the map's
    size, and the flag would only be stored in the spec and shown as the map's size."""
    table = data.get("map")
    if flags.get("size") is not None and isinstance(table, Mapping) and table.get("kind") == "file":
        raise InvalidInput(f"{prefix}size", flags["size"], "no size with a map file (the file sets the map's size)")


def looks_like_toml(text: str) -> bool:
    """A string argument is TOML text when it holds a newline or an ``=``; else it is a file path."""
    return "\n" in text or "=" in text


def spec_source(spec: Any, field: str = "spec") -> dict[str, Any]:
    """The base mapping of :func:`resolve`: None (every default), a :class:`RunSpec`, a mapping, TOML text
    or the path of a TOML file."""
    from maps.io import parse_toml

    if spec is None:
        return {}
    if isinstance(spec, RunSpec):
        return spec.canonical()
    if isinstance(spec, Mapping):
        return dict(spec)
    if isinstance(spec, str) and looks_like_toml(spec):
        return parse_toml(spec, field, shorten(spec, 60))
    if isinstance(spec, (str, os.PathLike)):
        return load_spec_file(spec, field)
    raise InvalidInput(field, spec, "a RunSpec, a mapping, TOML text or the path of a TOML run spec")


KEYWORDS = tuple(dict.fromkeys(("map", *FLAG_FIELDS, *TOP_FLAGS, "params", "map_params", *SECTIONS)))
"""What :func:`resolve` accepts as overrides (``swarm.run(spec, **overrides)``)."""


def resolve(spec: Any = None, overrides: Mapping[str, Any] | None = None, field: str = "spec") -> RunSpec:
    """The :class:`RunSpec` of ``spec`` (see :func:`spec_source`) with keyword ``overrides`` applied as
    ``swarm run`` applies its flags: ``map`` (a kind or a file), ``size``, ``map_seed``, ``robots``,
    ``spawn``, ``algorithm``, ``seed``, ``max_ticks``, ``explored``, ``transport``, ``params`` (the
    algorithm's) and ``map_params``; a section name with a table (``lidar={"range_m": 4}``,
    ``radio={"model": "los"}``, or ``radio="los"`` for the model alone) merges into that section. Unknown
    keywords are one-line errors."""
    data = spec_source(spec, field)
    flags: dict[str, Any] = {}
    tables: dict[str, Any] = {}
    for key, value in (overrides or {}).items():
        if key not in KEYWORDS:
            raise InvalidInput(shorten(str(key), 60), value, f"a keyword of swarm.run: {', '.join(KEYWORDS)}")
        if key in SECTIONS and isinstance(value, Mapping):
            tables[key] = merge(tables.get(key, {}), value)
        elif key == "radio" and isinstance(value, str):  # radio="los": the model alone
            tables["radio"] = merge(tables.get("radio", {}), {"model": value})
        elif key == "params":
            tables.setdefault("algorithm", {})["params"] = _table(key, value)
        elif key == "map_params":
            tables.setdefault("map", {})["params"] = _table(key, value)
        elif key in ("map", "algorithm"):
            if not isinstance(value, str):
                raise InvalidInput(key, value, f"a {'map kind or file path' if key == 'map' else 'name'} (str) "
                                               f"or a table of {key} settings")
            flags[key] = value
        elif key in FLAG_FIELDS or key in TOP_FLAGS:
            flags[key] = value
        else:
            raise InvalidInput(key, value, f"a table of {key} settings")
    data = merge(data, merge(tables, flag_overrides(flags)))
    check_size_flag(data, flags)
    return RunSpec.from_mapping(data)


def _table(key: str, value: Any) -> dict[str, Any]:
    if not isinstance(value, Mapping):
        raise InvalidInput(key, value, "a table of parameters, e.g. {'door_width': 2}")
    return dict(value)


__all__ = ["FLAG_FIELDS", "KEYWORDS", "SECTIONS", "check_size_flag", "flag_overrides", "load_spec_file", "merge", "resolve", "spec_source"]
