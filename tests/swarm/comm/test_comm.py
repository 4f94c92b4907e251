"""The radio medium and map sharing: one-tick delivery, the link model decides, deltas equal full maps."""

from __future__ import annotations

import zlib

import numpy as np
import pytest

from maps import Map, generate
from radio import RadioConfig, build_link_model
from swarm.api import CELL_M, FREE
from swarm.comm.medium import CommSpec, Medium
from swarm.comm.sharing import MapSharing
from swarm.comm.messages import MapRequest, MapUpdate, decode, encode
from swarm.sim.loop import Simulation
from tests.swarm.agents import Ping, Talker

TALKER = "tests.swarm.agents:Talker"


def walled_map(walls: int = 1) -> Map:
    """A 20 x 10 m box split by ``walls`` 1 m concrete walls at x = 9.5.. m (one cell gap between walls)."""
    solid = np.zeros((20, 40), dtype=bool)
    solid[0, :] = solid[-1, :] = solid[:, 0] = solid[:, -1] = True
    for k in range(walls):
        solid[:, 18 + 3 * k: 20 + 3 * k] = True
    return Map(solid=solid, material=solid.astype(np.uint8), materials=("air", "concrete"))


def talk(truth, poses, radio, ticks=4, comm=None):
    Talker.log = {}
    spec = {"algorithm": {"name": TALKER}, "robots": {"count": len(poses)}, "radio": radio,
            "comm": comm or {"map_sharing": "off"}, "stop": {"max_ticks": ticks, "explored": 1.0},
            "map": {"kind": "file", "path": "unused.npz"}}
    return Simulation(spec, truth=truth, start_poses=np.array(poses, dtype=float)).run()


def test_one_tick_delivery_and_no_self_delivery():
    talk(walled_map(0), [(3, 3, 0), (6, 3, 0)], {"model": "global"}, ticks=4)
    heard = Talker.log
    assert [(t, s, st) for t, s, st in heard[1]] == [(1, 0, 0), (2, 0, 1), (3, 0, 2)], \
        "each ping arrives exactly one tick after it was sent, and only then"
    assert all(s != 0 for _, s, _ in heard[0]) and all(s != 1 for _, s, _ in heard[1])


def test_concrete_blocks_and_open_space_carries():
    # 2 robots 13 m apart: open space at 2.4 GHz loses 17.3*log10(13) + 32.4 + 20*log10(2.4) = 59.3 dB
    # -> 15 - 59.3 = -44.3 dBm >= -82 dBm: linked.
    r = talk(walled_map(0), [(3, 5, 0), (16, 5, 0)], {"model": "multiwall"})
    assert r.summary["messages"]["delivered"] > 0
    # Three 15 dB concrete walls add 45 dB -> -89.3 dBm < -82 dBm: no link, nothing arrives.
    r = talk(walled_map(3), [(3, 5, 0), (16, 5, 0)], {"model": "multiwall"})
    assert r.summary["messages"]["delivered"] == 0 and Talker.log[1] == []
    # Line of sight fails through any wall, global never does.
    assert talk(walled_map(1), [(3, 5, 0), (13, 5, 0)], {"model": "los"}).summary["messages"]["delivered"] == 0
    assert talk(walled_map(1), [(3, 5, 0), (13, 5, 0)], {"model": "global"}).summary["messages"]["delivered"] > 0


def test_delivery_follows_the_link_matrix_exactly():
    truth = generate("building", 60, 3)
    sim = Simulation({"map": {"kind": "building", "size": 60, "seed": 3}, "robots": {"count": 7, "spawn": "random"},
                      "algorithm": {"name": TALKER}, "comm": {"map_sharing": "off"}, "stop": {"max_ticks": 3},
                      "seed": 11}, truth=truth)
    Talker.log = {}
    sim.run()
    link = build_link_model(truth, RadioConfig()).evaluate(sim.world.poses[:, :2]).link
    assert 0 < link.sum() < 7 * 6, "a mix of links and no links makes the test meaningful"
    for i in range(7):
        heard = {s for t, s, _ in Talker.log[i] if t == 1}
        assert heard == set(np.flatnonzero(link[i]).tolist())


def test_loss_is_seeded_and_counted():
    poses = [(3, 3, 0), (6, 3, 0), (9, 3, 0)]
    a = talk(walled_map(0), poses, {"model": "global"}, ticks=200, comm={"map_sharing": "off", "loss": 0.5})
    b = talk(walled_map(0), poses, {"model": "global"}, ticks=200, comm={"map_sharing": "off", "loss": 0.5})
    ma, mb = a.summary["messages"], b.summary["messages"]
    assert ma == mb
    attempts = ma["delivered"] + ma["dropped_loss"]
    assert attempts == 200 * 3 * 2 and 0.4 < ma["dropped_loss"] / attempts < 0.6


def test_bandwidth_budget_drops_what_does_not_fit():
    size = len(encode(Ping(0, 0)))
    r = talk(walled_map(0), [(3, 3, 0), (6, 3, 0)], {"model": "global"}, ticks=20,
             comm={"map_sharing": "off", "bandwidth": size - 1})
    assert r.summary["messages"]["delivered"] == 0 and r.summary["messages"]["dropped_bandwidth"] == 2 * 20


def test_delta_sharing_gives_the_same_run_as_full_maps():
    spec = {"map": {"kind": "building", "size": 40}, "robots": {"count": 3}, "seed": 5, "stop": {"max_ticks": 600}}
    delta = Simulation({**spec, "comm": {"map_sharing": "delta"}})
    full = Simulation({**spec, "comm": {"map_sharing": "full"}})
    rd, rf = delta.run(), full.run()
    assert np.array_equal(delta.known, full.known)
    assert rd.timeseries["explored"] == rf.timeseries["explored"]
    assert rd.summary["messages"]["map_bytes_sent"] < rf.summary["messages"]["map_bytes_sent"]


def test_map_sharing_makes_maps_converge():
    spec = {"map": {"kind": "building", "size": 40}, "robots": {"count": 3}, "seed": 5, "stop": {"max_ticks": 300},
            "radio": {"model": "global"}}
    shared, alone = Simulation(spec), Simulation({**spec, "comm": {"map_sharing": "off"}})
    shared.run(), alone.run()
    union = shared.known.max(axis=0)
    assert (shared.known[0] > 0).sum() > 0.9 * (union > 0).sum()
    assert (alone.known[0] > 0).sum() < (alone.known.max(axis=0) > 0).sum()


