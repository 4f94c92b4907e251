"""The report's README.md: what was run, what came out, every figure and table linked, and how the numbers
were computed (so a reader can trust or dispute them without reading this code)."""

from __future__ import annotations

import math

import pandas as pd

from . import comm, effects, tables
from .contents import PairedSection, Report

INLINE_ROWS = 300
"""Tables longer than this are linked, not inlined (a 54,000-run campaign has ~1,600 summary rows)."""
EMBED_FIGURES = 24
"""Up to this many curve figures are shown inline; more are listed as links."""
FAILED_SHOWN = 50
FILE_NOTES = {"tables/runs.csv": ": every committed run with its cell, stop reason and ticks to target",
              "tables/map_quality.csv": ": pose error and map quality per cell (runs with a localisation model)",
              "tables/collisions.csv": ": robot-wall and robot-robot contacts per robot-hour per cell",
              "tables/benchmark.csv": ": Explore-Bench and MAES benchmark metrics per cell",
              "tables/pairs.csv": ": every pair of runs compared", "tables/failed.csv": ": failed runs and errors"}
SECTION = {"algorithm": "Algorithms compared", "radio": "Radio models compared", "comm": "Comm settings compared",
           None: "Every cell"}


def section(compare: str | None) -> str:
    """The heading of a comparison's figures (an axis: 'Values of radio.sensitivity_dbm compared')."""
    return SECTION.get(compare, f"Values of {compare} compared")


def render(rep: Report) -> str:
    parts = [_head(rep), _finding(rep), _runs(rep), _campaign(rep), _maps(rep), _layout(rep), _summary(rep), _curves(rep),
             _cactus(rep), _paired(rep), _comm(rep), _communication(rep), _map_quality(rep), _collisions(rep),
             _benchmark(rep), _failed(rep), _maes(rep), _method(rep), _files(rep)]
    return "\n".join(p for p in parts if p).rstrip() + "\n"


def _pct(x: float) -> str:
    return f"{100 * x:g} %"


def _head(rep: Report) -> str:
    d = rep.data
    lines = [f"# Campaign report: {d.name}", ""]
    if d.description:
        lines += [d.description, ""]
    lines += [f"- Made by: `{rep.command}`",
              f"- Target: **{_pct(rep.target)} explored**. Time to target is {rep.ttt_source}; a run that never "
              f"reaches it is DNF (did not finish), as in MAES.",
              "- Time: a tick is 0.1 simulated seconds. Every figure is in simulated seconds; tables count "
              "ticks (their headers say so).",
              "- Figures: 300 dpi with a PDF copy beside each, sized for "
              + ("one journal column (3.5 in)" if rep.width < 5 else "a full journal page (7.16 in)")
              + "; colours are colour-blind safe (Okabe-Ito) and each label keeps its colour in every figure.", ""]
    return "\n".join(lines)


def _finding(rep: Report) -> str:
    """The finding in one sentence with its figure, before everything else (:mod:`.headline`)."""
    if not rep.finding:
        return ""
    lines = ["## Finding", "", f"**{rep.finding}** Whether each difference is established: "
             "[Paired comparisons](#paired-comparisons).", ""]
    if rep.finding_figure is not None:
        title, path = rep.finding_figure
        lines += [f"![{title}]({path})", "", f"*{title}.*", ""]
    return "\n".join(lines)


def _runs(rep: Report) -> str:
    d = rep.data
    pending = "unknown" if d.pending is None else str(d.pending)
    total = "unknown" if d.total is None else str(d.total)
    lines = ["## Runs", "", "| Done | Failed | Pending | Total in spec |", "|---:|---:|---:|---:|",
             f"| {len(d.ok)} | {len(d.failed)} | {pending} | {total} |", ""]
    if len(d.ok):
        reasons = d.ok["stop_reason"].value_counts().sort_index()
        lines += ["Stop reasons of done runs: " + ", ".join(f"{r} {n}" for r, n in reasons.items()) + ".", ""]
    if d.pending:
        lines += [f"{d.pending} runs are still pending: the statistics below cover finished runs only.", ""]
    if len(d.failed):
        lines += ["Failed runs are excluded from every statistic (see [Failed runs](#failed-runs)).", ""]
    if d.foreign:
        lines += [f"{d.foreign} runs in the folder are not runs of its spec (their keys are not the spec's, e.g. "
                  "map files resolved in another folder): they are left out.", ""]
    for note in rep.notes:
        lines += [f"> **Note.** {note}", ""]
    return "\n".join(lines)


