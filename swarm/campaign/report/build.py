"""``build_report``: a results folder in, a report folder out (README.md, figures, tables, MAES CSVs).

Layout of the report folder::

    README.md                        everything below, linked, with the summary tables inline
    curves/<cmp>__<cell>.png|.pdf|.csv  explored % vs time, mean and 95 % band per line (csv: the plotted numbers)
    cactus/<cmp>__<cell>.png|.pdf    cactus + ECDF of the time to target
    paired/algorithms__<cell>.png|.pdf  per-replicate scatter for every pair of algorithms
    figures/<name>.png|.pdf|.csv     with --figures: the multi-panel figures of a layout file (layout.py)
    tables/summary.md|.tex|.csv      per cell and algorithm: runs, successes, DNF, ticks to target
    tables/pooled.md|.tex|.csv       every cell pooled, per dimension and pair of values: paired statistics
    tables/paired.md|.tex|.csv       per cell and algorithm pair: wins, ties, ratio a/b with its 95 % CI,
                                     rank-biserial r, Wilcoxon p and Holm's p (effects.py)
    tables/paired_<dim>.md|.tex|.csv the same for radio, comm, transport, robots, spawn when they vary
    tables/pairs.csv, pairs_<dim>.csv every pair of runs compared
    tables/comm_effect.md|.tex|.csv  per cell: mean ticks per radio model and their ordering
    tables/runs.csv                  every run with its ticks to target
    tables/failed.csv                failed runs and their errors
    maes-csv/*.csv                   with --maes-csv: one MAES statistics CSV per run (+ maes-csv-index.csv)
    files.txt                        what this report wrote

Every figure is in :mod:`.figures`' style (seconds, units, palette, 300 dpi) with a PDF copy beside it.
``<cmp>`` is the dimension compared inside a figure (``algorithms``, ``radio``, ``comm``; ``cells`` when
nothing varies) and ``<cell>`` the labels of every other shown dimension in grid order, e.g.
``curves/algorithms__building_150_16_together_multiwall.png``.
"""

from __future__ import annotations

import shlex
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from swarm.base.errors import InvalidInput
from swarm.results.schema import LOCALIZATION_RUN_COLUMNS

from ..store import ResultsStore
from . import comm, comm_figures, effects, figures, headline, stats, tables, units
from .contents import CommSection, FigureSet, LayoutFigure, PairedSection, Report
from .layout import FigureLayout, check_layout, load_layout
from .load import CampaignData, load
from .output import ReportWriter, slug
from .series import sample, sample_columns

COMPARE = ("algorithm", "radio", "comm")
PREFIX = {"algorithm": "algorithms", "radio": "radio", "comm": "comm", None: "cells"}
DEFAULT_TARGET = 0.98


class ReportProgress:
    """What :func:`build_report` tells a progress display: each stage as it starts, each file written."""

    def stage(self, name: str) -> None:
        pass

    def wrote(self, relative: str) -> None:
        pass


def check_target(target: Any) -> float:
    if isinstance(target, bool) or not isinstance(target, (int, float)) or not 0 < float(target) <= 1:
        raise InvalidInput("--target", target, "an explored fraction in (0, 1], e.g. 0.98")
    return float(target)


def command_line(results_dir: Path, report_dir: Path, target: float, maes_csv: bool, fmt: str,
                 figures_file: Path | None = None, cell_figures: bool = True, figure_width: str = "page") -> str:
    """The ``swarm`` command that builds this same report (what the README says made it)."""
    parts = ["swarm", "campaign", "report", str(results_dir), "-o", str(report_dir), "--target", f"{target:g}"]
    if figures_file is not None:
        parts += ["--figures", str(figures_file)]
    if not cell_figures:
        parts.append("--no-cell-figures")
    if maes_csv:
        parts.append("--maes-csv")
    if fmt != "png":
        parts += ["--format", fmt]
    if figure_width != "page":
        parts += ["--figure-width", figure_width]
    return shlex.join(parts)


