"""The simulation loop end to end: exploration completes, runs are reproducible, bad specs fail early."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from maps import InvalidInput
from swarm.api import Action
from swarm.sim.loop import Simulation
from swarm.sim.spec import RunSpec


def small_spec(**over):
    spec = {"seed": 3, "map": {"kind": "building", "size": 30}, "robots": {"count": 2},
            "stop": {"max_ticks": 400}}
    spec.update(over)
    return spec


def test_same_spec_twice_is_bit_identical():
    a = Simulation(small_spec()).run()
    b = Simulation(small_spec()).run()
    assert a.deterministic_view() == b.deterministic_view()
    assert [float(v).hex() for p in a.summary["final_poses"] for v in p] == \
        [float(v).hex() for p in b.summary["final_poses"] for v in p]
    assert a.timeseries["explored"][-1] > 0.2


def test_same_spec_in_another_process_is_bit_identical():
    spec = small_spec()
    here = Simulation(spec).run()
    code = ("import json,sys; from swarm.sim.loop import Simulation; "
            "r = Simulation(json.loads(sys.argv[1])).run(); print(json.dumps(r.deterministic_view(), sort_keys=True))")
    proc = subprocess.run([sys.executable, "-c", code, json.dumps(spec)], capture_output=True, text=True,
                          timeout=300, env={"PYTHONHASHSEED": "123", "PATH": ""})
    assert proc.returncode == 0, proc.stderr
    assert json.loads(proc.stdout) == json.loads(json.dumps(here.deterministic_view(), sort_keys=True))


def test_different_seeds_differ():
    a = Simulation(small_spec()).run()
    b = Simulation(small_spec(seed=4)).run()
    assert a.summary["final_poses"] != b.summary["final_poses"]


def test_one_robot_explores_a_50_building():
    r = Simulation({"seed": 1, "map": {"kind": "building", "size": 50}, "robots": {"count": 1}}).run()
    assert r.summary["stop_reason"] == "explored"
    assert r.summary["explored"] >= 0.99
    assert r.summary["ticks_to"]["0.99"] == r.summary["ticks"] <= 36000
    ts = r.timeseries
    assert ts["tick"][-1] == r.summary["ticks"] and all(np.diff(ts["explored"]) >= 0)


def test_four_robots_explore_a_100_cave():
    r = Simulation({"seed": 2, "map": {"kind": "cave", "size": 100}, "robots": {"count": 4}}).run()
    assert r.summary["stop_reason"] == "explored", r.one_line()
    assert r.summary["ticks"] <= 36000


def test_result_shape_matches_design():
    r = Simulation(small_spec()).run()
    d = json.loads(r.to_json())
    assert set(d) >= {"spec", "summary", "timeseries"}
    s = d["summary"]
    assert set(s) >= {"ticks", "explored", "coverage", "ticks_to", "distance_m", "collisions", "wall_time_s"}
    assert set(s["ticks_to"]) == {"0.5", "0.75", "0.9", "0.95", "0.98", "0.99"}
    assert len(s["distance_m"]) == 2
    ts = d["timeseries"]
    assert ts["tick"][:3] == [0, 10, 20] and len(ts["tick"]) == len(ts["explored"]) == len(ts["coverage"])


class Spinner:
    """A module:Class algorithm that drives with velocity commands only."""

    name = "spinner"

    def reset(self, robot, params, rng):
        self.turn = float(rng.uniform(0.5, 1.0))

    def act(self, obs):
        return Action(velocity=(0.0, self.turn))


def test_module_class_algorithm_with_velocity_control():
    r = Simulation(small_spec(algorithm={"name": "tests.swarm.sim.test_simulation:Spinner"})).run()
    assert max(r.summary["distance_m"]) < 0.1, "a robot turning on the spot does not travel"
    assert r.summary["explored"] > 0


class Charger:
    """Drives straight ahead until the run ends."""

    name = "charger"

    def reset(self, robot, params, rng):
        pass

    def act(self, obs):
        return Action(velocity=(1.0, 0.0))


class Gatherer:
    """Every robot drives to where robot 0 started (robot 0 stays there)."""

    name = "gatherer"
    meet: tuple = ()

    def reset(self, robot, params, rng):
        self.robot = robot

    def act(self, obs):
        if obs.robot_id == 0 and obs.tick == 0:
            Gatherer.meet = (obs.pose.x, obs.pose.y)
        return Action(goal=Gatherer.meet)


def test_collisions_are_counted_apart_for_walls_and_robots():
    alone = Simulation(small_spec(robots={"count": 1}, algorithm={"name": "tests.swarm.sim.test_simulation:Charger"},
                                  stop={"max_ticks": 300})).run().summary
    assert alone["collisions_wall"] >= 1 and alone["collisions_robot"] == 0
    assert alone["collisions"] >= 1
    crowd = Simulation(small_spec(robots={"count": 6, "spawn": "together"}, stop={"max_ticks": 200},
                                  algorithm={"name": "tests.swarm.sim.test_simulation:Gatherer"})).run().summary
    assert crowd["collisions_robot"] >= 5, "five robots pile onto robot 0"
    # a robot starting to touch anything starts touching a wall or a robot
    assert 0 < crowd["collisions"] <= crowd["collisions_wall"] + crowd["collisions_robot"]


class Pacer:
    """Reports what it sees so the test can check the observation contract."""

    name = "pacer"
    seen: list = []

    def reset(self, robot, params, rng):
        self.robot = robot

    def act(self, obs):
        Pacer.seen.append(obs)
        return Action(goal=(obs.pose.x, obs.pose.y))


def test_observation_contract():
    Pacer.seen = []
    Simulation(small_spec(algorithm={"name": "tests.swarm.sim.test_simulation:Pacer"}, stop={"max_ticks": 5})).run()
    first = Pacer.seen[0]
    assert first.tick == 0 and first.robot_id == 0
    assert not first.known.flags.writeable
    from swarm.grid._validate import _VOUCHED
    assert _VOUCHED.get(id(first.known)) is first.known, "the runtime vouches for its maps' values"
    with pytest.raises(ValueError):
        first.known[0, 0] = 2
    assert (first.known > 0).any(), "the robot has sensed before its first decision"
    ticks = sorted({o.tick for o in Pacer.seen})
    assert ticks == [0, 1, 2, 3, 4]


@pytest.mark.parametrize("spec, field", [
    ({"algorithm": {"name": "nope"}}, "algorithm.name"),
    ({"algorithm": {"name": "frontier", "params": {"speed": 3}}}, "algorithm.params.speed"),
    ({"robots": {"count": -1}}, "robots.count"),
    ({"robots": {"count": 0}}, "robots.count"),
    ({"map": {"kind": "castle"}}, "map.kind"),
    ({"map": {"size": 5}}, "size"),
    ({"stop": {"explored": 1.5}}, "stop.explored"),
    ({"lidar": {"range_m": -2}}, "range_m"),
    ({"bogus": 1}, "bogus"),
])
def test_bad_specs_fail_before_running(spec, field):
    with pytest.raises(InvalidInput) as info:
        RunSpec.from_mapping(spec)
    assert field in info.value.field


def test_a_run_takes_up_to_ten_thousand_robots():
    from swarm.sim.spec import MAX_ROBOTS

    assert MAX_ROBOTS == 10_000
    assert RunSpec.from_mapping({"robots": {"count": MAX_ROBOTS}}).robots.count == MAX_ROBOTS
    with pytest.raises(InvalidInput, match="robots.count: got 10001; allowed: an integer in 1..10000"):
        RunSpec.from_mapping({"robots": {"count": MAX_ROBOTS + 1}})


def test_more_robots_than_space():
    with pytest.raises(InvalidInput, match="robots.count"):
        Simulation({"map": {"kind": "building", "size": 20}, "robots": {"count": 1000}})


def test_spec_key_is_stable_and_defaults_are_resolved():
    a = RunSpec.from_mapping({"robots": {"count": 3, "spawn": "random"}, "seed": 5})
    b = RunSpec.from_mapping({"seed": 5, "robots": {"spawn": "random", "count": 3}})
    assert a.key == b.key and len(a.key) == 16
    assert a.canonical()["lidar"]["range_m"] == 7.0
    assert RunSpec.from_mapping(a.canonical()).key == a.key, "the canonical form round-trips"
    assert RunSpec.from_mapping({"seed": 6}).key != RunSpec.from_mapping({"seed": 5}).key


def test_path_length_of_a_straight_drive_is_its_length():
    """Issue 52: path length per robot (Explore-Bench) is the distance each drove; two robots driving the same
    straight line in an open hall drive equal lengths (spread 0) and see much of the same hall."""
    from maps import Map
    from swarm.results.schema import benchmark_columns

    solid = np.ones((20, 160), dtype=bool)   # an 80 m x 10 m hall
    solid[1:-1, 1:-1] = False
    hall = Map(solid=solid, material=solid.astype(np.uint8), materials=("air", "concrete"))
    start = np.array([[2.0, 3.0, 0.0], [2.0, 7.0, 0.0]])
    sim = Simulation(small_spec(stop={"max_ticks": 150}, algorithm={"name": "tests.swarm.sim.test_simulation:Charger"}),
                     truth=hall, start_poses=start)
    s = sim.run().summary
    driven = [p[0] - x0 for p, x0 in zip(s["final_poses"], start[:, 0])]
    assert min(driven) > 10 and max(p[0] for p in s["final_poses"]) < 78      # drove far, never reached the wall
    assert [abs(p[1] - y0) for p, y0 in zip(s["final_poses"], start[:, 1])] == pytest.approx([0, 0], abs=1e-9)
    assert s["distance_m"] == pytest.approx(driven, rel=1e-9)
    cols = benchmark_columns(s)
    assert cols["path_length_mean_m"] == pytest.approx(sum(driven) / 2) and cols["path_length_cv"] < 1e-9
    assert 0 < s["overlap_rate"] <= 1 and len(s["own_seen_cells"]) == 2
    assert s["seen_cells"] == np.count_nonzero(sim.tracker.seen)
    assert sum(s["own_seen_cells"]) >= s["seen_cells"] > max(s["own_seen_cells"])


def test_benchmark_columns_from_a_hand_built_summary():
    from swarm.results.schema import benchmark_columns

    cols = benchmark_columns({"distance_m": [1.0, 3.0], "overlap_rate": 0.25, "coverage_spread": 0.1})
    assert cols == {"path_length_mean_m": 2.0, "path_length_cv": 0.5, "overlap_rate": 0.25, "coverage_spread": 0.1}
    assert benchmark_columns({"distance_m": [0.0, 0.0]})["path_length_cv"] == 0.0   # nobody moved; older results
    assert benchmark_columns(None) == dict.fromkeys(cols)
