"""Campaign specs: one TOML file -> thousands of run specs, validated before anything runs.

```toml
[campaign]
name = "quick"
seed = 123456
replicates = 3

[grid]                                   # lists to cross; every entry may be a plain value or a table
map = ["building", "cave"]               # or {kind = "building", params = {door_width = 3}, label = "b3"}
                                         # or {files = "plans/*.json", label = "houseexpo", params = {scale = 2.5}}
size = [50, 100]
robots = [2, 8]
spawn = ["together", "random"]
algorithm = ["greed", {name = "tnf", params = {alpha = 1, beta = 10}}]
radio = ["global", "los", "multiwall"]   # or {model = "multiwall", frequency_ghz = 5.2, label = "mw5"}
comm = [{map_sharing = "delta"}]         # optional; needs a label when it has several entries
transport = ["inprocess"]                # optional
"radio.sensitivity_dbm" = [-70, -82]     # optional axes: any radio or comm parameter, one value per cell

[run]                                    # applied to every run: lidar, motion, navigation, comm, ...
lidar = {range_m = 7.0}

[stop]
explored = 0.98
max_ticks = 36000

[output]
timeseries_every = 10
robot_series_every = 100                 # per-robot comm rows (*.robots.parquet) every N ticks; 0: none

[[exclude]]                              # drop cells matching every key (a list matches any of its values)
robots = 8
size = 50

[[include]]                              # add cells outside the cross product: a value or a list per
                                         # key; a key left out takes every grid value
map = "building"
size = 150
robots = 16
spawn = "together"
algorithm = "greed"
radio = "global"
```

Seeds (docs/maes.md section 10.1 says what not to copy): a run's map seed, spawn seed and master
seed derive from (campaign seed, map kind, size, replicate) only, through :func:`swarm.sim.spec.derive_seed`.
Every algorithm, robot count and comm model therefore meets the same worlds and starting points (paired
comparisons), and nothing depends on the order runs execute in. Each run is keyed by the hash of its
canonical spec (:attr:`swarm.sim.spec.RunSpec.key`).

**Map files.** A map entry ``{files = "<glob>", label = "..."}`` is one grid value over a folder of map files
(any format :func:`maps.io.load_map` reads; the glob is relative to the campaign file's folder, ``**``
allowed). The matches are sorted, and replicate ``r`` runs on file ``r mod n``: replicate r is the same
world (file and seeds) for every algorithm, robot count and radio, so paired statistics stay paired by map.
``replicates`` must be at least the number of files (every file is run), ideally a multiple of it. A glob
that matches nothing is an error. The run specs hold absolute paths, so the folder (recorded as the first
line of the stored spec, ``# swarm: campaign folder = "..."``) decides the run keys; ``size`` is ignored
by file maps (give one value). ``params`` may hold a HouseExpo plan's ``scale`` (:mod:`maps.houseexpo`).

**Axes.** Any radio or comm parameter can be a grid dimension of its own, named ``radio.<parameter>`` or
``comm.<parameter>`` (a field of :class:`radio.RadioConfig` other than ``model``, or of
:class:`swarm.comm.medium.CommSpec`), with plain values (numbers, strings, booleans) labelled by their text. In
``[grid]`` either quote the name (``"radio.sensitivity_dbm" = [...]``, beside ``radio = [...]``) or write
the ``radio`` / ``comm`` entry as a table of lists (``radio.sensitivity_dbm = [...]``, ``comm.loss =
[...]``), in which ``radio.model`` lists the radio dimension (default ``["multiwall"]``). An axis value
overrides ``[run]``; a radio or comm entry of the grid that sets the same parameter is an error. Rules name
axes the same way (``"radio.sensitivity_dbm" = -88``). Axes come after the fixed dimensions, in the
order given.

Every ``[grid]`` entry is a list. The runs are never all built at once: the run count comes from the grid
(:mod:`.cells`), a campaign of more than ``max_runs`` runs is refused before any run spec exists, one run
spec per cell is built to validate it, and a run's spec JSON and key are written from its cell's template
when needed (:meth:`CampaignSpec.iter_keys`, :meth:`CampaignSpec.run_at`), in the same order, with the same
indices and keys as when every run was built up front.
"""

from __future__ import annotations

import dataclasses
import hashlib
import itertools
import json
import tomllib
from array import array
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from functools import cached_property, lru_cache
from pathlib import Path
from typing import Any

from swarm.base.errors import InvalidInput

from swarm.sim.spec import RobotsSpec, RunSpec, derive_seed
from . import cells as cellgrid
from .files import read_user_file
from .limits import MAX_RUNS
from .text import clip