def build_report(results_dir: str | Path, report_dir: str | Path, *, target: float = DEFAULT_TARGET,
                 maes_csv: bool = False, fmt: str = "png", figures_file: str | Path | None = None,
                 cell_figures: bool = True, figure_width: str = "page",
                 progress: "ReportProgress | None" = None) -> Path:
    """Write the report of ``results_dir`` into ``report_dir``; returns the path of its README.md.

    ``figures_file``: a figure layout (:mod:`.layout`) whose multi-panel figures are drawn first.
    ``cell_figures=False``: no per-cell curves, cactus and paired figures (tables and layout figures only;
    a 540-cell campaign has ~1,200 of them, ~70 MB: right for exploring, too much to publish).
    ``figure_width``: ``page`` (7.16 in, two journal columns) or ``column`` (3.5 in), :data:`.figures.WIDTHS`.
    ``progress``: told each stage as it starts and each file as it is written."""
    from .readme import render

    stage = progress.stage if progress is not None else (lambda name: None)

    target = check_target(target)
    if fmt not in figures.FORMATS:
        raise InvalidInput("--format", fmt, ", ".join(figures.FORMATS))
    if figure_width not in figures.WIDTHS:
        raise InvalidInput("--figure-width", figure_width, ", ".join(figures.WIDTHS))
    results_dir, report_dir = Path(results_dir), Path(report_dir)
    layout_figs = load_layout(figures_file) if figures_file is not None else ()
    stage("loading results")
    data = load(results_dir)
    if layout_figs:
        check_layout(layout_figs, {d: data.orders[d] for d in data.all_dims})  # a constant one too
    out = ReportWriter(report_dir, on_write=progress.wrote if progress is not None else None)
    store = ResultsStore(data.folder)
    dims = list(data.dims)
    ok = data.ok.reset_index(drop=True)
    cell_id = ok.groupby(dims, observed=True, sort=True).ngroup().to_numpy() if len(ok) else np.zeros(0, np.int64)
    stage("reading time series")
    sampled = sample(store, ok, cell_id, data.every, target)
    runs_t = stats.add_time_to_target(ok, target, sampled.first_at_target)
    column = stats.threshold_column(target)
    source = (f"the exact per-tick crossing recorded in column `{column}`" if column else
              f"the first time-series row at or above the target (rows every {data.every} ticks, so up to "
              f"{data.every - 1} ticks late)")
    figures_path = Path(figures_file) if figures_file is not None else None
    rep = Report(data=data, target=target,
                 command=command_line(results_dir, report_dir, target, maes_csv, fmt, figures_path, cell_figures,
                                      figure_width),
                 fmt=fmt, width=figures.WIDTHS[figure_width], runs_t=runs_t, ttt_source=source,
                 layout_file=figures_path.name if figures_path is not None else None, cell_figures=cell_figures)
    if len(ok):
        stage("figures")
        _layout_figures(rep, out, ok.assign(cell=cell_id), sampled, layout_figs)
        if cell_figures:
            _figures(rep, out, ok.assign(cell=cell_id), sampled)
        stage("tables and paired statistics")
        _summary(rep, out)
        _paired(rep, out)
        _comm(rep, out)
        _communication(rep, out, ok.assign(cell=cell_id), store)
        _finding(rep)
    _run_tables(rep, out)
    _maps(rep, out)
    _map_quality(rep, out)
    _collisions(rep, out)
    _benchmark(rep, out)
    _notes(rep)
    if maes_csv:
        from ..maes_csv import write_runs

        stage("MAES CSVs")
        rep.maes = write_runs(store, data, out, "maes-csv")
    rep.written = list(out.written)
    readme = out.write("README.md", render(rep))
    out.finish()
    return readme


# ------------------------------------------------------------------------------------------ parts ----
def _finding(rep: Report) -> None:
    """The first page's sentence and figure: exploration time and communication against the radio model
    when it varies, else the first curves figure comparing algorithms."""
    rep.finding = headline.finding(rep.runs_t, rep.data.orders, rep.target)
    if rep.finding is None:
        return
    against = [(t, path) for t, path, _ in rep.communication.against if "/against_radio." in path] \
        if rep.communication is not None else []
    curves = [(f.title, f.curves) for f in rep.figures if f.compare == "algorithm"]
    rep.finding_figure = (against or curves or [None])[0]


def comparisons(data: CampaignData) -> list[str | None]:
    found: list[str | None] = [d for d in (*COMPARE, *data.axes) if d in data.dims and data.varies(d)]
    return found or [None]  # nothing compared: one figure per cell


def map_size(size: str) -> str:
    """A map size label in metres (a tile is 1 m, maps/model.py): '150' -> '150 × 150 m', '120x80' ->
    '120 × 80 m'; another label is kept."""
    parts = size.lower().split("x")
    if not all(p.strip().isdigit() for p in parts) or len(parts) > 2:
        return f"size {size}"
    w, h = (parts * 2)[:2]
    return f"{w.strip()}\u00a0×\u00a0{h.strip()}\u00a0m"  # no-break spaces: a wrapped title keeps it whole


def describe(values: dict[str, str]) -> str:
    """A figure title from cell labels, e.g. '150 × 150 m building, 16 robots, spawn together, radio
    multiwall' (the map and its size in one phrase)."""
    words = {"map": "{}", "robots": "{} robots", "spawn": "spawn {}", "algorithm": "algorithm {}",
             "radio": "radio {}", "comm": "comm {}", "transport": "transport {}"}
    parts = []
    for d, v in values.items():
        if d == "size":
            parts.append(f"{map_size(v)} {values['map']}" if "map" in values else map_size(v))
        elif not (d == "map" and "size" in values):
            parts.append("1 robot" if (d, v) == ("robots", "1") else words[d].format(v) if d in words else f"{d} {v}")
    return ", ".join(parts)


class _Names:
    """File-name stems, made unique if two label sets slug to the same text."""

    def __init__(self) -> None:
        self.used: set[str] = set()

    def __call__(self, prefix: str, values: dict[str, str]) -> str:
        base = f"{prefix}__" + "_".join(slug(v) for v in values.values())
        name, k = base, 2
        while name in self.used:
            name, k = f"{base}-{k}", k + 1
        self.used.add(name)
        return name


def _curve_rows(label: str, ticks: np.ndarray, mean: np.ndarray, lo: np.ndarray, hi: np.ndarray,
                n: np.ndarray) -> pd.DataFrame:
    """The numbers a curve plots, as the CSV written beside its figure."""
    return pd.DataFrame({"line": label, "tick": ticks, "seconds": units.seconds(ticks),
                         "explored_mean_pct": np.round(100 * mean, 4), "ci95_low_pct": np.round(100 * lo, 4),
                         "ci95_high_pct": np.round(100 * hi, 4), "runs": n})


