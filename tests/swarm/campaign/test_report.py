"""Campaign reports: every promised file from a real (tiny) campaign, statistics checked against numbers
worked out by hand on a synthetic results folder, deterministic output, and the CLI."""

from __future__ import annotations

import re
import shutil
import statistics
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from scipy import stats as sps

from swarm.campaign import ResultsStore, make_executor, parse_campaign, run_campaign
from swarm.campaign.report import build_report, stats
from swarm.campaign.report.load import expected_runs, load
from swarm.campaign.report.series import sample
from swarm.cli import main

from .synthetic_results import FakeRun, series_to, write

TINY = """
[campaign]
name = "report-test"
seed = 11
replicates = 2
description = "tiny campaign for the report tests"

[grid]
map = ["building"]
size = [20]
robots = [1, 2]
spawn = ["together"]
algorithm = ["frontier", "greed"]
radio = ["global", "los"]

[stop]
explored = 0.6
max_ticks = 300
"""


@pytest.fixture(scope="module")
def real(tmp_path_factory) -> tuple[Path, Path]:
    """16 short real runs and their report (with MAES CSVs)."""
    root = tmp_path_factory.mktemp("real")
    results = root / "results"
    run_campaign(parse_campaign(TINY), results, executor=make_executor(inline=True), progress=False)
    report = build_report(results, root / "report", maes_csv=True)
    return results, report.parent


# The synthetic campaign: 2 algorithms x 2 radios, replicates 0..5 written of 7 (so 4 runs pending).
# Ticks to 98 % per replicate (None = DNF); "failed" = the run raised.
GREED_GLOBAL = [100, 200, 300, 400, 500, None]        # rep 5 times out at max_ticks = 1000
FRONTIER_GLOBAL = [150, 150, 350, 300, 600, 700]
GREED_LOS = [120, 220, 320, 420, 520, 620]
FRONTIER_LOS = ["failed", None, 200, 300, 400, 620]  # rep 1 stalls at tick 400


def fake_runs() -> list[FakeRun]:
    runs = []
    for alg, radio, times in (("greed", "global", GREED_GLOBAL), ("frontier", "global", FRONTIER_GLOBAL),
                              ("greed", "los", GREED_LOS), ("frontier", "los", FRONTIER_LOS)):
        for rep, t in enumerate(times):
            if t == "failed":
                runs.append(FakeRun(alg, radio, rep, None, failed="RuntimeError: boom in the algorithm"))
            elif t is None and radio == "los":
                runs.append(FakeRun(alg, radio, rep, None, series_to(None, 400), stop_reason="stalled"))
            elif t is None:
                runs.append(FakeRun(alg, radio, rep, None, stop_reason="max_ticks"))
            else:
                runs.append(FakeRun(alg, radio, rep, t))
    return runs


@pytest.fixture(scope="module")
def synthetic(tmp_path_factory) -> tuple[Path, Path]:
    root = tmp_path_factory.mktemp("synthetic")
    results = write(root / "results", fake_runs(), replicates=7)
    return results, build_report(results, root / "report").parent


def csv(report: Path, name: str) -> pd.DataFrame:
    return pd.read_csv(report / "tables" / f"{name}.csv")