DIMENSIONS = ("map", "size", "robots", "spawn", "algorithm", "radio", "comm", "transport")
REQUIRED = ("map", "size", "robots", "spawn", "algorithm", "radio")
AXIS_SECTIONS = ("radio", "comm", "motion", "robots", "localization", "navigation")
"""Run-spec sections whose parameters may be grid axes (``radio.sensitivity_dbm``, ``comm.loss``)."""
DEFAULT_ROBOT_SERIES_EVERY = 10
"""``output.robot_series_every`` defaults to this many time-series rows."""
SECTIONS = ("campaign", "grid", "run", "stop", "output", "exclude", "include")
SPEC_FORMAT = 1
MAX_OPTIONS = 10_000
MAX_MAP_FILES = 10_000
"""Files one ``{files = "<glob>"}`` map entry may match."""
FOLDER_LINE = "# swarm: campaign folder = "
"""First line of a stored spec whose map entries name files: the folder their globs are relative to."""
"""Values per grid dimension."""
MAX_INCLUDED_CELLS = 100_000
"""Cells all ``[[include]]`` rules may add (they are listed, not counted from the grid)."""


@dataclass(frozen=True)
class Option:
    """One value of a grid dimension: its label (used in tables and plots) and the run-spec pieces it sets."""

    label: str
    value: Any


@dataclass(frozen=True)
class Run:
    """One run of a campaign: where it sits in the grid (``cell`` labels), its replicate, its seeds and its
    canonical spec JSON (what :attr:`swarm.sim.spec.RunSpec.key` hashes). The :class:`RunSpec` is built on first
    use: a campaign lists its runs by key without building 54,000 of them."""

    index: int
    cell: dict[str, Any]
    replicate: int
    seeds: dict[str, int]
    spec_json: str = field(repr=False)

    @cached_property
    def key(self) -> str:
        return run_key(self.spec_json)

    @cached_property
    def spec(self) -> RunSpec:
        return RunSpec.from_mapping(json.loads(self.spec_json))

    def canonical(self) -> dict[str, Any]:
        """The spec as the executor sends it (the same dict as ``self.spec.canonical()``)."""
        return json.loads(self.spec_json)


def run_key(spec_json: str) -> str:
    """:attr:`swarm.sim.spec.RunSpec.key` of a canonical spec JSON, without building the spec."""
    return hashlib.sha256(spec_json.encode()).hexdigest()[:16]


_SEED_SLOTS = {"run_seed": "\x00swarm:run-seed\x00", "map_seed": "\x00swarm:map-seed\x00",
               "spawn_seed": "\x00swarm:spawn-seed\x00"}


class _NoTemplate(Exception):
    """A spec whose seeds cannot be left open (one of its strings holds a placeholder)."""


