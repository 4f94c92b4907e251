"""Tables as text: Markdown for the README, LaTeX ``table*`` (booktabs) for a paper, CSV for machines.

Numbers are formatted here, once, so the Markdown and LaTeX versions of a table always agree. The LaTeX
version leaves out the columns that are the same in every row (the caption states them once); the summary's
LaTeX version is a paper's selection of its columns (:func:`summary_latex_table`).
"""

from __future__ import annotations

import io
import math
from collections.abc import Sequence
from dataclasses import dataclass

import pandas as pd

HEADERS = {"map": "Map", "size": "Size", "robots": "Robots", "spawn": "Spawn", "algorithm": "Algorithm",
           "radio": "Radio", "comm": "Comm", "transport": "Transport"}
AXIS_TITLES = {"radio.sensitivity_dbm": "Sensitivity (dBm)", "radio.tx_power_dbm": "Tx power (dBm)",
               "radio.frequency_ghz": "Frequency (GHz)", "comm.loss": "Loss (per message)",
               "comm.bandwidth": "Bandwidth (bytes/tick)", "comm.share_every": "Map share period (ticks)"}
"""Headers of the radio and comm parameter axes the report knows; others are named by :func:`header`."""
UNITS = {"_dbm": "dBm", "_db": "dB", "_ghz": "GHz", "_m": "m"}


def header(dim: str) -> str:
    """A column header for a grid dimension or axis: ``Radio``, ``Sensitivity (dBm)``; an axis the report
    does not know is named from its parameter: ``radio.shadowing_sigma_db`` -> ``Shadowing sigma (dB)``."""
    if dim in HEADERS:
        return HEADERS[dim]
    if dim in AXIS_TITLES:
        return AXIS_TITLES[dim]
    name = dim.partition(".")[2] or dim
    unit = next((u for suffix, u in UNITS.items() if name.endswith(suffix)), None)
    if unit is not None:
        name = name[: name.rindex("_")]
    words = name.replace("_", " ").strip().capitalize()
    return f"{words} ({unit})" if unit else words


@dataclass
class Table:
    """Formatted cells; ``numeric`` columns are right-aligned."""

    headers: list[str]
    rows: list[list[str]]
    numeric: list[bool]


def ticks(x: float, missing: str = "DNF") -> str:
    if x is None or (isinstance(x, float) and math.isnan(x)) or pd.isna(x):
        return missing
    return f"{x:.0f}" if float(x).is_integer() else f"{x:.1f}"


def signed(x: float) -> str:
    return "–" if pd.isna(x) else ("+" if x > 0 else "") + ticks(x)


def rate(x: float) -> str:
    return "–" if pd.isna(x) else f"{100 * x:.1f} %"


def p_value(p: float) -> str:
    if pd.isna(p):
        return "n/a"
    return "< 0.001" if p < 0.001 else f"{p:.3f}"


def summary_table(df: pd.DataFrame, dims: Sequence[str]) -> Table:
    headers = [header(d) for d in dims] + ["Runs", "Successes", "Success rate", "DNF", "Timeouts", "Mean ticks",
                                           "Median ticks", "Mean ticks (DNF = max)", "Fastest ticks",
                                           "Slowest ticks"]
    rows = [[str(r[d]) for d in dims] + [str(r["runs"]), str(r["successes"]), rate(r["success_rate"]), str(r["dnf"]),
                                         str(r["timeouts"]), ticks(r["mean_ticks"]), ticks(r["median_ticks"]),
                                         ticks(r["mean_ticks_dnf_max"], "–"), ticks(r["fastest"]),
                                         ticks(r["slowest"])]
            for _, r in df.iterrows()]
    return Table(headers, rows, [False] * len(dims) + [True] * 10)


