"""Issue #31: bad map files, legends, generator parameters and flags end in one short ``InvalidInput`` line.

Every case here used to end in a traceback (OverflowError, RecursionError, ValueError...), to be accepted
and give a wrong map, to allocate memory in proportion to a number in a header, or to echo a huge value.
"""

from __future__ import annotations

import io
import json
import tracemalloc
import zipfile
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from maps import InvalidInput, Map, generate
from maps.io import (MAX_CELLS, check_legend, import_csv, import_image, import_pgm, load_legend, load_map,
                     map_from_bytes, map_to_bytes)
from swarm.cli import main

MAX_MESSAGE_CHARS = 600
"""An error line may name a field, a value cut to 80 characters and a list of what is allowed."""


def one_line(message: str) -> str:
    """``message`` if it is one short line (the contract of every error), else fail."""
    assert len(message.splitlines()) == 1, message[:500]
    assert len(message) <= MAX_MESSAGE_CHARS, message[:500]
    return message


def cli_error(capfd, *args: str) -> str:
    """Run ``swarm ARGS`` in-process; it must exit 2 with one ``swarm: error:`` line and nothing else."""
    code = main([str(a) for a in args])
    out, err = capfd.readouterr()
    assert code == 2, (code, out[-500:], err[-2000:])
    assert err.startswith("swarm: error: "), err[-2000:]
    return one_line(err.rstrip("\n"))


def peak_mib(fn, *args, **kwargs) -> float:
    """Peak traced Python/numpy allocation (MiB) while ``fn`` raises InvalidInput."""
    tracemalloc.start()
    try:
        with pytest.raises(InvalidInput) as info:
            fn(*args, **kwargs)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    one_line(str(info.value))
    return peak / 2**20


# ------------------------------------------------------------------------------------------- PGM ----
def write_pgm(path: Path, w: int, h: int, values, maxval: int = 255, magic: str = "P2") -> Path:
    path.write_text(f"{magic}\n# a comment\n{w} {h}\n{maxval}\n" + " ".join(str(v) for v in values) + "\n")
    return path


def test_pgm_pixel_of_ten_to_the_22_is_refused(tmp_path):
    path = write_pgm(tmp_path / "x.pgm", 3, 3, [0, 0, 0, 0, 10**22, 0, 0, 0, 0])
    with pytest.raises(InvalidInput) as info:
        import_pgm(path)
    assert info.value.field == "map file" and "0..255" in info.value.allowed


def test_cli_import_and_run_of_a_pgm_with_a_huge_pixel_give_one_line(tmp_path, capfd):
    path = write_pgm(tmp_path / "x.pgm", 3, 3, [0, 0, 0, 0, 10**22, 0, 0, 0, 0])
    assert "x.pgm" in cli_error(capfd, "map", "import", path, "-o", tmp_path / "m.npz")
    assert not (tmp_path / "m.npz").exists()
    assert "x.pgm" in cli_error(capfd, "run", "--map", path, "--max-ticks", "5")


@pytest.mark.parametrize("header, needle", [
    ("P2 -4 4 255", "width"),
    ("P2 4 -4 255", "width"),
    ("P2 4 4 0", "maxval"),
    ("P2 4 4 -1", "maxval"),
    ("P2 4 4 70000", "maxval"),
    ("P2 4 4 " + "9" * 5000, "maxval"),
    ("P2 " + "9" * 5000 + " 4 255", "width"),
    ("P2 1e3 4 255", "integer"),
    ("P5 4 4 255", "P2"),
])
def test_pgm_header_variants_are_refused_with_the_reason(tmp_path, header, needle):
    path = tmp_path / "h.pgm"
    path.write_text(header + "\n" + " ".join(["0"] * 16) + "\n")
    with pytest.raises(InvalidInput) as info:
        import_pgm(path)
    assert needle in one_line(str(info.value))


def test_pgm_pixels_outside_0_to_maxval_are_refused(tmp_path):
    for bad in (-1, 256):
        path = write_pgm(tmp_path / "v.pgm", 3, 3, [0, 0, 0, 0, bad, 0, 0, 0, 0])
        with pytest.raises(InvalidInput, match="0..255"):
            import_pgm(path)


def test_pgm_with_fewer_pixels_than_declared(tmp_path):
    path = write_pgm(tmp_path / "f.pgm", 4, 4, [0] * 15)
    with pytest.raises(InvalidInput, match="16 pixel values"):
        import_pgm(path)


