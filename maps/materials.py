"""Material names used by maps, and their rendering colours.

A map stores a small material table ``id -> name``; id 0 is always ``"air"`` (free space). The radio
package resolves names to attenuation figures, so a map file never carries physics numbers, only names.

**Vocabulary.** :data:`KNOWN_MATERIALS` are the names the radio's built-in table prices
(``radio.materials.DEFAULT_MATERIALS`` has exactly these; ``maps`` cannot import ``radio``, so the list
lives here). Where a user *types* a material name (generator parameters, importer options, legend
colours) it must be one of them, or, for a legend, one the legend declares in its ``materials`` list: a
typo such as ``concrette`` is an error up front instead of a map the radio refuses later. A :class:`Map`
itself (a file, or one built in Python) may carry any valid name: the radio resolves it at build time
and refuses names that neither its built-in table nor the run's ``[radio.materials]`` define.
"""

from __future__ import annotations

import hashlib
import math
import re
from collections.abc import Mapping
from typing import Any

from swarm.base.errors import InvalidInput, field_name, shorten
from swarm.base.params import check_float

AIR = "air"
DEFAULT_WALL_MATERIALS: tuple[str, ...] = ("concrete", "wood", "brick")
DEFAULT_TABLE: tuple[str, ...] = (AIR, *DEFAULT_WALL_MATERIALS)

KNOWN_MATERIALS: tuple[str, ...] = (AIR, "concrete", "wood", "brick", "wall", "glass", "drywall", "metal")
"""Every material the built-in radio table defines; all but ``air`` are wall materials."""
KNOWN_WALL_MATERIALS: tuple[str, ...] = KNOWN_MATERIALS[1:]

_NAME_RE = re.compile(r"^[a-z][a-z0-9_\-]{0,31}$")

#: RGB colours for rendering; unknown materials get a stable colour derived from their name.
COLOURS: dict[str, tuple[int, int, int]] = {
    AIR: (250, 250, 247),
    "concrete": (110, 112, 118),
    "wood": (160, 110, 60),
    "brick": (178, 60, 45),
    "glass": (120, 190, 220),
    "drywall": (215, 205, 180),
    "metal": (70, 90, 120),
    "wall": (40, 40, 40),
}


def check_material_name(name: object, field: str = "material") -> str:
    """Return ``name`` if it is a valid material name (lower-case identifier), else raise."""
    if not isinstance(name, str) or not _NAME_RE.match(name):
        raise InvalidInput(field, name, "a lower-case name of 1-32 letters, digits, '_' or '-', starting with a letter")
    return name


def check_known_material(name: object, field: str = "material", declared: tuple[str, ...] = ()) -> str:
    """Return ``name`` if it is a known wall material (or one in ``declared``), else raise naming ``field``.

    ``air`` is never a wall material. The message lists the allowed names.
    """
    allowed = f"a wall material: {', '.join(KNOWN_WALL_MATERIALS)}"
    if declared:
        allowed += f" (or one the legend declares: {shorten(', '.join(declared))})"
    if not isinstance(name, str) or name == AIR or (name not in KNOWN_WALL_MATERIALS and name not in declared):
        raise InvalidInput(field, name, allowed)
    return name


def colour_of(name: str) -> tuple[int, int, int]:
    """Rendering colour of a material; stable across runs for names we do not know."""
    if name in COLOURS:
        return COLOURS[name]
    digest = hashlib.sha256(name.encode()).digest()
    return (60 + digest[0] % 150, 60 + digest[1] % 150, 60 + digest[2] % 150)


def check_table(table: tuple[str, ...]) -> tuple[str, ...]:
    """Validate a material table: id 0 is air, names unique and valid, at most 255 entries."""
    if not table or table[0] != AIR:
        raise InvalidInput("materials", table, f"a table whose entry 0 is {AIR!r}")
    if len(table) > 255:
        raise InvalidInput("materials", len(table), "at most 255 materials")
    for i, name in enumerate(table):
        check_material_name(name, f"materials[{i}]")
    if len(set(table)) != len(table):
        raise InvalidInput("materials", table, "unique names")
    return tuple(table)


def check_weights(name: str, value: Any) -> tuple[tuple[str, float], ...]:
    """A non-empty mapping known wall material -> non-negative weight with a positive, finite sum, as sorted
    pairs (generators' ``materials`` tables)."""
    if not isinstance(value, Mapping) or not value:
        raise InvalidInput(name, value, "a non-empty table of material = weight")
    pairs = []
    for key, w in value.items():
        check_known_material(key, field_name(name, key))
        check_float(field_name(name, key), w, 0.0)
        pairs.append((key, float(w)))
    total = sum(w for _, w in pairs)
    if not 0 < total < math.inf:
        raise InvalidInput(name, dict(value), "weights with a positive, finite sum")
    return tuple(sorted(pairs))
