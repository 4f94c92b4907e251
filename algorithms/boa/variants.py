"""The seven BOA-family variants (plus xABOA) as data: which strategy piece fills each slot.

A variant is a frozen record of slot names; the engine (``engine.py``) maps the names to the operators in
``operators.py``, the r-sources in ``draws.py`` and the schedules in ``schedules.py``. Adding a variant is
adding one entry to :data:`VARIANTS`. Slots follow docs/boa.md section 10.3.

| variant   | global move        | local move      | fragrance | schedule | r     | local accept | extra        |
|-----------|--------------------|-----------------|-----------|----------|-------|--------------|--------------|
| BOA       | Eq. 2              | Eq. 3           | c|F|^a    | Arora c  | r1*r2 | greedy       |              |
| xBOA      | crossover          | Eq. 3           | c|F|^a    | Arora c  | r1*r2 | always       |              |
| xABOA     | crossover          | Eq. 3           | c|F|^a    | ABOA     | r1*r2 | always       |              |
| mBOA      | Eq. 2              | Eq. 3           | c|F|^a    | Arora c  | r1*r2 | greedy       | intensive    |
| ABOA      | Eq. 2              | Eq. 3           | c|F|^a    | ABOA     | r1*r2 | greedy       |              |
| SABOA     | g*+f(x-g*)         | 0.5(g*+xw)f     | u(1-t/T)  | none     | -     | greedy       |              |
| IBOA-Kent | Eq. 7 (w)          | Eq. 8 (w)       | c|F|^a    | Arora c  | Kent  | greedy       | lens OBL     |
| IBOA-Levy | Eq. 9 (inertia W)  | Eq. 5 (Levy)    | c|F|^a    | Arora c  | r**2  | greedy       |              |
"""

from __future__ import annotations

from dataclasses import dataclass

from swarm.api import InvalidInput


@dataclass(frozen=True)
class Variant:
    """Slot names of one variant (see the module table)."""

    name: str
    global_move: str        # "boa" | "crossover" | "saboa"
    local_move: str         # "boa" | "levy" | "saboa"
    fragrance: str          # "power" | "saboa"
    schedule: str           # "arora" | "aboa" | "none"
    r_source: str           # "product" | "square" | "kent"
    local_accept: str       # "greedy" | "always"
    weight: str = "none"    # "none" | "kent" (adaptive w, Eqs. 6-8) | "levy" (inertia W, Eqs. 8-9)
    post: str = "none"      # "none" | "mboa" (intensive trial) | "obl" (convex-lens OBL on the best)


VARIANTS: dict[str, Variant] = {v.name: v for v in (
    Variant("BOA", "boa", "boa", "power", "arora", "product", "greedy"),
    Variant("xBOA", "crossover", "boa", "power", "arora", "product", "always"),
    Variant("xABOA", "crossover", "boa", "power", "aboa", "product", "always"),
    Variant("mBOA", "boa", "boa", "power", "arora", "product", "greedy", post="mboa"),
    Variant("ABOA", "boa", "boa", "power", "aboa", "product", "greedy"),
    Variant("SABOA", "saboa", "saboa", "saboa", "none", "product", "greedy"),
    Variant("IBOA-Kent", "boa", "boa", "power", "arora", "kent", "greedy", weight="kent", post="obl"),
    Variant("IBOA-Levy", "boa", "levy", "power", "arora", "square", "greedy", weight="levy"),
)}

#: The issue's seven (xABOA is an extra combination from the reference code).
FAMILY: tuple[str, ...] = ("BOA", "xBOA", "mBOA", "ABOA", "SABOA", "IBOA-Kent", "IBOA-Levy")

_ALIASES = {name.lower().replace("_", "-"): name for name in VARIANTS}


def get_variant(name: str | Variant) -> Variant:
    """A variant by name, case-insensitive, ``_`` or ``-`` (``"iboa_kent"`` works); a Variant passes through."""
    if isinstance(name, Variant):
        return name
    key = str(name).lower().replace("_", "-") if isinstance(name, str) else None
    if key not in _ALIASES:
        raise InvalidInput("variant", name, " | ".join(VARIANTS))
    return VARIANTS[_ALIASES[key]]
