"""The Python API: swarm.run and swarm.campaign.run / load / load_timeseries read input as the command line
does (the same spec, the same one-line errors) and return what the CLI writes."""

from __future__ import annotations

import json
from pathlib import Path

import pandas as pd
import pytest

import swarm
from maps import InvalidInput
from swarm.campaign import deterministic_rows
from swarm.cli import main
from swarm.results.schema import RUNS, TIMESERIES


def cli_spec(argv: list[str], capsys) -> str:
    """The key of the spec ``swarm run ARGV --print-spec`` prints."""
    assert main(["run", *argv, "--print-spec"]) == 0
    return swarm.RunSpec.from_mapping(__import__("tomllib").loads(capsys.readouterr().out)).key


def cli_error(argv: list[str], capsys) -> str:
    assert main(argv) == 2
    return capsys.readouterr().err.strip().removeprefix("swarm: error: ")


@pytest.mark.parametrize("argv, kwargs", [
    ([], {}),
    (["--robots", "8", "--map", "cave", "--size", "60", "--seed", "3"], {"robots": 8, "map": "cave", "size": 60, "seed": 3}),
    (["--algorithm", "tnf", "--param", "alpha=2.0", "--set", "radio.model=los", "--set", "lidar.range_m=4"],
     {"algorithm": "tnf", "params": {"alpha": 2.0}, "radio": "los", "lidar": {"range_m": 4}}),
    (["--map-param", "door_width=2", "--max-ticks", "500", "--explored", "0.9", "--spawn", "random"],
     {"map_params": {"door_width": 2}, "max_ticks": 500, "explored": 0.9, "spawn": "random"}),
])
def test_overrides_build_the_spec_the_cli_builds(argv, kwargs, capsys):
    assert swarm.resolve_spec(**kwargs).key == cli_spec(argv, capsys)


def test_a_spec_file_toml_text_and_a_runspec_read_alike(tmp_path, capsys):
    text = 'seed = 4\nrobots = { count = 3 }\n[map]\nkind = "cave"\nsize = 40\n'
    path = tmp_path / "run.toml"
    path.write_text(text)
    key = cli_spec(["--spec", str(path), "--robots", "5"], capsys)
    assert swarm.resolve_spec(path, robots=5).key == key
    assert swarm.resolve_spec(str(path), robots=5).key == key
    assert swarm.resolve_spec(text, robots=5).key == key
    assert swarm.resolve_spec(swarm.resolve_spec(path), robots=5).key == key
    assert swarm.resolve_spec({"seed": 4, "robots": {"count": 3}, "map": {"kind": "cave", "size": 40}}, robots=5).key == key


def test_run_returns_the_result_the_cli_writes(tmp_path, capsys):
    out = tmp_path / "r.json"
    assert main(["run", "--robots", "2", "--size", "20", "--max-ticks", "150", "--json", str(out)]) == 0
    written = json.loads(out.read_text())
    result = swarm.run(robots=2, size=20, max_ticks=150)
    assert result.key == written["key"]
    assert result.deterministic_view()["summary"] == {k: v for k, v in written["summary"].items()
                                                      if not k.endswith("_time_s")}
    assert result.timeseries == written["timeseries"]


