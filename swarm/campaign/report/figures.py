"""The report's figures, drawn with matplotlib's object API (no pyplot: no global state, no display needed)
and saved with fixed metadata so the same results give the same bytes.

Time axes: curves are in simulated minutes (600 ticks = 1 min, a tick is 0.1 s, as in the paper's
figures); cactus, ECDF and paired plots are in ticks (as MAES's maes-csv-reader).
"""

from __future__ import annotations

import io
import textwrap
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import matplotlib
import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.ticker import LogFormatter, MaxNLocator

TICKS_PER_MINUTE = 600
PANEL_TITLE_CHARS = 58  # a panel title longer than this wraps: 4.6-inch panels side by side
FORMATS = ("png", "svg", "pdf")
_METADATA = {"png": {"Software": None}, "svg": {"Date": None, "Creator": None},
             "pdf": {"CreationDate": None, "Creator": None, "Producer": None}}
_RC: Any = {"svg.hashsalt": "swarm-campaign-report", "font.size": 9, "axes.titlesize": 9, "legend.fontsize": 8,
       "path.simplify": True}


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


def colour(index: int) -> tuple[float, float, float, float]:
    """The same label gets the same colour in every figure (its position in the spec)."""
    return matplotlib.colormaps["tab10"](index % 10)


def render(fig: Figure, fmt: str) -> bytes:
    buf = io.BytesIO()
    with matplotlib.rc_context(_RC):
        fig.savefig(buf, format=fmt, metadata=_METADATA[fmt], dpi=110)
    return buf.getvalue()


def _figure(width: float, height: float, **margins: float) -> Figure:
    """Fixed margins: a layout engine would draw every figure twice (most of the report's run time)."""
    fig = Figure(figsize=(width, height))
    FigureCanvasAgg(fig)
    fig.subplots_adjust(**{"left": 0.09, "right": 0.98, "bottom": 0.12, "top": 0.92, **margins})
    return fig


class _PlainLogFormatter(LogFormatter):
    """LogFormatter's choice of which ticks to label, printed as plain numbers (20000, not 2e+04)."""

    def __call__(self, x: float, pos: int | None = None) -> str:
        return f"{x:.0f}" if x >= 1 and super().__call__(x, pos) else ("" if x >= 1 else f"{x:g}")


def _plain_log(axis: Any) -> None:
    """Log-axis labels as plain numbers: readable as ticks, and no math-text parsing per label."""
    axis.set_major_formatter(_PlainLogFormatter(labelOnlyBase=False))
    axis.set_minor_formatter(_PlainLogFormatter(labelOnlyBase=False, minor_thresholds=(1, 0.4)))


def _text(label: str) -> str:
    """A user label shown literally (a '$' would start matplotlib's math mode)."""
    return label.replace("$", r"\$")


def _draw_curves(ax: Any, curves: Sequence[Curve], target: float) -> None:
    """Mean lines with 95 % bands in simulated minutes, the target as a dotted line, axes limited to the
    data; a line whose runs have all stopped holds its final value to the axis's end."""
    end = max((int(c.ticks[-1]) for c in curves), default=0)
    for c in curves:
        t, m, lo, hi = c.ticks, c.mean, c.lo, c.hi
        if t[-1] < end:
            t, m, lo, hi = (np.append(t, end), np.append(m, m[-1]), np.append(lo, lo[-1]), np.append(hi, hi[-1]))
        x = t / TICKS_PER_MINUTE
        ax.plot(x, 100 * m, color=colour(c.colour), lw=1.5,
                label=_text(f"{c.label} (n = {c.runs}, {c.successes} reached)"))
        if np.any(np.isfinite(lo)):
            ax.fill_between(x, np.clip(100 * lo, 0, 100), np.clip(100 * hi, 0, 100), color=colour(c.colour),
                            alpha=0.18, lw=0)
    ax.axhline(100 * target, color="0.4", lw=0.8, ls=":")
    ax.set_xlim(0, end / TICKS_PER_MINUTE if end else 1)
    ax.set_ylim(0, 100)


def curves_figure(curves: Sequence[Curve], title: str, target: float, fmt: str) -> bytes:
    """Explored % vs simulated minutes, mean over replicates with a 95 % band; runs that stopped hold their
    final value."""
    with matplotlib.rc_context(_RC):
        fig = _figure(6.4, 4.2)
        ax = fig.add_subplot()
        _draw_curves(ax, curves, target)
        ax.set_xlabel("simulated time (minutes; 600 ticks = 1 min)")
        ax.set_ylabel("explored (%)")
        ax.set_title(_text(title))
        ax.grid(alpha=0.3)
        ax.legend(loc="lower right")
        return render(fig, fmt)


