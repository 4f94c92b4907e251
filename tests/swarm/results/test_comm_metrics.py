"""Communication metrics of real runs on hand-made maps (docs/comm-metrics.md): age of information, the
share of the team's map a robot misses, drops by cause, and that comm settings show in these numbers
where exploration time does not."""

from __future__ import annotations

import numpy as np
import pytest

from maps import Map
from swarm.results.metrics import InfoAges
from swarm.results.schema import COMM_ROBOT_SERIES, COMM_SERIES, DROP_CAUSES, CommSummary
from swarm.sim.loop import Simulation

QUIET = "tests.swarm.agents:Quiet"
TALKER = "tests.swarm.agents:Talker"
WALL_60DB = {"model": "multiwall", "materials": {"concrete": [60, 60, 60]}}
"""Concrete re-priced so that no link crosses the wall (15 dBm - 40 dB - 60 dB < -82 dBm at any distance)."""


def two_rooms() -> Map:
    """A 24 x 10 m box split by a 1.5 m concrete wall at x = 11.5..13 m: two sealed 11 x 9 m rooms."""
    solid = np.zeros((20, 48), dtype=bool)
    solid[0, :] = solid[-1, :] = solid[:, 0] = solid[:, -1] = True
    solid[:, 23:26] = True
    return Map(solid=solid, material=solid.astype(np.uint8), materials=("air", "concrete"))


def run(poses, radio, comm=None, algorithm=QUIET, ticks=30, explored=1.0):
    spec = {"algorithm": {"name": algorithm}, "robots": {"count": len(poses)}, "radio": radio,
            "comm": comm or {}, "stop": {"max_ticks": ticks, "explored": explored}, "record_every": 1,
            "map": {"kind": "file", "path": "unused.npz"}}
    return Simulation(spec, truth=two_rooms(), start_poses=np.array(poses, dtype=float)).run()


LEFT3 = [(3.0, 5.0, 0.0), (6.0, 5.0, 0.0), (20.0, 5.0, 0.0)]  # robots 0 and 1 left of the wall, 2 right


def test_the_comm_result_has_the_schemas_fields():
    r = run(LEFT3, {"model": "global"}, ticks=5)
    assert set(r.comm["series"]) == set(COMM_SERIES)
    assert set(r.comm["robots"]) == set(COMM_ROBOT_SERIES)
    assert set(r.comm["summary"]) == set(CommSummary.__annotations__)
    assert r.comm["series"]["tick"] == r.timeseries["tick"], "one row per time-series row"
    assert all(len(row) == 3 for rows in r.comm["robots"].values() for row in rows)


def test_age_is_zero_for_every_robot_under_global_radio_sharing_every_tick():
    r = run(LEFT3, {"model": "global"}, comm={"map_sharing": "full", "share_every": 1}, ticks=8)
    ages = r.comm["robots"]["aoi_age"]
    ticks = r.comm["series"]["tick"]
    assert ticks[0] == 0 and ages[0] == [0.0, 0.0, 0.0], "at the start nobody's information is old"
    for tick, row in zip(ticks[1:], ages[1:]):
        assert row == [0.0, 0.0, 0.0], f"tick {tick}: every robot merged every other's map this tick"
    missing = r.comm["robots"]["missing_free"]
    assert max(missing[0]) > 0.3 and all(row == [0.0] * 3 for row in missing[1:]), \
        "after one exchange every robot knows every free cell the team knows"


def test_age_grows_for_a_robot_cut_off_behind_concrete():
    r = run(LEFT3, WALL_60DB, comm={"map_sharing": "full", "share_every": 1}, ticks=12)
    ticks = r.comm["series"]["tick"]
    ages = np.array(r.comm["robots"]["aoi_age"])
    assert ages[:, 2].tolist() == [float(t) for t in ticks], "robot 2 never merges anyone's map: age = ticks"
    assert np.all(np.diff(ages[1:, 2]) > 0)
    assert ages[1:, 0].tolist() == [t / 2 for t in ticks[1:]], "robot 0: robot 1 current (0), robot 2 never (t)"
    missing = np.array(r.comm["robots"]["missing_free"])[-1]
    assert missing[0] == missing[1] > 0.3 and missing[2] > 0.3, "each side misses the other room"
    groups = r.comm["robots"]["group"][-1]
    assert groups == [0, 0, 1], "groups are numbered by their lowest robot"
    assert r.comm["summary"]["all_connected_share"] == 0
    assert r.comm["summary"]["biggest_group_mean"] == pytest.approx(2 / 3)