def test_gap_in_deltas_is_repaired_with_a_full_map():
    rng = np.random.default_rng(0)
    shape = (30, 30)
    spec = CommSpec(share_every=1)
    sharing = MapSharing(2, shape, spec)
    known = np.zeros((2, *shape), np.uint8)
    receiver = np.zeros(shape, np.uint8)
    for tick in range(12):
        cells = rng.integers(0, 900, 40)  # knowledge only grows (UNSEEN < FREE < SOLID), as lidar writes it
        flat = known[0].reshape(-1)
        flat[cells] = np.maximum(flat[cells], rng.integers(1, 3, 40))
        out = sharing.outgoing(tick, known, np.zeros((2, 3)))
        for msg in out[0]:
            if isinstance(msg, MapUpdate) and msg.seq in (3, 4, 8):
                continue  # lost on the way
            sharing.receive(1, [decode(encode(msg))], receiver)
        sharing.receive(0, [decode(encode(m)) for m in out[1]], known[0])  # robot 1's request reaches robot 0
    final = sharing.outgoing(12, known, np.zeros((2, 3)))
    sharing.receive(1, final[0], receiver)
    assert np.array_equal(receiver, known[0]), "after the requested full map the receiver knows what the sender knows"


def test_deltas_from_the_lidar_windows_equal_the_whole_map_comparison():
    """With ``lidar_reach`` the service compares only the windows scanned and the cells merged since a
    robot's last update; every message must be the same as when it compares the whole maps."""
    rng = np.random.default_rng(3)
    shape, reach, n = (60, 50), 4, 3
    spec = CommSpec(share_every=3)
    whole, windows = MapSharing(n, shape, spec), MapSharing(n, shape, spec, lidar_reach=reach)
    maps = {id(whole): np.zeros((n, *shape), np.uint8), id(windows): np.zeros((n, *shape), np.uint8)}
    inboxes: dict[int, list[list]] = {id(whole): [[] for _ in range(n)], id(windows): [[] for _ in range(n)]}
    kinds = set()
    for tick in range(60):
        poses = np.column_stack([rng.uniform(0, 25, n), rng.uniform(0, 30, n), np.zeros(n)])
        scan = []
        for r in range(n):  # what a lidar might write: cells within ``reach`` of the robot's cell
            row, col = int(poses[r, 1] / CELL_M), int(poses[r, 0] / CELL_M)
            rows = rng.integers(max(row - reach, 0), min(row + reach + 1, shape[0]), 15)
            cols = rng.integers(max(col - reach, 0), min(col + reach + 1, shape[1]), 15)
            scan.append((rows, cols, rng.integers(1, 3, 15).astype(np.uint8)))
        sent = {}
        for sharing in (whole, windows):
            known = maps[id(sharing)]
            for r, (rows, cols, values) in enumerate(scan):
                known[r, rows, cols] = np.maximum(known[r, rows, cols], values)
            sharing.scanned(poses)
            for r in range(n):
                sharing.receive(r, inboxes[id(sharing)][r], known[r])
            out = sharing.outgoing(tick, known, poses)
            sent[id(sharing)] = [[encode(m) for m in msgs] for msgs in out]
            lost = tick % 7 == 0  # now and then robot 1 misses robot 0's messages: gaps, requests, full maps
            inboxes[id(sharing)] = [[decode(encode(m)) for s in range(n) if s != r for m in out[s]
                                     if not (lost and r == 1 and s == 0)] for r in range(n)]
        assert sent[id(whole)] == sent[id(windows)], tick
        assert np.array_equal(maps[id(whole)], maps[id(windows)])
        kinds |= {type(m).__name__ + ("-full" if getattr(m, "full", False) else "")
                  for box in inboxes[id(windows)] for m in box}
    assert kinds == {"MapUpdate", "MapUpdate-full", "MapRequest"}  # deltas, and full maps after gaps


def _same_cell_lists(a: list, b: list) -> bool:
    return len(a) == len(b) and all(len(x) == len(y) and all(
        (u is None and v is None) or (u is not None and v is not None and np.array_equal(u, v)) for u, v in zip(x, y))
        for x, y in zip(a, b))


def test_receive_tick_equals_receive_per_robot():
    """One call for a tick's deliveries does what a call per robot with its inbox does: the same maps,
    cell lists, sequence books, requests and full-map flags (robot 2 is down and left alone)."""
    rng = np.random.default_rng(4)
    shape, n = (20, 30), 4
    live = np.array([True, True, False, True])
    per_robot, at_once = MapSharing(n, shape, CommSpec(share_every=2)), MapSharing(n, shape, CommSpec(share_every=2))
    maps = [np.zeros((n, *shape), np.uint8), np.zeros((n, *shape), np.uint8)]
    deliveries: list = []
    kinds = set()
    for tick in range(40):
        cells, values = rng.integers(0, 600, 30), rng.integers(0, 3, (n, 30)).astype(np.uint8)
        for known in maps:  # the same new knowledge in both, only ever growing
            flat = known.reshape(n, -1)
            flat[:, cells] = np.maximum(flat[:, cells], values)
        inboxes = [[m for m, to in deliveries if r in to] for r in range(n)]
        lists = [per_robot.receive(r, inboxes[r], maps[0][r]) if live[r] else [] for r in range(n)]
        assert _same_cell_lists(at_once.receive_tick(deliveries, maps[1], live), lists), tick
        assert np.array_equal(maps[0], maps[1]), tick
        assert np.array_equal(per_robot.seen_seq, at_once.seen_seq), tick
        assert (per_robot.requests, per_robot.full_requested) == (at_once.requests, at_once.full_requested), tick
        out = per_robot.outgoing(tick, maps[0], np.zeros((n, 3)))
        assert [[encode(m) for m in msgs] for msgs in out] == \
            [[encode(m) for m in msgs] for msgs in at_once.outgoing(tick, maps[1], np.zeros((n, 3)))], tick
        deliveries = [(decode(encode(m)), [r for r in range(n) if r != s and rng.random() < 0.7])
                      for s in range(n) for m in out[s]]
        deliveries.append((Ping(sender=0, tick=tick), [1, 3]))  # an algorithm's message: not the service's
        kinds |= {type(m).__name__ + ("-full" if getattr(m, "full", False) else "") for m, _ in deliveries}
    assert {"MapUpdate", "MapUpdate-full", "MapRequest"} <= kinds  # deltas, gaps, requests and full maps


