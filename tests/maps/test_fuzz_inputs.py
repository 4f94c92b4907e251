"""Fuzzing every way a user hands swarm a map (issue #31): files of every suffix the loader accepts, legends,
and the ``swarm map`` / ``swarm radio`` flags.

Every case must end in a result or in :class:`InvalidInput` (in-process CLI: exit status 2 and one short
``swarm: error:`` line), never a traceback, a hang (each case runs under a time limit) or unbounded memory
(inputs are bounded here, and the process's peak RSS may grow by at most ``MAX_RSS_GROWTH_MIB`` over the
module). The number of cases tried is printed at the end of the module (``-rA`` or ``-s`` shows it).
"""

from __future__ import annotations

import collections
import contextlib
import io
import json
import os
import resource
import signal
import zipfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from PIL import Image

from maps import InvalidInput, Map, generate
from maps.io import check_legend, load_legend, load_map, map_from_bytes, map_to_bytes, save_npz
from swarm.cli import main

CASES: collections.Counter[str] = collections.Counter()
ACCEPTED: collections.Counter[str] = collections.Counter()
CASE_SECONDS = 20
MAX_RSS_GROWTH_MIB = 600
MAX_MESSAGE_CHARS = 600


def fuzz(examples: int) -> settings:
    """Hypothesis settings of a fuzz test: ``examples`` cases (times ``$SWARM_FUZZ_SCALE`` for a deeper run),
    no deadline (the machine is noisy; hangs are caught by :func:`time_limit`), no example database (every
    run explores afresh)."""
    return settings(max_examples=examples * int(os.environ.get("SWARM_FUZZ_SCALE", "1")), deadline=None, database=None,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture,
                                           HealthCheck.data_too_large, HealthCheck.filter_too_much])


@pytest.fixture(scope="module", autouse=True)
def report_cases(request):
    """Count the cases and watch the memory over the module; print the counts at the end."""
    rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    yield
    growth = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024 - rss0
    reporter = request.config.pluginmanager.get_plugin("terminalreporter")
    text = ", ".join(f"{k} {v} ({ACCEPTED[k]} accepted)" for k, v in sorted(CASES.items()))
    if reporter is not None:
        reporter.write_line(f"\nfuzz cases tried: {sum(CASES.values())}, {sum(ACCEPTED.values())} accepted: {text}; "
                            f"peak RSS growth {growth:.0f} MiB")
    assert growth < MAX_RSS_GROWTH_MIB, f"peak RSS grew by {growth:.0f} MiB"


@contextlib.contextmanager
def time_limit(seconds: float = CASE_SECONDS):
    """Turn a hang into a failure: SIGALRM after ``seconds``."""
    def on_alarm(signum, frame):
        raise TimeoutError(f"case took more than {seconds} s")

    old = signal.signal(signal.SIGALRM, on_alarm)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)


def short_line(message: str) -> None:
    assert len(message.splitlines()) == 1 and len(message) <= MAX_MESSAGE_CHARS, message[:600]


def load_or_refuse(kind: str, fn, *args, **kwargs) -> Map | None:
    """``fn(*args)`` gives a Map or one short InvalidInput line; anything else fails the test."""
    CASES[kind] += 1
    with time_limit():
        try:
            m = fn(*args, **kwargs)
        except InvalidInput as exc:
            short_line(str(exc))
            return None
    assert isinstance(m, Map) and m.solid.shape == m.material.shape
    ACCEPTED[kind] += 1
    return m


def cli(capsys, kind: str, *args: str) -> int:
    """Run ``swarm ARGS`` in-process: exit 0, or exit 2 with exactly one short ``swarm: error:`` line."""
    CASES[kind] += 1
    with time_limit():
        code = main([str(a) for a in args])
    out, err = capsys.readouterr()
    if code == 0:
        assert "swarm: error" not in err, err[:600]
        ACCEPTED[kind] += 1
        return 0
    assert code == 2, (code, args[:6], err[-600:])
    assert err.startswith("swarm: error: ") and err.endswith("\n"), err[:600]
    short_line(err.rstrip("\n"))
    return 2


