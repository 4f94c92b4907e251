"""The recorder and reader: a recording reproduces exactly what the simulation had at every tick."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from swarm.record import Recorder, load_recording
from swarm.record.container import BLOCK, HEAD, MAGIC, TAIL, encode_chunk, iter_chunks
from swarm.record.reader import Recording
from swarm.sim.loop import Simulation

SPEC = {"seed": 2, "map": {"kind": "building", "size": 30}, "robots": {"count": 4},
        "algorithm": {"name": "tests.swarm.viewer.agents:DebugExplorer"}, "stop": {"max_ticks": 700},
        "radio": {"tx_power_dbm": -30.0}}  # weak radios: links come and go as the robots move
CHECK_TICKS = (0, 1, 2, 63, 64, 65, 200, 411)
BLOCK_TICKS = 64  # several blocks, so block boundaries are exercised


@dataclass
class Truth:
    """What the simulation had, captured by our own observer."""

    states: dict[int, dict[str, Any]] = field(default_factory=dict)
    messages: list[tuple[int, int, int, str, int, tuple[int, ...], tuple[float, ...]]] = field(default_factory=list)
    rssi_error: float = 0.0

    def __call__(self, view: Any) -> None:
        rssi = view.links.rssi
        for outbox in view.sent:
            for env in outbox:
                self.messages.append((view.tick, env.sender, env.seq, type(env.message).message_type, len(env.data),
                                      tuple(env.delivered_to), tuple(rssi[env.delivered_to, env.sender].tolist())))
        if view.tick in CHECK_TICKS:
            self.states[view.tick] = {"poses": view.poses.copy(), "known": view.known.copy(),
                                      "seen": np.array(view.tracker.seen), "link": view.links.link.copy(),
                                      "rssi": rssi.copy(), "explored": view.tracker.explored,
                                      "coverage": view.tracker.coverage, "actions": list(view.actions)}


def record(spec: dict[str, Any], truth: Truth | None = None, **options: Any) -> tuple[bytes, Any, Simulation]:
    sim = Simulation(spec)
    if truth is not None:
        sim.observers = (truth,)
    recorder = Recorder.attach(sim, **options)
    result = sim.run()
    recorder.finish(sim, result)
    return recorder.to_bytes(), result, sim


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    truth = Truth()
    data, result, sim = record(SPEC, truth, block_ticks=BLOCK_TICKS)
    path = tmp_path_factory.mktemp("rec") / "run.swr"
    path.write_bytes(data)
    final = {"poses": sim.world.poses.copy(), "known": sim.known.copy(), "seen": np.array(sim.tracker.seen)}
    return {"data": data, "path": path, "result": result, "truth": truth, "final": final, "rec": load_recording(path)}


def test_the_run_is_long_enough_for_the_checks(run):
    assert run["result"].summary["ticks"] > max(CHECK_TICKS)
    assert set(run["truth"].states) == set(CHECK_TICKS)


@pytest.mark.parametrize("tick", CHECK_TICKS)
def test_reconstruction_equals_the_simulation(run, tick):
    rec, want = run["rec"], run["truth"].states[tick]
    state = rec.state_at(tick)
    assert np.array_equal(state.poses, want["poses"])          # float64, bit for bit
    assert np.array_equal(state.known, want["known"])
    assert np.array_equal(state.seen, want["seen"])
    assert np.array_equal(state.link, want["link"])
    assert state.explored == want["explored"] and state.coverage == want["coverage"]
    finite = np.isfinite(want["rssi"])
    assert np.array_equal(finite, np.isfinite(state.rssi))
    assert np.abs(state.rssi[finite] - want["rssi"][finite]).max() <= 1.0 + 0.25 / 2


@pytest.mark.parametrize("tick", CHECK_TICKS)
def test_actions_are_recorded_in_normalised_form(run, tick):
    got = run["rec"].actions_at(tick)
    for action, recorded in zip(run["truth"].states[tick]["actions"], got):
        assert recorded["goal"] == (list(action.goal) if action.goal is not None else None)
        assert recorded["velocity"] == (list(action.velocity) if action.velocity is not None else None)
        debug = recorded["debug"]
        assert debug["phase"] == tick // 10 and debug["tags"] == ["a", "b"]
        assert debug["weights"] == [float(v) for v in action.debug["weights"]]
        assert debug["n"] == int(action.debug["n"]) and math.isnan(debug["nan"])
        assert debug["target"] == (list(action.debug["target"]) if action.debug["target"] else None)


def test_actions_are_stored_only_when_they_change(run):
    rec = run["rec"]
    assert len(rec._acts) < rec.ticks * rec.n_robots / 3


def test_the_final_tick_is_what_the_simulation_ended_with(run):
    rec, final, summary = run["rec"], run["final"], run["result"].summary
    assert rec.ticks == summary["ticks"] + 1
    state = rec.state_at(rec.last_tick)
    assert np.array_equal(state.poses, final["poses"])
    assert np.array_equal(state.known, final["known"])
    assert np.array_equal(state.seen, final["seen"])
    assert state.explored == summary["explored"]
    assert rec.summary["ticks"] == summary["ticks"] and "wall_time_s" not in rec.summary


def test_every_message_is_recorded(run):
    truth = run["truth"].messages
    got = run["rec"].messages()
    assert {"swarm.map_update", "test.viewer.note"} <= {m.type for m in got}
    assert [(m.tick, m.sender, m.seq, m.type, m.size, m.receivers) for m in got] == [t[:6] for t in truth]
    for m, t in zip(got, truth):
        assert all(abs(a - b) <= 0.125 for a, b in zip(m.rssi_dbm, t[6]))
    tick = truth[len(truth) // 2][0]
    assert run["rec"].messages_at(tick) == [m for m in got if m.tick == tick]


def test_link_state_recomputes_the_exact_rssi(run):
    want = run["truth"].states[200]["rssi"]
    assert np.array_equal(run["rec"].link_state(200).rssi, want, equal_nan=True)


def test_truth_map_round_trips(run):
    rec = run["rec"]
    m = rec.truth
    assert m.shape == rec.shape and rec.spec["seed"] == 2
    assert np.array_equal(m.solid, Simulation(SPEC).truth.solid)


def test_same_spec_gives_identical_bytes(run):
    again, _, _ = record(SPEC, block_ticks=BLOCK_TICKS)
    assert again == run["data"]


def test_a_block_closes_at_its_byte_budget_and_reads_back_the_same(run, monkeypatch):
    """A swarm's blocks close by size (recorder.BLOCK_BYTES), not only by ticks: with a small budget the
    same run makes more, shorter blocks, whose every tick reads back as before."""
    import swarm.record.recorder as recorder_module
    monkeypatch.setattr(recorder_module, "BLOCK_BYTES", 12_000)
    data, _, _ = record(SPEC, block_ticks=BLOCK_TICKS)
    lengths = [body["n"] for kind, body in iter_chunks(data, "x") if kind == BLOCK]
    default = [body["n"] for kind, body in iter_chunks(run["data"], "x") if kind == BLOCK]
    assert len(lengths) > len(default) and max(lengths) < BLOCK_TICKS
    small, whole = Recording(data, "small.swr"), run["rec"]
    for tick in CHECK_TICKS:
        a, b = small.state_at(tick), whole.state_at(tick)
        assert np.array_equal(a.known, b.known) and np.array_equal(a.link, b.link)
        assert np.array_equal(a.poses, b.poses) and small.messages_at(tick) == whole.messages_at(tick)
        assert np.array_equal(small.comm_at(tick).merged_at, whole.comm_at(tick).merged_at)


def test_tick_out_of_range_is_invalid_input(run):
    from maps import InvalidInput

    with pytest.raises(InvalidInput, match="tick"):
        run["rec"].state_at(run["rec"].ticks)


def test_robots_and_links_change_over_the_run(run):
    """Guards the tests above against a degenerate run (nobody moves, links never change)."""
    rec = run["rec"]
    assert not np.array_equal(rec.poses[0], rec.poses[-1])
    assert len(rec._link_idx) > rec.n_robots * (rec.n_robots - 1)  # toggles beyond the first tick's links


def test_lossy_line_of_sight_radio(tmp_path):
    """Receivers are who actually got each message (loss thins broadcasts); -inf RSSI survives."""
    spec = {"seed": 5, "map": {"kind": "building", "size": 20}, "robots": {"count": 3}, "radio": {"model": "los"},
            "comm": {"loss": 0.5}, "stop": {"max_ticks": 120}}
    truth = Truth()
    data, _, _ = record(spec, truth)
    rec = Recording(data)
    got = rec.messages()
    assert [m.receivers for m in got] == [t[5] for t in truth.messages]
    assert any(0 < len(m.receivers) < 2 for m in got)
    for tick in (0, 65):
        want = truth.states[tick]["rssi"]
        link, rssi = rec.links_at(tick)
        assert np.array_equal(link, truth.states[tick]["link"])
        assert np.array_equal(rssi, want, equal_nan=True)  # los: tx power or -inf, both exact here


def test_action_normalisation():
    from swarm.api import Action
    from swarm.record.recorder import MAX_DEBUG_BYTES, pack_action

    class Thing:
        def __repr__(self) -> str:
            return "<thing>"

    import msgpack

    debug = {"obj": Thing(), "set": frozenset({3, 1}), "arr": np.array([[1, 2]]), "f": np.float32(0.5)}
    goal, velocity, clear, got = msgpack.unpackb(pack_action(Action(goal=(1.0, 2.0), debug=debug)))
    assert goal == [1.0, 2.0] and velocity is None and clear is False
    assert got == {"obj": "<thing>", "set": [1, 3], "arr": [[1, 2]], "f": 0.5}
    huge = msgpack.unpackb(pack_action(Action(velocity=(0.5, 0.0), debug={"blob": "x" * MAX_DEBUG_BYTES})))
    assert huge[1] == [0.5, 0.0] and "_omitted" in huge[3]
    assert msgpack.unpackb(pack_action(None)) is None


# ------------------------------------------------------------------------------- bad files ----
def rebuild(data: bytes, edit) -> bytes:
    """Re-encode every chunk (with valid CRCs) after ``edit(kind, body)`` changed some."""
    out = [MAGIC]
    for kind, body in iter_chunks(data, "x"):
        edited = edit(kind, body)
        if edited is not None:
            out.append(encode_chunk(kind, edited))
    return b"".join(out)


def test_a_rebuilt_file_still_loads(run):
    assert Recording(rebuild(run["data"], lambda k, b: b)).ticks == run["rec"].ticks


@pytest.mark.parametrize("edit, needle", [
    (lambda k, b: {**b, "version": 99} if k == HEAD else b, "version 99"),
    (lambda k, b: {**b, "format": "other"} if k == HEAD else b, "format"),
    (lambda k, b: {**b, "n_robots": 0} if k == HEAD else b, "n_robots"),
    (lambda k, b: None if k == TAIL else b, "TAIL"),
    (lambda k, b: None if k == HEAD else b, "HEAD"),
    (lambda k, b: {**b, "t0": b["t0"] + 1} if k == BLOCK else b, "starts at tick"),
    (lambda k, b: {**b, "pose": ["<f8", False, b"\0" * 8]} if k == BLOCK else b, "pose"),
    (lambda k, b: {**b, "known_val": ["|u1", False, b"\7" * len(b["known_val"][2])]} if k == BLOCK else b,
     "knowledge value"),
    (lambda k, b: {**b, "msg_sender": ["<u2", False, b"\xff\xff" * (len(b["msg_sender"][2]) // 2)]}
     if k == BLOCK and b["msg_sender"][2] else b, "sender"),
    (lambda k, b: {**b, "act": [1] * len(b["act"])} if k == BLOCK else b, "act"),
    (lambda k, b: {**b, "pose": ["<f4", False, b""]} if k == BLOCK else b, "dtype"),
    (lambda k, b: {**b, "ticks": 3} if k == TAIL else b, "TAIL says"),
])
def test_semantically_broken_files_are_invalid_input(run, edit, needle):
    from maps import InvalidInput

    with pytest.raises(InvalidInput, match=needle):
        Recording(rebuild(run["data"], edit), "bad.swr")


@pytest.fixture(scope="module")
def tiny() -> bytes:
    spec = {"seed": 1, "map": {"kind": "building", "size": 20}, "robots": {"count": 2}, "stop": {"max_ticks": 30}}
    return record(spec, block_ticks=8)[0]


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_any_truncation_or_byte_flip_is_invalid_input(tiny, data):
    from maps import InvalidInput

    if data.draw(st.booleans()):
        damaged = tiny[: data.draw(st.integers(0, len(tiny) - 1))]
    else:
        at = data.draw(st.integers(0, len(tiny) - 1))
        damaged = tiny[:at] + bytes([tiny[at] ^ data.draw(st.integers(1, 255))]) + tiny[at + 1:]
    with pytest.raises(InvalidInput, match="recording"):
        Recording(damaged)


def test_unreadable_path_is_invalid_input(tmp_path):
    from maps import InvalidInput

    with pytest.raises(InvalidInput, match="readable"):
        load_recording(tmp_path / "missing.swr")
