"""ROS 2 messages for swarm runs: rosbags' type store for Jazzy, builders for the message types our topics
use, CDR serialisation, and each type's ``.msg`` definition (MCAP schemas) and RIHS01 hash (rmw_zenoh).

Every message, schema and hash comes from one :func:`typestore`, so an MCAP file and a live publisher
speak exactly the same types. Builders take plain numbers (metres, radians, nanoseconds of sim time) and
return rosbags message objects; :func:`serialize` turns one into CDR bytes. Needs the ``ros`` extra.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from functools import lru_cache
from typing import Any

import numpy as np

CLOCK = "rosgraph_msgs/msg/Clock"
FLOAT64 = "std_msgs/msg/Float64"
LASER_SCAN = "sensor_msgs/msg/LaserScan"
MARKER_ARRAY = "visualization_msgs/msg/MarkerArray"
OCCUPANCY_GRID = "nav_msgs/msg/OccupancyGrid"
POSE_STAMPED = "geometry_msgs/msg/PoseStamped"
TF_MESSAGE = "tf2_msgs/msg/TFMessage"

LINE_STRIP, LINE_LIST, TRIANGLE_LIST = 4, 5, 11
"""visualization_msgs/Marker types we draw with."""
ADD, DELETE = 0, 2
"""visualization_msgs/Marker actions."""

_NO_BYTES = np.zeros(0, dtype=np.uint8)
_NO_FLOATS = np.zeros(0, dtype=np.float32)


@lru_cache(maxsize=1)
def typestore() -> Any:
    """rosbags' type store of ROS 2 Jazzy (every message type our topics use is in it)."""
    from rosbags.typesys import Stores, get_typestore

    return get_typestore(Stores.ROS2_JAZZY)


def _t(name: str) -> Any:
    return typestore().types[name]


def serialize(message: Any) -> bytes:
    """``message`` as CDR bytes (little-endian, with the encapsulation header), as ROS 2 sends it."""
    return bytes(typestore().serialize_cdr(message, message.__msgtype__))


def definition(typename: str) -> str:
    """The ``ros2msg`` text of ``typename`` with every type it uses appended, as rosbag2 writes MCAP schemas."""
    return typestore().generate_msgdef(typename, ros_version=2)[0]


def type_hash(typename: str) -> str:
    """The type's ``RIHS01_...`` hash (ROS 2 Iron and later: rosbag2 metadata, rmw_zenoh key expressions)."""
    return typestore().hash_rihs01(typename)


# ----------------------------------------------------------------------------------------- pieces ----
def time(ns: int) -> Any:
    sec, nanosec = divmod(int(ns), 1_000_000_000)
    return _t("builtin_interfaces/msg/Time")(sec=sec, nanosec=nanosec)


def duration(ns: int) -> Any:
    sec, nanosec = divmod(int(ns), 1_000_000_000)
    return _t("builtin_interfaces/msg/Duration")(sec=sec, nanosec=nanosec)


def header(frame: str, ns: int) -> Any:
    return _t("std_msgs/msg/Header")(stamp=time(ns), frame_id=frame)


def point(x: float, y: float, z: float = 0.0) -> Any:
    return _t("geometry_msgs/msg/Point")(x=float(x), y=float(y), z=float(z))


def yaw(theta: float) -> Any:
    """The quaternion of a rotation by ``theta`` about z."""
    half = 0.5 * float(theta)
    return _t("geometry_msgs/msg/Quaternion")(x=0.0, y=0.0, z=math.sin(half), w=math.cos(half))


def pose(x: float, y: float, theta: float = 0.0) -> Any:
    return _t("geometry_msgs/msg/Pose")(position=point(x, y), orientation=yaw(theta))


def colour(rgb: Sequence[int], alpha: float = 1.0) -> Any:
    """A ``std_msgs/ColorRGBA`` from 0-255 channels and an opacity."""
    return _t("std_msgs/msg/ColorRGBA")(r=rgb[0] / 255.0, g=rgb[1] / 255.0, b=rgb[2] / 255.0, a=float(alpha))


# ---------------------------------------------------------------------------------------- messages ----
def clock(ns: int) -> Any:
    return _t(CLOCK)(clock=time(ns))


def float64(value: float) -> Any:
    return _t(FLOAT64)(data=float(value))


