"""The ``.swr`` container: a magic number, then CRC-checked, zlib-compressed msgpack chunks.

Why a home-made chunk stream rather than zip or HDF5: the browser viewer has to parse the very same bytes
(it embeds the file and decodes it in plain JavaScript), and a flat ``kind | length | crc | payload``
stream with zlib payloads is a few lines there (``DecompressionStream('deflate')`` is built in), while zip
needs a central-directory parser and HDF5 is out of reach. Every chunk carries a CRC-32, so a corrupt or
truncated file is reported as such instead of decoding garbage. The layout is documented in
``docs/recording-format.md``.

Arrays travel as ``[dtype, shuffled, bytes]`` triples (little-endian numpy dtype strings). ``shuffled``
means the bytes were transposed into planes (all first bytes, then all second bytes, ...), the trick
blosc uses: float64 poses and uint32 index gaps then compress 2-4x better with plain zlib.
"""

from __future__ import annotations

import struct
import zlib
from collections.abc import Iterator
from typing import Any

import msgpack
import numpy as np

from swarm.base.errors import InvalidInput

MAGIC = b"\x89SWR\r\n\x1a\n"
"""PNG-style: a high byte catches 7-bit transfers, CR LF and the EOF byte catch text-mode mangling."""
FORMAT_NAME = "swarm-recording"
FORMAT_VERSION = 3
"""Version 2 (issue 34) added the communication streams: failed deliveries, groups, map merges, contacts.
Version 3 (issue 47) stores the link toggles, RSSI updates and map merges as per-tick gaps (``link_gap``,
``rssi_gap``, ``aoi_gap`` instead of ``*_idx``) and shuffles ``msg_rssi``: a 1,000-robot run's sharing round
changes up to a million merge entries, which compress ~100x as gaps of 1 and only ~2x as indices."""
READABLE_VERSIONS = (1, 2, 3)
"""Versions this reader opens: a version 1 file simply has no communication streams."""
CHUNK_HEADER = struct.Struct("<4sII")  # kind, payload length, CRC-32 of the payload
HEAD, BLOCK, TAIL = b"HEAD", b"BLCK", b"TAIL"
MAX_CHUNK_BYTES = 1 << 30
"""No chunk's payload (compressed) may exceed 1 GiB: a corrupt length field must not allocate the world."""
MAX_RATIO = 200
"""Past :data:`RATIO_FLOOR`, a chunk may inflate to at most 200 times its size in the file. Real chunks
inflate 10-14x (a 256-tick block of 64 robots: 1.3 MB -> 13 MB; 61 ticks of 1,000 robots: 136 MB -> 1.9 GB);
zlib reaches ~1,030x, which is what a decompression bomb uses: 1 MiB asking for a gigabyte."""
RATIO_FLOOR = 64 << 20
"""A chunk may always inflate to 64 MiB, however well it compressed (small chunks of repetitive data do)."""
MAX_FILE_RATIO = 100
"""All chunks together may inflate to at most 100 times the file's size (or :data:`FILE_FLOOR`): many small
chunks each under :data:`RATIO_FLOOR` must not add up to a bomb either."""
FILE_FLOOR = 256 << 20
MAX_INFLATED_CHUNK = 16 << 30
"""Whatever its ratio, no chunk may inflate to more than 16 GiB (msgpack holds at most 4 GiB in one array)."""
MAX_INFLATED_TOTAL = 64 << 30
"""Whatever its ratio, no file may inflate to more than 64 GiB (the reader holds every stream in memory)."""
ITEMS_FLOOR = 1 << 20
"""Array elements plus map entries a chunk may always decode to (1 Mi); beyond, one per two bytes of the
chunk in the file. msgpack makes a Python object of ~60 bytes from one byte (an empty array), so the
inflated size alone does not bound memory. Real chunks: 0.001 items a compressed byte (a block holds 3 per
array field and one per changed action), a TAIL's per-robot lists 0.3."""
FILE_ITEMS_FLOOR = 1 << 22
"""Items the whole file may always decode to (4 Mi); beyond, one per two bytes of the file."""
INFLATE_STEP = 1 << 24
"""Bytes inflated per step (16 MiB): the limits are checked between steps, so an oversized chunk is refused
after at most this much more than the limit, whatever it claims to hold."""


