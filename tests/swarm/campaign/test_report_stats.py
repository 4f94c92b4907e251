"""The report's paired statistics (swarm/campaign/report/effects.py) on cases worked out by hand: signed-rank
p-values, Holm's correction, the bootstrap interval, per-map pooling, and the ablation hook."""

from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from scipy import stats as sps

from swarm.campaign.report import build_report, effects
from swarm.campaign.report.load import DIMS, load

from .synthetic_results import FakeRun, write


def brute_force_p(values) -> float:
    """Two-sided signed-rank p by listing every sign pattern (mid-ranks, zeros dropped)."""
    v = np.asarray([x for x in values if x != 0], dtype=float)
    ranks = sps.rankdata(np.abs(v))
    observed = ranks[v > 0].sum()
    sums = [sum(r for r, s in zip(ranks, signs) if s) for signs in itertools.product((0, 1), repeat=len(v))]
    lower = sum(s <= observed + 1e-9 for s in sums) / len(sums)
    upper = sum(s >= observed - 1e-9 for s in sums) / len(sums)
    return min(1.0, 2 * min(lower, upper))


# ------------------------------------------------------------------------------------ signed rank ----
def test_signed_rank_known_p_values():
    # all six positive: only 1 of the 64 sign patterns is as extreme on each side
    t = effects.signed_rank([1, 2, 3, 4, 5, 6])
    assert (t.n, t.w_plus, t.w_minus, t.r) == (6, 21, 0, 1.0) and t.p == pytest.approx(2 / 64)
    # negatives of rank 1 and 2: W- = 3; the subsets of {1..6} summing to <= 3 are {}, 1, 2, 3, 12: 5 of 64
    t = effects.signed_rank([5, -3, 8, 12, -1, 7])
    assert (t.w_plus, t.w_minus) == (18, 3) and t.p == pytest.approx(10 / 64) and t.r == pytest.approx(15 / 21)
    assert t.p == pytest.approx(sps.wilcoxon([5, -3, 8, 12, -1, 7]).pvalue)


def test_signed_rank_matches_scipy_exact_without_ties():
    rng = np.random.default_rng(0)
    for n in (6, 9, 17, 40):
        for _ in range(5):
            x = rng.normal(0.4, 1.0, n)
            assert effects.signed_rank(x).p == pytest.approx(sps.wilcoxon(x, method="exact").pvalue, abs=1e-12)


def test_signed_rank_with_ties_and_zeros_is_the_exact_permutation_p():
    # zeros are dropped (and counted); tied magnitudes share mid-ranks
    x = [0, 0, 2, 2, -2, 3, 5, 5, -1, 4]
    t = effects.signed_rank(x)
    assert (t.n, t.zeros) == (8, 2)
    assert t.p == pytest.approx(brute_force_p(x), abs=1e-12)
    rng = np.random.default_rng(3)
    for _ in range(20):
        x = rng.integers(-3, 5, size=11)
        t = effects.signed_rank(x)
        if t.n >= effects.MIN_UNITS:
            assert t.p == pytest.approx(brute_force_p(x), abs=1e-12)


def test_signed_rank_needs_six_values_that_differ():
    assert np.isnan(effects.signed_rank([1, 2, 3, 4, 5]).p)
    assert np.isnan(effects.signed_rank([0, 0, 0, 1, 2, 3, 4, 5]).p), "zeros do not count towards the six"
    t = effects.signed_rank(np.zeros(8))
    assert (t.n, t.zeros) == (0, 8) and np.isnan(t.p) and np.isnan(t.r)
    assert effects.signed_rank([1, 2, 3, 4, 5, 6, 0, 0]).p == pytest.approx(1 / 32), "the smallest p with 6"


def test_signed_rank_normal_approximation_above_the_exact_limit(monkeypatch):
    x = np.random.default_rng(5).normal(0.1, 1.0, 150)
    exact = effects.signed_rank(x).p
    monkeypatch.setattr(effects, "EXACT_MAX", 10)
    approx = effects.signed_rank(x).p
    assert approx == pytest.approx(exact, abs=2e-3) and approx != exact