# ----------------------------------------------------------------------------------- real campaign ----
def test_real_campaign_report_has_every_promised_file(real):
    results, report = real
    runs = ResultsStore(results).runs_table().to_pandas()
    assert len(runs) == 16
    for robots in (1, 2):
        for radio in ("global", "los"):
            stem = f"algorithms__building_20_{robots}_together_{radio}"
            for path in (f"curves/{stem}.png", f"curves/{stem}.csv", f"cactus/{stem}.png", f"paired/{stem}.png"):
                assert (report / path).stat().st_size > 1000, path
        for alg in ("frontier", "greed"):
            stem = f"radio__building_20_{robots}_together_{alg}"
            assert (report / f"curves/{stem}.png").exists() and (report / f"cactus/{stem}.png").exists()
    for name in ("summary", "paired", "comm_effect"):
        for ext in ("md", "tex", "csv"):
            assert (report / "tables" / f"{name}.{ext}").exists(), (name, ext)
    assert (report / "tables/summary.tex").read_text().startswith("\\begin{table*}")
    assert len(pd.read_csv(report / "tables/runs.csv")) == 16
    maes = sorted((report / "maes-csv").glob("*.csv"))
    assert len(maes) == (runs["status"] == "ok").sum()
    listed = set((report / "files.txt").read_text().split("\n")[1:]) - {""}
    on_disk = {str(p.relative_to(report)) for p in report.rglob("*") if p.is_file()}
    assert listed == on_disk


def test_real_readme_states_the_campaign_and_links_resolve(real):
    results, report = real
    text = (report / "README.md").read_text()
    assert text.startswith("# Campaign report: report-test\n")
    assert "| 16 | 0 | 0 | 16 |" in text  # done, failed, pending, total
    assert "**98 % explored**" in text
    assert f"`swarm campaign report {results} -o {report} --target 0.98 --maes-csv`" in text
    # the first page: the finding in one sentence, with the radio figure, before the tables
    assert text.index("## Finding") < text.index("## Runs")
    finding = text[text.index("## Finding"):text.index("## Runs")]
    assert "**No run reached 98 % explored within its time limit (2 maps).**" in finding  # these short runs
    assert "](comm/against_radio.png)" in finding
    links = re.findall(r"\]\(([^)#]+)\)", text)
    assert len(links) > 30
    for link in links:
        assert (report / link).exists(), link


def test_rebuild_is_identical_and_removes_only_its_own_stale_files(real, tmp_path):
    results, report = real
    copy = tmp_path / "copy"
    shutil.copytree(report, copy)
    (copy / "my-notes.txt").write_text("mine")
    build_report(results, copy, maes_csv=False)
    assert not (copy / "maes-csv").exists() and not (copy / "maes-csv-index.csv").exists()
    assert (copy / "my-notes.txt").read_text() == "mine"
    originals = [p.relative_to(report) for p in report.rglob("*") if p.is_file() and "maes-csv" not in str(p)]
    changed = sorted(str(p) for p in originals if (report / p).read_bytes() != (copy / p).read_bytes())
    assert changed == ["README.md", "files.txt"]  # the command line and the file list; figures are byte-identical


def test_time_to_a_target_without_a_threshold_column_comes_from_the_series(real):
    results, _ = real
    data = load(results)
    ok = data.ok.reset_index(drop=True)
    cells = ok.groupby(list(data.dims), observed=True).ngroup().to_numpy()
    sampled = sample(ResultsStore(results), ok, cells, data.every, 0.55)
    runs_t = stats.add_time_to_target(ok, 0.55, sampled.first_at_target)
    ts = ResultsStore(results).timeseries_table().to_pandas()
    for _, run in runs_t.iterrows():
        series = ts[ts["key"] == run["key"]].sort_values("tick")
        reached = series[series["explored"] >= 0.55]
        expected = float(reached["tick"].iloc[0]) if len(reached) else np.nan
        assert run["ttt"] == expected or (np.isnan(expected) and np.isnan(run["ttt"]))
        if not np.isnan(expected):  # 55 % comes no earlier than the exact per-tick 50 % crossing
            assert expected >= run["t50"]
    assert runs_t["success"].any() and not runs_t["success"].all(), "the tiny campaign mixes reached and DNF"


