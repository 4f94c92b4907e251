"""Map files: the lossless ``.npz`` format, and importers for images with a legend, MAES PGM and xBOA CSV
(ROS map_server YAML files: :mod:`maps.ros`; HouseExpo JSON plans: :mod:`maps.houseexpo`).

Every reader turns anything malformed into one :class:`InvalidInput` naming the file and what is wrong;
every writer writes to a temporary file and renames it, so an existing file is never left half-written.

The ``.npz`` format (version 1) is a zip of ``.npy`` arrays, readable with ``numpy.load``:
``solid`` (bool[H, W]), ``material`` (uint8[H, W]), optional ``rooms`` (int16[H, W]) and ``meta`` (uint8
bytes of UTF-8 JSON: ``format``, ``version``, ``kind``, ``seed``, ``params``, ``materials``, ``graph``).
Zip timestamps are fixed, so the same map always gives the same bytes.
"""

from __future__ import annotations

import io
import json
import math
import os
import re
import stat
import tempfile
import tomllib
import zipfile
from pathlib import Path
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from swarm.base.errors import InvalidInput, field_name, short_repr, shorten
from . import houseexpo, ros
from .materials import AIR, DEFAULT_TABLE, check_known_material, check_material_name
from .model import CELL_M, CELLS_PER_TILE, Map, graph_from_json, graph_to_json

FORMAT = "swarm-map"
VERSION = 1
FREE_NAMES = ("free", AIR)
MAX_CELLS = 4000 * 4000
MAX_FILE_BYTES = 256 * 2**20
"""No map file is read if it is bigger: the largest map (``MAX_CELLS``) fits many times over."""
MAX_TEXT_FILE_BYTES = 64 * 2**20
"""PGM and CSV files: ``MAX_CELLS / 4`` tiles of a few characters each, plus comments."""
MAX_LEGEND_BYTES = 2**20
MAX_META_BYTES = 64 * 2**20
MAX_LEGEND_COLOURS = 1024
PGM_MAX_MAXVAL = 65535
"""The PGM format's own limit on ``maxval`` (pixel values are 0..maxval)."""
_MATCH_CHUNK_ELEMENTS = 4 * 2**20
"""Image import compares pixels with legend colours this many (pixel, colour, channel) values at a time."""
_FIXED_ZIP_TIME = (1980, 1, 1, 0, 0, 0)
_COLOUR_RE = re.compile(r"#[0-9a-fA-F]{6}")
_PGM_COMMENT_RE = re.compile(rb"#[^\r\n]*")


# ------------------------------------------------------------------------------------ writing ----
def atomic_write_bytes(path: Path, data: bytes) -> Path:
    """Write ``data`` to ``path`` via a temporary file in the same folder and an atomic rename."""
    path = Path(path)
    folder = path.parent if str(path.parent) else Path(".")
    try:
        if not folder.is_dir():
            raise InvalidInput("output", str(path), "a path in an existing folder")
        if path.is_dir():
            raise InvalidInput("output", str(path), "a file path (this is a folder)")
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name[:100]}.", suffix=".tmp", dir=folder)
    except InvalidInput:
        raise
    except (OSError, ValueError) as exc:  # a read-only or special folder (/proc), a name too long, NUL...
        reason = getattr(exc, "strerror", None) or type(exc).__name__
        raise InvalidInput("output", str(path), f"a path in a folder we can write to ({shorten(reason)})") from None
    try:
        os.chmod(tmp, 0o666 & ~_umask())  # mkstemp makes 0600; a written file should look like any other
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except FileNotFoundError:
            pass
        raise
    return path


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def map_to_bytes(m: Map) -> bytes:
    """The ``.npz`` bytes of a map (deterministic)."""
    meta = {
        "format": FORMAT, "version": VERSION, "kind": m.kind, "seed": m.seed, "params": dict(m.params),
        "materials": list(m.materials), "graph": graph_to_json(m.graph),
    }
    arrays: dict[str, np.ndarray] = {"solid": m.solid, "material": m.material,
                                     "meta": np.frombuffer(json.dumps(meta, sort_keys=True).encode(), np.uint8)}
    if m.rooms is not None:
        arrays["rooms"] = m.rooms
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", compression=zipfile.ZIP_DEFLATED) as zf:
        for name in sorted(arrays):
            info = zipfile.ZipInfo(f"{name}.npy", date_time=_FIXED_ZIP_TIME)
            info.compress_type = zipfile.ZIP_DEFLATED
            with zf.open(info, "w", force_zip64=True) as f:
                np.lib.format.write_array(f, np.ascontiguousarray(arrays[name]), allow_pickle=False)
    return buf.getvalue()