class _Template:
    """The canonical JSON of a cell's run spec with its three seeds left open.

    Replicates of a cell differ only in ``seed``, ``map.seed`` and ``robots.spawn_seed`` (see
    :meth:`CampaignSpec.run_for`), all validated as integers in 0..2**63-1 and all drawn by
    :func:`swarm.sim.spec.derive_seed`, which yields exactly that range. So one validated spec per cell is the
    validation of every replicate, and a replicate's JSON is the cell's with its seeds written in.
    """

    def __init__(self, spec: RunSpec) -> None:
        self.first = spec.to_json()
        data = json.loads(self.first)
        data["seed"] = _SEED_SLOTS["run_seed"]
        data["map"]["seed"] = _SEED_SLOTS["map_seed"]
        data["robots"]["spawn_seed"] = _SEED_SLOTS["spawn_seed"]
        text = json.dumps(data, sort_keys=True, separators=(",", ":"))
        slots = sorted((text.find(json.dumps(mark)), name, json.dumps(mark)) for name, mark in _SEED_SLOTS.items())
        self.pieces: list[str] = []
        self.order: list[str] = []
        pos = 0
        for at, name, token in slots:
            if at < 0 or text.count(token) != 1:
                raise _NoTemplate(name)
            self.pieces.append(text[pos:at])
            self.order.append(name)
            pos = at + len(token)
        self.pieces.append(text[pos:])

    def render(self, seeds: Mapping[str, int]) -> str:
        out = [self.pieces[0]]
        for name, piece in zip(self.order, self.pieces[1:]):
            out.append(str(int(seeds[name])))
            out.append(piece)
        return "".join(out)


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
    base: str = ""
    """The folder ``{files = ...}`` map globs are relative to (the campaign file's; empty: the current one)."""

    @property
    def timeseries_every(self) -> int:
        return int(self.output.get("timeseries_every", 10))

    @property
    def robot_series_every(self) -> int:
        """Ticks between per-robot rows in ``*.robots.parquet`` (0: none)."""
        return int(self.output.get("robot_series_every", DEFAULT_ROBOT_SERIES_EVERY * self.timeseries_every))

    @property
    def axes(self) -> tuple[str, ...]:
        """The grid's radio and comm parameter axes (``radio.sensitivity_dbm``), in grid order."""
        return tuple(dim for dim in self.grid if is_axis(dim))

    # ---------------------------------------------------------------------------------- cells ----
    def cells(self) -> list[dict[str, Option]]:
        """The grid cells (one option per dimension): the cross product minus ``[[exclude]]`` plus
        ``[[include]]``, in a stable order."""
        return [cell for _, cell in self._coded_cells()]

    def cell_bound(self) -> int:
        """How many cells :meth:`cells` lists, counted from the grid without listing them (cells that turn
        out to define the same runs, e.g. an ``[[include]]`` repeating a grid cell, still count)."""
        sizes = [len(opts) for opts in self.grid.values()]
        return cellgrid.count(sizes, self._boxes) + len(self._include_cells)

    def run_bound(self) -> int:
        """An upper bound of :meth:`run_count`, from the grid alone (no run spec built)."""
        return self.cell_bound() * self.replicates

    @cached_property
    def _boxes(self) -> list[dict[int, frozenset[int]]]:
        """Each ``[[exclude]]`` rule as option indices per dimension position (see :mod:`.cells`)."""
        dims = list(self.grid)
        boxes = []
        for rule in self.exclude:
            box = {}
            for key, wanted in rule.items():
                if key not in self.grid:
                    box = None  # names a dimension the grid lacks: matches no cell (as _matches)
                    break
                box[dims.index(key)] = frozenset(i for i, opt in enumerate(self.grid[key])
                                                 if _option_matches(opt, wanted))
            if box is not None:
                boxes.append(box)
        return boxes

    @cached_property
    def _include_cells(self) -> tuple[dict[str, Option], ...]:
        """The cells each ``[[include]]`` adds: per dimension its value, a list of values (each one), or, when
        the dimension is left out, every value the grid has for it; crossed in grid order. So one include
        can add a whole slice, e.g. one algorithm under another radio on every map of the grid."""
        extra = []
        for k, rule in enumerate(self.include):
            choices = []
            for dim in self.grid:
                if dim not in rule:
                    choices.append(list(self.grid[dim]))
                    continue
                values = rule[dim] if isinstance(rule[dim], list) else [rule[dim]]
                if not values:
                    raise InvalidInput(f"include[{k}].{dim}", rule[dim], "a value, a non-empty list, or the key left "
                                                                         "out (every grid value)")
                choices.append([self._option(dim, v, f"include[{k}].{dim}") for v in values])
            for combo in itertools.product(*choices):
                extra.append(dict(zip(self.grid, combo)))
                if len(extra) > MAX_INCLUDED_CELLS:
                    raise InvalidInput(f"include[{k}]", None, f"at most {MAX_INCLUDED_CELLS} cells from all "
                                                              "[[include]] rules together")
        return tuple(extra)

    def _coded_cells(self) -> Iterator[tuple[int, dict[str, Option]]]:
        """``(code, cell)`` in :meth:`cells` order; ``code`` finds the cell again (:meth:`_cell_of`)."""
        dims, options = list(self.grid), list(self.grid.values())
        for code, idx in cellgrid.iter_cells([len(o) for o in options], self._boxes):
            yield code, {dim: opts[i] for dim, opts, i in zip(dims, options, idx)}
        for k, cell in enumerate(self._include_cells):
            yield -1 - k, dict(cell)

    def _cell_of(self, code: int) -> dict[str, Option]:
        if code < 0:
            return dict(self._include_cells[-1 - code])
        options = list(self.grid.values())
        idx = cellgrid.decode(code, [len(o) for o in options])
        return {dim: opts[i] for dim, opts, i in zip(self.grid, options, idx)}

    # ----------------------------------------------------------------------------------- runs ----
    @cached_property
    def _distinct(self) -> array:
        """Codes of the cells that define distinct runs, each validated by building its replicate 0.

        Two cells with identical run specs (an ``[[include]]`` repeating a grid cell, a comm option that
        restates a default) are one: the later is dropped, as before. Seeds depend on (map kind, size,
        replicate) only and kind and size are in the spec, so cells equal at replicate 0 are equal at every
        replicate, and cells that differ at replicate 0 differ at every replicate."""
        codes = array("q")
        seen: set[str] = set()
        for code, cell in self._coded_cells():
            run = self.run_for(cell, 0)
            if run.key in seen:
                continue
            seen.add(run.key)
            if len(self._templates) < _TEMPLATE_CACHE:
                self._templates[len(codes)] = self._new_template(run.spec)
            codes.append(code)
        return codes

    @cached_property
    def _templates(self) -> dict[int, Any]:
        return {}

    def _template(self, pos: int) -> Any:
        tpl = self._templates.get(pos)
        if tpl is None:
            if len(self._templates) >= _TEMPLATE_CACHE:
                self._templates.clear()
            tpl = self._templates[pos] = self._new_template(self.run_for(self._cell_of(self._distinct[pos]), 0).spec)
        return tpl

    @staticmethod
    def _new_template(spec: RunSpec) -> Any:
        if spec.map.kind == "file":
            return spec  # the file may change with the replicate (a {files = ...} entry): build each run's spec
        try:
            tpl = _Template(spec)
        except _NoTemplate:
            return spec  # a string in the spec holds a placeholder: build each replicate's spec instead
        return tpl if tpl.render(_seeds_of(spec)) == tpl.first else spec

    def run_count(self) -> int:
        """How many runs the campaign holds (distinct run specs); validates one run spec per cell."""
        return len(self._distinct) * self.replicates

    def validate(self, max_runs: int | None = MAX_RUNS) -> int:
        """Check the grid before anything runs: at most ``max_runs`` runs (counted from the grid, before any
        run spec is built), every cell's run spec valid, at least one run. Returns :meth:`run_count`."""
        if max_runs is not None:
            bound = self.run_bound()
            if bound > max_runs:
                raise InvalidInput("grid", f"{bound:,} runs ({bound // self.replicates:,} cells x "
                                           f"{self.replicates:,} replicates)",
                                   f"at most {max_runs:,} runs (raise the limit with --max-runs N)")
        total = self.run_count()
        if total == 0:
            raise InvalidInput("exclude", f"{len(self.exclude)} rules",
                               "rules that keep at least one cell ([[exclude]] removes every cell of the grid)")
        return total

    def run_at(self, index: int) -> Run:
        """Run number ``index`` of :meth:`runs`, built alone."""
        pos, rep = divmod(index, self.replicates)
        if not 0 <= index < self.run_count():
            raise IndexError(index)
        cell = self._cell_of(self._distinct[pos])
        tpl = self._template(pos)
        if isinstance(tpl, RunSpec):
            return self.run_for(cell, rep, index)
        kind, size_key = _world(cell)
        seeds = _world_seeds(self.seed, kind, size_key, rep)
        return Run(index=index, cell={dim: opt.label for dim, opt in cell.items()}, replicate=rep,
                   seeds=dict(seeds), spec_json=tpl.render(seeds))

    def indices(self, shard: tuple[int, int] | None = None) -> range:
        """Indices of the runs of ``shard`` (``(i, n)``: every n-th run from the i-th), or of every run."""
        i, n = shard or (0, 1)
        return range(i, self.run_count(), n)

    def iter_runs(self, shard: tuple[int, int] | None = None) -> Iterator[Run]:
        """The runs of :meth:`runs` (or of ``shard``) one at a time, in order."""
        for index in self.indices(shard):
            yield self.run_at(index)

    def iter_keys(self, shard: tuple[int, int] | None = None) -> Iterator[tuple[int, str]]:
        """``(index, key)`` of every run (or of ``shard``), without building runs."""
        reps = self.replicates
        for index in self.indices(shard):
            pos, rep = divmod(index, reps)
            tpl = self._template(pos)
            if isinstance(tpl, RunSpec):
                yield index, self.run_at(index).key
                continue
            kind, size_key = _world(self._cell_of(self._distinct[pos]))
            yield index, run_key(tpl.render(_world_seeds(self.seed, kind, size_key, rep)))

    def runs(self) -> list[Run]:
        """Every run, in a stable order (grid order, then replicate). Builds the whole list: prefer
        :meth:`iter_runs`, :meth:`iter_keys` and :meth:`run_at` for big campaigns."""
        return list(self.iter_runs())

    def _option(self, dim: str, value: Any, where: str) -> Option:
        for opt in self.grid.get(dim, ()):
            if value == opt.label or value == opt.value:
                return opt
        return _parse_option(dim, value, where, self.grid.get("radio"), self.reps_and_base)

    @property
    def reps_and_base(self) -> tuple[int, str]:
        return self.replicates, self.base

    def run_for(self, cell: Mapping[str, Option], rep: int, index: int = 0) -> Run:
        """The run of a grid cell at replicate ``rep`` (``index``: its position in :meth:`runs`), its spec
        built and validated."""
        kind_opt, size = cell["map"], cell["size"].value
        kind, size_key = _world(cell)
        seeds = _world_seeds(self.seed, kind, size_key, rep)
        spec: dict[str, Any] = json.loads(json.dumps(self.run))
        spec["seed"] = seeds["run_seed"]
        spec["map"] = {**kind_opt.value, "size": size, "seed": seeds["map_seed"]}
        if "files" in spec["map"]:  # a folder of maps: replicate r runs on file r mod n (module docstring)
            files = spec["map"].pop("files")
            spec["map"]["path"] = files[rep % len(files)]
        spec["robots"] = {**spec.get("robots", {}), "count": cell["robots"].value, "spawn": cell["spawn"].value,
                          "spawn_seed": seeds["spawn_seed"]}
        spec["algorithm"] = cell["algorithm"].value
        spec["radio"] = dict(cell["radio"].value)
        if "comm" in cell:
            spec["comm"] = {**spec.get("comm", {}), **cell["comm"].value}
        for axis in (dim for dim in cell if is_axis(dim)):
            section, name = axis.split(".", 1)
            dim_opt = cell.get(section)
            if dim_opt is not None and isinstance(dim_opt.value, Mapping) and name in dim_opt.value:
                raise InvalidInput(f"grid.{section}", dim_opt.label, f"an entry without '{name}' ({axis} is a grid "
                                                                      "axis: set it in one place)")
            spec[section] = {**spec.get(section, {}), name: cell[axis].value}
        if "transport" in cell:
            spec["transport"] = cell["transport"].value
        spec["stop"] = {**spec.get("stop", {}), **self.stop}
        spec["record_every"] = self.timeseries_every
        labels = {dim: opt.label for dim, opt in cell.items()}
        try:
            built = RunSpec.from_mapping(spec)
        except InvalidInput as exc:  # a combination of valid entries that does not fit: name the cell
            where = ", ".join(f"{dim}={clip(str(label), 30)}" for dim, label in labels.items())
            raise InvalidInput(exc.field, exc.value, f"{exc.allowed}, in the grid cell {where}") from None
        run = Run(index=index, cell=labels, replicate=rep, seeds=dict(seeds), spec_json=built.to_json())
        run.__dict__["spec"] = built  # cached_property slot: no second build
        return run

    def to_json(self) -> str:
        return json.dumps({"format": SPEC_FORMAT, "name": self.name, "seed": self.seed,
                           "replicates": self.replicates, "source": self.source}, sort_keys=True)