# -------------------------------------------------------------------------------- synthetic numbers ----
def test_summary_matches_hand_computed_values(synthetic):
    _, report = synthetic
    s = csv(report, "summary").set_index(["radio", "algorithm"])
    g = s.loc[("global", "greed")]
    assert (g["runs"], g["successes"], g["dnf"], g["timeouts"]) == (6, 5, 1, 1)
    assert g["success_rate"] == pytest.approx(5 / 6)
    assert g["mean_ticks"] == 300 and g["median_ticks"] == 300
    assert g["mean_ticks_dnf_max"] == pytest.approx((100 + 200 + 300 + 400 + 500 + 1000) / 6)
    assert (g["fastest"], g["slowest"]) == (100, 500)
    f = s.loc[("global", "frontier")]
    assert f["mean_ticks"] == pytest.approx(375) and f["median_ticks"] == 325 and f["success_rate"] == 1
    lf = s.loc[("los", "frontier")]  # rep 0 failed (excluded), rep 1 stalled: DNF but not a timeout
    assert (lf["runs"], lf["successes"], lf["dnf"], lf["timeouts"]) == (5, 4, 1, 0)
    assert lf["mean_ticks"] == pytest.approx((200 + 300 + 400 + 620) / 4) and lf["median_ticks"] == 350
    assert lf["mean_ticks_dnf_max"] == pytest.approx((1000 + 200 + 300 + 400 + 620) / 5)
    md = (report / "tables/summary.md").read_text()
    assert "| building | 20 | 2 | together | global | greed | 6 | 5 | 83.3 % | 1 | 1 | 300 | 300 | 416.7 | 100 | 500 |" in md


def test_latex_summary_has_booktabs_rules_varying_columns_and_an_interval(synthetic):
    _, report = synthetic
    tex = (report / "tables/summary.tex").read_text()
    assert "\\hline" not in tex and tex.count("\\toprule") == tex.count("\\midrule") == tex.count("\\bottomrule") == 1
    assert "In every row: Map: building; Size: 20; Robots: 2; Spawn: together." in tex  # constant: in the caption
    assert "\\begin{tabular}{llrrrr}" in tex
    assert "Radio & Algorithm & Reached & Median ticks & Q1--Q3 ticks & Mean ticks (DNF = max) \\\\" in tex
    assert "global & greed & 5/6 & 300 & 200--400 & 416.7 \\\\" in tex  # quartiles of 100..500
    s = csv(report, "summary").set_index(["radio", "algorithm"])
    assert (s.loc[("global", "greed"), "q1_ticks"], s.loc[("global", "greed"), "q3_ticks"]) == (200, 400)


def test_paired_comparison_matches_hand_computed_values(synthetic):
    _, report = synthetic
    p = csv(report, "paired").set_index("radio")
    g = p.loc["global"]
    diffs = [100 - 150, 200 - 150, 300 - 350, 400 - 300, 500 - 600, 1000 - 700]  # greed DNF counted at 1000
    assert (g["a"], g["b"], g["pairs"], g["a_wins"], g["b_wins"], g["ties"]) == ("greed", "frontier", 6, 3, 3, 0)
    assert g["mean_diff"] == pytest.approx(statistics.mean(diffs)) and g["median_diff"] == 0
    # the test runs on log ratios t_a / t_b: magnitudes rank 6, 3.5, 1, 3.5, 2, 5 with signs - + - + - +
    ratios = [100 / 150, 200 / 150, 300 / 350, 400 / 300, 500 / 600, 1000 / 700]
    assert g["tested"] == 6 and g["maps"] == 6 and g["dnf_pairs"] == 1
    assert g["rank_biserial"] == pytest.approx((12 - 9) / 21)  # W+ = 3.5 + 3.5 + 5, W- = 1 + 2 + 6
    assert g["p_value"] == pytest.approx(2 * 25 / 64)  # 25 of the 64 sign patterns give W+ >= 12
    assert g["p_min"] == pytest.approx(1 / 32)
    assert g["ratio"] == pytest.approx(np.sqrt(300 / 350 * 400 / 300))  # median of 6: the two middle ratios
    assert g["ratio_low"] <= min(ratios[2], ratios[3]) and g["ratio_high"] >= max(ratios[2], ratios[3])
    assert g["median_a"] == 350 and g["median_b"] == 325
    los = p.loc["los"]  # rep 0 has no pair (frontier failed); rep 1 frontier stalled; rep 5 ties at 620
    assert (los["pairs"], los["a_wins"], los["b_wins"], los["ties"]) == (5, 1, 3, 1)
    assert los["mean_diff"] == pytest.approx((220 - 1000 + 120 + 120 + 120 + 0) / 5) and los["median_diff"] == 120
    assert np.isnan(los["p_value"]), "fewer than 6 pairs: no test"
    pairs = csv(report, "pairs")
    assert len(pairs) == 11 and set(pairs["winner"]) == {"a", "b", "tie"}