def save_npz(m: Map, path: str | Path) -> Path:
    return atomic_write_bytes(Path(path), map_to_bytes(m))


# ------------------------------------------------------------------------------------ reading ----
def _bad(path: Any, what: str) -> InvalidInput:
    return InvalidInput("map file", str(path), what)


def read_file_bytes(path: str | Path, field: str, limit: int = MAX_FILE_BYTES) -> bytes:
    """The bytes of a regular file of at most ``limit`` bytes, or an :class:`InvalidInput` naming ``field``.

    Checked before reading: a FIFO or device (``/dev/zero``) would hang or fill the memory, and a file
    bigger than any valid one is refused without loading it.
    """
    try:
        info = os.stat(path)
        if not stat.S_ISREG(info.st_mode):
            raise InvalidInput(field, str(path), "a regular file")
        if info.st_size > limit:
            raise InvalidInput(field, str(path), f"a file of at most {limit // 2**20} MiB "
                                                 f"(this one has {info.st_size / 2**20:.0f} MiB)")
        with open(path, "rb") as f:
            data = f.read(info.st_size + 1)  # not read(limit): that would allocate the limit up front
    except InvalidInput:
        raise
    except OSError as exc:
        raise InvalidInput(field, str(path), f"a readable file ({shorten(exc.strerror or type(exc).__name__)})") from None
    except ValueError:  # an embedded NUL byte, e.g. from a spec file's "\u0000"
        raise InvalidInput(field, str(path), "a file path without NUL characters") from None
    if len(data) > limit:
        raise InvalidInput(field, str(path), f"a file of at most {limit // 2**20} MiB")
    return data


def parse_toml(text: str, field: str, value: Any) -> dict[str, Any]:
    """``tomllib.loads`` whose every failure (syntax, a 5000-digit integer, 10^4 nested brackets) is one
    :class:`InvalidInput` naming ``field`` and ``value``."""
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        reason = str(exc).splitlines()[0] if str(exc) else "syntax error"
        raise InvalidInput(field, value, f"valid TOML ({shorten(reason)})") from None
    except RecursionError:
        raise InvalidInput(field, value, "valid TOML (arrays and tables nested too deeply)") from None
    except ValueError as exc:  # int() past 4300 digits raises a plain ValueError inside tomllib
        raise InvalidInput(field, value, f"valid TOML ({shorten(str(exc), 60)})") from None


_NPZ_ARRAYS: dict[str, tuple[np.dtype, int, int]] = {
    "solid": (np.dtype(np.bool_), 2, MAX_CELLS), "material": (np.dtype(np.uint8), 2, MAX_CELLS),
    "rooms": (np.dtype(np.int16), 2, MAX_CELLS), "meta": (np.dtype(np.uint8), 1, MAX_META_BYTES),
}
_NPZ_EXPECTED = "arrays solid bool, material uint8 and meta uint8 bytes"


