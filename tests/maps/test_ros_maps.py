"""ROS map_server map files (issue 51): import with map_server's semantics, export as map_saver writes, one-line
errors, and an Explore-Bench map imported and explored.

Explore-Bench's repository has no licence file, so its maps are not copied here: ``explore_bench_loop`` draws a
map of the same kind (its ``loop`` blueprint: map_saver's P5 header, 250 x 250 pixels of 0.1 m, walls one pixel
thick, unknown 205 outside and inside the loop) with a YAML of the same keys and values.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from PIL import Image

import swarm
from maps import InvalidInput, generate
from maps.io import MAX_CELLS, import_ros, load_map, save_npz, save_ros
from maps.ros import FREE, OCCUPIED, UNKNOWN, RosMapYaml, parse_ros_yaml, pixel_classes, resample_free, ros_origin
from swarm.cli import main

from .test_fuzz_inputs import EDITS, fuzz, load_or_refuse, mutate, time_limit
from .test_input_errors import cli_error

SAVER_YAML = ("image: {image}\nresolution: {resolution}\norigin: {origin}\nnegate: {negate}\n"
              "occupied_thresh: {occupied}\nfree_thresh: {free}\n")


def write_pgm(path: Path, pixels: np.ndarray, comment: str = "test") -> Path:
    """A binary (P5) PGM, top row first, as map_saver writes one."""
    rows, cols = pixels.shape
    path.write_bytes(f"P5\n# CREATOR: {comment}\n{cols} {rows}\n255\n".encode() + pixels.astype(np.uint8).tobytes())
    return path


def write_ros(folder: Path, pixels: np.ndarray, *, mode: str | None = None, negate: object = 0,
              occupied: object = 0.65, free: object = 0.196, resolution: object = 0.5,
              origin: str = "[0.0, 0.0, 0.0]", name: str = "m") -> Path:
    """A map_server YAML and its image (PGM for greys, PNG for colour or alpha); returns the YAML."""
    if pixels.ndim == 2:
        image = write_pgm(folder / f"{name}.pgm", pixels)
    else:
        image = folder / f"{name}.png"
        Image.fromarray(pixels.astype(np.uint8), "RGBA" if pixels.shape[2] == 4 else "RGB").save(image)
    text = SAVER_YAML.format(image=image.name, resolution=resolution, origin=origin, negate=negate,
                             occupied=occupied, free=free)
    if mode is not None:
        text += f"mode: {mode}\n"
    path = folder / f"{name}.yaml"
    path.write_text(text)
    return path


def framed(inner: list[list[int]], wall: int = 0) -> np.ndarray:
    """``inner`` pixels inside a one-pixel frame of ``wall`` (a swarm map's edge must be solid)."""
    return np.pad(np.array(inner, dtype=np.uint8), 1, constant_values=wall)


def read_ros_yaml(path: Path) -> RosMapYaml:
    return parse_ros_yaml(path.read_bytes(), path)


def info(mode: str = "trinary", negate: bool = False, occupied: float = 0.65, free: float = 0.196) -> RosMapYaml:
    return RosMapYaml(Path("unused.pgm"), 0.5, (0.0, 0.0, 0.0), negate, occupied, free, mode)


# ------------------------------------------------------------------------------------- semantics ----
def test_trinary_follows_map_server():
    # p = (255 - x) / 255: 0 -> 1.0 occupied, 205 -> 0.196078 unknown (map_saver's unknown), 254 -> free
    pixels = np.array([[0, 89, 90, 204, 205, 254, 255]], dtype=np.uint8)
    assert pixel_classes(pixels, info()).tolist() == [[OCCUPIED, OCCUPIED, UNKNOWN, UNKNOWN, UNKNOWN, FREE, FREE]]


def test_negate_reads_white_as_occupied():
    pixels = np.array([[0, 40, 100, 254, 255]], dtype=np.uint8)  # p = x / 255
    assert pixel_classes(pixels, info(negate=True)).tolist() == [[FREE, FREE, UNKNOWN, OCCUPIED, OCCUPIED]]


def test_thresholds_are_strict_at_their_boundaries():
    occupied, free = 100 / 255, 50 / 255  # exactly p of pixels 155 and 205
    pixels = np.array([[154, 155, 156, 204, 205, 206]], dtype=np.uint8)
    got = pixel_classes(pixels, info(occupied=occupied, free=free)).tolist()
    assert got == [[OCCUPIED, UNKNOWN, UNKNOWN, UNKNOWN, UNKNOWN, FREE]]


def test_thresholds_at_their_boundaries_round_trip_through_the_yaml(tmp_path):
    path = write_ros(tmp_path, framed([[205, 206]]), occupied=repr(100 / 255), free=repr(50 / 255))
    assert read_ros_yaml(path).free_thresh == 50 / 255
    m = import_ros(path)
    assert m.solid[1, 1:3].tolist() == [True, False]  # 205 sits on free_thresh: unknown, so solid


def test_thresholds_of_zero_and_one_make_every_pixel_unknown():
    pixels = np.array([[0, 128, 255]], dtype=np.uint8)
    assert pixel_classes(pixels, info(occupied=1.0, free=0.0)).tolist() == [[UNKNOWN] * 3]


def test_colour_pixels_use_the_mean_of_their_channels():
    pixels = np.array([[[10, 20, 30], [250, 252, 254], [200, 205, 210]]], dtype=np.uint8)  # means 20, 252, 205
    assert pixel_classes(pixels, info()).tolist() == [[OCCUPIED, FREE, UNKNOWN]]


def test_alpha_is_averaged_in_trinary_and_means_unknown_in_scale():
    # map_server's quirk: trinary averages alpha with the colours, so opaque 205 grey reads (3*205+255)/4 = 217.5
    opaque_grey, see_through_white = [205, 205, 205, 255], [255, 255, 255, 128]
    pixels = np.array([[opaque_grey, see_through_white, [0, 0, 0, 255]]], dtype=np.uint8)
    assert pixel_classes(pixels, info("trinary")).tolist() == [[FREE, FREE, OCCUPIED]]
    assert pixel_classes(pixels, info("scale")).tolist() == [[UNKNOWN, UNKNOWN, OCCUPIED]]


def test_scale_mode_in_between_pixels_are_not_free():
    pixels = np.array([[0, 128, 255]], dtype=np.uint8)
    assert pixel_classes(pixels, info("scale")).tolist() == [[OCCUPIED, UNKNOWN, FREE]]


def test_raw_mode_reads_the_pixel_as_percent_occupancy_and_ignores_negate():
    pixels = np.array([[0, 19, 20, 65, 66, 100, 101, 205, 255]], dtype=np.uint8)
    expected = [[FREE, FREE, UNKNOWN, UNKNOWN, OCCUPIED, OCCUPIED, UNKNOWN, UNKNOWN, UNKNOWN]]
    for negate in (False, True):
        assert pixel_classes(pixels, info("raw", negate, free=0.2)).tolist() == expected


@pytest.mark.parametrize("mode, negate, inner, free", [
    (None, 0, [[254, 205], [0, 255]], [[True, False], [False, True]]),
    ("Trinary", 1, [[254, 205], [0, 1]], [[False, False], [True, True]]),
    ("scale", 0, [[254, 128], [0, 255]], [[True, False], [False, True]]),
    ("raw", 0, [[0, 100], [255, 10]], [[True, False], [False, True]]),
])
def test_each_mode_through_the_importer(tmp_path, mode, negate, inner, free):
    wall = 255 if negate and mode != "raw" else 100 if mode == "raw" else 0
    m = import_ros(write_ros(tmp_path, framed(inner, wall), mode=mode, negate=negate))
    assert (~m.solid[1:3, 1:3])[::-1].tolist() == free  # image rows run top-down, map rows bottom-up
    assert m.solid[0].all() and m.solid[-1].all() and m.params["mode"] == (mode or "trinary").lower()


def test_png_images_import_too(tmp_path):
    rgb = np.repeat(framed([[254, 254], [254, 0]])[..., None], 3, axis=2)
    m = import_ros(write_ros(tmp_path, rgb))
    assert (~m.solid).sum() == 3 and m.solid[1, 2]


# ------------------------------------------------------------------------------------ resampling ----
def test_a_cell_is_free_only_if_every_pixel_it_covers_is_free():
    free = np.ones((10, 10), dtype=bool)
    free[3, 7] = False  # a wall one 0.1 m pixel wide
    expected = np.ones((2, 2), dtype=bool)
    expected[0, 1] = False
    assert resample_free(free, 0.1).tolist() == expected.tolist()


def test_pixels_that_straddle_cells_block_both_and_cells_past_the_image_are_solid():
    free = np.ones((5, 4), dtype=bool)  # 0.3 m pixels: 1.2 m wide (2.4 cells), 1.5 m high (3 cells)
    free[0, 1] = False  # x in [0.3, 0.6): in cells 0 and 1
    assert resample_free(free, 0.3).tolist() == [[False, False, False], [True, True, False], [True, True, False]]


def test_coarse_pixels_cover_several_cells():
    free = np.ones((3, 3), dtype=bool)
    free[1, 1] = False
    assert np.array_equal(resample_free(free, 1.0), np.repeat(np.repeat(free, 2, 0), 2, 1))


# ------------------------------------------------------------------------------ origin, round trip ----
def test_origin_is_recorded_and_a_border_moves_it(tmp_path):
    path = write_ros(tmp_path, framed([[254] * 4] * 4), origin="[-3.5, 2.25, 0.0]")
    assert ros_origin(import_ros(path)) == (-3.5, 2.25)
    assert ros_origin(import_ros(path, border=2)) == (-5.5, 0.25)
    assert ros_origin(generate("building", 20, 1)) == (0.0, 0.0)


def test_export_then_import_gives_the_same_raster_and_origin(tmp_path):
    inner = np.full((6, 8), 254)
    inner[2, 3] = 0
    truth = import_ros(write_ros(tmp_path, framed(inner.tolist()), resolution=0.25, origin="[-12.5, 7.0, 0.0]"),
                       border=1)
    assert 0 < truth.free_cells < truth.solid.size
    yaml_path, image_path = save_ros(truth, tmp_path / "out.yaml")
    doc = read_ros_yaml(yaml_path)
    assert (doc.image, doc.resolution, doc.origin, doc.mode) == (image_path, 0.5, (-13.5, 6.0, 0.0), "trinary")
    with Image.open(image_path) as im:
        assert im.format == "PPM" and im.mode == "L" and set(np.unique(np.asarray(im))) == {0, 254}
    back = import_ros(yaml_path)
    assert np.array_equal(back.solid, truth.solid) and ros_origin(back) == ros_origin(truth) == (-13.5, 6.0)
    building = generate("building", 30, 4)
    assert np.array_equal(import_ros(save_ros(building, tmp_path / "b.yaml")[0]).solid, building.solid)


def test_cli_export_and_import_round_trip(tmp_path, capsys):
    ros = tmp_path / "b.yaml"
    assert main(["map", "export", "--kind", "building", "--size", "24", "--seed", "5", "--ros", str(ros)]) == 0
    assert main(["map", "import", str(ros), "-o", str(tmp_path / "b.npz")]) == 0
    assert np.array_equal(load_map(tmp_path / "b.npz").solid, generate("building", 24, 5).solid)
    assert main(["map", "export", str(tmp_path / "b.npz"), "--ros", str(tmp_path / "c.yml")]) == 0
    assert (tmp_path / "c.pgm").read_bytes() == (tmp_path / "b.pgm").read_bytes()
    assert "wrote" in capsys.readouterr().out


def test_an_export_that_fails_leaves_no_image(tmp_path, monkeypatch):
    import maps.io

    real = maps.io.atomic_write_bytes

    def full_disk_for_yaml(path: Path, data: bytes) -> Path:
        if path.suffix == ".yaml":
            raise OSError(28, "No space left on device")
        return real(path, data)

    monkeypatch.setattr(maps.io, "atomic_write_bytes", full_disk_for_yaml)
    with pytest.raises(OSError):
        save_ros(generate("building", 20, 1), tmp_path / "m.yaml")
    assert list(tmp_path.iterdir()) == []


# ------------------------------------------------------------------------------------- bad input ----
def yaml_with(folder: Path, **changes: str) -> Path:
    """A valid map_server YAML with some values replaced (``None`` drops a key) next to a valid image."""
    write_pgm(folder / "m.pgm", framed([[254, 254], [254, 254]]))
    values = {"image": "m.pgm", "resolution": "0.5", "origin": "[0.0, 0.0, 0.0]", "negate": "0",
              "occupied_thresh": "0.65", "free_thresh": "0.196", **changes}
    path = folder / "m.yaml"
    path.write_text("".join(f"{k}: {v}\n" for k, v in values.items() if v is not None))
    return path


@pytest.mark.parametrize("changes, needles", [
    ({"image": "missing.pgm"}, ["image in m.yaml", "missing.pgm", "No such file"]),
    ({"image": "''"}, ["image in m.yaml", "the path of the map's PGM or PNG image"]),
    ({"mode": "fuzzy"}, ["mode in m.yaml: got 'fuzzy'", "trinary | scale | raw"]),
    ({"mode": "x" * 5000}, ["mode in m.yaml: got 'xxx", "...", "trinary | scale | raw"]),
    ({"occupied_thresh": "1.5"}, ["occupied_thresh in m.yaml: got 1.5", "a number in 0..1"]),
    ({"free_thresh": "-0.1"}, ["free_thresh in m.yaml: got -0.1", "a number in 0..1"]),
    ({"free_thresh": "0.7"}, ["free_thresh in m.yaml: got 0.7", "below occupied_thresh (0.65)"]),
    ({"free_thresh": "0.65"}, ["free_thresh in m.yaml: got 0.65", "below occupied_thresh"]),
    ({"free_thresh": ".nan"}, ["free_thresh in m.yaml: got nan", "a number in 0..1"]),
    ({"occupied_thresh": None}, ["occupied_thresh in m.yaml: got None", "a number in 0..1"]),
    ({"resolution": "-0.05"}, ["resolution in m.yaml: got -0.05", "a number from 0.001 to 1000 (metres per pixel)"]),
    ({"resolution": "0"}, ["resolution in m.yaml: got 0", "a number from 0.001 to 1000"]),
    ({"resolution": "1e-193"}, ["resolution in m.yaml: got '1e-193'", "a number from 0.001 to 1000"]),
    ({"resolution": "fine"}, ["resolution in m.yaml: got 'fine'", "a number from 0.001 to 1000"]),
    ({"origin": "[0.0, 0.0, 0.5]"}, ["origin in m.yaml: got [0.0, 0.0, 0.5]", "yaw 0"]),
    ({"origin": "[1.0, 2.0]"}, ["origin in m.yaml: got [1.0, 2.0]", "[x, y, yaw]"]),
    ({"negate": "2"}, ["negate in m.yaml: got 2", "0, 1, true or false"]),
])
def test_bad_yaml_values_are_one_line_naming_the_field(tmp_path, capfd, changes, needles):
    err = cli_error(capfd, "map", "import", yaml_with(tmp_path, **changes), "-o", tmp_path / "out.npz")
    assert all(n in err for n in needles), err
    assert not (tmp_path / "out.npz").exists()


@pytest.mark.parametrize("text, needles", [
    ("- image\n- m.pgm\n", ["m.yaml: got ['image', 'm.pgm']", "a YAML mapping with the map_server keys"]),
    ("just text\n", ["m.yaml: got 'just text'", "a YAML mapping"]),
    ("image: [unclosed\n", ["map file", "valid YAML"]),
    ("[" * 10_000, ["map file", "valid YAML"]),
])
def test_a_yaml_that_is_not_a_mapping_is_one_line(tmp_path, capfd, text, needles):
    (tmp_path / "m.yaml").write_text(text)
    err = cli_error(capfd, "map", "import", tmp_path / "m.yaml", "-o", tmp_path / "out.npz")
    assert all(n in err for n in needles), err


ODD_VALUES = st.one_of(
    st.sampled_from(["0", "-1", "1", "0.5", "1e400", ".nan", "-.inf", "~", "''", "[]", "{}", "[1, 2, 3]",
                     "[0, 0, 0]", "[0, 0, 1e-300]", "true", "'0.5'", "5e-1", "0x10", "9" * 5000, "[" * 60,
                     "!!python/object:os.getcwd x", "m.pgm", "/dev/zero", ".", "trinary", "SCALE", "raw",
                     "\"\\0\""]),
    st.floats().map(repr), st.text(max_size=8).map(json.dumps))
KEYS = ("image", "resolution", "origin", "negate", "occupied_thresh", "free_thresh", "mode")
VALID_PGM = b"P5\n4 4\n255\n" + bytes([0] * 5 + [254, 254, 0, 0, 205, 254] + [0] * 5)


@fuzz(200)
@given(changes=st.dictionaries(st.sampled_from(KEYS), st.one_of(st.none(), ODD_VALUES), max_size=3),
       edits=st.one_of(st.none(), EDITS))
def test_fuzz_yaml_and_image(tmp_path_factory, changes, edits):
    folder = tmp_path_factory.mktemp("fuzz")
    path = yaml_with(folder, **changes)
    (folder / "m.pgm").write_bytes(VALID_PGM if edits is None else mutate(VALID_PGM, edits))
    load_or_refuse("ros map", import_ros, path)


def test_yaml_aliases_cannot_blow_up_an_error_message(tmp_path, capfd):
    # nine levels of nine aliases: a value of 9**10 items whose full repr would take gigabytes
    lists = ["[1, 1, 1, 1, 1, 1, 1, 1, 1]"] + [f"[{', '.join([f'*a{i - 1}'] * 9)}]" for i in range(1, 10)]
    anchors = "".join(f"a{i}: &a{i} {text}\n" for i, text in enumerate(lists))
    as_origin = yaml_with(tmp_path, origin="*a9")
    as_origin.write_text(anchors + as_origin.read_text())
    as_document = tmp_path / "d.yaml"
    as_document.write_text("".join(f"- &a{i} {text}\n" for i, text in enumerate(lists)))
    with time_limit(20):
        err = cli_error(capfd, "map", "import", as_origin, "-o", tmp_path / "o.npz")
        assert err.startswith("swarm: error: origin in m.yaml: got [[[[...], [...],") and "[x, y, yaw]" in err
        err = cli_error(capfd, "map", "import", as_document, "-o", tmp_path / "o.npz")
        assert err.startswith("swarm: error: d.yaml: got [[1, 1, 1, 1, 1, 1, ...], ") and "a YAML mapping" in err


def test_accepted_spellings_match_map_server(tmp_path):
    path = yaml_with(tmp_path, resolution="'5e-1'", negate="false", mode="RAW", origin="[1, -2, -0.0]")
    doc = read_ros_yaml(path)
    assert (doc.resolution, doc.negate, doc.mode, doc.origin) == (0.5, False, "raw", (1.0, -2.0, 0.0))


def test_a_huge_image_is_refused_from_its_header(tmp_path, capfd):
    side = int(MAX_CELLS ** 0.5) + 100
    (tmp_path / "m.pgm").write_bytes(f"P5\n{side} {side}\n255\n".encode())  # no pixels: never read
    path = tmp_path / "m.yaml"
    path.write_text(SAVER_YAML.format(image="m.pgm", resolution=0.5, origin="[0, 0, 0]", negate=0, occupied=0.65,
                                      free=0.196))
    err = cli_error(capfd, "map", "import", path, "-o", tmp_path / "o.npz")
    assert "image in m.yaml" in err and f"an image of at most {MAX_CELLS} pixels" in err


def test_a_map_that_would_be_too_big_is_refused_before_decoding(tmp_path):
    path = write_ros(tmp_path, framed([[254] * 98] * 98), resolution=100)  # 100 m pixels: 20000 x 20000 cells
    with pytest.raises(InvalidInput, match=f"a map of at most {MAX_CELLS} cells"):
        import_ros(path)


def test_sixteen_bit_images_are_refused(tmp_path):
    image = tmp_path / "m.pgm"
    image.write_bytes(b"P5\n3 3\n65535\n" + b"\x00\x00" * 9)
    (tmp_path / "m.yaml").write_text(SAVER_YAML.format(image="m.pgm", resolution=0.5, origin="[0, 0, 0]",
                                                       negate=0, occupied=0.65, free=0.196))
    with pytest.raises(InvalidInput, match="an 8-bit greyscale or colour image"):
        import_ros(tmp_path / "m.yaml")


def test_cli_flags_that_do_not_fit_are_one_line(tmp_path, capfd):
    ros = write_ros(tmp_path, framed([[254]]))
    legend = tmp_path / "legend.toml"
    legend.write_text('[colours]\n"#ffffff" = "free"\n')
    assert "no legend for a ROS map YAML" in cli_error(capfd, "map", "import", ros, "--legend", legend,
                                                       "-o", tmp_path / "o.npz")
    save_npz(generate("building", 20, 1), tmp_path / "b.npz")
    assert "--ros: got" in cli_error(capfd, "map", "export", tmp_path / "b.npz", "--ros", tmp_path / "b.txt")
    assert "PATH: got None" in cli_error(capfd, "map", "export", "--ros", tmp_path / "b.yaml")
    assert "PATH: got" in cli_error(capfd, "map", "export", tmp_path / "b.npz", "--kind", "cave",
                                    "--ros", tmp_path / "b.yaml")
    assert "--seed: got 3" in cli_error(capfd, "map", "export", tmp_path / "b.npz", "--seed", "3",
                                        "--ros", tmp_path / "b.yaml")
    assert not (tmp_path / "b.yaml").exists() and not (tmp_path / "b.pgm").exists()


# --------------------------------------------------------------------------------- Explore-Bench ----
@pytest.fixture
def explore_bench_loop(tmp_path: Path) -> Path:
    """A map like Explore-Bench's ``loop`` blueprint: a square corridor 2.8 m wide between one-pixel walls."""
    pixels = np.full((250, 250), 205, dtype=np.uint8)
    pixels[25:225, 25:225] = 0
    pixels[26:224, 26:224] = 254
    pixels[54:196, 54:196] = 0
    pixels[55:195, 55:195] = 205
    write_pgm(tmp_path / "loop.pgm", pixels, "map_saver.cpp 0.100 m/pix")
    (tmp_path / "loop.yaml").write_text("image: loop.pgm\nresolution: 0.100000\n"
                                        "origin: [-12.500000, -12.500000, 0.000000]\nnegate: 0\n"
                                        "occupied_thresh: 0.65\nfree_thresh: 0.196\n\n")
    return tmp_path / "loop.yaml"


def test_explore_bench_map_imports_with_its_geometry(explore_bench_loop):
    m = load_map(explore_bench_loop)
    assert m.shape == (50, 50) and ros_origin(m) == (-12.5, -12.5)
    # pixels 26..53 are free: cells 6..9 (pixels 30..49) lie wholly inside, cells 5 and 10 hold a wall pixel
    assert (~m.solid[25]).tolist() == [False] * 6 + [True] * 4 + [False] * 30 + [True] * 4 + [False] * 6
    assert m.free_cells == 38**2 - 30**2  # free cells 6..43 square, less the solid cells 10..39 inside


def test_explore_bench_map_is_explored_through_the_run_path(explore_bench_loop):
    spec = (f'seed = 1\nrecord_every = 10\n[map]\nkind = "file"\npath = "{explore_bench_loop}"\n'
            '[robots]\ncount = 2\n[stop]\nmax_ticks = 500\nexplored = 0.95\n')
    result = swarm.run(spec)
    explored = result.timeseries["explored"]
    assert explored[0] < 0.3 and explored[-1] > 0.7, explored
    assert result.summary["explored"] == explored[-1]


def test_scale_lets_the_default_robot_through_explore_bench_doors(tmp_path):
    """Two 6 m rooms joined by a 1.4 m door (Explore-Bench's ``room`` maps): it resamples to a 1 m gap the
    default robot cannot plan through; at scale 1.5 the gap is 2 m and the second room is explored."""
    pixels = np.full((80, 140), 0, dtype=np.uint8)   # 0.1 m pixels: 8 x 14 m of wall
    pixels[10:70, 10:68] = 254                        # room A, 5.8 x 6 m
    pixels[10:70, 72:130] = 254                       # room B
    pixels[33:47, 68:72] = 254                        # the 1.4 m door in the 0.4 m wall between them
    path = write_ros(tmp_path, pixels, resolution=0.1)
    base = {"seed": 1, "robots": {"count": 1, "spawn_seed": 1}, "stop": {"max_ticks": 1500}}
    narrow = swarm.run({**base, "map": {"kind": "file", "path": str(path)}})
    wide = swarm.run({**base, "map": {"kind": "file", "path": str(path), "params": {"scale": 1.5}}})
    assert narrow.summary["stop_reason"] == "stalled" and narrow.summary["explored"] < 0.9   # seen through the door
    assert wide.summary["stop_reason"] == "explored" and wide.summary["explored"] >= 0.99
    m = load_map(path, scale=1.5)
    assert m.params["scale"] == 1.5 and m.shape == (24, 42)   # 8 x 14 m at 1.5: 12 x 21 m in 0.5 m cells


def test_scale_is_refused_for_maps_without_metres_to_scale(tmp_path):
    with pytest.raises(InvalidInput, match="scale"):
        load_map(write_pgm(tmp_path / "m.pgm", framed([[254, 254]])), scale=1.5)
