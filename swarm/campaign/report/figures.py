"""The report's figures, drawn with matplotlib's object API (no pyplot: no global state, no display needed)
in one journal style (:data:`STYLE`) and saved with fixed metadata so the same results give the same bytes.

Conventions every figure follows, so a journal can take it as it is:

- **Time** is simulated seconds on every axis (:func:`.units.seconds`).
- **Width** is one journal column (3.5 in) or the full page (7.16 in): :data:`WIDTHS`.
- **Colour** comes from the Okabe-Ito palette (:data:`PALETTE`, safe for colour-blind readers) by a label's
  position in its dimension's spec order, so an algorithm has the same colour in every figure of a report;
  each such line or band carries ``gid = "series:<label>"`` (an id in SVG output, and what the tests check).
- **Bands** are named in the figure itself (:func:`band_text`), not only in the report's text.
- **Output**: 300 dpi PNG (or SVG) plus a PDF copy of every figure (:func:`write_figure`).
"""

from __future__ import annotations

import io
import textwrap
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import matplotlib
import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.ticker import FuncFormatter, LogLocator, MaxNLocator, NullFormatter

from .units import seconds

PANEL_TITLE_CHARS = 58  # a panel title longer than this wraps
FORMATS = ("png", "svg", "pdf")
DPI = 300
WIDTHS = {"column": 3.5, "page": 7.16}
"""Figure widths in inches: one column and two columns (full page) of a two-column journal."""
PALETTE = ("#E69F00", "#56B4E9", "#009E73", "#0072B2", "#D55E00", "#CC79A7", "#000000", "#F0E442")
"""Okabe & Ito's colour-blind-safe palette, yellow (faint on white) last."""
GID = "series:"
_METADATA = {"png": {"Software": None}, "svg": {"Date": None, "Creator": None},
             "pdf": {"CreationDate": None, "Creator": None, "Producer": None}}
STYLE: Any = {"svg.hashsalt": "swarm-campaign-report", "path.simplify": True, "font.size": 8,
              "axes.titlesize": 8, "axes.labelsize": 8, "xtick.labelsize": 7, "ytick.labelsize": 7,
              "legend.fontsize": 7, "legend.title_fontsize": 7, "figure.titlesize": 9, "lines.linewidth": 1.2,
              "axes.linewidth": 0.6, "grid.linewidth": 0.4, "grid.alpha": 0.35, "axes.grid": True,
              "axes.prop_cycle": matplotlib.cycler(color=PALETTE), "savefig.dpi": DPI,
              "pdf.fonttype": 42, "ps.fonttype": 42}
"""The matplotlib rcParams of every figure: journal font sizes at print size, TrueType fonts in PDFs (type 3
fonts are refused by some publishers), the palette as the default colour cycle."""


@dataclass
class Curve:
    """One line of an explored-vs-time figure: mean and band (fractions) on a tick grid."""

    label: str
    colour: int
    ticks: np.ndarray
    mean: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    runs: int
    successes: int


@dataclass
class Times:
    """Ticks to target of one line's runs (NaN = DNF)."""

    label: str
    colour: int
    ttt: np.ndarray


def colour(index: int) -> str:
    """The same label gets the same colour in every figure (its position in the spec's order)."""
    return PALETTE[index % len(PALETTE)]


DASHES = ("-", "--", ":", "-.")