def test_pgm_header_of_a_billion_squared_is_refused_before_reading_the_pixels(tmp_path):
    path = tmp_path / "big.pgm"
    path.write_bytes(b"P2\n1000000000 1000000000\n255\n" + b"0 " * 1_500_000)
    assert peak_mib(import_pgm, path) < 20  # the old parser built a list of every token first (~100 MiB)


def test_pgm_comment_and_whitespace_variants_still_import(tmp_path):
    path = tmp_path / "c.pgm"
    path.write_bytes(b"P2#c\n3#c\n3 255\n0 0 0\n0 255 0\n0 0 0#end")
    m = import_pgm(path)
    assert m.shape == (6, 6) and m.is_free_at(1.5, 1.5)


# ------------------------------------------------------------------------------------------- NPZ ----
VALID = map_to_bytes(generate("building", 20, 0))


def npz_with(**arrays_or_none) -> bytes:
    with np.load(io.BytesIO(VALID)) as z:
        arrays = {k: z[k] for k in z.files}
    arrays.update(arrays_or_none)
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", compression=zipfile.ZIP_DEFLATED) as zf:
        for k, v in arrays.items():
            if v is not None:
                with zf.open(f"{k}.npy", "w", force_zip64=True) as f:
                    np.lib.format.write_array(f, v)
    return buf.getvalue()


def meta_with(**changes) -> np.ndarray:
    with np.load(io.BytesIO(VALID)) as z:
        meta = json.loads(z["meta"].tobytes())
    meta.update(changes)
    return np.frombuffer(json.dumps(meta).encode(), np.uint8)


def raw_meta(text: str) -> np.ndarray:
    return np.frombuffer(text.encode(), np.uint8)


@pytest.mark.parametrize("arrays", [
    {"meta": raw_meta("[" * 100_000 + "]" * 100_000)},                      # RecursionError in json
    {"meta": raw_meta('{"format": "swarm-map", "version": 1, "seed": ' + "9" * 5000 + "}")},  # int digits
    {"meta": meta_with(graph={"rooms": [5], "doors": []})},                   # AttributeError
    {"meta": meta_with(graph={"rooms": [{"id": 1e400}], "doors": []})},       # OverflowError (inf)
    {"meta": meta_with(graph={"rooms": [], "doors": [{"rooms": [1, 2], "key": -1e400}]})},
    {"meta": meta_with(graph=[1, 2])},
    {"meta": meta_with(materials=["air", {"a": 1}])},
    {"meta": meta_with(kind=["cave"])},
    {"meta": meta_with(seed=True)},
    {"meta": np.zeros((2, 2), np.uint8)},
    {"solid": np.zeros((), bool)},
    {"rooms": np.zeros((3, 3), np.int16)},
])
def test_malformed_npz_contents_are_one_line_errors(arrays):
    with pytest.raises(InvalidInput) as info:
        map_from_bytes(npz_with(**arrays), "x.npz")
    assert info.value.field == "map file"
    one_line(str(info.value))


def test_npz_array_bigger_than_the_limit_is_refused_before_it_is_decompressed():
    side = int(MAX_CELLS ** 0.5) + 100
    bomb = npz_with(solid=np.ones((side, side), bool), material=np.ones((side, side), np.uint8))
    assert len(bomb) < 200_000, "deflate makes it small; the old reader inflated it before checking"
    assert peak_mib(map_from_bytes, bomb, "bomb.npz") < 8


def test_npz_member_that_lies_about_its_size_is_refused():
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as zf:
        with zf.open("solid.npy", "w") as f:  # header says 10^10 cells, no data follows
            f.write(np.lib.format.magic(1, 0))
            np.lib.format.write_array_header_1_0(f, {"descr": "|b1", "fortran_order": False,
                                                     "shape": (100_000, 100_000)})
    assert peak_mib(map_from_bytes, buf.getvalue(), "lie.npz") < 8


