"""Fuzzing the learning environments (issue 48): the Gymnasium env (goal and velocity actions) and the
PettingZoo parallel env, built with keyword arguments of every type and shape, reset with odd seeds and
options, and stepped with actions of wrong shapes and types (None, strings, arrays, mappings, lists of the
wrong length, NaN). Every case must end in a result or one short :class:`~swarm.base.errors.InvalidInput`
line (or, for ``step`` after the episode ended, the documented ``RuntimeError``): never another exception, a
hang (each case is timed) or more than 1 GB of memory (the file's peak RSS growth).

After a refused step the environment must still step: a bad action changes nothing.

Cases per run (``max_examples``): 120 (constructors) + 100 (``reset``) + 3 x 200 (``step`` of the goal,
velocity and parallel envs) = 820 (~15 s on a 2-core machine).
"""

from __future__ import annotations


import numpy as np
import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

pytest.importorskip("gymnasium")
pytest.importorskip("pettingzoo")

import swarm.env as senv
from swarm.base.errors import InvalidInput
from tests.fuzz_bounds import bounded_memory, check_refusal, timed  # noqa: F401 (bounded_memory: a fixture)

FUZZ = settings(deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
                database=None)
SMALL = {"robots": 3, "size": 20, "max_ticks": 40}

ODD = [None, True, False, -1, 2**63, 10**400, 0.5, float("nan"), float("inf"), "", "x" * 300, "1", b"1", [], [1],
       [1, 2], [1, 2, 3], ["a", "b"], [[1.0, 0.0]], [[1.0], [2.0, 3.0]], (0.5, 0.5), {}, {"robot_0": 1}, {1: 0},
       set(), object(), print, np.int64(2), np.int8(-3), np.float64(1.0), np.bool_(True), np.array(3),
       np.array([1, 2]), np.array([0.5, 0.5]), np.array(["a", "b"]), np.zeros((2, 2)), np.array([np.nan, 0.0]),
       np.array([], dtype=float), np.array([1, 2], dtype=object), 1j, Ellipsis, range(2), slice(1)]
"""Actions and arguments of every type and shape."""
odd = st.sampled_from(ODD)


def mostly(good: st.SearchStrategy, bad_in_ten: int = 2) -> st.SearchStrategy:
    return st.sampled_from([True] * (10 - bad_in_ten) + [False] * bad_in_ten).flatmap(
        lambda ok: good if ok else odd)


# --------------------------------------------------------------------------------- construction ----
options = st.fixed_dictionaries({}, optional={
    "action": mostly(st.sampled_from(["goal", "velocity", "jump"])), "delegate": mostly(st.booleans()),
    "ticks_per_step": mostly(st.integers(1, 4)), "crop_cells": mostly(st.sampled_from([8, 16, 31, 2])),
    "observe_all": mostly(st.booleans()), "margin_db": mostly(st.floats(1, 100)),
    "reward": mostly(st.sampled_from([None, {"own": 1.0}, {"team": 0.5, "speed": 1}, {"own": "x"}])),
    "render_mode": mostly(st.sampled_from([None, "rgb_array", "human"])),
    "robots": mostly(st.integers(1, 4)), "size": mostly(st.sampled_from([20, 24, "20x24", 19])),
    "radio": mostly(st.sampled_from(["los", "global", "wifi"])), "transport": mostly(st.just("inprocess")),
})


@settings(FUZZ, max_examples=120)
@given(kind=st.sampled_from(["gym", "parallel"]), chosen=options,
       who=st.sampled_from([None, 0, 1, 5, -1, [0], [0, 2], "0", [0, 0], 1.5, (1,)]))
def test_constructors_give_an_env_or_one_line(kind, chosen, who):
    kwargs = {"max_ticks": 20, **chosen}
    if who is not None:
        kwargs["learner" if kind == "gym" else "learners"] = who
    with timed():
        try:
            env = senv.SwarmEnv(**kwargs) if kind == "gym" else senv.SwarmParallelEnv(**kwargs)
        except InvalidInput as exc:
            check_refusal(exc)
            return
        event("built")
        try:
            env.reset(seed=0)
        finally:
            env.close()


@pytest.fixture(scope="module")
def envs() -> dict[str, object]:
    """One of each env, reset; a case that ends an episode resets it."""
    made = {"goal": senv.SwarmEnv(**SMALL), "velocity": senv.SwarmEnv(**SMALL, action="velocity"),
            "parallel": senv.SwarmParallelEnv(**SMALL)}
    for env in made.values():
        env.reset(seed=0)
    yield made
    for env in made.values():
        env.close()


@settings(FUZZ, max_examples=100)
@given(which=st.sampled_from(["goal", "velocity", "parallel"]), seed=mostly(st.integers(0, 2**63 - 1)),
       opts=st.sampled_from([None, {}, {"x": 1}, 5]))
def test_reset_gives_an_observation_or_one_line(which, seed, opts, envs):
    env = envs[which]
    with timed():
        try:
            obs, info = env.reset(seed=seed, options=opts)
        except InvalidInput as exc:
            check_refusal(exc)
            env.reset(seed=0)
            return
        event("reset")
        assert isinstance(obs, dict) and isinstance(info, dict)


def _valid(env, which: str):
    if which == "goal":
        return 1
    if which == "velocity":
        return np.array([0.5, 0.1])
    return dict.fromkeys(env.agents, 1)


parallel_actions = st.one_of(odd, st.dictionaries(st.sampled_from(["robot_0", "robot_1", "robot_2", "robot_9", 0]),
                                                  st.one_of(st.integers(-2, 12), odd), max_size=4),
                             st.fixed_dictionaries({"robot_0": odd, "robot_1": st.integers(0, 8),
                                                    "robot_2": st.integers(0, 8)}))


@pytest.mark.parametrize("which", ["goal", "velocity", "parallel"])
@settings(FUZZ, max_examples=200)
@given(data=st.data())
def test_step_gives_a_step_or_one_line_and_a_refused_step_changes_nothing(which, data, envs):
    env = envs[which]
    action = data.draw(parallel_actions if which == "parallel" else
                       st.one_of(odd, st.integers(-3, 12), st.lists(st.floats(-2, 2), max_size=3)))
    with timed():
        tick = env.core.info()["tick"]
        try:
            out = env.step(action)
        except InvalidInput as exc:
            check_refusal(exc)
            assert env.core.info()["tick"] == tick, "a refused step changed the run"
            out = env.step(_valid(env, which))
        else:
            event("stepped")
        assert len(out) == 5
        if env.core.done:
            env.reset(seed=0)
