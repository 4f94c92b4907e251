"""Wall materials and their radio attenuation, interpolated in log-frequency.

A :class:`Material` holds the attenuation in dB of **one wall crossing** at a few frequencies. Between the
table frequencies the figure is interpolated linearly in ``log(f)`` and it is clamped outside them, so
1.3 / 2.4 / 5.2 GHz reproduce the table exactly and e.g. 3.5 GHz sits between 2.4 and 5.2 GHz values.

``thickness_m`` is the wall thickness the per-crossing figure stands for; the optional per-metre wall mode
charges ``db / thickness_m`` per metre of wall path. Every default material uses 1.0 m, the nominal wall
of a generated map (one tile), so a right-angle crossing of a generated wall costs the same in both modes.

Sources of the defaults (``DEFAULT_MATERIALS``):

- ``concrete``, ``wood``, ``brick``: Minotaur paper (docs/papers.md; section 4.1, Table 1), taken from
  Ikpehai et al. 2019; the same numbers MAES ships (docs/maes.md section 6.4, "according to NIST").
- ``wall``: MAES's generic PGM wall, 0 dB at every frequency (docs/maes.md section 6.4): it blocks
  line-of-sight but does not attenuate.
- ``glass``: 3GPP TR 38.901 (v16) Table 7.4.3-1, standard multi-pane glass ``L = 2 + 0.2 f`` dB (f in GHz):
  2.26 / 2.48 / 3.04 dB.
- ``drywall``: about 3 dB at 2.4 GHz is the usual WLAN-planning figure for a plasterboard partition (Ekahau
  and Cisco/Airespace design notes quote 3-4 dB); 4 dB at 5.2 GHz. **Approximate**: we found no
  measurement to cite for exactly these numbers; override it for real studies.
- ``metal``: ITU-R P.2040-1 Table 3 gives metal a conductivity of 1e7 S/m (skin depth ~1 um), i.e. a metal
  sheet is opaque. We use 60 dB, an engineering stand-in for "opaque": with the default radio (97 dB
  budget, 40 dB of path loss at 1 m) one crossing always breaks the link.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from collections.abc import Mapping
from typing import Any

import numpy as np

from maps.materials import AIR, check_material_name
from swarm.base.errors import InvalidInput, shorten
from swarm.base.params import check_float

TABLE_FREQUENCIES_GHZ: tuple[float, ...] = (1.3, 2.4, 5.2)
"""The frequencies of the Minotaur paper's Table 1; a bare list of dB values in a config refers to these."""
NOMINAL_THICKNESS_M = 1.0
"""One tile: the wall thickness of generated maps and the default ``thickness_m`` of every material."""


@dataclass(frozen=True)
class Material:
    """Attenuation of one wall crossing, in dB, at ascending frequencies (GHz)."""

    name: str
    freq_ghz: tuple[float, ...]
    db: tuple[float, ...]
    thickness_m: float = NOMINAL_THICKNESS_M

    def __post_init__(self) -> None:
        check_material_name(self.name, "materials")
        field = f"materials.{self.name}"
        freqs = _float_tuple(f"{field}.freq_ghz", self.freq_ghz)
        dbs = _float_tuple(f"{field}.db", self.db)
        if not freqs:
            raise InvalidInput(f"{field}.freq_ghz", self.freq_ghz, "at least one frequency")
        if len(dbs) != len(freqs):
            raise InvalidInput(f"{field}.db", self.db, f"{len(freqs)} values, one per frequency in freq_ghz")
        for i, f in enumerate(freqs):
            check_float(f"{field}.freq_ghz[{i}]", f, 0.0, lo_open=True)
        for i, a in enumerate(dbs):
            check_float(f"{field}.db[{i}]", a, 0.0)
        if any(b <= a for a, b in zip(freqs, freqs[1:])):
            raise InvalidInput(f"{field}.freq_ghz", freqs, "strictly increasing frequencies")
        if self.name == AIR and any(dbs):
            raise InvalidInput(f"{field}.db", dbs, "0 (air is free space and never attenuates)")
        object.__setattr__(self, "freq_ghz", freqs)
        object.__setattr__(self, "db", dbs)
        object.__setattr__(self, "thickness_m", check_float(f"{field}.thickness_m", self.thickness_m, 0.0,
                                                            lo_open=True))

    def crossing_db(self, frequency_ghz: float) -> float:
        """dB for one crossing at ``frequency_ghz``: linear in log-frequency, clamped outside the table."""
        logs = np.log(np.asarray(self.freq_ghz))
        return float(np.interp(math.log(frequency_ghz), logs, np.asarray(self.db)))

    def per_metre_db(self, frequency_ghz: float) -> float:
        """dB per metre of wall path: the crossing figure spread over ``thickness_m``."""
        return self.crossing_db(frequency_ghz) / self.thickness_m

    def to_mapping(self) -> dict[str, Any]:
        """The canonical config form (what :func:`material_from_value` reads back)."""
        return {"freq_ghz": list(self.freq_ghz), "db": list(self.db), "thickness_m": self.thickness_m}