def test_age_comes_through_a_relaying_robots_map():
    """Robot 0 hears only robot 1, robot 1 hears robots 0 and 2: robot 0's information about robot 2 comes
    inside robot 1's map, one tick older than robot 1's."""
    ages = InfoAges(3)
    ages.sent(tick=4)
    ages.merged([(np.array([1]), 2, 4)], tick=5)   # robot 1 merges robot 2's update of tick 4 at tick 5
    ages.sent(tick=5)
    ages.merged([(np.array([0]), 1, 5)], tick=6)   # robot 0 merges robot 1's update of tick 5 at tick 6
    assert ages.merged_at[0].tolist() == [0, 6, 5] and ages.merged_at[1].tolist() == [0, 0, 5]
    assert ages.ages(6).tolist() == [(0 + 1) / 2, (6 + 1) / 2, 6.0]


def test_an_update_merged_keep_ticks_after_it_was_sent_counts_only_for_its_sender():
    """Snapshots are kept for KEEP_TICKS ticks, one per tick at which updates were sent (not one per tick of
    the window): an update relayed for longer brings its sender's own entry, not what its map held."""
    keep = InfoAges.KEEP_TICKS
    ages = InfoAges(3)
    ages.merged([(np.array([1]), 2, 0)], tick=1)          # robot 1 holds robot 2's map as of tick 1
    for tick in range(2, 3 * keep, 10):
        ages.sent(tick)                                   # updates go out every 10 ticks
    assert ages.snapshots() <= keep // 10 + 1, "a slot per sending tick of the window"
    now = 2 * keep + 3
    recent = max(t for t in range(2, now, 10))            # the last sending tick before now
    old = max(t for t in range(2, now - keep, 10))        # one more than keep ticks before now
    ages.merged([(np.array([0]), 1, recent)], tick=now)   # robot 2 comes inside robot 1's map
    assert ages.merged_at[0].tolist() == [0, now, 1]
    ages.merged([(np.array([2]), 1, old)], tick=now)      # too old: the sender's own entry only
    assert ages.merged_at[2].tolist() == [0, now, 0]


@pytest.mark.parametrize("seed", range(3))
def test_merged_ages_are_the_row_by_row_maxima_of_the_snapshots_read(seed):
    """InfoAges.merged against the definition, merge by merge: each receiver's row rises to its sender's row
    of the snapshot of the send tick, and its entry for the sender becomes now. 150 robots over three
    blocks of receivers; some merge nearly every sender of a snapshot (the column-top path), some a few
    (rows gathered per block), some an update older than the snapshots kept (own entry only)."""
    rng = np.random.default_rng(seed)
    n, keep = 150, 3
    ages = InfoAges(n, keep_ticks=keep)
    snapshots = {}
    for tick in (7, 8):  # (tables drawn afresh, so that neither snapshot nor the rows now bound another)
        ages.merged_at[:] = rng.integers(0, tick + 1, (n, n), dtype=np.int32)
        ages.sent(tick)
        snapshots[tick] = ages.merged_at.copy()
    ages.merged_at[:] = rng.integers(0, 5, (n, n), dtype=np.int32)
    now = 9
    merges = []
    for sender in range(n):
        for sent in (7, 8, 2):
            share = {7: 0.995, 8: 0.2, 2: 0.1}[sent]
            receivers = np.flatnonzero(rng.random(n) < share)
            receivers = receivers[receivers != sender]
            if len(receivers):
                merges.append((receivers.astype(np.int64), sender, sent))
    want = ages.merged_at.copy()
    for receivers, sender, sent in merges:
        if sent in snapshots:
            want[receivers] = np.maximum(want[receivers], snapshots[sent][sender])
    for receivers, sender, _ in merges:
        want[receivers, sender] = now
    ages.merged(merges, tick=now)
    assert np.array_equal(ages.merged_at, want)
    assert ages.merges == sum(len(m[0]) for m in merges)