# ------------------------------------------------------------------------------------ fixtures ----
@pytest.fixture(scope="module")
def workdir(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("fuzz")


@pytest.fixture(autouse=True)
def in_workdir(workdir, monkeypatch):
    monkeypatch.chdir(workdir)  # "swarm map generate" with no -o writes a picture into the current folder


def valid_png_bytes() -> bytes:
    img = np.zeros((8, 10, 3), np.uint8)
    img[1:-1, 1:-1] = 255
    img[3:5, 4] = (160, 82, 45)
    buf = io.BytesIO()
    Image.fromarray(img).save(buf, format="PNG")
    return buf.getvalue()


VALID_NPZ = map_to_bytes(generate("building", 20, 0))
VALID_PNG = valid_png_bytes()
VALID_CSV = "1,1,1,1,1\n1,0,0,0,1\n1,0,1,0,1\n1,0,0,0,1\n1,1,1,1,1\n"
VALID_PGM_TOKENS = ["P2", "5", "5", "255"] + [str(v) for v in
                                              [0] * 6 + [255, 255, 255, 0, 0, 255, 0, 255, 0, 0, 255, 255, 255] + [0] * 6]
LEGEND_TEXT = '[colours]\n"#ffffff" = "free"\n"#000000" = "concrete"\n"#a0522d" = "brick"\n'
SUFFIXES = [".npz", ".csv", ".json", ".pgm", ".png", ".jpg", ".bmp", ".gif", ".tif", ".webp", ".txt", ""]


@pytest.fixture(scope="module")
def legend_path(workdir) -> Path:
    path = workdir / "legend.toml"
    path.write_text(LEGEND_TEXT)
    return path


@pytest.fixture(scope="module")
def small_npz(workdir) -> Path:
    return save_npz(generate("building", 20, 3), workdir / "small.npz")


def mutate(data: bytes, edits: list[tuple[int, int, bytes]]) -> bytes:
    """Apply (position, deleted length, inserted bytes) edits; positions wrap around the data."""
    out = bytearray(data)
    for pos, delete, insert in edits:
        pos = pos % (len(out) + 1)
        out[pos:pos + delete] = insert
    return bytes(out)


EDITS = st.lists(st.tuples(st.integers(0, 10**6), st.integers(0, 8), st.binary(max_size=8)), min_size=1, max_size=6)
ODD_NUMBERS = st.one_of(st.integers(-10**25, 10**25), st.sampled_from([0, -1, 1, 65535, 65536, 10**22, 2**63, -2**63]))
ODD_TOKENS = st.one_of(ODD_NUMBERS.map(str), st.sampled_from(
    ["", "#", "#c\n", "P5", "P2", "nan", "inf", "1e3", "+1", "0x10", "1_0", "\u0663", "\x00", "9" * 5000]),
    st.text(max_size=6))


# -------------------------------------------------------------------------------------- files ----
@fuzz(500)
@given(suffix=st.sampled_from(SUFFIXES), data=st.binary(max_size=600), with_legend=st.booleans())
def test_random_bytes_with_every_suffix(workdir, legend_path, suffix, data, with_legend):
    path = workdir / f"random{suffix}"
    path.write_bytes(data)
    load_or_refuse("random bytes", load_map, path, legend=legend_path if with_legend else None)


@fuzz(300)
@given(edits=EDITS)
def test_mutated_npz(edits):
    load_or_refuse("mutated npz", map_from_bytes, mutate(VALID_NPZ, edits), "m.npz")


JSON = st.recursive(st.none() | st.booleans() | ODD_NUMBERS | st.floats() | st.text(max_size=10),
                    lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=6), inner, max_size=4),
                    max_leaves=12)
DTYPES = st.sampled_from([np.bool_, np.uint8, np.int16, np.int32, np.float64, np.uint16, ">i2", "<U2"])


@fuzz(300)
@given(member=st.sampled_from(["solid", "material", "rooms", "meta", "meta-json", "extra"]), dtype=DTYPES,
       shape=st.lists(st.integers(0, 50), max_size=3), key=st.sampled_from(
           ["format", "version", "kind", "seed", "params", "materials", "graph"]), value=JSON)