def _npz_arrays(data: bytes, source: str) -> dict[str, np.ndarray]:
    """The map arrays of ``.npz`` bytes; every header is checked (dtype, rank, size) before its data is
    read, so a small file that declares a huge array (a zip bomb) is refused without inflating it."""
    try:
        zf = zipfile.ZipFile(io.BytesIO(data))
    except Exception as exc:  # BadZipFile, truncated central directory, bad offsets...
        raise _bad(source, f"a swarm map .npz (unreadable: {type(exc).__name__})") from None
    with zf:
        members: dict[str, str] = {}
        for name in zf.namelist():
            members.setdefault(name[:-4] if name.endswith(".npy") else name, name)
        missing = {"solid", "material", "meta"} - set(members)
        if missing:
            raise _bad(source, f"a swarm map .npz (missing arrays: {', '.join(sorted(missing))})")
        out: dict[str, np.ndarray] = {}
        for key, (dtype, ndim, limit) in _NPZ_ARRAYS.items():
            if key not in members:
                continue
            try:
                with zf.open(members[key]) as f:
                    version = np.lib.format.read_magic(f)
                    if version == (1, 0):
                        shape, _, found = np.lib.format.read_array_header_1_0(f)
                    elif version in ((2, 0), (3, 0)):  # 3.0 only differs in the header's text encoding
                        shape, _, found = np.lib.format.read_array_header_2_0(f)
                    else:
                        raise ValueError("npy version")
                ok_shape = isinstance(shape, tuple) and all(isinstance(n, int) and n >= 0 for n in shape)
                if found != dtype or not ok_shape or len(shape) != ndim:
                    what = "a rooms array of int16" if key == "rooms" else _NPZ_EXPECTED
                    if key == "solid" and found == dtype and ok_shape:
                        what = f"a 2-D raster of at most {MAX_CELLS} cells"
                    raise _bad(source, what)
                if math.prod(shape) > limit:
                    raise _bad(source, f"a 2-D raster of at most {MAX_CELLS} cells" if ndim == 2
                               else f"metadata of at most {MAX_META_BYTES // 2**20} MiB")
                with zf.open(members[key]) as f:
                    out[key] = np.lib.format.read_array(f, allow_pickle=False)
            except InvalidInput:
                raise
            except Exception as exc:  # npy header, compression, CRC, truncation, encryption...
                raise _bad(source, f"a swarm map .npz (unreadable: {type(exc).__name__})") from None
    return out


def map_from_bytes(data: bytes, source: str = "<bytes>") -> Map:
    """Parse ``.npz`` bytes written by :func:`map_to_bytes`."""
    arrays = _npz_arrays(data, source)
    solid, material, meta_raw, rooms = arrays["solid"], arrays["material"], arrays["meta"], arrays.get("rooms")
    try:
        meta = json.loads(meta_raw.tobytes().decode("utf-8"))
    except (UnicodeDecodeError, ValueError, RecursionError):  # ValueError: also ints past 4300 digits
        raise _bad(source, "JSON metadata in the meta array") from None
    if not isinstance(meta, dict) or meta.get("format") != FORMAT:
        raise _bad(source, f"metadata with format {FORMAT!r}")
    if meta.get("version") != VERSION:
        raise _bad(source, f"format version {VERSION} (file has {short_repr(meta.get('version'))}; upgrade swarm?)")
    try:
        materials = meta["materials"]
        if not isinstance(materials, list):
            raise TypeError("materials is not a list")
        seed = meta["seed"]
        if isinstance(seed, bool):
            raise TypeError("seed is a boolean")
        graph = graph_from_json(meta.get("graph"))
        params = meta.get("params", {})
        if not isinstance(params, dict):
            raise TypeError("params")
        return Map(solid=solid, material=material, materials=tuple(materials), kind=meta["kind"], seed=seed,
                   params=params, rooms=rooms, graph=graph)
    except InvalidInput as exc:
        raise _bad(source, f"a consistent map ({shorten(str(exc), 160)})") from None
    except (KeyError, TypeError, ValueError, AttributeError, OverflowError, IndexError) as exc:
        raise _bad(source, f"complete metadata ({type(exc).__name__}: {shorten(str(exc), 120)})") from None


def load_npz(path: str | Path) -> Map:
    return map_from_bytes(read_file_bytes(path, "map file"), str(path))


# ---------------------------------------------------------------------------------- importers ----
def _finish_import(solid: np.ndarray, material: np.ndarray, materials: tuple[str, ...], cells_per_pixel: int,
                   border: int, border_material: str, source: str, params: Mapping[str, Any]) -> Map:
    _check_final_size(solid.shape, cells_per_pixel, border, source)
    if cells_per_pixel > 1:
        solid = np.repeat(np.repeat(solid, cells_per_pixel, 0), cells_per_pixel, 1)
        material = np.repeat(np.repeat(material, cells_per_pixel, 0), cells_per_pixel, 1)
    if border:
        if border_material not in materials:
            materials = (*materials, border_material)
        pad = border * CELLS_PER_TILE
        solid = np.pad(solid, pad, constant_values=True)
        material = np.pad(material, pad, constant_values=materials.index(border_material))
    try:
        return Map(solid=solid, material=material, materials=materials, kind="custom", seed=None,
                   params={"source": Path(source).name, **params})
    except InvalidInput as exc:
        if exc.field == "solid" and "edge" in str(exc.value):
            raise _bad(source, "a map whose outer edge is solid (or pass border >= 1 to add a wall border)") from None
        if exc.field == "solid" and exc.value == "no free cell":
            raise _bad(source, "a map with free space (it is all wall)") from None
        raise