def cactus_figure(lines: Sequence[Times], title: str, target: float, max_ticks: float, fmt: str) -> bytes:
    """Left: MAES-style cactus (successful runs sorted by ticks to target, log y). Right: ECDF, the
    fraction of all runs that reached the target by a given tick."""
    pct = f"{100 * target:g} %"
    with matplotlib.rc_context(_RC):
        fig = _figure(10.0, 4.0, left=0.07, wspace=0.22, top=0.9)
        cactus, ecdf = fig.subplots(1, 2)
        for line in lines:
            done = np.sort(line.ttt[np.isfinite(line.ttt)])
            label = _text(f"{line.label} ({len(done)}/{len(line.ttt)})")
            y = np.maximum(done, 1)  # log axis: a run explored at tick 0 is drawn at 1
            cactus.plot(np.arange(1, len(done) + 1), y, marker="o", ms=2.5, lw=1, color=colour(line.colour),
                        label=label)
            frac = np.arange(1, len(done) + 1) / max(len(line.ttt), 1)
            ecdf.step(np.r_[1, y], np.r_[0, frac], where="post", color=colour(line.colour), lw=1.2, label=label)
        cactus.set_yscale("log")
        _plain_log(cactus.yaxis)
        cactus.xaxis.set_major_locator(MaxNLocator(integer=True))
        cactus.set_xlabel("runs reaching the target, sorted")
        cactus.set_ylabel(f"ticks to {pct} explored (log)")
        cactus.set_title(_text(f"cactus: {title}"))
        ecdf.set_xscale("log")
        _plain_log(ecdf.xaxis)
        finite = np.concatenate([line.ttt[np.isfinite(line.ttt)] for line in lines] + [np.array([max_ticks])])
        right = max(max_ticks, 10.0)
        ecdf.set_xlim(min(10.0 ** np.floor(np.log10(max(float(finite.min()), 1.0))), right / 10), right)
        ecdf.set_ylim(0, 1.02)
        ecdf.set_xlabel(f"ticks to {pct} explored (log)")
        ecdf.set_ylabel("fraction of runs done")
        ecdf.set_title("ECDF (DNF runs never arrive)")
        for ax in (cactus, ecdf):
            ax.grid(alpha=0.3)
            ax.legend(loc="upper left" if ax is cactus else "lower right")
        return render(fig, fmt)


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


def paired_figure(panels: Sequence[PairPanel], title: str, max_ticks: float, fmt: str) -> bytes:
    """One scatter per algorithm pair, a point per replicate (same map and start poses): a point above the
    diagonal is a map where b took longer than a."""
    cols = min(3, len(panels))
    rows = -(-len(panels) // cols)
    height = 3.4 * rows + 0.5
    with matplotlib.rc_context(_RC):
        fig = _figure(3.7 * cols, height, left=0.35 / cols, right=0.98, bottom=0.5 / height, top=1 - 0.55 / height,
                      wspace=0.45, hspace=0.45)
        axes = fig.subplots(rows, cols, squeeze=False).ravel()
        for ax, p in zip(axes, panels):
            top = max(float(np.max(np.r_[p.t_a, p.t_b, 1])), 1.0) * 1.05
            ax.plot([0, top], [0, top], color="0.5", lw=0.8, ls="--")
            ax.scatter(p.t_a[~p.dnf], p.t_b[~p.dnf], s=12, color=colour(0), label="both reached")
            if p.dnf.any():
                ax.scatter(p.t_a[p.dnf], p.t_b[p.dnf], s=18, marker="x", color=colour(3),
                           label=f"a DNF run (at max_ticks = {max_ticks:g})")
            ax.set_xlim(0, top)
            ax.set_ylim(0, top)
            ax.set_aspect("equal")
            ax.set_xlabel(_text(f"{p.a}: ticks to target"))
            ax.set_ylabel(_text(f"{p.b}: ticks to target"))
            ax.set_title(_text(f"{p.a} faster {p.a_wins}, {p.b} faster {p.b_wins}, ties {p.ties}"))
            ax.grid(alpha=0.3)
            ax.legend(loc="upper left", fontsize=7)
        for ax in axes[len(panels):]:
            ax.set_visible(False)
        fig.suptitle(_text(f"paired by replicate (same map and start): {title}"))
        return render(fig, fmt)


def panels_figure(panels: Sequence[tuple[str, Sequence[Curve]]], title: str, target: float, fmt: str,
                  columns: int = 0) -> bytes:
    """Explored-vs-time panels in a grid (the layout of a paper's figure); ``panels`` = (panel title, its
    curves); ``columns`` panels per row (0: one row)."""
    with matplotlib.rc_context(_RC):
        n = len(panels)
        cols = min(columns or n, n)
        rows = -(-n // cols)
        titles = [textwrap.fill(t, PANEL_TITLE_CHARS) for t, _ in panels]
        lines = max((t.count("\n") + 1 for t in titles), default=1)
        width, height = 4.6 * cols + 0.4, (3.7 + 0.2 * lines) * rows + 0.5
        fig = _figure(width, height, left=0.7 / width, right=1 - 0.15 / width, bottom=0.55 / height,
                      top=1 - (0.4 + 0.2 * lines) / height, wspace=0.18, hspace=0.35 + 0.1 * lines)
        fig.suptitle(_text(title))
        for k, (panel_title, (_, curves)) in enumerate(zip(titles, panels)):
            ax = fig.add_subplot(rows, cols, k + 1)
            _draw_curves(ax, curves, target)
            if k // cols == rows - 1:
                ax.set_xlabel("simulated time (minutes)")
            if k % cols == 0:
                ax.set_ylabel("explored (%)")
            ax.set_title(_text(panel_title))
            ax.grid(alpha=0.3)
            ax.legend(loc="lower right")
        return render(fig, fmt)
