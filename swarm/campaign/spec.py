"""Campaign specs: one TOML file -> thousands of run specs, validated before anything runs.

```toml
[campaign]
name = "quick"
seed = 123456
replicates = 3

[grid]                                   # lists to cross; every entry may be a plain value or a table
map = ["building", "cave"]               # or {kind = "building", params = {door_width = 3}, label = "b3"}
size = [50, 100]
robots = [2, 8]
spawn = ["together", "random"]
algorithm = ["greed", {name = "tnf", params = {alpha = 1, beta = 10}}]
radio = ["global", "los", "multiwall"]   # or {model = "multiwall", frequency_ghz = 5.2, label = "mw5"}
comm = [{map_sharing = "delta"}]         # optional; needs a label when it has several entries
transport = ["inprocess"]                # optional

[run]                                    # applied to every run: lidar, motion, navigation, comm, ...
lidar = {range_m = 7.0}

[stop]
explored = 0.98
max_ticks = 36000

[output]
timeseries_every = 10

[[exclude]]                              # drop cells matching every key (a list matches any of its values)
robots = 8
size = 50

[[include]]                              # add cells outside the cross product (one value per key)
map = "building"
size = 150
robots = 16
spawn = "together"
algorithm = "greed"
radio = "global"
```

Seeds (reference/maes.md section 13 says what not to copy): a run's map seed, spawn seed and master
seed derive from (campaign seed, map kind, size, replicate) only, through :func:`swarm.spec.derive_seed`.
Every algorithm, robot count and comm model therefore meets the same worlds and starting points (paired
comparisons), and nothing depends on the order runs execute in. Each run is keyed by the hash of its
canonical spec (:attr:`swarm.spec.RunSpec.key`).
"""

from __future__ import annotations

import itertools
import json
import tomllib
from dataclasses import dataclass, field
from functools import cached_property, lru_cache
from pathlib import Path
from collections.abc import Mapping
from typing import Any

from maps.errors import InvalidInput

from ..spec import RunSpec, derive_seed

DIMENSIONS = ("map", "size", "robots", "spawn", "algorithm", "radio", "comm", "transport")
REQUIRED = ("map", "size", "robots", "spawn", "algorithm", "radio")
SECTIONS = ("campaign", "grid", "run", "stop", "output", "exclude", "include")
SPEC_FORMAT = 1


@dataclass(frozen=True)
class Option:
    """One value of a grid dimension: its label (used in tables and plots) and the run-spec pieces it sets."""

    label: str
    value: Any


@dataclass(frozen=True)
class Run:
    """One run of a campaign: where it sits in the grid (``cell`` labels), its replicate and its spec."""

    index: int
    cell: dict[str, Any]
    replicate: int
    spec: RunSpec
    seeds: dict[str, int]

    @property
    def key(self) -> str:
        return self.spec.key


@dataclass(frozen=True)
class CampaignSpec:
    name: str
    seed: int
    replicates: int
    grid: dict[str, tuple[Option, ...]]
    run: dict[str, Any] = field(default_factory=dict)
    stop: dict[str, Any] = field(default_factory=dict)
    output: dict[str, Any] = field(default_factory=dict)
    exclude: tuple[dict[str, Any], ...] = ()
    include: tuple[dict[str, Any], ...] = ()
    description: str = ""
    source: str = ""

    @property
    def timeseries_every(self) -> int:
        return int(self.output.get("timeseries_every", 10))

    def cells(self) -> list[dict[str, Option]]:
        """The grid cells (one option per dimension): the cross product minus ``[[exclude]]`` plus
        ``[[include]]``, in a stable order."""
        cells = [dict(zip(self.grid, combo)) for combo in itertools.product(*self.grid.values())]
        cells = [c for c in cells if not any(_matches(c, rule) for rule in self.exclude)]
        for k, rule in enumerate(self.include):
            extra = {}
            for dim in self.grid:
                if dim not in rule:
                    raise InvalidInput(f"include[{k}].{dim}", None, "a value for every grid dimension")
                extra[dim] = self._option(dim, rule[dim], f"include[{k}].{dim}")
            cells.append(extra)
        return cells

    def runs(self) -> list[Run]:
        """Every run, in a stable order (grid order, then replicate); specs validated (built once, cached)."""
        return list(self._runs)

    @cached_property
    def _runs(self) -> tuple[Run, ...]:
        out: list[Run] = []
        seen: set[str] = set()
        for cell in self.cells():
            for rep in range(self.replicates):
                run = self.run_for(cell, rep, len(out))
                if run.key in seen:
                    continue  # an [[include]] that repeats a grid cell
                seen.add(run.key)
                out.append(run)
        return tuple(out)

    def _option(self, dim: str, value: Any, where: str) -> Option:
        for opt in self.grid.get(dim, ()):
            if value == opt.label or value == opt.value:
                return opt
        return _parse_option(dim, value, where)

    def run_for(self, cell: Mapping[str, Option], rep: int, index: int = 0) -> Run:
        """The run of a grid cell at replicate ``rep`` (``index``: its position in :meth:`runs`)."""
        kind_opt, size = cell["map"], cell["size"].value
        kind = kind_opt.value["kind"]
        size_key = size if isinstance(size, int) else "x".join(map(str, size))
        seeds = _world_seeds(self.seed, kind, size_key, rep)
        spec: dict[str, Any] = json.loads(json.dumps(self.run))
        spec["seed"] = seeds["run_seed"]
        spec["map"] = {**kind_opt.value, "size": size, "seed": seeds["map_seed"]}
        spec["robots"] = {"count": cell["robots"].value, "spawn": cell["spawn"].value,
                          "spawn_seed": seeds["spawn_seed"]}
        spec["algorithm"] = cell["algorithm"].value
        spec["radio"] = cell["radio"].value
        if "comm" in cell:
            spec["comm"] = {**spec.get("comm", {}), **cell["comm"].value}
        if "transport" in cell:
            spec["transport"] = cell["transport"].value
        spec["stop"] = {**spec.get("stop", {}), **self.stop}
        spec["record_every"] = self.timeseries_every
        labels = {dim: opt.label for dim, opt in cell.items()}
        return Run(index=index, cell=labels, replicate=rep, spec=RunSpec.from_mapping(spec), seeds=dict(seeds))

    def to_json(self) -> str:
        return json.dumps({"format": SPEC_FORMAT, "name": self.name, "seed": self.seed,
                           "replicates": self.replicates, "source": self.source}, sort_keys=True)


