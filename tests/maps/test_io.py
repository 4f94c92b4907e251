"""Map files: exact round trips, importers, and clear errors for malformed input (fuzzed)."""

from __future__ import annotations

import io
import zipfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st
from PIL import Image

from maps import InvalidInput, generate
from maps.io import (check_legend, import_csv, import_image, import_pgm, load_legend, load_map, load_npz,
                     map_from_bytes, map_to_bytes, save_npz)

SHARED_HOUSE = Path(__file__).resolve().parents[3] / "shared" / "data" / "xboa-maps" / "map-house.csv"


@pytest.mark.parametrize("kind", ["cave", "building"])
def test_export_then_import_is_exact(tmp_path, kind):
    m = generate(kind, 50, 9)
    path = save_npz(m, tmp_path / "m.npz")
    back = load_npz(path)
    assert back.same_as(m)
    assert np.array_equal(back.rooms, m.rooms) if m.rooms is not None else back.rooms is None
    assert map_to_bytes(back) == path.read_bytes(), "re-saving gives the same bytes"
    with np.load(path) as z:  # plain numpy can read the format
        assert np.array_equal(z["solid"], m.solid)


def test_save_replaces_atomically_and_keeps_old_file_on_failure(tmp_path, monkeypatch):
    m = generate("building", 30, 1)
    path = save_npz(m, tmp_path / "m.npz")
    before = path.read_bytes()

    def broken_write(*_a, **_k):
        raise OSError("disk full")

    monkeypatch.setattr("os.fsync", broken_write)
    with pytest.raises(OSError):
        save_npz(generate("cave", 30, 1), path)
    assert path.read_bytes() == before
    assert [p.name for p in tmp_path.iterdir()] == ["m.npz"], "no temporary file left behind"


def test_csv_import_orientation_and_scale(tmp_path):
    rows = ["1,1,1,1", "1,0,0,1", "1,0,1,1", "1,1,1,1"]  # row index is y: row 2 (y = 2 m) has a wall at x = 2
    path = tmp_path / "g.csv"
    path.write_text("\n".join(rows))
    m = import_csv(path, material="brick")
    assert m.shape == (8, 8) and m.materials == ("air", "brick")
    assert m.is_free_at(1.5, 1.5) and not m.is_free_at(2.5, 2.5) and m.is_free_at(1.5, 2.5)


@pytest.mark.skipif(not SHARED_HOUSE.exists(), reason="xBOA house map not available beside the checkout")
def test_xboa_house_map():
    m = import_csv(SHARED_HOUSE)
    assert m.shape == (48, 48)
    assert int(m.solid.sum()) == 155 * 4  # the paper's house map has 155 wall cells of 1 m


def test_pgm_import_follows_maes(tmp_path):
    # 4x3 image, top row first; MAES writes one value per line after a comment line.
    values = [0, 0, 0, 0,
              0, 255, 124, 0,
              0, 0, 0, 0]
    path = tmp_path / "m.pgm"
    path.write_text("P2\n# CREATOR: GIMP\n4 3\n255\n" + "\n".join(map(str, values)) + "\n")
    m = import_pgm(path)
    assert m.shape == (6, 8)
    assert m.is_free_at(1.5, 1.5), "value 255 (>= 125) is free; top row of the file is y = 2 m"
    assert not m.is_free_at(2.5, 1.5), "value 124 (< 125) is wall"
    assert m.materials == ("air", "concrete")
    assert import_pgm(path, material="wall").materials == ("air", "wall")


def test_image_import_with_legend(tmp_path):
    img = np.zeros((6, 8, 3), dtype=np.uint8)
    img[:] = (0, 0, 0)                      # concrete everywhere
    img[1:5, 1:7] = (255, 255, 255)         # free inside
    img[1:3, 4] = (160, 82, 45)             # a brick stub in the top half (image rows 1-2)
    path = tmp_path / "plan.png"
    Image.fromarray(img).save(path)
    legend_path = tmp_path / "legend.toml"
    legend_path.write_text('metres_per_pixel = 1.0\n[colours]\n"#ffffff" = "free"\n"#000000" = "concrete"\n'
                           '"#a0522d" = "brick"\n')
    m = load_map(path, legend=legend_path)
    assert m.shape == (12, 16)
    assert m.materials == ("air", "concrete", "brick")
    # image row 1 (from the top) of 6 is y in [4, 5) m
    assert m.material[m.cell_of(4.5, 4.5)] == m.material_id("brick")
    assert m.is_free_at(4.5, 1.5)


def test_image_with_unknown_colour_names_the_pixel(tmp_path):
    img = np.zeros((4, 4, 3), dtype=np.uint8)
    img[1:3, 1:3] = 255
    img[2, 2] = (1, 2, 3)
    path = tmp_path / "p.png"
    Image.fromarray(img).save(path)
    legend = check_legend({"colours": {"#ffffff": "free", "#000000": "concrete"}})
    with pytest.raises(InvalidInput, match=r"x=2, y=2 .*#010203"):
        import_image(path, legend)
    m = import_image(path, {**legend, "tolerance": 3})  # #010203 is within 3 of black: concrete
    assert m.materials[m.material[m.cell_of(1.25, 0.75)]] == "concrete"
    assert m.is_free_at(0.75, 0.75)


