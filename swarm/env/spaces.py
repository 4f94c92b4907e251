"""Gymnasium spaces of the environments' observations and actions (shared by both environments)."""

from __future__ import annotations

import numpy as np
from gymnasium import spaces

from .config import SECTORS
from .core import INBOX_FIELDS, NEIGHBOUR_FIELDS, POSE_FIELDS, ExplorationCore


def observation_space(core: ExplorationCore) -> spaces.Dict:
    """``map`` uint8 (crop, crop) with 0 unseen, 1 free, 2 solid, 3 outside the map; ``pose``, ``neighbours``,
    ``inbox`` and (goal mode) ``choices`` float32 in [-1, 1] (see :mod:`swarm.env.core` for the fields)."""
    side = core.config.crop_cells
    parts = {
        "map": spaces.Box(0, 3, (side, side), dtype=np.uint8),
        "pose": spaces.Box(-1.0, 1.0, (len(POSE_FIELDS),), dtype=np.float32),
        "neighbours": spaces.Box(-1.0, 1.0, (max(core.n - 1, 1), len(NEIGHBOUR_FIELDS)), dtype=np.float32),
        "inbox": spaces.Box(0.0, 1.0, (len(INBOX_FIELDS),), dtype=np.float32),
    }
    if core.config.action == "goal":
        parts["choices"] = spaces.Box(-1.0, 1.0, (SECTORS, 3), dtype=np.float32)
    return spaces.Dict(parts)


def action_space(core: ExplorationCore) -> spaces.Space:
    """Goal mode: ``Discrete(9)`` (``10`` with ``delegate``); velocity mode: ``Box(-1, 1, (2,))``."""
    if core.config.action == "goal":
        return spaces.Discrete(core.config.n_actions)
    return spaces.Box(-1.0, 1.0, (2,), dtype=np.float32)