def test_truncated_npz_and_unreadable_paths(tmp_path):
    for n in (10, len(VALID) // 2, len(VALID) - 5):
        with pytest.raises(InvalidInput, match="x.npz"):
            map_from_bytes(VALID[:n], "x.npz")
    for bad in ("nul\x00byte.npz", "nul\x00byte.csv", "nul\x00byte.pgm", str(tmp_path)):
        with pytest.raises(InvalidInput):
            load_map(bad)
    with pytest.raises(InvalidInput):
        load_legend("nul\x00.toml")


# ------------------------------------------------------------------------------------------- CSV ----
def test_csv_with_a_huge_grid_is_refused_before_it_is_built(tmp_path):
    path = tmp_path / "wide.csv"
    path.write_text(",".join(["0"] * 5_000_000))
    assert peak_mib(import_csv, path) < 40  # the old reader made a Python list of every value first


@pytest.mark.parametrize("text", ["0,1\n0,x" + "y" * 20_000, "\ufeff1,1\n1,1", "1,1\r\n1,\x0b1"])
def test_csv_odd_values_are_short_one_line_errors(tmp_path, text):
    path = tmp_path / "odd.csv"
    path.write_text(text)
    with pytest.raises(InvalidInput) as info:
        import_csv(path)
    one_line(str(info.value))


# ---------------------------------------------------------------------------------- images/legend ----
def write_png(path: Path, w: int, h: int) -> Path:
    img = np.zeros((h, w, 3), np.uint8)
    img[1:-1, 1:-1] = 255
    Image.fromarray(img).save(path)
    return path


def test_image_scaled_past_the_cell_limit_is_refused_before_upscaling(tmp_path):
    path = write_png(tmp_path / "p.png", 80, 80)  # 80 px x 64 cells per px = 5120 cells a side > the limit
    legend = check_legend({"metres_per_pixel": 32, "colours": {"#ffffff": "free", "#000000": "concrete"}})
    assert peak_mib(import_image, path, legend) < 20


def test_legend_with_too_many_colours_is_refused(tmp_path):
    colours = {f"#{i:06x}": "concrete" for i in range(5000)} | {"#ffffff": "free"}
    with pytest.raises(InvalidInput) as info:
        check_legend({"colours": colours})
    assert info.value.field == "legend.colours"


@pytest.mark.parametrize("key", ["#-1-1-1", "#+f+f+f", "# f f f", "#１２３４５６", "#0x1234"])
def test_legend_colours_must_be_six_hex_digits(key):
    with pytest.raises(InvalidInput) as info:
        check_legend({"colours": {"#ffffff": "free", key: "concrete"}})
    assert info.value.field == f"legend.colours.{key}"


def test_legend_colour_listed_twice_with_different_materials_is_refused():
    with pytest.raises(InvalidInput, match="once"):
        check_legend({"colours": {"#ffffff": "free", "#FFFFFF": "concrete", "#000000": "wood"}})
    check_legend({"colours": {"#ffffff": "free", "#FFFFFF": "free", "#000000": "wood"}})  # same meaning: fine


@pytest.mark.parametrize("text", ["x = " + "9" * 5000, "x = " + "[" * 5000 + "]" * 5000,
                                  "colours = {" + "a = {" * 3000 + "}" * 3001])
def test_legend_toml_that_breaks_the_parser_is_an_error(tmp_path, text):
    path = tmp_path / "l.toml"
    path.write_text(text)
    with pytest.raises(InvalidInput) as info:
        load_legend(path)
    assert info.value.field == "legend"


def test_random_bytes_as_a_legend(tmp_path):
    rng = np.random.default_rng(1)
    for i in range(20):
        path = tmp_path / f"{i}.toml"
        path.write_bytes(rng.integers(0, 256, 200, dtype=np.uint8).tobytes())
        with pytest.raises(InvalidInput):
            load_legend(path)


# ------------------------------------------------------------------------------ material vocabulary ----
def test_known_materials_are_the_radio_table():
    from maps.materials import KNOWN_MATERIALS
    from radio.materials import DEFAULT_MATERIALS

    assert set(KNOWN_MATERIALS) == set(DEFAULT_MATERIALS)


@pytest.mark.parametrize("kind, params, field", [
    ("building", {"exterior_material": "unobtainium"}, "exterior_material"),
    ("building", {"exterior_material": "air"}, "exterior_material"),
    ("building", {"interior_materials": {"wood": 1, "bogus": 1}}, "interior_materials.bogus"),
    ("cave", {"materials": {"concrete": 1, "plasterr": 2}}, "materials.plasterr"),
])
def test_generators_refuse_unknown_materials(kind, params, field):
    with pytest.raises(InvalidInput) as info:
        generate(kind, 20, 0, params)
    assert info.value.field == f"{kind}.{field}", "the generator names its own fields in full"
    assert "concrete" in info.value.allowed and "glass" in info.value.allowed


def test_cli_generate_with_an_unknown_material_writes_nothing(tmp_path, capfd):
    err = cli_error(capfd, "map", "generate", "--kind", "building", "--size", "20",
                    "--param", "exterior_material=unobtainium", "-o", tmp_path / "m.npz")
    assert "exterior_material" in err and "unobtainium" in err and "concrete" in err
    assert not (tmp_path / "m.npz").exists()


def test_cli_import_with_an_unknown_material_flag(tmp_path, capfd):
    pgm = write_pgm(tmp_path / "p.pgm", 3, 3, [0, 0, 0, 0, 255, 0, 0, 0, 0])
    csv = tmp_path / "p.csv"
    csv.write_text("1,1,1\n1,0,1\n1,1,1\n")
    for path in (pgm, csv):
        err = cli_error(capfd, "map", "import", path, "--material", "bogus", "-o", tmp_path / "m.npz")
        assert err.startswith("swarm: error: --material: got 'bogus'") and "concrete" in err
        err = cli_error(capfd, "map", "import", path, "--border", "1", "--border-material", "bogus",
                        "-o", tmp_path / "m.npz")
        assert err.startswith("swarm: error: --border-material: got 'bogus'")
    assert not (tmp_path / "m.npz").exists()


def test_legend_colour_mapped_to_an_unknown_material(tmp_path):
    with pytest.raises(InvalidInput) as info:
        check_legend({"colours": {"#ffffff": "free", "#000000": "unobtainium"}})
    assert info.value.field == "legend.colours.#000000" and "concrete" in info.value.allowed


def test_legend_may_declare_extra_materials(tmp_path):
    path = write_png(tmp_path / "p.png", 6, 6)
    legend = check_legend({"materials": ["plaster"], "colours": {"#ffffff": "free", "#000000": "plaster"}})
    m = import_image(path, legend)
    assert m.materials == ("air", "plaster")
    with pytest.raises(InvalidInput) as info:
        check_legend({"materials": ["Bad Name"], "colours": {"#ffffff": "free"}})
    assert info.value.field == "legend.materials[0]"


def test_weights_whose_sum_overflows_are_refused():
    with pytest.raises(InvalidInput) as info:
        generate("building", 20, 0, {"interior_materials": {"concrete": 1e308, "wood": 1e308}})
    assert info.value.field == "building.interior_materials"


# ----------------------------------------------------------------------------------- long values ----
def test_invalid_input_is_always_one_short_line():
    huge = "x" * 20_000
    for exc in (InvalidInput(huge, huge, huge), InvalidInput("f\u2028g\x0bh\x1c", "v\nw", "a\fb\x85c\r"),
                InvalidInput("f", 10**5000, "any"), InvalidInput("f", {"k": huge}, "any")):
        one_line(str(exc))
    from swarm.base.errors import short_repr

    assert short_repr(10**5000).startswith("<an integer of")
    assert str(InvalidInput("size", 10, "an integer >= 20")) == "size: got 10; allowed: an integer >= 20"


def test_cli_errors_never_echo_a_20000_character_value(tmp_path, capfd):
    huge = "q" * 20_000
    legend = tmp_path / "l.toml"
    legend.write_text(f'[colours]\n"#ffffff" = "free"\n"{huge}" = "concrete"\n')
    png = write_png(tmp_path / "p.png", 6, 6)
    csv = tmp_path / "c.csv"
    csv.write_text("1,1\n1," + huge)
    for args in (["map", "generate", "--size", huge],
                 ["map", "generate", "--size", "20", "--param", f"{huge}=1"],
                 ["map", "generate", "--size", "20", "--param", f"exterior_material={huge}"],
                 ["map", "generate", "--size", "20", "--param", f"interior_materials.{huge}=1"],
                 ["map", "generate", "--size", "20", "--param", f"door_width={'9' * 20_000}"],
                 ["map", "generate", "--size", "20", "--param", f"door_width={'[' * 20_000}"],
                 ["map", "generate", "--kind", huge],
                 ["map", "generate", "--seed", "9" * 20_000],
                 ["map", "params", huge],
                 ["map", "show", tmp_path / huge[:200]],
                 ["map", "import", png, "--legend", legend, "-o", tmp_path / "m.npz"],
                 ["map", "import", csv, "-o", tmp_path / "m.npz"],
                 ["map", "import", csv, "--material", huge, "-o", tmp_path / "m.npz"]):
        err = cli_error(capfd, *args)
        assert huge[:200] not in err


def test_picture_size_is_bounded(tmp_path, capfd, monkeypatch):
    import maps.render

    monkeypatch.setattr(maps.render, "MAX_PICTURE_PIXELS", 100_000)
    err = cli_error(capfd, "map", "generate", "--size", "20", "--scale", "32", "--png", tmp_path / "p.png")
    assert err.startswith("swarm: error: --scale: got 32")
    assert not (tmp_path / "p.png").exists()


def test_map_model_keeps_custom_material_names():
    """The vocabulary is checked where users type names; a Map object (e.g. built in Python for a radio
    config that declares ``plaster``) may still carry any valid name."""
    solid = np.ones((5, 5), bool)
    solid[1:-1, 1:-1] = False
    m = Map(solid=solid, material=solid.astype(np.uint8), materials=("air", "plaster"))
    assert map_from_bytes(map_to_bytes(m)).materials == ("air", "plaster")


def test_a_cave_with_no_room_for_a_robot_is_an_error_naming_the_seed(capfd):
    """Found by the fuzz suite: the default 20 x 20 cave of seed 2000 used to raise a RuntimeError."""
    with pytest.raises(InvalidInput) as info:
        generate("cave", 20, 2000)
    assert info.value.field == "seed" and info.value.value == 2000
    assert "seed" in cli_error(capfd, "map", "generate", "--kind", "cave", "--size", "20", "--seed", "2000")


def test_special_and_oversized_files_are_refused_before_reading(tmp_path, monkeypatch):
    """A folder, a FIFO (reading it would hang) or a device (/dev/zero would fill the memory) is not read."""
    import os

    import maps.io

    (tmp_path / "folder.npz").mkdir()
    os.mkfifo(tmp_path / "fifo.pgm")
    for path in (tmp_path / "folder.npz", tmp_path / "fifo.pgm"):
        with pytest.raises(InvalidInput, match="a regular file"):
            load_map(path)
    if Path("/dev/zero").exists():
        with pytest.raises(InvalidInput, match="a regular file"):
            import_csv("/dev/zero")
    path = write_pgm(tmp_path / "p.pgm", 3, 3, [0, 0, 0, 0, 255, 0, 0, 0, 0])
    monkeypatch.setattr(maps.io, "MAX_TEXT_FILE_BYTES", 10)
    with pytest.raises(InvalidInput, match="at most"):
        import_pgm(path)


def test_a_building_too_small_inside_its_border_is_an_error_naming_the_size(capfd):
    """Found by the fuzz suite: 30 x 20 with border 8 leaves 14 x 4 tiles, rooms too thin for doors; that
    used to raise RuntimeError("... please report the seed")."""
    with pytest.raises(InvalidInput) as info:
        generate("building", (30, 20), 1, {"border": 8})
    assert info.value.field == "size" and "22" in info.value.allowed
    cli_error(capfd, "map", "generate", "--size", "30x20", "--seed", "1", "--param", "border=8")
    assert generate("building", 20, 0, {"border": 8}).free_cells > 0, "a single room inside a thick border is fine"


def test_a_building_border_that_leaves_no_inside_is_refused_in_one_line():
    """Found by the fuzz test: a border of half the map's side (20 tiles, border 10) left an empty inside,
    and the hall cutter divided by its area (ZeroDivisionError). One tile more is an inside (too thin for
    rooms with doors: refused as a size, as before); a wider map is a building."""
    with pytest.raises(InvalidInput, match="border") as info:
        generate("building", 20, 0, {"border": 10})
    assert "at most 9" in one_line(str(info.value))
    try:
        generate("building", 21, 0, {"border": 10})
    except InvalidInput as e:
        assert "size" in one_line(str(e))
    assert generate("building", 40, 0, {"border": 10}).solid.any()


def test_cli_map_generate_with_a_border_past_the_middle_exits_2(capfd, tmp_path):
    err = cli_error(capfd, "map", "generate", "--kind", "building", "--size", "20", "--seed", "0", "--param",
                    "hall_width=2", "--param", "border=10", "-o", str(tmp_path / "gen.npz"))
    assert "border" in err
