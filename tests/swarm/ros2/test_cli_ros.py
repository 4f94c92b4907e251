"""``swarm run --ros2``: its flags' one-line errors, and a ROS 2 driver that logs in with the zenoh config the
run prints (read by zenoh as rmw_zenoh reads ``ZENOH_SESSION_CONFIG_URI``) drives robot 1 to its goal."""

from __future__ import annotations

import json
import math
import subprocess
import sys
import time

import numpy as np
import pytest

pytest.importorskip("rosbags")

import zenoh  # noqa: E402

from swarm.cli import main  # noqa: E402
from .test_live import GOAL, STORE, Driver, free_endpoint, key  # noqa: E402

pytestmark = pytest.mark.timeout(300)
RUN = ["run", "--size", "20", "--robots", "2", "--max-ticks", "2"]


@pytest.mark.parametrize("argv,flag", [
    ([*RUN, "--ros-external", "1"], "--ros-external"),                                  # without --ros2
    ([*RUN, "--ros2", "--ros-external", "1"], "--ros-listen"),                          # needs a login endpoint
    ([*RUN, "--ros2", "--ros-external", "2", "--ros-listen", "tcp/127.0.0.1:7448"], "--ros-external"),
    ([*RUN, "--ros2", "--ros-listen", "tcp/127.0.0.1:7448", "--ros-connect", "tcp/127.0.0.1:7447"], "--ros-connect"),
    ([*RUN, "--ros2", "--ros-listen", "tcp/127.0.0.1:0"], "--ros-listen"),               # the configs need its port
    ([*RUN, "--ros2", "--ros-connect", "garbage"], "--ros-connect"),
    ([*RUN, "--ros2", "--ros-listen", "tcp/8.8.8.8:7448"], "--ros-listen"),              # not this machine's
])
def test_bad_ros_flags_are_one_line_errors(argv, flag, capsys):
    code = main(argv)
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and err[0].startswith("swarm: error: ") and flag in err[0], err


def test_a_driver_with_the_printed_config_drives_robot_1(tmp_path):
    endpoint = free_endpoint()
    out = tmp_path / "run.json"
    runtime = subprocess.Popen([sys.executable, "-m", "swarm", "run", "--seed", "1", "--size", "30", "--robots", "2",
                                "--max-ticks", "120", "--ros2", "--ros-listen", endpoint, "--ros-external", "1",
                                "--json", str(out)], stderr=subprocess.PIPE, text=True)
    driver = viewer = None
    heard: dict[str, list] = {"/robot_0/scan": [], "/robot_1/map": [], "/tf": []}
    types = {"/robot_0/scan": "sensor_msgs/msg/LaserScan", "/robot_1/map": "nav_msgs/msg/OccupancyGrid",
             "/tf": "tf2_msgs/msg/TFMessage"}
    try:
        config = watch = None
        deadline = time.monotonic() + 120
        while config is None and time.monotonic() < deadline:
            line = runtime.stderr.readline()
            assert line, "the run ended before printing robot 1's config"
            if "watch with ZENOH_SESSION_CONFIG_URI=" in line:
                watch = line.rsplit("ZENOH_SESSION_CONFIG_URI=", 1)[1].strip()
            if line.startswith("waiting for: a ROS 2 node driving robot 1"):
                config = line.rsplit("ZENOH_SESSION_CONFIG_URI=", 1)[1].strip()
        viewer = zenoh.open(zenoh.Config.from_file(watch))   # a viewer such as RViz, with the printed login
        for topic, typename in types.items():
            viewer.declare_subscriber(key(topic, typename),
                                      lambda sample, t=topic: heard[t].append(sample.payload.to_bytes()))
        time.sleep(0.5)
        driver = Driver(zenoh.Config.from_file(config))
        driver.start()
        assert runtime.wait(120) == 0, runtime.stderr.read()
    finally:
        if driver is not None:
            driver.stop.set()
        if runtime.poll() is None:
            runtime.kill()
        if viewer is not None:
            viewer.close()
    summary = json.loads(out.read_text())["summary"]
    x, y, _ = summary["final_poses"][1]
    assert driver.connected and math.hypot(x - GOAL[0], y - GOAL[1]) < 0.5
    # the MCAP export's topics go out live too, decoded by rosbags
    scans = [STORE.deserialize_cdr(b, types["/robot_0/scan"]) for b in heard["/robot_0/scan"]]
    assert len(scans) >= 100 and scans[0].header.frame_id == "robot_0/base_link"
    assert len(scans[0].ranges) > 10 and (np.isfinite(scans[0].ranges) | np.isinf(scans[0].ranges)).all()
    grids = [STORE.deserialize_cdr(b, types["/robot_1/map"]) for b in heard["/robot_1/map"]]
    assert grids and set(np.unique(grids[-1].data)) <= {-1, 0, 100} and (grids[-1].data == 0).any()
    tf = STORE.deserialize_cdr(heard["/tf"][-1], types["/tf"])
    assert {t.child_frame_id for t in tf.transforms} == {"robot_0/base_link", "robot_1/base_link"}
