"""Localisation error (issue 50): the odometry model's error statistics on a known square path, a straight
wall bent the way the heading drift says, a map written from a known offset landing by that offset when
merged, the bounded model's accuracy, and runs with the model on."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import swarm
from maps import Map
from swarm.base.errors import InvalidInput
from swarm.base.types import CELL_M, FREE, SOLID
from swarm.sim.spec import RunSpec
from swarm.world.localization import LocalizationSpec, Localizer
from swarm.world.sensing import Lidar, LidarParams

ZERO = dict(drift_per_m=0.0, turn_drift_per_rad=0.0, heading_drift_per_m=0.0, noise_per_m=0.0, noise_per_rad=0.0)
TICK = 0.1


def square_path(side: float, step: float = 0.1, turn_step: float = 0.2) -> np.ndarray:
    """True poses of a robot driving a square of ``side`` metres counter-clockwise from (0, 0) facing +x,
    turning 90 degrees in place between sides (three turns, four sides)."""
    poses = [(0.0, 0.0, 0.0)]
    x, y, th = 0.0, 0.0, 0.0
    for k in range(4):
        for _ in range(int(round(side / step))):
            x += step * math.cos(th)
            y += step * math.sin(th)
            poses.append((x, y, th))
        if k < 3:
            for _ in range(int(round((math.pi / 2) / turn_step))):
                th += (math.pi / 2) / round((math.pi / 2) / turn_step)
                poses.append((x, y, th))
    return np.array(poses)


def drive(spec: LocalizationSpec, path: np.ndarray, seed: int) -> np.ndarray:
    """The estimate's final error (x, y, heading wrapped) after one robot followed ``path``."""
    loc = Localizer(spec, seed, path[:1] + 50.0 * np.array([[1, 1, 0]]), TICK, (200.0, 200.0))
    for p in path[1:]:
        loc.update(p[None] + 50.0 * np.array([[1, 1, 0]]))
    err = loc.estimates[0] - (path[-1] + 50.0 * np.array([1, 1, 0]))
    err[2] = math.pi - (math.pi - err[2]) % (2 * math.pi)
    return err


def test_odometry_without_error_integrates_the_true_motion_exactly():
    path = square_path(10.0)
    err = drive(LocalizationSpec(model="odometry", **ZERO), path, seed=1)
    assert np.abs(err).max() < 1e-9


def test_a_square_path_ends_with_the_error_its_turn_drift_predicts():
    """Turn scale error t (std ``turn_drift_per_rad``) only: after three 90-degree turns the heading is off by
    1.5 pi t and the square fails to close by sqrt(2) pi L |t| (small angles: side k runs k pi t / 2 off
    its direction), so over seeds the heading error has std 1.5 pi sigma and the position error mean
    sqrt(2) pi L sigma sqrt(2 / pi)."""
    sigma, side = 0.02, 10.0
    path = square_path(side)
    spec = LocalizationSpec(model="odometry", **{**ZERO, "turn_drift_per_rad": sigma})
    errs = np.array([drive(spec, path, seed) for seed in range(400)])
    heading = np.abs(np.pi - (np.pi - errs[:, 2]) % (2 * np.pi))
    assert np.sqrt(np.mean(heading ** 2)) == pytest.approx(1.5 * math.pi * sigma, rel=0.1)
    position = np.hypot(errs[:, 0], errs[:, 1])
    assert position.mean() == pytest.approx(math.sqrt(2) * math.pi * side * sigma * math.sqrt(2 / math.pi), rel=0.1)


def test_a_straight_drive_errs_along_track_by_its_scale_error_and_its_noise():
    """Scale error s (std ``drift_per_m``) and random noise (std ``noise_per_m`` per square-root metre) on a
    straight drive of D metres: the along-track error has variance (sigma D)^2 + noise^2 D."""
    d, sigma, noise = 20.0, 0.02, 0.05
    path = np.array([(0.1 * k, 0.0, 0.0) for k in range(int(d / 0.1) + 1)])
    spec = LocalizationSpec(model="odometry", **{**ZERO, "drift_per_m": sigma, "noise_per_m": noise})
    errs = np.array([drive(spec, path, seed) for seed in range(400)])
    assert np.abs(errs[:, 1]).max() < 1e-9 and np.abs(errs[:, 2]).max() < 1e-12   # no heading error terms
    assert errs[:, 0].std() == pytest.approx(math.sqrt((sigma * d) ** 2 + noise ** 2 * d), rel=0.1)


def wall_room(width_cells: int = 100, height_cells: int = 60, wall_row: int | None = None) -> Map:
    """A walled room, with a straight wall across it at ``wall_row`` if given."""
    solid = np.ones((height_cells, width_cells), dtype=bool)
    solid[1:-1, 1:-1] = False
    if wall_row is not None:
        solid[wall_row, :] = True
    return Map(solid=solid, material=solid.astype(np.uint8), materials=("air", "concrete"))


