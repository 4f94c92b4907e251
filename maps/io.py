"""Map files: the lossless ``.npz`` format, and importers for images with a legend, MAES PGM and xBOA CSV.

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
import os
import tempfile
import tomllib
import zipfile
from pathlib import Path
from collections.abc import Mapping
from typing import Any

import numpy as np

from .errors import InvalidInput
from .materials import AIR, DEFAULT_TABLE, check_material_name
from .model import CELL_M, CELLS_PER_TILE, Map, graph_from_json, graph_to_json

FORMAT = "swarm-map"
VERSION = 1
FREE_NAMES = ("free", AIR)
MAX_CELLS = 4000 * 4000
_FIXED_ZIP_TIME = (1980, 1, 1, 0, 0, 0)


# ------------------------------------------------------------------------------------ writing ----
def atomic_write_bytes(path: Path, data: bytes) -> Path:
    """Write ``data`` to ``path`` via a temporary file in the same folder and an atomic rename."""
    path = Path(path)
    folder = path.parent if str(path.parent) else Path(".")
    if not folder.is_dir():
        raise InvalidInput("output", str(path), "a path in an existing folder")
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=folder)
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


def map_from_bytes(data: bytes, source: str = "<bytes>") -> Map:
    """Parse ``.npz`` bytes written by :func:`map_to_bytes`."""
    try:
        with np.load(io.BytesIO(data), allow_pickle=False) as z:
            names = set(z.files)
            missing = {"solid", "material", "meta"} - names
            if missing:
                raise _bad(source, f"a swarm map .npz (missing arrays: {', '.join(sorted(missing))})")
            solid, material, meta_raw = z["solid"], z["material"], z["meta"]
            rooms = z["rooms"] if "rooms" in names else None
    except InvalidInput:
        raise
    except Exception as exc:  # zip, npy header, compression and pickle errors all mean "not our file"
        raise _bad(source, f"a swarm map .npz (unreadable: {type(exc).__name__})") from None
    if solid.dtype != np.bool_ or material.dtype != np.uint8 or meta_raw.dtype != np.uint8 or meta_raw.ndim != 1:
        raise _bad(source, "arrays solid bool, material uint8 and meta uint8 bytes")
    if rooms is not None and rooms.dtype != np.int16:
        raise _bad(source, "a rooms array of int16")
    if solid.ndim != 2 or solid.size > MAX_CELLS:
        raise _bad(source, f"a 2-D raster of at most {MAX_CELLS} cells")
    try:
        meta = json.loads(meta_raw.tobytes().decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError):
        raise _bad(source, "JSON metadata in the meta array") from None
    if not isinstance(meta, dict) or meta.get("format") != FORMAT:
        raise _bad(source, f"metadata with format {FORMAT!r}")
    if meta.get("version") != VERSION:
        raise _bad(source, f"format version {VERSION} (file has {meta.get('version')!r}; upgrade swarm?)")
    try:
        materials = tuple(meta["materials"])
        graph = graph_from_json(meta.get("graph"))
        params = meta.get("params", {})
        if not isinstance(params, dict):
            raise TypeError("params")
        return Map(solid=solid, material=material, materials=materials, kind=meta["kind"], seed=meta["seed"],
                   params=params, rooms=rooms, graph=graph)
    except InvalidInput as exc:
        raise _bad(source, f"a consistent map ({exc})") from None
    except (KeyError, TypeError, ValueError) as exc:
        raise _bad(source, f"complete metadata ({type(exc).__name__}: {exc})") from None


def load_npz(path: str | Path) -> Map:
    path = Path(path)
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise _bad(path, f"a readable file ({exc.strerror})") from None
    return map_from_bytes(data, str(path))


# ---------------------------------------------------------------------------------- importers ----
def _finish_import(solid: np.ndarray, material: np.ndarray, materials: tuple[str, ...], cells_per_pixel: int,
                   border: int, border_material: str, source: str, params: Mapping[str, Any]) -> Map:
    if cells_per_pixel > 1:
        solid = np.repeat(np.repeat(solid, cells_per_pixel, 0), cells_per_pixel, 1)
        material = np.repeat(np.repeat(material, cells_per_pixel, 0), cells_per_pixel, 1)
    if border:
        if border_material not in materials:
            materials = (*materials, border_material)
        pad = border * CELLS_PER_TILE
        solid = np.pad(solid, pad, constant_values=True)
        material = np.pad(material, pad, constant_values=materials.index(border_material))
    if solid.size > MAX_CELLS:
        raise _bad(source, f"a map of at most {MAX_CELLS} cells")
    try:
        return Map(solid=solid, material=material, materials=materials, kind="custom", seed=None,
                   params={"source": Path(source).name, **params})
    except InvalidInput as exc:
        if exc.field == "solid" and "edge" in str(exc.value):
            raise _bad(source, "a map whose outer edge is solid (or pass border >= 1 to add a wall border)") from None
        raise


def _check_border(border: Any, border_material: Any) -> None:
    if not isinstance(border, int) or isinstance(border, bool) or not 0 <= border <= 10:
        raise InvalidInput("border", border, "an integer number of tiles in 0..10")
    check_material_name(border_material, "border_material")


def import_csv(path: str | Path, material: str = "concrete", border: int = 0,
               border_material: str = "concrete") -> Map:
    """The xBOA paper's 0/1 grids: 1 = wall, one value per 1 m cell, row index is y (row 0 at the bottom)."""
    check_material_name(material)
    _check_border(border, border_material)
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise _bad(path, f"a readable UTF-8 CSV ({type(exc).__name__})") from None
    rows = [line.strip() for line in text.splitlines() if line.strip()]
    if not rows:
        raise _bad(path, "a CSV of 0/1 values (file is empty)")
    grid = []
    for i, line in enumerate(rows):
        values = [v.strip() for v in line.split(",")]
        bad = [v for v in values if v not in ("0", "1")]
        if bad:
            raise _bad(path, f"only 0 (free) and 1 (wall) values (line {i + 1} has {bad[0]!r})")
        grid.append([v == "1" for v in values])
    if len({len(r) for r in grid}) != 1:
        raise _bad(path, "rows of equal length")
    if len(grid) * len(grid[0]) * 4 > MAX_CELLS:
        raise _bad(path, "a smaller grid")
    solid = np.array(grid, dtype=bool)
    table = (AIR, material)
    return _finish_import(solid, solid.astype(np.uint8), table, CELLS_PER_TILE, border, border_material,
                          str(path), {"format": "xboa-csv", "material": material, "border": border})


