"""Radio and comm parameters as grid axes: both ways of writing them, rules that name them, their values in
every run spec and in the runs table, and one-line errors that name the field."""

from __future__ import annotations

import pandas as pd
import pytest

from maps import InvalidInput
from swarm.campaign import make_executor, parse_campaign, run_campaign
from swarm.campaign.store import ResultsStore

HEAD = """
[campaign]
name = "axes"
seed = 3
replicates = 1

[grid]
map = ["building"]
size = [20]
robots = [2]
spawn = ["together"]
algorithm = ["greed"]
"""
NESTED = HEAD + """
radio.model = ["global", "multiwall"]
radio.sensitivity_dbm = [-70, -88.5]
comm.loss = [0, 0.25]

[stop]
max_ticks = 30
"""
QUOTED = HEAD + """
radio = ["global", "multiwall"]
"radio.sensitivity_dbm" = [-70, -88.5]
"comm.loss" = [0, 0.25]

[stop]
max_ticks = 30
"""


def error_of(text: str) -> InvalidInput:
    with pytest.raises(InvalidInput) as info:
        parse_campaign(text)
    assert "\n" not in str(info.value) and len(str(info.value)) < 400, str(info.value)
    return info.value


def test_nested_and_quoted_axes_give_the_same_runs():
    nested, quoted = parse_campaign(NESTED), parse_campaign(QUOTED)
    assert nested.axes == quoted.axes == ("radio.sensitivity_dbm", "comm.loss")
    assert [r.key for r in nested.runs()] == [r.key for r in quoted.runs()]
    runs = nested.runs()
    assert len(runs) == 2 * 2 * 2
    seen = {(r.cell["radio"], r.cell["radio.sensitivity_dbm"], r.cell["comm.loss"]):
            (r.spec.radio.model, r.spec.radio.sensitivity_dbm, r.spec.comm.loss) for r in runs}
    assert seen[("multiwall", "-88.5", "0.25")] == ("multiwall", -88.5, 0.25)
    assert seen[("global", "-70", "0")] == ("global", -70.0, 0.0)


def test_radio_axes_alone_sweep_the_default_model():
    spec = parse_campaign(HEAD + "radio.sensitivity_dbm = [-70, -80]\n")
    assert [o.label for o in spec.grid["radio"]] == ["multiwall"]
    assert {r.spec.radio.sensitivity_dbm for r in spec.runs()} == {-70.0, -80.0}


def test_an_axis_overrides_run_and_rules_name_axes():
    text = NESTED + '[run]\ncomm = {loss = 0.5, bandwidth = 900}\n'
    text += '\n[[exclude]]\n"radio.sensitivity_dbm" = -70\nradio = "global"\n'
    text += '\n[[exclude]]\ncomm.loss = 0.25\nradio.model = "global"\n'
    runs = parse_campaign(text).runs()
    cells = {(r.cell["radio"], r.cell["radio.sensitivity_dbm"], r.cell["comm.loss"]) for r in runs}
    assert cells == {("global", "-88.5", "0"), ("multiwall", "-70", "0"), ("multiwall", "-70", "0.25"),
                     ("multiwall", "-88.5", "0"), ("multiwall", "-88.5", "0.25")}
    assert all(r.spec.comm.bandwidth == 900 and r.spec.comm.loss in (0.0, 0.25) for r in runs)


def test_an_include_adds_a_value_outside_the_axis():
    rule = '\n[[include]]\nradio = "multiwall"\n"radio.sensitivity_dbm" = -94\n"comm.loss" = 0\n'
    spec = parse_campaign(NESTED + rule)
    extra = [r for r in spec.runs() if r.cell["radio.sensitivity_dbm"] == "-94"]
    assert len(extra) == 1 and extra[0].spec.radio.sensitivity_dbm == -94.0


@pytest.mark.parametrize("old, new, field, needle", [
    ("comm.loss = [0, 0.25]", "comm.loss = [0, 1.5]", "grid.comm.loss[1]", ">= 0 and <= 1"),
    ("comm.loss = [0, 0.25]", "comm.lost = [0]", "grid.comm.lost", "a comm parameter with plain values"),
    ("comm.loss = [0, 0.25]", "comm.loss = 0.25", "grid.comm.loss", "a list"),
    ("comm.loss = [0, 0.25]", "comm.loss = [0, 0.0]", "grid.comm.loss", "distinct values"),
    ("comm.loss = [0, 0.25]", 'comm.loss = [0, "x"]', "grid.comm.loss[1]", "a finite number"),
    ("radio.sensitivity_dbm = [-70, -88.5]", "radio.sensitivity_dbm = [-70, [1]]", "grid.radio.sensitivity_dbm[1]",
     "a plain value"),
    ("radio.sensitivity_dbm = [-70, -88.5]", "radio.max_range_m = [3.0]", "grid.radio.max_range_m[0]",
     "only with model = 'los'"),
    ("radio.sensitivity_dbm = [-70, -88.5]", "radio.materials = [1]", "grid.radio.materials",
     "a radio parameter with plain values"),
])
def test_a_bad_axis_is_one_line_naming_the_field(old, new, field, needle):
    assert old in NESTED
    err = error_of(NESTED.replace(old, new))
    assert err.field == field and needle in str(err), str(err)