# ------------------------------------------------------------------------------------------ Holm ----
def test_holm_on_known_p_values():
    # sorted 0.005, 0.01, 0.03, 0.04 times 4, 3, 2, 1 = 0.02, 0.03, 0.06, 0.04 -> running max 0.02, 0.03, 0.06, 0.06
    assert effects.holm([0.01, 0.04, 0.03, 0.005]) == pytest.approx([0.03, 0.06, 0.06, 0.02])
    out = effects.holm([0.01, np.nan, 0.04])  # NaN is not a test: the family has 2 members
    assert out[0] == pytest.approx(0.02) and np.isnan(out[1]) and out[2] == pytest.approx(0.04)
    assert effects.holm([0.5, 0.9]) == pytest.approx([1.0, 1.0]), "capped at 1"
    assert effects.holm([]).shape == (0,)


# ------------------------------------------------------------------------------------- bootstrap ----
def test_bootstrap_interval_is_reproducible_and_covers_the_median():
    sample = np.random.default_rng(11).normal(0.3, 1.0, 200)  # true median 0.3
    a = effects.bootstrap_median_ci(sample, effects.row_rng(["cell", "a", "b"]))
    b = effects.bootstrap_median_ci(sample, effects.row_rng(["cell", "a", "b"]))
    c = effects.bootstrap_median_ci(sample, effects.row_rng(["other", "a", "b"]))
    assert a == b and a != c
    assert a[0] < 0.3 < a[1] and a[0] < np.median(sample) < a[1]
    assert 0.1 < a[1] - a[0] < 0.6  # about 2 x 1.96 x 1.25 / sqrt(200) = 0.35


def test_bootstrap_interval_coverage_is_near_95_percent():
    rng = np.random.default_rng(2)
    covered = 0
    for k in range(100):
        lo, hi = effects.bootstrap_median_ci(rng.exponential(1.0, 60), effects.row_rng([k]), resamples=1000)
        covered += lo <= np.log(2) <= hi  # the exponential's median
    assert covered >= 85


def test_log_ratios_count_a_double_dnf_as_a_tie():
    lr = effects.log_ratios([100, 1000, 1000, 0], [200, 500, 1000, 5], [True, False, False, True],
                            [True, True, False, True])
    assert lr[0] == pytest.approx(np.log(0.5)) and lr[1] == pytest.approx(np.log(2)) and lr[2] == 0
    assert lr[3] == pytest.approx(np.log(1 / 5)), "ticks floored at 1"
    both_dnf_other_limits = effects.log_ratios([1000], [2000], [False], [False])
    assert both_dnf_other_limits[0] == 0


# ------------------------------------------------------------------------------------- summarise ----
def pair_frame(rows):
    """Pairs as summarise reads them: (cell, map, replicate, t_a, t_b) with every run successful."""
    df = pd.DataFrame(rows, columns=["cell", "map", "replicate", "t_a", "t_b"])
    df["size"] = "50"
    df["ok_a"] = df["ok_b"] = True
    df["winner"] = np.where(df["t_a"] < df["t_b"], "a", np.where(df["t_b"] < df["t_a"], "b", "tie"))
    df["group"] = "g"
    return df


def test_pooled_pairs_count_each_map_once_with_its_mean_log_ratio():
    # two cells on the same 6 maps: map k has pairs with ratios x and y; its value is (log x + log y) / 2
    rows = []
    for k in range(6):
        rows.append(("c1", "building", k, 100, 200))          # ratio 1/2 on every map
        rows.append(("c2", "building", k, 100 * (k + 1), 100))  # ratio 1, 2, ..., 6
    out = effects.summarise(pair_frame(rows), ["group"], cell=["cell"]).iloc[0]
    values = [(np.log(0.5) + np.log(k + 1)) / 2 for k in range(6)]  # log(0.5 (k+1)) / 2: k = 1 is 0, a tie
    t = effects.signed_rank(values)
    assert (out["cells"], out["pairs"], out["maps"], out["tested"]) == (2, 12, 6, 5)
    assert out["p_value"] == pytest.approx(t.p, nan_ok=True) and np.isnan(out["p_value"]), "5 maps differ: no test"
    assert out["rank_biserial"] == pytest.approx(t.r)
    assert out["ratio"] == pytest.approx(np.exp(np.median(values)))
    assert (out["a_wins"], out["b_wins"], out["ties"]) == (6 + 0, 5, 1)


