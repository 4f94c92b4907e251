"""``render()`` of the RL environments: a readable picture (about ``render_px`` on its longer side), the
team's knowledge painted by the viewer's rules (:mod:`swarm.draw`), every robot drawn where the
runtime has it, learners blue and teammates red."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("gymnasium")
pytest.importorskip("pettingzoo")

import swarm.env as senv
from maps import InvalidInput
from maps.materials import colour_of
from swarm.env.render import (
    FREE,
    LEARNER,
    SCRIPTED,
    UNKNOWN,
    cell_px,
    world_to_pixel,
)
from swarm.draw import UNSEEN_WALL_FADE, mix

SPEC = {"robots": {"count": 3, "spawn": "random"}, "size": 20, "stop": {"max_ticks": 300}}


def _frame_after(env, steps: int) -> np.ndarray:
    env.reset(seed=3)
    for _ in range(steps):
        env.step({a: 0 for a in env.agents})
    return env.render()


@pytest.mark.parametrize("render_px, side", [(600, 600), (300, 280), (1000, 1000)])
def test_the_picture_has_the_asked_size_and_type(render_px, side):
    env = senv.SwarmParallelEnv(**SPEC, render_mode="rgb_array", render_px=render_px)
    frame = _frame_after(env, 0)
    rows, cols = env.core.sim.truth.shape
    assert frame.dtype == np.uint8 and frame.shape == (rows * cell_px((rows, cols), render_px),
                                                       cols * cell_px((rows, cols), render_px), 3)
    assert frame.shape[:2] == (side, side)  # 40 x 40 cells: 15, 7 and 25 px a cell


def test_robots_are_drawn_where_they_are_in_their_colours():
    env = senv.SwarmParallelEnv(**SPEC, learners=[1], render_mode="rgb_array")
    frame = _frame_after(env, 20)
    shape = env.core.sim.truth.shape
    scale = cell_px(shape, 600)
    poses = np.asarray(env.core.sim.world.poses)
    for robot, (x, y, _) in enumerate(poses):
        col, row = world_to_pixel(x, y, shape, scale)
        want = LEARNER if robot == 1 else SCRIPTED
        # the disc's centre, and a point half a radius off it (the heading line may cross the centre)
        pixels = {tuple(frame[int(row) + dr, int(col) + dc]) for dr, dc in [(0, 0), (2, 0), (-2, 0), (0, 2), (0, -2)]}
        assert want in pixels, (robot, pixels)
    # robot colours appear only near robots: nowhere more than 3 m from every robot
    rr, cc = np.nonzero(np.all(frame == LEARNER, axis=2) | np.all(frame == SCRIPTED, axis=2))
    xs, ys = cc / scale * 0.5, (shape[0] - rr / scale) * 0.5
    nearest = np.min(np.hypot(xs[:, None] - poses[None, :, 0], ys[:, None] - poses[None, :, 1]), axis=1)
    assert nearest.max() < 3.0


def test_knowledge_is_painted_as_the_viewer_paints_it():
    """Seen floor near-white, unseen floor grey, seen walls in their material's colour, unseen walls that
    colour faded towards the unseen grey (viewer.js ``paintCell``, union view)."""
    env = senv.SwarmParallelEnv(**SPEC, render_mode="rgb_array")
    frame = _frame_after(env, 5)
    sim = env.core.sim
    union = sim.known.max(axis=0)
    scale = cell_px(union.shape, 600)
    centre = frame[scale // 2::scale, scale // 2::scale][::-1]  # one pixel per cell, row 0 at the bottom
    poses = np.asarray(sim.world.poses)
    rows, cols = np.indices(union.shape)
    far = np.min(np.hypot((cols[..., None] + 0.5) * 0.5 - poses[:, 0], (rows[..., None] + 0.5) * 0.5 - poses[:, 1]),
                 axis=2) > 2.5  # away from discs and ids
    truth = sim.truth
    seen = union != 0
    free = ~truth.solid & far
    assert (free & seen).any() and np.all(centre[free & seen] == FREE)
    assert (free & ~seen).any() and np.all(centre[free & ~seen] == UNKNOWN)
    walls = truth.solid & far
    assert (walls & seen).any() and (walls & ~seen).any()
    for r, c in zip(*np.nonzero(walls)):
        colour = colour_of(truth.materials[truth.material[r, c]])
        want = colour if seen[r, c] else mix(colour, UNKNOWN, UNSEEN_WALL_FADE)
        assert tuple(centre[r, c]) == tuple(want), (r, c)


def test_single_agent_env_renders_the_same_way_and_none_without_a_mode():
    env = senv.SwarmEnv(**SPEC, render_mode="rgb_array", render_px=200)
    env.reset(seed=3)
    assert env.render().shape == (200, 200, 3)
    quiet = senv.SwarmEnv(**SPEC)
    quiet.reset(seed=3)
    assert quiet.render() is None


@pytest.mark.parametrize("bad", [0, 10, 5000, 600.5, "big"])
def test_a_bad_render_px_is_one_line_naming_it(bad):
    with pytest.raises(InvalidInput, match="render_px"):
        senv.SwarmParallelEnv(**SPEC, render_px=bad)
