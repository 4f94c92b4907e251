"""The communication section's figures (matplotlib, in :mod:`.figures`' style, palette and time unit):
exploration time and the key comm metrics against a talk-only dimension (a radio model, a comm setting, a
swept radio or comm parameter), and comm metrics over time per cell."""

from __future__ import annotations

import textwrap
from collections.abc import Sequence
from dataclasses import dataclass, field

import matplotlib
import numpy as np
from matplotlib.figure import Figure

from .figures import (
    GID,
    PANEL_TITLE_CHARS,
    STYLE,
    _figure,
    _grid,
    _text,
    _wrap,
    band_text,
    colour,
    line_style,
)
from .units import seconds


@dataclass
class Band:
    """Mean and 95 % interval of one quantity at each x (NaN where no run)."""

    mean: np.ndarray
    lo: np.ndarray
    hi: np.ndarray


@dataclass
class Line:
    """One algorithm's values against the compared dimension (``x``: positions on the axis)."""

    label: str
    colour: int
    x: np.ndarray
    bands: dict[str, Band] = field(default_factory=dict)


@dataclass
class Panel:
    title: str
    lines: list[Line]


def against_figure(panels: Sequence[Panel], metrics: Sequence[tuple[str, str]], xlabel: str,
                   xticks: tuple[np.ndarray, list[str]], title: str, width: float) -> Figure:
    """A column per panel, a row per metric (``(key, y label)``): each line's mean with its 95 % band
    against the compared values. Wider than ``width`` when more panels than fit (2 in each) are side by side."""
    cols, rows = len(panels), len(metrics)
    width = max(width, 1.9 * cols + 0.8)
    titles = [textwrap.fill(_text(p.title), max(20, int(PANEL_TITLE_CHARS * (width - 0.8) / cols / 4.6)))
              for p in panels]
    heading = _wrap(title, width)
    lines = max((t.count("\n") + 1 for t in titles), default=1) + heading.count("\n") + 1
    height = 1.7 * rows + 0.9 + 0.15 * lines
    with matplotlib.rc_context(STYLE):
        fig = _figure(width, height, left=0.75, right=0.1, bottom=0.45, top=0.3 + 0.15 * lines, wspace=0.35,
                      hspace=0.25)
        fig.suptitle(heading)
        axes = fig.subplots(rows, cols, squeeze=False)
        positions, labels = xticks
        for c, (panel, panel_title) in enumerate(zip(panels, titles)):
            for r, (key, ylabel) in enumerate(metrics):
                ax = axes[r][c]
                for line in panel.lines:
                    band = line.bands.get(key)
                    if band is None or not np.isfinite(band.mean).any():
                        continue
                    ax.plot(line.x, band.mean, **line_style(line.colour), marker="o", ms=3,
                            label=_text(line.label), gid=GID + line.label)
                    if np.isfinite(band.lo).any():
                        lo, hi = _clip(key, band)
                        ax.fill_between(line.x, lo, hi, color=colour(line.colour), alpha=0.15, lw=0,
                                        gid=GID + line.label)
                ax.set_xticks(positions)
                ax.set_xticklabels(labels if r == rows - 1 else [""] * len(labels))
                if r == 0:
                    ax.set_title(panel_title)
                if c == 0:
                    ax.set_ylabel(ylabel)
                if r == rows - 1:
                    ax.set_xlabel(_text(xlabel))
                if r == 0 and c == cols - 1:
                    ax.legend(loc="best", fontsize=6, title="mean, 95 % t-interval\nover the runs (maps)")
    return fig


def _clip(quantity: str, band: Band) -> tuple[np.ndarray, np.ndarray]:
    """A band within what the quantity can be: never below 0, and a percentage never above 100 (a
    t-interval of few runs reaches past both)."""
    top = 100.0 if "pct" in quantity or "%" in quantity else np.inf
    return np.clip(band.lo, 0.0, top), np.clip(band.hi, 0.0, top)


@dataclass
class Series:
    """One compared value's mean of a quantity over time, with its 95 % band (a tick grid)."""

    label: str
    colour: int
    ticks: np.ndarray
    band: Band
    runs: int


def over_time_figure(panels: Sequence[tuple[str, str, Sequence[Series]]], title: str, width: float) -> Figure:
    """Comm metrics over simulated seconds, a panel per metric (``(panel title, y label, series)``); a run
    that stopped holds its last value. The band is named in the first panel's legend."""
    cols, rows = _grid(len(panels), width)
    heading = _wrap(title, width)
    panel_h = min(0.75 * (width - 0.6) / cols, 2.6) + 0.6
    height = panel_h * rows + 0.3 + 0.15 * heading.count("\n")
    with matplotlib.rc_context(STYLE):
        fig = _figure(width, height, left=0.55, right=0.1, bottom=0.45, top=0.4 + 0.15 * heading.count("\n"),
                      wspace=0.4, hspace=0.6 / max(panel_h - 0.6, 0.5))
        fig.suptitle(heading)
        axes = fig.subplots(rows, cols, squeeze=False).ravel()
        # at least one tick wide: runs that all ended at tick 0 would give matplotlib an empty range
        end = max((int(s.ticks[-1]) for _, _, series in panels for s in series if len(s.ticks)), default=1) or 1
        for ax, (panel_title, ylabel, series) in zip(axes, panels):
            for s in series:
                x = seconds(s.ticks)
                ax.plot(x, s.band.mean, **line_style(s.colour), label=_text(f"{s.label} (n = {s.runs})"),
                        gid=GID + s.label)
                if np.isfinite(s.band.lo).any():
                    lo, hi = _clip(ylabel, s.band)
                    ax.fill_between(x, lo, hi, color=colour(s.colour), alpha=0.15, lw=0, gid=GID + s.label)
            ax.set_xlim(0, float(seconds(end)))
            ax.set_xlabel("simulated time (s)")
            ax.set_ylabel(ylabel)
            ax.set_title(_text(panel_title))
        for ax in axes[len(panels):]:
            ax.set_visible(False)
        runs = [s.runs for _, _, series in panels for s in series]
        axes[0].legend(loc="best", fontsize=6, title=band_text(runs or [0], "runs"))
    return fig