def test_communication_effect_flags_the_unexpected_order(synthetic):
    _, report = synthetic
    c = csv(report, "comm_effect").set_index("algorithm")
    assert c.loc["greed", "mean:global"] == pytest.approx(2500 / 6)
    assert c.loc["greed", "mean:los"] == pytest.approx(370)
    assert c.loc["greed", "ordering"] == "los < global" and not c.loc["greed", "as_expected"]
    assert c.loc["frontier", "ordering"] == "global < los" and c.loc["frontier", "as_expected"]
    readme = (report / "README.md").read_text()
    assert "**1 of 2 cells** break that order" in readme


def test_curves_average_held_values_with_a_t_band(synthetic):
    _, report = synthetic
    curves = pd.read_csv(report / "curves/algorithms__building_20_2_together_global.csv")
    greed = curves[curves["line"] == "greed"].set_index("tick")
    at100 = [0.98, 0.98 * 100 / 200, 0.98 * 100 / 300, 0.98 * 100 / 400, 0.98 * 100 / 500, 0.9 * 100 / 1000]
    at600 = [0.98] * 5 + [0.9 * 600 / 1000]  # the five finished runs hold 0.98 after they stopped
    for tick, values in ((100, at100), (600, at600)):
        mean = statistics.mean(values)
        half = sps.t.ppf(0.975, 5) * statistics.stdev(values) / np.sqrt(6)
        assert greed.loc[tick, "explored_mean_pct"] == pytest.approx(100 * mean, abs=1e-3)
        assert greed.loc[tick, "ci95_high_pct"] == pytest.approx(100 * (mean + half), abs=1e-3)
        assert greed.loc[tick, "runs"] == 6
    los = pd.read_csv(report / "curves/algorithms__building_20_2_together_los.csv")
    assert set(los.loc[los["line"] == "frontier", "runs"]) == {5}, "the failed run has no curve"


def test_failed_and_pending_runs_are_counted_and_listed(synthetic):
    _, report = synthetic
    readme = (report / "README.md").read_text()
    assert "| 23 | 1 | 4 | 28 |" in readme
    assert "RuntimeError: boom in the algorithm" in readme
    assert "4 runs are still pending" in readme
    failed = csv(report, "failed")
    assert list(failed["algorithm"]) == ["frontier"] and list(failed["replicate"]) == [0]


def test_a_target_above_the_stop_rule_is_explained(synthetic, tmp_path):
    results, _ = synthetic
    readme = build_report(results, tmp_path / "r", target=0.99).read_text()
    assert "below the target 0.99" in readme
    assert "| 23 | 1 | 4 | 28 |" in readme
    summary = pd.read_csv(tmp_path / "r/tables/summary.csv")
    assert summary["successes"].sum() == 0


# ------------------------------------------------------------------------------------- statistics ----
def test_mean_band_skips_missing_runs_and_needs_two():
    values = np.array([[0.2, 0.5, np.nan], [0.4, np.nan, np.nan], [0.6, np.nan, np.nan]])
    mean, lo, hi, n = stats.mean_band(values)
    assert list(n) == [3, 1, 0]
    assert mean[0] == pytest.approx(0.4) and mean[1] == pytest.approx(0.5) and np.isnan(mean[2])
    assert hi[0] - mean[0] == pytest.approx(sps.t.ppf(0.975, 2) * 0.2 / np.sqrt(3))
    assert np.isnan(lo[1]) and np.isnan(hi[1])