def test_npz_with_odd_arrays_and_metadata(member, dtype, shape, key, value):
    with np.load(io.BytesIO(VALID_NPZ)) as z:
        arrays = {k: z[k] for k in z.files}
    if member == "meta-json":
        meta = json.loads(arrays["meta"].tobytes())
        meta[key] = value
        arrays["meta"] = np.frombuffer(json.dumps(meta).encode(), np.uint8)
    else:
        arrays[member] = np.zeros(shape, dtype=dtype)
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as zf:
        for k, v in arrays.items():
            with zf.open(f"{k}.npy", "w") as f:
                np.lib.format.write_array(f, v, allow_pickle=False)
    load_or_refuse("npz arrays/meta", map_from_bytes, buf.getvalue(), "m.npz")


@fuzz(400)
@given(header=st.tuples(st.sampled_from(["P2", "P5", "p2", "P2\n#c", "P3"]), ODD_NUMBERS, ODD_NUMBERS, ODD_NUMBERS),
       use_header=st.booleans(), replace=st.lists(st.tuples(st.integers(0, 40), ODD_TOKENS), max_size=4),
       cut=st.integers(0, 40), comments=st.booleans())
def test_mutated_pgm(workdir, header, use_header, replace, cut, comments):
    tokens = list(VALID_PGM_TOKENS)
    if use_header:
        tokens[:4] = [str(t) for t in header]
    for i, t in replace:
        tokens[i % len(tokens)] = t
    tokens = tokens[:len(tokens) - cut % 8]
    sep = "\n# a comment\n" if comments else " "
    path = workdir / "m.pgm"
    path.write_text(sep.join(tokens), encoding="utf-8", errors="surrogatepass")
    load_or_refuse("mutated pgm", load_map, path)


@fuzz(300)
@given(text=st.one_of(st.text(alphabet="01,\n\r\t 2x-.", max_size=200), st.text(max_size=60),
                      st.lists(st.tuples(st.integers(0, 60), st.text(max_size=3)), max_size=5).map(
                          lambda edits: _edit_text(VALID_CSV, edits))),
       border=st.integers(0, 2))
def test_mutated_csv(workdir, text, border):
    path = workdir / "m.csv"
    path.write_text(text, encoding="utf-8", errors="surrogatepass")
    load_or_refuse("mutated csv", load_map, path, border=border)


def _edit_text(text: str, edits: list[tuple[int, str]]) -> str:
    for pos, insert in edits:
        pos = pos % (len(text) + 1)
        text = text[:pos] + insert + text[pos + 1:]
    return text


@fuzz(240)
@given(edits=EDITS, suffix=st.sampled_from([".png", ".pgm", ".gif"]))
def test_mutated_png(workdir, legend_path, edits, suffix):
    path = workdir / f"m{suffix}"
    path.write_bytes(mutate(VALID_PNG, edits))
    load_or_refuse("mutated png", load_map, path, legend=legend_path, border=1)


# ------------------------------------------------------------------------------------- legends ----
def toml_value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        return repr(v) if not isinstance(v, float) or v == v and abs(v) != float("inf") else "nan"
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, list):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{json.dumps(k)} = {toml_value(x)}" for k, x in v.items()) + "}"
    return '""'


COLOUR_KEYS = st.one_of(st.sampled_from(["#ffffff", "#000000", "#FFFFFF", "#a0522d", "#fff", "#-1-1-1", "#+f+f+f",
                                         "#gggggg", "#１２３４５６", "x" * 300]),
                        st.text(max_size=9))
MATERIAL_NAMES = st.one_of(st.sampled_from(["free", "air", "concrete", "brick", "plaster", "unobtainium", "Concrete",
                                            "", "w" * 40]), st.text(max_size=6), ODD_NUMBERS)
BASE_COLOURS = st.sampled_from([{}, {"#ffffff": "free"}, {"#ffffff": "free", "#000000": "concrete"},
                                {"#ffffff": "air", "#000000": "concrete", "#a0522d": "brick"}])
