"""Every figure of a report as a journal takes it (issue 53): units on every axis, simulated seconds as the
one time unit, the band named in the figure, labelled log ticks, 300 dpi with a PDF copy, a journal width,
and one colour-blind-safe colour per label across every figure. The checker inspects the matplotlib Figure
objects the report saves (and the PNG written), on a small synthetic report that builds in seconds."""

from __future__ import annotations

import io
import re
from pathlib import Path

import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import PolyCollection
from matplotlib.colors import to_hex
from matplotlib.figure import Figure
from matplotlib.text import Text
from matplotlib.ticker import FixedFormatter
from PIL import Image

from swarm.campaign.report import build_report, comm_figures, figures
from swarm.cli import main

from .synthetic_results import FakeRun, write

TIMES = {("greed", "global"): [20, 40, 100, 300, 600, None],   # 2-60 s: more than a decade, a log axis
         ("frontier", "global"): [900, 950, 1000, 1100, 1200, 1500],  # less than a decade: linear
         ("greed", "los"): [120, 220, 320, 420, 520, 620],
         ("frontier", "los"): [150, 250, 350, 450, None, 650]}
LAYOUT = """
[[figure]]
name = "fig"
title = "Algorithms and radios"
columns = 2
[[figure.panel]]
compare = "algorithm"
radio = "global"
[[figure.panel]]
compare = "radio"
algorithm = "greed"
"""
SPEC = """
[campaign]
name = "quality"
seed = 5
replicates = 6

[grid]
map = ["building"]
size = [40]
robots = [2]
spawn = ["together"]
algorithm = ["greed", "frontier"]
radio = ["global", "los"]

[stop]
explored = 0.98
max_ticks = 2000
"""


def check_figure(fig: Figure) -> list[str]:
    """What keeps ``fig`` from print: each problem as a sentence (none: it passes)."""
    problems = []
    axes = [ax for ax in fig.axes if ax.get_visible()]
    labels = [(ax, axis, axis.get_label_text()) for ax in axes for axis in (ax.xaxis, ax.yaxis)]
    if not any(text for _, axis, text in labels if axis.axis_name == "x"):
        problems.append("no x axis is labelled")
    for ax, axis, text in labels:
        if not text or isinstance(axis.get_major_formatter(), FixedFormatter):
            continue  # an unlabelled inner panel, or a categorical axis (its tick labels are its values)
        if not re.search(r"\([^)]+\)", text):
            problems.append(f"axis label without a unit: {text!r}")
        if re.search(r"\btick", text, re.IGNORECASE) or re.search(r"\bmin(ute)?s?\b", text):
            problems.append(f"time not in seconds: {text!r}")
        if "time" in text and "(s)" not in text:
            problems.append(f"a time axis not in seconds: {text!r}")
        if axis.get_scale() == "log":
            lo, hi = sorted(axis.get_view_interval())
            shown = [t for t in axis.get_majorticklocs() if lo <= t <= hi]
            named = [axis.get_major_formatter()(t) for t in shown]
            if sum(1 for n in named if n) < 3:
                problems.append(f"log axis {text!r} labels fewer than 3 ticks: {named}")
    banded = any(isinstance(c, PolyCollection) for ax in axes for c in ax.collections)
    texts = [t.get_text() for t in fig.findobj(Text)]
    if banded and not any("95 % t-interval" in t for t in texts):
        problems.append("a band is drawn but the figure does not say what it is")
    for label, hexes in series_colours(fig).items():
        if len(hexes) > 1 or not hexes <= {c.lower() for c in figures.PALETTE}:
            problems.append(f"{label}: colours {sorted(hexes)} are not one colour of the palette")
    for ax in axes:
        styles = {line.get_gid(): (to_hex(line.get_color()), line.get_linestyle()) for line in ax.get_lines()
                  if (line.get_gid() or "").startswith(figures.GID)}
        if len(set(styles.values())) < len(styles):
            problems.append(f"two lines of one panel look the same: {styles}")
    return problems


