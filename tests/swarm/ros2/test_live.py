"""A live run speaks ROS 2 as rmw_zenoh does (issue 51), checked over real zenoh sessions on loopback.

The peers here are plain zenoh sessions that know only rmw_zenoh's conventions, built from rosbags and the
formats of rmw_zenoh's design doc (tests/swarm/ros2/test_rmw.py checks those against the doc's examples):
they stand where an rmw_zenohd router, RViz or a ROS 2 driver node would.
"""

from __future__ import annotations

import json
import math
import socket
import threading
import time
from typing import Any, Callable

import numpy as np
import pytest

pytest.importorskip("rosbags")

import zenoh  # noqa: E402
import zenoh.ext as ze  # noqa: E402
from rosbags.typesys import Stores, get_typestore  # noqa: E402

from swarm.api import Action  # noqa: E402
from swarm.ros2 import rmw  # noqa: E402
from swarm.ros2.external import TICK_NS, RosHost  # noqa: E402
from swarm.ros2.live import MAX_COMMAND_BYTES, MAX_MESSAGE_BYTES, RosAccess, open_node  # noqa: E402
from swarm.sim.loop import Simulation, TransportOptions  # noqa: E402
from swarm.transport.auth import RunSecret  # noqa: E402
from swarm.transport.sessions import session_config  # noqa: E402

pytestmark = pytest.mark.timeout(300)

STORE = get_typestore(Stores.ROS2_JAZZY)  # what a Jazzy peer has
SPEC = {"seed": 1, "map": {"kind": "building", "size": 30}, "robots": {"count": 2}, "stop": {"max_ticks": 120}}
GOAL = (26.25, 4.25)  # free, in robot 1's room, 2.9 m from where it starts (23.75, 2.75)
RUN_ID = "ros-test"
TIMES = ("wall_time_s", "setup_time_s")


