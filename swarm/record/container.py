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
"""No chunk, compressed or not, may exceed 1 GiB: a corrupt length field must not allocate the world."""

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


def iter_chunks(data: bytes, path: str) -> Iterator[tuple[bytes, dict[str, Any]]]:
    """Yield ``(kind, body)`` for every chunk after the magic; corrupt or truncated data raises."""
    if data[: len(MAGIC)] != MAGIC:
        raise bad(path, "the file does not start with the .swr magic number")
    pos = len(MAGIC)
    index = 0
    while pos < len(data):
        if pos + CHUNK_HEADER.size > len(data):
            raise bad(path, f"truncated inside the header of chunk {index}")
        kind, length, crc = CHUNK_HEADER.unpack_from(data, pos)
        pos += CHUNK_HEADER.size
        if length > MAX_CHUNK_BYTES:
            raise bad(path, f"chunk {index} claims {length} bytes")
        payload = data[pos: pos + length]
        if len(payload) != length:
            raise bad(path, f"truncated inside chunk {index} ({len(payload)} of {length} bytes)")
        if zlib.crc32(payload) != crc:
            raise bad(path, f"chunk {index} fails its CRC check")
        pos += length
        yield kind, _decode_body(payload, index, path)
        index += 1


def _decode_body(payload: bytes, index: int, path: str) -> dict[str, Any]:
    try:
        inflater = zlib.decompressobj()
        raw = inflater.decompress(payload, MAX_CHUNK_BYTES)
        if inflater.unconsumed_tail or not inflater.eof:
            raise zlib.error("incomplete or oversized stream")
        body = msgpack.unpackb(raw, raw=False, strict_map_key=False, max_bin_len=MAX_CHUNK_BYTES,
                               max_str_len=MAX_CHUNK_BYTES, max_array_len=1 << 26, max_map_len=1 << 20)
    except Exception as exc:  # zlib and msgpack raise several unrelated types for corrupt input
        raise bad(path, f"chunk {index} does not decode ({type(exc).__name__})") from None
    if not isinstance(body, dict):
        raise bad(path, f"chunk {index} is not a map")
    return body