def test_a_straight_wall_is_mapped_bent_the_way_the_heading_drift_says():
    """Driving 40 m beside a straight wall with heading drift h rad/m, the robot believes it curves by h per
    metre (its believed track moves across by h x^2 / 2 after x metres), so its map shows the wall bent
    by as much, to the side h turns it."""
    truth = wall_room(wall_row=30)                      # the wall's top face at y = 15.5 m
    lidar = Lidar(truth, LidarParams(range_m=4.0))
    x0, y0 = 3.0, 17.5                                  # 2 m above the face
    path = np.array([(x0 + 0.1 * k, y0, 0.0) for k in range(400)])
    spec = LocalizationSpec(model="odometry", **{**ZERO, "heading_drift_per_m": 0.005})
    loc = Localizer(spec, 11, path[:1], TICK, (truth.width_m, truth.height_m))
    h = float(loc._heading[0])
    assert abs(h) > 0.002                               # this seed drew a drift worth testing
    known = np.zeros((1, *truth.shape), dtype=np.uint8)
    for p in path:
        believed = loc.update(p[None]).copy()
        ranges = lidar.scan(p[None], known, write=False)
        lidar.write_from(believed, ranges, known)

    def face_row(x_m: float) -> float:
        """The median row of the SOLID cells between the floor and the track, over a few columns near x (the
        wall as mapped; scans from behind and ahead thicken it by a row here and there)."""
        c = int(x_m / CELL_M)
        rows = [np.flatnonzero(known[0, 5:int(y0 / CELL_M), col] == SOLID) + 5 for col in range(c - 2, c + 3)]
        return float(np.median(np.concatenate(rows)))

    assert face_row(6.0) == pytest.approx(30.0, abs=0.5)   # where the drive began, the wall is where it is
    for x in (20.0, 30.0, 40.0):
        predicted = 30.0 + h * (x - x0) ** 2 / 2 / CELL_M   # rows the believed track has moved across by x
        assert face_row(x) == pytest.approx(predicted, abs=1.5), (h, x, face_row(x), predicted)
    assert abs(face_row(40.0) - 30.0) >= 3                  # visibly bent


def test_a_map_written_from_a_known_offset_is_merged_there():
    """A robot that believes itself (1.0, 0.5) m from where it is maps everything shifted by that offset,
    and a robot merging its map gets the shifted cells: where the sender believed it was."""
    truth = wall_room(60, 40)
    lidar = Lidar(truth, LidarParams(range_m=5.0))
    pose = np.array([[10.25, 8.25, 0.3]])
    right = np.zeros((1, *truth.shape), dtype=np.uint8)
    lidar.scan(pose, right)
    shifted = np.zeros_like(right)
    ranges = Lidar(truth, LidarParams(range_m=5.0)).scan(pose, shifted, write=False)
    lidar.write_from(pose + np.array([[1.0, 0.5, 0.0]]), ranges, shifted)
    assert (shifted[0, 1:, 2:] == right[0, :-1, :-2]).all()    # every cell two columns right, one row up
    receiver = np.zeros_like(right[0])
    np.maximum(receiver, shifted[0], out=receiver)              # the merge rule: elementwise maximum
    assert (receiver[1:, 2:] == right[0, :-1, :-2]).all() and not (receiver == right[0]).all()


def test_the_bounded_model_keeps_its_accuracy_and_is_correlated_in_time():
    spec = LocalizationSpec(model="bounded", sigma_m=0.2, sigma_rad=0.05, correlation_s=5.0, correlation_m=4.0)
    rng = np.random.default_rng(0)
    poses = np.column_stack([rng.uniform(5, 95, 40), rng.uniform(5, 95, 40), np.zeros(40)])
    loc = Localizer(spec, 3, poses, TICK, (100.0, 100.0))
    errors = []
    for _ in range(2000):
        poses[:, 0] = np.clip(poses[:, 0] + 0.05, 1, 99)
        errors.append(loc.update(poses) - poses)
    e = np.array(errors)                                # (ticks, robots, 3)
    assert e[..., 0].std() == pytest.approx(0.2, rel=0.2) and e[..., 1].std() == pytest.approx(0.2, rel=0.2)
    lag1 = np.corrcoef(e[1:, :, 0].ravel(), e[:-1, :, 0].ravel())[0, 1]
    assert lag1 > 0.9                                   # a tick apart the error barely changes


def test_the_section_is_left_out_while_perfect_and_a_bad_value_is_named():
    assert "localization" not in json.loads(RunSpec.from_mapping({}).to_json())
    assert RunSpec.from_mapping({"localization": {"model": "perfect"}}).key == RunSpec.from_mapping({}).key
    with pytest.raises(InvalidInput, match=r"localization\.drift_per_m"):
        RunSpec.from_mapping({"localization": {"model": "odometry", "drift_per_m": -1}})
    with pytest.raises(InvalidInput, match=r"localization\.model"):
        RunSpec.from_mapping({"localization": {"model": "gps"}})