def _check_final_size(shape: tuple[int, ...], cells_per_pixel: int, border: int, source: str) -> None:
    """Refuse, before any upscaling allocates it, an import whose map would exceed ``MAX_CELLS``."""
    pad = 2 * border * CELLS_PER_TILE
    rows, cols = shape[0] * cells_per_pixel + pad, shape[1] * cells_per_pixel + pad
    if rows * cols > MAX_CELLS:
        raise _bad(source, f"a map of at most {MAX_CELLS} cells (this one would have {cols} x {rows})")


def _check_border(border: Any, border_material: Any) -> None:
    if not isinstance(border, int) or isinstance(border, bool) or not 0 <= border <= 10:
        raise InvalidInput("border", border, "an integer number of tiles in 0..10")
    check_known_material(border_material, "border_material")


def import_csv(path: str | Path, material: str = "concrete", border: int = 0,
               border_material: str = "concrete") -> Map:
    """The xBOA paper's 0/1 grids: 1 = wall, one value per 1 m cell, row index is y (row 0 at the bottom)."""
    check_known_material(material)
    _check_border(border, border_material)
    path = Path(path)
    data = read_file_bytes(path, "map file", MAX_TEXT_FILE_BYTES)
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        raise _bad(path, "a readable UTF-8 CSV (UnicodeDecodeError)") from None
    del data
    rows = [line.strip() for line in text.splitlines() if line.strip()]
    del text
    if not rows:
        raise _bad(path, "a CSV of 0/1 values (file is empty)")
    if (sum(r.count(",") for r in rows) + len(rows)) * 4 > MAX_CELLS:  # before a list of every value
        raise _bad(path, "a smaller grid")
    grid = []
    for i, line in enumerate(rows):
        values = [v.strip() for v in line.split(",")]
        bad = [v for v in values if v not in ("0", "1")]
        if bad:
            raise _bad(path, f"only 0 (free) and 1 (wall) values (line {i + 1} has {short_repr(bad[0], 40)})")
        grid.append([v == "1" for v in values])
    if len({len(r) for r in grid}) != 1:
        raise _bad(path, "rows of equal length")
    if len(grid) * len(grid[0]) * 4 > MAX_CELLS:
        raise _bad(path, "a smaller grid")
    solid = np.array(grid, dtype=bool)
    table = (AIR, material)
    return _finish_import(solid, solid.astype(np.uint8), table, CELLS_PER_TILE, border, border_material,
                          str(path), {"format": "xboa-csv", "material": material, "border": border})


def _pgm_number(token: bytes, name: str, source: str, lo: int, hi: int) -> int:
    if not (token.isdigit() and len(token) <= 10) or not lo <= int(token) <= hi:
        raise _bad(source, f"a PGM header 'P2 width height maxval' with {name} an integer in {lo}..{hi} "
                           f"(found {short_repr(token.decode('latin-1'), 30)})")
    return int(token)


