"""TNF's terms on the window of what the robot knows equal the whole map's (issue 47): every candidate,
its gain, distance, penalty and utility, bit for bit, on buildings seen from one spot, with other robots'
destinations near and far, exclusions, and robots at the map's edge."""

from __future__ import annotations

import numpy as np
import pytest

from algorithms import tnf_utility
from algorithms.tnf_utility import score_frontiers
from maps import generate
from swarm.api import FREE, SOLID, UNSEEN


def seen_from_spots(truth_solid: np.ndarray, spots: list[tuple[int, int]], radius: int) -> np.ndarray:
    """A map known only in squares around ``spots`` (what a robot early in a large map knows)."""
    known = np.full(truth_solid.shape, UNSEEN, np.uint8)
    for r, c in spots:
        box = (slice(max(r - radius, 0), r + radius + 1), slice(max(c - radius, 0), c + radius + 1))
        known[box] = np.where(truth_solid[box], SOLID, FREE)
    return known


@pytest.mark.parametrize("seed", range(6))
def test_every_frontier_score_on_the_window_is_the_whole_maps(seed: int, monkeypatch: pytest.MonkeyPatch) -> None:
    truth = generate("building", 150, seed)
    rng = np.random.default_rng(seed)
    free = np.argwhere(~truth.solid)
    windowed = penalised = scored = 0
    for trial in range(5):
        start = tuple(int(v) for v in free[rng.integers(len(free))])
        spots = [start] + [(start[0] + int(rng.integers(-40, 40)), start[1] + int(rng.integers(-40, 40)))
                           for _ in range(4)]
        known = seen_from_spots(truth.solid, spots, int(rng.integers(10, 25)))
        seen_free = np.argwhere(known == FREE)
        dest = np.array([tuple(int(v) for v in seen_free[rng.integers(len(seen_free))]) for _ in range(6)]
                        + [tuple(int(v) for v in free[rng.integers(len(free))]) for _ in range(4)]
                        + [(-5, 10), (400, 400)], dtype=np.int64)
        exclude = None
        if trial % 2:
            exclude = np.zeros(known.shape, bool)
            exclude[start[0] - 6:start[0] + 6, start[1] + 3:start[1] + 9] = True
        kw = dict(alpha=1.0, beta=10.0, robot_radius_m=0.3, penalty_radius_m=float(rng.choice([3.0, 7.0, 0.0])),
                  reach=2, exclude=exclude, min_size=int(rng.integers(1, 4)))
        monkeypatch.setattr(tnf_utility, "WINDOW_SHARE", 0.5)
        got = score_frontiers(known, start, dest, **kw)
        windowed += tnf_utility._known_window(known, start, 2, 0.3, 0.05, kw["penalty_radius_m"]) is not None
        monkeypatch.setattr(tnf_utility, "WINDOW_SHARE", 0.0)        # never a window: the whole map
        want = score_frontiers(known, start, dest, **kw)
        assert got == want, (seed, trial)
        scored += len(got)
        penalised += sum(score.penalty > 0 for score in got)
    assert windowed >= 4 and scored >= 5 and penalised >= 1, "the cases must be decided on windows, with penalties"
