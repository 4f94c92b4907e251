"""Greed's ``variant = "maes"`` (issue 49 rows 4 and 5): it drives on to its target until within 0.5 m
(``Greed.cs`` 149-176, 237) however soon the target is seen, and its first move is straight ahead until it
hits something (``Greed.cs`` 179-184), from MAES's +y spawn heading (``robots.heading = "maes"``)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from algorithms.greed import MAES_REACHED_M, Greed, GreedParams
from maps import InvalidInput, Map
from swarm.api import FREE, NavStatus, Pose, RobotInfo
from swarm.sim.loop import Simulation
from swarm.sim.spec import RunSpec

from .test_greed import new_greed, observe, wall_map


def started(**params) -> tuple[Greed, tuple[float, float]]:
    """A MAES-variant Greed past its straight first move (a collision ended it; no back-off, so it chooses
    at once) and its first goal, on wall_map()."""
    g = new_greed(variant="maes", backoff_ticks=0, **params)
    goal = g.act(observe(wall_map(), tick=0, collided=True)).goal
    assert goal is not None
    return g, goal


# ------------------------------------------------------------------------ row 4: drive on to 0.5 m ----
def test_maes_keeps_its_target_after_it_is_seen_until_within_half_a_metre():
    g, first = started()
    known = wall_map()
    known[18:23, 2:6] = FREE                      # the west block is seen: swarm's Greed re-targets here
    moving = NavStatus(goal=first, state="moving")
    assert g.act(observe(known, tick=1, nav=moving)).goal == first, "MAES drives on to a seen target"
    # Still 0.6 m short: it keeps going.
    short = (first[0] + 0.6, first[1])
    assert g.act(observe(known, tick=2, nav=moving, pose=_pose(short))).goal == first
    # Within 0.5 m (MAES's IsDestinationReached): it chooses again -- the block behind the wall.
    near = (first[0] + 0.4, first[1])
    again = g.act(observe(known, tick=3, nav=moving, pose=_pose(near))).goal
    assert again != first and again[0] > 15.0
    assert MAES_REACHED_M == 0.5


def test_swarm_variant_still_retargets_when_the_target_is_seen():
    g = new_greed(backoff_ticks=0)
    first = g.act(observe(wall_map(), tick=0)).goal
    known = wall_map()
    known[18:23, 2:6] = FREE
    assert g.act(observe(known, tick=1, nav=NavStatus(goal=first, state="moving"))).goal != first


def test_maes_still_gives_up_an_unreachable_target():
    g, first = started()
    second = g.act(observe(wall_map(), tick=1, nav=NavStatus(goal=first, state="unreachable"))).goal
    assert second is not None and math.dist(first, second) > 1.0


# ------------------------------------------------------------------ row 5: the straight first move ----
def test_maes_first_move_is_straight_ahead_at_full_speed_until_a_collision():
    g = Greed()
    g.reset(RobotInfo(id=0, n_robots=1, map_shape=(40, 60), max_speed=3.0), GreedParams(variant="maes"),
            np.random.default_rng(0))
    for tick in range(30):   # a known unseen block and nothing hit yet: no target, straight on
        a = g.act(observe(wall_map(), tick=tick, theta=math.pi / 2))
        assert a.velocity == (3.0, 0.0) and a.goal is None
    hit = g.act(observe(wall_map(), tick=30, theta=math.pi / 2, collided=True))
    assert hit.velocity != (3.0, 0.0), "the collision ends the straight move"
    later = [g.act(observe(wall_map(), tick=t, theta=math.pi / 2)) for t in range(31, 60)]
    assert any(a.goal is not None for a in later), "then it heads for the nearest unseen cell"
    assert new_greed().act(observe(wall_map())).goal is not None, "swarm's Greed chooses at once"


def box() -> Map:
    """12 x 12 m, walls 0.5 m thick, all open inside."""
    solid = np.zeros((24, 24), dtype=bool)
    solid[0, :] = solid[-1, :] = solid[:, 0] = solid[:, -1] = True
    return Map(solid=solid, material=solid.astype(np.uint8), materials=("air", "concrete"))


def test_maes_robot_spawned_facing_up_drives_straight_up_until_it_hits_the_wall():
    poses, goals, forward = [], [], []

    def watch(view):
        poses.append(view.poses[0].copy())
        action = view.actions[0]
        goals.append(action.goal if action is not None else None)
        forward.append(action is not None and action.velocity is not None and action.velocity[0] > 0)

    spec = {"seed": 0, "robots": {"count": 1}, "algorithm": {"name": "greed", "params": {"variant": "maes"}},
            "stop": {"max_ticks": 160, "explored": 1.0}}
    Simulation(spec, truth=box(), start_poses=np.array([[3.25, 2.25, math.pi / 2]]), observers=(watch,)).run()
    p = np.array(poses)
    first_goal = next(i for i, goal in enumerate(goals) if goal is not None)
    straight = p[:first_goal]
    assert np.allclose(straight[:, 0], 3.25, atol=1e-6) and np.allclose(straight[:, 2], math.pi / 2, atol=1e-6)
    assert straight[-1, 1] > 10.5, f"it went up to the top wall (y 11.5 m) before choosing: {straight[-1]}"
    ahead = forward.index(False)            # the straight move ends with the collision (then backs off)
    assert ahead > 50 and all(forward[:ahead]) and not any(goals[:ahead])
    assert np.all(np.diff(p[:ahead, 1]) >= -1e-9) and p[ahead, 1] > 10.5


# -------------------------------------------------------------------------------- spawn heading ----
def test_maes_spawn_heading_faces_every_robot_up_and_changes_nothing_else():
    base = {"seed": 5, "map": {"kind": "cave", "size": 30}, "robots": {"count": 3}, "stop": {"max_ticks": 1}}
    maes = {**base, "robots": {"count": 3, "heading": "maes"}}
    a, b = Simulation(base).start_poses, Simulation(maes).start_poses
    assert np.array_equal(a[:, :2], b[:, :2]) and np.all(b[:, 2] == math.pi / 2)
    assert len(set(a[:, 2].tolist())) == 3, "the default draws random headings"
    assert "heading" not in RunSpec.from_mapping(base).to_json(), "default specs keep their key"
    with pytest.raises(InvalidInput):
        RunSpec.from_mapping({**base, "robots": {"count": 3, "heading": "north"}})


def test_variant_is_validated():
    assert GreedParams().variant == "swarm"
    with pytest.raises(InvalidInput):
        GreedParams(variant="MAES")


def _pose(xy: tuple[float, float]) -> Pose:
    return Pose(xy[0], xy[1], 0.0)


def test_maes_variant_passes_the_explorer_checker():
    from swarm.testing import check_explorer

    report = check_explorer("greed", params={"variant": "maes"})   # raises on a failed check
    messages = next(r.detail for r in report.results if r.check == "messages")
    assert messages.startswith("sends no messages of its own"), messages
