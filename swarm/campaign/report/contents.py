"""What a report holds: the tables, figures and findings :func:`.build.build_report` computes and
:func:`.readme.render` writes out (kept apart so the two never import each other)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import pandas as pd

from . import comm, tables
from .load import CampaignData


@dataclass
class FigureSet:
    """One figure cell: its title and the files drawn for it."""

    compare: str | None
    title: str
    curves: str
    cactus: str
    data: str


@dataclass
class LayoutFigure:
    """A figure drawn from a layout file (``--figures``)."""

    name: str
    title: str
    path: str
    data: str
    panels: list[str]


@dataclass
class PairedSection:
    """One table of paired statistics: per cell for one dimension, or every cell pooled (``dim`` None)."""

    dim: str | None
    name: str
    table: tables.Table
    caption: str
    family: str
    """The caption's last sentence: which comparisons Holm's correction runs over."""
    rows: int
    tested: int
    nominal: int
    """Rows with p < 0.05 before correction."""
    holm: int
    """Rows with Holm's p < 0.05."""
    single_robot_cells: int = 0
    """1-robot cells left out (radio, comm, transport)."""


@dataclass
class CommSection:
    """The communication section (:mod:`.comm`): tables, findings and figures."""

    available: bool
    talk: list[str] = field(default_factory=list)
    """The compared talk-only dimensions (radio, comm, axes) that vary."""
    cells: tables.Table | None = None
    cell_rows: int = 0
    pooled: tables.Table | None = None
    pooled_rows: int = 0
    effects: tables.Table | None = None
    effects_rows: int = 0
    findings: list[comm.Finding] = field(default_factory=list)
    against: list[tuple[str, str, str]] = field(default_factory=list)
    """(title, figure, data) of exploration time and comm metrics against a compared dimension."""
    over_time: list[tuple[str, str]] = field(default_factory=list)
    single_robot_runs: int = 0


@dataclass
class Report:
    """What the README is rendered from (paths are relative to the report folder)."""

    data: CampaignData
    target: float
    command: str
    fmt: str
    runs_t: pd.DataFrame
    ttt_source: str
    width: float = 7.16
    """Figure width in inches (:data:`.figures.WIDTHS`)."""
    figures: list[FigureSet] = field(default_factory=list)
    layout_figures: list[LayoutFigure] = field(default_factory=list)
    layout_file: str | None = None
    cell_figures: bool = True
    summary: tables.Table | None = None
    summary_rows: int = 0
    paired: list[PairedSection] = field(default_factory=list)
    pooled: PairedSection | None = None
    paired_figures: list[tuple[str, str]] = field(default_factory=list)
    comm: tables.Table | None = None
    comm_unexpected: int = 0
    comm_rows: int = 0
    comm_compared: int = 0
    comm_single: int = 0
    maes: dict[str, Any] | None = None
    map_quality: tables.Table | None = None
    map_quality_rows: int = 0
    collisions: tables.Table | None = None
    collisions_rows: int = 0
    benchmark: tables.Table | None = None
    benchmark_rows: int = 0
    map_figures: list[tuple[str, str]] = field(default_factory=list)
    """(title, path) of each map value's drawing (:mod:`.mapfigs`)."""
    communication: CommSection | None = None
    notes: list[str] = field(default_factory=list)
    finding: str | None = None
    """One sentence for the first page (:func:`.headline.finding`)."""
    finding_figure: tuple[str, str] | None = None
    """(title, path) of the figure shown with it."""
    written: list[str] = field(default_factory=list)
