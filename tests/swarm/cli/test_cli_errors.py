"""The command line's boundary (issue 31): every bad flag of ``swarm run`` and ``swarm agent`` ends in one
line ``swarm: error: ...`` naming the flag and exit status 2, before anything runs; and a fuzz over
their flags never ends in a traceback.
"""

from __future__ import annotations

import os
import string
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from swarm.cli import main

FUZZ_CASES = 250


def run_cli(argv: list[str], capsys) -> tuple[int, str, str]:
    code = main(argv)
    out, err = capsys.readouterr()
    return code, out, err


def assert_one_line_error(code: int, err: str, flag: str | None = None) -> None:
    assert code == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("swarm: error: "), err
    assert "Traceback" not in err and len(lines[0]) < 600
    if flag is not None:
        assert flag in lines[0], lines[0]


ZENOH = ["run", "--transport", "zenoh", "--size", "20", "--max-ticks", "2"]
AGENT = ["agent", "--connect", "tcp/127.0.0.1:9", "--run", "demo", "--robot", "1", "--timeout", "1"]


@pytest.mark.parametrize("argv,flag", [
    ([*ZENOH, "--listen", "garbage"], "--listen"),
    ([*ZENOH, "--listen", "tcp/999.1.1.1:1"], "--listen"),
    ([*ZENOH, "--listen", "tcp/127.0.0.1:99999"], "--listen"),
    ([*ZENOH, "--listen", "tcp/8.8.8.8:7447"], "--listen"),          # not an address of this machine
    ([*ZENOH, "--listen", "tcp/127.0.0.1:7447?x=1"], "--listen"),
    ([*ZENOH, "--run-id", "$*"], "--run-id"),
    ([*ZENOH, "--run-id", "a b?#"], "--run-id"),
    ([*ZENOH, "--run-id", "**"], "--run-id"),
    ([*ZENOH, "--run-id", "a/b"], "--run-id"),
    ([*ZENOH, "--agent-timeout", "nan"], "--agent-timeout"),
    ([*ZENOH, "--agent-timeout", "inf"], "--agent-timeout"),
    ([*ZENOH, "--agent-timeout", "1e300"], "--agent-timeout"),
    ([*ZENOH, "--agent-timeout", "-1"], "--agent-timeout"),
    ([*ZENOH, "--remote", "1"], "--listen"),                          # remote agents need an endpoint
    (["run", "--remote", "1", "--listen", "tcp/127.0.0.1:0"], "--remote"),  # ... and the zenoh transport
    ([*ZENOH, "--token-file", "t.token"], "--token-file"),           # a secret, but nobody to give it to
    (["run", "--max-ticks", "2", "--json", "/proc/version"], "--json"),
    (["run", "--max-ticks", "2", "--gif", "/nonexistent/x.gif"], "--gif"),
    (["run", "--max-ticks", "2", "--json", "/"], "--json"),
    (["run", "--max-ticks", "2", "--record", "/nonexistent/r.swr"], "--record"),
    (["agent", "--connect", "garbage", "--run", "demo", "--robot", "1"], "--connect"),
    (["agent", "--connect", "tcp/1.2.3:7447", "--run", "demo", "--robot", "1"], "--connect"),
    ([*AGENT[:4], "a b", *AGENT[5:]], "--run"),
    ([*AGENT[:4], "$*", *AGENT[5:]], "--run"),
    ([*AGENT[:-1], "nan"], "--timeout"),
    ([*AGENT[:-1], "inf"], "--timeout"),
    (AGENT, "--token"),                                               # no token at all
    ([*AGENT, "--token", "swarm-run-secret:abcd"], "--token"),
    ([*AGENT, "--token", "swarm-robot-token:other:1:" + "ab" * 32], "--token"),  # another run's token
    ([*AGENT, "--token", "x" * 20_000], "--token"),
])
def test_bad_run_and_agent_flags_are_one_line_errors(argv, flag, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("SWARM_TOKEN", raising=False)
    code, out, err = run_cli(argv, capsys)
    assert_one_line_error(code, err, flag)
    assert "x" * 100 not in err, "a long value is cut"
    assert not list(tmp_path.iterdir()), "nothing was written"


@pytest.fixture
def map_file(tmp_path) -> Path:
    from maps import generate
    from maps.io import save_npz

    return save_npz(generate("building", "30x20", 1), tmp_path / "b.npz")


@pytest.mark.parametrize("argv, message", [
    (["--map", "{file}", "--size", "200"], "--size: got '200'; allowed: no size with a map file"),
    (["--spec", "{spec}", "--size", "200"], "--size: got '200'; allowed: no size with a map file"),
    (["--map", "cavee"],
     "--map: got 'cavee'; allowed: a map kind (building | cave) or a map file (.npz, .pgm, .csv, .yaml, .yml)"),
    (["--map", "{folder}"], "--map: got '{folder}'; allowed: a map kind (building | cave) or a map file"),
])
def test_map_flags_that_do_not_fit_are_refused(argv, message, map_file, capsys):
    spec = map_file.with_suffix(".toml")
    spec.write_text(f'[map]\nkind = "file"\npath = "{map_file}"\n')
    fill = {"file": map_file, "spec": spec, "folder": map_file.parent}
    code, out, err = run_cli(["run", "--max-ticks", "2", *[a.format(**fill) for a in argv]], capsys)
    assert_one_line_error(code, err)
    assert err.startswith(f"swarm: error: {message.format(**fill)}"), err
    assert out == ""


def test_a_map_file_runs_without_a_size(map_file, capsys):
    code, _, err = run_cli(["run", "--max-ticks", "2", "--map", str(map_file)], capsys)
    assert code == 0, err


@pytest.mark.parametrize("sets, field", [
    (["--set", "motion.max_speed=-1"], "motion.max_speed"), (["--param", "recheck_ticks=-1"], "algorithm.params.recheck_ticks"),
    (["--set", "lidar.range_m=-1"], "lidar.range_m"), (["--set", "radio.per='x'"], "radio.per"),
    (["--set", "radio.shadowing_sigma_db=-1"], "radio.shadowing_sigma_db"),
    (["--set", "radio.materials.glass='x'"], "radio.materials.glass"),
    (["--map", "cave", "--map-param", "fill_percent=200"], "map.params.fill_percent"),
    (["--map-param", "bogus=1"], "map.params.bogus"),
])
def test_errors_name_the_full_field(sets, field, capsys):
    code, _, err = run_cli(["run", "--max-ticks", "2", *sets], capsys)
    assert_one_line_error(code, err)
    assert err.startswith(f"swarm: error: {field}: got "), err


def test_output_flags_are_checked_before_the_run(capsys, tmp_path):
    """A result that cannot be written is refused before the run is computed, not after it."""
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(0o500)
    try:
        if os.access(locked, os.W_OK) and os.geteuid() == 0:
            (tmp_path / "blocker").write_text("")  # root may write anywhere: use a path under a file instead
            target = tmp_path / "blocker" / "r.json"
        else:
            target = locked / "r.json"
        code, out, err = run_cli(["run", "--size", "20", "--max-ticks", "3", "--json", str(target)], capsys)
    finally:
        locked.chmod(0o700)
    assert_one_line_error(code, err, "--json")
    assert "stopped at tick" not in out, "no run was computed"


def test_an_existing_token_file_of_a_robot_is_not_a_run_secret(capsys, tmp_path):
    from swarm.transport.auth import RunSecret

    robot_file = tmp_path / "robot.token"
    robot_file.write_text(RunSecret.generate().robot_token("demo", 1).text())
    code, _, err = run_cli([*ZENOH, "--listen", "tcp/127.0.0.1:0", "--remote", "1", "--robots", "2",
                            "--token-file", str(robot_file)], capsys)
    assert_one_line_error(code, err, "--token-file")


# ------------------------------------------------------------------------------------------ fuzz ----
printable = st.text(alphabet=string.printable + "é€\u202e", max_size=60)
numbers = st.one_of(st.floats(allow_nan=True, allow_infinity=True).map(repr), st.integers(-10**30, 10**30).map(str))
RUN_FLAGS = {
    "--listen": printable, "--run-id": printable, "--agent-timeout": numbers | printable,
    "--remote": numbers | printable, "--robots": numbers | printable, "--size": numbers | printable,
    "--seed": numbers | printable, "--explored": numbers | printable, "--spawn": printable,
    "--transport": st.sampled_from(["zenoh", "inprocess", "udp"]) | printable, "--algorithm": printable,
    "--set": st.tuples(st.sampled_from(["lidar.range_m", "motion.max_speed", "comm.loss", "radio.model",
                                        "stop.max_ticks", "radio.tx_power_overrides.0", "nav.x", "x"]),
                       numbers | printable).map(lambda kv: f"{kv[0]}={kv[1]}"),
    "--param": st.tuples(st.sampled_from(["recheck_ticks", "exclude_ticks", "bogus"]), numbers | printable)
                 .map(lambda kv: f"{kv[0]}={kv[1]}"),
    "--map-param": st.tuples(st.sampled_from(["door_width", "exterior_material", "x"]), numbers | printable)
                     .map(lambda kv: f"{kv[0]}={kv[1]}"),
}


@settings(max_examples=FUZZ_CASES, deadline=None, suppress_health_check=[HealthCheck.too_slow,
                                                                         HealthCheck.function_scoped_fixture])
@given(flags=st.dictionaries(st.sampled_from(sorted(RUN_FLAGS)), st.none(), min_size=1, max_size=4), data=st.data())
def test_fuzzed_run_flags_end_in_a_spec_or_a_one_line_error(flags, data, capsys):
    """``swarm run --print-spec`` with random flag values: it prints the resolved spec as TOML (exit 0) or one line
    naming what is wrong (exit 2), never a traceback; the transport flags are checked there too."""
    argv = ["run", "--print-spec"]
    for flag in flags:
        argv += [flag, data.draw(RUN_FLAGS[flag])]
    try:
        code = main(argv)
    except SystemExit as exc:  # click never exits in standalone_mode=False, so this is a bug
        pytest.fail(f"SystemExit {exc.code} for {argv}")
    out, err = capsys.readouterr()
    if code == 0:  # a TOML run spec that reads back to itself
        import tomllib

        from swarm.sim.spec import RunSpec

        assert not err and RunSpec.from_mapping(tomllib.loads(out)).to_toml() == out
    else:
        assert_one_line_error(code, err)


@settings(max_examples=FUZZ_CASES // 2, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(connect=printable, run=printable, robot=numbers | printable, timeout=numbers | printable, token=printable)
def test_fuzzed_agent_flags_end_in_a_one_line_error(connect, run, robot, timeout, token, capsys):
    """``swarm agent`` with random flags: a one-line error or (if everything happens to be valid) an agent
    that finds no runtime; never a traceback. Valid-looking endpoints point at a closed loopback port."""
    if connect.startswith(("tcp/", "udp/", "tls/", "quic/", "ws/", "unixsock")):
        connect = "tcp/127.0.0.1:9"
    code = main(["agent", "--connect", connect, "--run", run, "--robot", robot, "--timeout", timeout,
                 "--token", token])
    _, err = capsys.readouterr()
    assert code in (1, 2), err
    if code == 2:
        assert_one_line_error(code, err)


def test_the_readme_remote_agent_commands_work(tmp_path):
    """The README's two commands, with --token-file: the agent waits for the file the runtime creates."""
    import subprocess
    import sys

    from tests.swarm.transport.test_transport import free_port

    endpoint = f"tcp/127.0.0.1:{free_port()}"
    token = tmp_path / "demo.token"
    runtime = subprocess.Popen([sys.executable, "-m", "swarm", "run", "--transport", "zenoh", "--listen", endpoint,
                                "--remote", "1", "--robots", "2", "--run-id", "demo", "--token-file", str(token),
                                "--size", "30", "--max-ticks", "30"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                               text=True)
    agent = subprocess.run([sys.executable, "-m", "swarm", "agent", "--connect", endpoint, "--run", "demo",
                            "--robot", "1", "--token-file", str(token)], capture_output=True, text=True, timeout=120)
    out, err = runtime.communicate(timeout=120)
    assert runtime.returncode == 0 and agent.returncode == 0, (err, agent.stderr)
    assert "stopped at tick 30" in out and "run ended" in agent.stderr
    assert oct(Path(token).stat().st_mode & 0o777) == "0o600"


def test_an_agent_that_finds_no_runtime_exits_1(capsys, monkeypatch):
    """Not a usage error (exit 2) and not success: the command's own exit status reaches the shell."""
    from swarm.transport.auth import RunSecret

    monkeypatch.setenv("SWARM_TOKEN", RunSecret.generate().text())
    code, _, err = run_cli(AGENT, capsys)
    assert code == 1 and "no runtime at tcp/127.0.0.1:9" in err