def test_an_entry_setting_an_axis_parameter_is_refused():
    text = QUOTED.replace('radio = ["global", "multiwall"]',
                          'radio = [{model = "multiwall", sensitivity_dbm = -80, label = "mw"}]')
    err = error_of(text)
    assert err.field == "grid.radio" and "radio.sensitivity_dbm is a grid axis" in str(err)


def test_output_robot_series_every_must_fit_the_time_series():
    assert parse_campaign(NESTED + "[output]\nrobot_series_every = 0\n").robot_series_every == 0
    err = error_of(NESTED + "[output]\ntimeseries_every = 10\nrobot_series_every = 15\n")
    assert err.field == "output.robot_series_every" and "multiple of timeseries_every (10)" in str(err)


def test_axis_labels_and_comm_metrics_reach_the_parquet_results(tmp_path):
    spec = parse_campaign(NESTED + "[output]\ntimeseries_every = 5\nrobot_series_every = 10\n")
    run_campaign(spec, tmp_path, executor=make_executor(inline=True), progress=False)
    store = ResultsStore(tmp_path)
    runs = store.runs_table().to_pandas()
    assert sorted(set(runs["radio.sensitivity_dbm"])) == ["-70", "-88.5"] and set(runs["comm.loss"]) == {"0", "0.25"}
    assert runs["aoi_age_mean"].notna().all() and runs["msgs_dropped_loss"].sum() > 0
    ts = store.timeseries_table().to_pandas()
    assert {"missing_free_mean", "aoi_age_max", "msgs_dropped_link"} <= set(ts.columns)
    robots = store.robots_table().to_pandas()
    assert set(robots["robot"]) == {0, 1} and {"missing_free", "aoi_age", "since_contact", "group"} <= set(robots)
    per_run = robots.groupby("key")["tick"].agg(lambda t: sorted(set(t)))
    finals = dict(zip(runs["key"], runs["ticks"]))
    for key, ticks in per_run.items():
        assert all(t % 10 == 0 for t in ticks[:-1]) and ticks[-1] == finals[key]


MOTION = HEAD + """
radio = ["global"]
motion.model = ["continuous", "maes"]
"robots.heading" = ["random", "maes"]

[run]
motion = {max_speed = 3.0, max_turn_rate = 4.0, max_accel = 60.0, max_turn_accel = 120.0}

[stop]
max_ticks = 30
"""


def test_the_motion_model_and_the_spawn_heading_are_axes():
    """Issue 49: MAES's motion and MAES's spawn heading can be switched per cell (the ablation's departures)."""
    runs = parse_campaign(MOTION).runs()
    assert len(runs) == 4
    for run in runs:
        assert run.spec.motion.model == run.cell["motion.model"]
        assert run.spec.robots.heading == run.cell["robots.heading"]
        assert run.spec.motion.max_speed == 3.0      # the axis joins [run]'s motion table
    assert len({r.spec.robots.spawn_seed for r in runs}) == 1   # the same worlds in every cell


def test_run_may_set_the_heading_but_not_the_robot_count():
    text = HEAD + 'radio = ["global"]\n[run]\nrobots = {heading = "maes"}\n[stop]\nmax_ticks = 30\n'
    assert {r.spec.robots.heading for r in parse_campaign(text).runs()} == {"maes"}
    err = error_of(text.replace('robots = {heading = "maes"}', "robots = {count = 4}"))
    assert err.field == "run.robots" and "only {heading = ...}" in str(err)
    err = error_of(MOTION.replace('motion.model = ["continuous", "maes"]', 'motion.model = ["continuous", "unity"]'))
    assert err.field == "grid.motion.model[1]" and "'maes'" in str(err)
    err = error_of(MOTION.replace('"robots.heading" = ["random", "maes"]', '"robots.count" = [3]'))
    assert err.field == "grid.robots.count" and "heading" in str(err)