def series_colours(fig: Figure) -> dict[str, set[str]]:
    """The colours of each labelled line and band (``gid = series:<label>``)."""
    out: dict[str, set[str]] = {}
    for artist in fig.findobj(lambda a: (a.get_gid() or "").startswith(figures.GID)):
        rgba = artist.get_color() if hasattr(artist, "get_color") and not isinstance(artist, PolyCollection) else (
            artist.get_facecolor()[0])
        out.setdefault(artist.get_gid()[len(figures.GID):], set()).add(to_hex(rgba, keep_alpha=False))
    return out


@pytest.fixture(scope="module", params=["page", "column"])
def report(request, tmp_path_factory) -> tuple[str, Path, dict[str, Figure]]:
    """The report of the synthetic results at one width, with every Figure it saved (by file stem)."""
    root = tmp_path_factory.mktemp(request.param)
    runs = [FakeRun(alg, radio, rep, t, stop_reason="explored" if t else "max_ticks")
            for (alg, radio), times in TIMES.items() for rep, t in enumerate(times)]
    results = write(root / "results", runs, spec_text=SPEC)
    (root / "layout.toml").write_text(LAYOUT)
    saved: dict[str, Figure] = {}
    original = figures.write_figure

    def keep(write_, stem, fig, fmt):
        saved[stem] = fig
        return original(write_, stem, fig, fmt)

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(figures, "write_figure", keep)
        readme = build_report(results, root / "report", figures_file=root / "layout.toml",
                              figure_width=request.param)
    return request.param, readme.parent, saved


def test_every_figure_passes_the_checker(report):
    width, folder, saved = report
    assert {stem.split("/")[0] for stem in saved} == {"curves", "cactus", "paired", "figures"}
    for stem, fig in saved.items():
        assert check_figure(fig) == [], stem
        assert fig.get_size_inches()[0] == pytest.approx(min(figures.WIDTHS[width], figures.WIDTHS["column"])
                                                         if stem.startswith("paired") else figures.WIDTHS[width])
        png = Image.open(io.BytesIO((folder / f"{stem}.png").read_bytes()))
        assert png.info["dpi"] == pytest.approx((300, 300), abs=0.01), stem
        assert (folder / f"{stem}.pdf").read_bytes()[:5] == b"%PDF-", stem


def test_each_label_has_one_colour_in_every_figure(report):
    _, _, saved = report
    seen: dict[str, set[str]] = {}
    for fig in saved.values():
        for label, hexes in series_colours(fig).items():
            seen.setdefault(label, set()).update(hexes)
    assert set(seen) == {"greed", "frontier", "global", "los"}
    assert all(len(hexes) == 1 for hexes in seen.values()), seen
    assert seen["greed"] != seen["frontier"]


def test_titles_give_the_map_size_in_metres_and_the_readme_no_minutes(report):
    _, folder, saved = report
    titles = [t.get_text() for fig in saved.values() for t in fig.findobj(Text)]
    assert any("40\u00a0×\u00a040\u00a0m building" in t for t in titles)
    assert not any("size 40" in t for t in titles)
    assert "minutes" not in (folder / "README.md").read_text()


def test_time_axes_are_log_only_over_a_decade_and_stay_near_the_data(report):
    _, _, saved = report
    wide = saved["cactus/algorithms__building_40_2_together_global"].axes[0]  # cactus: 2 s .. 150 s
    assert wide.get_yscale() == "log"
    lo, hi = wide.get_ylim()
    assert 1.5 <= lo < 2 and 150 < hi <= 200
    narrow = saved["cactus/algorithms__building_40_2_together_los"].axes[0]  # 12 s .. 65 s
    assert narrow.get_yscale() == "linear" and 5 < narrow.get_ylim()[0] < 12
    ax = Figure().add_subplot()
    figures._time_axis(ax, "x", np.array([90.0, 150.0]), 0.1)  # 900-1,500 ticks: linear, not 10..10,000
    assert ax.get_xscale() == "linear" and 80 < ax.get_xlim()[0] < 90 and 150 < ax.get_xlim()[1] < 160