def test_a_run_with_drift_maps_worse_and_reports_its_errors():
    base = {"map": {"kind": "building", "size": 30, "seed": 3}, "robots": {"count": 3, "spawn": "together",
                                                                             "spawn_seed": 1},
            "seed": 5, "algorithm": {"name": "frontier"}, "stop": {"explored": 0.9, "max_ticks": 800}}
    perfect = swarm.run(base).summary
    assert "localization" not in perfect
    drift = swarm.run({**base, "localization": {"model": "odometry", "drift_per_m": 0.05}}).summary
    loc = drift["localization"]
    assert loc["model"] == "odometry" and len(loc["final_position_error_m"]) == 3
    assert max(loc["final_position_error_m"]) > 0.05
    assert loc["false_free_share"] + loc["false_occupied_share"] > 0.0
    again = swarm.run({**base, "localization": {"model": "odometry", "drift_per_m": 0.05}}).summary
    assert again["localization"] == loc and again["ticks"] == drift["ticks"]


def test_the_log_odds_lidar_unlearns_walls_a_pose_error_misplaced():
    """With the ternary lidar a cell once written SOLID stays SOLID, so every wall a momentary pose error
    misplaced stays; the log-odds lidar votes from the believed pose too, and later scans from better
    estimates vote the misplaced cells free again: fewer false-occupied cells and more of the map right."""
    base = {"map": {"kind": "building", "size": 30, "seed": 3}, "robots": {"count": 3, "spawn": "together",
                                                                             "spawn_seed": 1},
            "seed": 5, "algorithm": {"name": "frontier"}, "stop": {"explored": 0.9, "max_ticks": 1500},
            "localization": {"model": "bounded", "sigma_m": 0.1}}
    ternary = swarm.run(base).summary["localization"]
    logodds = swarm.run({**base, "lidar": {"mode": "logodds"}}).summary["localization"]
    assert logodds["false_occupied_share"] < 0.75 * ternary["false_occupied_share"]
    assert logodds["explored_correct"] > ternary["explored_correct"]
    assert 0.0 < logodds["wall_offset_mean_m"] < 1.0
    series = logodds["pose_error_series"]
    assert series["tick"][:2] == [0, 10] and len(series["position_m"][0]) == 3


def test_a_robot_hides_what_is_behind_it_and_does_not_enter_the_map():
    """lidar.robots_occlude: robot 0 looks east along a corridor at a wall 6 m away, robot 1 stands 2 m in
    front of it. The ray straight east ends 0.3 m before robot 1's centre; robot 0 maps no wall behind
    robot 1 and no SOLID cell where robot 1 stands, and the cells between them are FREE."""
    truth = wall_room(40, 20)
    solid = truth.solid.copy()
    solid[:, 24] = True                                   # a wall across the room at x = 12-12.5 m
    truth = Map(solid=solid, material=solid.astype(np.uint8), materials=("air", "concrete"))
    lidar = Lidar(truth, LidarParams(range_m=7.0, robots_occlude=True))
    poses = np.array([[6.25, 5.25, 0.0], [8.25, 5.25, np.pi]])
    limits = lidar.occlusion(poses, 0.3)
    east = int(np.argmin(np.abs(np.angle(np.exp(1j * lidar.angles)))))   # the ray along +x
    assert limits[0, east] == pytest.approx(2.0 - 0.3, abs=1e-9)
    known = np.zeros((2, *truth.shape), dtype=np.uint8)
    ranges = lidar.scan(poses, known, write=False, limits=limits)
    lidar.write_from(poses, ranges, known, limits)
    row = int(5.25 / CELL_M)
    assert (known[0, row, 13:16] == FREE).all()           # x 6.5-8 m: between the robots
    assert known[0, row, 16] != SOLID and known[0, row, 24] == 0   # robot 1's cell, and the hidden wall
    open_view = np.zeros_like(known)
    plain = Lidar(truth, LidarParams(range_m=7.0))
    plain.write_from(poses, plain.scan(poses, open_view, write=False), open_view)
    assert open_view[0, row, 24] == SOLID                 # without occlusion the wall is seen through robot 1
    with pytest.raises(InvalidInput, match="robots_occlude"):
        LidarParams(mode="logodds", robots_occlude=True)


def test_the_correctly_explored_fraction_is_recorded_over_time_with_a_localisation_model():
    base = {"map": {"kind": "building", "size": 30, "seed": 3}, "robots": {"count": 3, "spawn": "together",
                                                                             "spawn_seed": 1},
            "seed": 5, "algorithm": {"name": "frontier"}, "stop": {"max_ticks": 600}, "lidar": {"mode": "logodds"}}
    perfect = swarm.run(base)
    assert "explored_correct" not in perfect.timeseries
    bounded = swarm.run({**base, "localization": {"model": "bounded", "sigma_m": 0.05}})
    ts, loc = bounded.timeseries, bounded.summary["localization"]
    correct = np.asarray(ts["explored_correct"])
    assert len(correct) == len(ts["tick"]) and correct[-1] == loc["explored_correct"]
    assert (correct <= np.asarray(ts["explored"]) + 0.05).all() and correct[-1] > 0.3
    for key, tick in loc["ticks_to_correct"].items():   # the first recorded tick at or above each threshold
        reached = [t for t, v in zip(ts["tick"], correct) if v >= float(key)]
        assert tick == (reached[0] if reached else None), key