def _figures(rep: Report, out: ReportWriter, ok: pd.DataFrame, sampled: Any) -> None:
    data, dims, fmt = rep.data, list(rep.data.dims), rep.fmt
    cells = ok.drop_duplicates("cell").sort_values("cell")[[*dims, "cell"]]
    names = _Names()
    for compare in comparisons(data):
        fig_dims = [d for d in dims if d != compare]
        for keys, grp in cells.groupby(fig_dims, observed=True, sort=True):
            if compare is not None and len(grp) < 2:
                continue  # a single line compares nothing
            values = dict(zip(fig_dims, (str(k) for k in keys)))
            name, title = names(PREFIX.get(compare) or slug(str(compare)), values), describe(values)
            curves, times, rows = [], [], []
            for _, cell in grp.iterrows():
                c = int(cell["cell"])
                label = str(cell[compare]) if compare else "all runs"
                colour = data.orders[compare].index(label) if compare else 0
                members = sampled.cell_rows[c]
                mean, lo, hi, n = stats.mean_band(sampled.cell_values[c])
                ttt = rep.runs_t["ttt"].to_numpy()[members]
                curves.append(figures.Curve(label, colour, sampled.cell_ticks[c], mean, lo, hi, len(members),
                                            int(np.isfinite(ttt).sum())))
                times.append(figures.Times(label, colour, ttt))
                rows.append(_curve_rows(label, sampled.cell_ticks[c], mean, lo, hi, n))
            max_ticks = float(rep.runs_t["max_ticks"].to_numpy()[np.concatenate(
                [sampled.cell_rows[int(c)] for c in grp["cell"]])].max())
            figures.write_figure(out.write, f"curves/{name}",
                                 figures.curves_figure(curves, title, rep.target, rep.width), fmt)
            out.write(f"curves/{name}.csv", tables.csv_text(pd.concat(rows, ignore_index=True)))
            figures.write_figure(out.write, f"cactus/{name}",
                                 figures.cactus_figure(times, title, rep.target, max_ticks, rep.width), fmt)
            rep.figures.append(FigureSet(compare, title, f"curves/{name}.{fmt}", f"cactus/{name}.{fmt}",
                                         f"curves/{name}.csv"))


def _pooled_curve(rep: Report, sampled: Any, cells: list[int], label: str, colour: int) -> tuple[figures.Curve, pd.DataFrame]:
    """One line from the runs of several cells: each cell's grid resampled onto a common grid (value at g =
    the last value at a tick <= g; a finished run holds its final value), then mean and band over all runs."""
    ticks = [sampled.cell_ticks[c] for c in cells]
    end = max(int(t[-1]) for t in ticks)
    step = max(int(t[1] - t[0]) if len(t) > 1 else rep.data.every for t in ticks)
    grid = np.arange(0, end + step, step, dtype=np.int64)
    grid[-1] = min(grid[-1], end) if len(grid) > 1 else grid[-1]
    blocks = [sampled.cell_values[c][:, np.searchsorted(t, grid, side="right") - 1] for c, t in zip(cells, ticks)]
    values = np.concatenate(blocks, axis=0)
    members = np.concatenate([sampled.cell_rows[c] for c in cells])
    mean, lo, hi, n = stats.mean_band(values)
    ttt = rep.runs_t["ttt"].to_numpy()[members]
    curve = figures.Curve(label, colour, grid, mean, lo, hi, len(members), int(np.isfinite(ttt).sum()))
    return curve, _curve_rows(label, grid, mean, lo, hi, n)


def _layout_figures(rep: Report, out: ReportWriter, ok: pd.DataFrame, sampled: Any,
                    layout: tuple[FigureLayout, ...]) -> None:
    data, fmt = rep.data, rep.fmt
    cells = ok.drop_duplicates("cell")
    for fig in layout:
        panels, rows, titles = [], [], []
        for k, panel in enumerate(fig.panels):
            chosen = cells
            for dim, value in panel.fixed:
                chosen = chosen[chosen[dim].astype(str) == value]
            pooled = [d for d in data.dims if d != panel.compare and d not in dict(panel.fixed) and data.varies(d)]
            title = (panel.title or describe({d: v for d, v in panel.fixed})) + (
                f" (pooled over {', '.join(pooled)})" if pooled else "")
            curves = []
            for label in data.orders[panel.compare]:
                members = chosen[chosen[panel.compare].astype(str) == label]["cell"].astype(int).tolist()
                if members:
                    curve, frame = _pooled_curve(rep, sampled, members, label, data.orders[panel.compare].index(label))
                    curves.append(curve)
                    rows.append(frame.assign(panel=k + 1).loc[:, ["panel", *frame.columns]])
            panels.append((title, curves))
            titles.append(title)
        if not any(curves for _, curves in panels):
            rep.notes.append(f"Figure `{fig.name}` of the layout has no finished runs to draw.")
            continue
        figures.write_figure(out.write, f"figures/{fig.name}",
                             figures.panels_figure(panels, fig.title, rep.target, rep.width, fig.columns), fmt)
        out.write(f"figures/{fig.name}.csv", tables.csv_text(pd.concat(rows, ignore_index=True)))
        rep.layout_figures.append(LayoutFigure(fig.name, fig.title, f"figures/{fig.name}.{fmt}",
                                               f"figures/{fig.name}.csv", titles))


