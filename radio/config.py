"""The radio's parameter set: which link model, the radios, eq. 1 coefficients, walls, materials.

Built from the ``[radio]`` table of a run's TOML with :func:`config_from_mapping` (unknown keys are an error
naming the key). Defaults are the Minotaur paper's (docs/papers.md; section 4.1: 15 dBm, -82 dBm, 2.4 GHz,
802.11ax) and 3GPP TR 38.901's indoor-office line-of-sight fit for eq. 1 (see :mod:`radio.pathloss`).

```toml
[radio]
model = "multiwall"            # "multiwall" | "global" | "los" | "maes"
frequency_ghz = 2.4
tx_power_dbm = 15.0
sensitivity_dbm = -82.0
wall_mode = "crossing"         # or "per_metre"
shadowing_sigma_db = 4.0       # log-normal shadowing (0 = off, the default); correlated over shadowing_corr_m
per = "bpsk"                   # packet errors rising smoothly near the sensitivity ("off", the default)
tx_power_overrides = { "3" = 10.0 }        # robot id -> dBm
[radio.materials]
glass = [2.26, 2.48, 3.04]                 # dB per crossing at 1.3 / 2.4 / 5.2 GHz
plaster = { db = 4.0, thickness_m = 0.5 }  # same at every frequency; 8 dB/m in per_metre mode
```
"""

from __future__ import annotations

import json
import types
from dataclasses import dataclass, field
from collections.abc import Mapping
from typing import Any

import numpy as np

from swarm.base.errors import InvalidInput, field_name
from swarm.base.params import OMIT_DEFAULT, check_choice, check_float, check_int, from_mapping, to_mapping

from .crossings import DEFAULT_GRAZE_TOLERANCE_M
from .materials import Material, material_from_value
from .per import PER_CURVES

MODELS: tuple[str, ...] = ("multiwall", "global", "los", "maes")
WALL_MODES: tuple[str, ...] = ("crossing", "per_metre")
MAX_ROBOT_ID_DIGITS = 9
"""Per-robot override keys are robot ids of at most this many digits (a run has at most 1000 robots)."""
PHYSICAL_MODELS: tuple[str, ...] = ("multiwall", "maes")
"""Models with a received power to shadow and a margin to turn into packet errors."""
MAX_SHADOWING_SIGMA_DB = 50.0
MAX_FREQUENCY_GHZ = 100.0
"""Upper end of the 3GPP TR 38.901 model (0.5-100 GHz); lower frequencies are allowed and clamp the table."""


