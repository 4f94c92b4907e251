"""The channel beyond a hard threshold, in real runs: multi-hop relaying, packet errors, shadowing; with
all of them off a run is the run it was before they existed."""

from __future__ import annotations

import numpy as np
import pytest

from maps import Map
from radio import RadioConfig, build_link_model
from radio.per import PacketErrorCurve
from swarm.cli import main
from swarm.comm.medium import CommSpec, Envelope, Medium
from swarm.comm.messages import encode
from swarm.sim.loop import Simulation, TickView
from swarm.sim.spec import RunSpec
from tests.swarm.agents import Ping, Talker

TALKER = "tests.swarm.agents:Talker"
QUIET = "tests.swarm.agents:Quiet"
CHAIN_RADIO = {"model": "los", "max_range_m": 15.0}
"""Robots 12 m apart hear each other, 24 m apart do not."""


def long_box(width_m: float = 50.0, height_m: float = 6.0) -> Map:
    """An open box with a one-cell concrete border."""
    solid = np.zeros((int(height_m / 0.5), int(width_m / 0.5)), dtype=bool)
    solid[0, :] = solid[-1, :] = solid[:, 0] = solid[:, -1] = True
    return Map(solid=solid, material=solid.astype(np.uint8), materials=("air", "concrete"))


def chain(n: int) -> np.ndarray:
    return np.array([(3.0 + 12.0 * k, 3.0, 0.0) for k in range(n)])


def run(poses, algorithm=TALKER, radio=None, comm=None, ticks=10, observers=(), **extra):
    Talker.log = {}
    spec = {"algorithm": {"name": algorithm}, "robots": {"count": len(poses)}, "radio": radio or CHAIN_RADIO,
            "comm": {"map_sharing": "off", **(comm or {})}, "stop": {"max_ticks": ticks, "explored": 1.0},
            "map": {"kind": "file", "path": "unused.npz"}, **extra}
    sim = Simulation(spec, truth=long_box(), start_poses=np.asarray(poses, dtype=float), observers=observers)
    return sim, sim.run()


def heard(robot: int, sender: int) -> list[tuple[int, int]]:
    """(tick heard, tick sent) of the pings ``robot`` heard from ``sender``."""
    return [(t, sent) for t, s, sent in Talker.log[robot] if s == sender]


def test_a_relayed_message_reaches_two_hops_away_one_tick_after_the_neighbour():
    _, flood = run(chain(3), comm={"relay": "flood"})
    assert heard(1, 0) == [(t, t - 1) for t in range(1, 10)], "the neighbour hears each ping one tick later"
    assert heard(2, 0) == [(t, t - 2) for t in range(2, 10)], "two hops away: exactly one tick after that"
    assert heard(0, 2) == [(t, t - 2) for t in range(2, 10)]
    assert heard(0, 0) == [] and heard(1, 1) == [], "a robot never gets its own message back"
    m = flood.summary["messages"]
    assert m["relayed"] > 0 and m["duplicates"] > 0 and m["bytes_sent"] > m["bytes_relayed"] > 0

    _, plain = run(chain(3))
    assert heard(2, 0) == [] and heard(0, 2) == [], "never without relaying"
    assert heard(1, 0) == [(t, t - 1) for t in range(1, 10)]
    assert "relayed" not in plain.summary["messages"]


def test_the_hop_limit_bounds_how_far_a_message_goes():
    run(chain(4), comm={"relay": "flood", "relay_hops": 2})
    assert heard(2, 0) == [(t, t - 2) for t in range(2, 10)] and heard(3, 0) == []
    run(chain(4), comm={"relay": "flood", "relay_hops": 3})
    assert heard(3, 0) == [(t, t - 3) for t in range(3, 10)]