def pose_msg(store: Any, stamp_ns: int, x: float, y: float, theta: float, frame: str = "map") -> Any:
    """A PoseStamped built from rosbags' types alone, as a ROS 2 driver would send it."""
    t = store.types
    stamp = t["builtin_interfaces/msg/Time"](sec=stamp_ns // 1_000_000_000, nanosec=stamp_ns % 1_000_000_000)
    return t["geometry_msgs/msg/PoseStamped"](
        header=t["std_msgs/msg/Header"](stamp=stamp, frame_id=frame),
        pose=t["geometry_msgs/msg/Pose"](position=t["geometry_msgs/msg/Point"](x=float(x), y=float(y), z=0.0),
                                         orientation=t["geometry_msgs/msg/Quaternion"](
                                             x=0.0, y=0.0, z=math.sin(theta / 2), w=math.cos(theta / 2))))


def free_endpoint() -> str:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return f"tcp/127.0.0.1:{s.getsockname()[1]}"


def key(topic: str, typename: str) -> str:
    """The rmw_zenoh key of ``topic`` for a Jazzy peer: only the design doc's format and rosbags' hash."""
    return f"0/{topic.lstrip('/')}/{typename.replace('/msg/', '::msg::dds_::')}_/{STORE.hash_rihs01(typename)}"


def wait_for_peer(session: zenoh.Session, seconds: float = 10.0) -> None:
    deadline = time.monotonic() + seconds
    while not list(session.info.peers_zid()):
        assert time.monotonic() < deadline, "no peer connected"
        time.sleep(0.01)
    time.sleep(0.3)  # the peers' declarations follow the connection


def summary(result: Any) -> dict[str, Any]:
    return {k: v for k, v in result.summary.items() if k not in TIMES}


class Driver(threading.Thread):
    """A ROS 2 node driving robot ``robot`` as an rmw_zenoh node would: subscribes to ``/clock`` and declares
    a ``goal_pose`` publisher (liveliness ``MP`` token, attachment with sequence numbers and its GID); for
    each ``/clock`` it puts what ``answer(stamp_ns)`` returns, as ``(payload, attachment)`` pairs (None:
    an honest goal for that stamp)."""

    def __init__(self, config: zenoh.Config, robot: int = 1,
                 answer: Callable[[int, Driver], list[tuple[bytes, bytes | None]]] | None = None) -> None:
        super().__init__(daemon=True)
        self.config, self.robot = config, robot
        self.answer = answer or (lambda stamp, driver: [driver.goal(stamp, *GOAL)])
        self.clocks: list[int] = []
        self.sequence = 0
        self.ready, self.stop = threading.Event(), threading.Event()
        self.connected = False

    def goal(self, stamp_ns: int, x: float, y: float) -> tuple[bytes, bytes]:
        self.sequence += 1
        payload = bytes(STORE.serialize_cdr(pose_msg(STORE, stamp_ns, x, y, 0.0), "geometry_msgs/msg/PoseStamped"))
        return payload, rmw.encode_attachment(self.sequence, time.time_ns(), self.gid)

    def run(self) -> None:
        with zenoh.open(self.config) as s:
            deadline = time.monotonic() + 5
            while not list(s.info.peers_zid()) and time.monotonic() < deadline:
                time.sleep(0.01)
            self.connected = bool(list(s.info.peers_zid()))
            topic, typename = f"/robot_{self.robot}/goal_pose", "geometry_msgs/msg/PoseStamped"
            pub = s.declare_publisher(key(topic, typename))
            token = (f"@ros2_lv/0/{s.zid()}/0/1/MP/%/%/driver/%robot_{self.robot}%goal_pose/"
                     f"geometry_msgs::msg::dds_::PoseStamped_/{STORE.hash_rihs01(typename)}/::,10:,:,:,,")
            self.gid = rmw.gid(token)

            def on_clock(sample: zenoh.Sample) -> None:
                clock = STORE.deserialize_cdr(sample.payload.to_bytes(), "rosgraph_msgs/msg/Clock").clock
                stamp = clock.sec * 1_000_000_000 + clock.nanosec
                self.clocks.append(stamp)
                for payload, attachment in self.answer(stamp, self):
                    pub.put(payload, attachment=attachment)

            s.declare_subscriber(key("/clock", "rosgraph_msgs/msg/Clock"), on_clock)  # before the token, as rclcpp
            s.declare_subscriber(key(f"/robot_{self.robot}/pose", "geometry_msgs/msg/PoseStamped"), lambda _s: None)
            alive = s.liveliness().declare_token(token)
            self.ready.set()
            self.stop.wait(120)
            alive.undeclare()


def driven_run(answer=None, user: str | None = None, password: str | None = None, timeout_s: float = 5.0,
               join_timeout_s: float = 30.0, spec: dict | None = None) -> tuple[Any, Driver]:
    """A run of :data:`SPEC` with robot 1 external, its node listening on loopback, and a :class:`Driver`
    (robot 1's own login unless ``user``/``password`` say otherwise)."""
    endpoint = free_endpoint()
    secret = RunSecret.generate()
    node, access = open_node(listen=[endpoint], secret=secret, run_id=RUN_ID, external=[1])
    token = secret.robot_token(RUN_ID, 1)
    driver = Driver(session_config(connect=[endpoint], user=user or token.user, password=password or token.password),
                    answer=answer)
    driver.start()
    driver.ready.wait(10)
    hosts: list[RosHost] = []

    def wrap(host):
        hosts.append(RosHost(host, node, external=[1], timeout_s=timeout_s, join_timeout_s=join_timeout_s))
        return hosts[0]

    try:
        t0 = time.monotonic()
        result = Simulation(spec or SPEC, transport=TransportOptions(wrap=wrap)).run()
    finally:
        driver.stop.set()
        driver.join(10)
    assert not access.folder.exists()  # the logins and configs are gone with the run
    if user is None:  # robot 1's driver was seen joining (its MP token), so the run did not wait it out
        assert hosts[0].joined == {1} and time.monotonic() - t0 < join_timeout_s
    return result, driver


# ---------------------------------------------------------------------------------------- watching ----
def test_clock_and_poses_reach_a_peer_that_knows_only_rmw_zenohs_key_format():
    router = zenoh.open(session_config(listen=[endpoint := free_endpoint()]))  # where rmw_zenohd would be
    clocks, poses, attachments = [], [], []

    def on_clock(sample: zenoh.Sample) -> None:
        clocks.append(STORE.deserialize_cdr(sample.payload.to_bytes(), "rosgraph_msgs/msg/Clock").clock)
        attachments.append(rmw.decode_attachment(sample.attachment.to_bytes()))

    router.declare_subscriber(key("/clock", "rosgraph_msgs/msg/Clock"), on_clock)
    router.declare_subscriber(key("/robot_1/pose", "geometry_msgs/msg/PoseStamped"), lambda s: poses.append(
        STORE.deserialize_cdr(s.payload.to_bytes(), "geometry_msgs/msg/PoseStamped")))
    node, access = open_node(connect=[endpoint])
    assert access is None
    wait_for_peer(node.session)
    tokens: list[str] = []

    def watch(host):
        wrapped = RosHost(host, node)
        original = wrapped.act

        def act(batch):  # query the graph mid-run, as `ros2 node list` / `ros2 topic list` would
            actions = original(batch)
            if batch.tick == 5:  # declarations reach the router asynchronously: ask until all four
                deadline = time.monotonic() + 5  # (node, /clock, two poses) have arrived
                while time.monotonic() < deadline:
                    found = [str(r.ok.key_expr) for r in router.liveliness().get("@ros2_lv/**", timeout=2) if r.ok]
                    if len(found) >= 4:
                        break
                    time.sleep(0.05)
                tokens.extend(found)
            return actions
        wrapped.act = act
        return wrapped

    try:
        sim = Simulation({**SPEC, "stop": {"max_ticks": 20}}, transport=TransportOptions(wrap=watch))
        start = sim.start_poses[1]
        result = sim.run()
        time.sleep(0.3)
    finally:
        router.close()
    assert [c.sec * 1_000_000_000 + c.nanosec for c in clocks] == [t * TICK_NS for t in range(20)]
    assert poses[0].header.frame_id == "map" and poses[0].header.stamp.sec == 0
    assert (poses[0].pose.position.x, poses[0].pose.position.y) == (start[0], start[1])
    assert math.isclose(2 * math.atan2(poses[0].pose.orientation.z, poses[0].pose.orientation.w), start[2])
    assert result.summary["ticks"] == 20
    # the attachment: sequence numbers from 1 by the publisher, one GID, wall-clock source timestamps
    assert [a.sequence for a in attachments] == list(range(1, 21))
    assert {a.gid for a in attachments} == {node.publishers["/clock"].gid}
    assert abs(attachments[-1].timestamp_ns - time.time_ns()) < 60e9
    # the liveliness tokens: the node and a publisher per topic, in the documented layout
    zid = node.zid
    hashes = {t: STORE.hash_rihs01(t) for t in ("rosgraph_msgs/msg/Clock", "geometry_msgs/msg/PoseStamped")}
    assert f"@ros2_lv/0/{zid}/0/0/NN/%/%/swarm" in tokens
    assert (f"@ros2_lv/0/{zid}/0/1/MP/%/%/swarm/%clock/rosgraph_msgs::msg::dds_::Clock_/"
            f"{hashes['rosgraph_msgs/msg/Clock']}/::,10:,:,:,,") in tokens
    assert (f"@ros2_lv/0/{zid}/0/3/MP/%/%/swarm/%robot_1%pose/geometry_msgs::msg::dds_::PoseStamped_/"
            f"{hashes['geometry_msgs/msg/PoseStamped']}/::,10:,:,:,,") in tokens
    assert node.publishers["/clock"].gid == rmw.gid(node.publishers["/clock"].token)


def test_a_latched_map_reaches_a_late_rmw_zenoh_subscriber_through_the_authenticated_listener():
    endpoint = free_endpoint()
    secret = RunSecret.generate()
    node, access = open_node(listen=[endpoint], secret=secret, run_id=RUN_ID)
    grid = STORE.types["nav_msgs/msg/OccupancyGrid"]
    meta = STORE.types["nav_msgs/msg/MapMetaData"]
    occupancy = grid(header=pose_msg(STORE, 0, 0, 0, 0).header,
                     info=meta(map_load_time=pose_msg(STORE, 0, 0, 0, 0).header.stamp, resolution=0.5, width=2,
                               height=1, origin=pose_msg(STORE, 0, 0, 0, 0).pose),
                     data=np.array([0, 100], dtype=np.int8))
    try:
        node.publish_tick([("/map", "nav_msgs/msg/OccupancyGrid", occupancy, 0)])
        login = json.loads(access.configs["viewer"].read_text())
        user = login["transport"]["auth"]["usrpwd"]
        assert login["connect"]["endpoints"] == [endpoint] and user["user"] == "viewer"
        with zenoh.open(session_config(connect=[endpoint], user=user["user"], password=user["password"])) as late:
            wait_for_peer(late)
            got, volatile = [], []
            late.declare_subscriber(key("/map", "nav_msgs/msg/OccupancyGrid"), lambda s: volatile.append(s))
            # rmw_zenoh's TRANSIENT_LOCAL subscription (rmw_subscription_data.cpp, SubscriptionData::init)
            ze.declare_advanced_subscriber(
                late, key("/map", "nav_msgs/msg/OccupancyGrid"), lambda s: got.append(
                    (STORE.deserialize_cdr(s.payload.to_bytes(), "nav_msgs/msg/OccupancyGrid"),
                     rmw.decode_attachment(s.attachment.to_bytes()))),
                history=ze.HistoryConfig(detect_late_publishers=True, max_samples=1),
                recovery=ze.RecoveryConfig(periodic_queries=None, heartbeat=True), subscriber_detection=True)
            deadline = time.monotonic() + 10
            while not got and time.monotonic() < deadline:
                time.sleep(0.05)
            tokens = [str(r.ok.key_expr) for r in late.liveliness().get("@ros2_lv/**", timeout=2) if r.ok]
    finally:
        node.close()
    assert len(got) == 1 and list(got[0][0].data) == [0, 100] and got[0][1].sequence == 1
    assert volatile == []  # published before it joined: only the cache query brings it
    hash_ = STORE.hash_rihs01("nav_msgs/msg/OccupancyGrid")
    assert (f"@ros2_lv/0/{node.zid}/0/1/MP/%/%/swarm/%map/nav_msgs::msg::dds_::OccupancyGrid_/{hash_}/"
            ":1:,1:,:,:,,") in tokens  # TRANSIENT_LOCAL, depth 1
    assert not access.folder.exists()


def test_ros2_without_external_robots_changes_no_result():
    plain = Simulation(SPEC).run()
    node, _ = open_node(connect=[free_endpoint()])  # nobody there: publishing into the void
    live = Simulation(SPEC, transport=TransportOptions(wrap=lambda host: RosHost(host, node))).run()
    assert summary(live) == summary(plain)


# ---------------------------------------------------------------------------------------- driving ----
def test_a_ros2_driver_takes_robot_1_to_its_goal_the_same_way_every_time():
    first, driver = driven_run()
    second, _ = driven_run()
    assert driver.connected and driver.clocks[:3] == [0, TICK_NS, 2 * TICK_NS]
    assert summary(first) == summary(second)
    x, y, _theta = first.summary["final_poses"][1]
    assert math.hypot(x - GOAL[0], y - GOAL[1]) < 0.5
    assert all(not any(counts) for counts in first.summary["acts"].values())
    # robot 0 explored on its own as it does without ROS: its algorithm was asked, robot 1's never
    assert first.summary["distance_m"][0] > 1.0


def test_twist_commands_drive_robot_1_and_a_silent_tick_keeps_the_last_one():
    def twist(stamp: int, driver: Driver) -> list[tuple[bytes, bytes | None]]:
        if stamp >= 10 * TICK_NS:  # silent from tick 10: the robot keeps going at the last Twist
            return []
        msg = STORE.types["geometry_msgs/msg/Twist"](linear=STORE.types["geometry_msgs/msg/Vector3"](x=0.5, y=0, z=0),
                                                     angular=STORE.types["geometry_msgs/msg/Vector3"](x=0, y=0, z=0))
        payload = bytes(STORE.serialize_cdr(msg, "geometry_msgs/msg/Twist"))
        driver.sequence += 1
        twist_key = key("/robot_1/cmd_vel", "geometry_msgs/msg/Twist")
        twist_session.put(twist_key, payload, attachment=rmw.encode_attachment(driver.sequence, 0, bytes(16)))
        return []

    secret = RunSecret.generate()
    endpoint = free_endpoint()
    node, _ = open_node(listen=[endpoint], secret=secret, run_id=RUN_ID, external=[1])
    token = secret.robot_token(RUN_ID, 1)
    twist_session = zenoh.open(session_config(connect=[endpoint], user=token.user, password=token.password))
    driver = Driver(session_config(connect=[endpoint], user=token.user, password=token.password), answer=twist)
    driver.start()
    driver.ready.wait(10)
    spec = {**SPEC, "stop": {"max_ticks": 14}}
    try:
        sim = Simulation(spec, transport=TransportOptions(wrap=lambda host: RosHost(host, node, external=[1],
                                                                                  timeout_s=1.0)))
        start = sim.start_poses[1]
        taken: list[Any] = []
        sim.observers = (lambda view: taken.append(view.actions[1]),)
        result = sim.run()
    finally:
        driver.stop.set()
        twist_session.close()
    assert taken == [Action(velocity=(0.5, 0.0))] * 14  # ticks 10-13 kept the last Twist
    x, y, _ = result.summary["final_poses"][1]
    assert math.hypot(x - start[0], y - start[1]) > 0.3


def test_malformed_commands_are_dropped_and_counted_and_change_nothing_else():
    def tampering(stamp: int, driver: Driver) -> list[tuple[bytes, bytes | None]]:
        honest = driver.goal(stamp, *GOAL)
        if stamp != 0:
            return [honest]
        nan_goal = driver.goal(0, math.nan, 1.0)
        other_frame = bytes(STORE.serialize_cdr(pose_msg(STORE, 0, 1.0, 1.0, 0.0, frame="odom"),
                                                "geometry_msgs/msg/PoseStamped"))
        return [(b"\x00\x01\x00\x00garbage", honest[1]),            # not a PoseStamped
                (honest[0], None),                                   # no attachment
                (honest[0], honest[1][:20]),                         # a short one
                (b"\x00\x01\x00\x00" + bytes(MAX_COMMAND_BYTES), honest[1]),  # too big
                (bytes(2 * MAX_MESSAGE_BYTES), honest[1]),          # too big for zenoh: dropped uncounted
                nan_goal, (other_frame, honest[1]),
                driver.goal(5 * TICK_NS, 1.0, 1.0),                  # for a tick not asked yet
                honest, driver.goal(0, 1.0, 1.0)]                    # the honest one, then a second for tick 0

    honest_run, _ = driven_run()
    tampered, _ = driven_run(answer=tampering)
    acts = tampered.summary["acts"]
    assert (acts["malformed"], acts["late"], acts["duplicate"]) == ([0, 6], [0, 1], [0, 1])
    assert {k: v for k, v in summary(tampered).items() if k != "acts"} == (
        {k: v for k, v in summary(honest_run).items() if k != "acts"})


def test_no_one_but_robot_1s_login_drives_robot_1():
    stranger = RunSecret.generate().robot_token(RUN_ID, 1)  # the right user name, another run's password
    spec = {**SPEC, "stop": {"max_ticks": 15}}
    sim = Simulation(spec)
    start = sim.start_poses[1]
    for user, password in ((stranger.user, stranger.password), ("viewer", None)):
        if password is None:  # the run's own viewer login: admitted, but it may not put on robot 1's topics
            result, driver = viewer_driven(spec)
        else:
            result, driver = driven_run(user=user, password=password, timeout_s=0.05, join_timeout_s=0.5,
                                        spec=spec)
            assert not driver.connected and driver.clocks == []
        x, y, _ = result.summary["final_poses"][1]
        assert math.hypot(x - start[0], y - start[1]) < 0.05
        assert all(not any(counts) for counts in result.summary["acts"].values())


def viewer_driven(spec: dict) -> tuple[Any, Driver]:
    """A run whose would-be driver logs in as the run's viewer and answers every /clock with a goal."""
    endpoint = free_endpoint()
    node, access = open_node(listen=[endpoint], secret=RunSecret.generate(), run_id=RUN_ID, external=[1])
    driver = Driver(zenoh.Config.from_file(str(access.configs["viewer"])))  # as rmw_zenoh reads it
    driver.start()
    driver.ready.wait(10)
    try:
        result = Simulation(spec, transport=TransportOptions(wrap=lambda host: RosHost(
            host, node, external=[1], timeout_s=0.05, join_timeout_s=5))).run()
    finally:
        driver.stop.set()
    assert driver.connected and len(driver.clocks) == spec["stop"]["max_ticks"]  # it watched every tick
    return result, driver


def test_access_policy_and_configs_name_only_what_each_login_may_do():
    access = RosAccess(RunSecret.generate(), RUN_ID, 3, [1, 4], ["tcp/127.0.0.1:7448"])
    try:
        policy = access.policy()
        assert policy["default_permission"] == "deny"
        puts = {r["id"]: r["key_exprs"] for r in policy["rules"] if r["messages"] == ["put"]}
        assert puts == {"drive-1": ["3/robot_1/goal_pose/**", "3/robot_1/cmd_vel/**"],
                        "drive-4": ["3/robot_4/goal_pose/**", "3/robot_4/cmd_vel/**"]}
        assert sorted(access.configs) == ["robot-1", "robot-4", "viewer"]
        assert {p.stat().st_mode & 0o777 for p in access.folder.iterdir()} == {0o600}
        assert access.folder.stat().st_mode & 0o777 == 0o700
    finally:
        access.remove()
    assert not access.folder.exists()