def test_summarise_holm_runs_across_the_rows_of_one_table():
    rows = []
    for g, ratio in (("x", 0.5), ("y", 0.9), ("z", 1.0)):
        for k in range(8):
            rows.append((g, k, 100 * ratio * (1 + 0.01 * k) if g != "z" else 100 * (1 + (-1) ** k * 0.1), 100))
    df = pd.DataFrame(rows, columns=["group", "replicate", "t_a", "t_b"]).assign(map="m", size="1", ok_a=True,
                                                                                ok_b=True, winner="a")
    out = effects.summarise(df, ["group"]).set_index("group")
    assert out.loc["x", "p_value"] == pytest.approx(2 / 256) and out.loc["y", "p_value"] == pytest.approx(2 / 256)
    assert list(out["p_holm"]) == pytest.approx(list(effects.holm(out["p_value"].to_numpy())))
    assert out.loc["x", "p_holm"] == pytest.approx(3 * 2 / 256)


def test_a_contrast_whose_maps_mostly_tie_has_its_side_from_the_test_not_the_median():
    """20 maps tie exactly (a radio that cannot matter), 12 favour a: the median ratio is 1, the test and
    :func:`.effects.a_faster` say a; with the signs swapped they say b."""
    for sign, expect in ((1, True), (-1, False)):
        ratios = [1.0] * 20 + [1 - sign * 0.05 * (1 + k / 12) for k in range(12)]
        df = pd.DataFrame({"replicate": range(len(ratios)), "t_a": [100 * r for r in ratios], "t_b": 100.0,
                           "group": "g"}).assign(map="m", size="1", ok_a=True, ok_b=True, winner="tie")
        out = effects.summarise(df, ["group"]).iloc[0]
        assert out["ratio"] == 1.0 and out["p_value"] < 0.001
        assert effects.a_faster(out) is expect


def test_summarise_is_reproducible_and_independent_of_other_rows():
    rng = np.random.default_rng(4)
    rows = [(g, k, float(rng.integers(50, 150)), 100.0) for g in ("a", "b") for k in range(10)]
    df = pd.DataFrame(rows, columns=["group", "replicate", "t_a", "t_b"]).assign(map="m", size="1", ok_a=True,
                                                                                ok_b=True, winner="a")
    both = effects.summarise(df, ["group"]).set_index("group")
    alone = effects.summarise(df[df["group"] == "b"], ["group"]).set_index("group")
    again = effects.summarise(df, ["group"]).set_index("group")
    assert both.loc["b", "ratio_low"] == alone.loc["b", "ratio_low"] == again.loc["b", "ratio_low"]
    assert both.loc["b", "ratio_high"] == alone.loc["b", "ratio_high"]


# ------------------------------------------------------------------------------------------ hook ----
def runs_frame(times: dict[tuple[str, str, str], list[float | None]], max_ticks: int = 1000) -> pd.DataFrame:
    """A runs-with-ticks frame: times[(algorithm, radio, robots)] = ticks per replicate (None: DNF)."""
    rows = []
    for (alg, radio, robots), values in times.items():
        for rep, t in enumerate(values):
            rows.append({"map": "building", "size": "50", "robots": robots, "spawn": "together", "algorithm": alg,
                         "radio": radio, "comm": "default", "transport": "inprocess", "replicate": rep,
                         "map_seed": 1000 + rep, "status": "ok", "key": f"{alg}-{radio}-{robots}-{rep}",
                         "success": t is not None, "ttt_or_max": float(max_ticks if t is None else t)})
    return pd.DataFrame(rows)


