"""README examples stay true: every TOML block parses and validates against the code it documents, and every
command of its code blocks runs as written, in README order, in one scratch folder.

A command too costly to run here is either shrunk by flags it takes (``SHRINK``: e.g. ``--max-ticks``) or
skipped with the reason (``SKIP``); both tables must name commands the README still has, so neither can
hide a command that changed. Fixtures stand in for the files a reader would have: ``grid.toml`` is the
README's campaign spec cut to 8 runs of 80 ticks, ``run.toml`` the README's run spec, and a tiny
``floor.png`` with its legend, and ``plan.json``, a hand-made HouseExpo plan from ``examples/plans/``.
"""

from __future__ import annotations

import os
import re
import shlex
import socket
import subprocess
import sys
import tomllib
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
import tomli_w

from maps.io import check_legend
from radio import config_from_mapping
from swarm.campaign import parse_campaign
from swarm.sim.spec import RunSpec

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text()


@dataclass(frozen=True)
class Block:
    line: int
    lang: str
    lines: tuple[str, ...]


def fenced_blocks(text: str) -> list[Block]:
    """Every fenced code block: its first line number, its language tag and its lines."""
    lines = text.splitlines()
    out, i = [], 0
    while i < len(lines):
        m = re.match(r"^```(\w*)\s*$", lines[i])
        if not m:
            i += 1
            continue
        j = i + 1
        while not lines[j].startswith("```"):
            j += 1
        out.append(Block(i + 2, m.group(1), tuple(lines[i + 1:j])))
        i = j + 1
    return out


BLOCKS = fenced_blocks(README)
TOML_BLOCKS = ["\n".join(b.lines) + "\n" for b in BLOCKS if b.lang == "toml"]


@dataclass(frozen=True)
class Command:
    """One command of a bash block (``a && b`` is two), or a ``$ ...`` line of a console block with the
    output shown under it."""

    text: str
    line: int
    background: bool = False
    expected: tuple[str, ...] | None = None

    @property
    def id(self) -> str:
        return f"L{self.line}: {self.text[:60]}"


def _strip_comment(line: str) -> str:
    """The line without a trailing ``# comment`` (a ``#`` outside quotes after whitespace)."""
    quote = None
    for k, ch in enumerate(line):
        if ch in "'\"" and quote in (None, ch):
            quote = None if quote else ch
        elif ch == "#" and quote is None and (k == 0 or line[k - 1].isspace()):
            return line[:k].rstrip()
    return line.rstrip()


def commands() -> list[Command]:
    out = []
    for block in BLOCKS:
        if block.lang == "bash":
            for k, raw in enumerate(block.lines):
                text = _strip_comment(raw)
                if not text:
                    continue
                background = text.endswith("&") and not text.endswith("&&")
                for part in text.rstrip("&").split("&&"):
                    out.append(Command(part.strip(), block.line + k, background))
        elif block.lang == "" and block.lines and block.lines[0].startswith("$ "):
            out.append(Command(block.lines[0][2:].strip(), block.line, expected=block.lines[1:]))
    return out


COMMANDS = commands()
SKIP = {
    "pip install .": "installs swarm; benchmarks/speed/bench_first_run.py times it from a fresh clone",
    "pip install '.[test]'": "installs the test extras (present where this runs)",
    "pytest": "the test suite itself",
    'sbatch --array=1-8 --wrap "swarm campaign run grid.toml -o results/grid --shard slurm"':
        "needs SLURM; --shard slurm with SLURM's variables: tests/swarm/campaign/test_first_run.py",
}
"""Commands not run, and why."""
SHRINK = {
    "swarm campaign run": ["--shard", "0/24", "--inline"],  # 2 of the quick campaign's 48 runs, and its report
    "swarm run --map cave --size 100 --robots 8 --spawn random --seed 3 --json r.json --gif r.gif":
        ["--max-ticks", "150"],
    "swarm run --spec run.toml --robots 16 --set lidar.range_m=4": ["--max-ticks", "150"],
    "swarm run --set motion.max_speed=3 --set motion.max_turn_rate=4": ["--max-ticks", "300"],
    "swarm run --transport zenoh --listen tcp/127.0.0.1:7447 --remote 1 --robots 2 --run-id demo "
    "--token-file demo.token": ["--max-ticks", "100"],
    "swarm run --map building --size 100 --robots 8 --algorithm minotaur --record run.swr": ["--max-ticks", "150"],
    "swarm view run.swr": ["--no-open"],
}
"""Commands run with these flags added (a shorter run, no browser)."""
PYTHON_SKIP: dict[str, str] = {}


def test_every_toml_block_is_valid_for_what_it_configures():
    assert TOML_BLOCKS
    for block in TOML_BLOCKS:
        data = tomllib.loads(block)
        if "colours" in data:
            check_legend(data)
        elif set(data) == {"radio"}:
            config_from_mapping(data["radio"])
        elif "campaign" in data:
            assert parse_campaign(block).runs()
        elif "project" in data:
            assert "swarm.algorithms" in data["project"]["entry-points"]
        else:
            RunSpec.from_mapping(data)