@lru_cache(maxsize=65536)
def _world_seeds(campaign_seed: int, kind: str, size_key: int | str, replicate: int) -> dict[str, int]:
    """Map, spawn and run seeds of one world: a function of (campaign seed, kind, size, replicate) only."""
    return {"map_seed": derive_seed(campaign_seed, kind, size_key, replicate, "map"),
            "spawn_seed": derive_seed(campaign_seed, kind, size_key, replicate, "spawn"),
            "run_seed": derive_seed(campaign_seed, kind, size_key, replicate, "run")}


# -------------------------------------------------------------------------------------- parsing ----
def load_campaign(path: str | Path) -> CampaignSpec:
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise InvalidInput("spec", str(path), f"a readable campaign TOML ({exc.strerror})") from None
    return parse_campaign(text, str(path))


def parse_campaign(text: str, source: str = "<string>") -> CampaignSpec:
    try:
        raw = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InvalidInput("spec", source, f"valid TOML ({str(exc).splitlines()[0]})") from None
    spec = campaign_from_mapping(raw)
    spec = CampaignSpec(**{**spec.__dict__, "source": text})
    spec.runs()  # validate every run before anything runs
    return spec


def campaign_from_mapping(raw: Mapping[str, Any]) -> CampaignSpec:
    for key in raw:
        if key not in SECTIONS:
            raise InvalidInput(key, raw[key], f"a section of a campaign spec: {', '.join(SECTIONS)}")
    head = _table(raw, "campaign")
    for key in head:
        if key not in ("name", "seed", "replicates", "description"):
            raise InvalidInput(f"campaign.{key}", head[key], "name, seed, replicates, description")
    name = head.get("name", "campaign")
    if not isinstance(name, str) or not name or "/" in name:
        raise InvalidInput("campaign.name", name, "a non-empty name without '/'")
    seed = head.get("seed", 0)
    if not isinstance(seed, int) or isinstance(seed, bool) or not 0 <= seed < 2**63:
        raise InvalidInput("campaign.seed", seed, "an integer in 0..2**63-1")
    reps = head.get("replicates", 1)
    if not isinstance(reps, int) or isinstance(reps, bool) or not 1 <= reps <= 100_000:
        raise InvalidInput("campaign.replicates", reps, "an integer in 1..100000")
    grid_raw = _table(raw, "grid")
    for key in grid_raw:
        if key not in DIMENSIONS:
            raise InvalidInput(f"grid.{key}", grid_raw[key], f"one of {', '.join(DIMENSIONS)}")
    for key in REQUIRED:
        if key not in grid_raw:
            raise InvalidInput(f"grid.{key}", None, "a list of values (every campaign crosses map, size, robots, "
                                                    "spawn, algorithm and radio)")
    grid: dict[str, tuple[Option, ...]] = {}
    for dim in DIMENSIONS:
        if dim not in grid_raw:
            continue
        values = grid_raw[dim] if isinstance(grid_raw[dim], list) else [grid_raw[dim]]
        if not values:
            raise InvalidInput(f"grid.{dim}", values, "a non-empty list")
        options = tuple(_parse_option(dim, v, f"grid.{dim}[{i}]") for i, v in enumerate(values))
        labels = [o.label for o in options]
        if len(set(labels)) != len(labels):
            raise InvalidInput(f"grid.{dim}", labels, "distinct entries (give tables a distinct 'label')")
        grid[dim] = options
    run_base = _table(raw, "run")
    for key in ("seed", "map", "robots", "algorithm", "radio", "transport", "stop", "record_every"):
        if key in run_base:
            raise InvalidInput(f"run.{key}", run_base[key], "not in [run]: set it in [grid], [stop] or [output]")
    stop = _table(raw, "stop")
    output = _table(raw, "output")
    for key in output:
        if key not in ("timeseries_every",):
            raise InvalidInput(f"output.{key}", output[key], "timeseries_every")
    every = output.get("timeseries_every", 10)
    if not isinstance(every, int) or isinstance(every, bool) or not 1 <= every <= 100_000:
        raise InvalidInput("output.timeseries_every", every, "an integer in 1..100000 (ticks)")
    exclude = tuple(_rules(raw, "exclude", grid))
    include = tuple(_rules(raw, "include", grid))
    return CampaignSpec(name=name, seed=seed, replicates=reps, grid=grid, run=dict(run_base), stop=dict(stop),
                        output=dict(output), exclude=exclude, include=include,
                        description=str(head.get("description", "")))


