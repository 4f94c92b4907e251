"""The package layering holds, checked on the parsed imports of every module (not a grep).

docs/design.md section 2 draws the layers. Bottom to top, a package may import only packages on lower
layers (and its own modules); two packages on one layer never import each other:

* ``swarm.base`` (errors, parameter validators, the robot vocabulary) and ``swarm.util`` sit under
  everything, ``maps`` and ``radio`` included;
* the runtime climbs one stage at a time (what robots know, the physical world, communication, navigation,
  transport) up to ``swarm.sim`` (one run), and the tools on top of a run (campaigns, recording, the
  learning environments, the viewer, the CLI) come last;
* ``algorithms`` imports ``swarm.api`` only, and nothing in ``swarm`` imports ``algorithms``.

Every import counts: at module level, inside functions and under ``TYPE_CHECKING``. No import circle may
exist between any two modules, inside a package or across packages.
"""

from __future__ import annotations

import ast
from pathlib import Path

import networkx as nx
import pytest

ROOT = Path(__file__).resolve().parents[1]

LAYERS: list[tuple[str, ...]] = [
    ("swarm.base", "swarm.util"),
    ("maps",),
    ("radio",),
    ("swarm.knowledge", "swarm.results", "swarm.draw"),
    ("swarm.grid", "swarm.world"),
    ("swarm.plugins", "swarm.comm"),
    ("swarm.navigation", "swarm.transport", "swarm.api"),
    ("swarm.sim",),
    ("swarm.testing", "swarm.record", "swarm.env", "swarm.campaign"),
    ("swarm.viewer", "swarm.ros2"),
    ("swarm.cli",),
    ("swarm",),  # the root package: names imported on first use, and ``python -m swarm``
]
"""Bottom to top. A module belongs to the longest package name here that prefixes its own."""

LAYER_OF = {package: level for level, packages in enumerate(LAYERS) for package in packages}
CHECKED = ("swarm", "maps", "radio", "algorithms")


def module_name(path: Path) -> str:
    parts = path.relative_to(ROOT).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def all_modules() -> dict[str, Path]:
    return {module_name(p): p for top in CHECKED for p in sorted((ROOT / top).rglob("*.py"))}


def imports_of(name: str, path: Path, known: set[str]) -> set[str]:
    """Every project module that ``name`` imports (relative imports resolved; ``from pkg import mod`` is
    ``pkg.mod`` when that is a module, else ``pkg``)."""
    package = name.split(".") if path.name == "__init__.py" else name.split(".")[:-1]
    found: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
        if isinstance(node, ast.Import):
            found |= {alias.name for alias in node.names}
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package[: len(package) - node.level + 1]
                module = ".".join([*base, node.module] if node.module else base)
            else:
                module = node.module or ""
            for alias in node.names:
                found.add(f"{module}.{alias.name}" if f"{module}.{alias.name}" in known else module)
    return {m for m in found if m.split(".")[0] in CHECKED and m != name}


def import_graph() -> dict[str, set[str]]:
    modules = all_modules()
    known = set(modules)
    return {name: imports_of(name, path, known) for name, path in modules.items()}


def package_of(module: str) -> str | None:
    parts = module.split(".")
    for k in range(len(parts), 0, -1):
        if ".".join(parts[:k]) in LAYER_OF:
            return ".".join(parts[:k])
    return None


def layer_violations(graph: dict[str, set[str]]) -> list[str]:
    """``importer -> imported`` for every import that does not go to a lower layer or stay in its package."""
    out = []
    for module, deps in sorted(graph.items()):
        if module.split(".")[0] == "algorithms":
            continue
        own = package_of(module)
        for dep in sorted(deps):
            if dep.split(".")[0] == "algorithms":
                out.append(f"{module} -> {dep} (the runtime finds algorithms by name)")
                continue
            target = package_of(dep)
            if target != own and LAYER_OF[target] >= LAYER_OF[own]:
                out.append(f"{module} -> {dep} ({own} on layer {LAYER_OF[own]}, {target} on {LAYER_OF[target]})")
    return out


def plugin_violations(graph: dict[str, set[str]]) -> list[str]:
    """An algorithm imports nothing of swarm outside ``swarm.api``, and nothing of maps or radio."""
    out = []
    for module, deps in sorted(graph.items()):
        if module.split(".")[0] != "algorithms":
            continue
        for dep in sorted(deps):
            top = dep.split(".")[0]
            if top in ("maps", "radio") or (top == "swarm" and not (dep == "swarm.api" or dep.startswith("swarm.api."))):
                out.append(f"{module} -> {dep}")
    return out


def circles(graph: dict[str, set[str]]) -> list[list[str]]:
    g = nx.DiGraph()
    g.add_nodes_from(graph)
    g.add_edges_from((m, d) for m, deps in graph.items() for d in deps if d in graph)
    return [sorted(c) for c in nx.strongly_connected_components(g) if len(c) > 1]


@pytest.fixture(scope="module")
def graph() -> dict[str, set[str]]:
    return import_graph()


def test_every_module_has_a_layer(graph):
    """A new package of swarm must be placed on a layer (else it would escape the check)."""
    unplaced = [m for m in graph if m.split(".")[0] != "algorithms" and package_of(m) is None]
    assert unplaced == []
    assert all(p in graph for p in LAYER_OF), [p for p in LAYER_OF if p not in graph]


def test_imports_only_go_down(graph):
    assert layer_violations(graph) == []


def test_algorithms_use_only_the_plugin_api(graph):
    assert plugin_violations(graph) == []


def test_no_import_circle(graph):
    assert circles(graph) == []


def test_relative_imports_are_resolved(graph):
    """The parser itself: a relative import in algorithms/boa resolves inside algorithms, one in a swarm
    package to the module it names."""
    assert {"algorithms.boa.pathplan", "swarm.api"} <= graph["algorithms.boa.planner_plugin"]
    assert "swarm.knowledge.cellcodec" in graph["swarm.knowledge.packed"]


@pytest.mark.parametrize("module, dep", [
    ("swarm.knowledge.probe", "swarm.sim.loop"),     # a lower package reaching up
    ("swarm.comm.probe", "swarm.plugins.explorers"),  # across one layer
    ("maps.probe", "radio.models"),
    ("radio.probe", "swarm.world.physics"),
    ("swarm.base.probe", "maps"),
    ("swarm.grid.probe", "algorithms.frontier"),
])
def test_the_layer_check_catches_what_it_forbids(graph, module, dep):
    probe = {**graph, module: {dep}}
    assert any(v.startswith(f"{module} -> {dep}") for v in layer_violations(probe))


@pytest.mark.parametrize("dep", ["swarm.grid", "swarm.comm.messages", "swarm.base.params", "radio"])
def test_the_plugin_check_catches_what_it_forbids(graph, dep):
    probe = {**graph, "algorithms.probe": {dep, "swarm.api"}}
    assert plugin_violations(probe) == [f"algorithms.probe -> {dep}"]


def test_the_circle_check_catches_a_circle(graph):
    probe = {**graph, "maps.model": graph["maps.model"] | {"maps.io"}}
    assert any({"maps.io", "maps.model"} <= set(circle) for circle in circles(probe))  # with what joins them