def test_relaying_one_hop_is_the_plain_medium_exactly():
    """relay_hops = 1 relays nothing: the relaying medium must then count and draw exactly as the plain one,
    seeded loss included (it is a second loop: this pins it to the first)."""
    comm = {"loss": 0.3}
    _, plain = run(chain(3) * [0.5, 1, 1], comm=comm, ticks=60)
    log_plain = dict(Talker.log)
    _, one = run(chain(3) * [0.5, 1, 1], comm={**comm, "relay": "flood", "relay_hops": 1}, ticks=60)
    assert Talker.log == log_plain
    counts = dict(one.summary["messages"])
    assert (counts.pop("relayed"), counts.pop("bytes_relayed"), counts.pop("duplicates")) == (0, 0, 0)
    assert counts == plain.summary["messages"] and counts["dropped_loss"] > 0


def test_map_updates_travel_one_tick_per_hop_and_merge_once():
    """Three still robots in a row, 0 and 2 out of each other's reach: robot 2 learns the cells only robot 0
    sees at tick 2 with relaying (robot 0's first update, sent at tick 0, two hops), at tick 11 without (robot
    1 merges it at tick 1 and its own update of tick 10 carries it on). Every robot gets each update once."""
    def first_tick_robot_2_knows_the_far_end(comm):
        seen: list[int] = []
        deliveries: list[tuple[int, int, int]] = []

        def watch(view: TickView) -> None:
            if view.known[2][:, :12].any():  # x < 6 m: within robot 0's lidar (7 m), beyond robot 1's
                seen.append(view.tick)
            deliveries.extend((env.sender, env.seq, i) for box in view.sent for env in box for i in env.delivered_to)

        run(chain(3), algorithm=QUIET, comm={"map_sharing": "delta", **comm}, ticks=30, observers=[watch])
        assert len(deliveries) == len(set(deliveries)), "no robot receives a message twice"
        return seen[0]

    assert first_tick_robot_2_knows_the_far_end({"relay": "flood"}) == 2
    assert first_tick_robot_2_knows_the_far_end({}) == 11


def test_sent_counts_every_copy_and_the_causes_add_up():
    """(n - 1) * transmissions = delivered + duplicates + drops by cause, with every feature on."""
    spec = {"seed": 3, "map": {"kind": "building", "size": 40}, "robots": {"count": 6, "spawn": "random"},
            "stop": {"max_ticks": 400}, "radio": {"shadowing_sigma_db": 6.0, "per": "bpsk", "sensitivity_dbm": -70.0},
            "comm": {"relay": "flood", "loss": 0.1, "bandwidth": 400, "share_every": 5}}
    m = Simulation(spec).run().summary["messages"]
    drops = m["dropped_link"] + m["dropped_loss"] + m["dropped_bandwidth"]
    assert 5 * m["sent"] == m["delivered"] + m["duplicates"] + drops
    assert min(m["dropped_link"], m["dropped_loss"], m["dropped_bandwidth"], m["relayed"], m["duplicates"]) > 0


def margin_for(truth: Map, poses: np.ndarray, radio: dict) -> float:
    return build_link_model(truth, RadioConfig(**radio)).budget(poses[0, :2], poses[1, :2]).margin_db


@pytest.mark.parametrize("target", [0.3, -1.0])
def test_packet_errors_lose_what_the_curve_says_and_count_by_reach(target):
    """Two talkers at a chosen margin: the loss rate is the curve's within 4 standard errors; at or above
    the sensitivity the lost are dropped_loss, below it dropped_link, and some still arrive there."""
    poses = np.array([(5.0, 3.0, 0.0), (25.0, 3.0, 0.0)])
    size = len(encode(Ping(0, 0)))
    base = {"model": "multiwall", "per": "bpsk", "per_ref": 0.5, "per_ref_bytes": size}
    sens = -82.0 + margin_for(long_box(), poses, base) - target
    radio = {**base, "sensitivity_dbm": sens}
    assert margin_for(long_box(), poses, radio) == pytest.approx(target)
    ticks = 400
    _, r = run(poses, radio=radio, ticks=ticks)
    m = r.summary["messages"]
    attempts = 2 * ticks
    p = float(PacketErrorCurve(0.5, size).per(margin_for(long_box(), poses, radio), size))
    lost = m["dropped_loss"] + m["dropped_link"]
    assert m["delivered"] + lost == attempts and 0.05 < p < 0.95
    assert abs(lost / attempts - p) < 4 * np.sqrt(p * (1 - p) / attempts)
    assert (m["dropped_link"] == 0) if target >= 0 else (m["dropped_loss"] == 0 and m["delivered"] > 0)