_TEMPLATE_CACHE = 4096
"""Cell templates kept per campaign (runs of a cell are consecutive, so a small cache serves any order)."""


def _world(cell: Mapping[str, Option]) -> tuple[str, int | str]:
    """(map kind, size key) of a cell: with the replicate, all its seeds depend on."""
    size = cell["size"].value
    return cell["map"].value["kind"], size if isinstance(size, int) else "x".join(map(str, size))


def _seeds_of(spec: RunSpec) -> dict[str, int]:
    return {"run_seed": spec.seed, "map_seed": spec.map.seed, "spawn_seed": spec.robots.spawn_seed}


@lru_cache(maxsize=65536)
def _world_seeds(campaign_seed: int, kind: str, size_key: int | str, replicate: int) -> dict[str, int]:
    """Map, spawn and run seeds of one world: a function of (campaign seed, kind, size, replicate) only."""
    return {"map_seed": derive_seed(campaign_seed, kind, size_key, replicate, "map"),
            "spawn_seed": derive_seed(campaign_seed, kind, size_key, replicate, "spawn"),
            "run_seed": derive_seed(campaign_seed, kind, size_key, replicate, "run")}


# -------------------------------------------------------------------------------------- parsing ----
def load_campaign(path: str | Path, max_runs: int | None = MAX_RUNS) -> CampaignSpec:
    """Read, parse and validate the campaign TOML at ``path`` (see :func:`parse_campaign`); ``{files = ...}``
    map globs are relative to its folder."""
    text = read_user_file(path, "spec", "campaign TOML")
    return parse_campaign(text, str(path), max_runs=max_runs, base=str(Path(path).resolve().parent))


