"""MAES's controller as a motion model (swarm.navigation.maes_drive, issue 49 row 3): hand-built cases of
``PathAndMoveTo`` (turn in place, move one tile, stop), ``MoveTo`` (one straight move) and TNF's runs,
driven in the real pymunk world, and the model selected by a run spec."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import swarm
from maps import Map
from swarm.base.errors import InvalidInput
from swarm.base.types import FREE, SOLID, Pose
from swarm.navigation.maes_drive import (MaesDrive, MaesDriveFleet, PASSED_M, coarse_open, path_runs, tile_centre,
                                         tile_of)
from swarm.navigation.spec import NavigationSpec
from swarm.sim.spec import RunSpec
from swarm.world.motion import TICK_S, MotionParams
from swarm.world.physics import World

MAES = MotionParams(max_speed=3.0, max_turn_rate=4.0, max_accel=60.0, max_turn_accel=120.0, substeps=8, model="maes")


def room(width_cells: int = 40, height_cells: int = 40, walls: list[tuple[int, int]] = ()) -> Map:
    solid = np.ones((height_cells, width_cells), dtype=bool)
    solid[1:-1, 1:-1] = False
    for cell in walls:
        solid[cell] = True
    return Map(solid=solid, material=solid.astype(np.uint8), materials=("air", "concrete"))


def known_of(truth: Map) -> np.ndarray:
    return np.where(truth.solid, SOLID, FREE).astype(np.uint8)


class Trace:
    """Drives one MaesDrive in a World tick by tick, as the runtime does, and keeps what happened."""

    def __init__(self, truth: Map, pose: tuple[float, float, float], motion: MotionParams = MAES) -> None:
        self.world = World(truth, [list(pose)], motion)
        self.known = known_of(truth)
        self.fleet = MaesDriveFleet(NavigationSpec(), motion, [np.random.default_rng(0)])
        self.drive = self.fleet.navigators[0]
        self.tasks: list[str] = []        # "rotate" / "move" as each starts
        self.poses: list[np.ndarray] = []
        self.commands: list[tuple[float, float]] = []
        self.was_colliding = np.zeros(1, dtype=bool)

    def run(self, goal: tuple[float, float], drive: str, max_ticks: int = 400) -> int:
        """Ticks until the goal is no longer ``moving`` (reached, unreachable or blocked)."""
        self.drive.set_goal(goal, drive)
        for tick in range(max_ticks):
            pose = Pose(*self.world.poses[0].tolist())
            collided = self.world.collided.copy()
            began = collided > self.was_colliding
            self.was_colliding = collided
            before = self.drive.tasks
            out = np.zeros((1, 2))
            self.fleet.command([0], self.world.poses, [pose], self.known[None], out, began)
            if self.drive.tasks > before:
                self.tasks.append(self.drive.last_task)
            self.poses.append(self.world.poses[0].copy())
            self.commands.append((float(out[0, 0]), float(out[0, 1])))
            if self.drive.state != "moving":
                return tick
            self.world.step(out)
        pytest.fail(f"the drive was still moving after {max_ticks} ticks")


def test_coarse_tiles_are_open_only_when_all_four_cells_are_seen_free() -> None:
    known = np.full((4, 6), FREE, dtype=np.uint8)
    known[0, 0] = 0          # one unseen cell closes tile (0, 0)
    known[3, 5] = SOLID      # one solid cell closes tile (1, 2)
    assert coarse_open(known).tolist() == [[False, True, True], [True, True, False]]
    odd = np.full((3, 3), FREE, dtype=np.uint8)   # cells beyond the map count as solid
    assert coarse_open(odd).tolist() == [[True, False], [False, False]]


def test_path_runs_end_where_the_direction_changes() -> None:
    """AStar.PathToSteps: one step per straight run (AStar.cs 228-257)."""
    tiles = np.array([[5, 5], [5, 6], [5, 7], [6, 8], [7, 9], [8, 9], [9, 9]])
    assert path_runs(tiles).tolist() == [[5, 7], [7, 9], [9, 9]]
    assert path_runs(tiles[:1]).tolist() == [[5, 5]]


def test_a_path_of_three_tiles_turns_once_then_moves_and_stops_at_each_tile() -> None:
    """PathAndMoveTo (Robot2DController.cs 359-397): facing +y, a goal three tiles to the east is one
    rotation in place and three one-tile moves, each from rest; it takes longer than the continuous
    follower's single drive, and no shorter than the tasks' kinematic minimum."""
    start, goal = (5.5, 5.5, math.pi / 2), (8.5, 5.5)
    trace = Trace(room(), start)
    ticks = trace.run(goal, "path")
    assert trace.drive.state == "reached"
    assert trace.tasks == ["rotate", "move", "move", "move"]
    x, y, _ = trace.poses[-1]
    assert math.hypot(x - goal[0], y - goal[1]) < PASSED_M
    # the robot turned in place: it did not leave its tile's centre before facing east
    first_move = next(i for i, (v, _) in enumerate(trace.commands) if v > 0)
    assert np.allclose(trace.poses[first_move][:2], start[:2], atol=1e-6)
    assert abs(trace.poses[first_move][2]) < math.radians(1.5)
    # it stopped at each tile centre: near 6.5 and 7.5 it was slower than 1 m/s (MAES's idle threshold,
    # a wheel moving less than 0.01 m per 10 ms physics step, Robot2DController.cs 154) after cruising faster
    xs = np.array([p[0] for p in trace.poses])
    speed = np.abs(np.diff(xs)) / TICK_S
    assert speed.max() > 2.0
    for centre in (6.5, 7.5):
        near = int(np.argmin(np.abs(xs[:-1] - centre)))
        assert abs(xs[near] - centre) < 0.05 and speed[near - 1:near + 1].min() < 1.0, (centre, xs.round(2))
    # kinematics: a quarter turn at 4 rad/s and three 1 m moves at 3 m/s, each whole ticks at least
    minimum = math.ceil(math.pi / 2 / 4.0 / TICK_S) + 3 * math.ceil(1.0 / 3.0 / TICK_S)
    assert ticks >= minimum
    continuous = MotionParams(max_speed=3.0, max_turn_rate=4.0, max_accel=60.0, max_turn_accel=120.0, substeps=8)
    smooth = swarm_ticks_continuous(start, goal, continuous)
    assert ticks > smooth + 2   # the stops cost ticks


def swarm_ticks_continuous(start: tuple[float, float, float], goal: tuple[float, float], motion: MotionParams) -> int:
    from swarm.navigation.navigator import NavigationFleet

    truth = room()
    world = World(truth, [list(start)], motion)
    fleet = NavigationFleet(NavigationSpec(), motion, [np.random.default_rng(0)])
    nav = fleet.navigators[0]
    nav.set_goal(goal)
    known = known_of(truth)
    for tick in range(400):
        out = np.zeros((1, 2))
        fleet.command([0], world.poses, [Pose(*world.poses[0].tolist())], known[None], out)
        if nav.state != "moving" and nav.state != "planning":
            return tick
        world.step(out)
    pytest.fail("the continuous navigator never arrived")


def test_runs_turn_only_where_the_path_bends() -> None:
    """TNF's following (TnfExplorationAlgorithm.cs 373-389): around a block the path is a few straight
    runs, each one turn (if needed) and one move; tile by tile it is a move per tile."""
    start, goal = (3.5, 3.5, 0.0), (8.5, 8.5)
    walls = [(r, c) for r in range(10, 24) for c in range(1, 16)]   # x 0.5-8 m, y 5-12 m: go east, then north
    truth = room(walls=walls)
    tile_trace = Trace(truth, start)
    tile_trace.run(goal, "path")
    run_trace = Trace(truth, start)
    run_trace.run(goal, "runs")
    assert tile_trace.drive.state == run_trace.drive.state == "reached"
    tiles = np.array(_tile_path(truth, start, goal))
    assert tile_trace.tasks.count("move") == len(tiles) - 1
    assert run_trace.tasks.count("move") == len(path_runs(tiles)) < len(tiles) - 1


def _tile_path(truth: Map, start: tuple[float, float, float], goal: tuple[float, float]) -> list[list[int]]:
    from swarm import grid

    space = coarse_open(known_of(truth))
    return grid.plan(space, tile_of(*start[:2]), tile_of(*goal)).tolist()


def test_a_straight_move_plans_nothing_and_turns_first() -> None:
    """MoveTo (Robot2DController.cs 403-409): turn while more than 0.5 degrees off, then one move."""
    trace = Trace(room(), (5.5, 5.5, math.pi))
    trace.run((9.5, 8.5), "straight")
    assert trace.drive.state == "reached"
    assert trace.tasks == ["rotate", "move"]
    assert trace.drive.plans == 0


def test_a_straight_move_into_a_wall_ends_blocked_on_this_side() -> None:
    """No plan: the move runs into the wall, the contact ends the task, and the goal is reported blocked
    instead of pushing for ever; the robot never crosses the wall."""
    walls = [(r, 20) for r in range(1, 39)]          # a wall at x = 10..10.5 m from top to bottom
    trace = Trace(room(walls=walls), (5.5, 10.5, 0.0))
    trace.run((15.5, 10.5), "straight", max_ticks=300)
    assert trace.drive.state == "blocked"
    assert max(p[0] for p in trace.poses) < 10.0


def test_a_collision_ends_the_task_under_way() -> None:
    drive = MaesDrive(NavigationSpec(), MAES)
    fleet = MaesDriveFleet(NavigationSpec(), MAES, [np.random.default_rng(0)])
    fleet.navigators[0] = drive
    known = known_of(room())[None]
    drive.set_goal((15.5, 5.5), "straight")
    pose = Pose(5.5, 5.5, 0.0)
    out = np.zeros((1, 2))
    fleet.command([0], np.array([[5.5, 5.5, 0.0]]), [pose], known, out, np.array([False]))
    assert drive._task is not None and out[0, 0] > 0
    fleet.command([0], np.array([[5.5, 5.5, 0.0]]), [pose], known, out, np.array([True]))
    assert drive.tasks == 2 and drive.state == "moving"   # ended by the contact, then started again
    fleet.command([], np.array([[5.5, 5.5, 0.0]]), [pose], known, np.zeros((1, 2)), np.array([False]))
    assert drive._task is None                              # driving by velocity ends it too


def test_a_new_goal_waits_for_the_task_under_way() -> None:
    """MAES's algorithms may ask every tick; the controller acts only when idle."""
    trace = Trace(room(), (5.5, 5.5, 0.0))
    trace.drive.set_goal((12.5, 5.5), "path")
    pose = Pose(5.5, 5.5, 0.0)
    trace.drive.command(pose, trace.known)
    task = trace.drive._task
    assert task is not None and task[0] == 1.0               # a move east, one tile
    trace.drive.set_goal((5.5, 12.5), "path")
    trace.drive.command(Pose(5.8, 5.5, 0.0), trace.known)
    assert trace.drive._task == task                         # still the same move


