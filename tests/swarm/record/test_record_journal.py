"""The recorder diffs robots' maps only where the run's journal says they were written: its recordings
must be byte for byte those of whole-map diffs, whatever writes the maps (lidar from a believed pose,
delta and full map sharing with losses, MAES's merges, a log-odds lidar, failures)."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from swarm.knowledge.journal import KnowledgeJournal
from swarm.record import Recorder
from swarm.sim.loop import Simulation

BASE = {"seed": 4, "map": {"kind": "building", "size": 40}, "robots": {"count": 5, "spawn": "random"},
        "algorithm": {"name": "frontier"}, "stop": {"max_ticks": 260}}

CASES: dict[str, dict[str, Any]] = {
    "delta_lossy": {"comm": {"loss": 0.3, "share_every": 3}},
    "full_sharing": {"comm": {"map_sharing": "full", "share_every": 5}},
    "maes_merge": {"algorithm": {"name": "greed"}, "comm": {"map_sharing": "maes"}},
    "odometry": {"localization": {"model": "odometry", "drift_per_m": 0.05}},
    "logodds": {"lidar": {"noise_std": 0.05, "mode": "logodds"}},
    "no_sharing": {"comm": {"map_sharing": "off"}},
}


def _spec(extra: dict[str, Any]) -> dict[str, Any]:
    spec = {k: dict(v) if isinstance(v, dict) else v for k, v in BASE.items()}
    for key, value in extra.items():
        spec[key] = {**spec.get(key, {}), **value}
    return spec


def _record(spec: dict[str, Any], journal: bool) -> bytes:
    sim = Simulation(spec)
    recorder = Recorder.attach(sim, journal=journal, block_ticks=50)
    result = sim.run()
    recorder.finish(sim, result)
    return recorder.to_bytes()


@pytest.mark.parametrize("case", sorted(CASES))
def test_journal_recording_is_the_whole_map_recording(case):
    spec = _spec(CASES[case])
    assert _record(spec, journal=True) == _record(spec, journal=False)


def test_take_finds_exactly_the_changed_cells_and_only_noted_places_are_read():
    rng = np.random.default_rng(0)
    n, h, w = 3, 70, 90
    known = np.zeros((n, h, w), dtype=np.uint8)
    mirror = np.zeros_like(known)
    journal = KnowledgeJournal(n, (h, w), reach=4)
    assert len(journal.take(known, mirror)) == 0          # whole at first: compared, nothing differs
    known[1, 10, 12] = 1                                    # inside robot 1's lidar window (pose at cell 10, 12)
    known[2, 65, 85] = 2                                    # a merged cell of robot 2
    known[0, 40, 40] = 2                                    # written but never noted: not seen by take
    poses = np.array([[0, 0, 0], [6.25, 5.25, 0], [0, 0, 0]], dtype=np.float64)
    journal.scanned(poses, np.array([False, True, False]))

    journal.merged([2], np.array([65 * w + 85], dtype=np.int64))   # a delta's cells, for its receiver
    journal.merged([], None)                                           # reaching nobody: nothing noted
    got = journal.take(known, mirror)
    assert got.tolist() == [1 * h * w + 10 * w + 12, 2 * h * w + 65 * w + 85]
    assert mirror[0, 40, 40] == 0 and mirror[1, 10, 12] == 1 and mirror[2, 65, 85] == 2
    assert not journal.noted.any() and not journal.tiles.any()
    journal.rewritten([0])                                  # e.g. MAES's merge: the whole map is compared
    assert journal.take(known, mirror).tolist() == [40 * w + 40]
    # a random workload against a plain diff, tile edges included
    for _ in range(20):
        cells = rng.integers(0, h * w, size=30)
        robots = rng.integers(0, n, size=30)
        known.reshape(n, -1)[robots, cells] = rng.integers(1, 3, size=30).astype(np.uint8)
        for r in range(n):
            mine = np.sort(cells[robots == r])
            journal.merged([r], mine)
        expected = np.flatnonzero(known.reshape(-1) != mirror.reshape(-1))
        assert journal.take(known, mirror).tolist() == expected.tolist()