def _summary(rep: Report, out: ReportWriter) -> None:
    dims = [d for d in rep.data.dims if d != "algorithm"] + ["algorithm"]
    df = stats.summary(rep.runs_t, dims)
    table = tables.summary_table(df, dims)
    pct = f"{100 * rep.target:g} %"
    _write_table(out, "summary", df, table, f"Ticks to {pct} explored per cell and algorithm "
                 f"(campaign {rep.data.name}; means, medians and quartiles Q1–Q3 over successful runs; DNF: target "
                 "not reached; a tick is 0.1 s).", tables.summary_latex_table(df, dims))
    rep.summary, rep.summary_rows = table, len(df)


NOUN = {"algorithm": "algorithms", "radio": "radio models", "comm": "comm settings", "transport": "transports",
        "robots": "robot counts", "spawn": "spawn modes"}


def noun(dim: str) -> str:
    """What the values of a dimension are called in captions (an axis by its name: 'values of comm.loss')."""
    return NOUN.get(dim, f"values of {dim}")
READING = ("Pairs share map and start poses (same replicate). Ticks to target, a DNF counted at max_ticks; a "
           "pair of two DNFs is a tie. a/b: median over maps of the ratio of ticks, a to b, with a 95 % percentile "
           "bootstrap interval. r: matched-pairs rank-biserial correlation, +1 when a is slower on every map. p: "
           "two-sided Wilcoxon signed-rank test on the log ratios, ties dropped; not tested (n/a) below "
           f"{effects.MIN_UNITS} maps that differ.")


def _paired(rep: Report, out: ReportWriter) -> None:
    """Per varying dimension: the per-cell table of paired statistics; then every cell pooled."""
    dims = list(rep.data.dims)
    pooled = []
    for k, dim in enumerate(d for d in (*effects.PAIRED_DIMS, *rep.data.axes) if d in dims and rep.data.varies(d)):
        cell = [d for d in dims if d != dim]
        pairs = stats.pair_runs(rep.runs_t, dims, dim)
        single = 0
        if effects.talk_only(dim) and "robots" in cell and len(pairs):
            lone = effects.single_robot(pairs)
            single = len(pairs.loc[lone, cell].drop_duplicates())
            pairs = pairs[~lone].reset_index(drop=True)
        if pairs.empty:
            continue
        df = effects.summarise(pairs, [*cell, "a", "b"], cell=cell)
        tested, nominal, holm = effects.tally(df)
        name = "paired" if dim == "algorithm" else f"paired_{slug(dim)}"
        family = (f"Holm family: the {tested or ''} tested comparisons of this table (every pair of {noun(dim)} "
                  f"in every cell){'' if tested else '; none here'}.").replace("the  tested", "the tested")
        if single:
            family += f" The {single} 1-robot cells are left out: a lone robot talks to no one."
        caption = f"Paired comparison of {noun(dim)} per cell. {READING} {family}"
        table = effects.effects_table(df, [*cell, "a", "b"])
        _write_table(out, name, df, table, caption)
        out.write(f"tables/{'pairs' if dim == 'algorithm' else f'pairs_{slug(dim)}'}.csv", tables.csv_text(pairs))
        rep.paired.append(PairedSection(dim, name, table, caption, family, len(df), tested, nominal, holm, single))
        order = {lab: i for i, lab in enumerate(rep.data.orders[dim])}
        pooled.append(pd.DataFrame({
            "dimension": dim, "a": pairs["a"].astype(str).to_numpy(), "b": pairs["b"].astype(str).to_numpy(),
            "cell": pairs.groupby(cell, observed=True, sort=False).ngroup().to_numpy(),
            **{u: pairs[u].to_numpy() for u in effects.UNITS},
            **{c: pairs[c].to_numpy() for c in ("t_a", "t_b", "ok_a", "ok_b", "winner")},
            "_dim": k, "_a": pairs["a"].astype(str).map(order).to_numpy(),
            "_b": pairs["b"].astype(str).map(order).to_numpy()}))
        if dim == "algorithm" and rep.cell_figures:
            _paired_figures(rep, out, pairs, cell)
    if pooled:
        frame = pd.concat(pooled, ignore_index=True).sort_values(["_dim", "_a", "_b"], kind="stable")
        df = effects.summarise(frame, ["dimension", "a", "b"], cell=["dimension", "cell"], sort=False)
        tested, nominal, holm = effects.tally(df)
        family = (f"Holm family: the {tested or ''} tested comparisons of this table (every pair of values of "
                  f"every dimension){'' if tested else '; none here'}.").replace("the  tested", "the tested")
        caption = (f"Paired comparisons with every cell pooled, per dimension and pair of values. {READING} Each "
                   "map (map, size, replicate) counts once, with the mean log ratio of its pairs: the cells that "
                   f"share a map are not independent. {family}")
        table = effects.effects_table(df, ["dimension", "a", "b"], cells=True, maps=True)
        _write_table(out, "pooled", df, table, caption)
        rep.pooled = PairedSection(None, "pooled", table, caption, family, len(df), tested, nominal, holm)


