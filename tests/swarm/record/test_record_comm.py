"""The recording's communication streams (format version 2): every failed delivery with its cause, the
tick's groups, and each robot's age of information, time since contact and missing share, equal to what the
run itself measured; recording changes nothing in the run; version 1 files still load."""

from __future__ import annotations

from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from maps import InvalidInput
from swarm.comm.medium import LOSS_CAUSES
from swarm.record import Recorder, load_recording
from swarm.record.reader import Recording
from swarm.sim.loop import Simulation

from .test_record import rebuild

V1_FILE = Path(__file__).parent / "data" / "v1-building20.swr"
"""Recorded by swarm's format version 1 writer (main before issue 34): 3 robots, building 20, 40 ticks."""
V2_FILE = Path(__file__).parent / "data" / "v2-building20.swr"
"""Recorded by swarm's format version 2 writer (main before issue 47) from :data:`V2_SPEC`."""
V2_SPEC = {"seed": 3, "map": {"kind": "building", "size": 20}, "robots": {"count": 4}, "stop": {"max_ticks": 120},
           "radio": {"tx_power_dbm": -30.0}, "comm": {"loss": 0.1, "relay": "flood"}, "record_every": 1}

EVERY_CAUSE = {"seed": 3, "map": {"kind": "building", "size": 30}, "robots": {"count": 5}, "stop": {"max_ticks": 400},
               "radio": {"tx_power_dbm": -20.0, "per": "bpsk", "per_ref": 0.9, "per_ref_bytes": 100,
                         "shadowing_sigma_db": 4.0},
               "comm": {"loss": 0.1, "bandwidth": 300, "relay": "flood"}}
"""Weak radios with packet errors, loss, a byte budget and relaying: every cause of a failed delivery."""
PLAIN = {"seed": 2, "map": {"kind": "building", "size": 30}, "robots": {"count": 4}, "stop": {"max_ticks": 500},
         "radio": {"tx_power_dbm": -30.0}, "comm": {"loss": 0.2, "share_every": 3}, "record_every": 1}
"""Metrics rows at every tick, maps shared every third tick: contacts on consecutive ticks."""
MAES_RECEIVE = {"seed": 3, "map": {"kind": "building", "size": 30}, "robots": {"count": 4}, "stop": {"max_ticks": 400},
                "radio": {"tx_power_dbm": -30.0}, "algorithm": {"name": "tnf"},
                "comm": {"loss": 0.1, "link_at": "receive", "map_sharing": "maes"}, "record_every": 1}


class Envelopes:
    """Keeps every envelope the run sent (read after the run: with ``link_at = "receive"`` a tick's
    messages are delivered during the next tick) and the link matrix of each tick."""

    def __init__(self) -> None:
        self.sent: list[tuple[int, Any]] = []
        self.links: dict[int, np.ndarray] = {}

    def __call__(self, view: Any) -> None:
        self.sent.extend((view.tick, env) for box in view.sent for env in box)
        self.links[view.tick] = view.links.link.copy()


def record(spec: dict[str, Any], *observers: Any) -> tuple[Recording, Any, bytes]:
    sim = Simulation(spec, observers=observers)
    recorder = Recorder.attach(sim, block_ticks=64)
    result = sim.run()
    recorder.finish(sim, result)
    data = recorder.to_bytes()
    return Recording(data, "test.swr"), result, data


@pytest.fixture(scope="module")
def every_cause():
    seen = Envelopes()
    rec, result, data = record(EVERY_CAUSE, seen)
    return rec, result, seen, data


@pytest.mark.parametrize("spec", [EVERY_CAUSE, MAES_RECEIVE])
def test_recording_changes_nothing_in_the_run(spec):
    """The recorder asks the medium to list failed deliveries; the run's results stay bit for bit."""
    plain = Simulation(spec).run()
    _, recorded, _ = record(spec)
    untimed = lambda summary: {k: v for k, v in summary.items() if not k.endswith("_time_s")}  # noqa: E731
    assert untimed(recorded.summary) == untimed(plain.summary)
    assert recorded.timeseries == plain.timeseries and recorded.events == plain.events
    assert recorded.comm == plain.comm


def test_every_failed_delivery_is_recorded_with_its_cause(every_cause):
    rec, result = every_cause[:2]
    m = result.summary["messages"]
    lost = Counter(cause for msg in rec.messages() for _, cause in msg.lost)
    assert set(lost) == set(LOSS_CAUSES), "the run exercises every cause"
    assert lost["link"] == m["dropped_link"] and lost["bandwidth"] == m["dropped_bandwidth"]
    assert lost["loss"] + lost["packet_error"] == m["dropped_loss"]
    for msg in rec.messages():
        missed = [robot for robot, _ in msg.lost]
        assert len(set(missed)) == len(missed) and not set(missed) & set(msg.receivers)
        assert msg.transmitter not in missed and msg.transmitter not in msg.receivers
        assert len(missed) + len(msg.receivers) <= rec.n_robots - 1  # the rest: relayed copies already held


def test_failed_deliveries_name_their_transmitter_and_follow_the_links(every_cause):
    """Each recorded transmission is the run's envelope (relayed copies from their relay); a delivery lost
    for want of a link had none, and every other failure (loss, byte budget, packet error) had one."""
    rec, _, seen, _ = every_cause
    got = rec.messages()
    assert [(m.tick, m.sender, m.seq, m.transmitter) for m in got] == \
        [(tick, env.sender, env.seq, env.transmitter) for tick, env in seen.sent]
    assert any(m.transmitter != m.sender for m in got)
    for m, (tick, env) in zip(got, seen.sent):
        assert m.lost == tuple((robot, LOSS_CAUSES[cause]) for robot, cause in env.lost)
        link = seen.links[tick]
        for robot, cause in m.lost:
            assert link[robot, m.transmitter] == (cause != "link"), (tick, m, robot, cause)