@pytest.mark.parametrize("argv, kwargs", [
    (["run", "--set", "robots.count=0"], {"robots": 0}),
    (["run", "--set", "lidar.range_m=-1"], {"lidar": {"range_m": -1}}),
    (["run", "--spec", "BAD"], {"spec": "BAD"}),
    (["run", "--set", "stop.explored=2"], {"explored": 2}),
    (["run", "--algorithm", "no-such-explorer"], {"algorithm": "no-such-explorer"}),
])
def test_errors_are_the_clis_one_line_errors(argv, kwargs, capsys, tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("robots = = 2\n")
    argv = [str(bad) if a == "BAD" else a for a in argv]
    expected = cli_error(argv, capsys)
    spec = str(bad) if kwargs.pop("spec", None) else None
    with pytest.raises(InvalidInput) as exc:
        swarm.run(spec, **kwargs)
    message = str(exc.value)
    assert "\n" not in message
    if spec is None:
        assert message == expected
    else:  # the field is the argument's name, the rest is the CLI's
        assert message.replace("spec:", "--spec:", 1) == expected


@pytest.mark.parametrize("kwargs, field", [({"robts": 2}, "robts"), ({"lidar": 3}, "lidar"), ({"map": 5}, "map"),
                                           ({"params": [1]}, "params"), ({"map": "cavee"}, "map"),
                                           ({"map": "x.npz", "size": 30}, "size"),
                                           ({"motion": {"max_speed": -1}}, "motion.max_speed")])
def test_unknown_or_ill_typed_keywords_are_one_line_errors(kwargs, field):
    with pytest.raises(InvalidInput) as exc:
        swarm.run(**kwargs)
    assert str(exc.value).startswith(f"{field}: got ")


GRID = {"campaign": {"name": "api", "seed": 5, "replicates": 2},
        "grid": {"map": ["building"], "size": [20], "robots": [1, 2], "spawn": ["together"],
                 "algorithm": ["frontier", "greed"], "radio": ["global"]},
        "stop": {"explored": 0.7, "max_ticks": 200}}


def test_campaign_run_load_and_timeseries(tmp_path, capsys):
    import tomli_w

    spec = tmp_path / "grid.toml"
    spec.write_text(tomli_w.dumps(GRID))
    assert main(["campaign", "run", str(spec), "-o", str(tmp_path / "cli"), "--inline", "--quiet"]) == 0
    out = swarm.campaign.run(GRID, tmp_path / "api", inline=True)
    assert (out.total, out.ran, out.skipped, out.failed) == (8, 8, 0, 0)
    assert deterministic_rows(tmp_path / "api") == deterministic_rows(tmp_path / "cli")
    again = swarm.campaign.run(spec, tmp_path / "api", inline=True)
    assert (again.ran, again.skipped) == (0, 8), "a results folder resumes"
    runs = swarm.campaign.load(tmp_path / "api")
    assert isinstance(runs, pd.DataFrame) and len(runs) == 8 and set(RUNS) <= set(runs.columns)
    assert runs["index"].tolist() == list(range(8))
    assert runs.equals(out.runs())
    series = swarm.campaign.load_timeseries(tmp_path / "api")
    assert set(TIMESERIES) <= set(series.columns) and {"algorithm", "robots", "replicate"} <= set(series.columns)
    for key, rows in series.groupby("key"):
        run = runs.set_index("key").loc[key]
        assert rows["tick"].tolist() == sorted(rows["tick"]) and rows["tick"].iloc[-1] == run["ticks"]
        assert rows["explored"].iloc[-1] == pytest.approx(run["explored"])
        assert (rows["algorithm"] == run["algorithm"]).all()
    one = runs["key"].iloc[3]
    assert set(swarm.campaign.load_timeseries(tmp_path / "api", keys=[one])["key"]) == {one}


UNGUARDED_SCRIPT = """
import sys
import swarm
print("script body ran", flush=True)
out = swarm.campaign.run(sys.argv[1], sys.argv[2], workers=2)
print("ran", out.ran, "of", out.total, "failed", out.failed)
"""


def test_a_campaign_script_without_a_main_guard_runs_as_written(tmp_path):
    """The README's ``swarm.campaign.run(...)`` saved as a script, with no ``if __name__ == "__main__":``:
    the pool's workers must not run the script again (they did, and the pool broke)."""
    import os
    import subprocess
    import sys

    import tomli_w

    spec = tmp_path / "grid.toml"
    spec.write_text(tomli_w.dumps(GRID))
    script = tmp_path / "grid.py"
    script.write_text(UNGUARDED_SCRIPT)
    root = str(Path(swarm.__file__).resolve().parents[1])
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [root, os.environ.get("PYTHONPATH")]))}
    proc = subprocess.run([sys.executable, str(script), str(spec), str(tmp_path / "out")], capture_output=True,
                          text=True, timeout=300, cwd=tmp_path, env=env, check=False)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert proc.stdout.splitlines() == ["script body ran", "ran 8 of 8 failed 0"], proc.stdout
    assert "Traceback" not in proc.stderr and len(swarm.campaign.load(tmp_path / "out")) == 8


MAIN_ALGORITHM_SCRIPT = """
import sys
import swarm
from algorithms.greed import Greed


class MyGreed(Greed):
    pass


spec = sys.argv[1]
try:
    swarm.campaign.run(spec, sys.argv[2], workers=2)
except swarm.InvalidInput as exc:
    print(exc)
print(swarm.campaign.run(spec, sys.argv[2] + "-inline", inline=True).ran)
"""