def test_figure_panels_may_fix_or_compare_an_axis(tmp_path):
    """The ablation's figures hold MAES's motion fixed, and one compares the motion models."""
    from pathlib import Path

    from swarm.campaign.report.layout import check_layout, load_layout, parse_layout

    layout = parse_layout('[[figure]]\nname = "f"\ntitle = "t"\n[[figure.panel]]\ncompare = "algorithm"\n'
                          '"motion.model" = "maes"\n[[figure.panel]]\ncompare = "motion.model"\nmap = "cave"\n')
    assert layout[0].panels[0].fixed == (("motion.model", "maes"),)
    assert layout[0].panels[1].compare == "motion.model"
    check_layout(layout, {"algorithm": ["greed"], "map": ["cave"], "motion.model": ["maes", "continuous"]})
    with pytest.raises(InvalidInput) as info:
        check_layout(layout, {"algorithm": ["greed"], "map": ["cave"], "motion.model": ["continuous"]})
    assert info.value.field == "figure[0].panel[0].motion.model"
    with pytest.raises(InvalidInput, match="grid axis"):
        parse_layout('[[figure]]\nname = "f"\ntitle = "t"\n[[figure.panel]]\ncompare = "algorithm"\nmotor = 1\n')
    root = Path(__file__).resolve().parents[3]
    figures = load_layout(root / "examples" / "minotaur-ablation-figures.toml")
    spec = parse_campaign((root / "examples" / "minotaur-ablation.toml").read_text())
    orders = {dim: [o.label for o in opts] for dim, opts in spec.grid.items()}
    for rule in spec.include:   # labels the includes add
        for dim, value in rule.items():
            for v in value if isinstance(value, list) else [value]:
                label = v.get("label") if isinstance(v, dict) else str(v)
                if label not in orders.setdefault(dim, []):
                    orders[dim].append(label)
    check_layout(figures, orders)


def test_localization_axes_and_map_quality_reach_the_runs_table_and_report(tmp_path):
    """Issue 50: a drift sweep is a grid axis; runs with a localisation model fill the pose-error and
    map-quality columns, runs without leave them null, and the report's runs table carries them."""
    from swarm.campaign.report import build_report

    text = HEAD + 'radio = ["global"]\n"localization.model" = ["perfect", "odometry"]\n' \
                  '"localization.drift_per_m" = [0.05]\n[stop]\nmax_ticks = 60\n'
    spec = parse_campaign(text)
    assert {r.spec.localization.model for r in spec.runs()} == {"perfect", "odometry"}
    run_campaign(spec, tmp_path / "res", executor=make_executor(inline=True), progress=False)
    runs = ResultsStore(tmp_path / "res").runs_table().to_pandas().set_index("localization.model")
    assert runs.loc["perfect", ["pose_error_m", "false_free_share", "false_occupied_share"]].isna().all()
    assert runs.loc["odometry", "pose_error_m"] >= 0 and runs.loc["odometry", "false_occupied_share"] >= 0
    build_report(tmp_path / "res", tmp_path / "report")
    header = (tmp_path / "report" / "tables" / "runs.csv").read_text().splitlines()[0].split(",")
    assert {"localization.model", "pose_error_m", "false_free_share", "false_occupied_share", "wall_offset_m",
            "explored_correct"} <= set(header)
    quality = (tmp_path / "report" / "tables" / "map_quality.csv").read_text().splitlines()
    assert quality[0].startswith("localization.model,runs,pose_error_m") and len(quality) == 3
    readme = (tmp_path / "report" / "README.md").read_text()
    assert "## Localisation and map quality" in readme and "counts only correctly known cells" in readme
    assert runs.loc["odometry", "explored_measure"] == "correct" and pd.isna(runs.loc["perfect", "explored_measure"])
    report_runs = pd.read_csv(tmp_path / "report" / "tables" / "runs.csv").set_index("localization.model")
    assert report_runs.loc["odometry", "explored"] == pytest.approx(runs.loc["odometry", "explored_correct"])
    assert report_runs.loc["perfect", "explored"] == pytest.approx(runs.loc["perfect", "explored"])
    err = error_of(text.replace('"localization.drift_per_m" = [0.05]', '"localization.drift_per_m" = [2]'))
    assert err.field == "grid.localization.drift_per_m[0]"