LEGENDS = st.fixed_dictionaries(
    {"colours": st.builds(lambda base, extra: {**base, **extra}, BASE_COLOURS,
                          st.dictionaries(COLOUR_KEYS, MATERIAL_NAMES, max_size=3))},
    optional={"metres_per_pixel": st.one_of(st.floats(), ODD_NUMBERS, st.sampled_from([0.5, 1.0, 32, 32.5])),
              "tolerance": st.one_of(ODD_NUMBERS, st.floats()),
              "materials": st.one_of(st.lists(MATERIAL_NAMES, max_size=3), JSON),
              "scale": JSON})


@fuzz(400)
@given(legend=LEGENDS, as_bytes=st.one_of(st.none(), st.binary(max_size=200)))
def test_legends(workdir, legend, as_bytes):
    path = workdir / "fuzz-legend.toml"
    if as_bytes is None:
        lines = [f"{k} = {toml_value(v)}" for k, v in legend.items() if k != "colours"]
        lines += ["[colours]"] + [f"{json.dumps(k)} = {toml_value(v)}" for k, v in legend["colours"].items()]
        path.write_text("\n".join(lines), encoding="utf-8", errors="surrogatepass")
    else:
        path.write_bytes(as_bytes)
    CASES["legend"] += 1
    try:
        parsed = load_legend(path)
    except InvalidInput as exc:
        short_line(str(exc))
    else:
        ACCEPTED["legend"] += 1
        assert parsed["colours"] and "air" in parsed["colours"].values()
        png = workdir / "legend-target.png"
        png.write_bytes(VALID_PNG)
        load_or_refuse("legend+image", load_map, png, legend=path, border=1)
    CASES["legend dict"] += 1
    try:
        check_legend(legend)
    except InvalidInput as exc:
        short_line(str(exc))
    else:
        ACCEPTED["legend dict"] += 1


# --------------------------------------------------------------------------------- CLI: swarm map ----
def mostly(valid: st.SearchStrategy, odd: st.SearchStrategy, odd_in: int = 4) -> st.SearchStrategy:
    """``valid`` most of the time, ``odd`` one time in ``odd_in``: a case near a valid command explores the
    code behind the first check, and a run of odd values still tries every check."""
    return st.integers(0, odd_in - 1).flatmap(lambda i: odd if i == 0 else valid)


CLI_VALUES = st.one_of(
    st.text(max_size=12), ODD_NUMBERS.map(str), st.floats().map(repr),
    st.sampled_from(["nan", "inf", "-inf", "1e400", "9" * 5000, "x" * 20_000, "", " ", "[", "{", "'", '"', "[1, 2]",
                     "{concrete = 1e308, wood = 1e308}", "{bogus = 1}", "{}", "true", "\n", "a\nb", "[" * 3000,
                     "unobtainium", "concrete", "0", "-1", "20", "1.5", "1\nx = 2"]))
NUMBERS = st.one_of(st.integers(0, 60).map(str), st.floats(0, 100).map(repr))
MATERIAL_VALUES = st.sampled_from(["concrete", "wood", "brick", "glass", "metal", "wall", "drywall", "air", "plaster",
                                   "{concrete = 1, glass = 2}", "{wood = 0, brick = 0}", "{metal = 1e308}"])
GENERATOR_PARAMS = {
    "building": ["hall_width", "max_hall_percent", "min_room_side", "wall_thickness", "door_width", "door_padding",
                 "room_split_percent", "extra_door_percent", "border", "exterior_material", "interior_materials",
                 "interior_materials.wood", "interior_materials.bogus"],
    "cave": ["fill_percent", "smoothing_runs", "smoothing_threshold", "passage_radius", "wall_threshold",
             "room_threshold", "border", "materials", "materials.brick", "materials.x", "material_smoothing"],
}
KEYS_ODD = st.one_of(st.text(max_size=8), st.sampled_from(["k" * 20_000, "a..b", ".", "border.x", "=", " "]))
SIZES = mostly(st.sampled_from(["20", "24", "30x20", "20x36", "40", "21X23"]),
               st.one_of(st.sampled_from(["19", "2001", "0", "-20", "20x", "x", "20x20x20", "1e2", "\uff19\uff19",
                                          "9" * 5000, "", "20 x 20", "x" * 20_000]), st.text(max_size=8)))