def _table(raw: Mapping[str, Any], name: str) -> dict[str, Any]:
    value = raw.get(name, {})
    if not isinstance(value, Mapping):
        raise InvalidInput(name, value, f"a [{name}] table")
    return dict(value)


def _rules(raw: Mapping[str, Any], name: str, grid: Mapping[str, Any]) -> list[dict[str, Any]]:
    rules = raw.get(name, [])
    if not isinstance(rules, list) or not all(isinstance(r, Mapping) for r in rules):
        raise InvalidInput(name, rules, f"[[{name}]] tables")
    for k, rule in enumerate(rules):
        for key in rule:
            if key not in grid:
                raise InvalidInput(f"{name}[{k}].{key}", rule[key], f"a grid dimension: {', '.join(grid)}")
    return [dict(r) for r in rules]


def _parse_option(dim: str, value: Any, where: str) -> Option:
    """Turn one grid entry into an Option, validating it in isolation so errors name its key."""
    from ..comm import CommSpec
    from ..spec import MapSpec, RobotsSpec
    from maps.params import from_mapping

    try:
        if dim == "map":
            table = {"kind": value} if isinstance(value, str) else dict(value) if isinstance(value, Mapping) else None
            if table is None:
                raise InvalidInput(where, value, "a map kind or a table {kind, params, label}")
            label = table.pop("label", table.get("kind"))
            if "size" in table or "seed" in table:
                raise InvalidInput(where, value, "kind, params, path and label only (size and seeds come from the grid)")
            MapSpec(**table)
            return Option(str(label), table)
        if dim == "size":
            from maps import parse_size

            w, h = parse_size(value)
            return Option(str(w) if w == h else f"{w}x{h}", w if w == h else [w, h])
        if dim == "robots":
            RobotsSpec(count=value)
            return Option(str(value), value)
        if dim == "spawn":
            RobotsSpec(spawn=value)
            return Option(str(value), value)
        if dim == "algorithm":
            table = {"name": value} if isinstance(value, str) else dict(value) if isinstance(value, Mapping) else None
            if table is None:
                raise InvalidInput(where, value, "an algorithm name or a table {name, params, label}")
            label = table.pop("label", table.get("name"))
            RunSpec.from_mapping({"algorithm": table})
            return Option(str(label), table)
        if dim == "radio":
            table = {"model": value} if isinstance(value, str) else dict(value) if isinstance(value, Mapping) else None
            if table is None:
                raise InvalidInput(where, value, "a radio model name or a [radio] table with an optional label")
            label = table.pop("label", table.get("model", "multiwall"))
            RunSpec.from_mapping({"radio": table})
            return Option(str(label), table)
        if dim == "comm":
            if not isinstance(value, Mapping):
                raise InvalidInput(where, value, "a [comm] table with an optional label")
            table = dict(value)
            label = table.pop("label", None) or ",".join(f"{k}={v}" for k, v in sorted(table.items())) or "default"
            from_mapping(CommSpec, table, prefix="comm.")
            return Option(str(label), table)
        if dim == "transport":
            RunSpec.from_mapping({"transport": value})
            return Option(str(value), value)
    except InvalidInput as exc:
        if exc.field.startswith(where):
            raise
        raise InvalidInput(f"{where}: {exc.field}", exc.value, exc.allowed) from None
    raise InvalidInput(where, value, f"a grid dimension: {', '.join(DIMENSIONS)}")


def _matches(cell: Mapping[str, Option], rule: Mapping[str, Any]) -> bool:
    for key, wanted in rule.items():
        opt = cell.get(key)
        if opt is None:
            return False
        choices = wanted if isinstance(wanted, list) else [wanted]
        if not any(w == opt.label or w == opt.value or str(w) == opt.label for w in choices):
            return False
    return True
