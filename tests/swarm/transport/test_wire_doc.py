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

from swarm.sim.loop import Simulation, TransportOptions
from swarm.transport.auth import RunSecret

DOC = Path(__file__).resolve().parents[3] / "docs" / "wire-format.md"


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
    secret = RunSecret.generate()
    sim = Simulation(spec, transport=TransportOptions(listen=(endpoint,), remote=(1,), timeout_s=20, run_id=run_id,
                                                      secret=secret))
    box = {}
    t = threading.Thread(target=lambda: box.setdefault("r", sim.run()))
    t.start()
    agent = subprocess.Popen([sys.executable, str(script), endpoint, run_id, "1", secret.robot_token(run_id, 1).text()],
                             stderr=subprocess.PIPE, text=True)
    t.join(120)
    agent.wait(30)
    r = box["r"]
    assert agent.returncode == 0, agent.stderr.read()
    assert r.summary["failed_robots"] == [] and r.summary["acts"] == {k: [0, 0] for k in ("malformed", "refused", "late", "duplicate")}
    assert r.summary["distance_m"][1] > 1.0, "the documented agent drove robot 1 forward"


def test_documented_layouts_match_the_code():
    """Version, struct layouts, sizes, offsets and nav states in the doc are the ones wire.py uses."""
    from swarm.transport.wire import NAV_STATES, NEIGHBOUR, OBS_STATE, WIRE_VERSION

    doc = DOC.read_text()
    assert f"# The agent wire format (version {WIRE_VERSION})" in doc and f"`version = {WIRE_VERSION}`" in doc
    for kind in ("reset", "obs", "act"):
        assert f'`["{kind}", {WIRE_VERSION}, ' in doc
    assert f"`state` is {OBS_STATE.size} bytes" in doc and f"format `{OBS_STATE.format}`" in doc
    assert f"{NEIGHBOUR.size} bytes each" in doc and f"(`{NEIGHBOUR.format}`)" in doc
    assert f"an index into `{' '.join(NAV_STATES)}`" in doc
    rows = re.findall(r"^  \| (\d+) \| (\w+)(?: x (\d))? \|", doc, re.M)  # the state table: offset, type, count
    codes, at, layout = {"float64": ("d", 8), "uint32": ("I", 4), "uint8": ("B", 1)}, 0, "<"
    for offset, kind, count in rows:
        assert int(offset) == at, f"documented offset {offset}, the fields before it take {at} bytes"
        code, size = codes[kind]
        layout += int(count or 1) * code
        at += int(count or 1) * size
    expand = lambda fmt: re.sub(r"(\d+)(\w)", lambda m: int(m.group(1)) * m.group(2), fmt)
    assert layout == expand(OBS_STATE.format) and at == OBS_STATE.size