def _read_pgm_values(data: bytes, source: str) -> np.ndarray:
    """Parse an ASCII P2 PGM (any whitespace, ``#`` comments) into a (rows, cols) int array, top row first."""
    tokens: list[bytes] = []
    for line in data.splitlines():
        tokens.extend(line.split(b"#", 1)[0].split())
    if not tokens or tokens[0] != b"P2":
        raise _bad(source, "an ASCII PGM starting with 'P2'")
    try:
        w, h, maxval = (int(t) for t in tokens[1:4])
        values = np.array([int(t) for t in tokens[4:]], dtype=np.int64)
    except ValueError:
        raise _bad(source, "a PGM header 'P2 width height maxval' followed by integer pixels") from None
    if w <= 0 or h <= 0 or maxval <= 0 or w * h * 4 > MAX_CELLS:
        raise _bad(source, f"a positive PGM size of at most {MAX_CELLS // 4} pixels")
    if values.size != w * h:
        raise _bad(source, f"{w * h} pixel values for {w} x {h} (found {values.size})")
    return values.reshape(h, w)


def import_pgm(path: str | Path, material: str = "concrete", threshold: int = 125, border: int = 0,
               border_material: str = "concrete") -> Map:
    """MAES's ASCII PGM maps: one pixel per 1 m tile, value < ``threshold`` is wall, top row is north.

    MAES gives these walls a generic material with 0 dB attenuation; we default to ``concrete`` because a
    wall that does not attenuate is not physical. Pass ``material="wall"`` (0 dB in the radio library) for
    MAES parity.
    """
    check_material_name(material)
    _check_border(border, border_material)
    if not isinstance(threshold, int) or isinstance(threshold, bool):
        raise InvalidInput("threshold", threshold, "an integer pixel value")
    path = Path(path)
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise _bad(path, f"a readable file ({exc.strerror})") from None
    values = _read_pgm_values(data, str(path))
    solid = (values < threshold)[::-1]
    return _finish_import(solid, solid.astype(np.uint8), (AIR, material), CELLS_PER_TILE, border,
                          border_material, str(path),
                          {"format": "maes-pgm", "material": material, "threshold": threshold, "border": border})


# --------------------------------------------------------------------------------- image+legend ----
def _parse_colour(text: Any, field: str) -> tuple[int, int, int]:
    if isinstance(text, str) and len(text) == 7 and text.startswith("#"):
        try:
            return int(text[1:3], 16), int(text[3:5], 16), int(text[5:7], 16)
        except ValueError:
            pass
    raise InvalidInput(field, text, "a colour written '#rrggbb'")


def load_legend(path: str | Path) -> dict[str, Any]:
    """Read a legend TOML: ``metres_per_pixel``, ``tolerance``, and a ``[colours]`` table colour -> material.

    Example::

        metres_per_pixel = 0.5      # a multiple of 0.5; 1.0 means one pixel per tile
        tolerance = 0               # max per-channel difference to match a legend colour
        [colours]
        "#ffffff" = "free"          # "free" or "air" is open space
        "#000000" = "concrete"
        "#a0522d" = "brick"
    """
    path = Path(path)
    try:
        raw = tomllib.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise InvalidInput("legend", str(path), f"a readable TOML file ({exc.strerror})") from None
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise InvalidInput("legend", str(path), f"valid TOML ({str(exc).splitlines()[0]})") from None
    return check_legend(raw)


