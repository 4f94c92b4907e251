"""The plugin API reference builds from the docstrings, and what it shows is complete and true.

``python -m pdoc swarm.api -o docs/api`` writes it (the HTML is built, not committed). Here pdoc builds it
into a temporary folder and any warning it emits fails; every public name of ``swarm.api`` and its
submodules must appear documented, functions with their real signature and a stated cost. The guide's
"Grid helpers" table must name every helper with its real signature.
"""

from __future__ import annotations

import html
import inspect
import re
import warnings
from pathlib import Path
from types import ModuleType

import pdoc
import pdoc.doc
import pdoc.doc_ast
import pytest

import swarm.api
import swarm.api.grid
import swarm.api.messages
import swarm.api.params
import swarm.base.params
import swarm.base.types
import swarm.grid.cspace

ROOT = Path(__file__).resolve().parents[1]
MODULES: tuple[ModuleType, ...] = (swarm.api, swarm.api.grid, swarm.api.messages, swarm.api.params)
CONSTANT_SOURCES: dict[str, ModuleType] = {"UNSEEN": swarm.base.types, "FREE": swarm.base.types,
                                           "SOLID": swarm.base.types, "CELL_M": swarm.base.types,
                                           "ROBOT_RADIUS_M": swarm.base.types, "OMIT_DEFAULT": swarm.base.params,
                                           "DEFAULT_MARGIN_M": swarm.grid.cspace}


def _text(page: str) -> str:
    """A page's visible text without any whitespace, to look for a signature however pdoc wraps it."""
    return re.sub(r"\s+", "", html.unescape(re.sub(r"<[^>]+>", "", page)))


def _page(out: Path, module: ModuleType) -> Path:
    return out.joinpath(*module.__name__.split(".")).with_suffix(".html")


@pytest.fixture(scope="module")
def reference(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The reference of ``swarm.api``, built as ``python -m pdoc swarm.api -o DIR`` does; no warning allowed."""
    out = tmp_path_factory.mktemp("api")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        pdoc.pdoc("swarm.api", output_directory=out)
    assert [str(w.message) for w in caught] == []
    return out


def test_the_reference_has_a_page_per_module(reference: Path) -> None:
    for module in MODULES:
        assert _page(reference, module).is_file(), module.__name__


@pytest.mark.parametrize("module", MODULES, ids=lambda m: m.__name__)
def test_every_public_name_is_documented_with_its_signature(reference: Path, module: ModuleType) -> None:
    page = _page(reference, module).read_text(encoding="utf-8")
    text = _text(page)
    docs = pdoc.doc.Module(module)
    for name in module.__all__:
        if isinstance(getattr(module, name), ModuleType):
            continue   # a submodule: its own page (test_the_reference_has_a_page_per_module)
        assert f'id="{name}"' in page, f"{module.__name__}.{name} is not in the reference"
        doc = docs.get(name)
        assert doc is not None and doc.docstring.strip(), f"{module.__name__}.{name} has no docstring"
        obj = getattr(module, name)
        if isinstance(doc, pdoc.doc.Function):
            real = inspect.signature(obj)
            assert list(doc.signature.parameters) == list(real.parameters), name
            assert re.sub(r"\s+", "", f"{name}{doc.signature}") in text, f"{name}'s signature is not shown"
            assert all(p.annotation is not inspect.Parameter.empty for p in real.parameters.values()), \
                f"{name} lacks type hints"


def test_every_grid_helper_states_its_cost() -> None:
    for name in swarm.api.grid.__all__:
        obj = getattr(swarm.api.grid, name)
        if callable(obj) and not inspect.isclass(obj):
            doc = inspect.getdoc(obj) or ""
            assert re.search(r"\bCost\b|\bO\(", doc), f"swarm.api.grid.{name}'s docstring states no cost"


def test_constant_docstrings_match_their_definitions() -> None:
    """Constants have no ``__doc__``: the facades repeat their docstrings for pdoc, kept equal here."""
    for module in MODULES:
        shown = pdoc.doc_ast.walk_tree(module).var_docstrings
        for name in module.__all__:
            if name in CONSTANT_SOURCES:
                assert shown.get(name) == pdoc.doc_ast.walk_tree(CONSTANT_SOURCES[name]).var_docstrings[name], \
                    f"{module.__name__}.{name}"


GUIDE = ROOT / "docs" / "plugins.md"


def guide_helpers() -> dict[str, str]:
    """The "Grid helpers" table of docs/plugins.md: helper name -> the signature it shows."""
    section = GUIDE.read_text(encoding="utf-8").split("## Grid helpers", 1)[1].split("\n## ", 1)[0]
    rows = re.findall(r"^\| `((\w+)\((.*?)\))` \|", section, flags=re.MULTILINE)
    return {name: shown for shown, name, _ in rows}


def test_the_guide_lists_every_grid_helper() -> None:
    helpers = {n for n in swarm.api.grid.__all__ if inspect.isfunction(inspect.unwrap(getattr(swarm.api.grid, n)))}
    assert set(guide_helpers()) == helpers


def test_the_guide_shows_the_real_signatures() -> None:
    for name, shown in guide_helpers().items():
        real = inspect.signature(getattr(swarm.api.grid, name))
        params = [p.strip() for p in shown[len(name) + 1:-1].split(",") if p.strip() not in ("", "*", "...")]
        expected = [p.name if p.default is inspect.Parameter.empty else f"{p.name}={p.default!r}"
                    for p in real.parameters.values()]
        assert params == expected, f"docs/plugins.md shows {shown}; the real signature is {name}{real}"
