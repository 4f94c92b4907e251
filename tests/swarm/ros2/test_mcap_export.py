"""MCAP export of runs (issue 51): every topic decodes with decoders we did not write (mcap_ros2's and
rosbags'), the values are the run's, ``swarm export`` of a recording and ``swarm run --mcap`` of the same
spec give the same bytes, and bad input ends in one line and exit status 2."""

from __future__ import annotations

import json
import math
import re
import sys
import warnings
from collections import defaultdict
from pathlib import Path
from typing import Any

import numpy as np
import pytest

pytest.importorskip("mcap_ros2")
pytest.importorskip("rosbags")

with warnings.catch_warnings():   # mcap_ros2.reader warns on import that mcap_ros1.reader is deprecated
    warnings.simplefilter("ignore", DeprecationWarning)
    from mcap_ros2.reader import read_ros2_messages
from rosbags.highlevel import AnyReader
from rosbags.typesys import Stores, get_typestore

from maps import Map
from swarm.cli import main
from swarm.record import Recorder, load_recording
from swarm.record.animation import ROBOT_COLOURS
from swarm.record.container import MAGIC, encode_chunk, iter_chunks
from swarm.ros2.frames import recording_frames, recording_info, robot_action
from swarm.ros2.mcap_export import McapRecorder, export_recording
from swarm.ros2.topics import (
    CAUSE_COLOURS,
    KNOWN_TO_OCCUPANCY,
    LOST_TICKS,
    RAMP,
    RunInfo,
    RunTopics,
    ramp_colour,
)
from swarm.sim.loop import Simulation
from swarm.world.sensing import LidarParams

ROOT = Path(__file__).resolve().parents[3]
TICK_NS = 100_000_000

# A hand-built 24 x 16 m hall: a border wall and, at x = 10 m, a wall with a 2 m doorway (y 7-9 m)
SOLID = np.zeros((32, 48), dtype=bool)
SOLID[[0, -1], :] = SOLID[:, [0, -1]] = True
SOLID[:, 20] = True
SOLID[14:18, 20] = False
START = np.array([[7.25, 3.25, 0.0],         # faces the wall at x = 10 m: its first ray ends at 2.75 m
                  [3.25, 12.25, math.pi / 2],
                  [5.25, 8.25, math.pi]])     # faces the border wall (its cells end at x = 0.5 m): 4.75 m
SPEC = {"seed": 3, "robots": {"count": 3}, "algorithm": {"name": "minotaur"}, "stop": {"max_ticks": 160},
        "comm": {"loss": 0.3}}  # seeded packet loss: failed deliveries to draw


def hall() -> Map:
    return Map(solid=SOLID, material=SOLID.astype(np.uint8), materials=("air", "concrete"))


@pytest.fixture(scope="module")
def run(tmp_path_factory) -> dict[str, Any]:
    """One run of the hall, recorded (.swr) and exported live (MCAP) at once, then the recording exported."""
    folder = tmp_path_factory.mktemp("mcap")
    sim = Simulation(SPEC, truth=hall(), start_poses=START)
    recorder = Recorder.attach(sim)
    live = McapRecorder.attach(sim, map_every=5)
    result = sim.run()
    recorder.finish(sim, result)
    recorder.save(folder / "run.swr")
    live.save(sim, folder / "live.mcap")
    export_recording(folder / "run.swr", folder / "export.mcap", map_every=5)
    return {"folder": folder, "rec": load_recording(folder / "run.swr"), "live": folder / "live.mcap",
            "export": folder / "export.mcap", "by_mcap": by_mcap_ros2(folder / "export.mcap"),
            "by_rosbags": by_rosbags(folder / "export.mcap")}


def by_mcap_ros2(path: Path) -> dict[str, list[tuple[int, Any]]]:
    out: dict[str, list[tuple[int, Any]]] = defaultdict(list)
    for m in read_ros2_messages(str(path)):
        out[m.channel.topic].append((m.log_time_ns, m.ros_msg))
    return dict(out)