def test_compare_runs_pairs_by_map_and_applies_holm_across_the_list():
    slow = [200, 220, 240, 260, 280, 300]
    fast = [100, 120, 130, 150, None, 160]
    runs = runs_frame({("TNF", "maes", "4"): fast, ("TNF", "materials", "4"): slow,
                       ("Greed", "maes", "4"): slow, ("Greed", "materials", "4"): slow,
                       ("TNF", "maes", "1"): slow, ("TNF", "materials", "1"): slow})
    out = effects.compare_runs(runs, [
        ("TNF", {"algorithm": "TNF", "radio": "maes"}, {"algorithm": "TNF", "radio": "materials"}),
        ("Greed", {"algorithm": "Greed", "radio": "maes"}, {"algorithm": "Greed", "radio": "materials"}),
        ("TNF vs Greed", {"algorithm": "TNF", "robots": 4}, {"algorithm": "Greed", "robots": 4}),
    ]).set_index("name")
    tnf = out.loc["TNF"]
    assert (tnf["a"], tnf["b"]) == ("algorithm=TNF, radio=maes", "algorithm=TNF, radio=materials")
    # the 1-robot cell is left out of a radio-only contrast; the DNF counts at 1000 (ratio 1000/280)
    assert (tnf["cells"], tnf["pairs"], tnf["maps"], tnf["a_wins"], tnf["b_wins"], tnf["dnf_pairs"]) == (1, 6, 6, 5, 1, 1)
    assert tnf["median_a"] == pytest.approx(140) and tnf["median_b"] == pytest.approx(250)
    assert tnf["p_value"] == pytest.approx(brute_force_p(np.log([1 / 2, 120 / 220, 130 / 240, 150 / 260, 1000 / 280,
                                                                 160 / 300])))
    greed = out.loc["Greed"]
    assert greed["ties"] == 6 and greed["tested"] == 0 and np.isnan(greed["p_value"])
    both = out.loc["TNF vs Greed"]  # pairs on radio too: 2 cells x 6 maps, each map's value the mean of 2
    assert (both["cells"], both["pairs"], both["maps"]) == (2, 12, 6)
    tested = out["p_value"].notna()
    assert list(out.loc[tested, "p_holm"]) == pytest.approx(list(effects.holm(out.loc[tested, "p_value"].to_numpy())))
    assert tested.sum() == 2 and out.loc["TNF", "p_holm"] == pytest.approx(min(1, 2 * out.loc["TNF", "p_value"]))


def test_unit_log_ratios_are_the_values_compare_runs_tests():
    """Per map, the mean log ratio of the contrast's pairs (a DNF at its limit): the median of them is the
    summary's ratio, and one per map."""
    slow = [200, 220, 240, 260, 280, 300]
    fast = [100, 120, 130, 150, None, 160]
    runs = runs_frame({("TNF", "maes", "4"): fast, ("TNF", "materials", "4"): slow})
    a, b = {"algorithm": "TNF", "radio": "maes"}, {"algorithm": "TNF", "radio": "materials"}
    values = effects.unit_log_ratios(runs, a, b)
    assert list(values) == pytest.approx(list(np.log([1 / 2, 120 / 220, 130 / 240, 150 / 260, 1000 / 280, 160 / 300])))
    assert len(values.index.names) == len(effects.UNITS)
    summary = effects.compare_runs(runs, [("x", a, b)]).iloc[0]
    assert summary["ratio"] == pytest.approx(float(np.exp(np.median(values)))) and summary["maps"] == len(values)


def test_compare_runs_keeps_single_robot_cells_when_asked():
    runs = runs_frame({("TNF", "maes", "1"): [100] * 6, ("TNF", "materials", "1"): [100] * 6})
    kept = effects.compare_runs(runs, [("x", {"radio": "maes"}, {"radio": "materials"})], single_robot=True)
    dropped = effects.compare_runs(runs, [("x", {"radio": "maes"}, {"radio": "materials"})])
    assert kept.loc[0, "pairs"] == 6 and kept.loc[0, "ties"] == 6
    assert dropped.loc[0, "pairs"] == 0 and np.isnan(dropped.loc[0, "ratio"])


