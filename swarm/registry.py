"""Find exploration algorithms by name: the ``swarm.algorithms`` entry-point group, or ``"pkg.mod:Class"``.

Like Gymnasium's registry, but backed by packaging metadata: a researcher's own package declares

    [project.entry-points."swarm.algorithms"]
    mine = "mypkg.explorer:MyExplorer"

and ``swarm run --algorithm mine`` finds it. Nothing in ``swarm`` imports ``algorithms`` at module load.
"""

from __future__ import annotations

import dataclasses
import importlib
from functools import lru_cache
from importlib.metadata import entry_points
from typing import Any, Mapping

from maps.errors import InvalidInput
from maps.params import from_mapping, to_mapping

from .api import NoParams

GROUP = "swarm.algorithms"


def available() -> dict[str, str]:
    """Registered algorithm names -> ``module:Class`` targets, sorted by name."""
    return {ep.name: ep.value for ep in sorted(entry_points(group=GROUP), key=lambda e: e.name)}


@lru_cache(maxsize=None)
def load(name: str) -> type:
    """The algorithm class for a registered name or a ``module:Class`` path."""
    if not isinstance(name, str) or not name:
        raise InvalidInput("algorithm.name", name, "a registered algorithm name or 'package.module:Class'")
    if ":" in name:
        module_name, _, attr = name.partition(":")
        try:
            obj = getattr(importlib.import_module(module_name), attr)
        except (ImportError, AttributeError) as exc:
            raise InvalidInput("algorithm.name", name, f"an importable 'package.module:Class' ({exc})") from None
    else:
        matches = [ep for ep in entry_points(group=GROUP) if ep.name == name]
        if not matches:
            names = ", ".join(available()) or "(none installed)"
            raise InvalidInput("algorithm.name", name, f"one of {names}, or 'package.module:Class'")
        try:
            obj = matches[0].load()
        except (ImportError, AttributeError) as exc:
            raise InvalidInput("algorithm.name", name, f"an installed algorithm ({matches[0].value}: {exc})") from None
    for method in ("reset", "act"):
        if not callable(getattr(obj, method, None)):
            raise InvalidInput("algorithm.name", name, f"a class with reset() and act() (missing {method})")
    params_cls = getattr(obj, "Params", NoParams)
    if not dataclasses.is_dataclass(params_cls):
        raise InvalidInput("algorithm.name", name, "a class whose Params is a dataclass")
    return obj


def params_class(name: str) -> type:
    return getattr(load(name), "Params", NoParams)


def build_params(name: str, params: Mapping[str, Any] | None) -> Any:
    """Validated parameter dataclass; unknown parameters are an error naming them."""
    return from_mapping(params_class(name), params, prefix="algorithm.params.")


def resolve_params(name: str, params: Mapping[str, Any] | None) -> dict[str, Any]:
    """Fully-resolved parameters (defaults filled in) as a plain dict."""
    return to_mapping(build_params(name, params))


def create(name: str) -> Any:
    """A fresh instance of the algorithm."""
    return load(name)()


def describe(name: str) -> list[tuple[str, Any, str]]:
    """(parameter, default, type) rows for ``swarm algorithms``."""
    rows = []
    for f in dataclasses.fields(params_class(name)):
        default = f.default if f.default is not dataclasses.MISSING else (
            f.default_factory() if f.default_factory is not dataclasses.MISSING else None)
        rows.append((f.name, default, str(f.type)))
    return rows
