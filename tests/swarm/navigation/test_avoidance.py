"""Local inter-robot avoidance (issue 50, navigation.avoidance): two robots driven head-on at each other
touch without it and pass each other with it, in the real pymunk world; the setting is validated and left
out of specs while off."""

from __future__ import annotations

import json

import numpy as np
import pytest

from swarm.base.errors import InvalidInput
from swarm.sim.spec import RunSpec
from swarm.world.motion import MotionParams
from swarm.world.physics import World
from tests.swarm.world.test_motion import open_room

pytest.importorskip("navground.core")

from swarm.navigation.avoidance import Avoidance  # noqa: E402


def head_on(kind: str | None, offset: float = 0.05, ticks: int = 120) -> tuple[bool, np.ndarray]:
    """Two robots 8 m apart, facing each other (slightly offset across), each commanded straight ahead at
    full speed every tick; whether they ever touched, and their final poses."""
    motion = MotionParams()
    world = World(open_room(), [[11.0, 15.0, 0.0], [19.0, 15.0 + offset, np.pi]], motion)
    avoid = Avoidance(kind, motion, 2, range_m=3.0) if kind else None
    touched = False
    for _ in range(ticks):
        commands = np.array([[motion.max_speed, 0.0], [motion.max_speed, 0.0]])
        if avoid is not None:
            avoid.adjust(commands, [0, 1], world.poses.copy())
        world.step(commands)
        touched |= any(b >= 0 for _, b in world._contacts)
    return touched, world.poses.copy()


def test_without_avoidance_robots_driven_head_on_collide():
    touched, _ = head_on(None)
    assert touched


@pytest.mark.parametrize("kind", ["orca", "hrvo"])
def test_with_avoidance_they_pass_each_other_without_touching(kind):
    touched, poses = head_on(kind)
    assert not touched
    assert poses[0, 0] > 19.0 and poses[1, 0] < 11.0      # each got past where the other started


def test_the_setting_is_checked_and_left_out_while_off():
    assert "avoidance" not in json.loads(RunSpec.from_mapping({}).to_json())["navigation"]
    assert json.loads(RunSpec.from_mapping({"navigation": {"avoidance": "orca"}}).to_json())["navigation"][
        "avoidance"] == "orca"
    with pytest.raises(InvalidInput, match=r"navigation\.avoidance.*'orca'"):
        RunSpec.from_mapping({"navigation": {"avoidance": "rvo3"}})
