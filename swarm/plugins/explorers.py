"""Find exploration algorithms by name: the ``swarm.algorithms`` entry-point group, or ``"pkg.mod:Class"``.

Like Gymnasium's registry, but backed by packaging metadata: a researcher's own package declares

    [project.entry-points."swarm.algorithms"]
    mine = "mypkg.explorer:MyExplorer"

and ``swarm run --algorithm mine`` finds it. Nothing in ``swarm`` imports ``algorithms`` at module load.
Whatever goes wrong in a plugin's module or its ``Params`` (an import error, a ``ValueError`` in its
``__post_init__``) is an :class:`InvalidInput` naming ``algorithm.name`` or ``algorithm.params[.field]``:
one line on the command line, not a traceback. :func:`distribution` says which installed distribution
(name, version) provides an algorithm.
"""

from __future__ import annotations

import dataclasses
import importlib
import re
from functools import lru_cache
from importlib.metadata import entry_points, packages_distributions
from typing import Any, Mapping

from swarm.base.errors import InvalidInput
from swarm.base.params import from_mapping, to_mapping

from swarm.base.types import NoParams

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
        except Exception as exc:  # the plugin's module itself fails (a SyntaxError, a NameError...)
            raise InvalidInput("algorithm.name", name, f"an importable 'package.module:Class' "
                               f"(importing it raised {type(exc).__name__}: {exc})") from exc
    else:
        matches = [ep for ep in entry_points(group=GROUP) if ep.name == name]
        if not matches:
            names = ", ".join(available()) or "(none installed)"
            raise InvalidInput("algorithm.name", name, f"one of {names}, or 'package.module:Class'")
        try:
            obj = matches[0].load()
        except (ImportError, AttributeError) as exc:
            raise InvalidInput("algorithm.name", name, f"an installed algorithm ({matches[0].value}: {exc})") from None
        except Exception as exc:
            raise InvalidInput("algorithm.name", name, f"an installed algorithm ({matches[0].value}: importing it "
                               f"raised {type(exc).__name__}: {exc})") from exc
    for method in ("reset", "act"):
        if not callable(getattr(obj, method, None)):
            raise InvalidInput("algorithm.name", name, f"a class with reset() and act() (missing {method})")
    params_cls = getattr(obj, "Params", NoParams)
    if not dataclasses.is_dataclass(params_cls):
        raise InvalidInput("algorithm.name", name, "a class whose Params is a dataclass")
    return obj


def params_class(name: str) -> type:
    return getattr(load(name), "Params", NoParams)


PARAMS_FIELD = "algorithm.params"


def build_params(name: str, params: Mapping[str, Any] | None) -> Any:
    """Validated parameter dataclass; unknown parameters and values that do not fit a field's annotation
    are an error naming them (:func:`swarm.base.params.from_mapping`), and so is any exception the class raises
    while it is built (a ``ValueError`` in the author's ``__post_init__``): an :class:`InvalidInput` naming
    ``algorithm.params``, and the field when the message names exactly one."""
    cls = params_class(name)
    try:
        return from_mapping(cls, params, prefix=f"{PARAMS_FIELD}.")
    except InvalidInput:
        raise
    except Exception as exc:
        raise _params_error(cls, params, exc) from exc


def _params_error(cls: type, params: Mapping[str, Any] | None, exc: Exception) -> InvalidInput:
    """One line for an exception raised while building ``cls`` from ``params``."""
    text = str(exc)
    names = [f.name for f in dataclasses.fields(cls) if f.init]
    named = [n for n in names if re.search(rf"(?<![\w.]){re.escape(n)}(?!\w)", text)]
    given = dict(params) if isinstance(params, Mapping) else params
    reason = f"parameters {cls.__name__} accepts ({type(exc).__name__}{': ' + text if text else ''})"
    if len(named) == 1:
        field = named[0]
        value = given.get(field, _default(cls, field)) if isinstance(given, dict) else given
        return InvalidInput(f"{PARAMS_FIELD}.{field}", value, reason)
    return InvalidInput(PARAMS_FIELD, given, reason)


def _default(cls: type, field: str) -> Any:
    for f in dataclasses.fields(cls):
        if f.name == field:
            if f.default is not dataclasses.MISSING:
                return f.default
            if f.default_factory is not dataclasses.MISSING:
                return f.default_factory()
    return None


def distribution(name: str) -> tuple[str, str] | None:
    """``(distribution name, version)`` of the installed distribution that provides the algorithm ``name``:
    a registered name's entry point's distribution, or for a ``module:Class`` path the distribution that
    installs the module's top-level package; None when it comes from no installed distribution (a module
    found on ``sys.path``, e.g. a checkout or a test folder)."""
    if not isinstance(name, str) or not name:
        raise InvalidInput("algorithm.name", name, "a registered algorithm name or 'package.module:Class'")
    if ":" not in name:
        matches = [ep for ep in entry_points(group=GROUP) if ep.name == name]
        if not matches:
            load(name)  # the usual error for an unknown name
            return None
        dist = getattr(matches[0], "dist", None)
        if dist is not None:
            return _name_version(dist)
        name = matches[0].value
    module_name = name.partition(":")[0]
    for ep in entry_points(group=GROUP):  # a path some distribution registers: that distribution
        if ep.value == name and getattr(ep, "dist", None) is not None:
            return _name_version(ep.dist)
    top = module_name.split(".")[0]
    owners = sorted(set(packages_distributions().get(top, ())))
    if len(owners) != 1:
        return None
    from importlib.metadata import PackageNotFoundError, distribution as find_distribution

    try:
        return _name_version(find_distribution(owners[0]))
    except PackageNotFoundError:
        return None


def _name_version(dist: Any) -> tuple[str, str]:
    return str(dist.metadata["Name"] or dist.name), str(dist.version)


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