def _versions(runs: pd.DataFrame) -> str:
    """Which code computed the runs (``swarm_version``: the package version, and the commit when run from a
    git checkout), with counts: a report over runs of several versions, or of a changed checkout, says so."""
    v = runs["swarm_version"].astype("string").fillna("not recorded") if "swarm_version" in runs else \
        pd.Series(["not recorded"] * len(runs), dtype="string")
    counts = v.value_counts(sort=False).sort_index()
    text = "Computed by swarm " + ", ".join(f"`{k}` ({n} runs)" for k, n in counts.items()) + "."
    if len(counts) > 1:
        text += " **More than one version of the code computed these runs**: compare them only where the " \
                "versions between are known to give the same results."
    if any(str(k).endswith("-dirty") for k in counts.index):
        text += " A `-dirty` version ran from a checkout with uncommitted changes: its commit alone does not " \
                "reproduce it."
    return text


def _campaign(rep: Report) -> str:
    d = rep.data
    spec = d.spec
    lines = ["## Campaign", ""]
    if spec is not None:
        stop = ", ".join(f"{k} = {v}" for k, v in sorted(spec.stop.items())) or "run defaults"
        lines += [f"Seed {spec.seed}, {spec.replicates} replicates (maps) per cell, stop rule: {stop}, a "
                  f"time-series row every {spec.timeseries_every} ticks, {len(spec.exclude)} exclude and "
                  f"{len(spec.include)} include rules.", ""]
    lines += [_versions(d.runs), ""] if len(d.runs) else []
    lines += ["| Dimension | Values (spec order) |", "|---|---|"]
    lines += [f"| {dim} | {', '.join(f'`{v}`' for v in d.orders[dim])} |" for dim in d.orders if d.orders[dim]]
    lines += ["", "<details><summary>campaign.toml</summary>", "", "```toml", d.source.rstrip(), "```", "",
              "</details>", ""]
    return "\n".join(lines)


def _links(name: str) -> str:
    return f"[Markdown](tables/{name}.md) · [LaTeX](tables/{name}.tex) · [CSV](tables/{name}.csv)"


def _inline(table: tables.Table | None, rows: int, name: str) -> list[str]:
    if table is None:
        return []
    if rows <= INLINE_ROWS:
        return [tables.markdown(table), _links(name), ""]
    return [f"{rows} rows: too long to show here. {_links(name)}", ""]


def _summary(rep: Report) -> str:
    if rep.summary is None:
        return "## Summary\n\nNo finished runs yet.\n"
    lines = [f"## Summary: ticks to {_pct(rep.target)} explored", "",
             "Per cell and algorithm, over done runs. Mean, median, fastest and slowest cover the runs that reached "
             "the target; *Mean ticks (DNF = max)* counts every DNF run at its `max_ticks`; *Timeouts* are the "
             "DNF runs stopped by `max_ticks`.", ""]
    return "\n".join(lines + _inline(rep.summary, rep.summary_rows, "summary"))


def _layout(rep: Report) -> str:
    if not rep.layout_figures:
        return ""
    lines = ["## Figures", "",
             f"Drawn as laid out in `{rep.layout_file}`: mean explored % over the runs of each line with a 95 % "
             "t-interval band; dimensions a panel does not fix are pooled.", ""]
    for f in rep.layout_figures:
        lines += [f"**{f.title}** ([data]({f.data}))", "", f"![{f.title}]({f.path})", ""]
        lines += [f"{k}. {t}" for k, t in enumerate(f.panels, 1)] + [""]
    return "\n".join(lines)