def test_expected_runs_counts_like_the_spec_without_building_every_run():
    text = TINY.replace('radio = ["global", "los"]', 'radio = ["global", "los"]\ncomm = [{label = "plain"}, '
                        '{map_sharing = "delta", label = "restated-default"}, {map_sharing = "full", label = "full"}]')
    text += '\n[[exclude]]\nrobots = 2\nradio = "los"\n\n[[include]]\nmap = "building"\nsize = 24\nrobots = 1\n' \
            'spawn = "together"\nalgorithm = "greed"\nradio = "global"\ncomm = "full"\n'
    spec = parse_campaign(text)
    # 2 robots x 2 algorithms x 2 radios x 2 distinct comm settings = 16 cells, minus the 4 with 2 robots and LOS,
    # plus the included cell = 13 cells, x 2 replicates
    assert expected_runs(spec) == len(spec.runs()) == 26


def test_threshold_columns():
    assert stats.threshold_column(0.98) == "t98" and stats.threshold_column(0.5) == "t50"
    assert stats.threshold_column(0.97) is None


# -------------------------------------------------------------------------------------------- CLI ----
def test_cli_report(synthetic, tmp_path, capsys):
    results, _ = synthetic
    code = main(["campaign", "report", str(results), "-o", str(tmp_path / "rep"), "--target", "0.9",
                 "--format", "svg"])
    out, _ = capsys.readouterr()
    assert code == 0 and "README.md" in out
    assert (tmp_path / "rep/curves/algorithms__building_20_2_together_global.svg").exists()
    assert "--target 0.9 --format svg" in (tmp_path / "rep/README.md").read_text()


@pytest.mark.parametrize("args, needle", [
    (["{missing}"], "DIR: got"),
    (["{empty}"], "no campaign.toml"),
    (["{results}", "--target", "1.5"], "--target: got 1.5"),
    (["{results}", "--target", "0"], "--target: got 0.0"),
    (["{results}", "--target", "abc"], "'--target'"),
    (["{results}", "--format", "gif"], "'--format'"),
    (["{results}", "-o", "{file}"], "-o: got"),
])
def test_cli_bad_input_is_one_line_and_status_2(synthetic, tmp_path, capsys, args, needle):
    results, _ = synthetic
    (tmp_path / "empty").mkdir()
    (tmp_path / "file").write_text("x")
    paths = {"missing": tmp_path / "nope", "empty": tmp_path / "empty", "results": results, "file": tmp_path / "file"}
    code = main(["campaign", "report", *(a.format(**paths) for a in args)])
    _, err = capsys.readouterr()
    assert code == 2
    assert err.count("\n") == 1 and err.startswith("swarm: error:") and needle in err


# ------------------------------------------------------------------------------- figure layouts ----
LAYOUT = """
[[figure]]
name = "two_panels"
title = "Algorithms and radios"
columns = 1
[[figure.panel]]
compare = "algorithm"
robots = 2
radio = "global"
[[figure.panel]]
compare = "radio"
title = "greed"
algorithm = "greed"
"""


