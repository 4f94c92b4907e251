"""Is a campaign TOML the same campaign as the one a results folder holds?

A results folder belongs to one spec. Two texts are the same spec when they parse to the same TOML data:
comments, blank lines, quoting style, inline vs. standard tables and the order of keys in a table change
nothing (the grid is crossed in a fixed dimension order and every run key hashes sorted JSON). Any change of
a parsed value is a different spec, including ``20`` vs ``20.0`` (different labels) and ``true`` vs ``1``;
so is the folder ``{files = ...}`` map globs were resolved in (the first line the stored text carries): a run
on ``/a/plans/x.json`` and one on ``/b/plans/x.json`` have different keys.
"""

from __future__ import annotations

import datetime as _dt
import tomllib
from typing import Any

from .spec import folder_of
from .text import clip, clip_repr


def difference(stored: str, given: str) -> str | None:
    """None when ``given`` is the campaign ``stored`` is; else a short note of the first difference."""
    if stored == given:
        return None
    old_folder, new_folder = folder_of(stored) or "", folder_of(given) or ""
    if old_folder != new_folder:  # map files: a run's key holds its file's path, so other files are other runs
        return (f"its map files are in {old_folder or 'no folder'}, these in {new_folder or 'no folder'}: run it from "
                "the first, or into a new folder")
    try:
        old = tomllib.loads(stored)
    except (tomllib.TOMLDecodeError, RecursionError):
        return "the folder's campaign.toml is not valid TOML"
    try:
        new = tomllib.loads(given)
    except (tomllib.TOMLDecodeError, RecursionError):
        return "the given spec is not valid TOML"
    return _first_difference(old, new, "")


def _first_difference(a: Any, b: Any, path: str) -> str | None:
    where = path or "the spec"
    if isinstance(a, dict) and isinstance(b, dict):
        for key in sorted(set(a) | set(b)):
            sub = f"{path}.{key}" if path else key
            if key not in b:
                return f"{_short(sub)} removed"
            if key not in a:
                return f"{_short(sub)} added"
            found = _first_difference(a[key], b[key], sub)
            if found:
                return found
        return None
    if isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            return f"{_short(where)}: {len(a)} entries -> {len(b)}"
        for i, (x, y) in enumerate(zip(a, b)):
            found = _first_difference(x, y, f"{path}[{i}]")
            if found:
                return found
        return None
    if _same_scalar(a, b):
        return None
    return f"{_short(where)}: {clip_repr(a, 30)} -> {clip_repr(b, 30)}"


def _same_scalar(a: Any, b: Any) -> bool:
    if type(a) is not type(b):  # 1 vs 1.0 vs true, a table vs a value
        return False
    if isinstance(a, float):
        return repr(a) == repr(b)  # nan == nan, -0.0 != 0.0 (it hashes differently)
    if isinstance(a, (_dt.datetime, _dt.time)):
        return a == b and a.tzinfo == b.tzinfo
    return a == b


def _short(path: str) -> str:
    return clip(path, 60)