def _curves(rep: Report) -> str:
    if not rep.figures:
        return ""
    lines = ["## Explored vs time", "",
             "Mean explored % over replicates (maps) with a 95 % t-interval band; a run that stopped keeps its "
             "final value. The dotted line is the target. Each figure has its numbers in a CSV next to it.", ""]
    embed = sum(1 for _ in rep.figures) <= EMBED_FIGURES
    for compare in dict.fromkeys(f.compare for f in rep.figures):
        lines += [f"### {section(compare)}", ""]
        for f in (f for f in rep.figures if f.compare == compare):
            if embed:
                lines += [f"**{f.title}** ([data]({f.data}))", "", f"![{f.title}]({f.curves})", ""]
            else:
                lines.append(f"- [{f.title}]({f.curves}) ([data]({f.data}))")
        lines.append("")
    return "\n".join(lines)


def _cactus(rep: Report) -> str:
    if not rep.figures:
        return ""
    lines = ["## Time to target: cactus and ECDF", "",
             "Left: runs that reached the target sorted by their time to it, as maes-csv-reader's cactus plot "
             "(log scale when the times span more than a decade). Right: the fraction of all runs done by a "
             "given time; it stops at the success rate.", ""]
    for compare in dict.fromkeys(f.compare for f in rep.figures):
        lines += [f"### {section(compare)}", ""]
        lines += [f"- [{f.title}]({f.cactus})" for f in rep.figures if f.compare == compare]
        lines.append("")
    return "\n".join(lines)


PAIRED_TITLE = {"algorithm": "Algorithms", "radio": "Radio models", "comm": "Comm settings",
                "transport": "Transports", "robots": "Robot counts", "spawn": "Spawn modes"}


def _tally(sec: PairedSection) -> str:
    if not sec.tested:
        return ("No row has enough maps for a test (6 maps whose runs differ; with n maps the smallest "
                "two-sided p is 2^(1−n)).")
    text = (f"{sec.tested} of {sec.rows} rows tested; p < 0.05 in {sec.nominal} before correction, "
            f"**{sec.holm} after Holm's correction** over those {sec.tested}.")
    if not sec.holm and sec.tested > 1:  # say why: the smallest p n maps can give is 2^(1-n)
        need = math.ceil(math.log2(2 * sec.tested / 0.05))
        text += (f" (Holm's smallest threshold is 0.05 / {sec.tested}: a row needs at least {need} maps whose "
                 "runs differ, all in one direction, to pass it.)")
    return text


def _paired(rep: Report) -> str:
    if not rep.paired:
        return ""
    lines = ["## Paired comparisons", "",
             "Runs pair when they share everything but the compared dimension, replicate included: the same map "
             "and start poses. *a faster* counts pairs where a reached the target and b did not or later; *DNF* "
             "pairs with a run that did not reach it (counted at `max_ticks`, a lower bound). How to read a row: "
             "*a/b* is the median ratio of ticks to target, a to b, over maps (0.80: a needed 20 % fewer ticks) "
             "with its 95 % bootstrap interval; *r* is the rank-biserial correlation (−1: a faster on every map, "
             "+1: slower on every map); a difference is established when *p (Holm)* < 0.05, i.e. it survives "
             "Holm's correction over every tested comparison of its table (the family named above the table). "
             f"*p* is a Wilcoxon signed-rank test on the log ratios, from {effects.MIN_UNITS} maps whose runs "
             "differ. Details: [Method](#method).", ""]
    if rep.pooled is not None:
        sec = rep.pooled
        lines += ["### All cells pooled", "", "Each map (map, size, replicate) counts once, with the mean log ratio "
                  "of its pairs: the cells that share a map are not independent. " + sec.family + " " + _tally(sec),
                  ""]
        lines += _inline(sec.table, sec.rows, sec.name)
    for sec in rep.paired:
        title = PAIRED_TITLE.get(sec.dim, f"Values of {sec.dim}")
        lines += [f"### {title}, per cell", "", sec.family + " " + _tally(sec), ""]
        lines += _inline(sec.table, sec.rows, sec.name)
        if sec.dim == "algorithm" and rep.paired_figures:
            lines += ["Per-replicate scatter plots (a point above the diagonal: b took longer than a on that map):",
                      ""]
            lines += [f"- [{title}]({path})" for title, path in rep.paired_figures] + [""]
    return "\n".join(lines) + "\n"