def test_a_run_keeps_snapshots_only_as_long_as_its_updates_travel(monkeypatch):
    """InfoAges keeps a snapshot for one tick more than a map update can take to arrive (a tick; flooded, a
    tick a hop): one or two of them, not one per sending tick of KEEP_TICKS (n^2 int32 each). Ages, merges
    and every other result are those of the 64-tick window, direct and flooded."""
    from swarm.comm.medium import CommSpec

    assert CommSpec(relay_hops=4).longest_delivery_ticks + 1 == 2
    assert CommSpec(relay="flood", relay_hops=4).longest_delivery_ticks + 1 == 5
    ages = InfoAges(3, keep_ticks=2)
    for tick in range(1, 30):
        ages.sent(tick)                                   # full maps asked for: updates every tick
    assert ages.snapshots() == 2
    ages.merged([(np.array([0]), 1, 29)], tick=30)        # a tick old: read from its snapshot
    ages.merged([(np.array([1]), 2, 28)], tick=30)        # two: older than any update of the run
    assert ages.merged_at[0, 1] == 30 and ages.merged_at[1, 2] == 30
    for comm in ({"share_every": 1}, {"relay": "flood", "relay_hops": 3, "loss": 0.2}):
        spec = {"seed": 4, "map": {"kind": "building", "size": 40}, "robots": {"count": 6, "spawn": "random"},
                "algorithm": {"name": "frontier"}, "comm": comm, "stop": {"max_ticks": 150}}
        kept = Simulation(spec)
        result = kept.run()
        assert kept.ages.snapshots() <= kept.comm.longest_delivery_ticks + 1
        monkeypatch.setattr(CommSpec, "longest_delivery_ticks", property(lambda self: InfoAges.KEEP_TICKS))
        wide = Simulation(spec)
        other = wide.run()
        assert other.comm == result.comm and other.timeseries == result.timeseries
        assert wide.ages.snapshots() > kept.ages.snapshots()
        assert result.comm["summary"]["map_merges"] > 0
        monkeypatch.undo()


def test_a_gap_in_deltas_stops_counting_merges_until_the_full_map():
    """A delta after a lost one leaves the receiver without the sender's whole map: no merge counted (age
    keeps growing) until the full map it asks for arrives."""
    from swarm.comm.medium import CommSpec
    from swarm.comm.sharing import MapSharing
    from swarm.comm.messages import decode, encode

    ages = InfoAges(2)
    sharing = MapSharing(2, (10, 10), CommSpec(share_every=1), ages=ages)
    known = np.zeros((2, 10, 10), np.uint8)
    merged = []
    for tick in range(6):
        known[0].reshape(-1)[tick] = 1  # robot 0 learns a cell every tick
        out = sharing.outgoing(tick, known, np.zeros((2, 3)))
        deliveries = [(decode(encode(m)), [1]) for m in out[0] if tick != 1]  # update 2 is lost
        deliveries += [(decode(encode(m)), [0]) for m in out[1]]
        sharing.receive_tick(deliveries, known, np.ones(2, bool), cells=False, tick=tick + 1)
        merged.append(int(ages.merged_at[1, 0]))
    assert merged == [1, 1, 1, 1, 5, 6], ("the deltas of ticks 2 and 3 follow the lost one; the full map robot 1 "
                                          "asked for is sent at tick 4, and the delta after it counts again")