def chunk_limits(compressed: int) -> tuple[int, int]:
    """(bytes, items) a chunk of ``compressed`` bytes in the file may inflate and decode to."""
    return (min(MAX_INFLATED_CHUNK, max(RATIO_FLOOR, MAX_RATIO * compressed)),
            max(ITEMS_FLOOR, compressed // 2))


def file_limits(size: int) -> tuple[int, int]:
    """(bytes, items) all chunks of a file of ``size`` bytes may inflate and decode to together."""
    return min(MAX_INFLATED_TOTAL, max(FILE_FLOOR, MAX_FILE_RATIO * size)), max(FILE_ITEMS_FLOOR, size // 2)

DTYPES = ("<f8", "<u4", "<u2", "<i2", "|u1")
"""The only array dtypes the format uses; the JavaScript reader knows exactly these."""


def bad(path: str, problem: str) -> InvalidInput:
    """The one error for an unusable recording: names the file and what is wrong with it."""
    versions = " or ".join(str(v) for v in READABLE_VERSIONS)
    return InvalidInput("recording", path, f"a complete swarm recording (.swr version {versions}); {problem}")


# ------------------------------------------------------------------------------------- arrays ----
def pack_array(values: np.ndarray, dtype: str, shuffle: bool = False) -> list[Any]:
    """``[dtype, shuffled, bytes]`` for ``values`` cast to ``dtype`` (one of :data:`DTYPES`)."""
    arr = np.ascontiguousarray(values, dtype=np.dtype(dtype))
    size = arr.dtype.itemsize
    if shuffle and size > 1 and arr.size:
        raw = arr.reshape(-1).view(np.uint8).reshape(-1, size).T.tobytes()
    else:
        raw = arr.tobytes()
        shuffle = False
    return [dtype, bool(shuffle), raw]


def unpack_array(item: Any, field: str, path: str) -> np.ndarray:
    """The numpy array of a ``[dtype, shuffled, bytes]`` triple; raises :func:`bad` when malformed."""
    if (not isinstance(item, list) or len(item) != 3 or item[0] not in DTYPES or not isinstance(item[1], bool)
            or not isinstance(item[2], bytes)):
        raise bad(path, f"field {field!r} is not a [dtype, shuffled, bytes] array")
    dtype = np.dtype(item[0])
    raw = item[2]
    if len(raw) % dtype.itemsize:
        raise bad(path, f"field {field!r} has {len(raw)} bytes, not a multiple of {dtype.itemsize}")
    n = len(raw) // dtype.itemsize
    if item[1] and n:
        planes = np.frombuffer(raw, dtype=np.uint8).reshape(dtype.itemsize, n)
        return np.ascontiguousarray(planes.T).view(dtype).reshape(-1)
    return np.frombuffer(raw, dtype=dtype).copy()


# ------------------------------------------------------------------------------------- chunks ----
def encode_chunk(kind: bytes, body: dict[str, Any], level: int = 6) -> bytes:
    """One chunk: header + zlib(msgpack(body))."""
    payload = zlib.compress(msgpack.packb(body, use_bin_type=True), level)
    return CHUNK_HEADER.pack(kind, len(payload), zlib.crc32(payload)) + payload


class Budget:
    """What a file's chunks have inflated and decoded to so far, against :func:`file_limits` (one per file:
    :func:`iter_chunks` makes it)."""

    def __init__(self, size: int) -> None:
        self.size = size
        self.max_inflated, self.max_items = file_limits(size)
        self.inflated = 0
        self.items = 0


def iter_chunks(data: bytes, path: str, budget: Budget | None = None) -> Iterator[tuple[bytes, dict[str, Any]]]:
    """Yield ``(kind, body)`` for every chunk after the magic; corrupt, truncated or oversized data raises
    before the oversized part is allocated (:func:`chunk_limits`, :func:`file_limits`: what a chunk and the
    file may inflate and decode to follows from their size in the file, docs/recording-format.md#limits)."""
    if data[: len(MAGIC)] != MAGIC:
        raise bad(path, "the file does not start with the .swr magic number")
    budget = budget if budget is not None else Budget(len(data))
    pos = len(MAGIC)
    index = 0
    while pos < len(data):
        if pos + CHUNK_HEADER.size > len(data):
            raise bad(path, f"truncated inside the header of chunk {index}")
        kind, length, crc = CHUNK_HEADER.unpack_from(data, pos)
        pos += CHUNK_HEADER.size
        if length > MAX_CHUNK_BYTES:
            raise bad(path, f"chunk {index} claims {length} bytes (at most {MAX_CHUNK_BYTES})")
        if length > len(data) - pos:
            raise bad(path, f"truncated inside chunk {index} ({len(data) - pos} of {length} bytes)")
        payload = data[pos: pos + length]
        if zlib.crc32(payload) != crc:
            raise bad(path, f"chunk {index} fails its CRC check")
        pos += length
        yield kind, _decode_body(payload, index, path, budget)
        index += 1


def _mib(n: int) -> str:
    return f"{n / (1 << 30):.4g} GiB" if n >= 1 << 30 else f"{n / (1 << 20):.4g} MiB"


def inflate(payload: bytes, index: int, path: str, budget: Budget) -> bytearray:
    """The inflated payload of chunk ``index``, :data:`INFLATE_STEP` bytes at a time: refused as soon as it
    passes the chunk's limit or takes the file past its own (:func:`chunk_limits`, :func:`file_limits`)."""
    limit = chunk_limits(len(payload))[0]
    inflater = zlib.decompressobj()
    out = bytearray()
    pending = payload
    try:
        while not inflater.eof:
            piece = inflater.decompress(pending, INFLATE_STEP)
            pending = inflater.unconsumed_tail
            size = len(out) + len(piece)  # checked before the piece is kept
            if size > limit:
                raise bad(path, f"chunk {index} inflates to more than {_mib(limit)} from {len(payload)} bytes (a "
                                f"chunk may inflate to {MAX_RATIO}x its size or {_mib(RATIO_FLOOR)}, at most "
                                f"{_mib(MAX_INFLATED_CHUNK)}: docs/recording-format.md#limits)")
            if budget.inflated + size > budget.max_inflated:
                raise bad(path, f"its chunks inflate to more than {_mib(budget.max_inflated)} by chunk {index} (a "
                                f"file may inflate to {MAX_FILE_RATIO}x its size or {_mib(FILE_FLOOR)}, at most "
                                f"{_mib(MAX_INFLATED_TOTAL)}: docs/recording-format.md#limits)")
            out += piece
            if not piece and not pending:
                raise zlib.error("incomplete stream")
    except zlib.error:
        raise bad(path, f"chunk {index} does not inflate (a damaged zlib stream)") from None
    budget.inflated += len(out)
    return out


class _TooMany(Exception):
    """Raised from msgpack's hooks once a chunk or the file decodes to too many items."""


def _decode_body(payload: bytes, index: int, path: str, budget: Budget) -> dict[str, Any]:
    raw = inflate(payload, index, path, budget)
    chunk_items = chunk_limits(len(payload))[1]
    limit = min(chunk_items, budget.max_items - budget.items)
    items = 0

    def count(obj: Any) -> Any:  # msgpack calls it for every array and map it builds, innermost first
        nonlocal items
        items += len(obj)
        if items > limit:
            raise _TooMany
        return obj

    try:
        body = msgpack.unpackb(raw, raw=False, strict_map_key=False, max_bin_len=len(raw), max_str_len=len(raw),
                               max_array_len=limit, max_map_len=limit, max_ext_len=0, list_hook=count,
                               object_hook=count)
    except (_TooMany, ValueError) as exc:
        if not isinstance(exc, _TooMany) and "exceeds max_" not in str(exc):  # msgpack's own length checks
            raise bad(path, f"chunk {index} does not decode ({type(exc).__name__})") from None
        raise bad(path, f"chunk {index} decodes to more than {limit} array items and map entries (a chunk may "
                        f"hold one per 2 bytes it occupies or {ITEMS_FLOOR}, a file one per 2 bytes or "
                        f"{FILE_ITEMS_FLOOR}: docs/recording-format.md#limits)") from None
    except Exception as exc:  # msgpack raises several unrelated types for corrupt input
        raise bad(path, f"chunk {index} does not decode ({type(exc).__name__})") from None
    budget.items += items
    if not isinstance(body, dict):
        raise bad(path, f"chunk {index} is not a map")
    return body
