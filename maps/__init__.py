"""Ground truth for swarm: the :class:`Map` raster, cave and building generators, import/export, rendering."""

from swarm.base.errors import InvalidInput

from .generate import generate, params_for, parse_size
from .model import CELL_M, CELLS_PER_TILE, Map
from .rects import WallRect

__all__ = ["CELL_M", "CELLS_PER_TILE", "InvalidInput", "Map", "WallRect", "generate", "params_for", "parse_size"]