def test_medium_drops_and_counts_what_an_algorithm_may_not_send():
    """A forged sender, something that is not a registered message, a map update of another shape or with a
    corrupt payload: dropped before the radio, counted per sender, the reason noted; good messages pass."""
    from swarm.comm.messages import MapUpdate, full_update

    medium = Medium(3, CommSpec(), np.random.default_rng(0), map_shape=(8, 8))
    corrupt = MapUpdate(sender=1, seq=1, tick=0, full=False, shape=(8, 8), count=2, payload=b"junk", pose=(0.0, 0.0, 0.0))
    bad = [(0, Ping(sender=1, tick=0)), (1, Ping(sender=True, tick=0)), (1, "a string"), (2, object()),
           (1, full_update(1, 1, 0, np.zeros((3, 3), np.uint8), (0.0, 0.0, 0.0))), (1, corrupt)]
    for sender, msg in bad:
        assert medium.envelope(sender, msg) is None
    good = medium.envelope(1, full_update(1, 1, 0, np.ones((8, 8), np.uint8), (0.0, 0.0, 0.0)))
    assert good is not None and good.seq == 1, "dropped messages take no sequence number"
    assert medium.envelope(2, Ping(sender=2, tick=0)) is not None
    assert medium.stats.malformed == len(bad) and medium.stats.malformed_by_robot == [1, 4, 1]
    reasons = [reason for _, reason in medium.dropped]
    assert "claims sender 1" in reasons[0] and "shape" in reasons[4] and "corrupt" in reasons[5]


def test_comm_metrics_in_the_time_series():
    r = Simulation({"map": {"kind": "building", "size": 40}, "robots": {"count": 4}, "seed": 2,
                    "stop": {"max_ticks": 100}}).run()
    ts = r.timeseries
    for column in ("msgs_sent", "bytes_sent", "msgs_delivered", "msgs_dropped", "comm_groups", "biggest_group",
                   "all_connected"):
        assert len(ts[column]) == len(ts["tick"])
    assert ts["msgs_sent"][-1] > 0 and 0 < ts["biggest_group"][-1] <= 1
    assert r.summary["messages"]["last_contact"][0] > 0


class Looker:
    """Records what it senses of its neighbours."""

    name = "looker"
    seen: dict = {}

    def reset(self, robot, params, rng):
        self.id = robot.id

    def act(self, obs):
        Looker.seen[self.id] = list(obs.neighbours)
        from swarm.api import Action

        return Action(velocity=(0.0, 0.0))


def test_neighbours_are_robots_in_range_and_line_of_sight():
    Looker.seen = {}
    truth = walled_map(1)                                   # 20 x 10 m, wall at x in [9, 10) m
    poses = [(1.5, 1.5, 0.0), (4.5, 5.5, np.pi / 2), (12, 5, 0.0), (8.5, 8.5, 0.0)]
    spec = {"algorithm": {"name": "tests.swarm.comm.test_comm:Looker"}, "robots": {"count": 4},
            "stop": {"max_ticks": 1, "explored": 1.0}, "map": {"kind": "file", "path": "unused.npz"}}
    Simulation(spec, truth=truth, start_poses=np.array(poses)).run()
    ids = {i: sorted(n.id for n in Looker.seen[i]) for i in range(4)}
    assert ids[0] == [1], "robot 2 is behind the wall, robot 3 is 9.9 m away (beyond the 7 m lidar range)"
    assert ids[1] == [0, 3] and ids[3] == [1]
    assert ids[2] == [], "the wall hides everyone from robot 2"
    n = Looker.seen[1][0]
    assert n.id == 0 and n.distance == pytest.approx(5.0) and (n.x, n.y) == (1.5, 1.5)
    # robot 1 faces north (+y); robot 0 is at dx=-3, dy=-4: bearing atan2(-4, -3) - pi/2, wrapped
    assert n.bearing == pytest.approx(np.arctan2(-4, -3) - np.pi / 2 + 2 * np.pi)