def check_legend(raw: Mapping[str, Any]) -> dict[str, Any]:
    allowed = {"metres_per_pixel", "tolerance", "colours"}
    for key in raw:
        if key not in allowed:
            raise InvalidInput(f"legend.{key}", raw[key], f"one of {', '.join(sorted(allowed))}")
    mpp = raw.get("metres_per_pixel", CELL_M)
    if (not isinstance(mpp, (int, float)) or isinstance(mpp, bool) or not 0 < mpp <= 32
            or abs(mpp / CELL_M - round(mpp / CELL_M)) > 1e-9):
        raise InvalidInput("legend.metres_per_pixel", mpp, "a positive multiple of 0.5 up to 32")
    tol = raw.get("tolerance", 0)
    if not isinstance(tol, int) or isinstance(tol, bool) or not 0 <= tol <= 255:
        raise InvalidInput("legend.tolerance", tol, "an integer in 0..255")
    colours = raw.get("colours")
    if not isinstance(colours, Mapping) or not colours:
        raise InvalidInput("legend.colours", colours, "a table of '#rrggbb' = material (or 'free')")
    parsed: dict[tuple[int, int, int], str] = {}
    for key, name in colours.items():
        rgb = _parse_colour(key, f"legend.colours.{key}")
        if name not in FREE_NAMES:
            check_material_name(name, f"legend.colours.{key}")
        parsed[rgb] = AIR if name in FREE_NAMES else name
    if AIR not in parsed.values():
        raise InvalidInput("legend.colours", dict(colours), "at least one colour mapped to 'free'")
    return {"metres_per_pixel": float(mpp), "tolerance": tol, "colours": parsed}


def import_image(path: str | Path, legend: Mapping[str, Any], border: int = 0,
                 border_material: str = "concrete") -> Map:
    """A PNG (or any image Pillow reads, PGM included) whose colours the legend maps to materials.

    The top image row is the top (north) of the map.
    """
    from PIL import Image, UnidentifiedImageError

    _check_border(border, border_material)
    if not isinstance(legend, Mapping) or any(isinstance(k, str) for k in legend.get("colours") or {"": 0}):
        legend = check_legend(legend if isinstance(legend, Mapping) else {})  # raw TOML form: validate it
    path = Path(path)
    try:
        with Image.open(path) as im:
            if im.width * im.height > MAX_CELLS:
                raise _bad(path, f"an image of at most {MAX_CELLS} pixels")
            rgb = np.asarray(im.convert("RGB"), dtype=np.int16)
    except InvalidInput:
        raise
    except (OSError, UnidentifiedImageError, ValueError, Image.DecompressionBombError) as exc:
        raise _bad(path, f"an image Pillow can read ({type(exc).__name__})") from None
    colours = legend["colours"]
    keys = np.array(list(colours), dtype=np.int16)                # (k, 3)
    names = list(colours.values())
    diff = np.abs(rgb[:, :, None, :] - keys[None, None, :, :]).max(axis=3)   # (h, w, k)
    best = diff.argmin(axis=2)
    unmatched = diff.min(axis=2) > legend["tolerance"]
    if unmatched.any():
        y, x = np.argwhere(unmatched)[0]
        r, g, b = (int(v) for v in rgb[y, x])
        raise _bad(path, f"only legend colours (pixel x={x}, y={y} from the top-left is #{r:02x}{g:02x}{b:02x})")
    table = (AIR, *[n for n in DEFAULT_TABLE[1:] if n in names], *sorted(set(names) - set(DEFAULT_TABLE)))
    lut = np.array([table.index(n) for n in names], dtype=np.uint8)
    material = lut[best][::-1]
    solid = material != 0
    k = int(round(legend["metres_per_pixel"] / CELL_M))
    return _finish_import(solid, material, table, k, border, border_material, str(path),
                          {"format": "image", "metres_per_pixel": legend["metres_per_pixel"], "border": border})


def load_map(path: str | Path, legend: str | Path | None = None, **options: Any) -> Map:
    """Open any supported map file by its suffix: ``.npz``, ``.csv``, ``.pgm`` (ASCII P2, or an image with a
    legend), or an image with a legend."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix == ".npz":
        return load_npz(path)
    if suffix == ".csv":
        return import_csv(path, **options)
    if suffix == ".pgm" and legend is None:
        return import_pgm(path, **options)
    if legend is None:
        raise InvalidInput("legend", None, f"a legend TOML to import {path.name} (colours -> materials)")
    return import_image(path, load_legend(legend), **options)