def summary_latex_table(df: pd.DataFrame, dims: Sequence[str]) -> Table:
    """The summary as a paper shows it: per cell, runs that reached the target, the median ticks to target with
    its interquartile range (over those runs) and the mean with DNF counted at ``max_ticks``."""
    headers = [header(d) for d in dims] + ["Reached", "Median ticks", "Q1–Q3 ticks", "Mean ticks (DNF = max)"]
    rows = [[str(r[d]) for d in dims] + [f"{r['successes']}/{r['runs']}", ticks(r["median_ticks"], "–"),
                                         interval(r["q1_ticks"], r["q3_ticks"]), ticks(r["mean_ticks_dnf_max"], "–")]
            for _, r in df.iterrows()]
    return Table(headers, rows, [False] * len(dims) + [True] * 4)


def interval(lo: float, hi: float) -> str:
    return "–" if pd.isna(lo) or pd.isna(hi) else f"{ticks(lo)}–{ticks(hi)}"


def comm_table(df: pd.DataFrame, cell: Sequence[str], labels: Sequence[str]) -> Table:
    """Mean ticks per radio label (DNF counted at max_ticks; '(k/n)' when not every run reached)."""

    def mean_cell(r: pd.Series, lab: str) -> str:
        if pd.isna(r[f"mean:{lab}"]):
            return "–"
        ok, n = int(r[f"ok:{lab}"]), int(r[f"n:{lab}"])
        return ticks(r[f"mean:{lab}"]) + ("" if ok == n else f" ({ok}/{n})")

    flag = {True: "yes", False: "**no**", None: "–"}
    rows = [[str(r[d]) for d in cell] + [mean_cell(r, lab) for lab in labels]
            + [str(r["ordering"]), flag[r["as_expected"] if r["as_expected"] in (True, False) else None]]
            for _, r in df.iterrows()]
    return Table([header(d) for d in cell] + list(labels) + ["Ordering (fastest first)", "As expected"], rows,
                 [False] * len(cell) + [True] * len(labels) + [False, False])


# -------------------------------------------------------------------------------------- renderers ----
def markdown(table: Table) -> str:
    def esc(text: str) -> str:
        return text.replace("|", "\\|")

    lines = ["| " + " | ".join(esc(h) for h in table.headers) + " |",
             "|" + "|".join("---:" if num else "---" for num in table.numeric) + "|"]
    lines += ["| " + " | ".join(esc(c) for c in row) + " |" for row in table.rows]
    return "\n".join(lines) + "\n"


_LATEX_SPECIAL = {"\\": r"\textbackslash{}", "&": r"\&", "%": r"\%", "$": r"\$", "#": r"\#", "_": r"\_",
                  "{": r"\{", "}": r"\}", "~": r"\textasciitilde{}", "^": r"\textasciicircum{}", "−": "$-$",
                  "–": "--", "<": r"$<$", ">": r"$>$"}


def latex_escape(text: str) -> str:
    return "".join(_LATEX_SPECIAL.get(ch, ch) for ch in text).replace("**", "")


def latex(table: Table, caption: str, label: str) -> str:
    """A ``table*`` (full text width) with booktabs rules (``\\usepackage{booktabs}``); a column with the same
    value in every row (of two or more) is left out and named once in the caption."""
    n = len(table.headers)
    same = [len(table.rows) > 1 and len({row[j] for row in table.rows}) == 1 for j in range(n)]
    same = [False] * n if all(same) else same
    keep = [j for j in range(n) if not same[j]]
    if any(same):
        caption += " In every row: " + "; ".join(f"{table.headers[j]}: {table.rows[0][j]}" for j in range(n)
                                                 if same[j]) + "."
    spec = "".join("r" if table.numeric[j] else "l" for j in keep)
    out = ["\\begin{table*}[t]", "\\centering", f"\\caption{{{latex_escape(caption)}}}", f"\\label{{{label}}}",
           f"\\begin{{tabular}}{{{spec}}}", "\\toprule",
           " & ".join(latex_escape(table.headers[j]) for j in keep) + " \\\\", "\\midrule"]
    out += [" & ".join(latex_escape(row[j]) for j in keep) + " \\\\" for row in table.rows]
    out += ["\\bottomrule", "\\end{tabular}", "\\end{table*}"]
    return "\n".join(out) + "\n"


def csv_text(df: pd.DataFrame) -> str:
    buf = io.StringIO()
    df.to_csv(buf, index=False, lineterminator="\n")
    return buf.getvalue()