def occupancy_grid(frame: str, ns: int, cells: np.ndarray, resolution: float) -> Any:
    """A grid whose cell (row, col) covers x in [col, col + 1) * resolution and y in [row, row + 1) *
    resolution of ``frame`` (row 0 at y = 0, as ROS stores rows); ``cells`` int8 [H, W]: -1 unknown, 0-100
    occupancy."""
    h, w = cells.shape
    info = _t("nav_msgs/msg/MapMetaData")(map_load_time=time(ns), resolution=float(resolution), width=w, height=h,
                                          origin=pose(0.0, 0.0))
    return _t(OCCUPANCY_GRID)(header=header(frame, ns), info=info,
                              data=np.ascontiguousarray(cells, dtype=np.int8).reshape(-1))


def laser_scan(frame: str, ns: int, ranges: np.ndarray, angle_min: float, angle_increment: float,
               range_max: float, scan_time: float) -> Any:
    """A scan of ``len(ranges)`` rays at ``angle_min + k * angle_increment`` from ``frame``'s x axis; ``inf``
    is no return within ``range_max`` (REP 117)."""
    r = np.ascontiguousarray(ranges, dtype=np.float32)
    return _t(LASER_SCAN)(header=header(frame, ns), angle_min=float(angle_min),
                          angle_max=float(angle_min + angle_increment * (len(r) - 1)),
                          angle_increment=float(angle_increment), time_increment=0.0, scan_time=float(scan_time),
                          range_min=0.0, range_max=float(range_max), ranges=r, intensities=_NO_FLOATS)


def pose_stamped(frame: str, ns: int, x: float, y: float, theta: float = 0.0) -> Any:
    return _t(POSE_STAMPED)(header=header(frame, ns), pose=pose(x, y, theta))


def tf_message(ns: int, parent: str, children: Iterable[tuple[str, float, float, float]]) -> Any:
    """One transform ``parent -> child`` per ``(child, x, y, theta)``, all stamped ``ns``."""
    vector, stamped, transform = (_t("geometry_msgs/msg/Vector3"), _t("geometry_msgs/msg/TransformStamped"),
                                  _t("geometry_msgs/msg/Transform"))
    return _t(TF_MESSAGE)(transforms=[
        stamped(header=header(parent, ns), child_frame_id=child,
                transform=transform(translation=vector(x=float(x), y=float(y), z=0.0), rotation=yaw(theta)))
        for child, x, y, theta in children])


def marker(frame: str, ns: int, space: str, ident: int, kind: int, points: Sequence[tuple[float, float]] = (),
           colours: Sequence[Any] = (), rgb: Sequence[int] = (0, 0, 0), alpha: float = 1.0, width: float = 0.05,
           z: float = 0.0, lifetime_ns: int = 0, action: int = ADD) -> Any:
    """A ``visualization_msgs/Marker`` ``(space, ident)`` of ``points`` (x, y) at height ``z``: lines of
    ``width`` m in one colour, or one colour per point (``colours``); ``lifetime_ns`` 0 lasts until replaced."""
    m = _t("visualization_msgs/msg/Marker")
    return m(header=header(frame, ns), ns=space, id=int(ident), type=kind, action=action, pose=pose(0.0, 0.0),
             scale=_t("geometry_msgs/msg/Vector3")(x=float(width), y=float(width), z=float(width)),
             color=colour(rgb, alpha), lifetime=duration(lifetime_ns), frame_locked=False,
             points=[point(x, y, z) for x, y in points], colors=list(colours), texture_resource="",
             texture=_t("sensor_msgs/msg/CompressedImage")(header=header("", 0), format="", data=_NO_BYTES),
             uv_coordinates=[], text="", mesh_resource="",
             mesh_file=_t("visualization_msgs/msg/MeshFile")(filename="", data=_NO_BYTES),
             mesh_use_embedded_materials=False)


def marker_array(markers: Sequence[Any]) -> Any:
    return _t(MARKER_ARRAY)(markers=list(markers))


__all__ = ["ADD", "CLOCK", "DELETE", "FLOAT64", "LASER_SCAN", "LINE_LIST", "LINE_STRIP", "MARKER_ARRAY",
           "OCCUPANCY_GRID", "POSE_STAMPED", "TF_MESSAGE", "TRIANGLE_LIST", "clock", "colour", "definition",
           "float64", "laser_scan", "marker", "marker_array", "occupancy_grid", "pose_stamped", "serialize",
           "tf_message", "type_hash", "typestore"]