def test_a_tile_that_turned_solid_is_skipped() -> None:
    """PathAndMoveTo line 372: when the robot is idle and its current path tile has turned solid, it goes on
    to the next one. MAES checks before it moves on from a reached tile (374-378), so a solid tile just
    dequeued is driven at once and skipped on the next idle tick; so here."""
    trace = Trace(room(), (5.5, 5.5, 0.0))
    drive = trace.drive
    drive.set_goal((9.5, 5.5), "path")
    drive.command(Pose(5.5, 5.5, 0.0), trace.known)   # plans tiles (5,5)..(5,9), moves to (5,6)
    trace.known[10:12, 14:16] = SOLID                 # tile (5, 7) seen solid
    drive._task = None
    drive.command(Pose(6.5, 5.5, 0.0), trace.known)   # (5,6) reached: on to (5,7), as MAES
    assert tuple(drive._path[drive._next]) == tile_centre((5, 7))
    drive._task = None                                # (the move ended against the wall)
    drive.command(Pose(6.6, 5.5, 0.0), trace.known)
    assert tuple(drive._path[drive._next]) == tile_centre((5, 8))


def test_an_unreachable_goal_is_reported() -> None:
    walls = [(r, 20) for r in range(1, 39)]
    trace = Trace(room(walls=walls), (5.5, 10.5, 0.0))
    trace.run((15.5, 10.5), "path")
    assert trace.drive.state == "unreachable"
    assert trace.tasks == []


