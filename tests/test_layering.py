"""The package layering holds, checked on the parsed imports of every module (not a grep):

* ``maps <- radio <- swarm``: maps imports neither radio nor swarm, radio does not import swarm;
* ``algorithms -> swarm.api`` only: an algorithm imports nothing else of swarm, and nothing of maps or
  radio (the validators and InvalidInput come through swarm.api);
* the runtime (swarm outside swarm/api) never imports algorithms: it finds them through entry points.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def absolute_imports(path: Path) -> list[tuple[int, str]]:
    """(line, module) of every import in a file, relative imports resolved against its package."""
    package = list(path.relative_to(ROOT).with_suffix("").parts)
    if package[-1] == "__init__":
        package = package[:-1]
    else:
        package = package[:-1]
    out = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
        if isinstance(node, ast.Import):
            out += [(node.lineno, alias.name) for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package[: len(package) - node.level + 1]
                module = ".".join([*base, node.module] if node.module else base)
            else:
                module = node.module or ""
            out.append((node.lineno, module))
            out += [(node.lineno, f"{module}.{alias.name}") for alias in node.names if module in ("swarm", "maps")]
    return out


def files(package: str) -> list[Path]:
    return sorted((ROOT / package).rglob("*.py"))


def top(module: str) -> str:
    return module.split(".")[0]


def violations(package: str, allowed) -> list[str]:
    return [f"{p.relative_to(ROOT)}:{line}: {module}" for p in files(package) for line, module in absolute_imports(p)
            if not allowed(p, module)]


def test_relative_imports_are_resolved():
    """The checker itself: a relative import in algorithms/boa resolves inside algorithms."""
    mods = [m for _, m in absolute_imports(ROOT / "algorithms" / "boa" / "planner_plugin.py")]
    assert "algorithms.boa.pathplan" in mods and "swarm.api" in mods


def test_maps_and_radio_stay_below_swarm():
    assert violations("maps", lambda p, m: top(m) not in ("swarm", "radio", "algorithms")) == []
    assert violations("radio", lambda p, m: top(m) not in ("swarm", "algorithms")) == []


def plugin_allowed(path: Path, module: str) -> bool:
    """What an algorithm may import: anything but maps, radio and the parts of swarm outside swarm.api."""
    if top(module) in ("maps", "radio"):
        return False
    return top(module) != "swarm" or module == "swarm.api" or module.startswith("swarm.api.")


def test_algorithms_use_only_the_plugin_api():
    assert violations("algorithms", plugin_allowed) == []


def test_the_runtime_never_imports_algorithms():
    assert violations("swarm", lambda p, m: top(m) != "algorithms") == []


@pytest.mark.parametrize("bad, field", [("from swarm import grid", "swarm.grid"), ("import swarm.messages", "swarm.messages"),
                                        ("from maps.params import check_int", "maps.params")])
def test_the_check_catches_what_it_forbids(bad, field):
    """A module importing past the boundary is reported (so the tests above can fail)."""
    probe = ROOT / "algorithms" / "_layering_probe.py"
    probe.write_text(bad + "\n")
    try:
        found = violations("algorithms", plugin_allowed)
    finally:
        probe.unlink()
    assert any("_layering_probe.py" in v and field in v for v in found), found