def _read_pgm_values(data: bytes, source: str) -> np.ndarray:
    """Parse an ASCII P2 PGM (any whitespace, ``#`` comments) into a (rows, cols) int array, top row first.

    The header is checked before the pixels are parsed, so a header of 10^9 x 10^9 costs nothing; pixel
    values must be integers in ``0..maxval`` and ``maxval`` at most 65535 (the PGM format's limits).
    """
    body = _PGM_COMMENT_RE.sub(b"", data)  # a comment runs from '#' to the end of its line
    del data
    head = body.split(None, 4)
    if not head or head[0] != b"P2":
        hint = " (binary P5 PGMs import as images: pass --legend)" if head and head[0] == b"P5" else ""
        raise _bad(source, f"an ASCII PGM starting with 'P2'{hint}")
    if len(head) < 4:
        raise _bad(source, "a PGM header 'P2 width height maxval' followed by integer pixels")
    limit = MAX_CELLS // 4
    if not all(t.isdigit() for t in head[1:4]):
        raise _bad(source, "a PGM header 'P2 width height maxval' followed by integer pixels "
                           f"(found {short_repr(b' '.join(head[1:4]).decode('latin-1'), 40)})")
    w = _pgm_number(head[1], "width", source, 1, limit)
    h = _pgm_number(head[2], "height", source, 1, limit)
    if w * h > limit:
        raise _bad(source, f"a positive PGM size of at most {limit} pixels (width and height {w} x {h})")
    maxval = _pgm_number(head[3], "maxval", source, 1, PGM_MAX_MAXVAL)
    tokens = head[4].split(None, w * h) if len(head) > 4 else []
    if len(tokens) != w * h:
        found = "more" if len(tokens) > w * h else str(len(tokens))
        raise _bad(source, f"{w * h} pixel values for {w} x {h} (found {found})")
    if not (b"".join(tokens).isdigit() and max(map(len, tokens)) <= 10):  # a sign, a letter, 10^22...
        i = next(i for i, t in enumerate(tokens) if not (t.isdigit() and len(t) <= 10))
        raise _bad(source, f"integer pixel values in 0..{maxval} "
                           f"(pixel {i} is {short_repr(tokens[i].decode('latin-1'), 30)})")
    values = np.array([int(t) for t in tokens], dtype=np.int64)
    if values.max(initial=0) > maxval:
        i = int(np.argmax(values > maxval))
        raise _bad(source, f"integer pixel values in 0..{maxval} (pixel {i} is {int(values[i])})")
    return values.reshape(h, w)


def import_pgm(path: str | Path, material: str = "concrete", threshold: int = 125, border: int = 0,
               border_material: str = "concrete") -> Map:
    """MAES's ASCII PGM maps: one pixel per 1 m tile, value < ``threshold`` is wall, top row is north.

    MAES gives these walls a generic material with 0 dB attenuation; we default to ``concrete`` because a
    wall that does not attenuate is not physical. Pass ``material="wall"`` (0 dB in the radio library) for
    MAES parity.
    """
    check_known_material(material)
    _check_border(border, border_material)
    if not isinstance(threshold, int) or isinstance(threshold, bool):
        raise InvalidInput("threshold", threshold, "an integer pixel value")
    path = Path(path)
    values = _read_pgm_values(read_file_bytes(path, "map file", MAX_TEXT_FILE_BYTES), str(path))
    solid = (values < min(max(threshold, 0), PGM_MAX_MAXVAL + 1))[::-1]  # pixels are 0..65535: same test
    return _finish_import(solid, solid.astype(np.uint8), (AIR, material), CELLS_PER_TILE, border,
                          border_material, str(path),
                          {"format": "maes-pgm", "material": material, "threshold": threshold, "border": border})


# --------------------------------------------------------------------------------- image+legend ----
def decode_image(path: Path, field: str, check_size: Callable[[int, int], None],
                 mode_of: Callable[[Any], str]) -> np.ndarray:
    """The pixels of an image file Pillow reads, converted to the Pillow mode ``mode_of(image)`` chooses.

    The size is checked from the header before any pixel is decoded: at most ``MAX_CELLS`` pixels, then
    ``check_size(rows, cols)`` (the caller's bound on the map it will build). Any decoding failure is one
    :class:`InvalidInput` naming ``field``; shared by the legend and the ROS map_server importers.
    """
    from PIL import Image

    data = read_file_bytes(path, field)
    try:
        with Image.open(io.BytesIO(data)) as im:
            if im.width * im.height > MAX_CELLS:
                raise InvalidInput(field, str(path), f"an image of at most {MAX_CELLS} pixels")
            check_size(im.height, im.width)
            return np.asarray(im.convert(mode_of(im)))
    except InvalidInput:
        raise
    except Exception as exc:  # Pillow raises OSError, SyntaxError, ValueError, struct.error, zlib.error...
        raise InvalidInput(field, str(path), f"an image Pillow can read ({type(exc).__name__})") from None