def test_a_round_its_requests_and_the_full_maps_they_ask_for_take_one_snapshot():
    """A sharing round (tick 10), the requests for missed updates (tick 11: no map goes out) and the full maps
    they ask for (tick 12) keep one n x n snapshot, not two: a tick of requests alone has nothing for a
    snapshot to serve, and the round's is stale by tick 12 (a delivery takes a tick)."""
    from swarm.comm.medium import CommSpec
    from swarm.comm.messages import MapRequest, MapUpdate
    from swarm.comm.sharing import MapSharing

    ages = InfoAges(3, keep_ticks=2)
    sharing = MapSharing(3, (10, 10), CommSpec(share_every=10), ages=ages)
    known = np.zeros((3, 10, 10), np.uint8)
    known[:, 0, :3] = 1
    poses = np.zeros((3, 3))
    kinds, snapshots = [], []
    for tick in (10, 11, 12):
        if tick == 11:
            sharing.requests[2] = [0]  # robot 2 missed robot 0's update: it asks for the full map
        if tick == 12:
            sharing.full_requested[0] = True  # robot 0 heard the request
        out = sharing.outgoing(tick, known, poses)
        kinds.append(sorted(type(m).__name__ + (" full" if getattr(m, "full", False) else "") for box in out
                            for m in box))
        snapshots.append(ages.snapshots())
    assert kinds == [[MapUpdate.__name__] * 3, [MapRequest.__name__], [MapUpdate.__name__ + " full"]]
    assert snapshots == [1, 1, 1], "none for the requests; the round's slot is reused by the full maps"
    assert ages.snapshots() == 1 and ages._ring_tick.max() == 12


@pytest.mark.parametrize("relay", ["none", "flood"])
def test_drops_by_cause_add_up_to_sent_minus_delivered_per_receiver(relay):
    """Robot 3 is behind the wall (link), a third of the rest is lost (loss), and every link carries a ping a
    tick but no map update (bandwidth). Relaying adds copies a robot already had (duplicates)."""
    from swarm.comm.messages import encode
    from tests.swarm.agents import Ping

    poses = [(3.0, 5.0, 0.0), (6.0, 5.0, 0.0), (9.0, 3.0, 0.0), (20.0, 5.0, 0.0)]
    budget = 2 * len(encode(Ping(3, 40)))
    comm = {"map_sharing": "full", "share_every": 1, "loss": 0.3, "bandwidth": budget, "relay": relay}
    r = run(poses, WALL_60DB, comm=comm, algorithm=TALKER, ticks=40)
    m = r.summary["messages"]
    duplicates = m.get("duplicates", 0)
    assert all(m[cause] > 0 for cause in DROP_CAUSES) and m["delivered"] > 0, \
        "every cause occurs and some messages arrive, so the sum is a real check"
    assert (duplicates > 0) == (relay == "flood")
    assert sum(m[cause] for cause in DROP_CAUSES) == m["sent"] * 3 - m["delivered"] - duplicates
    s = r.comm["series"]
    for k in range(len(s["tick"])):
        dropped = sum(s[f"msgs_{cause}"][k] for cause in DROP_CAUSES)
        assert dropped == r.timeseries["msgs_dropped"][k]
        if relay == "none":
            assert dropped == r.timeseries["msgs_sent"][k] * 3 - r.timeseries["msgs_delivered"][k]
    assert r.comm["summary"]["bytes_dropped"] == m["bytes_sent"] * 3 - m["bytes_delivered"] > 0


def test_comm_settings_differ_in_these_numbers_where_exploration_time_does_not():
    """One frontier robot per sealed room: each explores its own room whatever it hears, so comm off, global
    and multiwall explore in the same ticks; the comm metrics tell them apart."""
    poses = [(3.0, 5.0, 0.0), (21.0, 5.0, 0.0)]
    runs = {name: run(poses, radio, comm, algorithm="frontier", ticks=3000, explored=0.99)
            for name, radio, comm in (("off", {"model": "global"}, {"map_sharing": "off"}),
                                      ("global", {"model": "global"}, {}), ("multiwall", WALL_60DB, {}))}
    assert len({tuple(r.summary["ticks_to"].items()) for r in runs.values()}) == 1, "exploration time is the same"
    off, glob, wall = (runs[k].comm["summary"] for k in ("off", "global", "multiwall"))
    assert runs["off"].summary["messages"]["sent"] == 0 and runs["multiwall"].summary["messages"]["delivered"] == 0
    assert runs["multiwall"].summary["messages"]["dropped_link"] == runs["multiwall"].summary["messages"]["sent"] > 0
    assert glob["missing_free_mean"] < 0.1 < off["missing_free_mean"] == wall["missing_free_mean"]
    assert glob["aoi_age_mean"] < off["aoi_age_mean"] == wall["aoi_age_mean"]
    assert glob["map_merges"] > 0 == off["map_merges"] == wall["map_merges"]
    assert glob["biggest_group_mean"] == 1 and wall["biggest_group_mean"] == 0.5
    assert wall["bytes_dropped"] > 0 == glob["bytes_dropped"]


