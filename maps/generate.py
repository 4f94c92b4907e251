"""One entry point for every generator: ``generate(kind, size, seed, params)``."""

from __future__ import annotations

from typing import Any, Mapping

from swarm.base.errors import InvalidInput
from swarm.base.params import from_mapping
from .building import BuildingParams, generate_building
from .cave import CaveParams, generate_cave
from .model import Map

MIN_SIZE_TILES = 20
MAX_SIZE_TILES = 2000
GENERATORS = {"cave": (CaveParams, generate_cave), "building": (BuildingParams, generate_building)}


def parse_size(size: Any) -> tuple[int, int]:
    """``100`` -> (100, 100); ``(120, 80)`` or ``"120x80"`` -> (120, 80) tiles (width, height)."""
    original = size
    if isinstance(size, str):
        parts = size.lower().split("x")
        try:
            size = tuple(int(s) for s in parts) if len(parts) == 2 else int(size)
        except ValueError:
            raise InvalidInput("size", size, "tiles per side as N or WxH, e.g. 100 or 120x80") from None
    if isinstance(size, int) and not isinstance(size, bool):
        size = (size, size)
    if (not isinstance(size, (tuple, list)) or len(size) != 2
            or not all(isinstance(s, int) and not isinstance(s, bool) for s in size)):
        raise InvalidInput("size", size, "tiles per side as N or (W, H)")
    w, h = size
    for v in (w, h):
        if not MIN_SIZE_TILES <= v <= MAX_SIZE_TILES:
            raise InvalidInput("size", original, f"integers in {MIN_SIZE_TILES}..{MAX_SIZE_TILES} tiles per side")
    return int(w), int(h)


def params_for(kind: str, params: Mapping[str, Any] | None = None) -> Any:
    """The validated parameter dataclass for a generator kind."""
    if kind not in GENERATORS:
        raise InvalidInput("kind", kind, " | ".join(GENERATORS))
    cls, _ = GENERATORS[kind]
    return from_mapping(cls, params, prefix=f"{kind}.")


def generate(kind: str, size: Any = 50, seed: int = 0, params: Mapping[str, Any] | None = None) -> Map:
    """Generate a map: a pure function of (kind, size, seed, params)."""
    p = params_for(kind, params)
    if not isinstance(seed, int) or isinstance(seed, bool) or not 0 <= seed < 2**63:
        raise InvalidInput("seed", seed, "an integer in 0..2**63-1")
    w, h = parse_size(size)
    _, fn = GENERATORS[kind]
    return fn(w, h, seed, p)