def line_style(index: int) -> dict[str, str]:
    """Colour and line style of the label at ``index``: past the palette's eight colours the colours repeat
    with another dash pattern, so up to 32 lines of a figure stay apart."""
    return {"color": colour(index), "linestyle": DASHES[index // len(PALETTE) % len(DASHES)]}


def band_text(runs: Sequence[int], unit: str = "runs") -> str:
    """What a figure's lines and bands are, as :func:`.stats.mean_band` computes them."""
    counts = sorted(set(runs))
    over = f"{counts[0]} {unit}" if len(counts) == 1 else f"{counts[0]}–{counts[-1]} {unit} per line"
    return f"mean, 95 % t-interval over {over}"


def render(fig: Figure, fmt: str) -> bytes:
    buf = io.BytesIO()
    with matplotlib.rc_context(STYLE):
        fig.savefig(buf, format=fmt, metadata=_METADATA[fmt], dpi=DPI)
    return buf.getvalue()


def write_figure(write: Callable[[str, bytes], Any], stem: str, fig: Figure, fmt: str) -> str:
    """Write ``stem.<fmt>`` and, unless that is already PDF, a vector copy ``stem.pdf``; returns the first's
    path (the one the README shows)."""
    for f in dict.fromkeys((fmt, "pdf")):
        write(f"{stem}.{f}", render(fig, f))
    return f"{stem}.{fmt}"


def _figure(width: float, height: float, left: float = 0.55, right: float = 0.1, bottom: float = 0.45,
            top: float = 0.3, **spacing: float) -> Figure:
    """A figure with fixed margins in inches (a layout engine would draw every figure twice, most of the
    report's run time)."""
    fig = Figure(figsize=(width, height))
    FigureCanvasAgg(fig)
    fig.subplots_adjust(left=left / width, right=1 - right / width, bottom=bottom / height, top=1 - top / height,
                        **spacing)
    return fig


def _grid(n: int, width: float, panel: float = 2.3) -> tuple[int, int]:
    """Columns and rows for ``n`` panels at least ``panel`` inches wide in ``width``."""
    cols = max(1, min(n, int(width // panel)))
    return cols, -(-n // cols)


def _plain(x: float, pos: int | None = None) -> str:
    """A tick label as a plain number (20000, 0.5: not 2e+04)."""
    return f"{x:g}" if abs(x) < 1e6 else f"{x:.0f}"


def _time_axis(ax: Any, which: str, values: np.ndarray, floor: float) -> None:
    """A seconds axis over ``values`` (> 0) with a margin: log when they span more than a decade, labelled at
    1, 2 and 5 times each power of ten; linear otherwise (a log axis over less than a decade labels one or
    two ticks). ``floor``: the smallest value a log axis shows."""
    v = np.asarray(values, dtype=np.float64)
    v = v[np.isfinite(v)]
    lo, hi = (float(v.min()), float(v.max())) if len(v) else (floor, 10 * floor)
    axis = ax.yaxis if which == "y" else ax.xaxis
    set_lim = ax.set_ylim if which == "y" else ax.set_xlim
    if hi > 10 * max(lo, floor):
        (ax.set_yscale if which == "y" else ax.set_xscale)("log")
        axis.set_major_locator(LogLocator(base=10, subs=(1.0, 2.0, 5.0)))
        axis.set_major_formatter(FuncFormatter(_plain))
        axis.set_minor_formatter(NullFormatter())
        lo = max(lo, floor)
        set_lim(lo / 1.2, hi * 1.2)
    else:
        pad = 0.06 * (hi - lo) or 0.06 * hi or 1.0
        set_lim(max(lo - pad, 0.0), hi + pad)
        axis.set_major_formatter(FuncFormatter(_plain))


def _text(label: str) -> str:
    """A user label shown literally (a '$' would start matplotlib's math mode)."""
    return label.replace("$", r"\$")


def _wrap(title: str, width: float) -> str:
    return textwrap.fill(_text(title), max(30, int(width * 14)))


def _draw_curves(ax: Any, curves: Sequence[Curve], target: float) -> None:
    """Mean lines with their bands against simulated seconds, the target as a dotted line, axes limited to the
    data; a line whose runs have all stopped holds its final value to the axis's end."""
    end = max((int(c.ticks[-1]) for c in curves), default=0)
    for c in curves:
        t, m, lo, hi = c.ticks, c.mean, c.lo, c.hi
        if t[-1] < end:
            t, m, lo, hi = (np.append(t, end), np.append(m, m[-1]), np.append(lo, lo[-1]), np.append(hi, hi[-1]))
        x = seconds(t)
        ax.plot(x, 100 * m, **line_style(c.colour), gid=GID + c.label,
                label=_text(f"{c.label} ({c.successes}/{c.runs} reached)"))
        if np.any(np.isfinite(lo)):
            ax.fill_between(x, np.clip(100 * lo, 0, 100), np.clip(100 * hi, 0, 100), color=colour(c.colour),
                            alpha=0.2, lw=0, gid=GID + c.label)
    ax.axhline(100 * target, color="0.4", lw=0.8, ls=":")
    ax.set_xlim(0, float(seconds(end)) if end else 1.0)
    ax.set_ylim(0, 100)


def curves_figure(curves: Sequence[Curve], title: str, target: float, width: float, unit: str = "maps") -> Figure:
    """Explored % vs simulated seconds, mean over replicates with a 95 % band (named in the legend's title);
    runs that stopped hold their final value. ``unit``: what a line's runs are (one map each per cell)."""
    height = 0.6 * width + 0.4
    with matplotlib.rc_context(STYLE):
        fig = _figure(width, height, top=0.25 + 0.15 * _wrap(title, width).count("\n") + 0.15)
        ax = fig.add_subplot()
        _draw_curves(ax, curves, target)
        ax.set_xlabel("simulated time (s)")
        ax.set_ylabel("explored (%)")
        ax.set_title(_wrap(title, width))
        ax.legend(loc="lower right", title=band_text([c.runs for c in curves], unit))
    return fig


def cactus_figure(lines: Sequence[Times], title: str, target: float, max_ticks: float, width: float) -> Figure:
    """Left (above, at column width): MAES-style cactus, successful runs sorted by time to target. Right: ECDF,
    the fraction of all runs that reached the target by a given time. Time axes over the data only."""
    pct = f"{100 * target:g} %"
    side = width >= 5
    height = 0.42 * width + 0.4 if side else 1.5 * width
    heading = _wrap(f"time to {pct} explored: {title}", width)
    with matplotlib.rc_context(STYLE):
        fig = _figure(width, height, top=0.45 + 0.15 * heading.count("\n"), wspace=0.28, hspace=0.5)
        cactus, ecdf = fig.subplots(1, 2) if side else fig.subplots(2, 1)
        floor = float(seconds(1))  # log axes: a run explored at tick 0 is drawn at one tick
        done_s = [np.maximum(seconds(np.sort(line.ttt[np.isfinite(line.ttt)])), floor) for line in lines]
        every = np.concatenate(done_s + [np.zeros(0)])
        lo, hi = (float(every.min()), float(every.max())) if len(every) else (floor, float(seconds(max_ticks)))
        for line, y in zip(lines, done_s):
            label = _text(f"{line.label} ({len(y)}/{len(line.ttt)})")
            cactus.plot(np.arange(1, len(y) + 1), y, marker="o", ms=2.5, lw=1, **line_style(line.colour),
                        label=label, gid=GID + line.label)
            frac = np.arange(1, len(y) + 1) / max(len(line.ttt), 1)
            ecdf.step(np.r_[lo / 10, y, hi * 10], np.r_[0, frac, frac[-1] if len(frac) else 0], where="post",
                      **line_style(line.colour), label=label, gid=GID + line.label)
        _time_axis(cactus, "y", every, floor)
        _time_axis(ecdf, "x", every, floor)
        cactus.xaxis.set_major_locator(MaxNLocator(integer=True))
        cactus.set_xlabel("runs reaching the target (count, sorted)")
        cactus.set_ylabel(f"time to {pct} explored (s)")
        cactus.set_title("cactus")
        ecdf.set_ylim(0, 1.02)
        ecdf.set_xlabel(f"time to {pct} explored (s)")
        ecdf.set_ylabel("runs done (fraction)")
        ecdf.set_title(f"ECDF (DNF never arrive; max {float(seconds(max_ticks)):g} s)")
        cactus.legend(loc="best", title="runs reached / all")
        ecdf.legend(loc="lower right")
        fig.suptitle(heading)
    return fig


@dataclass
class PairPanel:
    """The per-replicate ticks of algorithms a and b in one cell (DNF at max_ticks)."""

    a: str
    b: str
    t_a: np.ndarray
    t_b: np.ndarray
    dnf: np.ndarray
    a_wins: int
    b_wins: int
    ties: int


def paired_figure(panels: Sequence[PairPanel], title: str, max_ticks: float, width: float) -> Figure:
    """One scatter per algorithm pair, a point per replicate (same map and start poses), in simulated seconds:
    a point above the diagonal is a map where b took longer than a. Markers are neutral (black, grey): colour
    stays the algorithms'."""
    if len(panels) == 1:
        width = min(width, WIDTHS["column"])  # one square panel: a column is wide enough
    cols, rows = _grid(len(panels), width)
    side = (width - 0.6) / cols - 0.45  # a square panel, its y label beside it
    heading = _wrap(f"paired by replicate (same map and start): {title}", width)
    top = 0.45 + 0.15 * heading.count("\n")
    height = rows * (side + 0.75) + top
    with matplotlib.rc_context(STYLE):
        fig = _figure(width, height, left=0.55, right=0.1, bottom=0.45, top=top, wspace=0.45 / side,
                      hspace=0.75 / side)
        axes = fig.subplots(rows, cols, squeeze=False).ravel()
        for ax, p in zip(axes, panels):
            a, b = seconds(p.t_a), seconds(p.t_b)
            both = np.r_[a, b]
            lo, hi = (float(both.min()), float(both.max())) if len(both) else (0.0, 1.0)
            pad = 0.06 * (hi - lo) or 0.06 * hi or 1.0
            lim = (max(lo - pad, 0.0), hi + pad)
            ax.plot(lim, lim, color="0.5", lw=0.8, ls="--")
            ax.scatter(a[~p.dnf], b[~p.dnf], s=10, color="0.1", label="both reached")
            if p.dnf.any():
                ax.scatter(a[p.dnf], b[p.dnf], s=14, marker="x", color="0.55",
                           label=f"a DNF (at max {float(seconds(max_ticks)):g} s)")
            ax.set_xlim(*lim)
            ax.set_ylim(*lim)
            ax.set_aspect("equal")
            ax.set_xlabel(_text(f"{p.a}: time to target (s)"))
            ax.set_ylabel(_text(f"{p.b}: time to target (s)"))
            ax.set_title(_text(f"{p.a} faster {p.a_wins}, {p.b} faster {p.b_wins}, ties {p.ties}"), fontsize=7)
            ax.legend(loc="upper left", fontsize=6)
        for ax in axes[len(panels):]:
            ax.set_visible(False)
        fig.suptitle(heading)
    return fig


def panels_figure(panels: Sequence[tuple[str, Sequence[Curve]]], title: str, target: float, width: float,
                  columns: int = 0) -> Figure:
    """Explored-vs-time panels in a grid (the layout of a paper's figure); ``panels`` = (panel title, its
    curves); ``columns`` panels per row (0: one row; fewer when panels would be narrower than 2.3 in). Each
    panel's legend names its band (pooled runs)."""
    n = len(panels)
    cols = min(columns or n, _grid(n, width)[0])
    rows = -(-n // cols)
    chars = max(20, int(PANEL_TITLE_CHARS * width / cols / 4.6))
    titles = [textwrap.fill(_text(t), chars) for t, _ in panels]
    lines = max((t.count("\n") + 1 for t in titles), default=1)
    heading = _wrap(title, width)
    panel_h = min(0.75 * (width - 0.6) / cols, 3.2) + 0.15 * lines + 0.35
    height = panel_h * rows + 0.45 + 0.15 * heading.count("\n")
    with matplotlib.rc_context(STYLE):
        fig = _figure(width, height, left=0.5, right=0.1, bottom=0.4, top=0.3 + 0.15 * (lines + heading.count("\n")),
                      wspace=0.3, hspace=(0.35 + 0.15 * lines) / max(panel_h - 0.35, 0.5))
        fig.suptitle(heading)
        for k, (panel_title, (_, curves)) in enumerate(zip(titles, panels)):
            ax = fig.add_subplot(rows, cols, k + 1)
            _draw_curves(ax, curves, target)
            if k // cols == rows - 1:
                ax.set_xlabel("simulated time (s)")
            if k % cols == 0:
                ax.set_ylabel("explored (%)")
            ax.set_title(panel_title)
            ax.legend(loc="lower right", title=band_text([c.runs for c in curves], "runs"))
    return fig