def _comm(rep: Report) -> str:
    if rep.comm is None:
        return ""
    lines = ["## Communication effect", "",
             "Mean ticks to target per radio model in each cell (DNF counted at `max_ticks`; *(k/n)* when only k "
             "of n runs reached the target). The paper expects global <= material-aware (multiwall, maes) <= LOS; "
             f"**{rep.comm_unexpected} of {rep.comm_compared} cells** break that order (*As expected* = **no**)"
             + (f"; the {rep.comm_single} 1-robot cells are not judged (*As expected* = –): a lone robot talks "
                "to no one, so every model gives the same run." if rep.comm_single else "."), ""]
    return "\n".join(lines + _inline(rep.comm, rep.comm_rows, "comm_effect"))


VERDICTS = ("identical", "slower", "faster", "no established difference", "not tested")


def _communication(rep: Report) -> str:
    sec = rep.communication
    if sec is None:
        return ""
    lines = ["## Communication", ""]
    if not sec.available:
        return "\n".join(lines + ["These results hold no communication metrics (they were written by a version "
                                  "of swarm that did not record them).", ""])
    lines += ["What the radio carried and lost, how the robots stayed in touch, and how complete and fresh their "
              "knowledge of the team was. *Missing* is the share of the team's known free cells (those in some "
              "robot's map) a robot's own map lacks; *AoI age* how long ago, on average, a robot last merged each "
              "other robot's map (directly, or inside a third robot's map it merged); both are means over robots "
              "and the recorded rows. Definitions: swarm's `docs/comm-metrics.md`.", ""]
    if sec.findings:
        counts = {v: sum(f.verdict == v for f in sec.findings) for v in VERDICTS}
        said = ", ".join(f"{v} in {n}" for v, n in counts.items() if n)
        lines += ["### What made a difference", "",
                  f"Each value against the first of its dimension (the reference), per algorithm, every other "
                  f"dimension pooled, paired by map; exploration time was {said} of {len(sec.findings)} "
                  "comparisons. Each line says which metric shows why (thresholds in [Method](#method)).", ""]
        for dim in dict.fromkeys(f.dimension for f in sec.findings):
            lines += [f"**{dim}** (reference: `{next(f.a for f in sec.findings if f.dimension == dim)}`)", ""]
            lines += [f"- {f.text}" for f in sec.findings if f.dimension == dim] + [""]
        lines += _inline(sec.effects, sec.effects_rows, "comm_effects")
    elif not sec.talk:
        lines += ["No radio or comm setting varies in this campaign: the tables below describe communication "
                  "under the one setting it has.", ""]
    for title, path, data in sec.against:
        lines += [f"**{title}** ([data]({data}))", "", f"![{title}]({path})", ""]
    if sec.pooled is not None:
        lines += ["### Pooled per compared value", ""] + _inline(sec.pooled, sec.pooled_rows, "comm_pooled")
    lines += ["### Per cell", ""]
    if sec.single_robot_runs:
        lines += [f"{sec.single_robot_runs} runs have a single robot: it talks to no one, so it sends and misses "
                  "nothing.", ""]
    lines += _inline(sec.cells, sec.cell_rows, "comm")
    if sec.over_time:
        lines += ["Missing share, AoI age and the biggest group over time, per cell (mean over runs with a 95 % "
                  "t-interval band):", ""]
        lines += [f"- [{title}]({path})" for title, path in sec.over_time] + [""]
    return "\n".join(lines)


def _map_quality(rep: Report) -> str:
    if rep.map_quality is None:
        return ""
    lines = ["## Localisation and map quality", "",
             "Runs with a localisation model (`[localization]`, docs/localization.md) map in the frame they believe "
             "they are in. Per cell, medians over its runs: the final position error of the pose estimate; the "
             "shares of the known cells that are false free and false occupied; the mean distance from a mapped "
             "wall cell to the nearest true wall; and the share of the free cells some map holds free where they "
             "are.", "", _explored_convention(rep), ""]
    return "\n".join(lines + _inline(rep.map_quality, rep.map_quality_rows, "map_quality"))