def _paired_figures(rep: Report, out: ReportWriter, pairs: pd.DataFrame, cell: list[str]) -> None:
    names = _Names()
    max_ticks = float(rep.runs_t["max_ticks"].max())
    for keys, grp in pairs.groupby(cell, observed=True, sort=True):
        values = dict(zip(cell, (str(k) for k in keys)))
        panels = []
        for (a, b), pg in grp.groupby(["a", "b"], observed=True, sort=True):
            w = pg["winner"]
            panels.append(figures.PairPanel(str(a), str(b), pg["t_a"].to_numpy(float), pg["t_b"].to_numpy(float),
                                            (~pg["ok_a"] | ~pg["ok_b"]).to_numpy(bool), int((w == "a").sum()),
                                            int((w == "b").sum()), int((w == "tie").sum())))
        name = names("algorithms", values)
        path = figures.write_figure(out.write, f"paired/{name}",
                                    figures.paired_figure(panels, describe(values), max_ticks, rep.width), rep.fmt)
        rep.paired_figures.append((describe(values), path))


def _comm(rep: Report, out: ReportWriter) -> None:
    if "radio" not in rep.data.dims or not rep.data.varies("radio"):
        return
    dims = list(rep.data.dims)
    cell = [d for d in dims if d != "radio"]
    ok = rep.runs_t
    models = dict(zip(ok["radio"].astype(str), ok["radio_model"].astype(str)))
    df = stats.comm_effect(ok, dims, models)
    labels = [lab for lab in rep.data.orders["radio"] if f"mean:{lab}" in df]
    rep.comm = tables.comm_table(df, cell, labels)
    rep.comm_unexpected = sum(1 for v in df["as_expected"] if v is False)  # None: no expectation
    rep.comm_rows = len(df)
    rep.comm_compared = sum(1 for v in df["as_expected"] if v in (True, False))
    rep.comm_single = int(effects.single_robot(df).sum()) if "robots" in df else 0
    _write_table(out, "comm_effect", df, rep.comm, "Mean ticks to target per radio model (DNF counted at max "
                 "ticks) and their ordering; expected: global <= material-aware (multiwall, maes) <= LOS "
                 "(not judged in 1-robot cells, where every model gives the same run).")


AGAINST_METRICS = (("ttt_or_max", "time to target (s)\n(DNF = max)"), ("missing_pct", "missing (%)"),
                   ("aoi_age_s", "AoI age (s)"), ("delivered_pct", "delivered (%)"))
def _percent(fraction: np.ndarray) -> np.ndarray:
    return 100.0 * fraction


OVER_TIME: tuple[tuple[str, str, Callable[[np.ndarray], np.ndarray], str], ...] = (
    ("missing_free_mean", "missing (%)", _percent, "share of the team's known free cells a robot misses"),
    ("aoi_age_mean", "AoI age (s)", units.seconds, "age of a robot's information about the others"),
    ("biggest_group", "biggest group (%)", _percent, "the biggest communication group's share of the robots"))
"""Comm metrics over time: column, y label, conversion from the recorded unit (fraction, ticks), panel title."""
AGAINST_TICKS = ("ttt_or_max",)
"""Metrics of :data:`AGAINST_METRICS` in ticks: drawn in seconds."""
MAX_AGAINST_PANELS = 6


def _communication(rep: Report, out: ReportWriter, ok: pd.DataFrame, store: ResultsStore) -> None:
    """The communication section: per-cell and pooled means, paired effects with their findings, and the
    figures (:mod:`.comm`)."""
    data = rep.data
    if not comm.has_comm(rep.runs_t):
        rep.communication = CommSection(available=False)
        return
    frame = comm.derive(rep.runs_t)
    talk = comm.talk_dims(data.dims, {d: data.varies(d) for d in data.dims})
    sec = rep.communication = CommSection(available=True, talk=talk)
    multi = frame[comm.robots_of(frame) > 1]
    sec.single_robot_runs = len(frame) - len(multi)
    causes = comm.causes_seen(frame)
    by = [d for d in data.dims if d != "algorithm"] + ["algorithm"]
    df = comm.cell_means(frame, by)
    sec.cells, sec.cell_rows = comm.means_table(df, by, causes), len(df)
    _write_table(out, "comm", df, sec.cells, "Communication per cell and algorithm: means over the cell's runs. "
                 + COMM_READING)
    pooled = [comm.cell_means(multi, [dim, "algorithm"]).rename(columns={dim: "value"}).assign(dimension=dim)
              for dim in talk] if talk else []
    if pooled:
        df = pd.concat(pooled, ignore_index=True)
        df = df[["dimension", "value", *[c for c in df.columns if c not in ("dimension", "value")]]]
        sec.pooled, sec.pooled_rows = comm.means_table(df, ["dimension", "value", "algorithm"], causes), len(df)
        _write_table(out, "comm_pooled", df, sec.pooled, "Communication per compared value and algorithm, every "
                     "other dimension pooled (multi-robot runs). " + COMM_READING)
    eff = comm.paired_effects(frame, list(data.dims), talk, data.orders)
    if len(eff):
        sec.effects, sec.effects_rows = comm.effects_table(eff), len(eff)
        sec.findings = comm.findings(eff)
        _write_table(out, "comm_effects", eff, sec.effects, EFFECTS_CAPTION)
    for dim in talk:
        _against_figure(rep, out, multi, dim)
    if rep.cell_figures and len(multi):
        _over_time_figures(rep, out, ok, store, talk[0] if talk else "algorithm")