def test_packet_errors_draw_from_their_own_stream():
    """Far above the sensitivity nothing is lost to packet errors and comm.loss draws exactly as without."""
    radio = {"model": "multiwall"}
    _, a = run(chain(2), radio=radio, comm={"loss": 0.4}, ticks=80)
    log_a = dict(Talker.log)
    _, b = run(chain(2), radio={**radio, "per": "bpsk"}, comm={"loss": 0.4}, ticks=80)
    assert Talker.log == log_a and a.summary["messages"] == b.summary["messages"]


def test_the_settings_at_their_defaults_are_todays_run():
    """Spelled-out defaults keep the run key and the result bit for bit (benchmarks/result_digests.py checks
    the same on eight longer runs)."""
    spec = {"seed": 2, "map": {"kind": "building", "size": 30}, "robots": {"count": 3}, "stop": {"max_ticks": 300}}
    spelled = {**spec, "radio": {"shadowing_sigma_db": 0.0, "shadowing_corr_m": 10.0, "per": "off",
                                 "per_ref": 0.1, "per_ref_bytes": 4096},
               "comm": {"relay": "none", "relay_hops": 4}}
    assert RunSpec.from_mapping(spelled).key == RunSpec.from_mapping(spec).key
    assert RunSpec.from_mapping({**spec, "comm": {"relay": "flood"}}).key != RunSpec.from_mapping(spec).key
    a, b = Simulation(spec).run(), Simulation(spelled).run()
    assert a.deterministic_view() == b.deterministic_view()


def shadowed_spec(transport: str = "inprocess") -> dict:
    return {"seed": 6, "map": {"kind": "building", "size": 40}, "robots": {"count": 4, "spawn": "random"},
            "stop": {"max_ticks": 250}, "transport": transport,
            "radio": {"shadowing_sigma_db": 8.0, "per": "bpsk", "per_ref": 0.5, "per_ref_bytes": 50,
                      "sensitivity_dbm": -72.0},
            "comm": {"relay": "flood", "share_every": 5}}


@pytest.mark.timeout(240)
def test_a_seeded_run_with_the_stochastic_channel_is_reproducible_in_process_and_over_zenoh():
    strip = lambda r: {k: v for k, v in r.deterministic_view().items() if k not in ("spec", "key")}  # noqa: E731
    a, b = Simulation(shadowed_spec()).run(), Simulation(shadowed_spec()).run()
    z = Simulation(shadowed_spec("zenoh")).run()
    assert strip(a) == strip(b) == strip(z)
    m = a.summary["messages"]
    assert m["relayed"] > 0 and m["dropped_link"] > 0 and m["dropped_loss"] > 0, "relays and error draws happened"
    plain = Simulation({**shadowed_spec(), "radio": {"sensitivity_dbm": -72.0}}).run()
    assert plain.summary["messages"]["dropped_link"] != m["dropped_link"], "the channel changed what arrived"


def test_the_shadowing_field_belongs_to_the_map():
    """Runs on the same map meet the same field whatever their own seed; another map seed, another field."""
    def field_at(seed: int, map_seed: int) -> np.ndarray:
        sim = Simulation({"seed": seed, "map": {"kind": "building", "size": 30, "seed": map_seed},
                          "radio": {"shadowing_sigma_db": 5.0}})
        return sim.links.evaluate(np.array([[3.0, 3.0], [20.0, 25.0], [12.0, 8.0]])).shadowing_db

    assert np.array_equal(field_at(1, 7), field_at(2, 7))
    assert not np.array_equal(field_at(1, 7), field_at(1, 8))