@pytest.mark.parametrize("a, b, needle", [
    ({"radio": "maes"}, {"radio": "maes"}, "select the same cells"),
    ({"size": 50}, {"size": 100}, "size = '100'"),
    ({"map": "building", "radio": "maes"}, {"map": "cave"}, "map = 'cave'"),
    ({"colour": "red"}, {"radio": "maes"}, "'colour', not a grid dimension"),
    ({"radio": ["maes", "materials"]}, {"radio": "global"}, "several runs per cell and replicate (radio"),
])
def test_compare_runs_refuses_comparisons_that_do_not_pair(a, b, needle):
    runs = runs_frame({("TNF", r, "4"): [100] * 6 for r in ("maes", "materials", "global")})
    with pytest.raises(ValueError, match=None) as err:
        effects.compare_runs(runs, [("bad", a, b)])
    assert needle in str(err.value) and str(err.value).startswith("bad: ")


def test_compare_runs_refuses_a_contrast_on_the_map():
    runs = pd.concat([runs_frame({("TNF", "maes", "4"): [100] * 6}),
                      runs_frame({("TNF", "maes", "4"): [200] * 6}).assign(map="cave")], ignore_index=True)
    with pytest.raises(ValueError, match="differ in map or size"):
        effects.compare_runs(runs, [("bad", {"map": "building"}, {"map": "cave"})])


def test_compare_cells_reads_a_results_folder_and_formats_a_table(tmp_path: Path):
    fakes = [FakeRun(alg, radio, rep, t) for alg, radio, base in (("greed", "global", 100), ("frontier", "global", 150),
                                                                   ("greed", "los", 110), ("frontier", "los", 170))
             for rep, t in enumerate([base + 10 * k for k in range(6)])]
    results = write(tmp_path / "results", fakes, replicates=6)
    data = load(results)
    out = effects.compare_cells(data, [("greed vs frontier", {"algorithm": "greed"}, {"algorithm": "frontier"}),
                                       ("global vs los", {"radio": "global"}, {"radio": "los"})])
    assert list(out["name"]) == ["greed vs frontier", "global vs los"]
    assert (out["pairs"] == 12).all() and (out["maps"] == 6).all() and (out["cells"] == 2).all()
    assert (out["a_wins"] == 12).all() and out["p_value"].iloc[0] == pytest.approx(1 / 32)
    assert out["p_holm"].iloc[0] == pytest.approx(2 / 32)
    # the same numbers from a target without a threshold column (read from the time series, rows every 10)
    series = effects.compare_cells(data, [("greed vs frontier", {"algorithm": "greed"}, {"algorithm": "frontier"})],
                                   target=0.85)
    assert series.loc[0, "pairs"] == 12 and series.loc[0, "ratio"] < 1
    table = effects.effects_table(out, ["name", "a", "b"], cells=True, maps=True)
    assert table.headers[:6] == ["Comparison", "a", "b", "Cells", "Pairs", "Maps"]
    assert table.rows[0][-4].startswith("0.") and "[" in table.rows[0][-4]
    assert set(DIMS) >= {"robots", "radio"}


# ---------------------------------------------------------------------------------- in the report ----
GRID = """
[campaign]
name = "grid"
seed = 5
replicates = 6

[grid]
map = ["building"]
size = [20]
robots = [1, 2]
spawn = ["together", "random"]
algorithm = ["greed", "frontier"]
radio = ["global", "los"]

[stop]
explored = 0.98
max_ticks = 1000
"""


