"""The run spec: everything that determines a run, validated up front, canonical, hashable.

A spec is built from a plain mapping (TOML, JSON, CLI flags) with :meth:`RunSpec.from_mapping`; every
section is checked by the dataclass that owns it, so a bad value fails before anything runs, with one
line naming the key. :meth:`RunSpec.canonical` is the fully-resolved dict (defaults filled in, keys
sorted) and :attr:`RunSpec.key` its SHA-256 prefix: the identity of a run in campaigns and results.

Seeds: ``seed`` is the master seed. ``map.seed`` and ``robots.spawn_seed`` default to values derived from
it, but campaigns set them explicitly from (campaign seed, map kind, size, replicate) so every algorithm
and comm model meets the same worlds. Every other stream (sensor noise, packet loss, each robot's
algorithm) is spawned from ``SeedSequence(seed)``; see :func:`seed_streams`.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass, field, fields
from functools import cached_property, lru_cache
from collections.abc import Mapping
from typing import Any

import numpy as np

from swarm.base.errors import InvalidInput
from swarm.base.params import OMIT_DEFAULT, check_choice, check_float, check_int, from_mapping, to_mapping
from swarm.navigation.spec import NavigationSpec
from swarm.world.localization import LocalizationSpec

SPAWN_MODES = ("together", "random")
HEADING_MODES = ("random", "maes")   # swarm.world.spawn.HEADING_MODES
TRANSPORTS = ("inprocess", "zenoh")
MAP_KINDS = ("building", "cave", "file")
SPEC_VERSION = 1
MAX_ROBOTS = 10_000
"""The largest team a run takes (benchmarks/speed/bench_scale.py runs it on a 2,000-tile building)."""


@dataclass(frozen=True)
class MapSpec:
    """Which world: a generated ``building``/``cave`` of ``size`` tiles, or a ``file`` at ``path``."""

    kind: str = "building"
    size: Any = 50
    seed: int | None = None
    params: Mapping[str, Any] = field(default_factory=dict)
    path: str | None = None

    def __post_init__(self) -> None:
        check_choice("map.kind", self.kind, MAP_KINDS)
        if self.kind == "file":
            if not isinstance(self.path, str) or not self.path:
                raise InvalidInput("map.path", self.path, "a map file path when map.kind = 'file'")
            if isinstance(self.params, Mapping) and self.params:
                from maps.houseexpo import check_scale

                for key, value in self.params.items():
                    if key != "scale" or not self.path.lower().endswith((".json", ".yaml", ".yml")):
                        raise InvalidInput(f"map.params.{key}", value, "only scale, for a HouseExpo .json plan or "
                                                                       "a ROS .yaml map (other map files take no "
                                                                       "parameters)")
                    check_scale(value, "map.params.scale")
        else:
            from maps import parse_size, params_for

            if self.path is not None:
                raise InvalidInput("map.path", self.path, "only with map.kind = 'file'")
            w, h = parse_size(self.size)
            object.__setattr__(self, "size", w if w == h else [w, h])
            try:
                params = params_for(self.kind, self.params)
            except InvalidInput as exc:  # the generator names its fields "<kind>.<field>"
                field = exc.field.removeprefix(f"{self.kind}.")
                raise InvalidInput(f"map.params.{field}", exc.value, exc.allowed) from None
            object.__setattr__(self, "params", to_mapping(params))
        if self.seed is not None:
            check_int("map.seed", self.seed, 0, 2**63 - 1)
        if not isinstance(self.params, Mapping):
            raise InvalidInput("map.params", self.params, "a table of generator parameters")
        object.__setattr__(self, "params", dict(self.params))


@dataclass(frozen=True)
class RobotsSpec:
    """How many robots and where they start (``together``: packed near one random point, ``random``:
    spread uniformly over the reachable space), facing random directions or, with ``heading = "maes"``, +y
    as MAES spawns them (left out of the canonical spec at its default, so earlier specs keep their key)."""

    count: int = 4
    spawn: str = "together"
    spawn_seed: int | None = None
    heading: str = field(default="random", metadata={OMIT_DEFAULT: True})

    def __post_init__(self) -> None:
        check_int("robots.count", self.count, 1, MAX_ROBOTS)
        check_choice("robots.spawn", self.spawn, SPAWN_MODES)
        check_choice("robots.heading", self.heading, HEADING_MODES)
        if self.spawn_seed is not None:
            check_int("robots.spawn_seed", self.spawn_seed, 0, 2**63 - 1)


@dataclass(frozen=True)
class AlgorithmSpec:
    """An algorithm by registered name (``swarm algorithms``) or ``"package.module:Class"``."""

    name: str = "frontier"
    params: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        from swarm.plugins.explorers import resolve_params

        object.__setattr__(self, "params", resolve_params(self.name, self.params))


@dataclass(frozen=True)
class StopSpec:
    """When a run ends: ``explored`` fraction reached, ``max_ticks`` elapsed, or every robot idle (no
    goal, no motion) for ``stall_ticks`` in a row."""

    explored: float = 0.99
    max_ticks: int = 36_000
    stall_ticks: int = 600

    def __post_init__(self) -> None:
        check_float("stop.explored", self.explored, 0.0, 1.0, lo_open=True)
        check_int("stop.max_ticks", self.max_ticks, 1, 10_000_000)
        check_int("stop.stall_ticks", self.stall_ticks, 1, 10_000_000)


def _section(cls: type, name: str, value: Any) -> Any:
    if isinstance(value, cls):
        return value
    if value is None:
        value = {}
    if not isinstance(value, Mapping):
        raise InvalidInput(name, value, f"a table of {name} settings")
    return from_mapping(cls, value, prefix=f"{name}.")


@dataclass(frozen=True)
class RunSpec:
    """One run, every section typed: the spec's own dataclasses, and the sections other modules own
    (:class:`~swarm.world.sensing.LidarParams`, :class:`~swarm.world.physics.MotionParams`, :class:`radio.RadioConfig`,
    :class:`~swarm.comm.medium.CommSpec`), each built once from its fully-resolved table. A section may be given
    as a mapping or as its dataclass."""

    seed: int = 0
    map: MapSpec = field(default_factory=MapSpec)
    robots: RobotsSpec = field(default_factory=RobotsSpec)
    algorithm: AlgorithmSpec = field(default_factory=AlgorithmSpec)
    lidar: Any = field(default_factory=dict)        # LidarParams
    motion: Any = field(default_factory=dict)       # MotionParams
    navigation: NavigationSpec = field(default_factory=NavigationSpec)
    radio: Any = field(default_factory=dict)        # radio.RadioConfig
    comm: Any = field(default_factory=dict)         # CommSpec
    transport: str = "inprocess"
    stop: StopSpec = field(default_factory=StopSpec)
    record_every: int = 10
    localization: LocalizationSpec = field(default_factory=LocalizationSpec, metadata={OMIT_DEFAULT: True})

    def __post_init__(self) -> None:
        check_int("seed", self.seed, 0, 2**63 - 1)
        object.__setattr__(self, "map", _section(MapSpec, "map", self.map))
        object.__setattr__(self, "robots", _section(RobotsSpec, "robots", self.robots))
        object.__setattr__(self, "algorithm", _section(AlgorithmSpec, "algorithm", self.algorithm))
        object.__setattr__(self, "navigation", _section(NavigationSpec, "navigation", self.navigation))
        object.__setattr__(self, "stop", _section(StopSpec, "stop", self.stop))
        object.__setattr__(self, "localization", _section(LocalizationSpec, "localization", self.localization))
        for name in _EXTERNAL_SECTIONS:
            object.__setattr__(self, name, _typed_section(name, getattr(self, name)))
        check_choice("transport", self.transport, TRANSPORTS)
        check_int("record_every", self.record_every, 1, 100_000)
        _check_override_ids(self.radio, self.robots.count)

    # ------------------------------------------------------------------------------ construction ----
    @classmethod
    def from_mapping(cls, data: Mapping[str, Any]) -> "RunSpec":
        """Build from a nested mapping (e.g. parsed TOML); unknown keys are errors naming the key."""
        if isinstance(data, RunSpec):
            return data
        if not isinstance(data, Mapping):
            raise InvalidInput("spec", data, "a table of run settings")
        data = dict(data)
        data.pop("version", None)
        return from_mapping(cls, data)

    def replace(self, **changes: Any) -> "RunSpec":
        """A copy with some sections replaced (sections may be mappings)."""
        current = {f.name: getattr(self, f.name) for f in fields(self)}
        current.update(changes)
        return RunSpec(**current)

    # -------------------------------------------------------------------------------- identity ----
    def canonical(self) -> dict[str, Any]:
        """The fully-resolved spec as a JSON-able dict with sorted keys."""
        return json.loads(self.to_json())

    @cached_property
    def _json(self) -> str:
        out: dict[str, Any] = {"version": SPEC_VERSION}
        for f in fields(self):
            value = getattr(self, f.name)
            if f.metadata.get(OMIT_DEFAULT) and value == f.default_factory():  # type: ignore[misc]
                continue   # a section added later, left out at its default: older specs keep their key
            out[f.name] = _plain(to_mapping(value)) if hasattr(value, "__dataclass_fields__") else _plain(value)
        return json.dumps(out, sort_keys=True, separators=(",", ":"))

    def to_json(self) -> str:
        """Canonical JSON: sorted keys, no spaces (what :attr:`key` hashes)."""
        return self._json

    def to_toml(self) -> str:
        """The fully-resolved spec as a TOML run-spec file (``swarm run --spec`` reads it back to the same
        :attr:`key`), every default shown: also the settings the canonical form leaves out while they hold
        their default (:data:`~swarm.base.params.OMIT_DEFAULT`: ``comm.relay``, ``radio.per``, an algorithm's
        ``variant``...), which read back to the same key. TOML has no null: a setting that is None (a seed
        drawn from ``seed``, an automatic ray count) is left out, which is what its default means."""
        import tomli_w

        from swarm.plugins.explorers import build_params

        data = self.canonical()
        for f in fields(self):
            value = getattr(self, f.name)
            if hasattr(value, "__dataclass_fields__"):
                data[f.name] = _plain(to_mapping(value, omit_defaults=False))
        params = build_params(self.algorithm.name, self.algorithm.params)
        data["algorithm"]["params"] = _plain(to_mapping(params, omit_defaults=False))
        return tomli_w.dumps(_without_none(json.loads(json.dumps(data, sort_keys=True))))

    @cached_property
    def key(self) -> str:
        """16 hex digits of SHA-256 over the canonical JSON: stable across processes and dict order."""
        return hashlib.sha256(self._json.encode()).hexdigest()[:16]


def _without_none(v: Any) -> Any:
    if isinstance(v, dict):
        return {k: _without_none(x) for k, x in v.items() if x is not None}
    if isinstance(v, list):
        return [_without_none(x) for x in v]
    return v


def _plain(v: Any) -> Any:
    if isinstance(v, Mapping):
        return {str(k): _plain(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [_plain(x) for x in v]
    if isinstance(v, np.generic):
        return v.item()
    return v


def _check_override_ids(radio: Any, count: int) -> None:
    """Per-robot radio overrides must name robots of this run: an override for robot 999 of 4 would be
    silently unused (the radio config itself validated the keys as integers and the powers as finite)."""
    for section in ("tx_power_overrides", "sensitivity_overrides"):
        for key in getattr(radio, section) or {}:
            if int(key) >= count:
                raise InvalidInput(f"radio.{section}.{key}", int(key),
                                   f"a robot id in 0..{count - 1} (robots.count is {count})")


def _resolve_lidar(d: dict[str, Any]) -> dict[str, Any]:
    from swarm.world.sensing import LidarParams

    return to_mapping(from_mapping(LidarParams, d, prefix="lidar."))


def _resolve_motion(d: dict[str, Any]) -> dict[str, Any]:
    from swarm.world.physics import MotionParams

    return to_mapping(from_mapping(MotionParams, d, prefix="motion."))


def _resolve_radio(d: dict[str, Any]) -> dict[str, Any]:
    from radio import RadioConfig, config_from_mapping

    config = config_from_mapping(d, "radio.") if d else RadioConfig()
    return _plain(to_mapping(config))


def _resolve_comm(d: dict[str, Any]) -> dict[str, Any]:
    from swarm.comm.medium import CommSpec

    return to_mapping(from_mapping(CommSpec, d, prefix="comm."))


def _section_class(name: str) -> type:
    if name == "lidar":
        from swarm.world.sensing import LidarParams
        return LidarParams
    if name == "motion":
        from swarm.world.physics import MotionParams
        return MotionParams
    if name == "radio":
        from radio import RadioConfig
        return RadioConfig
    from swarm.comm.medium import CommSpec
    return CommSpec


@lru_cache(maxsize=256)
def _resolved_text(name: str, text: str) -> str:
    """The fully-resolved table of a section given as canonical JSON, as canonical JSON (cached: a campaign
    builds thousands of specs from a handful of distinct sections)."""
    return json.dumps(_EXTERNAL_SECTIONS[name](json.loads(text)), sort_keys=True)


@lru_cache(maxsize=256)
def _section_from_text(name: str, resolved: str) -> Any:
    """The section's dataclass, built from its resolved table (frozen, so one instance serves every spec
    with this section)."""
    data = json.loads(resolved)
    if name == "radio":
        from radio import config_from_mapping
        return config_from_mapping(data)
    return from_mapping(_section_class(name), data, prefix=f"{name}.")


def _typed_section(name: str, value: Any) -> Any:
    """A section (a mapping or its dataclass) validated, resolved and typed."""
    cls = _section_class(name)
    if isinstance(value, cls):
        value = _plain(to_mapping(value))
    if not isinstance(value, Mapping):
        raise InvalidInput(name, value, f"a table of {name} settings")
    try:
        text = json.dumps(dict(value), sort_keys=True)
    except (TypeError, ValueError):  # not JSON-able: let the resolver report what is wrong
        return _section_from_text(name, json.dumps(_EXTERNAL_SECTIONS[name](dict(value)), sort_keys=True))
    return _section_from_text(name, _resolved_text(name, text))


_EXTERNAL_SECTIONS = {"lidar": _resolve_lidar, "motion": _resolve_motion, "radio": _resolve_radio,
                      "comm": _resolve_comm}


# ---------------------------------------------------------------------------------------- seeds ----
@dataclass(frozen=True)
class SeedStreams:
    """Independent random streams of one run, all derived from the spec."""

    map_seed: int
    spawn: np.random.Generator
    sensor: np.random.Generator
    radio: np.random.Generator
    robots: tuple[np.random.Generator, ...]
    channel: np.random.Generator


def derive_seed(*parts: int | str) -> int:
    """A 63-bit seed from a tuple of ints/strings, stable across processes and Python versions."""
    words = [int.from_bytes(hashlib.sha256(p.encode()).digest()[:4], "little") if isinstance(p, str) else int(p)
             for p in parts]
    return int(np.random.SeedSequence(words).generate_state(2, np.uint32).view(np.uint64)[0] >> np.uint64(1))


ROBOT_STREAM = 3
"""Robot i's algorithm stream is ``SeedSequence(seed, spawn_key=(ROBOT_STREAM, i))``."""
PLANNER_STREAM = 4
"""Robot i's path-planner stream (stochastic planners such as IBOA) is ``spawn_key=(PLANNER_STREAM, i)``."""
CHANNEL_STREAM = 5
"""Packet errors (``radio.per``) draw from ``SeedSequence(seed, spawn_key=(CHANNEL_STREAM,))``: a stream of
its own, so turning them on changes no other draw (``comm.loss`` keeps the radio stream)."""