def folder_of(text: str) -> str | None:
    """The folder a stored spec's first line records (:data:`FOLDER_LINE`), or None."""
    first = text.split("\n", 1)[0]
    if first.startswith(FOLDER_LINE):
        try:
            value = json.loads(first[len(FOLDER_LINE):])
        except ValueError:
            return None
        return value if isinstance(value, str) else None
    return None


def parse_campaign(text: str, source: str = "<string>", max_runs: int | None = MAX_RUNS,
                   base: str | None = None) -> CampaignSpec:
    """Parse a campaign TOML and validate it before anything runs: its shape, its size (at most
    ``max_runs`` runs; None: no limit) and one run spec per cell. ``base``: the folder ``{files = ...}`` map
    globs are relative to (default: the one the text's first line records, else the current folder)."""
    recorded = folder_of(text)
    if recorded is not None:
        text = text.split("\n", 1)[1] if "\n" in text else ""
        base = recorded if base is None else base
    try:
        raw = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InvalidInput("spec", source, f"valid TOML ({clip(str(exc).splitlines()[0], 120)})") from None
    except (RecursionError, ValueError) as exc:  # nested too deeply; an integer of over 4300 digits
        raise InvalidInput("spec", source, f"valid TOML ({type(exc).__name__}: {clip(str(exc), 100)})") from None
    try:
        spec = campaign_from_mapping(raw, base or "")
        if spec.base:  # map entries name files: record their folder with the text (status, report, resume)
            text = f"{FOLDER_LINE}{json.dumps(spec.base)}\n{text}"
        spec = dataclasses.replace(spec, source=text)
        spec.validate(max_runs)
    except InvalidInput:
        raise
    except (TypeError, ValueError, KeyError, AttributeError, OverflowError, RecursionError) as exc:
        # a combination the checks above do not describe: still one line naming the file, not a traceback
        raise InvalidInput("spec", source, f"a valid campaign spec ({type(exc).__name__}: "
                                           f"{clip(str(exc), 120)})") from None
    return spec