@dataclass(frozen=True)
class RadioConfig:
    """Radio parameters of a run; validated on construction.

    - ``model``: ``multiwall`` (default: eq. 1 path loss + wall attenuation), ``global`` (always linked),
      ``los`` (linked iff no wall is crossed, and within ``max_range_m`` if set), ``maes`` (MAES-compatible:
      no distance term, attenuation per 0.25 m of wall path).
    - ``alpha``, ``beta``, ``gamma``: eq. 1 coefficients (3GPP TR 38.901 InH-office LOS by default).
    - ``wall_mode``: ``crossing`` charges each material's figure once per wall crossed; ``per_metre``
      charges ``db / thickness_m`` per metre of wall path (``multiwall`` only).
    - ``graze_tolerance_m``: wall runs / gaps at most this long along the segment are ignored / bridged
      (see :mod:`radio.crossings`).
    - ``materials``: extra or overriding materials, name -> entry (see :func:`radio.materials.material_from_value`).
    - ``tx_power_overrides`` / ``sensitivity_overrides``: robot id -> dBm (finite). A run spec refuses ids
      beyond its robot count (:class:`swarm.sim.spec.RunSpec`); used directly, :meth:`tx_power_array` ignores them.
    - ``shadowing_sigma_db``: log-normal shadowing's standard deviation (0 = none, the default; 3 dB is
      3GPP TR 38.901's indoor-office line-of-sight figure), spatially correlated over
      ``shadowing_corr_m`` metres (:mod:`radio.shadowing`). ``multiwall`` and ``maes`` only.
    - ``per``: ``off`` (default: every message within the sensitivity arrives) or ``bpsk``: a packet error
      rate that rises smoothly as the margin falls, ``per_ref`` of ``per_ref_bytes``-byte messages lost at
      the sensitivity (:mod:`radio.per`). ``multiwall`` and ``maes`` only.

    The channel settings (the last five) are left out of the canonical form while they hold their
    defaults, so specs written before they existed keep their run keys; a setting of a feature that is
    off (``shadowing_corr_m`` at sigma 0, ``per_ref`` with ``per = "off"``) is allowed and unused, so a sweep
    may include the off value.
    """

    model: str = "multiwall"
    frequency_ghz: float = 2.4
    tx_power_dbm: float = 15.0
    sensitivity_dbm: float = -82.0
    alpha: float = 1.73
    beta: float = 32.4
    gamma: float = 2.0
    wall_mode: str = "crossing"
    max_range_m: float | None = None
    graze_tolerance_m: float = DEFAULT_GRAZE_TOLERANCE_M
    materials: Mapping[str, Any] = field(default_factory=dict)
    tx_power_overrides: Mapping[Any, float] = field(default_factory=dict)
    sensitivity_overrides: Mapping[Any, float] = field(default_factory=dict)
    shadowing_sigma_db: float = field(default=0.0, metadata={OMIT_DEFAULT: True})
    shadowing_corr_m: float = field(default=10.0, metadata={OMIT_DEFAULT: True})
    per: str = field(default="off", metadata={OMIT_DEFAULT: True})
    per_ref: float = field(default=0.1, metadata={OMIT_DEFAULT: True})
    per_ref_bytes: int = field(default=4096, metadata={OMIT_DEFAULT: True})

    def __post_init__(self) -> None:
        check_choice("model", self.model, MODELS)
        check_choice("wall_mode", self.wall_mode, WALL_MODES)
        _set(self, "frequency_ghz", check_float("frequency_ghz", self.frequency_ghz, 0.0, MAX_FREQUENCY_GHZ,
                                                lo_open=True))
        _set(self, "tx_power_dbm", check_float("tx_power_dbm", self.tx_power_dbm))
        _set(self, "sensitivity_dbm", check_float("sensitivity_dbm", self.sensitivity_dbm))
        _set(self, "alpha", check_float("alpha", self.alpha, 0.0))
        _set(self, "beta", check_float("beta", self.beta))
        _set(self, "gamma", check_float("gamma", self.gamma, 0.0))
        _set(self, "graze_tolerance_m", check_float("graze_tolerance_m", self.graze_tolerance_m, 0.0, 0.25))
        if self.max_range_m is not None:
            _set(self, "max_range_m", check_float("max_range_m", self.max_range_m, 0.0, lo_open=True))
            if self.model != "los":
                raise InvalidInput("max_range_m", self.max_range_m, "only with model = 'los' (unset it otherwise)")
        if self.wall_mode != "crossing" and self.model != "multiwall":
            raise InvalidInput("wall_mode", self.wall_mode, "'crossing' unless model = 'multiwall'")
        self._check_channel()
        _set(self, "materials", types.MappingProxyType(_check_materials(self.materials)))
        _set(self, "tx_power_overrides", _check_overrides("tx_power_overrides", self.tx_power_overrides))
        _set(self, "sensitivity_overrides", _check_overrides("sensitivity_overrides", self.sensitivity_overrides))

    def _check_channel(self) -> None:
        """The stochastic channel's settings (shadowing, packet errors)."""
        _set(self, "shadowing_sigma_db", check_float("shadowing_sigma_db", self.shadowing_sigma_db, 0.0,
                                                     MAX_SHADOWING_SIGMA_DB))
        _set(self, "shadowing_corr_m", check_float("shadowing_corr_m", self.shadowing_corr_m, 0.1, 100_000.0))
        check_choice("per", self.per, PER_CURVES)
        _set(self, "per_ref", check_float("per_ref", self.per_ref, 0.0, 1.0, lo_open=True, hi_open=True))
        check_int("per_ref_bytes", self.per_ref_bytes, 1, 1_000_000)
        physical = " or ".join(repr(m) for m in PHYSICAL_MODELS)
        if self.shadowing_sigma_db > 0.0 and self.model not in PHYSICAL_MODELS:
            raise InvalidInput("shadowing_sigma_db", self.shadowing_sigma_db,
                               f"0 unless model = {physical} (model {self.model!r} has no received power to shadow)")
        if self.per != "off" and self.model not in PHYSICAL_MODELS:
            raise InvalidInput("per", self.per, f"'off' unless model = {physical} (model {self.model!r} has no link margin)")

    @property
    def stochastic(self) -> bool:
        """Shadowing or packet errors are on (the channel is more than a fixed threshold)."""
        return self.shadowing_sigma_db > 0.0 or self.per != "off"

    def __hash__(self) -> int:
        return hash(json.dumps(self.to_mapping(), sort_keys=True))

    def to_mapping(self) -> dict[str, Any]:
        """Plain JSON-able form; ``config_from_mapping(c.to_mapping()) == c``."""
        return to_mapping(self)

    def material_table(self) -> dict[str, Material]:
        """The config's materials as :class:`Material` objects (they override the built-in ones)."""
        return {name: Material(name, tuple(e["freq_ghz"]), tuple(e["db"]), e["thickness_m"])
                for name, e in self.materials.items()}

    def tx_power_array(self, n_robots: int) -> np.ndarray:
        """float64[n]: every robot's transmit power (dBm) with the overrides applied."""
        return _per_robot(self.tx_power_dbm, self.tx_power_overrides, n_robots)

    def sensitivity_array(self, n_robots: int) -> np.ndarray:
        """float64[n]: every robot's receiver sensitivity (dBm) with the overrides applied."""
        return _per_robot(self.sensitivity_dbm, self.sensitivity_overrides, n_robots)


