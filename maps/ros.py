"""ROS map_server map files: a YAML of metadata that names an occupancy image (PGM or PNG).

This is the format of ROS 1 map_server, nav2_map_server and map_saver, and of Explore-Bench's maps.

Reading follows ``loadMapYaml`` and ``loadMapFromFile`` of nav2_map_server's ``src/map_io.cpp`` on the
Humble branch, which keep the rules of ROS 1 map_server (``image_loader.cpp``, wiki.ros.org/map_server):

* ``image`` is absolute or relative to the YAML's folder; ``resolution``, ``origin`` (x, y, yaw),
  ``negate``, ``occupied_thresh`` and ``free_thresh`` are required; ``mode`` (trinary, scale or raw, in any
  letter case) defaults to trinary; other keys are ignored.
* x is the mean of a pixel's colour channels (in trinary mode the alpha channel is averaged in too, a
  map_server quirk); p = (255 - x) / 255, or x / 255 with ``negate``. A pixel is occupied if
  p > occupied_thresh, free if p < free_thresh, else unknown.
* scale: as trinary, but a pixel that is not opaque is unknown, and the in-between pixels (published as
  graded occupancy) are not free. raw: v = round(x) is the occupancy in percent if it is in 0..100, else
  unknown; swarm thresholds v / 100 like p above (map_server itself publishes v).

nav2 from Jazzy on (the Eigen rewrite) differs only for pixels exactly at a threshold (>=, <=), for colour
weighting and for alpha in trinary mode; map_saver's own files (pixels 0, 205, 254 with 0.65 / 0.196)
read the same under every version.

A swarm map is free or solid: free pixels are free, occupied and unknown pixels are solid (robots never
leave the mapped area, and never cross space nobody has seen). The image is resampled to swarm's 0.5 m
cells: a cell is free only if every pixel it overlaps is free and it lies inside the image, so a wall one
pixel thick is never lost. The map's lower-left corner is the image's, so swarm's (0, 0) is ``origin``
(x, y) in the ROS map frame; the import records it in the map's params and an export writes it back.

The files are read and written by :func:`maps.io.import_ros` and :func:`maps.io.save_ros`; this module holds
the format's rules.
"""

from __future__ import annotations

import math
import re
import reprlib
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from swarm.base.errors import InvalidInput, shorten
from .model import CELL_M, Map

FORMAT = "ros-map"
"""``params["format"]`` of a map imported from a map_server YAML."""
MODES = ("trinary", "scale", "raw")
MAX_YAML_BYTES = 2**20
MIN_RESOLUTION, MAX_RESOLUTION = 0.001, 1000.0
"""Metres per pixel: from 1 mm (a 16-Mpx image is then 8 m wide) to 1 km; ROS maps use about 0.01 to 1."""
RESOLUTION_ALLOWED = f"a number from {MIN_RESOLUTION:g} to {MAX_RESOLUTION:g} (metres per pixel)"
FREE, OCCUPIED, UNKNOWN = 0, 1, 2
"""The class of a pixel, as map_server publishes it (0, 100, -1 in an OccupancyGrid)."""
SAVER_FREE, SAVER_OCCUPIED = 254, 0
"""The pixels map_saver writes in trinary mode for free and occupied cells (205 is unknown; a swarm map has
no unknown cell)."""
SAVER_OCCUPIED_THRESH, SAVER_FREE_THRESH = 0.65, 0.196
"""The thresholds map_saver writes with those pixels."""
_EDGE_TOLERANCE = 1e-6
"""A cell edge this close (in pixels) to a pixel edge is on it: rounding in ``k * 0.5 / resolution`` must not
add a pixel to a cell."""
_DECIMAL_RE = re.compile(r"[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?")
_SHOW = reprlib.Repr()
_SHOW.maxlevel, _SHOW.maxlist, _SHOW.maxdict, _SHOW.maxstring, _SHOW.maxother, _SHOW.maxlong = 3, 6, 6, 60, 60, 40
_EIGHT_BIT_MODES = ("1", "L", "LA", "La", "P", "PA", "RGB", "RGBA", "RGBa", "RGBX", "CMYK", "YCbCr", "LAB", "HSV")


@dataclass(frozen=True)
class RosMapYaml:
    """The checked fields of a map_server YAML."""

    image: Path
    resolution: float
    origin: tuple[float, float, float]
    negate: bool
    occupied_thresh: float
    free_thresh: float
    mode: str


def field_in(key: str, path: Path) -> str:
    """How an error names a key of the YAML at ``path``: ``resolution in loop.yaml``."""
    return f"{key} in {path.name}"


class _Shown:
    """A YAML value in an error message, by a bounded repr: aliases let a tiny file hold a value whose full
    repr has billions of characters."""

    def __init__(self, value: Any) -> None:
        self.text = _SHOW.repr(value)

    def __repr__(self) -> str:
        return self.text


