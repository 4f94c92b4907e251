"""``swarm run --ros2``: its flags' one-line errors, and a ROS 2 driver that logs in with the zenoh config the
run prints (read by zenoh as rmw_zenoh reads ``ZENOH_SESSION_CONFIG_URI``) drives robot 1 to its goal."""

from __future__ import annotations

import json
import math
import subprocess
import sys
import time

import pytest

pytest.importorskip("rosbags")

import zenoh  # noqa: E402

from swarm.cli import main  # noqa: E402
from .test_live import GOAL, Driver, free_endpoint  # noqa: E402

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
    driver = None
    try:
        config = None
        deadline = time.monotonic() + 120
        while config is None and time.monotonic() < deadline:
            line = runtime.stderr.readline()
            assert line, "the run ended before printing robot 1's config"
            if line.startswith("waiting for: a ROS 2 node driving robot 1"):
                config = line.rsplit("ZENOH_SESSION_CONFIG_URI=", 1)[1].strip()
        driver = Driver(zenoh.Config.from_file(config))
        driver.start()
        assert runtime.wait(120) == 0, runtime.stderr.read()
    finally:
        if driver is not None:
            driver.stop.set()
        if runtime.poll() is None:
            runtime.kill()
    summary = json.loads(out.read_text())["summary"]
    x, y, _ = summary["final_poses"][1]
    assert driver.connected and math.hypot(x - GOAL[0], y - GOAL[1]) < 0.5