def config_from_mapping(data: Mapping[str, Any] | None, prefix: str = "") -> RadioConfig:
    """A :class:`RadioConfig` from a TOML-like mapping (the ``[radio]`` table); unknown keys are errors."""
    return from_mapping(RadioConfig, data, prefix)


def _set(obj: object, name: str, value: Any) -> None:
    object.__setattr__(obj, name, value)


def _check_materials(value: Any) -> dict[str, dict[str, Any]]:
    if not isinstance(value, Mapping):
        raise InvalidInput("materials", value, "a table of material name = dB entries")
    out = {}
    for name in sorted(value, key=lambda k: (not isinstance(k, str), k if isinstance(k, str) else "")):
        material = material_from_value(name, value[name])
        out[name] = {"freq_ghz": material.freq_ghz, "db": material.db, "thickness_m": material.thickness_m}
    return out


def _check_overrides(name: str, value: Any) -> types.MappingProxyType:
    if not isinstance(value, Mapping):
        raise InvalidInput(name, value, "a table of robot id = dBm")
    out: dict[int, float] = {}
    for key, dbm in value.items():
        where = field_name(name, key)
        robot = key
        if isinstance(key, str) and key.isascii() and key.isdigit() and len(key) <= MAX_ROBOT_ID_DIGITS:
            robot = int(key)  # isascii: "\u00b3".isdigit() is true but int() refuses it
        if (not isinstance(robot, (int, np.integer)) or isinstance(robot, bool) or robot < 0
                or robot >= 10**MAX_ROBOT_ID_DIGITS):
            raise InvalidInput(where, key, f"a robot id: an integer in 0..{10**MAX_ROBOT_ID_DIGITS - 1}")
        if int(robot) in out:
            raise InvalidInput(where, key, "each robot id once")
        out[int(robot)] = check_float(where, dbm)
    return types.MappingProxyType(dict(sorted(out.items())))


def _per_robot(default: float, overrides: Mapping[int, float], n_robots: int) -> np.ndarray:
    out = np.full(n_robots, default, dtype=np.float64)
    for robot, dbm in overrides.items():
        if robot < n_robots:
            out[robot] = dbm
    return out