def _explored_convention(rep: Report) -> str:
    runs = rep.data.runs
    if (runs["explored_measure"] == "correct").any():
        return ("**For runs with a localisation model, every explored fraction, curve and time to target in this "
                "report counts only correctly known cells** (the share of the free cells some robot's map holds "
                "free where they are, recorded with the time series); their stop rule still judged what the "
                "lidars had seen, so such a run can stop short of the target and count as DNF.")
    return ("**The explored fraction of the other tables counts what the lidars have seen** (these results predate "
            "the correctly-known series); *Explored correctly* counts only correctly known cells, at the end.")


def _maps(rep: Report) -> str:
    if not rep.map_figures:
        return ""
    lines = ["## Maps", "", "The maps the runs met, rebuilt from their specs (up to four per map value), north up, in "
             "metres; walls are coloured by material.", ""]
    for title, path in rep.map_figures:
        lines += [f"![Maps of {title}]({path})", ""]
    return "\n".join(lines)


def _collisions(rep: Report) -> str:
    if rep.collisions is None:
        return ""
    lines = ["## Collisions", "",
             ("Contacts begun per robot-hour of simulated time, split by what was touched: a robot starting to touch "
              "a wall, and a robot starting to touch another robot (counted for both). Local avoidance "
              "(`navigation.avoidance`) acts on the second. Per cell, medians over its runs."), ""]
    return "\n".join(lines + _inline(rep.collisions, rep.collisions_rows, "collisions"))


def _benchmark(rep: Report) -> str:
    if rep.benchmark is None:
        return ""
    lines = ["## Benchmark metrics", "",
             ("The field's metrics, defined in docs/benchmark-metrics.md: Explore-Bench's (ICRA 2022) time to 90 % "
              "and 99 % explored, path length per robot and its coefficient of variation, overlap rate (cells seen by "
              "two or more robots' own lidars over the cells seen) and coverage spread (the standard deviation of "
              "each robot's own-seen share), and MAES's share of recorded ticks with every robot connected and mean "
              "largest-cluster share. Per cell, medians over its runs."), ""]
    return "\n".join(lines + _inline(rep.benchmark, rep.benchmark_rows, "benchmark"))


def _failed(rep: Report) -> str:
    failed = rep.data.failed
    if failed.empty:
        return ""
    lines = ["## Failed runs", "", f"{len(failed)} runs failed; they are excluded from every statistic. "
             f"All of them with their errors: [tables/failed.csv](tables/failed.csv).", "",
             "| Key | Cell | Replicate | Error |", "|---|---|---:|---|"]
    for _, r in failed.head(FAILED_SHOWN).iterrows():
        cell = ", ".join(str(r[d]) for d in rep.data.dims)
        error = " ".join(str(r["error"]).split())[:200].replace("|", "\\|")
        lines.append(f"| `{r['key']}` | {cell} | {int(r['replicate'])} | {error} |")
    if len(failed) > FAILED_SHOWN:
        lines.append(f"| … | {len(failed) - FAILED_SHOWN} more | | |")
    return "\n".join(lines) + "\n"


def _maes(rep: Report) -> str:
    m = rep.maes
    if m is None:
        return ""
    lines = ["## MAES CSV export", "",
             f"{m['files']} files in [`{m['folder']}/`]({m['folder']}/), one per done run, in the format of MAES's "
             "`StatisticsCSVWriter` (header, column order, file naming, `_e{explored}-c{covered}` suffix); "
             f"[`{m['index']}`]({m['index']}) maps each file to its run key. Differences from MAES:", ""]
    lines += [f"- {note}" for note in m["notes"]]
    return "\n".join(lines) + "\n"


