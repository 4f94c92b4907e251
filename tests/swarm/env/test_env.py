"""swarm.env: the PettingZoo and Gymnasium environments over the real runtime.

The library checks (PettingZoo's parallel API test, Gymnasium's env checker), determinism from the seed,
the scripted explorers reproducing swarm.run bit for bit, and what the observations, actions and
rewards mean, checked against the runtime's own state.
"""

from __future__ import annotations

import hashlib
import subprocess
import sys
import warnings

import numpy as np
import pytest

gymnasium = pytest.importorskip("gymnasium")
pytest.importorskip("pettingzoo")

import swarm  # noqa: E402
import swarm.env as senv  # noqa: E402
from maps import InvalidInput, Map  # noqa: E402
from maps.io import save_npz  # noqa: E402
from swarm.api import FREE, UNSEEN, cell_centre  # noqa: E402

SMALL = {"robots": 3, "size": 20, "stop": {"max_ticks": 300}}


def test_parallel_api_test_passes_for_goals_and_velocities():
    from pettingzoo.test import parallel_api_test

    parallel_api_test(senv.SwarmParallelEnv(**SMALL), num_cycles=400)
    parallel_api_test(senv.SwarmParallelEnv(**SMALL, action="velocity", learners=[0, 2]), num_cycles=400)


@pytest.mark.parametrize("env_id, options", [("swarm/Explore-v0", {}), ("swarm/ExploreVelocity-v0", {}),
                                             ("swarm/Explore-v0", {"delegate": True, "algorithm": "greed"})])
def test_gymnasium_env_checker_passes(env_id, options):
    from gymnasium.utils.env_checker import check_env

    env = gymnasium.make(env_id, **SMALL, **options, render_mode="rgb_array")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        check_env(env.unwrapped)
    assert [str(w.message) for w in caught] == []
    env.reset(seed=1)
    frame = env.render()
    assert frame.dtype == np.uint8 and frame.shape == (600, 600, 3)  # 40 x 40 cells at 15 px (swarm.env.render)


def trajectory(seed: int, policy_seed: int, **options) -> str:
    """A digest of every observation, reward and flag of a seeded random policy's episode."""
    env = senv.SwarmParallelEnv(robots=4, size=24, stop={"max_ticks": 400}, **options)
    rng = np.random.default_rng(policy_seed)
    obs, _ = env.reset(seed=seed)
    h = hashlib.sha256()
    steps = 0
    while env.agents:
        for agent in env.possible_agents:
            for key in sorted(obs[agent]):
                h.update(obs[agent][key].tobytes())
        actions = {a: _sample(env, a, rng) for a in env.agents}
        obs, rewards, terms, truncs, _ = env.step(actions)
        h.update(repr((sorted(rewards.items()), sorted(terms.items()), sorted(truncs.items()))).encode())
        steps += 1
    h.update(repr(env.core.result().deterministic_view()).encode())
    return f"{steps}:{h.hexdigest()}"


def _sample(env, agent, rng):
    space = env.action_space(agent)
    if isinstance(space, gymnasium.spaces.Discrete):
        return int(rng.integers(space.n))
    return rng.uniform(-1, 1, size=2).astype(np.float32)


@pytest.mark.parametrize("action", ["goal", "velocity"])
def test_a_seeded_random_policy_gives_bit_identical_trajectories(action):
    first = trajectory(5, 11, action=action)
    assert trajectory(5, 11, action=action) == first
    assert trajectory(6, 11, action=action) != first, "another seed is another world"
    assert trajectory(5, 12, action=action) != first, "other actions drive elsewhere"


def test_reset_without_a_seed_is_a_deterministic_sequence():
    def starts(env):
        out = [env.reset()[0]["robot_0"]["pose"].tobytes()]
        out.append(env.reset()[0]["robot_0"]["pose"].tobytes())
        out.append(env.reset(seed=3)[0]["robot_0"]["pose"].tobytes())
        out.append(env.reset()[0]["robot_0"]["pose"].tobytes())
        return out

    options = {**SMALL, "robots": {"count": 3, "spawn": "random"}}
    a = starts(senv.SwarmParallelEnv(**options))
    b = starts(senv.SwarmParallelEnv(**options))
    assert a == b and len(set(a)) == 4


@pytest.mark.parametrize("algorithm, radio", [("greed", "multiwall"), ("frontier", "los"), ("tnf", "global")])
def test_every_robot_delegating_reproduces_swarm_run(algorithm, radio):
    """Stepping the env with each robot's own explorer deciding is the run swarm.run runs."""
    env = senv.SwarmParallelEnv(robots=4, size=30, algorithm=algorithm, radio=radio, delegate=True,
                                stop={"max_ticks": 600})
    env.reset(seed=7)
    delegate = env.core.config.n_actions - 1
    while env.agents:
        env.step({a: delegate for a in env.agents})
    stepped = env.core.result()
    reference = swarm.run(env.core.sim.spec)
    assert stepped.key == reference.key and reference.spec["seed"] == 7
    assert stepped.deterministic_view() == reference.deterministic_view()
    assert stepped.summary["messages"]["delivered"] > 0 or radio != "global"


