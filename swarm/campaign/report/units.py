"""Simulated time in the report: the one place ticks become seconds (figures, comm metrics, rates)."""

from __future__ import annotations

from typing import Any

import numpy as np


def seconds(ticks: Any) -> Any:
    """Ticks as simulated seconds, with the motion model's ``TICK_S`` (imported on first use: the report's
    modules load without the simulator's)."""
    from swarm.world.motion import TICK_S

    return np.asarray(ticks, dtype=np.float64) * TICK_S