def by_rosbags(path: Path) -> dict[str, list[tuple[int, Any]]]:
    out: dict[str, list[tuple[int, Any]]] = defaultdict(list)
    with AnyReader([path], default_typestore=get_typestore(Stores.ROS2_JAZZY)) as reader:
        for conn, stamp, raw in reader.messages():
            out[conn.topic].append((stamp, reader.deserialize(raw, conn.msgtype)))
    return dict(out)


def at(messages: list[tuple[int, Any]], tick: int) -> Any:
    found = [m for stamp, m in messages if stamp == tick * TICK_NS]
    assert len(found) == 1, (tick, len(found))
    return found[0]


def yaw(q: Any) -> float:
    return 2 * math.atan2(q.z, q.w)


# ---------------------------------------------------------------------------------------- decoding ----
def test_both_decoders_read_every_topic_alike(run):
    rec, ours, theirs = run["rec"], run["by_mcap"], run["by_rosbags"]
    declared = {t.name: t.type for t in RunTopics(recording_info(rec)).topics}
    assert set(ours) == set(theirs) and set(ours) <= set(declared)
    per_robot = {"pose", "scan", "goal", "map", "doorways"}
    assert {f"/robot_{i}/{name}" for i in range(3) for name in per_robot} <= set(ours)
    assert {"/clock", "/map", "/tf", "/explored", "/coverage", "/comm/links", "/comm/groups", "/comm/lost"} <= set(ours)
    for topic, messages in ours.items():
        assert [s for s, _ in messages] == [s for s, _ in theirs[topic]], topic
        assert all(type(m).__name__ == declared[topic].rsplit("/", 1)[1] for _, m in messages)
        assert all(m.__msgtype__ == declared[topic] for _, m in theirs[topic])
    for (_, a), (_, b) in zip(ours["/robot_1/pose"], theirs["/robot_1/pose"]):
        assert (a.pose.position.x, a.pose.position.y, a.pose.orientation.z) == \
               (b.pose.position.x, b.pose.position.y, b.pose.orientation.z)
    clock = [m.clock for _, m in ours["/clock"]]
    assert [c.sec * 10**9 + c.nanosec for c in clock] == [t * TICK_NS for t in range(rec.ticks)]


def test_the_map_is_latched_for_players(run):
    with AnyReader([run["export"]], default_typestore=get_typestore(Stores.ROS2_JAZZY)) as reader:
        qos = {c.topic: c.ext.offered_qos_profiles[0] for c in reader.connections}
    assert qos["/map"].durability.name == "TRANSIENT_LOCAL" and qos["/map"].depth == 1
    assert qos["/tf"].durability.name == "VOLATILE"
    assert len(run["by_mcap"]["/map"]) == 1


# ------------------------------------------------------------------------------------------ values ----
def test_poses_and_transforms_are_the_recorded_poses(run):
    rec, ours = run["rec"], run["by_mcap"]
    for tick in (0, 1, 57, rec.ticks - 1):
        tf = {t.child_frame_id: t for t in at(ours["/tf"], tick).transforms}
        for i in range(3):
            x, y, theta = rec.poses[tick, i]
            pose = at(ours[f"/robot_{i}/pose"], tick)
            assert pose.header.frame_id == "map"
            assert (pose.pose.position.x, pose.pose.position.y) == (x, y)
            assert math.isclose(math.remainder(yaw(pose.pose.orientation) - theta, math.tau), 0, abs_tol=1e-12)
            t = tf[f"robot_{i}/base_link"]
            assert t.header.frame_id == "map"
            assert (t.transform.translation.x, t.transform.translation.y) == (x, y)
            q, r = t.transform.rotation, pose.pose.orientation
            assert (q.x, q.y, q.z, q.w) == (r.x, r.y, r.z, r.w)


