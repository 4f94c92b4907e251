"""Typed, versioned messages and their compact wire format (msgpack).

Every message is a frozen dataclass registered under a type name with :func:`message`. On the wire a
message is the msgpack array ``[type, version, sender, field values in declaration order]``; numpy
arrays travel as ``[dtype, shape, bytes]``. Size on the wire is a metric, so encoding is compact:
field names are not sent, map updates are delta-encoded and zlib-compressed.

Built-ins: :class:`MapUpdate` (cells changed since the sender's last update, or the full map, with the
sender's pose), :class:`MapRequest` (ask a robot for its full map after a gap in its sequence numbers)
and :class:`Heartbeat`. Algorithms declare their own::

    @message("tnf.destination")
    @dataclass(frozen=True)
    class Destination:
        sender: int
        x: float
        y: float

Decoding never trusts its input: anything malformed raises :class:`MessageError` (the runtime drops the
message and counts it).
"""

from __future__ import annotations

import dataclasses
import math
import zlib
from typing import Any, Callable, TypeVar

import msgpack
import numpy as np

from swarm.base.types import frozen_builder
from swarm.knowledge import cellcodec as _cellcodec

T = TypeVar("T")

MAX_MESSAGE_BYTES = 4 * 1024 * 1024
MAX_MESSAGES_PER_TICK = 64
"""What one robot's algorithm (or remote agent) may send in one tick: at most this many messages, together
at most :data:`MAX_BYTES_PER_TICK` bytes encoded (one message of the largest size). The rest of its outbox
is dropped and counted as malformed (issue 48: one agent's 170,000 heartbeats in a tick failed or stalled
the other robots). The runtime's own map sharing is not counted."""
MAX_BYTES_PER_TICK = MAX_MESSAGE_BYTES
MAP_ZLIB_LEVEL = 6
"""zlib level of MapUpdate payloads by default (a run sets its own: ``comm.map_zlib_level``). Part of the
results: it sets the bytes counted and what a bandwidth cap lets through (level 1 was measured on one full
300 x 300 benchmark map: 25 against 118 us, 647 against 414 bytes; docs/radio.md has a swarm's)."""
KEEP_PLAIN_BYTES = 1 << 19
"""The largest full map (in plain bytes, 2 bits a cell: 2 million cells, a 700-tile map) whose plain bytes an
update built here keeps for its receivers here; a larger one is decompressed by each message's receivers
(a few milliseconds a megabyte), the same bytes either way."""
_REGISTRY: dict[str, type] = {}
_NAMES: dict[type, str] = {}
_FIELDS: dict[type, tuple[str, ...]] = {}  # field names in declaration order: encode reads them per message


class MessageError(ValueError):
    """A message that cannot be decoded or is not a registered message type."""


def message(type_name: str, version: int = 1) -> Callable[[type[T]], type[T]]:
    """Class decorator: register a frozen dataclass as a message type. The first field must be ``sender``.

    ``type_name`` must be unique across every package (prefix it with yours); ``version`` is sent with
    every message, and a message of another version fails to decode. Raises ``TypeError`` at import for a
    non-dataclass, a first field that is not ``sender`` or a name taken by another class. Returns the
    class itself, with ``message_type`` and ``message_version`` set."""

    def register(cls: type[T]) -> type[T]:
        if not dataclasses.is_dataclass(cls):
            raise TypeError(f"{cls.__name__}: messages must be dataclasses")
        names = [f.name for f in dataclasses.fields(cls)]
        if not names or names[0] != "sender":
            raise TypeError(f"{cls.__name__}: the first field of a message must be 'sender'")
        existing = _REGISTRY.get(type_name)
        if existing is not None and existing.__qualname__ != cls.__qualname__:
            raise TypeError(f"message type {type_name!r} is already registered by {existing.__qualname__}")
        cls.message_type = type_name  # type: ignore[attr-defined]
        cls.message_version = version  # type: ignore[attr-defined]
        _REGISTRY[type_name] = cls
        _NAMES[cls] = type_name
        _FIELDS[cls] = tuple(names)
        return cls

    return register


def registered() -> dict[str, type]:
    """Every registered message type: a new dict of type name to class (changing it registers nothing)."""
    return dict(_REGISTRY)


# ------------------------------------------------------------------------------------ encoding ----
def _default(obj: Any) -> Any:
    if isinstance(obj, np.ndarray):
        return msgpack.ExtType(1, msgpack.packb([obj.dtype.str, list(obj.shape), obj.tobytes()]))
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, tuple):
        return list(obj)
    raise TypeError(f"cannot encode {type(obj).__name__}")