def test_the_model_is_chosen_by_the_run_spec_and_changes_the_run() -> None:
    base = {"map": {"kind": "building", "size": 20, "seed": 1}, "robots": {"count": 2, "spawn": "together",
                                                                             "spawn_seed": 1},
            "algorithm": {"name": "greed", "params": {"variant": "maes"}}, "seed": 3, "lidar": {"range_m": 7.0},
            "stop": {"explored": 0.9, "max_ticks": 3000}}
    motion = {"max_speed": 3.0, "max_turn_rate": 4.0, "max_accel": 60.0, "max_turn_accel": 120.0, "substeps": 8}
    smooth = swarm.run({**base, "motion": motion}).summary
    maes = swarm.run({**base, "motion": {**motion, "model": "maes"}}).summary
    assert smooth["stop_reason"] == maes["stop_reason"] == "explored"
    assert maes["ticks"] > smooth["ticks"]
    assert swarm.run({**base, "motion": {**motion, "model": "maes"}}).summary["ticks"] == maes["ticks"]


def test_the_default_model_is_left_out_of_the_spec_and_a_bad_one_is_named() -> None:
    assert "model" not in json.loads(RunSpec.from_mapping({}).to_json())["motion"]
    assert json.loads(RunSpec.from_mapping({"motion": {"model": "maes"}}).to_json())["motion"]["model"] == "maes"
    with pytest.raises(InvalidInput, match=r"motion\.model.*'continuous' \| 'maes'"):
        RunSpec.from_mapping({"motion": {"model": "unity"}})
