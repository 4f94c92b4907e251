"""A plugin written from docs/plugins.md alone works: the guide's example code, run as a user would run it.

The two code blocks the guide marks ``<!-- walkthrough: ... -->`` (the goal-from-a-frontier helper and the
``Hopper`` explorer) are written into a module in a temporary folder, as the guide says to; that module
must import nothing of swarm but ``swarm.api``, explore a small building through ``swarm.run`` and pass
``swarm.testing.check_explorer``. A change to the API or the guide that breaks the example fails here.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

import swarm
from swarm.testing import check_explorer

GUIDE = Path(__file__).resolve().parents[1] / "docs" / "plugins.md"
BLOCKS = ("goal_for_cluster", "explorer")


def guide_block(marker: str) -> str:
    """The Python block that follows ``<!-- walkthrough: marker -->`` in the guide."""
    found = re.search(rf"<!-- walkthrough: {marker} -->\n```python\n(.*?)\n```", GUIDE.read_text(encoding="utf-8"),
                      flags=re.DOTALL)
    assert found, f"docs/plugins.md has no python block marked 'walkthrough: {marker}'"
    return found.group(1)


@pytest.fixture
def explorer_module(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> str:
    """The guide's example as the module ``guide_explorer`` on sys.path; its ``module:Class`` name."""
    (tmp_path / "guide_explorer.py").write_text("\n\n".join(guide_block(m) for m in BLOCKS) + "\n", encoding="utf-8")
    monkeypatch.syspath_prepend(str(tmp_path))
    return "guide_explorer:Hopper"


def test_the_example_imports_only_swarm_api(explorer_module: str, tmp_path: Path) -> None:
    tree = ast.parse((tmp_path / "guide_explorer.py").read_text(encoding="utf-8"))
    swarm_imports = {node.module for node in ast.walk(tree) if isinstance(node, ast.ImportFrom)
                     and node.module and node.module.split(".")[0] == "swarm"}
    swarm_imports |= {alias.name for node in ast.walk(tree) if isinstance(node, ast.Import)
                      for alias in node.names if alias.name.split(".")[0] == "swarm"}
    assert swarm_imports and all(m == "swarm.api" or m.startswith("swarm.api.") for m in swarm_imports), swarm_imports


def test_the_example_explores_through_swarm_run(explorer_module: str) -> None:
    result = swarm.run({"map": {"kind": "building", "size": 20}, "seed": 1}, robots=2, algorithm=explorer_module,
                       max_ticks=1500)
    assert result.summary["explored"] > 0.9, result.one_line()


def test_the_example_passes_the_checker(explorer_module: str) -> None:
    report = check_explorer(explorer_module)
    assert report.checks[0] == "contract" and "transports" in report.checks
