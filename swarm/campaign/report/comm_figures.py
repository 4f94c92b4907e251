"""The communication section's figures (matplotlib, as :mod:`.figures`): exploration time and the key comm
metrics against a talk-only dimension (a radio model, a comm setting, a swept radio or comm parameter), and
comm metrics over time per cell."""

from __future__ import annotations

import textwrap
from collections.abc import Sequence
from dataclasses import dataclass, field

import matplotlib
import numpy as np

from .figures import _RC, PANEL_TITLE_CHARS, TICKS_PER_MINUTE, _figure, _text, colour, render


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
                   xticks: tuple[np.ndarray, list[str]], title: str, fmt: str) -> bytes:
    """A column per panel, a row per metric (``(key, y label)``): each line's mean with its 95 % band
    against the compared values."""
    cols, rows = len(panels), len(metrics)
    titles = [textwrap.fill(p.title, PANEL_TITLE_CHARS - 20) for p in panels]
    width = 3.9 * cols + 1.1
    heading = textwrap.fill(title, int(width * 10))
    lines = max((t.count("\n") + 1 for t in titles), default=1) + heading.count("\n")
    height = 2.3 * rows + 0.9 + 0.2 * lines
    with matplotlib.rc_context(_RC):
        fig = _figure(width, height, left=1.0 / width, right=1 - 0.15 / width, bottom=0.55 / height,
                      top=1 - (0.5 + 0.2 * lines) / height, wspace=0.3, hspace=0.25)
        fig.suptitle(_text(heading))
        axes = fig.subplots(rows, cols, squeeze=False)
        positions, labels = xticks
        for c, (panel, panel_title) in enumerate(zip(panels, titles)):
            for r, (key, ylabel) in enumerate(metrics):
                ax = axes[r][c]
                for line in panel.lines:
                    band = line.bands.get(key)
                    if band is None or not np.isfinite(band.mean).any():
                        continue
                    ax.plot(line.x, band.mean, color=colour(line.colour), lw=1.4, marker="o", ms=3,
                            label=_text(line.label))
                    if np.isfinite(band.lo).any():
                        lo, hi = _clip(key, band)
                        ax.fill_between(line.x, lo, hi, color=colour(line.colour), alpha=0.15, lw=0)
                ax.set_xticks(positions)
                ax.set_xticklabels(labels if r == rows - 1 else [""] * len(labels))
                ax.grid(alpha=0.3)
                if r == 0:
                    ax.set_title(_text(panel_title))
                if c == 0:
                    ax.set_ylabel(ylabel)
                if r == rows - 1:
                    ax.set_xlabel(_text(xlabel))
                if r == 0 and c == cols - 1:
                    ax.legend(loc="best", fontsize=7)
        return render(fig, fmt)


def _clip(quantity: str, band: Band) -> tuple[np.ndarray, np.ndarray]:
    """A band within what the quantity can be: never below 0, and a percentage never above 100 (a
    t-interval of few runs reaches past both)."""
    top = 100.0 if "pct" in quantity or "%" in quantity else np.inf
    return np.clip(band.lo, 0.0, top), np.clip(band.hi, 0.0, top)


@dataclass
class Series:
    """One compared value's mean of a quantity over time, with its 95 % band (ticks on the x axis)."""

    label: str
    colour: int
    ticks: np.ndarray
    band: Band
    runs: int


def over_time_figure(panels: Sequence[tuple[str, str, Sequence[Series]]], title: str, fmt: str) -> bytes:
    """Comm metrics over simulated time, a panel per metric (``(panel title, y label, series)``); a run
    that stopped holds its last value."""
    cols = len(panels)
    width, height = 4.2 * cols + 0.6, 3.6
    with matplotlib.rc_context(_RC):
        fig = _figure(width, height, left=0.6 / width, right=1 - 0.15 / width, bottom=0.14, top=0.82, wspace=0.3)
        fig.suptitle(_text(textwrap.fill(title, 150)))
        axes = fig.subplots(1, cols, squeeze=False)[0]
        # at least one tick wide: runs that all ended at tick 0 would give matplotlib an empty range
        end = max((int(s.ticks[-1]) for _, _, series in panels for s in series if len(s.ticks)), default=1) or 1
        for ax, (panel_title, ylabel, series) in zip(axes, panels):
            for s in series:
                x = s.ticks / TICKS_PER_MINUTE
                ax.plot(x, s.band.mean, color=colour(s.colour), lw=1.4, label=_text(f"{s.label} (n = {s.runs})"))
                if np.isfinite(s.band.lo).any():
                    lo, hi = _clip(ylabel, s.band)
                    ax.fill_between(x, lo, hi, color=colour(s.colour), alpha=0.15, lw=0)
            ax.set_xlim(0, end / TICKS_PER_MINUTE)
            ax.set_xlabel("simulated time (minutes)")
            ax.set_ylabel(ylabel)
            ax.set_title(_text(panel_title))
            ax.grid(alpha=0.3)
        axes[0].legend(loc="best", fontsize=7)
        return render(fig, fmt)