def _ext_hook(code: int, data: bytes) -> Any:
    if code != 1:
        raise MessageError(f"unknown extension type {code}")
    dtype, shape, raw = msgpack.unpackb(data, raw=False)
    arr = np.frombuffer(raw, dtype=np.dtype(dtype)).reshape(shape).copy()
    arr.flags.writeable = False  # one decoded message may be shared by several receivers
    return arr


def encode(msg: Any) -> bytes:
    """The wire bytes of a registered message: msgpack ``[type, version, sender, fields...]``; their length
    is what the radio's bandwidth counts. Raises :class:`MessageError` for an unregistered type. Cost:
    ~3 us for a three-number message (loaded 2-core machine)."""
    cls = type(msg)
    name = _NAMES.get(cls)
    if name is None:
        raise MessageError(f"{cls.__name__} is not a registered message type (use @message)")
    values = [getattr(msg, field) for field in _FIELDS[cls]]
    return msgpack.packb([name, cls.message_version, *values], default=_default, use_bin_type=True)


def decode(data: bytes) -> Any:
    """A message from wire bytes; raises :class:`MessageError` for anything malformed (not bytes, over
    ``MAX_MESSAGE_BYTES``, an unknown type or version, wrong field count, or its ``validate()`` refusing
    it). Fields annotated as tuples come back as tuples. Cost: ~4 us for a three-number message."""
    if not isinstance(data, (bytes, bytearray, memoryview)) or len(data) > MAX_MESSAGE_BYTES:
        raise MessageError("not bytes, or larger than MAX_MESSAGE_BYTES")
    try:
        items = msgpack.unpackb(data, raw=False, ext_hook=_ext_hook, strict_map_key=False,
                                max_bin_len=MAX_MESSAGE_BYTES, max_str_len=1 << 20)
    except MessageError:
        raise
    except Exception as exc:  # msgpack raises several unrelated types for corrupt input
        raise MessageError(f"undecodable: {type(exc).__name__}") from None
    if not isinstance(items, list) or len(items) < 3 or not isinstance(items[0], str):
        raise MessageError("not a [type, version, sender, ...] array")
    cls = _REGISTRY.get(items[0])
    if cls is None:
        raise MessageError(f"unknown message type {items[0]!r}")
    if items[1] != cls.message_version:  # type: ignore[attr-defined]
        raise MessageError(f"{items[0]} version {items[1]!r}, expected {cls.message_version}")  # type: ignore[attr-defined]
    tuples = _TUPLES.get(cls)
    if tuples is None:
        tuples = _TUPLES[cls] = tuple(_tuple_depth(f.type) for f in dataclasses.fields(cls))
    if len(items) - 2 != len(tuples):
        raise MessageError(f"{items[0]} needs {len(tuples)} fields, got {len(items) - 2}")
    values = items[2:]
    for k, depth in enumerate(tuples):
        if depth and type(values[k]) is list:
            values[k] = _as_tuple(values[k], depth)
    if not isinstance(values[0], int) or isinstance(values[0], bool):
        raise MessageError(f"{items[0]}: sender must be an integer")
    build = _BUILDERS.get(cls)
    try:
        msg = build(**dict(zip(_FIELDS[cls], values))) if build is not None else cls(*values)
    except Exception as exc:
        raise MessageError(f"{items[0]}: {type(exc).__name__}: {exc}") from None
    check = getattr(msg, "validate", None)
    if check is not None:
        try:
            check()
        except MessageError:
            raise
        except Exception as exc:  # a validator that trips over a value of the wrong type: still malformed
            raise MessageError(f"{items[0]}: invalid fields ({type(exc).__name__})") from None
    return msg


def _is_int(v: Any) -> bool:
    return isinstance(v, int) and not isinstance(v, bool)