@st.composite
def generate_args(draw) -> list[str]:
    kind = draw(mostly(st.sampled_from(["building", "cave"]), st.text(max_size=8), 10))
    keys = GENERATOR_PARAMS.get(kind, GENERATOR_PARAMS["building"])
    args = ["map", "generate", "--kind", kind, "--size", draw(SIZES),
            "--seed", draw(mostly(st.integers(0, 2**63 - 1).map(str), CLI_VALUES, 8))]
    for _ in range(draw(st.integers(0, 3))):
        key = draw(mostly(st.sampled_from(keys), KEYS_ODD, 8))
        value = draw(mostly(MATERIAL_VALUES if "material" in key else NUMBERS, CLI_VALUES, 3))
        args += ["--param", f"{key}={value}"]
    output = draw(st.sampled_from(["-o", "--png", "both", "none"]))
    if output in ("-o", "both"):
        args += ["-o", "gen.npz"]
    if output in ("--png", "both"):
        args += ["--png", draw(mostly(st.just("gen.png"), st.sampled_from(["/", "no/such/dir/x.png", "x" * 300])))]
    if draw(st.booleans()):
        args += ["--scale", draw(mostly(st.sampled_from(["1", "2"]), st.sampled_from(["0", "33", "x", "9" * 400])))]
    return args


@fuzz(300)
@given(args=generate_args())
def test_cli_map_generate(capsys, args):
    cli(capsys, "cli map generate", *args)


@fuzz(80)
@given(kind=st.one_of(st.sampled_from(["building", "cave"]), st.text(max_size=10), st.just("k" * 20_000)))
def test_cli_map_params(capsys, kind):
    cli(capsys, "cli map params", "map", "params", kind)


FORMATS = {".npz": VALID_NPZ, ".png": VALID_PNG, ".csv": VALID_CSV.encode(),
           ".pgm": "\n".join(VALID_PGM_TOKENS).encode()}


@st.composite
def file_args(draw, command: str, workdir: Path, legend_path: Path) -> list[str]:
    fmt = draw(st.sampled_from(sorted(FORMATS)))
    suffix = draw(mostly(st.just(fmt), st.sampled_from(SUFFIXES), 5))
    content = draw(mostly(st.just(FORMATS[fmt]), st.one_of(st.builds(mutate, st.just(FORMATS[fmt]), EDITS),
                                                            st.binary(max_size=300)), 2))
    path = workdir / f"input{suffix}"
    path.write_bytes(content)
    args = ["map", command, str(path)]
    if draw(mostly(st.just(suffix == ".png"), st.booleans(), 5)):
        args += ["--legend", str(legend_path)]
    picture = draw(st.booleans())
    if command == "show":
        if picture:
            args += ["-o", "show.png", "--scale", draw(st.sampled_from(["1", "2", "0", "x"]))]
        return args
    args += ["-o", draw(mostly(st.just("imported.npz"), st.sampled_from(["/", "no/dir/m.npz", "m" * 300]), 8))]
    if picture:
        args += ["--png", "imported.png"]
    if draw(st.booleans()):
        args += ["--material", draw(mostly(st.sampled_from(["concrete", "wood", "wall", "glass"]),
                                           st.one_of(MATERIAL_NAMES.map(str), CLI_VALUES), 3))]
    if draw(st.booleans()):
        args += ["--border", draw(mostly(st.sampled_from(["0", "1", "2"]), st.sampled_from(["11", "-1", "x", ""])))]
    if draw(st.booleans()):
        args += ["--border-material", draw(mostly(st.sampled_from(["concrete", "brick", "metal"]),
                                                  MATERIAL_NAMES.map(str), 3))]
    return args


@fuzz(200)
@given(data=st.data())
def test_cli_map_show(capsys, workdir, legend_path, data):
    cli(capsys, "cli map show", *data.draw(file_args("show", workdir, legend_path)))


@fuzz(240)
@given(data=st.data())
def test_cli_map_import(capsys, workdir, legend_path, data):
    cli(capsys, "cli map import", *data.draw(file_args("import", workdir, legend_path)))