def planner_rng(seed: int, robot: int) -> np.random.Generator:
    return np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(PLANNER_STREAM, robot)))


def run_map_seed(seed: int, map_seed: int | None) -> int:
    """The map seed a run uses: ``map.seed`` if set, else one derived from the master ``seed`` (it also seeds
    the radio's shadowing field, so a recording's reader recomputes the run's radio picture from it)."""
    return map_seed if map_seed is not None else derive_seed(seed, "map")


def seed_streams(spec: RunSpec) -> SeedStreams:
    """Map seed and generators for spawning, sensor noise, radio loss, each robot's algorithm and packet
    errors. The first four are the root's first children (``spawn_key`` 0-3), packet errors
    :data:`CHANNEL_STREAM`; the shadowing field is drawn from the map seed (:mod:`radio.shadowing`)."""
    root = np.random.SeedSequence(spec.seed)
    spawn_ss, sensor_ss, radio_ss, robots_ss = root.spawn(ROBOT_STREAM + 1)
    map_seed = run_map_seed(spec.seed, spec.map.seed)
    spawn_seed = spec.robots.spawn_seed if spec.robots.spawn_seed is not None else None
    spawn_rng = (np.random.default_rng(np.random.SeedSequence(spawn_seed)) if spawn_seed is not None
                 else np.random.default_rng(spawn_ss))
    robots = tuple(np.random.default_rng(s) for s in robots_ss.spawn(spec.robots.count))
    channel = np.random.default_rng(np.random.SeedSequence(spec.seed, spawn_key=(CHANNEL_STREAM,)))
    return SeedStreams(map_seed=map_seed, spawn=spawn_rng, sensor=np.random.default_rng(sensor_ss),
                       radio=np.random.default_rng(radio_ss), robots=robots, channel=channel)