def _bad(key: str, path: Path, value: Any, allowed: str) -> InvalidInput:
    return InvalidInput(field_in(key, path), _Shown(value), allowed)


def _number(value: Any, key: str, path: Path, allowed: str) -> float:
    """A finite number; a decimal string counts, as yaml-cpp reads one (PyYAML leaves ``1e-1`` a string)."""
    number = math.nan
    if isinstance(value, str) and _DECIMAL_RE.fullmatch(value.strip()):
        number = float(value)
    elif isinstance(value, (int, float)) and not isinstance(value, bool):
        try:
            number = float(value)
        except OverflowError:  # an integer beyond any float
            pass
    if not math.isfinite(number):
        raise _bad(key, path, value, allowed)
    return number


def parse_ros_yaml(data: bytes, path: Path) -> RosMapYaml:
    """Check the bytes of the map_server YAML at ``path``; anything missing or out of range is one
    :class:`InvalidInput` naming the key and the file."""
    import yaml

    try:
        doc = yaml.safe_load(data.decode("utf-8"))
    except UnicodeDecodeError:
        raise InvalidInput("map file", str(path), "a UTF-8 YAML file") from None
    except yaml.YAMLError as exc:
        reason = str(getattr(exc, "problem", None) or type(exc).__name__)
        raise InvalidInput("map file", str(path), f"valid YAML ({reason})") from None
    except RecursionError:
        raise InvalidInput("map file", str(path), "valid YAML (nested too deeply)") from None
    except ValueError as exc:  # int() past 4300 digits raises a plain ValueError inside PyYAML
        raise InvalidInput("map file", str(path), f"valid YAML ({shorten(str(exc), 60)})") from None
    if not isinstance(doc, dict):
        raise InvalidInput(path.name, _Shown(doc), "a YAML mapping with the map_server keys image, resolution, "
                                                   "origin, negate, occupied_thresh, free_thresh and optionally mode")
    image = doc.get("image")
    if not isinstance(image, str) or not image:
        raise _bad("image", path, image, "the path of the map's PGM or PNG image, absolute or relative to the YAML")
    resolution = _number(doc.get("resolution"), "resolution", path, RESOLUTION_ALLOWED)
    if not MIN_RESOLUTION <= resolution <= MAX_RESOLUTION:
        raise _bad("resolution", path, doc["resolution"], RESOLUTION_ALLOWED)
    origin = doc.get("origin")
    if not isinstance(origin, list) or len(origin) != 3:
        raise _bad("origin", path, origin, "[x, y, yaw]: the pose of the lower-left pixel")
    x, y, yaw = (_number(v, "origin", path, "[x, y, yaw] of finite numbers") for v in origin)
    if yaw != 0:
        raise _bad("origin", path, origin, "yaw 0: swarm maps are axis-aligned (rotate the image and set yaw to 0)")
    negate = doc.get("negate")
    if negate not in (0, 1) or isinstance(negate, float):  # True == 1 and False == 0
        raise _bad("negate", path, negate, "0, 1, true or false")
    occupied = _number(doc.get("occupied_thresh"), "occupied_thresh", path, "a number in 0..1")
    free = _number(doc.get("free_thresh"), "free_thresh", path, "a number in 0..1")
    for key, value in (("occupied_thresh", occupied), ("free_thresh", free)):
        if not 0 <= value <= 1:
            raise _bad(key, path, doc[key], "a number in 0..1")
    if free >= occupied:
        raise _bad("free_thresh", path, doc["free_thresh"], f"a number below occupied_thresh ({occupied:g})")
    mode = doc.get("mode", "trinary")
    if not isinstance(mode, str) or mode.lower() not in MODES:
        raise _bad("mode", path, mode, " | ".join(MODES))
    image_path = Path(image) if Path(image).is_absolute() else path.parent / image
    return RosMapYaml(image_path, resolution, (x, y, 0.0), bool(negate), occupied, free, mode.lower())


def pillow_mode(path: Path, field: str) -> Callable[[Any], str]:
    """The Pillow mode an image is read in: L, RGB or RGBA (when it has transparency), as map_server sees it."""
    def choose(im: Any) -> str:
        if im.mode not in _EIGHT_BIT_MODES:
            raise InvalidInput(field, str(path), f"an 8-bit greyscale or colour image (this one is {im.mode})")
        if im.mode in ("LA", "La", "PA", "RGBA", "RGBa") or "transparency" in im.info:
            return "RGBA"
        return "L" if im.mode in ("1", "L") else "RGB"
    return choose