def test_open_edge_needs_a_border(tmp_path):
    path = tmp_path / "open.csv"
    path.write_text("0,0,0\n0,0,0\n0,0,0\n")
    with pytest.raises(InvalidInput, match="border"):
        import_csv(path)
    m = import_csv(path, border=1, border_material="wood")
    assert m.shape == (10, 10) and "wood" in m.materials
    assert m.is_free_at(2.5, 2.5) and not m.is_free_at(0.5, 0.5)


@pytest.mark.parametrize("legend, field", [
    ({"colours": {"#fff": "free"}}, "legend.colours.#fff"),
    ({"colours": {"#ffffff": "Concrete!"}}, "legend.colours.#ffffff"),
    ({"colours": {"#000000": "concrete"}}, "legend.colours"),
    ({"colours": {"#ffffff": "free"}, "metres_per_pixel": 0.3}, "legend.metres_per_pixel"),
    ({"colours": {"#ffffff": "free"}, "tolerance": -1}, "legend.tolerance"),
    ({"colours": {"#ffffff": "free"}, "scale": 2}, "legend.scale"),
])
def test_bad_legends_name_the_field(legend, field):
    with pytest.raises(InvalidInput) as info:
        check_legend(legend)
    assert info.value.field == field
    assert "\n" not in str(info.value)


def test_legend_file_errors(tmp_path):
    path = tmp_path / "l.toml"
    path.write_text("colours = [")
    with pytest.raises(InvalidInput, match="valid TOML"):
        load_legend(path)


def _valid_bytes() -> bytes:
    return map_to_bytes(generate("building", 20, 0))


VALID = _valid_bytes()


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.binary(max_size=400))
def test_fuzz_random_bytes_never_crash(data):
    with pytest.raises(InvalidInput):
        map_from_bytes(data)


@settings(max_examples=150, deadline=None)
@given(st.integers(0, len(VALID) - 1), st.integers(0, 255), st.integers(1, 8))
def test_fuzz_corrupted_npz_is_rejected_or_exact(pos, value, length):
    data = bytearray(VALID)
    data[pos:pos + length] = bytes([value]) * len(data[pos:pos + length])
    try:
        m = map_from_bytes(bytes(data))
    except InvalidInput as exc:
        assert "\n" not in str(exc)
    else:  # a mutation that decodes must still be a consistent map
        assert m.solid.shape == m.material.shape


def _npz_with(**overrides) -> bytes:
    with np.load(io.BytesIO(VALID)) as z:
        arrays = {k: z[k] for k in z.files}
    arrays.update(overrides)
    arrays = {k: v for k, v in arrays.items() if v is not None}
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as zf:
        for k, v in arrays.items():
            with zf.open(f"{k}.npy", "w") as f:
                np.lib.format.write_array(f, v)
    return buf.getvalue()


@pytest.mark.parametrize("overrides, message", [
    ({"solid": None}, "missing arrays: solid"),
    ({"material": np.zeros((40, 40), np.int32)}, "material uint8"),
    ({"meta": np.frombuffer(b"{not json", np.uint8)}, "JSON metadata"),
    ({"meta": np.frombuffer(b'{"format": "other"}', np.uint8)}, "format 'swarm-map'"),
    ({"meta": np.frombuffer(b'{"format": "swarm-map", "version": 99}', np.uint8)}, "version 1"),
    ({"material": np.zeros((40, 40), np.uint8)}, "wall material on every solid cell"),
])
def test_structurally_bad_files_say_what_is_wrong(overrides, message):
    with pytest.raises(InvalidInput, match=message):
        map_from_bytes(_npz_with(**overrides), "x.npz")


@settings(max_examples=100, deadline=None)
@given(st.text(alphabet="01,\n 2x", max_size=120))
def test_fuzz_csv_loader(tmp_path_factory, text):
    path = tmp_path_factory.mktemp("csv") / "f.csv"
    path.write_text(text)
    try:
        m = import_csv(path, border=1)
    except InvalidInput as exc:
        assert "\n" not in str(exc)
    else:
        assert m.solid[0].all()


@settings(max_examples=100, deadline=None)
@given(st.text(alphabet="P2# 0123456789\n-", max_size=80))
def test_fuzz_pgm_loader(tmp_path_factory, text):
    path = tmp_path_factory.mktemp("pgm") / "f.pgm"
    path.write_text(text)
    try:
        import_pgm(path, border=1)
    except InvalidInput as exc:
        assert "\n" not in str(exc)


@settings(max_examples=100, deadline=None)
@given(st.dictionaries(st.sampled_from(["colours", "metres_per_pixel", "tolerance", "x"]),
                       st.one_of(st.integers(-5, 300), st.floats(allow_nan=True), st.text(max_size=8),
                                 st.dictionaries(st.text(max_size=8), st.text(max_size=8), max_size=3)),
                       max_size=4))
@example({"colours": {"\n": ""}})                         # a newline in a key used to break the one-line error
@example({"metres_per_pixel": 8.98846567431158e+307})     # used to overflow round() instead of being refused
def test_fuzz_legend(raw):
    try:
        check_legend(raw)
    except InvalidInput as exc:
        assert "\n" not in str(exc)


def test_fuzz_image_bytes(tmp_path):
    rng = np.random.default_rng(0)
    legend = check_legend({"colours": {"#ffffff": "free"}})
    for i in range(30):
        path = tmp_path / f"{i}.png"
        path.write_bytes(rng.integers(0, 256, size=int(rng.integers(0, 300)), dtype=np.uint8).tobytes())
        with pytest.raises(InvalidInput):
            import_image(path, legend)