def test_one_learner_delegating_among_scripted_teammates_reproduces_swarm_run():
    env = senv.SwarmEnv(learner=1, delegate=True, robots=3, size=30, ticks_per_step=7, algorithm="greed",
                        stop={"max_ticks": 500})
    env.reset(seed=2)
    done = False
    steps = 0
    while not done:
        _, _, terminated, truncated, info = env.step(9)
        done = terminated or truncated
        steps += 1
    reference = swarm.run(env.core.sim.spec)
    assert env.core.result().deterministic_view() == reference.deterministic_view()
    assert info["tick"] == reference.summary["ticks"] and steps == -(-info["tick"] // 7)


def test_learners_differ_from_the_scripted_run():
    """Control: the same spec with one robot driven by constant 'keep' actions is not swarm.run's run."""
    env = senv.SwarmEnv(learner=0, robots=3, size=30, algorithm="greed", stop={"max_ticks": 300})
    env.reset(seed=2)
    done = False
    while not done:
        *_, terminated, truncated, _ = env.step(0)
        done = terminated or truncated
    assert env.core.result().summary["distance_m"][0] == 0.0, "robot 0 never got a goal"
    assert swarm.run(env.core.sim.spec).summary["distance_m"][0] > 0


# ------------------------------------------------------------------------------------ observations ----
def room_file(tmp_path, cells: int = 40) -> str:
    """A closed square room split by a concrete wall down its middle, with a door at the top end."""
    solid = np.zeros((cells, cells), dtype=bool)
    solid[0, :] = solid[-1, :] = solid[:, 0] = solid[:, -1] = True
    solid[: cells - 6, cells // 2] = True
    path = tmp_path / "room.npz"
    save_npz(Map(solid=solid, material=solid.astype(np.uint8), materials=("air", "concrete")), path)
    return str(path)


def test_the_crop_is_the_robots_own_map_centred_on_it(tmp_path):
    env = senv.SwarmParallelEnv(map=room_file(tmp_path), robots=2, crop_cells=16, stop={"max_ticks": 50})
    obs, _ = env.reset(seed=1)
    core = env.core
    for l, agent in enumerate(env.possible_agents):
        x, y, _ = core.sim.world.poses[l]
        row, col = int(y / 0.5), int(x / 0.5)
        crop = obs[agent]["map"]
        known = core.sim.known[l]
        h, w = known.shape
        for a in range(16):
            for b in range(16):
                r, c = row - 8 + a, col - 8 + b
                expected = known[r, c] if 0 <= r < h and 0 <= c < w else 3
                assert crop[a, b] == expected
        assert crop[8, 8] == FREE, "the robot stands on a free cell it sees"


def test_goal_choices_are_frontier_cells_in_their_sector_and_drive_the_navigator():
    env = senv.SwarmParallelEnv(robots=2, size=30, stop={"max_ticks": 200})
    obs, infos = env.reset(seed=4)
    core = env.core
    known = core.sim.known[0]
    x, y, _ = core.sim.world.poses[0]
    row, col = int(y / 0.5), int(x / 0.5)
    valid = 0
    for s in range(8):
        grow, gcol = core.goals[0, s]
        if grow < 0:
            assert obs["robot_0"]["choices"][s].tolist() == [0, 0, 0]
            continue
        valid += 1
        assert known[grow, gcol] == FREE
        around = [known[grow + dr, gcol + dc] for dr, dc in ((1, 0), (-1, 0), (0, 1), (0, -1))]
        assert UNSEEN in around, "a frontier cell borders unseen space"
        angle = np.degrees(np.arctan2(grow - row, gcol - col)) % 360
        assert min(abs(angle - 45 * s), 360 - abs(angle - 45 * s)) <= 22.5 + 1e-9
        assert obs["robot_0"]["choices"][s][1:].tolist() == pytest.approx([(gcol - col) / 16, (grow - row) / 16])
    assert valid >= 2 and infos["robot_0"]["action_mask"][1:9].sum() == valid
    s = int(np.flatnonzero(core.goals[0, :, 0] >= 0)[0])
    goal_cell = core.goals[0, s].copy()
    env.step({"robot_0": 1 + s, "robot_1": 0})
    chosen = cell_centre(*(int(v) for v in goal_cell))
    assert core.sim.navigators[0].goal == chosen, "the chosen frontier cell is the navigator's goal"
    assert core.sim.navigators[1].goal is None, "'keep' sets no goal"


def test_neighbours_show_links_and_margins_by_radio_model(tmp_path):
    room = room_file(tmp_path)
    spread = {"count": 2, "spawn": "random", "spawn_seed": 0}
    found = False
    for spawn_seed in range(40):  # a spawn with the robots on either side of the concrete wall
        spread["spawn_seed"] = spawn_seed
        los = senv.SwarmParallelEnv(map=room, robots=dict(spread), radio="los", stop={"max_ticks": 5})
        obs, _ = los.reset(seed=1)
        xs = los.core.sim.world.poses[:, 0]
        if (xs[0] < 10) != (xs[1] < 10):
            found = True
            break
    assert found
    assert obs["robot_0"]["neighbours"].tolist() == [[0, 0, 0, 0]], "behind the wall: nothing shown"
    seen = senv.SwarmParallelEnv(map=room, robots=dict(spread), radio="los", observe_all=True, stop={"max_ticks": 5})
    o = seen.reset(seed=1)[0]["robot_0"]["neighbours"][0]
    poses = seen.core.sim.world.poses
    assert o[0] == 0 and o[3] == -1.0
    assert o[1:3].tolist() == pytest.approx(((poses[1, :2] - poses[0, :2]) / 20.0).tolist(), rel=1e-6)
    glob = senv.SwarmParallelEnv(map=room, robots=dict(spread), radio="global", stop={"max_ticks": 5})
    o = glob.reset(seed=1)[0]["robot_0"]["neighbours"][0]
    assert o[0] == 1 and o[3] == 1.0, "global: linked, 15 - (-82) dBm clipped to the 60 dB scale"
    multi = senv.SwarmParallelEnv(map=room, robots=dict(spread), radio="multiwall", margin_db=100.0,
                                  stop={"max_ticks": 5})
    o = multi.reset(seed=1)[0]["robot_0"]["neighbours"][0]
    state = multi.core.sim.links.evaluate(multi.core.sim.world.poses[:, :2])
    margin = state.rssi[0, 1] - multi.core.sim.links.config.sensitivity_dbm
    assert o[3] == pytest.approx(np.clip(margin, -100, 100) / 100, abs=1e-6)
    assert o[0] == float(state.link[0, 1])


def test_inbox_counts_map_updates_received():
    env = senv.SwarmParallelEnv(robots=2, size=20, radio="global", comm={"share_every": 5}, ticks_per_step=5,
                                stop={"max_ticks": 100})
    env.reset(seed=3)
    seen = []
    while env.agents:
        obs, *_ = env.step({a: 0 for a in env.agents})
        seen.append(obs["robot_0"]["inbox"].copy())
    assert any(v[1] > 0 and v[0] >= v[1] and v[2] > 0 for v in seen), "map updates arrive under global radio"
    assert min(v[3] for v in seen[2:]) < 0.05, "contact is recent"
    known = env.core.sim.known
    cells = known.shape[1] * known.shape[2]
    for l in range(2):  # the known share follows lidar and merges exactly
        assert obs[f"robot_{l}"]["pose"][7] == np.float32(np.count_nonzero(known[l]) / cells)


# ----------------------------------------------------------------------------------------- rewards ----
def test_own_reward_is_the_area_the_robots_own_lidar_revealed():
    env = senv.SwarmParallelEnv(robots=2, size=24, comm={"map_sharing": "off"}, stop={"max_ticks": 300})
    env.reset(seed=8)
    start = np.count_nonzero(env.core.sim.known.reshape(2, -1), axis=1)
    total = np.zeros(2)
    rng = np.random.default_rng(0)
    while env.agents:
        _, rewards, *_ = env.step({a: int(rng.integers(9)) for a in env.agents})
        total += [rewards["robot_0"], rewards["robot_1"]]
    end = np.count_nonzero(env.core.sim.known.reshape(2, -1), axis=1)
    assert total.tolist() == pytest.approx(((end - start) * 0.25).tolist())
    assert total.min() > 0


def test_team_time_and_collision_rewards():
    reward = {"own": 0.0, "team": 1.0, "time_penalty": 0.01, "collision_penalty": 5.0}
    env = senv.SwarmParallelEnv(robots=2, size=20, action="velocity", ticks_per_step=3, reward=reward,
                                stop={"max_ticks": 240})
    env.reset(seed=1)
    core = env.core
    explored0 = core.sim.tracker.seen_free_cells
    total = {"robot_0": 0.0, "robot_1": 0.0}
    steps = 0
    while env.agents:  # full speed ahead with a slight turn: the robots hit walls sooner or later
        _, rewards, *_ = env.step({a: np.array([1.0, 0.1], dtype=np.float32) for a in env.agents})
        for a in total:
            total[a] += rewards[a]
        steps += 1
    collisions = core.state.collisions
    assert collisions > 0
    team = (core.sim.tracker.seen_free_cells - explored0) * 0.25
    ticks = core.state.tick
    assert team > 0 and steps == -(-ticks // 3)
    # each robot's total is team - time - 5 x the contacts it began: whole, non-negative, summing to the run's
    contacts = [(team - 0.01 * ticks - total[a]) / 5.0 for a in ("robot_0", "robot_1")]
    assert all(c == pytest.approx(round(c), abs=1e-6) and round(c) >= 0 for c in contacts)
    assert sum(round(c) for c in contacts) == collisions


# ------------------------------------------------------------------------------------------ options ----
@pytest.mark.parametrize("kwargs, field", [
    ({"action": "jump"}, "action"), ({"crop_cells": 31}, "crop_cells"), ({"learners": [5]}, "learners"),
    ({"transport": "zenoh"}, "transport"), ({"action": "velocity", "delegate": True}, "delegate"),
    ({"reward": {"speed": 1.0}}, "reward.speed"), ({"ticks_per_step": 0}, "ticks_per_step"),
    ({"robots": 0}, "robots.count"), ({"radio": "nonsense"}, "radio.model"),
])
def test_bad_options_are_one_line_errors(kwargs, field):
    with pytest.raises(InvalidInput) as exc:
        senv.SwarmParallelEnv(**{**SMALL, **kwargs})
    assert str(exc.value).startswith(f"{field}: got ") and "\n" not in str(exc.value)


def test_bad_actions_are_one_line_errors():
    env = senv.SwarmParallelEnv(**SMALL)
    env.reset(seed=0)
    with pytest.raises(InvalidInput, match=r"^actions\[0\]: got 9; allowed: an integer 0..8"):
        env.step({a: 9 for a in env.agents})
    with pytest.raises(InvalidInput, match="an action for every live agent"):
        env.step({"robot_0": 0})


@pytest.mark.parametrize("action", [np.array([1, 2]), np.array([[1]]), None, "1", b"1", 1.5, True, [1], {}, 2**70,
                                    np.float64("nan"), object()])
def test_a_goal_action_of_the_wrong_shape_or_type_is_a_one_line_error(action):
    env = senv.SwarmEnv(**SMALL)
    env.reset(seed=0)
    with pytest.raises(InvalidInput, match=r"^actions\[0\]: got .*; allowed: an integer 0..8$"):
        env.step(action)
    assert env.step(np.int64(1))[4]["tick"] == 1, "the env still steps"


@pytest.mark.parametrize("action", [["a", "b"], None, {}, "ab", [1.0], [1.0, float("inf")], [1, 2, 3],
                                    [object(), 1.0], [[1.0], [2.0, 3.0]]])
def test_a_velocity_action_of_the_wrong_shape_or_type_is_a_one_line_error(action):
    env = senv.SwarmEnv(**SMALL, action="velocity")
    env.reset(seed=0)
    with pytest.raises(InvalidInput, match=r"^actions\[0\]: got .*; allowed: two finite numbers"):
        env.step(action)
    assert env.step(np.array([0.5, 0.0]))[4]["tick"] == 1


@pytest.mark.parametrize("actions", [[0, 0, 0], None, (0, 0, 0), 0, "robot_0", np.zeros(3)])
def test_parallel_step_of_a_non_dict_is_a_one_line_error(actions):
    env = senv.SwarmParallelEnv(**SMALL)
    env.reset(seed=0)
    with pytest.raises(InvalidInput, match=r"^actions: got .*; allowed: a dict of agent name -> action"):
        env.step(actions)
    with pytest.raises(InvalidInput, match="an action for every live agent"):
        env.step({1: 0, "robot_0": 0})  # keys of mixed types are shown, not sorted
    assert env.step(dict.fromkeys(env.agents, 0))[4]["robot_0"]["tick"] == 1


def test_ticks_per_step_and_spec_options_reach_the_run():
    env = senv.SwarmEnv(robots=5, size=26, map="cave", radio="los", ticks_per_step=4,
                        lidar={"range_m": 5.0}, stop={"max_ticks": 60})
    env.reset(seed=9)
    spec = env.core.sim.spec
    assert (spec.robots.count, spec.map.kind, spec.map.size, spec.radio.model, spec.lidar.range_m) == \
        (5, "cave", 26, "los", 5.0)
    _, _, _, _, info = env.step(0)
    assert info["tick"] == 4
    assert env.observation_space["neighbours"].shape == (4, 4)


def test_import_swarm_imports_no_rl_library():
    code = ("import sys, swarm; swarm.run; swarm.campaign.load; swarm.RunSpec; "
            "print(sorted(m for m in sys.modules if m.split('.')[0] in ('gymnasium', 'pettingzoo', 'torch')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"