def test_a_medium_relays_in_inbox_order_and_forgets_finished_floods():
    """Medium alone, on a fixed chain 0 - 1 - 2 - 3: inboxes are sorted by (sender, sequence) even when
    relayed copies and direct messages meet, and a flood's bookkeeping is dropped when it ends."""
    n = 4
    link = np.zeros((n, n), dtype=bool)
    for a in range(n - 1):
        link[a, a + 1] = link[a + 1, a] = True
    medium = Medium(n, CommSpec(relay="flood", relay_hops=8), np.random.default_rng(0))
    failed = np.zeros(n, dtype=bool)
    got: dict[int, list[tuple[int, int, int]]] = {i: [] for i in range(n)}
    for tick in range(8):
        outboxes: list[list[Envelope]] = [[] for _ in range(n)]
        for sender in (0, 3):
            if tick < 2:
                outboxes[sender].append(medium.service_envelope(sender, Ping(sender, tick)))
        medium.add_relays(outboxes, failed)
        inboxes = medium.deliver(tick, outboxes, link)
        for i, box in enumerate(inboxes):
            assert [(e.sender, e.seq) for e in box] == sorted((e.sender, e.seq) for e in box)
            got[i] += [(tick + 1, e.sender, e.seq) for e in box]
        assert medium.deliveries(outboxes) == sorted(medium.deliveries(outboxes), key=lambda d: (d[0].sender, d[0].tick))
    assert [(t, s) for t, s, _ in got[3] if s == 0] == [(3, 0), (4, 0)]
    assert all(len(v) == len(set(v)) for v in got.values()) and len(got[1]) == 4
    assert medium._holders == {} and medium._pending_keys == set()


def test_cli_sets_the_channel_and_refuses_bad_values(capsys):
    ok = ["run", "--size", "20", "--robots", "3", "--max-ticks", "20", "--set", "radio.shadowing_sigma_db=4",
          "--set", "radio.per=bpsk", "--set", "comm.relay=flood", "--set", "comm.relay_hops=3"]
    assert main(ok) == 0
    capsys.readouterr()
    for flag, name in (("radio.shadowing_sigma_db=-2", "shadowing_sigma_db"), ("radio.per=qpsk", "per"),
                       ("comm.relay=gossip", "comm.relay"), ("comm.relay_hops=0", "comm.relay_hops")):
        assert main(["run", "--size", "20", "--max-ticks", "2", "--set", flag]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith("swarm: error: ") and name in err[0], err


def test_a_recording_keeps_the_shadowed_radio_and_relays_signal_strength():
    """A recording's reader rebuilds the run's shadowing field from the run's map seed (derived from its
    seed here: the hand-made map has none of its own) and gets the exact RSSI back; a relayed copy's RSSI is
    its relay's, not the original sender's."""
    from swarm.record import Recorder
    from swarm.record.reader import Recording

    captured: dict[str, np.ndarray] = {}
    relayed: list[tuple[int, int, int, int, float]] = []

    def watch(view: TickView) -> None:
        if view.tick == 7:
            captured["rssi"] = view.links.rssi.copy()
        for box in view.sent:
            for env in box:
                if env.hop > 1:
                    relayed.extend((view.tick, env.sender, env.seq, i, float(view.links.rssi[i, env.transmitter]))
                                   for i in env.delivered_to)

    Talker.log = {}
    spec = {"seed": 8, "algorithm": {"name": TALKER}, "robots": {"count": 4}, "map": {"kind": "file", "path": "x.npz"},
            "radio": {"shadowing_sigma_db": 3.0, "tx_power_dbm": -20.0}, "comm": {"map_sharing": "off", "relay": "flood"},
            "stop": {"max_ticks": 10, "explored": 1.0}}
    sim = Simulation(spec, truth=long_box(), start_poses=chain(4), observers=[watch])
    recorder = Recorder.attach(sim)
    result = sim.run()
    recorder.finish(sim, result)
    rec = Recording(recorder.to_bytes(), "test.swr")
    assert np.array_equal(rec.link_state(7).rssi, captured["rssi"], equal_nan=True)
    assert relayed, "some copies were relayed"
    got = {(m.tick, m.sender, m.seq, r): x for m in rec.messages() for r, x in zip(m.receivers, m.rssi_dbm)}
    for tick, sender, seq, receiver, rssi in relayed:
        assert abs(got[(tick, sender, seq, receiver)] - rssi) <= 0.125
