"""The radio channel: materials, path loss (Minotaur paper eq. 1), wall crossings and link models.

``build_link_model(truth, config)`` once per run, then ``model.evaluate(positions)`` once per tick gives the
distance, walls, RSSI and link matrices (``rssi[i, j]`` / ``link[i, j]``: robot i receiving from j), with
optional log-normal shadowing (:mod:`radio.shadowing`) and a packet error curve (:mod:`radio.per`).
"""

from .config import MODELS, WALL_MODES, RadioConfig, config_from_mapping
from .crossings import DEFAULT_GRAZE_TOLERANCE_M, WallCrossing
from .materials import DEFAULT_MATERIALS, Material, material_from_value
from .models import (Global, LineOfSight, LinkBudget, LinkModel, LinkState, MaesCompatible, MultiWall,
                     build_link_model)
from .pathloss import path_loss_db
from .per import PER_CURVES, PacketErrorCurve
from .shadowing import ShadowingField

__all__ = [
    "DEFAULT_GRAZE_TOLERANCE_M", "DEFAULT_MATERIALS", "MODELS", "WALL_MODES", "Global", "LineOfSight",
    "LinkBudget", "LinkModel", "LinkState", "MaesCompatible", "Material", "MultiWall", "PER_CURVES",
    "PacketErrorCurve", "RadioConfig", "ShadowingField", "WallCrossing", "build_link_model", "config_from_mapping",
    "material_from_value", "path_loss_db",
]