def pixel_classes(pixels: np.ndarray, info: RosMapYaml) -> np.ndarray:
    """FREE, OCCUPIED or UNKNOWN for every pixel of an L (rows, cols), RGB or RGBA (rows, cols, n) image."""
    channels = pixels if pixels.ndim == 3 else pixels[..., None]
    alpha = channels[..., 3] if channels.shape[2] == 4 else None
    averaged = channels if (alpha is not None and info.mode == "trinary") else channels[..., :3]
    n = averaged.shape[2]
    mean = np.arange(255 * n + 1) / n  # the mean x of every possible channel sum: a lookup table
    if info.mode == "raw":
        percent = np.floor(mean + 0.5)  # std::round(shade * 255)
        known = percent <= 100
        p = np.where(known, percent / 100, 0.0)
    else:
        known = np.ones(mean.shape, dtype=bool)
        p = mean / 255 if info.negate else (255 - mean) / 255
    table = np.full(mean.shape, UNKNOWN, dtype=np.uint8)
    table[known & (p > info.occupied_thresh)] = OCCUPIED
    table[known & (p < info.free_thresh)] = FREE
    classes = table[averaged.sum(axis=2, dtype=np.uint16)]
    if alpha is not None and info.mode == "scale":
        classes[alpha < 255] = UNKNOWN
    return classes


def cell_count(pixels: int, resolution: float) -> int:
    """Swarm cells along an image side of ``pixels`` pixels: the last cell may reach past the image."""
    return max(1, math.ceil((pixels - _EDGE_TOLERANCE) * resolution / CELL_M))


def _any_per_cell(blocked: np.ndarray, axis: int, resolution: float) -> np.ndarray:
    """Along ``axis``: True for each swarm cell that overlaps a True pixel or reaches past the image."""
    pixels = blocked.shape[axis]
    cells = cell_count(pixels, resolution)
    edges = np.arange(cells + 1) * (CELL_M / resolution)  # cell edges in pixels
    first = np.minimum(np.floor(edges[:-1] + _EDGE_TOLERANCE).astype(np.int64), pixels)
    end = np.ceil(edges[1:] - _EDGE_TOLERANCE).astype(np.int64)
    counts = np.cumsum(blocked, axis=axis, dtype=np.int32)
    counts = np.concatenate([np.zeros_like(np.take(counts, [0], axis=axis)), counts], axis=axis)
    out = (np.take(counts, np.minimum(end, pixels), axis=axis) - np.take(counts, first, axis=axis)) > 0
    shape = [1, 1]
    shape[axis] = cells
    return out | (end > pixels).reshape(shape)


def resample_free(free: np.ndarray, resolution: float) -> np.ndarray:
    """Swarm's free raster from a raster of free pixels of ``resolution`` metres (both with row 0 at the
    bottom and the same lower-left corner): a 0.5 m cell is free only if every pixel it overlaps is free."""
    blocked = _any_per_cell(~free, 1, resolution)
    return ~_any_per_cell(blocked, 0, resolution)


def ros_origin(m: Map) -> tuple[float, float]:
    """Where swarm's (0, 0) lies in the ROS map frame: the origin a ROS import recorded, else (0, 0)."""
    origin = m.params.get("origin") if m.params.get("format") == FORMAT else None
    if (isinstance(origin, list) and len(origin) == 3
            and all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in origin)):
        return float(origin[0]), float(origin[1])
    if origin is not None:
        raise InvalidInput("params.origin", origin, "[x, y, 0] of finite numbers (from a ROS map import)")
    return 0.0, 0.0


def pgm_bytes(m: Map) -> bytes:
    """A binary PGM of the map as map_saver writes one in trinary mode: one pixel per cell, top row first."""
    pixels = np.where(m.solid[::-1], SAVER_OCCUPIED, SAVER_FREE).astype(np.uint8)
    rows, cols = m.shape
    header = f"P5\n# CREATOR: swarm map export {CELL_M:.3f} m/pix\n{cols} {rows}\n255\n".encode()
    return header + pixels.tobytes()


def yaml_text(m: Map, image_name: str) -> str:
    """The map_server YAML naming ``image_name``, with the keys in map_saver's order."""
    import yaml

    x, y = ros_origin(m)
    doc = {"image": image_name, "mode": "trinary", "resolution": CELL_M, "origin": [x, y, 0.0], "negate": 0,
           "occupied_thresh": SAVER_OCCUPIED_THRESH, "free_thresh": SAVER_FREE_THRESH}
    return yaml.safe_dump(doc, sort_keys=False, default_flow_style=None)


def ros_image_path(yaml_path: Path) -> Path:
    """The image an export writes next to ``yaml_path`` (same name, ``.pgm``); the YAML must end in .yaml/.yml."""
    if yaml_path.suffix.lower() not in (".yaml", ".yml"):
        raise InvalidInput("output", str(yaml_path), "a .yaml or .yml path (the .pgm image goes next to it)")
    return yaml_path.with_suffix(".pgm")