def test_comm_figures_pass_the_checker():
    x = np.array([-90.0, -35.0])
    band = comm_figures.Band(np.array([10.0, 20.0]), np.array([5.0, 15.0]), np.array([15.0, 25.0]))
    lines = [comm_figures.Line("greed", 0, x, {"ttt_or_max": band}), comm_figures.Line("frontier", 1, x,
                                                                                        {"ttt_or_max": band})]
    against = comm_figures.against_figure([comm_figures.Panel("20 × 20 m building", lines)],
                                          [("ttt_or_max", "time to target (s)")], "Sensitivity (dBm)",
                                          (x, ["-90", "-35"]), "against sensitivity", figures.WIDTHS["page"])
    ticks = np.arange(0, 500, 100)
    flat = comm_figures.Band(np.full(5, 30.0), np.full(5, 20.0), np.full(5, 40.0))
    over = comm_figures.over_time_figure([("missing", "missing (%)", [comm_figures.Series("greed", 0, ticks, flat, 6)]),
                                          ("age", "AoI age (s)", [comm_figures.Series("greed", 0, ticks, flat, 6)])],
                                         "20 × 20 m building", figures.WIDTHS["column"])
    for fig in (against, over):
        assert check_figure(fig) == []
    assert over.axes[0].get_xlim()[1] == pytest.approx(40.0)  # 400 ticks are 40 s


def test_the_checker_fails_a_figure_made_the_old_way():
    fig = Figure(figsize=(6.4, 4.2))
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    ax.plot([1, 2], [900, 1000], color="#1f77b4", gid=figures.GID + "greed")  # tab10 blue
    ax.plot([1, 2], [950, 990], color=figures.colour(1), gid=figures.GID + "greed")
    ax.plot([1, 2], [920, 960], color=figures.colour(1), gid=figures.GID + "frontier")  # as greed's second line
    ax.fill_between([1, 2], [0, 1], [1, 2])
    ax.set_yscale("log")
    ax.set_ylim(850, 1100)
    ax.set_xlabel("simulated time (minutes; 600 ticks = 1 min)")
    ax.set_ylabel("explored")
    fig.canvas.draw()
    problems = "\n".join(check_figure(fig))
    for needle in ("time not in seconds", "without a unit: 'explored'", "labels fewer than 3 ticks",
                   "does not say what it is", "not one colour of the palette", "look the same"):
        assert needle in problems


def test_cli_figure_width_column_is_recorded_and_sizes_the_pngs(tmp_path):
    runs = [FakeRun(alg, "global", rep, t) for alg, t in (("greed", 100), ("frontier", 200)) for rep in range(2)]
    results = write(tmp_path / "results", runs, spec_text=SPEC.replace('radio = ["global", "los"]', 'radio = ["global"]'))
    assert main(["campaign", "report", str(results), "-o", str(tmp_path / "rep"), "--figure-width", "column",
                 "--quiet"]) == 0
    assert "--figure-width column" in (tmp_path / "rep/README.md").read_text()
    png = Image.open(tmp_path / "rep/curves/algorithms__building_40_2_together_global.png")
    assert png.size[0] == round(figures.WIDTHS["column"] * 300)


def test_more_lines_than_colours_differ_in_dashes():
    """A sweep of 12 values: the ninth line repeats the first colour, dashed."""
    curves = [figures.Curve(f"v{k}", k, np.array([0, 10]), np.array([0.1, 0.5]), np.full(2, np.nan),
                            np.full(2, np.nan), 1, 0) for k in range(12)]
    fig = figures.curves_figure(curves, "sweep", 0.98, figures.WIDTHS["page"])
    assert check_figure(fig) == []
    same = [line for line in fig.axes[0].get_lines() if to_hex(line.get_color()) == figures.PALETTE[0].lower()]
    assert sorted(line.get_linestyle() for line in same) == ["-", "--"]