def _method(rep: Report) -> str:
    return "\n".join([
        "## Method", "",
        f"- **Time to target**: {rep.ttt_source}.",
        "- **Curves**: each run's explored fraction is sampled on its cell's tick grid (the last recorded value at "
        "or before each grid tick; at most 400 points). After a run stops it holds its final value: it is "
        "finished, and dropping it would make the mean jump up or down as runs leave. The band is a two-sided "
        "95 % Student-t interval of the mean across replicates, n − 1 degrees of freedom.",
        "- **Cells**: a cell is one value of every grid dimension; a figure compares the values of one dimension "
        "(algorithm, radio or comm) with the others fixed. Replicates are maps: every algorithm and radio model "
        "of a replicate meets the same map and start poses.",
        "- **DNF** runs did not reach the target (timeout, stall, all robots failed, or a lower stop rule). "
        "Means over successes ignore them, which flatters cells with many DNFs: read them with the success "
        "rate, or use the DNF = max column (a lower bound).",
        "- **Paired statistics**: a pair gives the log ratio log(t_a / t_b) of its ticks to target, a DNF counted "
        "at its `max_ticks` (so the ratio understates a DNF's loss; the *DNF* column counts such pairs) and a "
        "pair where both runs are DNF a tie (ratio 1). Ratios, not tick differences, because ticks to target vary "
        "many-fold between small and large maps and few and many robots: a ratio compares alike across cells. The "
        "unit is the map (map, size, replicate): within a cell each pair is its own map; pooled over cells, a "
        "map that appears in several cells counts once, with the mean log ratio of its pairs, because runs on "
        "one map are not independent. *p* is the two-sided Wilcoxon signed-rank test of those values against "
        "0: ties (value 0) are dropped and counted, tied magnitudes get mid-ranks, the p-value is exact (the "
        f"permutation distribution of the signed ranks) up to {effects.EXACT_MAX} maps; no test below "
        f"{effects.MIN_UNITS} maps that differ (with n maps the smallest two-sided p is 2^(1−n): 0.031 for 6). "
        "*p (Holm)* is Holm's step-down correction over the tested rows of one table (the family named in its "
        "caption). *a/b* is the median of the maps' ratios with a 95 % percentile bootstrap interval "
        f"({effects.RESAMPLES} resamples of the maps from a generator seeded with {effects.SEED} and the row's "
        f"labels: the same numbers every time; none below {effects.MIN_UNITS} maps); *r* is the matched-pairs "
        "rank-biserial correlation (W+ − W−) / (W+ + W−) of the same signed ranks.",
        "- **Communication**: the delivered share is the share of the other robots each message reached, "
        "deliveries over `(msgs_sent - msgs_relayed) x (robots - 1)`; lost shares count failed deliveries of "
        "every transmission, relayed copies included, over `msgs_sent x (robots - 1)`. In *What made a "
        "difference* each value of a radio or comm dimension is paired with the dimension's first value per algorithm (every other dimension pooled, "
        "the map as the unit, 1-robot runs left out) and its exploration time judged as in the paired tables "
        "(Holm over that table's rows): *identical* when every pair ties. The sentence then names the metric "
        f"that explains it: the same deliveries (within {comm.SAME_DELIVERED_PP:g} percentage point), lost "
        f"messages but the same knowledge (missing within {comm.SAME_MISSING_PP:g} point) because robots stayed "
        f"in groups (mean biggest group at least {comm.GROUPED_PCT:g} % of the robots) or because their "
        f"information was as fresh (AoI age within {100 * comm.SAME_AGE:g} %), or lost knowledge that did not "
        "show in time. The metrics' own paired Wilcoxon p-values (Holm per metric) are in "
        "`tables/comm_effects.csv`.",
        "- **Failed runs** (an exception in the run) are listed and excluded, and so are the pairs they would "
        "have formed; **pending** runs are simply absent.",
        ""])


def _files(rep: Report) -> str:
    written = rep.written
    tables_ = [f for f in written if f.startswith("tables/")]
    lines = ["## Files", "", "- [files.txt](files.txt): every file of this report"]
    lines += [f"- [{f}]({f})" + FILE_NOTES.get(f, ": every pair of runs compared" if f.startswith("tables/pairs")
                                              else "") for f in tables_ if f.endswith(".csv")]
    for folder in ("curves", "cactus", "paired", "maes-csv"):
        count = sum(1 for f in written if f.startswith(f"{folder}/"))
        if count:
            lines.append(f"- `{folder}/`: {count} files")
    return "\n".join(lines) + "\n"
