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
FORMAT_VERSION = 2
"""Version 2 (issue 34) added the communication streams: failed deliveries, groups, map merges, contacts."""
READABLE_VERSIONS = (1, 2)
"""Versions this reader opens: a version 1 file simply has no communication streams."""
CHUNK_HEADER = struct.Struct("<4sII")  # kind, payload length, CRC-32 of the payload
HEAD, BLOCK, TAIL = b"HEAD", b"BLCK", b"TAIL"
MAX_CHUNK_BYTES = 1 << 30
"""No chunk's payload (compressed) may exceed 1 GiB: a corrupt length field must not allocate the world."""
MAX_INFLATED_CHUNK = 256 << 20
"""No chunk may inflate to more than 256 MiB. A 256-tick block of a 1,000-robot run inflates to a few tens of
MiB (docs/recording-format.md, Limits); zlib inflates up to ~1,000x, so without this a 1 MiB chunk could
ask for a gigabyte."""
MAX_INFLATED_TOTAL = 4 << 30
"""All chunks of a file together may inflate to at most 4 GiB: the reader holds every stream in memory."""
MAX_ITEMS_CHUNK = 1 << 21
"""Array elements and map entries one chunk may decode to (2 Mi): msgpack turns one byte into a Python object
of ~60 bytes, so the inflated size alone does not bound memory. A block holds 3 per array field plus one
per changed action: at most 256 Ki for 1,000 robots changing their action every tick of 256."""
MAX_ITEMS_TOTAL = 1 << 24
"""Array elements and map entries the whole file may decode to (16 Mi; ~3 Mi for 1,000 robots x 3,000 ticks
changing their action every tick)."""
INFLATE_STEP = 1 << 24
"""Bytes inflated per step (16 MiB): the limits are checked between steps, so an oversized chunk is refused
after at most this much more than the limit, whatever it claims to hold."""

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
    """What a file's chunks have inflated and decoded to so far, against :data:`MAX_INFLATED_TOTAL` and
    :data:`MAX_ITEMS_TOTAL` (one per file: :func:`iter_chunks` makes it)."""

    def __init__(self) -> None:
        self.inflated = 0
        self.items = 0


def iter_chunks(data: bytes, path: str, budget: Budget | None = None) -> Iterator[tuple[bytes, dict[str, Any]]]:
    """Yield ``(kind, body)`` for every chunk after the magic; corrupt, truncated or oversized data raises
    (sizes: :data:`MAX_CHUNK_BYTES`, :data:`MAX_INFLATED_CHUNK`, :data:`MAX_INFLATED_TOTAL`,
    :data:`MAX_ITEMS_CHUNK`, :data:`MAX_ITEMS_TOTAL`), before the oversized part is allocated."""
    if data[: len(MAGIC)] != MAGIC:
        raise bad(path, "the file does not start with the .swr magic number")
    budget = budget if budget is not None else Budget()
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
    return f"{n / (1 << 20):g} MiB"


def inflate(payload: bytes, index: int, path: str, budget: Budget) -> bytearray:
    """The inflated payload of chunk ``index``, :data:`INFLATE_STEP` bytes at a time: refused as soon as it
    passes :data:`MAX_INFLATED_CHUNK` or takes the file past :data:`MAX_INFLATED_TOTAL`."""
    inflater = zlib.decompressobj()
    out = bytearray()
    pending = payload
    try:
        while not inflater.eof:
            piece = inflater.decompress(pending, INFLATE_STEP)
            pending = inflater.unconsumed_tail
            size = len(out) + len(piece)  # checked before the piece is kept
            if size > MAX_INFLATED_CHUNK:
                raise bad(path, f"chunk {index} inflates to more than {_mib(MAX_INFLATED_CHUNK)} (the most a chunk "
                                "may hold, docs/recording-format.md#limits)")
            if budget.inflated + size > MAX_INFLATED_TOTAL:
                raise bad(path, f"its chunks inflate to more than {_mib(MAX_INFLATED_TOTAL)} by chunk {index} (the "
                                "most a file may hold, docs/recording-format.md#limits)")
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
    limit = min(MAX_ITEMS_CHUNK, MAX_ITEMS_TOTAL - budget.items)
    items = 0

    def count(obj: Any) -> Any:  # msgpack calls it for every array and map it builds, innermost first
        nonlocal items
        items += len(obj)
        if items > limit:
            raise _TooMany
        return obj

    try:
        body = msgpack.unpackb(raw, raw=False, strict_map_key=False, max_bin_len=MAX_INFLATED_CHUNK,
                               max_str_len=MAX_INFLATED_CHUNK, max_array_len=MAX_ITEMS_CHUNK,
                               max_map_len=MAX_ITEMS_CHUNK, max_ext_len=0, list_hook=count, object_hook=count)
    except _TooMany:
        raise bad(path, f"chunk {index} decodes to more than {limit} array items and map entries (at most "
                        f"{MAX_ITEMS_CHUNK} a chunk, {MAX_ITEMS_TOTAL} a file)") from None
    except Exception as exc:  # msgpack raises several unrelated types for corrupt input
        raise bad(path, f"chunk {index} does not decode ({type(exc).__name__})") from None
    budget.items += items
    if not isinstance(body, dict):
        raise bad(path, f"chunk {index} is not a map")
    return body
