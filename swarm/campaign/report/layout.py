"""Figure layouts: multi-panel explored-vs-time figures chosen by the researcher (``--figures FILE``).

The automatic report draws one figure per cell and compared dimension; a paper needs a few figures with
chosen panels side by side (the Minotaur paper's Figures 7-9). A layout file names them::

    [[figure]]
    name = "fig7"                                  # file stem: figures/fig7.png and figures/fig7.csv
    title = "Figure 7"
    columns = 2                                    # panels per row (default: all in one row)
    [[figure.panel]]
    compare = "radio"                              # one line per label of this dimension
    map = "building"
    size = 150
    robots = 16
    spawn = "together"
    algorithm = "Greed"
    [[figure.panel]]
    compare = "algorithm"
    map = "building"
    size = 150
    robots = 2
    radio = "materials"                            # spawn not given: runs of every spawn are pooled

Values are the grid labels of the campaign (as in the report's tables). A dimension a panel does not fix
is pooled: its runs are averaged together, and the panel's title says so. The layout lives outside the
campaign spec on purpose: presentation can change without changing the results folder's identity.
"""

from __future__ import annotations

import re
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from swarm.base.errors import InvalidInput

from ..text import clip, clip_list


PANEL_KEYS = ("compare", "title", "map", "size", "robots", "spawn", "algorithm", "radio", "comm", "transport")
COMPARABLE = ("algorithm", "radio", "comm", "spawn", "robots", "size", "map", "transport")


@dataclass(frozen=True)
class Panel:
    compare: str
    fixed: tuple[tuple[str, str], ...]
    title: str | None = None


@dataclass(frozen=True)
class FigureLayout:
    name: str
    title: str
    panels: tuple[Panel, ...]
    columns: int = 0
    """Panels per row; 0 = all in one row."""


def load_layout(path: str | Path) -> tuple[FigureLayout, ...]:
    from ..files import read_user_file

    return parse_layout(read_user_file(path, "--figures", "figure layout TOML"), str(path))


def parse_layout(text: str, source: str = "<string>") -> tuple[FigureLayout, ...]:
    """Parse and check the file's shape; labels are checked against a campaign by :func:`check_layout`."""
    try:
        raw = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InvalidInput("--figures", source, f"valid TOML ({clip(str(exc).splitlines()[0], 120)})") from None
    except RecursionError:
        raise InvalidInput("--figures", source, "valid TOML (nested too deeply)") from None
    extra = set(raw) - {"figure"}
    if extra:
        raise InvalidInput(clip(sorted(extra)[0]), "", "only [[figure]] tables in a figure layout")
    figures = raw.get("figure")
    if not isinstance(figures, list) or not figures:
        raise InvalidInput("figure", figures, "one or more [[figure]] tables")
    out, names = [], set()
    for i, fig in enumerate(figures):
        where = f"figure[{i}]"
        if not isinstance(fig, dict):
            raise InvalidInput(where, fig, "a [[figure]] table")
        unknown = set(fig) - {"name", "title", "columns", "panel"}
        if unknown:
            raise InvalidInput(f"{where}.{clip(sorted(unknown)[0])}", fig[sorted(unknown)[0]],
                               "name, title, columns and [[figure.panel]]")
        columns = fig.get("columns", 0)
        if isinstance(columns, bool) or not isinstance(columns, int) or not 0 <= columns <= 12:
            raise InvalidInput(f"{where}.columns", columns, "an integer from 1 to 12 (panels per row)")
        name = fig.get("name")
        if not isinstance(name, str) or not re.fullmatch(r"[A-Za-z0-9_-]+", name):
            raise InvalidInput(f"{where}.name", name, "a file-name stem of letters, digits, '-' and '_'")
        if name in names:
            raise InvalidInput(f"{where}.name", name, "a name no other figure uses")
        names.add(name)
        title = fig.get("title", name)
        if not isinstance(title, str):
            raise InvalidInput(f"{where}.title", title, "a string")
        panels = fig.get("panel")
        if not isinstance(panels, list) or not panels:
            raise InvalidInput(f"{where}.panel", panels, "one or more [[figure.panel]] tables")
        out.append(FigureLayout(name, title, tuple(_panel(p, f"{where}.panel[{j}]") for j, p in enumerate(panels)),
                                columns))
    return tuple(out)


def _panel(raw: Any, where: str) -> Panel:
    if not isinstance(raw, dict):
        raise InvalidInput(where, raw, "a table")
    from ..spec import is_axis

    for key in raw:
        if key not in PANEL_KEYS and not is_axis(key):
            raise InvalidInput(f"{where}.{clip(key)}", raw[key], ", ".join(PANEL_KEYS) + " or a grid axis "
                                                                 "(\"motion.model\", \"radio.sensitivity_dbm\", ...)")
    compare = raw.get("compare")
    if not isinstance(compare, str) or not (compare in COMPARABLE or is_axis(compare)):
        raise InvalidInput(f"{where}.compare", compare, ", ".join(COMPARABLE) + " or a grid axis")
    if compare in raw:
        raise InvalidInput(f"{where}.{compare}", raw[compare], f"nothing: '{compare}' is the compared dimension")
    title = raw.get("title")
    if title is not None and not isinstance(title, str):
        raise InvalidInput(f"{where}.title", title, "a string")
    fixed = []
    for key in [*PANEL_KEYS[2:], *sorted(k for k in raw if is_axis(k))]:
        if key in raw:
            value = raw[key]
            if isinstance(value, bool) or not isinstance(value, (str, int)):
                raise InvalidInput(f"{where}.{key}", value, "a grid label (string or integer)")
            fixed.append((key, str(value)))
    return Panel(compare, tuple(fixed), title)


def check_layout(layout: tuple[FigureLayout, ...], orders: dict[str, list[str]]) -> None:
    """Every fixed value and compared dimension must exist in the campaign (``orders``: labels per dim)."""
    for i, fig in enumerate(layout):
        for j, panel in enumerate(fig.panels):
            where = f"figure[{i}].panel[{j}]"
            if panel.compare not in orders:
                raise InvalidInput(f"{where}.compare", panel.compare, clip_list(orders))
            for dim, value in panel.fixed:
                if dim not in orders:
                    raise InvalidInput(f"{where}.{dim}", value, f"a dimension of this campaign ({clip_list(orders)})")
                if value not in orders[dim]:
                    raise InvalidInput(f"{where}.{dim}", value, clip_list(orders[dim]))