COMM_READING = ("Delivered %: the share of the other robots each message reached; lost %: failed deliveries of "
                "every transmission (relayed copies included), per cause; "
                "biggest group and all connected: over the recorded rows; contact gap: seconds since a robot "
                "last received anything; missing: share of the team's known free cells a robot does not know; "
                "AoI age: how old a robot's information about the others is (seconds since it last merged "
                "their maps); means over robots and rows, then runs.")
EFFECTS_CAPTION = ("Each value against the first (reference) value of its dimension, per algorithm, every other "
                   "dimension pooled; pairs share map and start poses; 1-robot runs left out. Ticks b/a: median "
                   "over maps of the ratio of ticks to target with its 95 % bootstrap interval; p (Holm): "
                   "Wilcoxon signed-rank on the log ratios, Holm over the rows of this table. Each metric a → b: "
                   "means over the paired runs; the CSV has the median paired difference per map and its "
                   "Wilcoxon p with Holm's correction per metric over the rows.")


def _numeric(labels: list[str]) -> np.ndarray | None:
    try:
        return np.array([float(v) for v in labels])
    except ValueError:
        return None


def _against_figure(rep: Report, out: ReportWriter, multi: pd.DataFrame, dim: str) -> None:
    """Exploration time and the key comm metrics against the values of ``dim``, a line per algorithm, a
    column per map and size (per map when there are more than :data:`MAX_AGAINST_PANELS`)."""
    data = rep.data
    labels = [lab for lab in data.orders[dim] if (multi[dim].astype(str) == lab).any()]
    if len(labels) < 2:
        return
    values = _numeric(labels)
    x = values if values is not None else np.arange(len(labels), dtype=float)
    # only the cells that have every value (an [[include]] may add a value to some cells only)
    keys = [d for d in data.dims if d != dim] + ["replicate"]
    complete = multi.groupby(keys, observed=True)[dim].transform("nunique") == len(labels)
    partial = not complete.all()
    multi = multi[complete]
    if multi.empty:  # no cell has run every value yet (a shard, a campaign in progress): nothing to draw
        return
    panel_dims = ["map", "size"]
    if len(multi.groupby(panel_dims, observed=True)) > MAX_AGAINST_PANELS:
        panel_dims = ["map"]
    pooled = [d for d in data.dims if d not in (*panel_dims, dim, "algorithm") and data.varies(d)]
    panels, rows = [], []
    for keys, grp in multi.groupby(panel_dims, observed=True, sort=True):
        keys = keys if isinstance(keys, tuple) else (keys,)
        title = describe(dict(zip(panel_dims, map(str, keys))))
        lines = []
        for alg in data.orders["algorithm"]:
            runs = grp[grp["algorithm"].astype(str) == alg]
            if runs.empty:
                continue
            line = comm_figures.Line(alg, data.orders["algorithm"].index(alg), x)
            for key, _ in AGAINST_METRICS:
                stacked = np.full((max(runs[dim].astype(str).value_counts().max(), 1), len(labels)), np.nan)
                for j, lab in enumerate(labels):
                    v = runs.loc[runs[dim].astype(str) == lab, key].to_numpy(float)
                    stacked[:len(v), j] = v
                mean, lo, hi, n = stats.mean_band(stacked)
                shown = units.seconds if key in AGAINST_TICKS else np.asarray  # the CSV keeps ticks
                line.bands[key] = comm_figures.Band(shown(mean), shown(lo), shown(hi))
                rows.append(pd.DataFrame({"panel": title, "algorithm": alg, "metric": key, "value": labels,
                                          "mean": mean, "ci95_low": lo, "ci95_high": hi, "runs": n}))
            lines.append(line)
        panels.append(comm_figures.Panel(title, lines))
    name = f"comm/against_{slug(dim)}"
    what = tables.header(dim) if dim not in ("radio", "comm") else {"radio": "radio model", "comm": "comm setting"}[dim]
    left_out = "1-robot runs" + (" and cells without every value" if partial else "") + " left out"
    title = f"Exploration time and communication against {what} (" + (
        f"pooled over {', '.join(pooled)}; " if pooled else "") + f"{left_out})"
    xlabel = tables.header(dim) if dim not in ("radio", "comm") else what
    figures.write_figure(out.write, name, comm_figures.against_figure(panels, AGAINST_METRICS, xlabel, (x, labels),
                                                                      title, rep.width), rep.fmt)
    out.write(f"{name}.csv", tables.csv_text(pd.concat(rows, ignore_index=True)))
    rep.communication.against.append((title, f"{name}.{rep.fmt}", f"{name}.csv"))