def test_a_scan_range_is_the_distance_to_a_known_wall(run):
    ours = run["by_mcap"]
    scans = [at(ours[f"/robot_{i}/scan"], 0) for i in range(3)]
    assert scans[0].header.frame_id == "robot_0/base_link" and scans[0].angle_min == 0.0
    assert scans[0].ranges[0] == pytest.approx(2.75, abs=1e-6)   # east to the wall at x = 10 m
    assert scans[2].ranges[0] == pytest.approx(4.75, abs=1e-6)   # west to the border wall's face, x = 0.5 m
    n = len(scans[0].ranges)
    assert scans[0].angle_increment == pytest.approx(2 * math.pi / n) and scans[0].range_max == 7.0
    assert scans[0].ranges[n // 2] == pytest.approx(7.25 - 0.5, abs=1e-6)   # west: the border wall
    assert np.isinf(scans[0].ranges[n // 4])                                # north: no wall within 7 m


def test_maps_are_the_truth_and_the_robots_knowledge(run):
    rec, ours = run["rec"], run["by_mcap"]
    grid = ours["/map"][0][1]
    assert (grid.info.width, grid.info.height, grid.info.resolution) == (48, 32, 0.5)
    assert np.array_equal(np.asarray(grid.data).reshape(32, 48), np.where(SOLID, 100, 0))
    for i in range(3):
        stamps = [stamp for stamp, _ in ours[f"/robot_{i}/map"]]
        assert stamps[0] == 0 and all(s % (5 * TICK_NS) == 0 or s == (rec.ticks - 1) * TICK_NS for s in stamps)
        for stamp, grid in ours[f"/robot_{i}/map"][::7]:
            known = rec.known_at(stamp // TICK_NS)[i]
            assert np.array_equal(np.asarray(grid.data).reshape(known.shape), KNOWN_TO_OCCUPANCY[known])
    last = rec.known_at(rec.ticks - 1)[0]
    grid = np.asarray(ours["/robot_0/map"][-1][1].data).reshape(last.shape)
    assert grid[6, 14] == 0 and last[6, 14] == 1            # its start cell: free
    assert grid[6, 20] == 100 and last[6, 20] == 2          # the wall it faced


def test_goals_are_the_actions_goals(run):
    rec, ours = run["rec"], run["by_mcap"]
    goals = {(stamp // TICK_NS, m.pose.position.x, m.pose.position.y) for stamp, m in ours["/robot_0/goal"]}
    assert goals
    for tick, x, y in goals:
        assert tuple(rec.actions_at(tick)[0]["goal"]) == (x, y)


def test_markers_for_links_groups_losses_and_doorways(run):
    rec, ours = run["rec"], run["by_mcap"]
    tick = next(t for t in range(rec.ticks) if rec.links_at(t)[0][0, 1] and rec.links_at(t)[0][1, 0])
    xy = rec.poses[tick, :, :2]
    links = at(ours["/comm/links"], tick).markers
    two_way = next(m for m in links if m.ns == "two_way")
    pairs = {tuple(sorted(((a.x, a.y), (b.x, b.y)))) for a, b in zip(two_way.points[::2], two_way.points[1::2])}
    assert tuple(sorted((tuple(xy[0]), tuple(xy[1])))) in pairs
    k = [tuple(sorted(((a.x, a.y), (b.x, b.y)))) for a, b in zip(two_way.points[::2], two_way.points[1::2])].index(
        tuple(sorted((tuple(xy[0]), tuple(xy[1])))))
    rssi, sensitivity = rec.link_state(tick).rssi, rec.header["sensitivity_dbm"]
    margin = min(rssi[0, 1] - sensitivity[0], rssi[1, 0] - sensitivity[1])
    c = two_way.colors[2 * k]
    assert (c.r, c.g, c.b, c.a) == pytest.approx([*(v / 255 for v in ramp_colour(margin)), 0.85])

    groups = at(ours["/comm/groups"], tick).markers
    together = [g for g in rec.link_state(tick).groups() if len(g) > 1]
    assert sorted(m.id for m in groups if m.action == 0) == sorted(min(g) for g in together)
    for m in groups:
        assert (m.color.r, m.color.g, m.color.b, m.color.a) == pytest.approx([*(v / 255 for v in ROBOT_COLOURS[m.id]),
                                                                               0.3])

    lost = [(t, m) for t in range(rec.ticks - 1) for m in rec.messages_at(t) if m.lost]
    assert lost
    t, message = lost[0]
    _, cause = message.lost[0]
    marker = next(m for m in at(ours["/comm/lost"], t + 1).markers if m.ns == f"lost/{cause}")
    sx, sy = rec.poses[t + 1, message.transmitter, :2]
    assert (marker.points[0].x, marker.points[0].y) == (sx, sy)
    assert marker.lifetime.nanosec + marker.lifetime.sec * 10**9 == LOST_TICKS * TICK_NS
    assert (marker.color.r, marker.color.g, marker.color.b) == pytest.approx([v / 255 for v in CAUSE_COLOURS[cause]])

    recorded = [(t, i, a) for t in range(rec.ticks) for i, a in rec.actions_changed(t).items()
                if a and a["debug"] and a["debug"].get("doorways")]
    assert recorded   # Minotaur found the doorway
    t, i, action = recorded[0]
    x, y, axis, width, _ = action["debug"]["doorways"][0]
    sent = next(m for s, m in ours[f"/robot_{i}/doorways"] if s >= t * TICK_NS)
    ends = {(p.x, p.y) for marker in sent.markers for p in marker.points}
    assert ((x, y - width / 2) if axis == 1 else (x - width / 2, y)) in ends
    for marker in sent.markers:
        assert (marker.color.r, marker.color.g, marker.color.b) == pytest.approx([v / 255 for v in ROBOT_COLOURS[i]])


def test_live_and_exported_files_are_the_same_bytes(run):
    assert run["live"].read_bytes() == run["export"].read_bytes()
    again = run["folder"] / "again.mcap"
    export_recording(run["folder"] / "run.swr", again, map_every=5)
    assert again.read_bytes() == run["export"].read_bytes()


def test_frames_replay_the_recording(run):
    rec = run["rec"]
    for frame in recording_frames(rec):
        if frame.tick in (0, 80, rec.ticks - 1):
            assert np.array_equal(frame.known, rec.known_at(frame.tick))
            assert np.array_equal(frame.link, rec.links_at(frame.tick)[0])
    assert frame.final and frame.tick == rec.ticks - 1


def test_actions_are_read_leniently():
    a = robot_action([1, 2.5], False, {"doorways": [[1.0, 2.0, 1, 1.5, True], ["x"], [1, 2, 5, 1, False]]})
    assert a.goal == (1.0, 2.5) and a.doorways == ((1.0, 2.0, 1, 1.5, True),)
    assert robot_action("nowhere", True, None) == robot_action(None, True, {"other": 1})


def test_colours_are_the_viewers():
    js = (ROOT / "swarm" / "viewer" / "viewer.js").read_text()
    ramp = re.search(r"const RAMP = (\[.*?\]);\n", js).group(1)
    assert json.loads(ramp) == [[v, list(c)] for v, c in RAMP]
    causes = dict(re.findall(r"(\w+): \[\[(\d+, \d+, \d+)\], '", js))
    assert {k: tuple(int(v) for v in c.split(", ")) for k, c in causes.items()} == CAUSE_COLOURS
    assert re.search(r"const LOST_TICKS = (\d+);", js).group(1) == str(LOST_TICKS)


def test_the_foxglove_layout_names_exported_topics():
    layout = json.loads((ROOT / "docs" / "foxglove-layout.json").read_text())
    assert {"configById", "globalVariables", "userNodes", "playbackConfig", "layout"} <= set(layout)

    def panels(node: Any) -> list[str]:
        return [node] if isinstance(node, str) else panels(node["first"]) + panels(node["second"])

    ids = panels(layout["layout"])
    assert sorted(ids) == sorted(layout["configById"]) and len(set(ids)) == len(ids)
    names = {t.name for t in RunTopics(RunInfo(hall(), 10, LidarParams(), 0.3, np.zeros(10))).topics}
    used = set()
    for config in layout["configById"].values():
        used |= set(config.get("topics", {}))
        used |= {p["value"].split(".", 1)[0] for p in config.get("paths", [])}
    assert used and used <= names, used - names
    assert any(panel.startswith("3D!") and config.get("followTf") == "map" for panel, config in layout["configById"].items())


# -------------------------------------------------------------------------------------------- CLI ----
def cli(capsys, *argv: str) -> tuple[int, str, str]:
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def one_line_error(code: int, err: str, needle: str) -> None:
    assert code == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("swarm: error: ") and needle in lines[0], err
    assert "Traceback" not in err


def test_cli_run_mcap_equals_export_of_the_recording(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    flags = ["--size", "20", "--robots", "3", "--algorithm", "minotaur", "--max-ticks", "60", "--set", "comm.loss=0.3"]
    assert cli(capsys, "run", *flags, "--record", "r.swr")[0] == 0
    assert cli(capsys, "run", *flags, "--mcap", "live.mcap", "--mcap-map-every", "7")[0] == 0
    code, out, _ = cli(capsys, "export", "r.swr", "--map-every", "7")
    assert code == 0 and out.strip() == "wrote r.mcap"
    assert Path("r.mcap").read_bytes() == Path("live.mcap").read_bytes()
    last = load_recording("r.swr").ticks - 1
    assert {s for s, _ in by_mcap_ros2(Path("r.mcap"))["/robot_0/map"]} <= {t * TICK_NS for t in (*range(0, last, 7), last)}


@pytest.fixture(scope="module")
def swr(run) -> Path:
    return run["folder"] / "run.swr"


@pytest.mark.parametrize("case", ["not_a_recording", "damaged", "truncated", "missing"])
def test_export_refuses_bad_recordings_in_one_line(case, swr, tmp_path, capsys):
    bad = tmp_path / "bad.swr"
    data = swr.read_bytes()
    if case == "not_a_recording":
        bad.write_text("hello\n")
    elif case == "damaged":
        bad.write_bytes(data[:200] + bytes([data[200] ^ 0xFF]) + data[201:])
    elif case == "truncated":
        bad.write_bytes(data[: len(data) // 2])
    code, _, err = cli(capsys, "export", str(bad), "-o", str(tmp_path / "out.mcap"))
    one_line_error(code, err, "bad.swr")
    assert not (tmp_path / "out.mcap").exists()


@pytest.mark.parametrize("edit", [
    lambda head: head["spec"].update(seed=-1),
    lambda head: head["spec"].update(lidar={"range_m": -1.0}),
    lambda head: head["spec"].update(radio="loud"),
    lambda head: head.update(sensitivity_dbm=["-82"] * 3),
])
def test_export_refuses_a_recording_whose_head_is_not_a_runs(edit, swr, tmp_path, capsys):
    """A file that loads (the reader checks HEAD's fields' types) but whose spec or radios cannot be a run's."""
    chunks = list(iter_chunks(swr.read_bytes(), str(swr)))
    edit(chunks[0][1])
    bad = tmp_path / "edited.swr"
    bad.write_bytes(MAGIC + b"".join(encode_chunk(kind, body) for kind, body in chunks))
    code, _, err = cli(capsys, "export", str(bad), "-o", str(tmp_path / "out.mcap"))
    one_line_error(code, err, "edited.swr")


@pytest.mark.parametrize("argv,needle", [
    (["-o", "/nonexistent/out.mcap"], "--output"),
    (["-o", "/proc/version"], "--output"),
    (["-o", "{swr}"], "--output"),
    (["--map-every", "0"], "--map-every"),
    (["--map-every", "ten"], "--map-every"),
])
def test_export_refuses_bad_flags_in_one_line(argv, needle, swr, capsys):
    code, _, err = cli(capsys, "export", str(swr), *[a.format(swr=swr) for a in argv])
    one_line_error(code, err, needle)


@pytest.mark.parametrize("argv,needle", [
    (["--mcap-map-every", "5"], "--mcap-map-every"),
    (["--mcap", "x.mcap", "--mcap-map-every", "0"], "--mcap-map-every"),
    (["--mcap", "/nonexistent/x.mcap"], "--mcap"),
])
def test_run_refuses_bad_mcap_flags_before_running(argv, needle, capsys):
    code, _, err = cli(capsys, "run", "--max-ticks", "2", *argv)
    one_line_error(code, err, needle)


def test_without_the_extra_one_line_names_it(swr, tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "mcap.writer", None)   # import mcap.writer now raises ImportError
    code, _, err = cli(capsys, "export", str(swr), "-o", str(tmp_path / "x.mcap"))
    one_line_error(code, err, "pip install 'swarm-sim[ros]'")
    code, _, err = cli(capsys, "run", "--max-ticks", "2", "--mcap", str(tmp_path / "x.mcap"))
    one_line_error(code, err, "pip install 'swarm-sim[ros]'")
    assert not (tmp_path / "x.mcap").exists()