def test_quick_start_has_exactly_the_two_marked_commands():
    for marker in ("<!-- ci:main -->", "<!-- ci:test -->"):
        after = README.split(marker, 1)[1]
        block = re.match(r"\s*```bash\n(.*?)```", after, re.S)
        assert block and len(block.group(1).strip().splitlines()) == 1


def test_the_skip_and_shrink_tables_name_commands_the_readme_has():
    texts = {c.text for c in COMMANDS}
    assert set(SKIP) <= texts, set(SKIP) - texts
    assert set(SHRINK) <= texts, set(SHRINK) - texts
    python = ["\n".join(b.lines) for b in BLOCKS if b.lang == "python"]
    assert all(any(code.startswith(k) for code in python) for k in PYTHON_SKIP)
    assert sum(c.expected is not None for c in COMMANDS) >= 1, "the console example of an error"
    assert len(COMMANDS) - len(SKIP) >= 25, "most commands run"


# ------------------------------------------------------------------------------- running them ----
def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture(scope="module")
def workspace(tmp_path_factory):
    """A scratch folder holding what the README's commands expect to find."""
    ws = tmp_path_factory.mktemp("readme")
    campaign = next(tomllib.loads(b) for b in TOML_BLOCKS if "campaign" in tomllib.loads(b))
    campaign["campaign"]["replicates"] = 1
    grid = campaign["grid"]
    grid.update(size=[20], spawn=grid["spawn"][:1], radio=grid["radio"][:2], robots=[2])
    grid.pop("comm", None)
    campaign["stop"] = {"explored": 0.9, "max_ticks": 80}
    (ws / "grid.toml").write_text(tomli_w.dumps(campaign))
    run_spec = next(b for b in TOML_BLOCKS if "robots" in tomllib.loads(b) and "campaign" not in tomllib.loads(b))
    (ws / "run.toml").write_text(run_spec)
    (ws / "legend.toml").write_text('metres_per_pixel = 0.5\n[colours]\n"#ffffff" = "free"\n"#000000" = "concrete"\n')
    from PIL import Image

    floor = np.full((40, 40, 3), 255, np.uint8)
    floor[:2], floor[-2:], floor[:, :2], floor[:, -2:] = 0, 0, 0, 0
    Image.fromarray(floor).save(ws / "floor.png")
    (ws / "plan.json").write_bytes((ROOT / "examples" / "plans" / "handmade_two_rooms.json").read_bytes())
    return ws


def _argv(command: Command, port: int) -> list[str]:
    argv = shlex.split(command.text.replace("7447", str(port)))
    return argv + SHRINK.get(command.text, [])


def _env(ws: Path) -> dict[str, str]:
    return {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]),
            "SWARM_CACHE_DIR": str(ws / "cache"), "DISPLAY": ""}


_background: list[subprocess.Popen] = []
PORT = _free_port()


@pytest.mark.parametrize("command", COMMANDS, ids=[c.id for c in COMMANDS])
def test_readme_command_runs_as_written(command, workspace, monkeypatch, capsys):
    if command.text in SKIP:
        pytest.skip(SKIP[command.text])
    monkeypatch.chdir(workspace)
    monkeypatch.setenv("SWARM_CACHE_DIR", str(workspace / "cache"))
    monkeypatch.setenv("DISPLAY", "")
    argv = _argv(command, PORT)
    assert argv[0] == "swarm", f"a README command that is not swarm's needs a SKIP entry: {command.text}"
    redirect = None
    if ">" in argv:
        at = argv.index(">")
        argv, redirect = argv[:at], argv[at + 1]
    if command.background or _background:  # the zenoh pair: two real processes on loopback
        proc = subprocess.Popen([sys.executable, "-m", "swarm", *argv[1:]], cwd=workspace, env=_env(workspace),
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        if command.background:
            _background.append(proc)
            return
        procs = [_background.pop(), proc]
        for p in procs:
            out, err = p.communicate(timeout=120)
            assert p.returncode == 0, f"{command.text}: exit {p.returncode}\n{err[-2000:]}"
        return
    from swarm.cli import main

    status = main(argv[1:])
    out, err = capsys.readouterr()
    if command.expected is not None:
        assert status == 2 and err.strip().splitlines() == list(command.expected), err
        return
    assert status == 0, f"{command.text}: exit {status}\n{err[-2000:]}"
    if redirect is not None:
        Path(redirect).write_text(out)


PYTHON_BLOCKS = [b for b in BLOCKS if b.lang == "python"]


@pytest.mark.parametrize("block", PYTHON_BLOCKS, ids=[f"L{b.line}" for b in PYTHON_BLOCKS])
def test_readme_python_runs_as_written(block, workspace, monkeypatch):
    code = "\n".join(block.lines)
    for start, reason in PYTHON_SKIP.items():
        if code.startswith(start):
            pytest.skip(reason)
    monkeypatch.chdir(workspace)
    exec(compile(code, f"README.md:{block.line}", "exec"), {})