def _over_time_figures(rep: Report, out: ReportWriter, ok: pd.DataFrame, store: ResultsStore, compare: str) -> None:
    """Per cell (every dimension but ``compare``), multi-robot cells only: missing share, AoI age and the
    biggest group over time, a line per value of ``compare``."""
    data = rep.data
    columns = [c for c, _, _, _ in OVER_TIME]
    sampled = sample_columns(store, ok, ok["cell"].to_numpy(), data.every, columns)
    cells = ok.drop_duplicates("cell").sort_values("cell")
    cells = cells[comm.robots_of(cells) > 1]
    fig_dims = [d for d in data.dims if d != compare]
    names = _Names()
    for keys, grp in cells.groupby(fig_dims, observed=True, sort=True):
        values = dict(zip(fig_dims, (str(k) for k in keys)))
        panels = []
        for column, ylabel, scale, panel_title in OVER_TIME:
            series = []
            for _, cell in grp.iterrows():
                c = int(cell["cell"])
                sampled_c = sampled[column]
                mean, lo, hi, _ = stats.mean_band(scale(sampled_c.cell_values[c].astype(np.float64)))
                label = str(cell[compare])
                series.append(comm_figures.Series(label, data.orders[compare].index(label), sampled_c.cell_ticks[c],
                                                  comm_figures.Band(mean, lo, hi), len(sampled_c.cell_rows[c])))
            panels.append((panel_title, ylabel, series))
        title = describe(values)
        name = figures.write_figure(out.write, f"comm/{names(PREFIX.get(compare) or slug(compare), values)}",
                                    comm_figures.over_time_figure(panels, title, rep.width), rep.fmt)
        rep.communication.over_time.append((title, name))


MAP_QUALITY = (("pose_error_m", "Pose error (m)", "{:.2f}"), ("false_free_share", "False free (%)", "pct"),
               ("false_occupied_share", "False occupied (%)", "pct"), ("wall_offset_m", "Wall offset (m)", "{:.2f}"),
               ("explored_correct", "Explored correctly (%)", "pct"))


def _map_quality(rep: Report, out: ReportWriter) -> None:
    """With a localisation model on some runs: per cell, the medians of the pose error and the map-quality
    columns over its runs (docs/localization.md), in ``tables/map_quality``."""
    data = rep.data
    runs = data.runs[data.runs["status"] == "ok"]
    columns = [c for c, _, _ in MAP_QUALITY if c in runs and runs[c].notna().any()]
    if not columns:
        return
    dims = [d for d in data.all_dims if runs[d].nunique() > 1] or list(data.all_dims[:1])
    df = runs.groupby(dims, observed=True, sort=True)[columns].median().reset_index()
    df.insert(len(dims), "runs", runs.groupby(dims, observed=True, sort=True).size().to_numpy())
    fmt = {c: f for c, _, f in MAP_QUALITY}
    names = {c: n for c, n, _ in MAP_QUALITY}

    def show(c: str, v: Any) -> str:
        if pd.isna(v):
            return "–"
        return f"{100 * v:.1f}" if fmt[c] == "pct" else fmt[c].format(v)

    table = tables.Table([*(tables.header(d) for d in dims), "Runs", *(names[c] for c in columns)],
                         [[*(str(r[d]) for d in dims), str(int(r["runs"])), *(show(c, r[c]) for c in columns)]
                          for _, r in df.iterrows()],
                         [False] * len(dims) + [True] * (1 + len(columns)))
    _write_table(out, "map_quality", df, table, "Localisation and map quality: medians over each cell's runs "
                                                "(runs without a localisation model show –)")
    rep.map_quality, rep.map_quality_rows = table, len(df)


COLLISIONS = (("collisions_wall", "Robot-wall"), ("collisions_robot", "Robot-robot"))


def _collisions(rep: Report, out: ReportWriter) -> None:
    """Per cell, the medians of the contacts begun with walls and with other robots per robot-hour of simulated
    time (``tables/collisions``); skipped for results older than the split (no columns) and for runs without a
    contact."""
    data = rep.data
    runs = data.runs[data.runs["status"] == "ok"]
    columns = [c for c, _ in COLLISIONS if c in runs and runs[c].notna().any()]
    if not columns or not runs[columns].fillna(0).to_numpy().any():
        return
    hours = pd.to_numeric(runs["robots"], errors="coerce") * units.seconds(runs["ticks"]) / 3600
    rates = pd.DataFrame({c: runs[c] / hours.where(hours > 0) for c in columns})
    dims = [d for d in data.all_dims if runs[d].nunique() > 1] or list(data.all_dims[:1])
    rates[dims] = runs[dims]
    df = rates.groupby(dims, observed=True, sort=True)[columns].median().reset_index()
    df.insert(len(dims), "runs", rates.groupby(dims, observed=True, sort=True).size().to_numpy())
    names = dict(COLLISIONS)
    table = tables.Table([*(tables.header(d) for d in dims), "Runs", *(names[c] for c in columns)],
                         [[*(str(r[d]) for d in dims), str(int(r["runs"])),
                           *("–" if pd.isna(r[c]) else f"{r[c]:.0f}" for c in columns)] for _, r in df.iterrows()],
                         [False] * len(dims) + [True] * (1 + len(columns)))
    _write_table(out, "collisions", df, table, "Contacts begun per robot-hour of simulated time: medians over "
                                               "each cell's runs (a robot-robot contact counts for both robots)")
    rep.collisions, rep.collisions_rows = table, len(df)