def campaign_from_mapping(raw: Mapping[str, Any], base: str = "") -> CampaignSpec:
    """The spec's shape and grid options checked, without building any run spec (see :func:`parse_campaign`);
    ``base``: the folder ``{files = ...}`` map globs are relative to (empty: the current folder)."""
    for key in raw:
        if key not in SECTIONS:
            raise InvalidInput(clip(key), raw[key], f"a section of a campaign spec: {', '.join(SECTIONS)}")
    head = _table(raw, "campaign")
    for key in head:
        if key not in ("name", "seed", "replicates", "description"):
            raise InvalidInput(f"campaign.{clip(key)}", head[key], "name, seed, replicates, description")
    name = head.get("name", "campaign")
    if not isinstance(name, str) or not name or "/" in name:
        raise InvalidInput("campaign.name", name, "a non-empty name without '/'")
    seed = head.get("seed", 0)
    if not isinstance(seed, int) or isinstance(seed, bool) or not 0 <= seed < 2**63:
        raise InvalidInput("campaign.seed", seed, "an integer in 0..2**63-1")
    reps = head.get("replicates", 1)
    if not isinstance(reps, int) or isinstance(reps, bool) or not 1 <= reps <= 100_000:
        raise InvalidInput("campaign.replicates", reps, "an integer in 1..100000")
    grid_raw = _flatten_axes(_table(raw, "grid"), "grid", default_model=True)
    for key in grid_raw:
        if key not in DIMENSIONS and not is_axis(key):
            raise InvalidInput(f"grid.{clip(key)}", grid_raw[key], f"one of {', '.join(DIMENSIONS)}, or a radio or "
                                                                   "comm parameter (radio.sensitivity_dbm, comm.loss)")
    for key in REQUIRED:
        if key not in grid_raw:
            raise InvalidInput(f"grid.{key}", None, "a list of values (every campaign crosses map, size, robots, "
                                                    "spawn, algorithm and radio)")
    grid: dict[str, tuple[Option, ...]] = {}
    for dim in [*DIMENSIONS, *(key for key in grid_raw if is_axis(key))]:
        if dim not in grid_raw:
            continue
        values = grid_raw[dim]
        if not isinstance(values, list):
            raise InvalidInput(f"grid.{dim}", values, f"a list, e.g. [{_example(values)}] (every grid entry "
                                                      "lists the values to cross)")
        if not values:
            raise InvalidInput(f"grid.{dim}", values, "a non-empty list")
        if len(values) > MAX_OPTIONS:
            raise InvalidInput(f"grid.{dim}", f"{len(values):,} values", f"at most {MAX_OPTIONS:,} values")
        options = tuple(_parse_option(dim, v, f"grid.{dim}[{i}]", grid.get("radio"), (reps, base))
                        for i, v in enumerate(values))
        labels = [o.label for o in options]
        if len(set(labels)) != len(labels):
            dup = next(label for i, label in enumerate(labels) if label in labels[:i])
            raise InvalidInput(f"grid.{dim}", dup, "distinct values (this one repeats)" if is_axis(dim) else
                               "distinct entries (this label repeats; give tables a distinct 'label')")
        grid[dim] = options
    run_base = _table(raw, "run")
    for key in ("seed", "map", "robots", "algorithm", "radio", "transport", "stop", "record_every"):
        if key == "robots" and isinstance(run_base.get(key), Mapping) and set(run_base[key]) <= {"heading"}:
            RobotsSpec(**run_base[key])   # robots.heading may be set for every run; count and spawn are dimensions
            continue
        if key in run_base:
            raise InvalidInput(f"run.{key}", run_base[key], "not in [run]: set it in [grid], [stop] or [output]"
                                                            if key != "robots" else "only {heading = ...} in [run]: "
                                                            "robot counts and spawns are [grid] dimensions")
    stop = _table(raw, "stop")
    output = _table(raw, "output")
    for key in output:
        if key not in ("timeseries_every", "robot_series_every"):
            raise InvalidInput(f"output.{clip(key)}", output[key], "timeseries_every, robot_series_every")
    every = output.get("timeseries_every", 10)
    if not isinstance(every, int) or isinstance(every, bool) or not 1 <= every <= 100_000:
        raise InvalidInput("output.timeseries_every", every, "an integer in 1..100000 (ticks)")
    robot_every = output.get("robot_series_every", DEFAULT_ROBOT_SERIES_EVERY * every)
    if (not isinstance(robot_every, int) or isinstance(robot_every, bool) or not 0 <= robot_every <= 10_000_000
            or robot_every % every):
        raise InvalidInput("output.robot_series_every", robot_every, f"0 (no per-robot rows) or a multiple of "
                                                                     f"timeseries_every ({every}) in ticks")
    _check_file_entries(grid["map"])
    uses_files = any("files" in opt.value for opt in grid["map"] if isinstance(opt.value, Mapping))
    spec = CampaignSpec(name=name, seed=seed, replicates=reps, grid=grid, run=dict(run_base), stop=dict(stop),
                        output=dict(output), exclude=(), include=(), description=str(head.get("description", "")),
                        base=str(Path(base or ".").resolve()) if uses_files else "")
    exclude = tuple(_rules(raw, "exclude", grid))
    include = tuple(_rules(raw, "include", grid))
    return dataclasses.replace(spec, exclude=exclude, include=include)


def _table(raw: Mapping[str, Any], name: str) -> dict[str, Any]:
    value = raw.get(name, {})
    if not isinstance(value, Mapping):
        raise InvalidInput(name, value, f"a [{name}] table")
    return dict(value)


def _rules(raw: Mapping[str, Any], name: str, grid: Mapping[str, Any]) -> list[dict[str, Any]]:
    rules = raw.get(name, [])
    if not isinstance(rules, list) or not all(isinstance(r, Mapping) for r in rules):
        raise InvalidInput(name, rules, f"[[{name}]] tables")
    rules = [_flatten_rule(rule, grid, f"{name}[{k}]") for k, rule in enumerate(rules)]
    for k, rule in enumerate(rules):
        for key in rule:
            if key not in grid:
                raise InvalidInput(f"{name}[{k}].{clip(key)}", rule[key], f"a grid dimension: {', '.join(grid)}")
    return [dict(r) for r in rules]