# ------------------------------------------------------------------------------- CLI: swarm radio ----
INSIDE = st.tuples(st.floats(0.5, 19.5), st.floats(0.5, 19.5)).map(lambda p: f"{p[0]!r},{p[1]!r}")
POINTS = mostly(INSIDE, st.one_of(
    st.sampled_from(["0,0", "20,20", "-1,5", "nan,1", "inf,1", "1e400,1", "1,2,3", "x", "", "7" * 20_000 + ",1",
                     "5,5 ", " 5 , 5"]),
    st.tuples(st.floats(), st.floats()).map(lambda p: f"{p[0]!r},{p[1]!r}"), st.text(max_size=8)))
RADIO_FLAGS = {"--model": st.sampled_from(["multiwall", "los", "maes", "global"]),
               "--freq": st.sampled_from(["2.4", "5.2", "1.3", "0.9", "60", "100"]),
               "--tx-power": st.sampled_from(["15", "0", "-10", "30", "1e308"]),
               "--sensitivity": st.sampled_from(["-82", "-95", "-50", "-1e308"]),
               "--wall-mode": st.sampled_from(["crossing", "per_metre"]),
               "--max-range": st.sampled_from(["5", "30", "0.5"])}
RADIO_PARAMS = {"alpha": NUMBERS, "beta": NUMBERS, "gamma": NUMBERS, "graze_tolerance_m": st.sampled_from(["0", "0.05", "0.25"]),
                "materials.glass": st.sampled_from(["[1, 2, 3]", "4", "{db = 4, thickness_m = 0.5}"]),
                "materials.concrete": st.sampled_from(["[13, 15, 23]", "0", "{db = [1, 2], freq_ghz = [1, 2]}"]),
                "materials.plaster": st.sampled_from(["3", "[1e308, 1e308, 1e308]"]),
                "tx_power_overrides.0": st.sampled_from(["10", "-5"]), "sensitivity_overrides.1": st.sampled_from(["-90"])}
ODD_RADIO_KEYS = st.one_of(st.sampled_from(["materials", "materials.concrete.db", "materials.concrete.freq_ghz",
                                            "tx_power_overrides.x", "tx_power_overrides", "unknown", "model",
                                            "materials.Bad", "tx_power_overrides.\u00b3"]), st.text(max_size=6))
RADIO_CONFIGS = st.sampled_from([b"radio = 5", b"[radio]\nmodel = 'los'\nmax_range_m = 5", b"[radio]\nmaterials = 3",
                                 b"x = " + b"9" * 5000, b"[radio]\nfrequency_ghz = 1e400", b"model = 'maes'",
                                 b"[radio]\ntx_power_overrides = {'2' = 1e400}", b"\xff\xfe", b"[radio]\n" + b"[" * 3000])


@st.composite
def radio_args(draw, workdir: Path, npz: Path) -> list[str]:
    command = draw(st.sampled_from(["link", "heatmap"]))
    args = ["radio", command, str(npz)]
    args += (["--from", draw(POINTS), "--to", draw(POINTS)] if command == "link"
             else ["--tx", draw(POINTS), "-o", "heat.png"])
    if command == "heatmap" and draw(st.booleans()):
        args += ["--scale", draw(mostly(st.sampled_from(["1", "2"]), st.sampled_from(["0", "x", "33"])))]
    for _ in range(draw(st.integers(0, 2))):
        flag = draw(st.sampled_from(sorted(RADIO_FLAGS)))
        args += [flag, draw(mostly(RADIO_FLAGS[flag], CLI_VALUES))]
    for _ in range(draw(st.integers(0, 2))):
        key = draw(mostly(st.sampled_from(sorted(RADIO_PARAMS)), ODD_RADIO_KEYS))
        value = draw(mostly(RADIO_PARAMS.get(key, NUMBERS), CLI_VALUES))
        args += ["--param", f"{key}={value}"]
    if draw(st.integers(0, 4)) == 0:
        path = workdir / "radio.toml"
        path.write_bytes(draw(st.one_of(RADIO_CONFIGS, st.binary(max_size=80))))
        args += ["--config", str(path)]
    return args


@fuzz(300)
@given(data=st.data())
def test_cli_radio(capsys, workdir, small_npz, data):
    args = data.draw(radio_args(workdir, small_npz))
    cli(capsys, f"cli radio {args[1]}", *args)