def _reference_payload(known: np.ndarray, changed: np.ndarray | None) -> bytes:
    """The documented MapUpdate layout written with plain numpy: 2-bit values four to a byte, low bits
    first; deltas prefixed by little-endian uint32 gaps between ascending flat indices."""
    flat = known.reshape(-1)
    values = flat if changed is None else flat[changed]
    padded = np.zeros((len(values) + 3) // 4 * 4, dtype=np.uint8)
    padded[:len(values)] = values
    q = padded.reshape(-1, 4)
    packed = (q[:, 0] | (q[:, 1] << 2) | (q[:, 2] << 4) | (q[:, 3] << 6)).astype(np.uint8).tobytes()
    if changed is None:
        return packed
    return np.diff(changed, prepend=0).astype("<u4").tobytes() + packed


def test_pack2_writes_four_values_a_byte_low_bits_first_for_every_tail_length():
    from swarm.knowledge.cellcodec import pack2

    rng = np.random.default_rng(4)
    for n in [*range(10), 4097]:
        values = rng.integers(0, 4, n).astype(np.uint8)
        padded = np.zeros((n + 3) // 4 * 4, dtype=np.uint8)
        padded[:n] = values
        q = padded.reshape(-1, 4)
        assert pack2(values).tobytes() == (q[:, 0] | (q[:, 1] << 2) | (q[:, 2] << 4) | (q[:, 3] << 6)).astype(np.uint8).tobytes()


def test_unpack2_splits_every_byte_and_reports_the_largest_value():
    from swarm.knowledge.cellcodec import unpack2

    rng = np.random.default_rng(5)
    for n in [*range(13), 4099]:
        for top in range(4):
            packed = rng.integers(0, 256, (n + 3) // 4).astype(np.uint8)
            if top < 3:  # only values 0..top in the first n fields, whatever the padding bits after them
                fields = np.minimum((packed[:, None] >> np.array([0, 2, 4, 6])) & 3, top).reshape(-1)
                fields[n:] = 3
                packed = (fields.reshape(-1, 4) << np.array([0, 2, 4, 6])).sum(axis=1).astype(np.uint8)
            want = ((packed[np.arange(n) >> 2] >> (2 * (np.arange(n) & 3))) & 3).astype(np.uint8)
            out = np.empty(n, dtype=np.uint8)
            assert unpack2(packed, n, out) == (int(want.max()) if n else 0)
            assert np.array_equal(out, want)


@pytest.mark.parametrize("shape", [(1, 1), (7, 13), (30, 41)])
def test_map_update_payload_layout_and_round_trip(shape):
    import zlib

    from swarm.comm.messages import map_update

    rng = np.random.default_rng(shape[0])
    known = rng.integers(0, 3, shape).astype(np.uint8)
    size = known.size
    for changed in (None, np.zeros(0, np.int64), np.array([size - 1]), np.arange(size),
                    np.sort(rng.choice(size, size // 2 + 1, replace=False))):
        local = map_update(3, 1, 0, known, (1.0, 2.0, 0.5), changed)
        msg = decode(encode(local))
        assert zlib.decompress(msg.payload) == _reference_payload(known, changed)
        want = np.flatnonzero(known) if changed is None else changed
        # The decoded message, and the built one whose receivers here skip zlib (MapUpdate._raw).
        for update in (msg, local):
            idx, values = update.cells()
            assert np.array_equal(idx, want) and np.array_equal(values, known.reshape(-1)[want])
            if changed is None:
                assert np.array_equal(update.dense(), known.reshape(-1))
        assert local.__dict__["_plain"] == zlib.decompress(local.payload)


def test_a_map_update_built_here_is_checked_like_a_received_one():
    """Receivers in this process read a built update's payload before zlib, with the same checks: a value
    outside 0..2 (packed as 2 bits) is refused as when the bytes arrive over the wire."""
    from swarm.comm.messages import MessageError, delta_update, full_update

    known = np.ones((4, 6), dtype=np.uint8)
    known[1, 2] = 3
    for update in (full_update(1, 1, 0, known, (0.0, 0.0, 0.0)),
                   delta_update(1, 1, 0, known, (0.0, 0.0, 0.0), np.array([3, 8], dtype=np.int64))):
        for msg in (update, decode(encode(update))):
            with pytest.raises(MessageError, match="outside"):
                msg.cells()


@pytest.mark.parametrize("raw, n, full, error", [
    (np.array([2, 0, 3], "<u4").tobytes() + bytes([0b010101]), 3, False, "repeated cells"),
    (np.array([0, 0], "<u4").tobytes() + bytes([0b0101]), 2, False, "repeated cells"),
    (np.array([5, 20], "<u4").tobytes() + bytes([0b0101]), 2, False, "cells outside the map"),
    (np.array([5, 6], "<u4").tobytes() + bytes([0b1101]), 2, False, "cells outside the map"),  # value 3
    (np.array([5], "<u4").tobytes(), 1, False, "wrong payload length"),
    (bytes([0b11]) + bytes(5), 24, True, "outside 0..2"),
    (bytes(5), 24, True, "wrong payload length"),
])
def test_corrupt_map_update_payloads_are_rejected(raw, n, full, error):
    import zlib

    from swarm.comm.messages import MessageError

    msg = MapUpdate(sender=1, seq=1, tick=0, full=full, shape=(4, 6), count=n, payload=zlib.compress(raw),
                    pose=(0.0, 0.0, 0.0))
    with pytest.raises(MessageError, match=error):
        decode(encode(msg)).cells()


def _deliver_reference(medium: Medium, tick: int, outboxes, link: np.ndarray):
    """Medium.deliver receiver by receiver, as first written: the semantics the faster loop must keep."""
    n, spec, stats = medium.n, medium.spec, medium.stats
    inboxes = [[] for _ in range(n)]
    budget = np.full((n, n), spec.bandwidth, dtype=np.int64) if spec.bandwidth else None
    for j in range(n):
        for env in outboxes[j]:
            size = len(env.data)
            stats.sent += 1
            stats.bytes_sent += size
            if isinstance(env.message, MapUpdate):
                stats.map_bytes_sent += size
            receivers = np.flatnonzero(link[:, j])
            stats.dropped_link += (n - 1) - len(receivers)
            if spec.loss > 0.0 and len(receivers):
                keep = medium.rng.random(len(receivers)) >= spec.loss
                stats.dropped_loss += int((~keep).sum())
                receivers = receivers[keep]
            for i in receivers.tolist():
                if i == j:
                    continue
                if budget is not None:
                    if budget[i, j] < size:
                        stats.dropped_bandwidth += 1
                        continue
                    budget[i, j] -= size
                inboxes[i].append(env)
                env.delivered_to = np.append(env.delivered_to, i)
                stats.delivered += 1
                stats.bytes_delivered += size
                stats.contact[i] = tick + 1
    return inboxes


@pytest.mark.parametrize("loss,bandwidth", [(0.0, 0), (0.3, 0), (0.0, 40), (0.4, 30)])
def test_medium_delivers_as_the_receiver_by_receiver_reference(loss, bandwidth):
    from swarm.comm.medium import Envelope

    rng = np.random.default_rng(int(loss * 10) + bandwidth)
    n = 6
    spec = CommSpec(loss=loss, bandwidth=bandwidth)
    fast, slow = Medium(n, spec, np.random.default_rng(1)), Medium(n, spec, np.random.default_rng(1))
    for tick in range(20):
        link = rng.random((n, n)) < 0.6
        sizes = [[int(s) for s in rng.integers(1, 25, rng.integers(0, 4))] for _ in range(n)]
        boxes_fast = [[Envelope(j, k, bytes(s), Ping(sender=j, tick=tick)) for k, s in enumerate(row)] for j, row in enumerate(sizes)]
        boxes_slow = [[Envelope(j, k, bytes(s), Ping(sender=j, tick=tick)) for k, s in enumerate(row)] for j, row in enumerate(sizes)]
        got = fast.deliver(tick, boxes_fast, link)
        want = _deliver_reference(slow, tick, boxes_slow, link)
        assert [[(e.sender, e.seq) for e in inbox] for inbox in got] == [[(e.sender, e.seq) for e in inbox] for inbox in want]
        for i in range(n):  # (without loss or a budget a sender's envelopes are held as one group)
            assert len(got[i]) == len(want[i]) and got.messages(i) == tuple(e.message for e in want[i])
            assert [(e.sender, e.seq) for e in got[i][1:]] == [(e.sender, e.seq) for e in want[i][1:]]
            assert not want[i] or (got[i][-1].sender, got[i][-1].seq) == (want[i][-1].sender, want[i][-1].seq)
        assert [[list(e.delivered_to) for e in row] for row in boxes_fast] == \
            [[list(e.delivered_to) for e in row] for row in boxes_slow]
        assert fast.stats.as_dict() == slow.stats.as_dict()
    assert fast.stats.delivered > 0 and (fast.stats.dropped_bandwidth > 0) == (bandwidth > 0)


@pytest.mark.parametrize("reach", [None, 4])
@pytest.mark.parametrize("n", [2, 5])  # with 2 robots no third one relays what a gap lost
def test_full_maps_reach_up_to_date_receivers_as_deltas_with_the_same_result(reach, n):
    """On monotone maps a broadcast full map is merged, into each receiver that holds every earlier update
    of its sender, as the cells since the sender's previous update: maps, messages and books must come
    out as merging the whole map does, through gaps, requests, robots that hear only some updates, and
    full maps an algorithm sends itself. Ages of information and counts of FREE cells come out as those of a
    service that compares whole maps (no ``lidar_reach``, none of the shortcuts)."""
    from swarm.comm.messages import full_update
    from swarm.results.metrics import FreeCounts, InfoAges

    rng = np.random.default_rng(21)
    shape = (80, 60)
    spec = CommSpec(share_every=2)
    kinds = [(reach, False), (reach, True), (None, False)]
    ages, free = [InfoAges(n) for _ in kinds], [FreeCounts(n, exact=True) for _ in kinds]
    services = [MapSharing(n, shape, spec, lidar_reach=r, monotone=m, ages=a, free=f)
                for (r, m), a, f in zip(kinds, ages, free)]
    maps = [np.zeros((n, *shape), np.uint8) for _ in services]
    pending: list[list] = [[] for _ in services]  # each service's deliveries: its own message objects (notes)
    live = np.ones(n, bool)
    quick = 0
    for tick in range(80):
        poses = np.column_stack([rng.uniform(0, 29, n), rng.uniform(0, 39, n), np.zeros(n)])
        rows = np.clip((poses[:, 1] / CELL_M).astype(int)[:, None] + rng.integers(-3, 4, (n, 4)), 0, shape[0] - 1)
        cols = np.clip((poses[:, 0] / CELL_M).astype(int)[:, None] + rng.integers(-3, 4, (n, 4)), 0, shape[1] - 1)
        values = rng.integers(1, 3, (n, 4)).astype(np.uint8)
        lists = []
        for sharing, known, deliveries, counts in zip(services, maps, pending, free):
            for r in range(n):  # what a ternary lidar writes near each robot: maxima only (and counts them)
                had = int((known[r] == FREE).sum())
                known[r, rows[r], cols[r]] = np.maximum(known[r, rows[r], cols[r]], values[r])
                counts.freed[r] += int((known[r] == FREE).sum()) - had
            sharing.scanned(poses)
            lists.append(sharing.receive_tick(deliveries, known, live, tick=tick))
        for k in (1, 2):
            assert np.array_equal(maps[0], maps[k]), tick
            assert np.array_equal(services[0].seen_seq, services[k].seen_seq), tick
            assert (services[0].requests, services[0].full_requested) == \
                (services[k].requests, services[k].full_requested), tick
            assert np.array_equal(ages[0].merged_at, ages[k].merged_at), tick
        for counts, known in zip(free, maps):
            assert counts.read(known).tolist() == (known == FREE).sum(axis=(1, 2)).tolist(), tick
        quick += sum(a is None and b is not None for x, y in zip(lists[0], lists[1]) for a, b in zip(x, y))
        out = [s.outgoing(tick, k, poses) for s, k in zip(services, maps)]
        for k in (1, 2):
            assert [[encode(m) for m in msgs] for msgs in out[0]] == [[encode(m) for m in msgs] for msgs in out[k]]
        reach_of = {(s, k): [r for r in range(n) if r != s and rng.random() < 0.8]
                    for s in range(n) for k in range(len(out[0][s]))}
        pending = [[(m, reach_of[s, k]) for s in range(n) for k, m in enumerate(o[s])] for o in out]
        if tick % 9 == 4:  # an algorithm's own full map of some other knowledge: not the service's
            other = np.where(rng.random(shape) < 0.01, rng.integers(1, 3, shape), 0).astype(np.uint8)
            fake = full_update(1, 10_000 + tick, tick, other, (0.0, 0.0, 0.0))
            for deliveries in pending:
                deliveries.append((fake, [0]))
    assert quick > 5 or n == 2, "full maps were taken as deltas (with 2 robots only the requester hears them)"
    assert ages[0].merges > 0 and (ages[0].merged_at > 0).any(), "merges counted for the ages"


@pytest.mark.parametrize("loss,bandwidth,relay", [(0.0, 0, "none"), (0.3, 30, "none"), (0.3, 30, "flood")])
def test_a_medium_noting_losses_lists_every_failed_delivery_and_changes_nothing(loss, bandwidth, relay):
    """With ``note_losses`` (the recorder's) every envelope lists each other robot it failed to reach, once, with
    the cause the counts give it; inboxes, delivered_to and counts are those of a medium that does not note."""
    from swarm.comm.medium import LOSS_CAUSES, Envelope

    rng = np.random.default_rng(7)
    n = 6
    spec = CommSpec(loss=loss, bandwidth=bandwidth, relay=relay)
    noting, plain = Medium(n, spec, np.random.default_rng(1)), Medium(n, spec, np.random.default_rng(1))
    noting.note_losses = True
    causes = {c: 0 for c in LOSS_CAUSES}
    for tick in range(30):
        link = rng.random((n, n)) < 0.6
        np.fill_diagonal(link, False)
        sizes = [[int(s) for s in rng.integers(1, 25, rng.integers(0, 3))] for _ in range(n)]
        boxes = [[[Envelope(j, 100 * tick + k, bytes(s), Ping(sender=j, tick=tick)) for k, s in enumerate(row)]
                  for j, row in enumerate(sizes)] for _ in range(2)]
        for medium, box in zip((noting, plain), boxes):
            if medium.relaying:
                medium.add_relays(box, np.zeros(n, dtype=bool))
        got, want = noting.deliver(tick, boxes[0], link), plain.deliver(tick, boxes[1], link)
        assert [[(e.sender, e.seq, e.hop) for e in inbox] for inbox in got] == \
            [[(e.sender, e.seq, e.hop) for e in inbox] for inbox in want]
        for env, other in zip((e for row in boxes[0] for e in row), (e for row in boxes[1] for e in row)):
            assert other.lost is None and list(env.delivered_to) == list(other.delivered_to)
            missed = [robot for robot, _ in env.lost]
            assert len(set(missed)) == len(missed) and not set(missed) & set(env.delivered_to)
            assert env.transmitter not in missed
            if relay == "none":
                assert sorted(missed + env.delivered_to.tolist()) == [i for i in range(n) if i != env.transmitter]
            for robot, cause in env.lost:
                assert link[robot, env.transmitter] == (LOSS_CAUSES[cause] != "link")
                causes[LOSS_CAUSES[cause]] += 1
    stats = noting.stats
    assert stats.as_dict() == plain.stats.as_dict()
    assert (causes["link"], causes["loss"], causes["bandwidth"]) == \
        (stats.dropped_link, stats.dropped_loss, stats.dropped_bandwidth)
    assert causes["link"] > 0 and (causes["loss"] > 0) == (loss > 0) and (causes["bandwidth"] > 0) == (bandwidth > 0)


def test_identical_full_maps_of_one_tick_share_one_compression_and_keep_their_bytes():
    """Robots whose maps converged send byte-identical full maps: one zlib call serves them (one copy of the
    plain bytes), and every update still carries exactly what compressing its own map gives."""
    import zlib

    from swarm.comm.messages import MAP_ZLIB_LEVEL, _cellcodec

    rng = np.random.default_rng(5)
    shape = (24, 31)
    common = rng.integers(0, 3, shape).astype(np.uint8)
    other = common.copy()
    other[3, 4] = 2 if other[3, 4] != 2 else 1
    known = np.stack([common, other, common.copy(), common.copy()])
    sharing = MapSharing(4, shape, CommSpec(map_sharing="full", share_every=1))
    out = sharing.outgoing(0, known, np.zeros((4, 3)))
    full = [msgs[0] for msgs in out]
    assert all(isinstance(m, MapUpdate) and m.full for m in full)
    for i, m in enumerate(full):
        plain = _cellcodec.pack2(known[i].reshape(-1)).tobytes()
        assert m.payload == zlib.compress(plain, MAP_ZLIB_LEVEL) and m.count == int(np.count_nonzero(known[i]))
        assert np.array_equal(decode(encode(m)).dense().reshape(shape), known[i])
    assert full[0].payload == full[2].payload == full[3].payload != full[1].payload
    assert full[0]._plain is full[2]._plain is full[3]._plain, "robots with the same map hold one plain copy"
    later = sharing.outgoing(1, known, np.zeros((4, 3)))[0][0]
    assert later.payload == full[0].payload and later._plain is not full[0]._plain, "shared within a tick only"


def test_a_large_full_map_keeps_no_plain_bytes_and_its_receivers_merge_the_same_cells(monkeypatch):
    """Over KEEP_PLAIN_BYTES a full map built here holds only its compressed payload (a swarm asked for all
    its full maps at once would hold a megabyte or more per robot until delivery); its receivers here
    decompress it and merge exactly what the kept bytes would have given, and identical maps still share one
    compression."""
    import swarm.comm.messages as messages

    rng = np.random.default_rng(11)
    shape = (40, 52)
    common = rng.integers(0, 3, shape).astype(np.uint8)
    known = np.stack([common, common.copy(), np.zeros(shape, np.uint8)])
    kept = MapSharing(3, shape, CommSpec(map_sharing="full", share_every=1)).outgoing(0, known, np.zeros((3, 3)))
    monkeypatch.setattr(messages, "KEEP_PLAIN_BYTES", 64)  # these maps now count as large
    out = MapSharing(3, shape, CommSpec(map_sharing="full", share_every=1)).outgoing(0, known, np.zeros((3, 3)))
    for small, large in zip(kept, out):
        assert "_plain" in small[0].__dict__ and "_plain" not in large[0].__dict__
        assert large[0].payload == small[0].payload
        assert all(np.array_equal(a, b) for a, b in zip(large[0].known_cells(), small[0].known_cells()))
    assert out[0][0].payload is out[1][0].payload, "identical maps: one compression"
    into = MapSharing(3, shape, CommSpec(map_sharing="full", share_every=1))
    maps = np.zeros((3, *shape), np.uint8)
    into.receive_tick([(out[0][0], [2])], maps, np.ones(3, dtype=bool))
    assert np.array_equal(maps[2], common)


def scan_at_random(known: np.ndarray, rng: np.random.Generator, extent_m: float, cells: int) -> np.ndarray:
    """Poses drawn in [1, extent_m) m, and around each robot what a ternary lidar writes: ``cells`` random cells
    within 3 of its cell raised to FREE or SOLID (maxima only). Returns the poses."""
    n, rows, cols = known.shape
    poses = np.column_stack([rng.uniform(1, extent_m, n), rng.uniform(1, extent_m, n), np.zeros(n)])
    for r in range(n):
        rr = np.clip(int(poses[r, 1] / CELL_M) + rng.integers(-3, 4, cells), 0, rows - 1)
        cc = np.clip(int(poses[r, 0] / CELL_M) + rng.integers(-3, 4, cells), 0, cols - 1)
        known[r, rr, cc] = np.maximum(known[r, rr, cc], rng.integers(1, 3, cells).astype(np.uint8))
    return poses


def run_sharing(service: MapSharing, known: np.ndarray, rng: np.random.Generator, ticks: int, extent_m: float,
                cells: int, route) -> list:
    """``ticks`` ticks of ``service`` over maps written by :func:`scan_at_random`; ``route(sender, message,
    tick)`` gives a message's receivers and its delay (0: merged next tick, 1: the tick after). Returns, per
    tick, the messages sent (encoded) and the maps after them."""
    n = known.shape[0]
    live = np.ones(n, bool)
    queue: dict[int, list] = {}
    sent = []
    for tick in range(ticks):
        poses = scan_at_random(known, rng, extent_m, cells)
        service.scanned(poses)
        service.receive_tick(queue.pop(tick, []), known, live, tick=tick)
        out = service.outgoing(tick, known, poses)
        sent.append(([[encode(m) for m in msgs] for msgs in out], known.tobytes()))
        for s in range(n):
            for m in out[s]:
                to, delay = route(s, m, tick)
                queue.setdefault(tick + 1 + delay, []).append((m, to))
    return sent


def test_a_receiver_that_missed_updates_takes_a_full_map_as_their_cells_with_the_same_result():
    """Robot 1 merges robot 0's updates 1-3, misses 4 and 5, hears 6 and asks for the full map: on monotone maps
    it takes only the cells of updates 4-8 (the full map is update 8; the values read from it), and every map, book and later message is
    that of a service that merges the whole map into it (``CATCH_UP`` off). Robot 3 first hears robot 0 at
    tick 8, further back than robot 0's history reaches: it takes the whole map."""
    from swarm.comm import sharing as sharing_module

    shape, n = (40, 40), 4
    results = []
    for catch_up in (True, False):
        rng = np.random.default_rng(4)  # the same knowledge both times
        sharing_module.CATCH_UP = catch_up
        try:
            service = MapSharing(n, shape, CommSpec(share_every=1), lidar_reach=3, monotone=True)
            known = np.zeros((n, *shape), np.uint8)
            caught: list[tuple[list[int], int]] = []
            original = service._catch_up

            def spy(msg, ids, *args, _original=original, _caught=caught):
                groups = _original(msg, ids, *args)
                _caught.extend(([ids[k] for k in np.flatnonzero(m)], msg.seq) for m, _ in groups)
                return groups

            service._catch_up = spy

            def route(s, m, tick):
                if s != 0:
                    return [r for r in range(n) if r != s], 0
                to = [2] if isinstance(m, MapUpdate) and m.seq in (4, 5) else [1, 2]
                return to + ([3] if tick >= 8 else []), 0

            sent = run_sharing(service, known, rng, 12, 19, 6, route)
            results.append((known.copy(), service.seen_seq.copy(), sent, caught))
        finally:
            sharing_module.CATCH_UP = True
    (maps_on, seen_on, sent_on, caught), (maps_off, seen_off, sent_off, none) = results
    assert np.array_equal(maps_on, maps_off) and np.array_equal(seen_on, seen_off) and sent_on == sent_off
    assert caught == [([1], 8)], "robot 1 caught up from robot 0's full map (its update 8); robot 3 took the whole map"
    assert not none, "with CATCH_UP off nothing is caught up"


def test_a_full_updates_values_at_some_cells_are_its_decoded_maps():
    from swarm.comm.messages import MessageError, delta_update, full_update

    rng = np.random.default_rng(9)
    known = rng.integers(0, 3, (37, 23)).astype(np.uint8)  # 851 cells: not a multiple of 4
    cells = np.sort(rng.choice(known.size, 200, replace=False)).astype(np.int64)
    for msg in (full_update(0, 1, 0, known, (0.0, 0.0, 0.0)),
                decode(encode(full_update(0, 1, 0, known, (0.0, 0.0, 0.0))))):  # kept plain bytes, or zlib
        assert np.array_equal(msg.values_at(cells), known.reshape(-1)[cells])
        assert np.array_equal(msg.values_at(np.array([known.size - 1])), known.reshape(-1)[-1:])
    with pytest.raises(MessageError, match="needs a full update"):
        delta_update(0, 1, 0, known, (0.0, 0.0, 0.0), cells).values_at(cells)


def test_a_ticks_equal_full_maps_share_one_compression_and_a_fingerprint_match_is_checked(monkeypatch):
    """full_update's per-tick cache: equal maps get the very same payload object (one zlib pass), different
    maps their own; a fingerprint collision (forced) still gives each map its own, correct payload."""
    import zlib

    from swarm.comm import messages
    from swarm.knowledge import cellcodec
    from swarm.knowledge.packed import packed_copy

    rng = np.random.default_rng(3)
    a = rng.integers(0, 3, (40, 50)).astype(np.uint8)
    b = a.copy()
    b[7, 9] = (b[7, 9] + 1) % 3

    def payload_of(update):
        return zlib.decompress(update.payload)

    for collide in (False, True):
        if collide:
            monkeypatch.setattr(cellcodec, "fingerprint", lambda data: (np.uint64(1), np.uint64(2)))
        payloads: dict = {}
        first = messages.full_update(0, 1, 0, a, (0.0, 0.0, 0.0), payloads, packed_copy(a))
        same = messages.full_update(1, 1, 0, a.copy(), (0.0, 0.0, 0.0), payloads)
        other = messages.full_update(2, 1, 0, b, (0.0, 0.0, 0.0), payloads, packed_copy(b))
        assert same.payload is first.payload
        assert payload_of(first) == cellcodec.pack2(a.reshape(-1)).tobytes()
        assert payload_of(other) == cellcodec.pack2(b.reshape(-1)).tobytes() != payload_of(first)
        assert np.array_equal(other.dense(), b.reshape(-1)) and np.array_equal(same.dense(), a.reshape(-1))
        assert (first.count, same.count, other.count) == (np.count_nonzero(a),) * 2 + (np.count_nonzero(b),)


def _converged_and_other_full_maps(seed: int):
    """Maps a and b (one cell apart) and full maps of them in one tick: robots 0 and 1 send a (one payload
    object), robot 2 sends b."""
    from swarm.comm.messages import full_update

    rng = np.random.default_rng(seed)
    a = rng.integers(0, 3, (30, 20)).astype(np.uint8)
    b = a.copy()
    b[0, 0] = 2 if b[0, 0] != 2 else 1
    payloads: dict = {}
    first, second = (full_update(s, 1, 0, a.copy(), (0.0, 0.0, 0.0), payloads) for s in (0, 1))
    other = full_update(2, 1, 0, b, (0.0, 0.0, 0.0), payloads)
    return a, b, first, second, other


def test_full_maps_with_one_payload_are_decoded_once_a_tick():
    """Robots whose maps converged send the same payload object: the service decodes it once per tick (per
    shape) and afresh after the tick, and a different payload is decoded on its own."""
    a, b, first, second, other = _converged_and_other_full_maps(5)
    assert first.payload is second.payload and other.payload is not first.payload
    sharing = MapSharing(3, a.shape, CommSpec())
    cells = sharing._decode(first, "known")
    assert sharing._decode(second, "known") is cells
    assert np.array_equal(cells[0], np.flatnonzero(a)) and np.array_equal(cells[1], a.reshape(-1)[cells[0]])
    assert np.array_equal(sharing._decode(other, "dense"), b.reshape(-1))
    sharing.receive_tick([], np.zeros((3, *a.shape), np.uint8), np.ones(3, dtype=np.bool_))
    assert sharing._decode(second, "known") is not cells  # a new tick decodes again


def test_a_tick_keeps_a_decoded_full_map_only_while_another_message_carries_it(monkeypatch):
    """receive_tick decodes a payload two full maps share once, keeps it until the second is merged and
    then lets it go; a payload only one message carries is never kept (a swarm's distinct repairs would
    otherwise all stay decoded to the end of the tick). The maps merged are the updates' maxima."""
    a, b, first, second, other = _converged_and_other_full_maps(6)
    decodes = []
    dense = MapUpdate.dense
    monkeypatch.setattr(MapUpdate, "dense", lambda self: (decodes.append(self.sender), dense(self))[1])
    sharing = MapSharing(4, a.shape, CommSpec())
    kept_after = []
    take = sharing._take
    monkeypatch.setattr(sharing, "_take", lambda *args: (take(*args), kept_after.append(len(sharing._decoded))))
    known = np.zeros((4, *a.shape), np.uint8)
    sharing.receive_tick([(first, [3]), (other, [3]), (second, [2])], known, np.ones(4, dtype=np.bool_))
    assert decodes == [0, 2], "the shared payload once, the other once"
    assert kept_after == [1, 1, 0], "kept while the second message was to come, then let go; the other never"
    assert np.array_equal(known[3], np.maximum(a, b)) and np.array_equal(known[2], a)


def test_catching_up_several_receivers_from_kept_or_delayed_full_maps_gives_the_same_result(monkeypatch):
    """Receivers that missed different runs of robot 0's updates catch up from one full map in groups (each the
    union of the updates it missed), read from robot 0's kept packed map while that still holds the map sent,
    or from the message's bytes when the map arrives after robot 0 built a newer update (a delivery delayed a
    tick): every map, book and message is that of a service that merges whole maps (``CATCH_UP`` off), tick by
    tick. (Only robot 0's updates travel, so no relay brings its cells to a receiver another way.)"""
    from swarm.comm import sharing as sharing_module

    shape, n = (48, 48), 6
    drops = {2: {3, 4, 12}, 3: {4, 12, 13}, 4: {2, 3, 4, 12}, 5: {3, 13}}  # receiver: robot 0's updates it misses
    results = []
    for catch_up in (True, False):
        rng = np.random.default_rng(9)
        monkeypatch.setattr(sharing_module, "CATCH_UP", catch_up)
        reads = {"kept": 0, "bytes": 0}
        monkeypatch.setattr(sharing_module, "values_at2",
                            lambda packed, cells, _f=sharing_module.values_at2, _r=reads: (
                                _r.__setitem__("kept", _r["kept"] + 1), _f(packed, cells))[1])
        original_values_at = MapUpdate.values_at
        monkeypatch.setattr(MapUpdate, "values_at", lambda self, cells, _r=reads: (
            _r.__setitem__("bytes", _r["bytes"] + 1), original_values_at(self, cells))[1])
        service = MapSharing(n, shape, CommSpec(share_every=1), lidar_reach=3, monotone=True)
        known = np.zeros((n, *shape), np.uint8)
        groups_seen: list[int] = []
        original = service._catch_up

        def spy(msg, ids, *args, _original=original, _seen=groups_seen):
            groups = _original(msg, ids, *args)
            _seen.append(len(groups))
            return groups

        service._catch_up = spy

        def route(s, m, tick):
            to = [r for r in range(n) if r != s]
            if s != 0:  # only robot 0's updates travel: no relay brings its cells another way
                return (to if isinstance(m, MapRequest) else []), 0
            if isinstance(m, MapUpdate) and not m.full:
                return [r for r in to if m.seq not in drops.get(r, ())], 0
            return to, int(isinstance(m, MapUpdate) and tick >= 10)  # a late full map: after robot 0's next update

        sent = run_sharing(service, known, rng, 20, 23, 8, route)
        results.append((known.copy(), service.seen_seq.copy(), sent, groups_seen, dict(reads)))
    (maps_on, seen_on, sent_on, groups_on, reads_on), (maps_off, seen_off, sent_off, groups_off, _) = results
    assert np.array_equal(maps_on, maps_off) and np.array_equal(seen_on, seen_off) and sent_on == sent_off
    assert max(groups_on) >= 2, "one full map caught up receivers that had missed different updates"
    assert reads_on["kept"] and reads_on["bytes"], "both ways of reading the full map were taken"
    assert not groups_off


@pytest.mark.parametrize("seed", range(5))
def test_union_of_sorted_cell_lists_is_numpys(seed):
    from swarm.comm.sharing import union_sorted

    rng = np.random.default_rng(seed)
    for _ in range(50):
        a = np.unique(rng.integers(0, 300, rng.integers(0, 80)))
        b = np.unique(rng.integers(0, 300, rng.integers(0, 80)))
        assert np.array_equal(union_sorted(a, b), np.union1d(a, b))


def test_dropping_a_merged_deltas_decoded_cells_changes_nothing(monkeypatch):
    """A large delta lets go of its decoded cells and plain bytes once merged into all its receivers; every
    map and message is then what it is when they are kept (here every delta counts as large), and a later
    reader decodes the same cells again."""
    from swarm.comm import sharing as sharing_module

    shape, n = (40, 40), 5
    runs = []
    for drop in (10**9, 1):
        monkeypatch.setattr(sharing_module, "DROP_DECODED_CELLS", drop)
        rng = np.random.default_rng(6)
        service = MapSharing(n, shape, CommSpec(share_every=2), lidar_reach=3, monotone=True)
        known = np.zeros((n, *shape), np.uint8)
        kept: list = []

        def route(s, m, tick, _kept=kept):
            if isinstance(m, MapUpdate) and not m.full:
                _kept.append(m)
            return [r for r in range(n) if r != s and (tick + r + s) % 4], 0

        sent = run_sharing(service, known, rng, 14, 19, 6, route)
        dropped = ["_cells" not in m.__dict__ and "_plain" not in m.__dict__ for m in kept]
        runs.append((sent, known.copy(), [m.cells() for m in kept], dropped))
    (sent_keep, maps_keep, cells_keep, dropped_keep), (sent_drop, maps_drop, cells_drop, dropped) = runs
    assert sent_drop == sent_keep and np.array_equal(maps_drop, maps_keep)
    assert not any(dropped_keep) and any(dropped), "merged deltas let go of their copies only when large"
    assert all(np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1]) for a, b in zip(cells_drop, cells_keep))


def test_the_zlib_level_changes_the_bytes_and_nothing_else_on_a_perfect_radio():
    """``comm.map_zlib_level`` sets the compression of the runtime's map updates: the same updates (the
    payloads decompress to the same bytes), so without packet errors or a bandwidth cap the run is the same
    but for the bytes counted; level 0 stores them. Level 6 is the default and the canonical form omits it."""
    from swarm.sim.spec import RunSpec

    def run(level: int | None):
        comm = {} if level is None else {"map_zlib_level": level}
        spec = {"seed": 2, "map": {"kind": "building", "size": 60}, "robots": {"count": 8},
                "stop": {"max_ticks": 150}, "comm": {**comm, "loss": 0.2}}
        sent: list[tuple[bytes, int]] = []
        sim = Simulation(spec)
        original = sim.sharing.outgoing

        def spy(*args, _original=original):
            out = _original(*args)
            sent.extend((zlib.decompress(m.payload), len(m.payload)) for msgs in out for m in msgs
                        if isinstance(m, MapUpdate))
            return out

        sim.sharing.outgoing = spy
        res = sim.run()
        summary = {k: v for k, v in res.summary.items() if not k.endswith("_time_s") and k != "messages"}
        return summary, res.summary["messages"], sent, RunSpec.from_mapping(spec).key

    default, messages, sent, key = run(None)
    assert any(len(plain) > 0 for plain, _ in sent) and any(m for m in messages.values())
    for level in (1, 0):
        summary, other_messages, other_sent, other_key = run(level)
        assert summary == default and other_key != key
        assert [plain for plain, _ in other_sent] == [plain for plain, _ in sent]
        assert other_messages["delivered"] == messages["delivered"]
        assert other_messages["map_bytes_sent"] != messages["map_bytes_sent"]
        if level == 0:
            assert sum(size for _, size in other_sent) > 2 * sum(size for _, size in sent)
    assert run(6)[3] == key