BENCHMARK = (("t90_s", "T90 (s)", "{:.0f}"), ("t99_s", "T99 (s)", "{:.0f}"),
             ("path_length_mean_m", "Path per robot (m)", "{:.1f}"), ("path_length_cv", "Path CV", "{:.2f}"),
             ("overlap_rate", "Overlap", "{:.2f}"), ("coverage_spread", "Coverage spread", "{:.3f}"),
             ("all_connected_share", "All connected", "{:.2f}"), ("biggest_group_mean", "Largest cluster", "{:.2f}"))
"""The benchmark table's columns (docs/benchmark-metrics.md): name in ``tables/benchmark.csv``, header, format."""


def _benchmark(rep: Report, out: ReportWriter) -> None:
    """Per cell, the medians of the field's benchmark metrics (``tables/benchmark``): Explore-Bench's times to 90 %
    and 99 % explored, path length per robot and its spread, overlap rate and coverage spread, MAES's
    all-connected and largest-cluster shares. A run that never reached 90 % (99 %) counts as never in the
    median (– when half of a cell's runs did not). Skipped for results older than the overlap column."""
    data = rep.data
    runs = data.runs[data.runs["status"] == "ok"]
    if runs.empty or "overlap_rate" not in runs or not runs["overlap_rate"].notna().any():
        return
    values = pd.DataFrame({f"{t}_s": units.seconds(runs[t].astype(float).fillna(np.inf)) for t in ("t90", "t99")},
                          index=runs.index)
    for col, _, _ in BENCHMARK[2:]:
        values[col] = runs[col].astype(float)
    dims = [d for d in data.all_dims if runs[d].nunique() > 1] or list(data.all_dims[:1])
    values[dims] = runs[dims]
    columns = [c for c, _, _ in BENCHMARK]
    df = values.groupby(dims, observed=True, sort=True)[columns].median().reset_index()
    df.insert(len(dims), "runs", values.groupby(dims, observed=True, sort=True).size().to_numpy())
    table = tables.Table([*(tables.header(d) for d in dims), "Runs", *(h for _, h, _ in BENCHMARK)],
                         [[*(str(r[d]) for d in dims), str(int(r["runs"])),
                           *("–" if pd.isna(r[c]) or np.isinf(r[c]) else fmt.format(r[c]) for c, _, fmt in BENCHMARK)]
                          for _, r in df.iterrows()],
                         [False] * len(dims) + [True] * (1 + len(BENCHMARK)))
    _write_table(out, "benchmark", df.replace([np.inf], np.nan), table,
                 "Benchmark metrics (Explore-Bench, MAES): medians over each cell's runs; T90/T99 in simulated "
                 "seconds, – when half of the runs did not reach the fraction")
    rep.benchmark, rep.benchmark_rows = table, len(df)


def _maps(rep: Report, out: ReportWriter) -> None:
    """The maps the campaign ran on (``figures/maps-*``): what each map value looks like."""
    from . import mapfigs

    for title, panels in mapfigs.campaign_maps(rep.data):
        stem = f"figures/maps-{slug(title)}"
        fig = mapfigs.map_figure(title, panels, rep.width)
        rep.map_figures.append((title, figures.write_figure(out.write, stem, fig, rep.fmt)))


def _write_table(out: ReportWriter, name: str, df: pd.DataFrame, table: tables.Table, caption: str,
                 latex_table: tables.Table | None = None) -> None:
    """Markdown, LaTeX (``latex_table`` when a paper shows fewer columns) and CSV of one table."""
    out.write(f"tables/{name}.md", f"*{caption}*\n\n" + tables.markdown(table))
    out.write(f"tables/{name}.tex", tables.latex(latex_table or table, caption, f"tab:{name.replace('_', '-')}"))
    out.write(f"tables/{name}.csv", tables.csv_text(df))


def _run_tables(rep: Report, out: ReportWriter) -> None:
    data = rep.data
    cols = ["key", *data.all_dims, "replicate", "status", "stop_reason", "ticks", "max_ticks", "explored", "map_seed"]
    cols += [c for c in ("collisions_wall", "collisions_robot", *LOCALIZATION_RUN_COLUMNS, "swarm_version")
             if data.runs[c].notna().any()]   # the collision split, a localisation model, the code's version
    runs = data.runs[cols].merge(rep.runs_t[["key", "ttt", "success"]], on="key", how="left")
    runs["success"] = runs["success"].fillna(False).astype(bool)
    out.write("tables/runs.csv", tables.csv_text(runs.rename(columns={"ttt": "ticks_to_target"})))
    failed = data.failed[["key", *data.all_dims, "replicate", "error"]]
    out.write("tables/failed.csv", tables.csv_text(failed))


def _notes(rep: Report) -> None:
    ok = rep.runs_t
    short = ok[pd.to_numeric(ok["explored_target"], errors="coerce") < rep.target - 1e-12]
    if len(short):
        rep.notes.append(f"{len(short)} runs stop at `stop.explored` = "
                         f"{', '.join(f'{v:g}' for v in sorted(short['explored_target'].unique()))}, below the "
                         f"target {rep.target:g}: they stop before reaching it and count as DNF. Use `--target` "
                         f"at or below the campaign's stop rule.")
    if rep.data.spec_error:
        rep.notes.append(f"campaign.toml could not be read by this installation ({rep.data.spec_error}); grid "
                         f"order follows the data and pending runs are unknown.")