def test_layout_figure_panels_select_and_pool_runs(real, tmp_path):
    results, _ = real
    (tmp_path / "layout.toml").write_text(LAYOUT)
    readme = build_report(results, tmp_path / "rep", figures_file=tmp_path / "layout.toml")
    folder = readme.parent
    assert (folder / "figures" / "two_panels.png").read_bytes()[:4] == b"\x89PNG"
    data = pd.read_csv(folder / "figures" / "two_panels.csv")
    runs = data.groupby(["panel", "line"])["runs"].max().to_dict()
    # panel 1 fixes everything but the algorithm: 2 replicates per line; panel 2 pools robots 1 and 2: 4
    assert runs == {(1, "frontier"): 2, (1, "greed"): 2, (2, "global"): 4, (2, "los"): 4}
    text = readme.read_text()
    assert "## Figures" in text and "figures/two_panels.png" in text and "greed (pooled over robots)" in text
    assert "--figures" in text  # the command that made the report
    # a pooled line is the mean of its runs: panel 2's 'los' line at its last tick equals the runs' mean
    runs_t = pd.read_csv(folder / "tables" / "runs.csv")
    los = runs_t[(runs_t["algorithm"] == "greed") & (runs_t["radio"] == "los")]
    last = data[(data["panel"] == 2) & (data["line"] == "los")].iloc[-1]
    assert last["explored_mean_pct"] == pytest.approx(100 * los["explored"].mean(), abs=1e-3)


@pytest.mark.parametrize("layout, needle", [
    ('[[figure]]\nname = "a"\n[[figure.panel]]\ncompare = "algorithm"\nradio = "wifi"\n', "figure[0].panel[0].radio: got 'wifi'"),
    ('[[figure]]\nname = "a"\n[[figure.panel]]\ncompare = "colour"\n', "figure[0].panel[0].compare: got 'colour'"),
    ('[[figure]]\nname = "a b"\n[[figure.panel]]\ncompare = "radio"\n', "figure[0].name: got 'a b'"),
    ('[[figure]]\nname = "a"\n', "figure[0].panel: got None"),
    ('[[figure]]\nname = "a"\n[[figure.panel]]\ncompare = "radio"\nradio = "los"\n', "figure[0].panel[0].radio: got 'los'"),
    ('[[figure]]\nname = "a"\n[[figure.panel]]\ncompare = "radio"\nrobot = 2\n', "figure[0].panel[0].robot: got 2"),
])
def test_bad_layouts_are_one_line_errors_and_write_nothing(real, tmp_path, capsys, layout, needle):
    results, _ = real
    (tmp_path / "layout.toml").write_text(layout)
    code = main(["campaign", "report", str(results), "-o", str(tmp_path / "rep"), "--figures",
                 str(tmp_path / "layout.toml")])
    _, err = capsys.readouterr()
    assert code == 2 and err.count("\n") == 1 and needle in err, err
    assert not (tmp_path / "rep").exists()


def test_example_paper_layout_is_valid_for_the_paper_campaign():
    from swarm.campaign import load_campaign
    from swarm.campaign.report.layout import check_layout, load_layout

    root = Path(__file__).resolve().parents[3]
    spec = load_campaign(root / "examples" / "minotaur-paper-small.toml")
    orders = {dim: [o.label for o in opts] for dim, opts in spec.grid.items()}
    layout = load_layout(root / "examples" / "minotaur-paper-figures.toml")
    check_layout(layout, orders)
    assert [f.name for f in layout[:3]] == ["fig7", "fig8", "fig9"] and all(len(f.panels) == 2 for f in layout[:3])
    # the overviews: one panel per (size, robots) of the grid, 5 per row
    assert all(len(f.panels) == 15 and f.columns == 5 for f in layout[3:])


def test_no_cell_figures_keeps_tables_and_layout_figures_only(real, tmp_path):
    results, _ = real
    (tmp_path / "layout.toml").write_text(LAYOUT)
    code = main(["campaign", "report", str(results), "-o", str(tmp_path / "rep"), "--figures",
                 str(tmp_path / "layout.toml"), "--no-cell-figures"])
    assert code in (0, None)
    folder = tmp_path / "rep"
    assert not (folder / "curves").exists() and not (folder / "cactus").exists() and not (folder / "paired").exists()
    assert (folder / "figures" / "two_panels.png").exists() and (folder / "tables" / "summary.md").exists()
    text = (folder / "README.md").read_text()
    assert "--no-cell-figures" in text
    for link in re.findall(r"\]\(([^)#]+)\)", text):
        assert (folder / link).exists(), link