def test_collisions_split_reaches_the_runs_table_and_report(tmp_path):
    """Issue 50: robot-wall and robot-robot contacts are runs-table columns, and the report tabulates them per
    robot-hour per cell."""
    from swarm.campaign.report import build_report

    text = HEAD.replace("robots = [2]", "robots = [2, 8]") + 'radio = ["global"]\n[stop]\nmax_ticks = 150\n'
    run_campaign(parse_campaign(text), tmp_path / "res", executor=make_executor(inline=True), progress=False)
    runs = ResultsStore(tmp_path / "res").runs_table().to_pandas().set_index("robots")
    assert runs["collisions_robot"].dtype.kind == "i" and runs.loc[8, "collisions_robot"] > 0
    assert (runs["collisions"] <= runs["collisions_wall"] + runs["collisions_robot"]).all()
    build_report(tmp_path / "res", tmp_path / "report")
    table = (tmp_path / "report" / "tables" / "collisions.csv").read_text().splitlines()
    assert table[0] == "robots,runs,collisions_wall,collisions_robot" and len(table) == 3
    row8 = dict(zip(table[0].split(","), table[2].split(",")))
    hours = 8 * runs.loc[8, "ticks"] * 0.1 / 3600
    assert float(row8["collisions_robot"]) == pytest.approx(runs.loc[8, "collisions_robot"] / hours)
    assert "## Collisions" in (tmp_path / "report" / "README.md").read_text()
    header = (tmp_path / "report" / "tables" / "runs.csv").read_text().splitlines()[0].split(",")
    assert {"collisions_wall", "collisions_robot"} <= set(header)


def test_benchmark_metrics_reach_the_runs_table_and_report(tmp_path):
    """Issue 52: path length per robot and its spread, overlap rate and coverage spread are runs-table columns,
    and the report tabulates them with times to 90/99 % and MAES's connectivity shares per cell."""
    from swarm.campaign.report import build_report
    from swarm.results.schema import BENCHMARK_RUN_COLUMNS

    text = HEAD.replace("robots = [2]", "robots = [2, 4]") + 'radio = ["global"]\n[stop]\nmax_ticks = 400\n'
    run_campaign(parse_campaign(text), tmp_path / "res", executor=make_executor(inline=True), progress=False)
    runs = ResultsStore(tmp_path / "res").runs_table().to_pandas().set_index("robots")
    for col in BENCHMARK_RUN_COLUMNS:
        assert runs[col].dtype.kind == "f" and runs[col].notna().all(), col
    assert ((runs["overlap_rate"] >= 0) & (runs["overlap_rate"] <= 1)).all()
    assert runs["path_length_mean_m"].mul(runs.index).to_numpy() == pytest.approx(runs["distance_m"].to_numpy())
    build_report(tmp_path / "res", tmp_path / "report")
    table = (tmp_path / "report" / "tables" / "benchmark.csv").read_text().splitlines()
    assert table[0] == ("robots,runs,t90_s,t99_s,path_length_mean_m,path_length_cv,overlap_rate,coverage_spread,"
                        "all_connected_share,biggest_group_mean") and len(table) == 3
    row4 = dict(zip(table[0].split(","), table[2].split(",")))
    assert float(row4["overlap_rate"]) == pytest.approx(runs.loc[4, "overlap_rate"])
    assert float(row4["all_connected_share"]) == pytest.approx(runs.loc[4, "all_connected_share"])
    if pd.notna(runs.loc[4, "t90"]):
        assert float(row4["t90_s"]) == pytest.approx(runs.loc[4, "t90"] * 0.1)
    readme = (tmp_path / "report" / "README.md").read_text()
    assert "## Benchmark metrics" in readme and "Coverage spread" in readme


def test_a_report_accepts_panels_that_fix_an_axis_with_one_value_so_far(tmp_path):
    """A campaign part-way through (issue 49's ablation before its motion slice ran) has one value of an
    axis the figures fix: the report is built, not refused for a dimension "not of this campaign"."""
    from swarm.campaign.report import build_report

    spec = parse_campaign(HEAD + 'radio = ["global"]\nmotion.model = ["maes"]\n[stop]\nmax_ticks = 20\n')
    run_campaign(spec, tmp_path / "out", executor=make_executor(inline=True), progress=False)
    figures = tmp_path / "figures.toml"
    figures.write_text('[[figure]]\nname = "f"\ntitle = "t"\n[[figure.panel]]\ncompare = "algorithm"\n'
                       '"motion.model" = "maes"\n')
    readme = build_report(tmp_path / "out", tmp_path / "report", figures_file=figures, cell_figures=False)
    assert (tmp_path / "report" / "figures" / "f.png").is_file() and readme.is_file()
    figures.write_text(figures.read_text().replace('= "maes"', '= "continuous"'))
    with pytest.raises(InvalidInput) as info:
        build_report(tmp_path / "out", tmp_path / "report2", figures_file=figures, cell_figures=False)
    assert info.value.field == "figure[0].panel[0].motion.model"