@pytest.mark.parametrize("spec", [PLAIN, EVERY_CAUSE, MAES_RECEIVE], ids=["plain", "every-cause", "maes-receive"])
def test_comm_at_every_row_is_what_the_run_measured(spec):
    """Groups, age of information, time since contact and missing share from the recording equal the run's
    own RunResult.comm rows, exactly, at every row (with links judged at send and at receipt)."""
    rec, result, _ = record(spec)
    robots = result.comm["robots"]
    rows = result.comm["series"]["tick"]
    assert len(rows) > 20
    for k, tick in enumerate(rows):
        state = rec.comm_at(tick)
        assert state.aoi_age.tolist() == robots["aoi_age"][k]
        assert state.since_contact.tolist() == robots["since_contact"][k]
        assert state.missing_free.tolist() == robots["missing_free"][k]
        labels = robots["group"][k]
        assert state.groups == [frozenset(i for i, g in enumerate(labels) if g == label)
                                for label in sorted(set(labels))]
    ages = np.array(robots["aoi_age"])
    assert ages.max() > 20 and len({len(rec.comm_at(t).groups) for t in rows}) > 1, "a run where comm matters"


def test_groups_at_any_tick_are_the_radios(every_cause):
    rec = every_cause[0]
    for tick in (0, 1, 57, 130, rec.last_tick):
        assert rec.comm_at(tick).groups == rec.link_state(tick).groups()


def test_receipt_time_links_record_who_got_each_message():
    """With link_at = "receive" a tick's messages are judged during the next tick: the recording still lists
    their receivers and failed deliveries (it writes a tick's messages one tick late)."""
    seen = Envelopes()
    rec, result, _ = record(MAES_RECEIVE, seen)
    got = rec.messages()
    assert [m.receivers for m in got] == [tuple(env.delivered_to) for _, env in seen.sent]
    assert sum(len(m.receivers) for m in got) == result.summary["messages"]["delivered"] > 0
    assert sum(len(m.lost) for m in got) == sum(result.summary["messages"][f"dropped_{c}"]
                                                for c in ("link", "loss", "bandwidth")) > 0


def test_a_version_1_recording_still_loads():
    rec = load_recording(V1_FILE)
    assert rec.version == 1 and not rec.has_comm and rec.ticks == 41 and rec.n_robots == 3
    messages = rec.messages()
    assert messages and all(m.lost == () and m.transmitter == m.sender for m in messages)
    assert rec.state_at(rec.last_tick).known.any()
    with pytest.raises(InvalidInput, match="version 1 has no communication streams"):
        rec.comm_at(5)


def test_a_version_2_recording_reads_as_version_3_of_the_same_run():
    """Version 3 stores link toggles, RSSI updates and merges as per-tick gaps: the run recorded by the
    version 2 writer (indices) reads back the same at every tick as the same run recorded now."""
    old = load_recording(V2_FILE)
    new, _, _ = record(V2_SPEC)  # blocks of 64 ticks; the old file's were 32
    assert (old.version, new.version) == (2, 3) and old.ticks == new.ticks == 121
    assert new.header["spec"] == old.header["spec"]
    toggles = merges = 0
    for tick in range(old.ticks):
        a, b = old.state_at(tick), new.state_at(tick)
        assert np.array_equal(a.known, b.known) and np.array_equal(a.link, b.link)
        assert np.array_equal(a.rssi, b.rssi, equal_nan=True)
        ca, cb = old.comm_at(tick), new.comm_at(tick)
        assert np.array_equal(ca.merged_at, cb.merged_at) and ca.groups == cb.groups
        assert old.messages_at(tick) == new.messages_at(tick)
        toggles += tick > 0 and not np.array_equal(a.link, old.state_at(tick - 1).link)
        merges += tick > 0 and not np.array_equal(ca.merged_at, old.comm_at(tick - 1).merged_at)
    assert toggles >= 3 and merges >= 10  # the gap-coded streams were exercised


@pytest.mark.parametrize("edit, needle", [
    (lambda k, b: {**b, "msg_lost_cause": ["|u1", False, b"\x09" * len(b["msg_lost_cause"][2])]}
     if k == b"BLCK" and b["msg_lost_cause"][2] else b, "loss cause"),
    (lambda k, b: {**b, "group_id": ["<u2", False, b"\x63\x00" * (len(b["group_id"][2]) // 2)]}
     if k == b"BLCK" and b["group_id"][2] else b, "group"),
    (lambda k, b: {**b, "team_free": ["<u4", False, b""]} if k == b"BLCK" else b, "team_free"),
    (lambda k, b: {k2: v for k2, v in b.items() if k2 != "aoi_gap"} if k == b"BLCK" else b, "aoi_gap"),
    (lambda k, b: {**b, "link_gap": ["<u4", True, b["link_gap"][2][:-4]]} if k == b"BLCK" and b["link_gap"][2] else b,
     "link_gap has"),
    (lambda k, b: {k2: v for k2, v in b.items() if k2 != "loss_causes"} if k == b"HEAD" else b, "loss_causes"),
    (lambda k, b: {**b, "version": 4} if k == b"HEAD" else b, "version 4; this reader knows 1 to 3"),
])
def test_broken_communication_streams_are_invalid_input(every_cause, edit, needle):
    data = rebuild(every_cause[3], edit)
    with pytest.raises(InvalidInput, match=needle) as err:
        Recording(data, "bad.swr")
    assert "\n" not in str(err.value)