@pytest.mark.parametrize("mode", ["maes_heartbeat", "maes_sync"])
def test_maes_merges_count_for_age_of_information(mode):
    r = run(LEFT3, {"model": "global"}, comm={"map_sharing": mode, "share_every": 1}, algorithm="greed", ticks=6)
    ages = np.array(r.comm["robots"]["aoi_age"])
    assert r.comm["summary"]["map_merges"] > 0
    assert ages[-1].min() < r.comm["series"]["tick"][-1], "a MAES merge made some robot's information fresher"


@pytest.mark.parametrize("comm, lidar", [({}, {}), ({"map_sharing": "full", "share_every": 3}, {}),
                                         ({"loss": 0.4, "share_every": 2}, {}),
                                         ({"map_sharing": "maes_heartbeat", "share_every": 5}, {}),
                                         ({}, {"mode": "logodds", "noise_std": 0.05})])
def test_the_kept_free_counts_equal_counting_the_maps(comm, lidar):
    """The lidar's and the merges' counts of cells turned FREE, and the maps counted afresh after a whole-map
    merge, add up to what counting the maps gives, whatever the sharing."""
    spec = {"map": {"kind": "building", "size": 30}, "robots": {"count": 4, "spawn": "random"}, "seed": 4,
            "algorithm": {"name": "greed"}, "comm": comm, "lidar": lidar, "stop": {"max_ticks": 150}}
    sim = Simulation(spec)
    r = sim.run()
    assert r.comm["summary"]["map_merges"] > 0
    assert sim.free.read(sim.known).tolist() == (sim.known == 1).sum(axis=(1, 2)).tolist()


def test_the_merge_of_a_round_equals_merging_row_by_row():
    """InfoAges.merged takes, per receiver and snapshot, the column maxima of the senders' rows it merged
    (the largest values of all of them when it merged nearly all): the same rows as merging update by
    update, on random rounds with several snapshots, an expired one and receivers that merged few or
    nearly all senders."""
    from swarm.results.metrics import _merge_ages

    def by_rows(merged_at, ring, ring_tick, receivers, ends, senders, sent, tick, keep):
        start = 0
        for j in range(len(ends)):
            slot = [k for k in range(len(ring_tick)) if ring_tick[k] == sent[j] and sent[j] > tick - keep]
            for r in receivers[start:ends[j]]:
                if slot:
                    merged_at[r] = np.maximum(merged_at[r], ring[slot[0], senders[j]])
                merged_at[r, senders[j]] = tick
            start = ends[j]

    rng = np.random.default_rng(0)
    for _ in range(200):
        n, slots = int(rng.integers(1, 40)), int(rng.integers(1, 4))
        ring = rng.integers(0, 100, (slots, n, n)).astype(np.int32)
        ring_tick = rng.choice(np.arange(90, 110), slots, replace=False).astype(np.int64)
        m = int(rng.integers(0, 3 * n + 1))
        senders = rng.integers(0, n, m).astype(np.int64)
        sent = rng.choice(np.concatenate([ring_tick, [5, 111]]), m).astype(np.int64)
        reached = [np.flatnonzero((rng.random(n) < rng.random()) & (np.arange(n) != s)) for s in senders]
        receivers = np.concatenate(reached).astype(np.int64) if m else np.zeros(0, np.int64)
        ends = np.cumsum([len(x) for x in reached]).astype(np.int64) if m else np.zeros(0, np.int64)
        start = rng.integers(0, 100, (n, n)).astype(np.int32)
        a, b = start.copy(), start.copy()
        _merge_ages(a, ring, ring_tick, receivers, ends, senders, sent, 120, 64)
        by_rows(b, ring, ring_tick, receivers, ends, senders, sent, 120, 64)
        assert np.array_equal(a, b)
