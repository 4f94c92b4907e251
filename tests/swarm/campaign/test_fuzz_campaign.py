"""Fuzzing the campaign inputs (issue 31): campaign TOML (random bytes, random structures of plausible keys
and values, mutations of a valid spec), figure layout files, and the flags of ``swarm campaign run``,
``status`` and ``report``. Every case must end in a result or one short line ``swarm: error: ...`` with exit
status 2: never a traceback, a hang or unbounded work.

Cases per run (``max_examples``): 300 + 600 + 600 + 300 + 200 + 100 + 250 + 60 + 100 = 2,510 in total
(~20 s on a 2-core machine); ``--hypothesis-show-statistics`` shows how many were accepted.

Damaged results folders (issue 48): 300 damaged copies of a real folder through status, load and
load_timeseries, and 40 more through ``campaign report`` and a resume (~2 min): 340 cases.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Iterator
from pathlib import Path

import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from maps import InvalidInput
from swarm.campaign import make_executor, parse_campaign, run_campaign
from swarm.campaign.report.layout import check_layout, parse_layout
from swarm.cli import main
from swarm.results.schema import NONDETERMINISTIC_COLUMNS

from .test_campaign import TINY

ROOT = Path(__file__).resolve().parents[3]
FIGURES = (ROOT / "examples" / "minotaur-paper-figures.toml").read_text()
SMALL = (TINY.replace("replicates = 2", "replicates = 1").replace('map = ["building", "cave"]', 'map = ["building"]')
         .replace("robots = [1, 2]", "robots = [1]").replace("max_ticks = 250", "max_ticks = 30"))
"""4 runs of 30 ticks: the spec of the results folder the CLI fuzzing uses."""
MAX_MESSAGE = 500

FUZZ = settings(deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
                database=None)


def check_parse(text: str) -> None:
    """A campaign text parses, or fails with one short line."""
    try:
        spec = parse_campaign(text)
    except InvalidInput as exc:
        msg = str(exc)
        assert "\n" not in msg and "\r" not in msg and len(msg) < MAX_MESSAGE, msg
        event(f"refused: {exc.field.split('[')[0].split('.')[0]}")
        return
    event("accepted")
    assert spec.run_count() >= 1
    first = spec.run_at(0)
    assert first.key == first.spec.key


def check_cli(capfd, argv: list[str]) -> int:
    """``swarm ARGV`` in this process: exit 0, or 2 with exactly one short error line on stderr."""
    capfd.readouterr()
    code = main(argv)
    out, err = capfd.readouterr()
    assert code in (0, 2), (argv, code, err)
    event(f"exit {code}")
    if code == 2:
        lines = err.strip("\n").split("\n")
        assert lines[-1].startswith("swarm: error: "), (argv, err)
        assert len(lines[-1]) < MAX_MESSAGE and "Traceback" not in err, (argv, err)
        assert all(not line.startswith("swarm: error") for line in lines[:-1]), err
    return code


# ------------------------------------------------------------------------- TOML text generation ----
def toml_string(text: str) -> str:
    """A TOML basic string (JSON's escapes, but astral characters raw rather than as surrogate pairs)."""
    return json.dumps(text, ensure_ascii=False).replace("\x7f", "\\u007f")


def toml_value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        return "nan" if math.isnan(v) else ("inf" if v > 0 else "-inf") if math.isinf(v) else repr(v)
    if isinstance(v, str):
        return toml_string(v)
    if isinstance(v, list):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    return "{" + ", ".join(f"{json.dumps(k)} = {toml_value(x)}" for k, x in v.items()) + "}"


def toml_text(doc: dict) -> str:
    """``doc`` as TOML: top-level values first, then [tables] and [[arrays of tables]]."""
    head, tables = [], []
    for section, body in doc.items():
        key = json.dumps(section)
        if isinstance(body, list) and body and all(isinstance(t, dict) for t in body):
            for table in body:
                tables.append(f"[[{key}]]")
                tables += [f"{json.dumps(k)} = {toml_value(v)}" for k, v in table.items()]
        elif isinstance(body, dict):
            tables.append(f"[{key}]")
            tables += [f"{json.dumps(k)} = {toml_value(v)}" for k, v in body.items()]
        else:
            head.append(f"{key} = {toml_value(body)}")
    return "\n".join(head + tables) + "\n"


NAMES = ["building", "cave", "file", "greed", "frontier", "tnf", "minotaur", "global", "los", "multiwall", "maes",
         "together", "random", "inprocess", "zenoh", "label", "kind", "name", "model", "params", "x" * 300, "",
         "tests.swarm.campaign.broken:Boom", "os:system", "../../etc/passwd", "\u00e9\u00e8", "a\tb"]
TEXT = st.text(st.characters(exclude_categories=["Cs"]), max_size=8)  # TOML strings cannot hold surrogates
scalars = st.one_of(st.sampled_from(NAMES), st.integers(-3, 200), st.sampled_from([0, 1, 2**63, -2**63, 10**30]),
                    st.floats(allow_nan=True, allow_infinity=True), st.booleans(), TEXT)
values = st.recursive(scalars, lambda inner: st.one_of(st.lists(inner, max_size=3),
                                                       st.dictionaries(st.sampled_from(NAMES + ["alpha", "beta",
                                                                                                "range_m", "loss"]),
                                                                       inner, max_size=3)), max_leaves=8)


def mostly(good: st.SearchStrategy, bad: st.SearchStrategy, in_ten: int = 8) -> st.SearchStrategy:
    """``good`` in ``in_ten`` draws of ten, else ``bad`` (``one_of`` would draw each branch equally often)."""
    return st.integers(0, 9).flatmap(lambda k: good if k < in_ten else bad)


def _distinct(options: list) -> list:
    out = []
    for o in options:
        if o not in out:
            out.append(o)
    return out


PLAUSIBLE = {  # mostly valid values per grid dimension, a few wrong ones
    "map": ["building", "cave", {"kind": "building", "label": "b"}, {"kind": "cave", "params": {}},
            "maze", {"kind": "file"}, {"kind": "building", "size": 20}],
    "size": [20, 25, 40, "20x30", [20, 30], 5, -1, 0.5, "big"],
    "robots": [1, 2, 3, 0, 10_001, True, "2"],
    "spawn": ["together", "random", "apart"],
    "algorithm": ["greed", "frontier", "tnf", "minotaur", {"name": "frontier", "label": "f2"},
                  {"name": "tnf", "params": {"alpha": 2.0}}, {"name": "greed", "params": {"nope": 1}}, "nope"],
    "radio": ["global", "los", "multiwall", {"model": "multiwall", "label": "mw"}, {"model": "los", "x": 1}, "wifi"],
    "comm": [{"label": "a"}, {"loss": 0.1}, {}, {"loss": 2.0}, "lossless"],
    "transport": ["inprocess", "zenoh", "carrier-pigeon"],
}
grid_value = st.one_of(values, *[
    st.lists(st.one_of(st.sampled_from(opts), scalars), min_size=1, max_size=3) for opts in PLAUSIBLE.values()])
SECTION_KEYS = {
    "campaign": {"name": st.sampled_from(NAMES + ["c", "a/b"]), "seed": scalars, "replicates": scalars,
                 "description": scalars, "bogus": values},
    "grid": {**{dim: st.one_of(st.lists(st.sampled_from(opts), min_size=1, max_size=2).map(_distinct),
                               grid_value) for dim, opts in PLAUSIBLE.items()}, "bogus": values},
}
VALID = {"map": 4, "size": 5, "robots": 3, "spawn": 2, "algorithm": 6, "radio": 4, "comm": 3, "transport": 2}
"""How many of the first PLAUSIBLE values of each dimension are valid."""


def _entries(dim: str) -> st.SearchStrategy:
    good, bad = PLAUSIBLE[dim][: VALID[dim]], PLAUSIBLE[dim][VALID[dim]:]
    entry = mostly(st.sampled_from(good), st.sampled_from(bad), 9)
    return st.lists(entry, min_size=1, max_size=2).map(_distinct)


FULL_GRID = st.fixed_dictionaries(  # every required dimension, mostly valid values
    {dim: _entries(dim) for dim in ("map", "size", "robots", "spawn", "algorithm", "radio")},
    optional={dim: _entries(dim) for dim in ("comm", "transport")})
SECTION_KEYS |= {
    "stop": {"explored": st.one_of(st.sampled_from([0.5, 0.98, 1.0]), scalars),
             "max_ticks": st.one_of(st.integers(1, 40), scalars), "stall_ticks": scalars, "bogus": values},
    "output": {"timeseries_every": scalars, "bogus": values},
    "run": {"lidar": values, "motion": values, "comm": values, "navigation": values, "seed": values},
}
SECTION_KEYS["grid"] = st.one_of(FULL_GRID, FULL_GRID, st.fixed_dictionaries({}, optional=SECTION_KEYS["grid"]))
rule = st.dictionaries(st.sampled_from(["map", "size", "robots", "spawn", "algorithm", "radio", "comm", "bogus"]),
                       st.one_of(scalars, st.lists(scalars, max_size=3)), max_size=4)
wild_documents = st.fixed_dictionaries({}, optional={
    **{name: keys if name == "grid" else st.fixed_dictionaries({}, optional=keys)
       for name, keys in SECTION_KEYS.items()},
    "exclude": st.lists(rule, max_size=3), "include": st.lists(rule, max_size=2), "bogus": values})
plausible_documents = st.fixed_dictionaries(  # the keys a campaign has, values mostly plausible
    {"campaign": st.fixed_dictionaries({"name": mostly(st.sampled_from(["c", "x" * 300]), st.sampled_from(["", "a/b"]))},
                                       optional={"seed": mostly(st.integers(0, 2**63 - 1), scalars),
                                                 "replicates": mostly(st.integers(1, 3), scalars)}),
     "grid": FULL_GRID,
     "stop": st.fixed_dictionaries({"max_ticks": st.integers(1, 40)},
                                   optional={"explored": st.one_of(st.sampled_from([0.5, 0.98, 1.0]), scalars)})},
    optional={"exclude": st.lists(rule, max_size=3), "include": st.lists(rule, max_size=2),
              "output": st.fixed_dictionaries({"timeseries_every": st.one_of(st.integers(1, 20), scalars)}),
              "run": st.fixed_dictionaries({}, optional={"lidar": st.sampled_from([{"range_m": 5.0}, {"range_m": -1},
                                                                                    {"nope": 1}]),
                                                         "comm": st.sampled_from([{"loss": 0.2}, {"loss": "x"}])})})
documents = mostly(plausible_documents, wild_documents, 7)


# -------------------------------------------------------------------------------- campaign TOML ----
@pytest.mark.timeout(120)
@settings(FUZZ, max_examples=300)
@given(data=st.binary(max_size=400))
def test_random_bytes_as_a_campaign_file(tmp_path, capfd, data):
    spec = tmp_path / "random.toml"
    spec.write_bytes(data)
    assert check_cli(capfd, ["campaign", "run", str(spec), "-o", str(tmp_path / "never")]) == 2
    assert not (tmp_path / "never" / "parts").exists() or not list((tmp_path / "never" / "parts").iterdir())


@pytest.mark.timeout(120)
@settings(FUZZ, max_examples=600)
@given(doc=documents)
def test_random_structures_of_plausible_keys_and_values(doc):
    check_parse(toml_text(doc))


LINES = TINY.strip("\n").split("\n")


@st.composite
def mutated(draw) -> str:
    lines = list(LINES)
    for _ in range(draw(st.integers(1, 3))):
        i = draw(st.integers(0, len(lines) - 1))
        how = draw(st.sampled_from(["drop", "repeat", "value", "key", "garble", "scalar-list"]))
        line = lines[i]
        if how == "drop":
            del lines[i]
        elif how == "repeat":
            lines.insert(i, line)
        elif how == "value" and "=" in line:
            lines[i] = line.split("=", 1)[0] + "= " + toml_value(draw(values))
        elif how == "key" and "=" in line:
            lines[i] = json.dumps(draw(st.sampled_from(NAMES + ["size", "robots", "seed"]))) + " =" + line.split("=", 1)[1]
        elif how == "garble":
            at = draw(st.integers(0, len(line)))
            lines[i] = line[:at] + draw(st.text(max_size=4)) + line[at:]
        elif how == "scalar-list" and "= [" in line:
            lines[i] = line.replace("[", "", 1).rsplit("]", 1)[0]
        if not lines:
            lines = ["[campaign]"]
    return "\n".join(lines) + "\n"


@pytest.mark.timeout(120)
@settings(FUZZ, max_examples=600)
@given(text=mutated())
def test_mutations_of_a_valid_spec(text):
    check_parse(text)


# ------------------------------------------------------------------------------- figure layouts ----
ORDERS = {"map": ["building", "cave"], "size": ["20"], "robots": ["1", "2"], "spawn": ["together"],
          "algorithm": ["frontier", "frontier-eager"], "radio": ["global", "los"]}
wild_panel = st.fixed_dictionaries({}, optional={
    "compare": st.sampled_from(["radio", "algorithm", "map", "comm", "bogus", "x" * 300]), "title": scalars,
    **{dim: st.one_of(st.sampled_from(labels + ["nope"]), scalars) for dim, labels in ORDERS.items()},
    "bogus": values})
plausible_panel = st.fixed_dictionaries(
    {"compare": st.sampled_from(["radio", "algorithm", "robots"])},
    optional={"title": st.sampled_from(["t", "x" * 300]), "map": st.sampled_from(ORDERS["map"]),
              "size": st.sampled_from([20, "20", 40]), "spawn": st.sampled_from(["together", "nope"])})
wild_figure = st.fixed_dictionaries({}, optional={"name": st.sampled_from(["fig1", "fig 2", "", "x" * 300, "a/b"]),
                                                  "title": scalars, "columns": scalars,
                                                  "panel": st.one_of(st.lists(wild_panel, max_size=3), values)})
plausible_figure = st.fixed_dictionaries(
    {"name": st.sampled_from(["fig1", "fig2", "fig1"]), "panel": st.lists(plausible_panel, min_size=1, max_size=3)},
    optional={"title": st.sampled_from(["T", "x" * 300]), "columns": st.integers(0, 13)})
layouts = st.one_of(st.fixed_dictionaries({"figure": st.lists(plausible_figure, min_size=1, max_size=2)}),
                    st.fixed_dictionaries({"figure": st.lists(st.one_of(plausible_figure, wild_figure), max_size=3)}),
                    documents)


def layout_text(doc: dict) -> str:
    if isinstance(doc.get("figure"), list) and all(isinstance(f, dict) for f in doc["figure"]):
        out = []
        for fig in doc["figure"]:
            out.append("[[figure]]")
            out += [f"{json.dumps(k)} = {toml_value(v)}" for k, v in fig.items() if k != "panel"]
            panels = fig.get("panel")
            if isinstance(panels, list) and all(isinstance(p, dict) for p in panels):
                for p in panels:
                    out.append("[[figure.panel]]")
                    out += [f"{json.dumps(k)} = {toml_value(v)}" for k, v in p.items()]
            elif "panel" in fig:
                out.append(f"panel = {toml_value(panels)}")
        return "\n".join(out) + "\n"
    return toml_text(doc)


def check_layout_text(text: str) -> None:
    try:
        check_layout(parse_layout(text, "layout.toml"), ORDERS)
    except InvalidInput as exc:
        assert "\n" not in str(exc) and len(str(exc)) < MAX_MESSAGE, str(exc)
        event("refused")
        return
    event("accepted")


@pytest.mark.timeout(120)
@settings(FUZZ, max_examples=300)
@given(doc=layouts)
def test_random_figure_layouts(doc):
    check_layout_text(layout_text(doc))


FIG_LINES = FIGURES.strip("\n").split("\n")


@pytest.mark.timeout(120)
@settings(FUZZ, max_examples=200)
@given(data=st.data())
def test_mutations_of_the_paper_figure_layout(data):
    lines = list(FIG_LINES)
    for _ in range(data.draw(st.integers(1, 3))):
        i = data.draw(st.integers(0, len(lines) - 1))
        if data.draw(st.booleans()) and "=" in lines[i]:
            lines[i] = lines[i].split("=", 1)[0] + "= " + toml_value(data.draw(values))
        else:
            at = data.draw(st.integers(0, len(lines[i])))
            lines[i] = lines[i][:at] + data.draw(st.text(max_size=4)) + lines[i][at:]
    check_layout_text("\n".join(lines) + "\n")


@pytest.mark.timeout(120)
@settings(FUZZ, max_examples=100)
@given(data=st.binary(max_size=300))
def test_random_bytes_as_a_figures_file(tmp_path, capfd, data):
    path = tmp_path / "figures.toml"
    path.write_bytes(data)
    assert check_cli(capfd, ["campaign", "report", str(tmp_path), "--figures", str(path)]) == 2


# ------------------------------------------------------------------------------------ CLI flags ----
@pytest.fixture(scope="module")
def folders(tmp_path_factory) -> Iterator[dict[str, Path]]:
    """A complete results folder (so no fuzzed 'run' computes anything), its spec, and bad paths; the
    working directory moves there (a relative -o lands in it)."""
    root = tmp_path_factory.mktemp("fuzz-cli")
    cwd = os.getcwd()
    os.chdir(root)
    spec = root / "small.toml"
    spec.write_text(SMALL)
    done = root / "done"
    run_campaign(parse_campaign(SMALL), done, executor=make_executor(inline=True), progress=False)
    parts = sorted(p.name for p in (done / "parts").iterdir())  # one part: runs, time series, per-robot rows
    garbage = root / "garbage"
    garbage.mkdir()
    (garbage / "campaign.toml").write_bytes(b"\xff\xfe[grid\x00")
    (root / "a-file").write_text("not a folder")
    (root / "random.toml").write_bytes(bytes(range(256)))
    (root / "figures.toml").write_text('[[figure]]\nname = "f"\n[[figure.panel]]\ncompare = "radio"\n')
    try:
        yield {"root": root, "spec": spec, "done": done, "parts": parts, "garbage": garbage,
               "file": root / "a-file",
               "random": root / "random.toml", "figures": root / "figures.toml", "missing": root / "missing",
               "in-file": root / "a-file" / "sub", "empty": root}
    finally:
        os.chdir(cwd)


PATHS = ["spec", "done", "garbage", "file", "random", "figures", "missing", "in-file", "empty"]
NUMBERS = st.one_of(st.integers(-5, 5).map(str), st.sampled_from(["0", "1", "2/3", "99999999999999999999", "1e3",
                                                                   "nan", "-inf", "", " ", "x" * 200, "0.98"]))
SHARDS = st.one_of(st.sampled_from(["0/2", "1/2", "2/2", "0/0", "-1/2", "1/-2", "a/b", "1/2/3", "/", "3", "",
                                    "0/99999999999999999999", "x" * 200]), st.text(max_size=6))
DASK = st.one_of(st.sampled_from(["garbage", "tcp://", "tcp://host", "tcp://:1", "http://h:1", "tcp://h:0",
                                  "tcp://h:99999", "local:", "", "x" * 300, "tcp://[::1:1"]),
                 st.text(alphabet="abc:/", max_size=6).filter(lambda s: not s.count(":")))


def flag(name: str, value: st.SearchStrategy) -> st.SearchStrategy:
    return value.map(lambda v: [name, v])


@st.composite
def run_argv(draw, folders: dict[str, Path]) -> list[str]:
    argv = ["campaign", "run"]
    out = draw(st.sampled_from(["done", "done", "done", "file", "in-file", "garbage", None]))
    if out != "done" or draw(st.integers(0, 5)):  # no SPEC: the built-in quick campaign, refused by 'done'
        argv.append(str(folders[draw(st.sampled_from(["spec", "spec", "spec", "random", "done", "missing"]))]))
    if out:
        argv += ["-o", str(folders[out])]
    extras = draw(st.lists(st.one_of(
        flag("--workers", NUMBERS), flag("--shard", SHARDS), flag("--part-size", NUMBERS),
        flag("--max-runs", NUMBERS), flag("--dask", DASK), st.just(["--inline"]), st.just(["--retry-failed"]),
        st.just(["--no-report"]), st.just(["--quiet"]), st.just(["--bogus"])), max_size=4))
    return argv + [a for e in extras for a in e]


@pytest.mark.timeout(120)
@settings(FUZZ, max_examples=250)
@given(data=st.data())
def test_run_flags(folders, capfd, data):
    argv = data.draw(run_argv(folders))
    check_cli(capfd, argv)
    assert not [p for p in (folders["done"] / "writers").iterdir() if p.name != ".registry.lock"], \
        "a writer left its lock file"
    assert sorted(p.name for p in (folders["done"] / "parts").iterdir()) == folders["parts"], \
        "nothing ran, nothing was removed"


@pytest.mark.timeout(120)
@settings(FUZZ, max_examples=60)
@given(where=st.sampled_from(PATHS), extra=st.lists(st.sampled_from(["--bogus", "x", "-o"]), max_size=2))
def test_status_flags(folders, capfd, where, extra):
    if check_cli(capfd, ["campaign", "status", str(folders[where]), *extra]) == 0:
        assert where == "done" and not extra


@st.composite
def report_argv(draw, folders: dict[str, Path]) -> list[str]:
    argv = ["campaign", "report", str(folders[draw(st.sampled_from(["done", "done", "garbage", "missing", "file",
                                                                    "empty"]))])]
    argv += ["-o", str(folders["root"] / "reports" / str(draw(st.integers(0, 3))))
             if draw(st.booleans()) else str(folders[draw(st.sampled_from(["file", "in-file"]))])]
    extras = draw(st.lists(st.one_of(
        flag("--target", NUMBERS), flag("--format", st.sampled_from(["png", "svg", "pdf", "gif", ""])),
        flag("--figures", st.sampled_from([str(folders[p]) for p in ("figures", "random", "missing", "empty",
                                                                       "spec")])),
        st.just(["--maes-csv"]), st.just(["--bogus"])), max_size=3))
    return argv + [a for e in extras for a in e] + ["--no-cell-figures"]


@pytest.mark.timeout(120)
@settings(FUZZ, max_examples=100)
@given(data=st.data())
def test_report_flags(folders, capfd, data):
    check_cli(capfd, data.draw(report_argv(folders)))


# ------------------------------------------------------------------ damaged results folders (issue 48) ----
# A real folder of 4 runs (one part each) damaged the way disks, copies and other tools damage files. Every
# case: status, load and load_timeseries end in a result or one line, agree on whether the folder is sound
# (status lists a damaged part exactly when load refuses), and what they read of a folder damaged at the
# byte level equals the undamaged folder (a damaged byte is refused or has no effect: never a changed
# result). Then resume must leave a sound folder with the undamaged rows.
SUFFIXES = (".runs.parquet", ".timeseries.parquet", ".robots.parquet")


@pytest.fixture(scope="module")
def pristine_results(tmp_path_factory) -> Iterator[dict]:
    import resource

    from swarm.campaign import deterministic_rows
    from swarm.campaign.api import load, load_timeseries

    folder = tmp_path_factory.mktemp("fuzz-results") / "pristine"
    run_campaign(parse_campaign(SMALL), folder, executor=make_executor(inline=True), progress=False, flush_runs=1,
                 warmup=False)
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    yield {"folder": folder, "runs": load(folder), "series": load_timeseries(folder),
           "rows": deterministic_rows(folder), "files": sorted(p.name for p in (folder / "parts").iterdir())}
    grew = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before
    assert grew < 1 << 20, f"the fuzzing grew the process by {grew // 1024} MB"


@st.composite
def damage(draw, files: list[str]) -> tuple[str, str, object]:
    """(kind, file name, argument): a byte-level damage of one file, or a crafted rewrite of one column."""
    name = draw(st.sampled_from(files))
    kind = draw(st.sampled_from(["flip", "flip", "flip", "byte", "truncate", "delete", "append", "empty",
                                 "copy", "stray", "column"]))
    if kind in ("flip", "byte", "truncate"):
        return kind, name, (draw(st.floats(0, 1, exclude_max=True)), draw(st.integers(0, 255)))
    if kind == "copy":
        return kind, name, draw(st.sampled_from([f for f in files if f != name]))
    if kind == "stray":
        return kind, name, draw(st.binary(max_size=64))
    if kind == "column":
        return kind, name, (draw(st.integers(0, 200)), draw(st.sampled_from(["null", "string", "dict", "int",
                                                                             "float", "drop"])))
    return kind, name, None


def apply_damage(folder: Path, case: tuple[str, str, object]) -> bool:
    """Damage ``folder``; True for byte-level damage (whose effect must be nil or a refusal)."""
    import pyarrow as pa
    import pyarrow.compute as pc
    import pyarrow.parquet as pq

    kind, name, arg = case
    path = folder / "parts" / name
    event(f"{kind} {name.split('.', 2)[-1]}")
    if kind in ("flip", "byte", "truncate"):
        data = bytearray(path.read_bytes())
        at = int(arg[0] * len(data))
        if kind == "truncate":
            path.write_bytes(bytes(data[:at]))
        else:
            data[at] = data[at] ^ (1 << (arg[1] % 8)) if kind == "flip" else arg[1]
            path.write_bytes(bytes(data))
    elif kind == "delete":
        path.unlink()
        return not name.endswith(".runs.parquet")  # no runs file: its run was never committed (then redone)
    elif kind == "append":
        path.write_bytes(path.read_bytes() + b"PAR1garbage")
    elif kind == "empty":
        path.write_bytes(b"")
    elif kind == "copy":
        path.write_bytes((folder / "parts" / arg).read_bytes())
        return False
    elif kind == "stray":
        (folder / "parts" / f"{'9' * 20}-000000.stray-1-0123abcd.runs.parquet").write_bytes(arg)
    else:
        table = pq.read_table(path)
        i, how = arg[0] % table.num_columns, arg[1]
        col = table.column(i)
        if how == "drop":
            table = table.remove_column(i)
        else:
            new = {"null": lambda: pa.nulls(len(col), col.type if how == "null" else pa.null()),
                   "string": lambda: pc.cast(col, pa.string()),
                   "dict": lambda: pc.cast(col, pa.string()).dictionary_encode(),
                   "int": lambda: pa.array(range(len(col)), pa.int64()),
                   "float": lambda: pa.array([0.5] * len(col), pa.float64())}[how]()
            table = table.set_column(i, table.field(i).name, new)
        pq.write_table(table, path)
        return False
    return True


def check_folder(folder: Path, pristine: dict, byte_level: bool) -> bool:
    """status, load and load_timeseries on a damaged folder; True when the folder was found sound."""
    from swarm.campaign import status
    from swarm.campaign.api import load, load_timeseries

    outcome = []
    for read in (status, load, load_timeseries):
        try:
            outcome.append(read(folder))
        except InvalidInput as exc:
            assert "\n" not in str(exc) and len(str(exc)) < MAX_MESSAGE, str(exc)
            outcome.append(exc)
    st_, runs, series = outcome
    assert isinstance(st_, dict), st_  # status describes any folder with a readable campaign.toml
    sound = not st_["damaged"]
    assert sound == (not isinstance(runs, Exception)) == (not isinstance(series, Exception)), (st_, runs, series)
    event("sound" if sound else "damaged")
    if sound and byte_level:  # a redone run differs only in its timings, worker and part
        same = [c for c in runs.columns if c not in NONDETERMINISTIC_COLUMNS]
        assert runs[same].equals(pristine["runs"][same])
        assert series.equals(pristine["series"])
    return sound


@pytest.mark.timeout(300)
@settings(FUZZ, max_examples=300)
@given(data=st.data())
def test_damaged_results_folders(pristine_results, tmp_path_factory, data):
    import shutil

    folder = tmp_path_factory.mktemp("damaged") / "results"
    shutil.copytree(pristine_results["folder"], folder)
    case = data.draw(damage(pristine_results["files"]))
    check_folder(folder, pristine_results, apply_damage(folder, case))


@pytest.mark.timeout(600)
@settings(FUZZ, max_examples=40)
@given(data=st.data())
def test_report_and_resume_on_damaged_folders(pristine_results, tmp_path_factory, capfd, data):
    """The CLI report gives a report or one line; a resume then leaves a sound folder with the undamaged
    rows whenever the damage was at the byte level (a crafted but well-typed value is a result, kept)."""
    import shutil

    from swarm.campaign import deterministic_rows

    root = tmp_path_factory.mktemp("resume")
    folder = root / "results"
    shutil.copytree(pristine_results["folder"], folder)
    case = data.draw(damage(pristine_results["files"]))
    byte_level = apply_damage(folder, case)
    sound = check_folder(folder, pristine_results, byte_level)
    code = check_cli(capfd, ["campaign", "report", str(folder), "-o", str(root / "report"), "--no-cell-figures",
                             "--quiet"])
    assert code == (0 if sound else 2)
    run_campaign(parse_campaign(SMALL), folder, executor=make_executor(inline=True), progress=False, warmup=False)
    assert check_folder(folder, pristine_results, byte_level)
    if byte_level:
        assert deterministic_rows(folder) == pristine_results["rows"]