def _parse_colour(text: Any, field: str) -> tuple[int, int, int]:
    if isinstance(text, str) and _COLOUR_RE.fullmatch(text):
        return int(text[1:3], 16), int(text[3:5], 16), int(text[5:7], 16)
    raise InvalidInput(field, text, "a colour written '#rrggbb' (six hex digits)")


def load_legend(path: str | Path) -> dict[str, Any]:
    """Read a legend TOML: ``metres_per_pixel``, ``tolerance``, ``materials`` and a ``[colours]`` table
    colour -> material.

    Example::

        metres_per_pixel = 0.5      # a multiple of 0.5; 1.0 means one pixel per tile
        tolerance = 0               # max per-channel difference to match a legend colour
        materials = ["plaster"]     # optional: names beyond the built-in ones (define them in [radio.materials])
        [colours]
        "#ffffff" = "free"          # "free" or "air" is open space
        "#000000" = "concrete"
        "#a0522d" = "brick"
        "#e0d0c0" = "plaster"
    """
    data = read_file_bytes(path, "legend", MAX_LEGEND_BYTES)
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        raise InvalidInput("legend", str(path), "a UTF-8 TOML file") from None
    return check_legend(parse_toml(text, "legend", str(path)))


def check_legend(raw: Mapping[str, Any]) -> dict[str, Any]:
    """Validate a legend table (see :func:`load_legend`); colours become ``(r, g, b)`` keys."""
    if not isinstance(raw, Mapping):
        raise InvalidInput("legend", raw, "a table with metres_per_pixel, tolerance, materials and colours")
    allowed = {"metres_per_pixel", "tolerance", "colours", "materials"}
    for key in raw:
        if key not in allowed:
            raise InvalidInput(field_name("legend", key), raw[key], f"one of {', '.join(sorted(allowed))}")
    mpp = raw.get("metres_per_pixel", CELL_M)
    if (not isinstance(mpp, (int, float)) or isinstance(mpp, bool) or not 0 < mpp <= 32
            or abs(mpp / CELL_M - round(mpp / CELL_M)) > 1e-9):
        raise InvalidInput("legend.metres_per_pixel", mpp, "a positive multiple of 0.5 up to 32")
    tol = raw.get("tolerance", 0)
    if not isinstance(tol, int) or isinstance(tol, bool) or not 0 <= tol <= 255:
        raise InvalidInput("legend.tolerance", tol, "an integer in 0..255")
    declared = _declared_materials(raw.get("materials", []))
    colours = raw.get("colours")
    if not isinstance(colours, Mapping) or not colours:
        raise InvalidInput("legend.colours", colours, "a table of '#rrggbb' = material (or 'free')")
    if len(colours) > MAX_LEGEND_COLOURS:
        raise InvalidInput("legend.colours", f"{len(colours)} colours", f"at most {MAX_LEGEND_COLOURS} colours")
    parsed: dict[tuple[int, int, int], str] = {}
    first_key: dict[tuple[int, int, int], str] = {}
    for key, name in colours.items():
        field = field_name("legend.colours", key)
        rgb = _parse_colour(key, field)
        if not (isinstance(name, str) and name in FREE_NAMES):
            try:
                check_known_material(name, field, declared)
            except InvalidInput as exc:
                hint = "" if declared else " (or a name the legend declares in materials = [...])"
                raise InvalidInput(field, name, f"'free' or {exc.allowed}{hint}") from None
        name = AIR if name in FREE_NAMES else name
        if rgb in parsed and parsed[rgb] != name:
            raise InvalidInput(field, name, f"each colour once (it is also {short_repr(first_key[rgb], 12)} = "
                                            f"{short_repr(parsed[rgb], 40)})")
        parsed[rgb] = name
        first_key.setdefault(rgb, key)
    if AIR not in parsed.values():
        raise InvalidInput("legend.colours", dict(colours), "at least one colour mapped to 'free'")
    return {"metres_per_pixel": float(mpp), "tolerance": tol, "colours": parsed, "materials": declared}