def test_report_writes_per_dimension_and_pooled_tables(tmp_path: Path):
    fakes = []
    for robots, spawn, alg, radio in itertools.product(("1", "2"), ("together", "random"), ("greed", "frontier"),
                                                       ("global", "los")):
        for rep in range(6):
            t = 100 * (2 if robots == "1" else 1) + (40 if alg == "frontier" else 0) + 10 * rep
            t += 5 if radio == "los" and robots != "1" else 0
            t += 3 if spawn == "random" else 0
            fakes.append(FakeRun(alg, radio, rep, t, cell={"robots": robots, "spawn": spawn}))
    results = write(tmp_path / "results", fakes, spec_text=GRID)
    readme = build_report(results, tmp_path / "report", cell_figures=False).read_text()
    tables = tmp_path / "report" / "tables"
    for name in ("pooled", "paired", "paired_radio", "paired_robots", "paired_spawn"):
        for ext in ("md", "tex", "csv"):
            assert (tables / f"{name}.{ext}").exists(), (name, ext)
    radio = pd.read_csv(tables / "paired_radio.csv")
    assert set(radio["robots"]) == {2}, "1-robot cells are left out of the radio comparison"
    assert (radio["ratio"] < 1).all() and list(radio["p_value"]) == pytest.approx([1 / 32] * 4)
    assert "The 4 1-robot cells are left out" in (tables / "paired_radio.tex").read_text()
    pooled = pd.read_csv(tables / "pooled.csv").set_index(["dimension", "a", "b"])
    alg = pooled.loc[("algorithm", "greed", "frontier")]
    assert (alg["cells"], alg["pairs"], alg["maps"], alg["a_wins"]) == (8, 48, 6, 48)
    assert alg["p_value"] == pytest.approx(1 / 32), "6 maps, not 48 pairs, are the test's sample"
    assert pooled.loc[("radio", "global", "los"), "pairs"] == 24
    assert pooled.loc[("robots", "1", "2"), "ratio"] > 1
    assert list(pooled["p_holm"]) == pytest.approx(list(effects.holm(pooled["p_value"].to_numpy())))
    assert "### All cells pooled" in readme and "### Radio models, per cell" in readme
    assert "Holm family: the 4 tested comparisons of this table (every pair of values of every dimension)." in readme
    assert "| algorithm | greed | frontier | 8 | 48 | 6 | 48 | 0 | 0 | 0 |" in readme
    assert (tables / "pooled.md").read_text().startswith("*Paired comparisons with every cell pooled")
    comm = pd.read_csv(tables / "comm_effect.csv")
    assert comm.loc[comm["robots"] == 1, "as_expected"].isna().all()
    assert "**0 of 4 cells** break that order" in readme and "the 4 1-robot cells are not judged" in readme


def test_a_reports_runs_csv_read_back_gives_the_same_statistics(tmp_path: Path):
    fakes = [FakeRun(alg, radio, rep, None if (alg, rep) == ("frontier", 3) else base + 7 * k * k)
             for alg, radio, base in (("greed", "global", 100), ("frontier", "global", 150), ("greed", "los", 110),
                                      ("frontier", "los", 170)) for rep, k in enumerate(range(6))]
    results = write(tmp_path / "results", fakes, replicates=6)
    build_report(results, tmp_path / "report", cell_figures=False)
    comparisons = [("alg", {"algorithm": "greed"}, {"algorithm": "frontier"}),
                   ("radio", {"radio": "global"}, {"radio": "los"})]
    direct = effects.compare_cells(load(results), comparisons)
    back = effects.compare_runs(effects.read_runs_csv(tmp_path / "report/tables/runs.csv"), comparisons)
    pd.testing.assert_frame_equal(direct, back)
    assert direct.loc[0, "dnf_pairs"] == 2 and direct.loc[0, "a_wins"] == 12, "a DNF loses its pair"


def test_the_report_says_which_code_computed_its_runs(tmp_path: Path):
    """Each run's swarm_version reaches runs.csv and the README counts them; runs of two versions, or of a
    changed checkout, are flagged."""
    fakes = [FakeRun(alg, "global", rep, 100 + rep, version="0.1.0+git.aaaa" if rep < 4 else "0.1.0+git.bbbb-dirty")
             for alg in ("greed", "frontier") for rep in range(6)]
    results = write(tmp_path / "results", fakes)
    readme = build_report(results, tmp_path / "report", cell_figures=False).read_text()
    runs = pd.read_csv(tmp_path / "report" / "tables" / "runs.csv")
    assert runs["swarm_version"].value_counts().to_dict() == {"0.1.0+git.aaaa": 8, "0.1.0+git.bbbb-dirty": 4}
    assert "Computed by swarm `0.1.0+git.aaaa` (8 runs), `0.1.0+git.bbbb-dirty` (4 runs)." in readme
    assert "More than one version of the code" in readme and "uncommitted changes" in readme
    one = write(tmp_path / "one", [FakeRun("greed", "global", rep, 100 + rep, version="0.1.0+git.aaaa")
                                   for rep in range(6)])
    readme = build_report(one, tmp_path / "report1", cell_figures=False).read_text()
    assert "Computed by swarm `0.1.0+git.aaaa` (6 runs)." in readme and "More than one" not in readme