def is_axis(dim: str) -> bool:
    """A radio, comm, motion, localisation or navigation parameter axis (``radio.sensitivity_dbm``,
    ``motion.model``, ``localization.drift_per_m``, ``navigation.avoidance``) or ``robots.heading``, not a
    fixed dimension."""
    return dim.partition(".")[0] in AXIS_SECTIONS and "." in dim


def axis_fields(section: str) -> tuple[str, ...]:
    """The parameters of a section that may be axes: every field of its dataclass (radio: but ``model``,
    the radio dimension itself; robots: ``heading`` only, count and spawn being dimensions)."""
    from radio import RadioConfig
    from swarm.comm.medium import CommSpec
    from swarm.world.motion import MotionParams

    if section == "robots":
        return ("heading",)
    from swarm.navigation.spec import NavigationSpec
    from swarm.world.localization import LocalizationSpec

    cls = {"radio": RadioConfig, "comm": CommSpec, "motion": MotionParams, "localization": LocalizationSpec,
           "navigation": NavigationSpec}[section]
    return tuple(f.name for f in dataclasses.fields(cls)  # tables (materials, overrides) are not plain values
                 if not (section == "radio" and f.name == "model") and f.default_factory is dataclasses.MISSING)


def _flatten_axes(table: Mapping[str, Any], where: str, default_model: bool = False) -> dict[str, Any]:
    """``[grid]`` with its ``radio`` / ``comm`` tables of lists (``radio.sensitivity_dbm = [...]`` in TOML)
    turned into axes (``"radio.sensitivity_dbm"``); a table's ``radio.model`` is the radio dimension
    (``default_model``: ``["multiwall"]`` when left out). Quoted axis names pass through; one given twice
    is an error."""
    out: dict[str, Any] = {}
    for key, value in table.items():
        if key not in AXIS_SECTIONS or not isinstance(value, Mapping):
            if key in out:
                raise InvalidInput(f"{where}.{clip(key)}", value, "each dimension once (this one is given twice)")
            out[key] = value
            continue
        if key == "radio" and default_model:
            out["radio"] = value.get("model", ["multiwall"])
        for name, values in value.items():
            if key == "radio" and name == "model":
                continue
            axis = f"{key}.{name}"
            if axis in table or axis in out:
                raise InvalidInput(f"{where}.{clip(axis)}", values, "each axis once (this one is given twice)")
            out[axis] = values
    return out


def _flatten_rule(rule: Mapping[str, Any], grid: Mapping[str, Any], where: str) -> dict[str, Any]:
    """A rule's ``radio`` / ``comm`` table whose keys all name axes of the grid (and ``model``, the radio
    dimension) written as axes, as in ``[grid]``; any other table stays a value (a radio or comm entry)."""
    flat = dict(rule)
    for section in AXIS_SECTIONS:
        value = rule.get(section)
        if not isinstance(value, Mapping) or not value:
            continue
        names = [n for n in value if not (section == "radio" and n == "model")]
        if names and all(f"{section}.{n}" in grid for n in names):
            flat.pop(section)
            flat.update(_flatten_axes({section: value}, where))
            if section == "radio" and "model" in value:
                flat["radio"] = value["model"]
    return flat


def _parse_axis(axis: str, value: Any, where: str, radio: tuple[Option, ...] | None) -> Option:
    """One value of a radio or comm parameter axis, checked alone (comm) or with one of the grid's radio
    entries (a radio parameter may depend on the model); combinations are checked per cell."""
    from radio import config_from_mapping
    from swarm.base.params import from_mapping
    from swarm.comm.medium import CommSpec

    section, name = axis.split(".", 1)
    if name not in axis_fields(section):
        hint = " (the radio models are the radio dimension: radio = [...])" if axis == "radio.model" else ""
        raise InvalidInput(f"grid.{clip(axis)}", value, f"a {section} parameter with plain values: "
                                                        f"{', '.join(axis_fields(section))}{hint}")
    if isinstance(value, (list, dict)) or value is None:
        raise InvalidInput(where, value, f"a plain value of {axis} (a number, string or boolean)")
    tables = [{}] if section != "radio" else [opt.value for opt in radio or ()] or [{}]
    for k, table in enumerate(tables):
        try:
            if section == "comm":
                from_mapping(CommSpec, {name: value}, prefix="comm.")
            elif section == "motion":
                from swarm.world.motion import MotionParams

                from_mapping(MotionParams, {name: value}, prefix="motion.")
            elif section == "robots":
                from_mapping(RobotsSpec, {name: value}, prefix="robots.")
            elif section == "localization":
                from swarm.world.localization import LocalizationSpec

                from_mapping(LocalizationSpec, {name: value}, prefix="localization.")
            elif section == "navigation":
                from swarm.navigation.spec import NavigationSpec

                from_mapping(NavigationSpec, {name: value}, prefix="navigation.")
            else:
                config_from_mapping({**table, name: value})
            break
        except InvalidInput as exc:
            if k == len(tables) - 1:
                raise InvalidInput(where, value, exc.allowed) from None
    if isinstance(value, bool):
        label = str(value).lower()
    elif isinstance(value, float):
        label = f"{value:g}"
    else:
        label = str(value)
    return Option(label, value)