def _declared_materials(value: Any) -> tuple[str, ...]:
    """The legend's ``materials`` list: extra wall material names it may map colours to."""
    if not isinstance(value, list) or len(value) > 254:
        raise InvalidInput("legend.materials", value, "a list of at most 254 material names")
    for i, name in enumerate(value):
        check_material_name(name, f"legend.materials[{i}]")
        if name in FREE_NAMES:
            raise InvalidInput(f"legend.materials[{i}]", name, "a wall material (free space needs no declaring)")
    return tuple(value)


def _match_colours(rgb: np.ndarray, keys: np.ndarray, tolerance: int, source: Path) -> np.ndarray:
    """Index of the nearest legend colour (max channel difference) of every pixel, a few rows at a time so
    the (pixels, colours, channels) difference never takes more than a few MiB; a pixel farther than
    ``tolerance`` from every colour is an error naming the first one (row-major)."""
    h, w = rgb.shape[:2]
    best = np.empty((h, w), dtype=np.intp)
    step = max(1, _MATCH_CHUNK_ELEMENTS // max(1, w * len(keys) * 3))
    for r0 in range(0, h, step):
        diff = np.abs(rgb[r0:r0 + step, :, None, :] - keys[None, None, :, :]).max(axis=3)   # (rows, w, k)
        best[r0:r0 + step] = diff.argmin(axis=2)
        unmatched = diff.min(axis=2) > tolerance
        if unmatched.any():
            y, x = np.argwhere(unmatched)[0]
            y = int(y) + r0
            r, g, b = (int(v) for v in rgb[y, x])
            raise _bad(source, f"only legend colours (pixel x={x}, y={y} from the top-left is #{r:02x}{g:02x}{b:02x})")
    return best


def import_image(path: str | Path, legend: Mapping[str, Any], border: int = 0,
                 border_material: str = "concrete") -> Map:
    """A PNG (or any image Pillow reads, PGM included) whose colours the legend maps to materials.

    The top image row is the top (north) of the map.
    """
    _check_border(border, border_material)
    if not isinstance(legend, Mapping) or any(isinstance(k, str) for k in legend.get("colours") or {"": 0}):
        legend = check_legend(legend if isinstance(legend, Mapping) else {})  # raw TOML form: validate it
    path = Path(path)
    k = int(round(legend["metres_per_pixel"] / CELL_M))
    rgb = decode_image(path, "map file", lambda rows, cols: _check_final_size((rows, cols), k, border, str(path)),
                       lambda im: "RGB").astype(np.int16)
    colours = legend["colours"]
    keys = np.array(list(colours), dtype=np.int16)                # (k, 3)
    names = list(colours.values())
    best = _match_colours(rgb, keys, legend["tolerance"], path)
    table = (AIR, *[n for n in DEFAULT_TABLE[1:] if n in names], *sorted(set(names) - set(DEFAULT_TABLE)))
    lut = np.array([table.index(n) for n in names], dtype=np.uint8)
    material = lut[best][::-1]
    solid = material != 0
    return _finish_import(solid, material, table, k, border, border_material, str(path),
                          {"format": "image", "metres_per_pixel": legend["metres_per_pixel"], "border": border})


# --------------------------------------------------------------------------------- ROS map_server ----
def import_ros(path: str | Path, material: str = "concrete", border: int = 0,
               border_material: str = "concrete", scale: float = 1.0) -> Map:
    """A ROS map_server YAML and its image as a swarm map (the rules: :mod:`maps.ros`).

    Walls get ``material``: a map_server image has occupancy, not materials. A ``border`` (tiles) moves the
    lower-left corner, and the recorded origin with it. ``scale`` multiplies the map's metres (its resolution
    and origin): maps drawn for small robots (Explore-Bench's 1.4 m doors, which resample to 1 m gaps) let
    swarm's default robot through at 1.5.
    """
    import dataclasses

    check_known_material(material)
    _check_border(border, border_material)
    scale = houseexpo.check_scale(scale)
    path = Path(path)
    info = ros.parse_ros_yaml(read_file_bytes(path, "map file", ros.MAX_YAML_BYTES), path)
    if scale != 1.0:
        info = dataclasses.replace(info, resolution=info.resolution * scale,
                                   origin=(info.origin[0] * scale, info.origin[1] * scale, info.origin[2]))
    field = ros.field_in("image", path)

    def check_size(rows: int, cols: int) -> None:
        cells = (ros.cell_count(rows, info.resolution), ros.cell_count(cols, info.resolution))
        _check_final_size(cells, 1, border, str(path))

    pixels = decode_image(info.image, field, check_size, ros.pillow_mode(info.image, field))
    free = ros.pixel_classes(pixels, info)[::-1] == ros.FREE  # image rows run top-down, map rows bottom-up
    solid = ~ros.resample_free(free, info.resolution)
    shift = border * CELLS_PER_TILE * CELL_M
    origin = [info.origin[0] - shift, info.origin[1] - shift, 0.0]
    return _finish_import(solid, solid.astype(np.uint8), (AIR, material), 1, border, border_material, str(path),
                          {"format": ros.FORMAT, "image": info.image.name, "resolution": info.resolution,
                           "mode": info.mode, "origin": origin, "material": material, "border": border,
                           **({"scale": scale} if scale != 1.0 else {})})


# ------------------------------------------------------------------------------------- HouseExpo ----
def import_houseexpo(path: str | Path, material: str = "concrete", border: int = 0,
                     border_material: str = "concrete", scale: float = 1.0) -> Map:
    """A HouseExpo JSON floor plan as a swarm map (the rules: :mod:`maps.houseexpo`); walls get ``material``,
    coordinates are multiplied by ``scale``."""
    check_known_material(material)
    _check_border(border, border_material)
    scale = houseexpo.check_scale(scale)
    path = Path(path)
    plan = houseexpo.parse_plan(read_file_bytes(path, "map file", houseexpo.MAX_BYTES), str(path), scale)
    solid, params = houseexpo.rasterise(plan)
    shift = border * CELLS_PER_TILE * CELL_M
    params["origin"] = [params["origin"][0] - shift, params["origin"][1] - shift]
    return _finish_import(solid, solid.astype(np.uint8), (AIR, material), 1, border, border_material, str(path),
                          {**params, "material": material, "border": border})


def save_ros(m: Map, yaml_path: str | Path) -> tuple[Path, Path]:
    """Write ``m`` as ROS map_server files, as map_saver writes a trinary map: ``yaml_path`` and the image next
    to it (same name, ``.pgm``). Both or neither: if the YAML cannot be written, the new image is removed."""
    yaml_path = Path(yaml_path)
    image_path = ros.ros_image_path(yaml_path)
    text = ros.yaml_text(m, image_path.name)
    atomic_write_bytes(image_path, ros.pgm_bytes(m))
    try:
        atomic_write_bytes(yaml_path, text.encode())
    except BaseException:
        image_path.unlink(missing_ok=True)
        raise
    return yaml_path, image_path


def load_map(path: str | Path, legend: str | Path | None = None, **options: Any) -> Map:
    """Open any supported map file by its suffix: ``.npz``, ``.csv``, ``.yaml``/``.yml`` (ROS map_server),
    ``.json`` (HouseExpo), ``.pgm`` (ASCII P2, or an image with a legend), or an image with a legend."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix == ".npz":
        return load_npz(path)
    if "scale" in options and suffix not in (".json", ".yaml", ".yml"):
        raise InvalidInput("scale", options["scale"], "only for HouseExpo .json plans and ROS .yaml maps")
    if suffix == ".json":
        if legend is not None:
            raise InvalidInput("legend", str(legend), "no legend for a HouseExpo .json plan (walls take the "
                                                      "material option)")
        return import_houseexpo(path, **options)
    if suffix == ".csv":
        return import_csv(path, **options)
    if suffix in (".yaml", ".yml"):
        if legend is not None:
            raise InvalidInput("legend", str(legend), "no legend for a ROS map YAML (its thresholds decide free "
                                                      "and wall; walls take the material option)")
        return import_ros(path, **options)
    if suffix == ".pgm" and legend is None:
        return import_pgm(path, **options)
    if legend is None:
        raise InvalidInput("legend", None, f"a legend TOML to import {shorten(path.name)} (colours -> materials)")
    return import_image(path, load_legend(legend), **options)