def test_an_algorithm_defined_in_the_script_is_refused_on_the_pool_and_runs_inline(tmp_path):
    """Pool workers do not run the caller's script, so a class defined there cannot run in them: one line,
    before the pool runs anything, instead of every run failing; inline, in the script's own process, it runs."""
    import os
    import subprocess
    import sys

    import tomli_w

    spec = tmp_path / "grid.toml"
    spec.write_text(tomli_w.dumps({**GRID, "grid": {**GRID["grid"], "algorithm": ["__main__:MyGreed"]}}))
    script = tmp_path / "mine.py"
    script.write_text(MAIN_ALGORITHM_SCRIPT)
    root = str(Path(swarm.__file__).resolve().parents[1])
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [root, os.environ.get("PYTHONPATH")]))}
    proc = subprocess.run([sys.executable, str(script), str(spec), str(tmp_path / "out")], capture_output=True,
                          text=True, timeout=300, cwd=tmp_path, env=env, check=False)
    assert proc.returncode == 0, proc.stderr[-2000:]
    refusal, ran = proc.stdout.splitlines()
    assert refusal.startswith("algorithm.name: got '__main__:MyGreed'; allowed: a class in an importable module")
    assert ran == "4"
    written = swarm.campaign.load(tmp_path / "out")  # the warm-up run in the script's process may be there
    assert (written["status"] == "ok").all(), "no run failed"


@pytest.mark.parametrize("kwargs, field", [
    ({"inline": True, "workers": 2}, "--inline"), ({"dask": "nowhere"}, "--dask"), ({"shard": "3/2"}, "--shard"),
    ({"workers": 0}, "--workers"), ({"dask": object()}, "dask"),
])
def test_campaign_errors_are_one_line(kwargs, field, tmp_path):
    with pytest.raises(InvalidInput) as exc:
        swarm.campaign.run(GRID, tmp_path / "x", **kwargs)
    assert str(exc.value).startswith(f"{field}: got ")


@pytest.mark.parametrize("observers, field", [(5, "observers"), ("print", "observers"), ([print, 5], "observers[1]"),
                                              (print, "observers")])
def test_observers_that_are_not_a_list_of_callables_are_one_line_errors(observers, field):
    with pytest.raises(InvalidInput) as exc:
        swarm.run({"map": {"size": 20}}, observers=observers, max_ticks=3)
    assert str(exc.value).startswith(f"{field}: got ") and "\n" not in str(exc.value)


@pytest.mark.parametrize("kwargs, field", [({"shard": (1, 2)}, "--shard"), ({"shard": 1}, "--shard"),
                                           ({"out": 5}, "-o"), ({"out": ""}, "-o"),
                                           ({"retry_failed": set()}, "--retry-failed"),  # found by the fuzz
                                           ({"retry_failed": "yes"}, "--retry-failed"), ({"progress": 1}, "progress")])
def test_campaign_run_arguments_of_the_wrong_type_are_one_line_errors(kwargs, field, tmp_path):
    args = {"out": tmp_path / "x", "inline": True, **kwargs}
    with pytest.raises(InvalidInput) as exc:
        swarm.campaign.run(GRID, args.pop("out"), **args)
    assert str(exc.value).startswith(f"{field}: got ")
    assert not (tmp_path / "x").exists()


@pytest.mark.parametrize("folder", [None, 5, "", ["a"]])
@pytest.mark.parametrize("load", ["load", "load_timeseries"])
def test_campaign_load_of_a_non_path_is_a_one_line_error(folder, load):
    with pytest.raises(InvalidInput, match="^DIR: got "):
        getattr(swarm.campaign, load)(folder)


def test_campaign_spec_and_folder_errors(tmp_path, capsys):
    bad = {**GRID, "grid": {**GRID["grid"], "robots": "two"}}
    with pytest.raises(InvalidInput, match=r"^grid\.robots: got 'two'"):
        swarm.campaign.run(bad, tmp_path / "x", inline=True)
    with pytest.raises(InvalidInput) as exc:
        swarm.campaign.load(tmp_path)
    assert str(exc.value) == cli_error(["campaign", "report", str(tmp_path)], capsys)
    with pytest.raises(InvalidInput, match="^DIR: got"):
        swarm.campaign.load_timeseries(tmp_path / "missing")


def test_a_results_repr_is_one_short_line():
    result = swarm.run({"map": {"size": 20}, "record_every": 1}, max_ticks=400, explored=1.0)
    assert len(result.timeseries["tick"]) > 300
    text = repr(result)
    assert len(text) < 300 and "\n" not in text and text.startswith(f"RunResult(key={result.key!r}, ")
    assert "time-series rows" in text
