"""Tables as text: Markdown for the README, LaTeX ``table*`` as maes-csv-reader writes, CSV for machines.

Numbers are formatted here, once, so the Markdown and LaTeX versions of a table always agree.
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
                                           "Median ticks", "Mean ticks (DNF = max)", "Fastest", "Slowest"]
    rows = [[str(r[d]) for d in dims] + [str(r["runs"]), str(r["successes"]), rate(r["success_rate"]), str(r["dnf"]),
                                         str(r["timeouts"]), ticks(r["mean_ticks"]), ticks(r["median_ticks"]),
                                         ticks(r["mean_ticks_dnf_max"], "–"), ticks(r["fastest"]),
                                         ticks(r["slowest"])]
            for _, r in df.iterrows()]
    return Table(headers, rows, [False] * len(dims) + [True] * 10)


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
    """A ``table*`` (full text width) as maes-csv-reader writes its tables."""
    spec = "".join("r" if num else "l" for num in table.numeric)
    out = ["\\begin{table*}[t]", "\\centering", f"\\caption{{{latex_escape(caption)}}}", f"\\label{{{label}}}",
           f"\\begin{{tabular}}{{{spec}}}", "\\hline",
           " & ".join(latex_escape(h) for h in table.headers) + " \\\\", "\\hline"]
    out += [" & ".join(latex_escape(c) for c in row) + " \\\\" for row in table.rows]
    out += ["\\hline", "\\end{tabular}", "\\end{table*}"]
    return "\n".join(out) + "\n"


def csv_text(df: pd.DataFrame) -> str:
    buf = io.StringIO()
    df.to_csv(buf, index=False, lineterminator="\n")
    return buf.getvalue()