def _finite(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def require_finite(type_name: str, **fields: Any) -> None:
    """For a message's ``validate``: raise :class:`MessageError` naming ``type_name`` and the fields unless
    every value is a finite int or float (a decoded message is untrusted: NaN, inf, bools and strings are
    refused). Cost: a type check per value."""
    if not all(_finite(v) for v in fields.values()):
        raise MessageError(f"{type_name}: {' and '.join(fields)} must be finite numbers")


_TUPLES: dict[type, tuple[int, ...]] = {}
"""Per message type, per field: how many levels of lists to turn back into tuples (2 for ``tuple[tuple...``,
1 for another ``tuple``, 0 otherwise), read off the annotations once per type, not per message."""


def _tuple_depth(annotation: Any) -> int:
    text = str(annotation)
    return 2 if "tuple[tuple" in text else 1 if "tuple" in text else 0


def _as_tuple(value: list, depth: int) -> tuple:
    """Lists come back for tuples; turn them back (``depth`` levels) so decoded messages equal the originals."""
    if depth == 1:
        return tuple(value)
    return tuple(tuple(v) if isinstance(v, list) else v for v in value)


# ------------------------------------------------------------------------------------ built-ins ----
@message("swarm.map_update", version=1)
@dataclasses.dataclass(frozen=True, eq=False)
class MapUpdate:
    """Knowledge-map cells from ``sender``: the cells changed since its previous update (``full=False``) or
    its whole map (``full=True``). ``seq`` numbers a sender's updates so receivers can detect gaps.

    ``payload`` is zlib-compressed: for a full map, the map's cells packed 4 per byte (2 bits each); for a
    delta, the gaps between successive changed flat indices (uint32) followed by the packed values.
    """

    sender: int
    seq: int
    tick: int
    full: bool
    shape: tuple[int, int]
    count: int
    payload: bytes
    pose: tuple[float, float, float]

    def validate(self) -> None:
        shape, pose = self.shape, self.pose  # unrolled: every robot decodes every update it hears
        if (not isinstance(shape, tuple) or len(shape) != 2 or not (_is_int(shape[0]) and 0 < shape[0] <= 100_000)
                or not (_is_int(shape[1]) and 0 < shape[1] <= 100_000)):
            raise MessageError("map_update: bad shape")
        if not (_is_int(self.seq) and self.seq >= 0 and _is_int(self.tick) and isinstance(self.full, bool)):
            raise MessageError("map_update: bad seq, tick or full flag")
        if not (isinstance(pose, tuple) and len(pose) == 3 and _finite(pose[0]) and _finite(pose[1])
                and _finite(pose[2])):
            raise MessageError("map_update: bad pose")
        if not isinstance(self.payload, bytes) or not isinstance(self.count, int) or self.count < 0:
            raise MessageError("map_update: bad payload")
        if self.count > self.shape[0] * self.shape[1]:
            raise MessageError("map_update: more cells than the map has")

    def cells(self) -> tuple[np.ndarray, np.ndarray]:
        """(flat indices, values) carried by this update, decoded once per message (a broadcast reaches
        many receivers); raises MessageError if corrupt."""
        cached = self.__dict__.get("_cells")
        if cached is None:
            cached = self._decode_cells()
            self.__dict__["_cells"] = cached
        return cached

    def dense(self) -> np.ndarray:
        """A full update's map as flat ``uint8[H * W]`` (read-only, decoded once): merging a whole map is
        one vectorised maximum, much cheaper than scattering its tens of thousands of known cells."""
        if not self.full:
            raise MessageError("map_update: dense() needs a full update")
        cached = self.__dict__.get("_dense")
        if cached is None:
            h, w = self.shape
            packed = np.frombuffer(self._raw(), dtype=np.uint8)
            if len(packed) != (h * w + 3) // 4:
                raise MessageError("map_update: wrong payload length")
            values = np.empty(h * w, dtype=np.uint8)
            if _cellcodec.unpack2(packed, h * w, values) > 2:
                raise MessageError("map_update: cell values outside 0..2")
            values.flags.writeable = False
            cached = self.__dict__["_dense"] = values
        return cached

    def known_cells(self) -> tuple[np.ndarray, np.ndarray]:
        """A full update's known cells: (ascending flat indices, values) of every cell that is not UNSEEN,
        decoded once per message from the packed bytes (read-only). All that merging it needs: only these
        can raise a receiver's cell."""
        if not self.full:
            raise MessageError("map_update: known_cells() needs a full update")
        cached = self.__dict__.get("_known")
        if cached is None:
            h, w = self.shape
            packed = np.frombuffer(self._raw(), dtype=np.uint8)
            if len(packed) != (h * w + 3) // 4:
                raise MessageError("map_update: wrong payload length")
            idx, values, top = _cellcodec.known2(packed, h * w)
            if top > 2:
                raise MessageError("map_update: cell values outside 0..2")
            idx.flags.writeable = False
            values.flags.writeable = False
            cached = self.__dict__["_known"] = (idx, values)
        return cached

    def values_at(self, cells: np.ndarray) -> np.ndarray:
        """A full update's values at ``cells`` (int64 flat indices inside its map), uint8, read off the packed
        bytes without decoding the rest (a receiver that needs only a few cells of it)."""
        if not self.full:
            raise MessageError("map_update: values_at() needs a full update")
        h, w = self.shape
        packed = np.frombuffer(self._raw(), dtype=np.uint8)
        if len(packed) != (h * w + 3) // 4:
            raise MessageError("map_update: wrong payload length")
        values = _cellcodec.values_at2(packed, np.ascontiguousarray(cells, dtype=np.int64))
        if len(values) and values.max() > 2:
            raise MessageError("map_update: cell values outside 0..2")
        return values

    def _raw(self) -> bytes:
        """The payload before zlib: kept by an update built in this process (:func:`full_update`,
        :func:`delta_update`), so its receivers here skip the decompression (lossless, so the same bytes);
        decompressed otherwise."""
        plain = self.__dict__.get("_plain")
        if plain is not None:
            return plain
        try:
            return zlib.decompress(self.payload, bufsize=max(64, 5 * self.count + 16))
        except zlib.error:
            raise MessageError("map_update: corrupt payload") from None

    def _decode_cells(self) -> tuple[np.ndarray, np.ndarray]:
        h, w = self.shape
        if self.full:
            values = self.dense()
            idx = np.flatnonzero(values)
            return idx, values[idx]
        raw = self._raw()
        n = self.count
        if len(raw) != 4 * n + (n + 3) // 4:
            raise MessageError("map_update: wrong payload length")
        idx = np.empty(n, dtype=np.int64)
        values = np.empty(n, dtype=np.uint8)
        status = _cellcodec.unpack_delta(np.frombuffer(raw, dtype=np.uint8), n, h * w, idx, values)
        if status == _cellcodec.DELTA_REPEATED:
            raise MessageError("map_update: repeated cells")
        if status != _cellcodec.DELTA_OK:
            raise MessageError("map_update: cells outside the map")
        return idx, values

    def merge_into(self, known: np.ndarray) -> np.ndarray:
        """Elementwise max of the carried cells into ``known`` (a map of the same shape); returns their
        flat indices."""
        if known.shape != self.shape:
            raise MessageError(f"map_update: shape {self.shape} does not match the receiver's {known.shape}")
        idx, values = self.cells()  # distinct indices (checked when decoded)
        flat = known.reshape(-1)
        flat[idx] = np.maximum(flat[idx], values)
        return idx


def gaps_u32(idx: np.ndarray) -> bytes:
    """Ascending flat indices as little-endian uint32 gaps (the first from 0), the delta encoding of map
    cells on the wire (``np.diff(idx, prepend=0)`` without its broadcasting overhead on small arrays)."""
    gaps = np.empty(len(idx), dtype="<u4")
    if len(idx):
        gaps[0] = idx[0]
        np.subtract(idx[1:], idx[:-1], out=gaps[1:], casting="unsafe")
    return gaps.tobytes()


def map_update(sender: int, seq: int, tick: int, known: np.ndarray, pose: tuple[float, float, float],
               changed: np.ndarray | None) -> MapUpdate:
    """Build a MapUpdate: ``changed`` = flat indices changed since the last update, or None for the full map."""
    pose = tuple(float(v) for v in pose)  # type: ignore[assignment]
    if changed is None:
        return full_update(sender, seq, tick, known, pose)
    return delta_update(sender, seq, tick, known, pose, np.sort(np.asarray(changed, dtype=np.int64)))


def full_update(sender: int, seq: int, tick: int, known: np.ndarray, pose: tuple[float, float, float],
                payloads: dict[tuple[int, int, int], tuple[np.ndarray, bytes | None, bytes, int]] | None = None,
                packed: np.ndarray | None = None, wire: Callable[[], np.ndarray] | None = None,
                shape: tuple[int, int] | None = None, level: int = MAP_ZLIB_LEVEL) -> MapUpdate:
    """The full-map MapUpdate of ``known`` (``pose``: three Python floats).

    ``payloads``: the full maps of one sharing tick so far (a fingerprint of the packed map -> (packed map,
    plain bytes or None, payload, count of known cells)). Robots whose maps have converged send
    byte-identical full maps in the same tick (a fifth to a quarter of the full maps of the paper's 16-robot
    runs under the materials radio, docs/performance-history.md; nearly all in a 1,000-robot crowd), and zlib
    gives the same bytes for the same input, so one compression (and one count) serves them all. A match is
    confirmed by comparing the packed maps, so the payload is always this map's. The plain bytes stay on the
    update (its receivers here skip zlib) only up to :data:`KEEP_PLAIN_BYTES`: a swarm asked for its full
    maps in one tick would otherwise hold a megabyte or more per robot until they are delivered (10,000
    robots on 2,000 tiles: 40 GB).
    ``packed``: ``known`` already packed 2 bits a cell (:func:`swarm.knowledge.packed.packed_copy`; the
    map-sharing service keeps it), unchanged while ``payloads`` is in use.
    ``wire``: for a map not stored row-major (:mod:`swarm.knowledge.tiles`; ``known`` and ``packed`` in its own
    order, ``shape`` its size): gives the row-major map packed when a payload has to be built; equal maps
    still share one, found and confirmed in their stored order. ``level``: zlib's (``comm.map_zlib_level``;
    one run uses one, so ``payloads`` never mixes them)."""
    if packed is None:
        packed = _cellcodec.pack2(known.reshape(-1))
    key = (*_cellcodec.fingerprint(packed), len(packed))
    shared = None if payloads is None else payloads.get(key)
    if shared is not None and not np.array_equal(shared[0], packed):
        shared, payloads = None, None  # a fingerprint collision: compress this one apart
    if shared is None:
        plain = packed.tobytes() if wire is None else wire().tobytes()
        shared = (packed, plain if len(plain) <= KEEP_PLAIN_BYTES else None, zlib.compress(plain, level),
                  int(np.count_nonzero(known)))
        if payloads is not None:
            payloads[key] = shared
    if shape is None:
        shape = (int(known.shape[0]), int(known.shape[1]))
    return _update_of(shared[1], shared[2], sender=sender, seq=seq, tick=tick, full=True,
                      shape=(int(shape[0]), int(shape[1])), count=shared[3], pose=pose)


def delta_update(sender: int, seq: int, tick: int, known: np.ndarray, pose: tuple[float, float, float],
                 changed: np.ndarray, *, values: np.ndarray | None = None,
                 shape: tuple[int, int] | None = None, level: int = MAP_ZLIB_LEVEL) -> MapUpdate:
    """The delta MapUpdate of cells ``changed`` of ``known``: distinct ascending int64 flat indices, as
    :func:`swarm.knowledge.maps.sync_changes` gives them, and ``pose`` three Python floats, so nothing is sorted
    or converted again (the map-sharing service builds one per robot per sharing tick). A map not stored
    row-major (:mod:`swarm.knowledge.tiles`) gives its ``values`` at ``changed`` and its ``shape``; ``level``:
    zlib's."""
    if values is None:
        values, shape = known.reshape(-1)[changed], known.shape
    assert shape is not None
    plain = _cellcodec.pack_delta(changed, np.ascontiguousarray(values, dtype=np.uint8)).tobytes()
    return _update_of(plain, zlib.compress(plain, level), sender=sender, seq=seq, tick=tick, full=False,
                      shape=(int(shape[0]), int(shape[1])), count=len(changed), pose=pose)


_new_update = frozen_builder(MapUpdate)
_BUILDERS: dict[type, Callable[..., Any]] = {MapUpdate: _new_update}
"""Message types :func:`decode` builds without their frozen ``__init__`` (see :func:`swarm.api.frozen_builder`):
the map updates every robot decodes every sharing tick, whose generated ``__init__`` only stores the fields."""


def _update_of(plain: bytes | None, payload: bytes, **fields: Any) -> MapUpdate:
    """A MapUpdate of ``payload`` (``plain`` compressed), keeping ``plain`` for receivers in this process
    (:meth:`MapUpdate._raw`; None: they decompress it)."""
    update = _new_update(payload=payload, **fields)
    if plain is not None:
        update.__dict__["_plain"] = plain
    return update


@message("swarm.map_request", version=1)
@dataclasses.dataclass(frozen=True)
class MapRequest:
    """Ask ``target`` for its full map (sent after missing one of its updates)."""

    sender: int
    target: int

    def validate(self) -> None:
        if not _is_int(self.target):
            raise MessageError("map_request: target must be an integer")


@message("swarm.heartbeat", version=1)
@dataclasses.dataclass(frozen=True)
class Heartbeat:
    """A robot's pose at ``tick``."""

    sender: int
    tick: int
    x: float
    y: float
    theta: float

    def validate(self) -> None:
        if not (_is_int(self.tick) and all(_finite(v) for v in (self.x, self.y, self.theta))):
            raise MessageError("heartbeat: tick must be an integer and x, y, theta finite numbers")