def _float_tuple(field: str, value: Any) -> tuple[float, ...]:
    if isinstance(value, (str, bytes)) or not hasattr(value, "__iter__"):
        raise InvalidInput(field, value, "a list of numbers")
    out = []
    for i, v in enumerate(value):
        out.append(check_float(f"{field}[{i}]", v))
    return tuple(out)


def _table(name: str, db: tuple[float, float, float]) -> Material:
    return Material(name, TABLE_FREQUENCIES_GHZ, db)


DEFAULT_MATERIALS: Mapping[str, Material] = {
    m.name: m
    for m in (
        _table(AIR, (0.0, 0.0, 0.0)),
        _table("concrete", (13.0, 15.0, 23.0)),
        _table("wood", (5.1, 6.7, 14.0)),
        _table("brick", (4.5, 5.5, 15.0)),
        _table("wall", (0.0, 0.0, 0.0)),
        _table("glass", (2.26, 2.48, 3.04)),
        _table("drywall", (3.0, 3.0, 4.0)),
        _table("metal", (60.0, 60.0, 60.0)),
    )
}
"""Built-in materials (see the module docstring for the source of every figure). Their names are
``maps.materials.KNOWN_MATERIALS``, the vocabulary map generators, importers and legends accept (tested)."""

_ENTRY_KEYS = ("freq_ghz", "db", "thickness_m")


def material_from_value(name: str, value: Any) -> Material:
    """Parse one ``[radio.materials]`` entry.

    Accepted forms: a number (the same dB at every frequency); a list of dB at 1.3 / 2.4 / 5.2 GHz (the
    paper's Table 1 columns); or a table ``{db = [...] | number, freq_ghz = [...], thickness_m = 1.0}``
    (``freq_ghz`` defaults to the Table 1 frequencies when ``db`` is a list of three).
    """
    check_material_name(name, "materials")
    field = f"materials.{name}"
    if isinstance(value, Material):
        if value.name != name:
            raise InvalidInput(field, value.name, f"a Material named {name!r}")
        return value
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return Material(name, (1.0,), (check_float(field, value, 0.0),))
    if isinstance(value, (list, tuple)):
        return _from_list(name, field, value, TABLE_FREQUENCIES_GHZ, NOMINAL_THICKNESS_M)
    if isinstance(value, Mapping):
        for key in value:
            if key not in _ENTRY_KEYS:
                raise InvalidInput(f"{field}.{key}", value[key], f"a key of a material: {', '.join(_ENTRY_KEYS)}")
        if "db" not in value:
            raise InvalidInput(field, dict(value), "a table with db = a number or a list of numbers")
        thickness = value.get("thickness_m", NOMINAL_THICKNESS_M)
        db = value["db"]
        if isinstance(db, (int, float)) and not isinstance(db, bool):
            if "freq_ghz" in value:
                raise InvalidInput(f"{field}.freq_ghz", value["freq_ghz"], "no frequencies when db is one number")
            return Material(name, (1.0,), (check_float(f"{field}.db", db, 0.0),), thickness)
        return _from_list(name, f"{field}.db", db, value.get("freq_ghz", TABLE_FREQUENCIES_GHZ), thickness)
    raise InvalidInput(field, value,
                       "dB as a number, a list at 1.3/2.4/5.2 GHz, or a table {db, freq_ghz, thickness_m}")


def _from_list(name: str, field: str, db: Any, freqs: Any, thickness: Any) -> Material:
    if not isinstance(db, (list, tuple)):
        raise InvalidInput(field, db, "a number or a list of numbers")
    if freqs is TABLE_FREQUENCIES_GHZ and len(db) != len(TABLE_FREQUENCIES_GHZ):
        raise InvalidInput(field, db, "3 values: dB at 1.3, 2.4 and 5.2 GHz (or give freq_ghz too)")
    if not isinstance(freqs, (list, tuple)):
        raise InvalidInput(f"materials.{name}.freq_ghz", freqs, "a list of frequencies in GHz, one per db value")
    return Material(name, tuple(freqs), tuple(db), thickness)


def resolve_table(names: tuple[str, ...], overrides: Mapping[str, Material]) -> tuple[Material, ...]:
    """The :class:`Material` for each of a map's material names (config entries win over the defaults).

    An unknown name is an :class:`InvalidInput` naming it and listing what is defined, so a map whose walls
    the radio cannot price fails at build time rather than silently costing 0 dB.
    """
    known = {**DEFAULT_MATERIALS, **overrides}
    out = []
    for name in names:
        if name not in known:
            raise InvalidInput("material", name,
                               f"a material the radio defines ({shorten(', '.join(sorted(known)), 200)}); "
                               f"add it under [radio.materials]")
        out.append(known[name])
    return tuple(out)
