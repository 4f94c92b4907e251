"""The minimal agent printed in docs/wire-format.md really drives a robot (no swarm imports on its side)."""

from __future__ import annotations

import re
import socket
import subprocess
import sys
import threading
import uuid
from pathlib import Path

import pytest

from swarm.simulation import Simulation, TransportOptions

DOC = Path(__file__).resolve().parents[2] / "docs" / "wire-format.md"


@pytest.mark.timeout(180)
def test_documented_agent_drives_its_robot(tmp_path):
    code = re.search(r"## A minimal agent.*?```python\n(.*?)```", DOC.read_text(), re.S).group(1)
    assert "import swarm" not in code and "from swarm" not in code
    script = tmp_path / "agent.py"
    script.write_text(code)
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        endpoint = f"tcp/127.0.0.1:{s.getsockname()[1]}"
    run_id = f"doc-{uuid.uuid4().hex[:8]}"
    spec = {"seed": 1, "map": {"kind": "building", "size": 30}, "robots": {"count": 2}, "transport": "zenoh",
            "stop": {"max_ticks": 40}}
    sim = Simulation(spec, transport=TransportOptions(listen=(endpoint,), remote=(1,), timeout_s=20, run_id=run_id))
    box = {}
    t = threading.Thread(target=lambda: box.setdefault("r", sim.run()))
    t.start()
    agent = subprocess.Popen([sys.executable, str(script), endpoint, run_id, "1"], stderr=subprocess.PIPE, text=True)
    t.join(120)
    agent.wait(30)
    r = box["r"]
    assert agent.returncode == 0, agent.stderr.read()
    assert r.summary["failed_robots"] == [] and r.summary["messages"]["malformed_from_agents"] == 0
    assert r.summary["distance_m"][1] > 1.0, "the documented agent drove robot 1 forward"
