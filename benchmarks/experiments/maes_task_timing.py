"""How many logic ticks MAES's two tasks take, against swarm's MAES motion model (issue 49 row 3).

MAES's side is its own arithmetic replayed in one dimension: ``FiniteMovementTask.GetNextDirective`` and
``FiniteRotationTask.GetNextDirective`` (``Assets/Scripts/Robot/Task/``, commit 1bb0312) once per 10 ms
physics step, the directive's force applied twice per step (``Robot2DController.cs`` 182, 192) at the two
wheels (``MoveForce`` 15, ``RotateForce`` 5, wheels 0.264 tiles from the centre), on MAES's rigid body
(mass 1, radius 0.297, linear drag 20, angular drag 30) integrated as Box2D does (velocity, then damping
``v / (1 + dt drag)``, then position). A task counts as done at the first logic tick (every 10 physics
steps) after it completed with the wheels slower than 0.01 tiles per step (``UpdateMotorPhysics`` 149-162:
the robot is then Idle). swarm's side drives ``swarm.navigation.maes_drive.MaesDrive`` in the pymunk world
with ``MotionParams.maes()``. Prints both per distance and angle::

    python benchmarks/experiments/maes_task_timing.py
"""

from __future__ import annotations

import math

import numpy as np

from maps import Map
from swarm.base.types import FREE, SOLID, Pose
from swarm.navigation.maes_drive import MaesDrive
from swarm.navigation.spec import NavigationSpec
from swarm.world.motion import MotionParams
from swarm.world.physics import World

DT, DRAG, ANGULAR_DRAG, MASS, RADIUS, WHEEL = 0.01, 20.0, 30.0, 1.0, 0.297, 0.264
INERTIA = 0.5 * MASS * RADIUS ** 2


def maes_move_ticks(distance: float) -> tuple[int, float]:
    """Logic ticks until MAES's FiniteMovementTask of ``distance`` is done and the robot idle; the end error."""
    x = v = 0.0
    previous = 0.0
    done = False
    for step in range(1, 100_000):
        if not done:
            remaining = distance - x
            if remaining > 0.1:
                per_step = abs(x - previous)
                previous = x
                stop_ticks = int(11.0 * (math.log(per_step) + 3 * math.log(10)) / 2.0) if per_step > 0 else -2 ** 31
                stop_distance = 11.0 * per_step / 2.0 + 11.0 * per_step / 2.0   # (-2 / 11) is 0: e^0 twice
                del stop_ticks
                factor = 1.0 if stop_distance <= remaining - 0.01 else 0.0
            else:
                done, factor = True, 0.0
        else:
            factor = 0.0
        force = 2 * 2 * 15.0 * factor        # two wheels, applied twice per physics step
        v = (v + DT * force / MASS) / (1 + DT * DRAG)
        x += DT * v
        if done and step % 10 == 0 and v * DT < 0.01:
            return step // 10, distance - x
    raise RuntimeError("never idle")


def maes_rotation_ticks(degrees: float) -> tuple[int, float]:
    """Logic ticks until MAES's FiniteRotationTask of ``degrees`` is done and the robot idle; the end error."""
    a = w = 0.0          # degrees turned, rad/s
    previous = 0.0
    done = False
    for step in range(1, 100_000):
        if not done:
            rate = a - previous
            previous = a
            ticks = int(-3.81 * math.log(0.01 / rate)) if rate > 0 else 0
            before_stop = sum(rate * math.exp(-(i + 1) / 3.81) for i in range(max(ticks, 0)))
            delta = abs(degrees) - a - before_stop
            factor = 1.0
            if delta < 2.28:
                factor = (1 / 2.28) * delta * 0.85
            if delta < 0.1:
                factor, done = 0.0, True
        else:
            factor = 0.0
        torque = 2 * 2 * 5.0 * factor * WHEEL   # two wheels in opposite directions, applied twice
        w = (w + DT * torque / INERTIA) / (1 + DT * ANGULAR_DRAG)
        a += math.degrees(DT * w)
        if done and step % 10 == 0 and w * WHEEL * DT < 0.01:
            return step // 10, abs(degrees) - a
    raise RuntimeError("never idle")


def swarm_ticks(goal_pose: tuple[float, float, float], drive: str) -> int:
    """Ticks swarm's MAES drive takes from (10.5, 10.5) facing +x to stop at the goal tile's centre."""
    solid = np.ones((60, 60), dtype=bool)
    solid[1:-1, 1:-1] = False
    truth = Map(solid=solid, material=solid.astype(np.uint8), materials=("air", "concrete"))
    known = np.where(solid, SOLID, FREE).astype(np.uint8)
    world = World(truth, [[10.5, 10.5, 0.0]], MotionParams.maes())
    nav = MaesDrive(NavigationSpec(), MotionParams.maes())
    nav.set_goal(goal_pose[:2], drive)
    for tick in range(1000):
        command = nav.command(Pose(*world.poses[0].tolist()), known)
        if nav.state != "moving":
            return tick
        world.step([command])
    raise RuntimeError("never arrived")


def main() -> None:
    print("| task | MAES ticks (end error) | swarm's MAES drive ticks |")
    print("|---|---|---|")
    for distance in (1, 2, 5):
        t, err = maes_move_ticks(float(distance))
        ours = swarm_ticks((10.5 + distance, 10.5, 0.0), "straight")
        print(f"| move {distance} m | {t} ({err:+.3f} m) | {ours} |")
    for dx, dy in ((3, 3), (0, 3), (-3, 0)):
        degrees, distance = math.degrees(math.atan2(dy, dx)), math.hypot(dx, dy)
        t, err = maes_rotation_ticks(degrees)
        move, _ = maes_move_ticks(distance)
        ours = swarm_ticks((10.5 + dx, 10.5 + dy, 0.0), "straight")
        print(f"| turn {degrees:.0f} deg, then move {distance:.2f} m | {t} ({err:+.2f} deg) + {move} = {t + move} | {ours} |")

if __name__ == "__main__":
    main()