def _parse_option(dim: str, value: Any, where: str, radio: tuple[Option, ...] | None = None,
                  reps_and_base: tuple[int, str] = (1, "")) -> Option:
    """Turn one grid entry into an Option, validating it in isolation so errors name its key (``radio``:
    the grid's radio entries, against which a radio parameter axis is checked)."""
    from swarm.base.params import from_mapping
    from swarm.comm.medium import CommSpec
    from swarm.sim.spec import MapSpec, RobotsSpec

    if is_axis(dim):
        return _parse_axis(dim, value, where, radio)
    try:
        if dim == "map":
            table = {"kind": value} if isinstance(value, str) else dict(value) if isinstance(value, Mapping) else None
            if table is None:
                raise InvalidInput(where, value, "a map kind or a table {kind, params, label}")
            if "files" in table:
                return _files_option(table, where, *reps_and_base)
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
            from radio import config_from_mapping

            config_from_mapping(table)  # alone: per-robot overrides are checked against each cell's robots
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


def _files_option(table: dict[str, Any], where: str, replicates: int, base: str) -> Option:
    from swarm.sim.spec import MapSpec

    """``{files = "<glob>", label = "..."}``: the sorted absolute paths of the files the glob matches, relative
    to ``base`` (see the module docstring, "Map files")."""
    pattern = table.pop("files")
    label = table.pop("label", pattern)
    params = table.pop("params", {})
    if table:
        raise InvalidInput(where, sorted(table), "files, label and params only in a map entry over files")
    if not isinstance(params, Mapping):
        raise InvalidInput(f"{where}.params", params, "a table, e.g. {scale = 2.5} (HouseExpo .json plans)")
    if not isinstance(pattern, str) or not pattern.strip() or "\x00" in pattern:
        raise InvalidInput(f"{where}.files", pattern, "a glob of map files relative to the campaign file, "
                                                      "e.g. \"plans/*.json\"")
    if not isinstance(label, str) or not label:
        raise InvalidInput(f"{where}.label", label, "a non-empty label")
    folder = Path(base or ".").resolve()
    if Path(pattern).is_absolute():
        raise InvalidInput(f"{where}.files", pattern, "a glob relative to the campaign file's folder")
    try:
        found = sorted(str(p.resolve()) for p in folder.glob(pattern) if p.is_file())
    except (ValueError, OSError) as exc:
        raise InvalidInput(f"{where}.files", pattern, f"a valid glob ({clip(str(exc), 60)})") from None
    if not found:
        raise InvalidInput(f"{where}.files", pattern, f"a glob matching at least one map file in {clip(str(folder), 80)}")
    if len(found) > MAX_MAP_FILES:
        raise InvalidInput(f"{where}.files", f"{len(found)} files", f"at most {MAX_MAP_FILES} files")
    if replicates < len(found):
        raise InvalidInput("campaign.replicates", replicates, f"at least {len(found)}: replicate r runs on file "
                                                              f"r mod {len(found)} of {clip(pattern, 40)}, so "
                                                              "fewer would leave files out")
    for path in found:  # each file's params checked here, so the error names this entry, not a run
        try:
            MapSpec(kind="file", path=path, params=dict(params))
        except InvalidInput as exc:
            raise InvalidInput(f"{where}.{exc.field.removeprefix('map.')}", exc.value,
                               f"{exc.allowed} ({clip(Path(path).name, 40)})") from None
    value: dict[str, Any] = {"kind": "file", "files": found}
    if params:
        value["params"] = dict(params)
    return Option(label, value)


def _check_file_entries(options: tuple[Option, ...]) -> None:
    """Two map entries over files must not share a file with the same params: their runs would be the same
    runs (one key) under two labels."""
    owner: dict[tuple[str, str], str] = {}
    for opt in options:
        if not (isinstance(opt.value, Mapping) and "files" in opt.value):
            continue
        params = json.dumps(opt.value.get("params", {}), sort_keys=True)
        for path in opt.value["files"]:
            other = owner.setdefault((path, params), opt.label)
            if other != opt.label:
                raise InvalidInput("grid.map", opt.label, f"map entries over distinct files ({clip(Path(path).name, 40)} "
                                                          f"is also in {clip(other, 30)}; or give other params)")


def _matches(cell: Mapping[str, Option], rule: Mapping[str, Any]) -> bool:
    """Does an ``[[exclude]]`` rule match a cell (every key; a list matches any of its values)?"""
    for key, wanted in rule.items():
        opt = cell.get(key)
        if opt is None or not _option_matches(opt, wanted):
            return False
    return True


def _option_matches(opt: Option, wanted: Any) -> bool:
    choices = wanted if isinstance(wanted, list) else [wanted]
    return any(w == opt.label or w == opt.value or str(w) == opt.label for w in choices)


def _example(value: Any) -> str:
    """``value`` as it would appear in a TOML list, if short (for 'a list, e.g. [40]')."""
    if isinstance(value, (bool, int, float, str)):
        text = json.dumps(value).lower() if isinstance(value, bool) else json.dumps(value)
        if len(text) <= 30:
            return text
    return "..."
