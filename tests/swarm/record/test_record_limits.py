"""Decompression limits of the ``.swr`` reader (issue 48, item 5): a small CRC-valid file that inflates to
gigabytes, or decodes to millions of Python objects, is refused early, in bounded time and memory.

The bombs are built here: a zlib stream of N zero bytes is a 17-byte head then the same ~1 KiB deflate
block per MiB (each block ends with a full flush, which resets the compressor, so every MiB compresses to
identical bytes), then an empty final block and the Adler-32 of the whole content.
"""

from __future__ import annotations

import struct
import subprocess
import sys
import time
import tracemalloc
import zlib
from pathlib import Path

import msgpack
import numpy as np
import pytest

from maps import InvalidInput
from swarm.record import container
from swarm.record.container import BLOCK, CHUNK_HEADER, HEAD, MAGIC, TAIL, encode_chunk
from swarm.record.reader import Recording

ROOT = Path(__file__).resolve().parents[3]
MIB = 1 << 20


def zero_bomb(prefix: bytes, zeros: int) -> bytes:
    """zlib(``prefix`` + ``zeros`` zero bytes), built in a fraction of the time zlib would take."""
    mib = b"\0" * MIB
    c = zlib.compressobj(9)
    head = c.compress(prefix) + c.flush(zlib.Z_FULL_FLUSH)
    block = c.compress(mib) + c.flush(zlib.Z_FULL_FLUSH)
    rest = c.compress(b"\0" * (zeros % MIB)) + c.flush(zlib.Z_FULL_FLUSH)
    tail = c.flush()[:-4]  # the final empty block; its Adler-32 covers only what c saw
    adler = zlib.adler32(prefix)
    for _ in range(zeros // MIB):
        adler = zlib.adler32(mib, adler)
    adler = zlib.adler32(b"\0" * (zeros % MIB), adler)
    return head + block * (zeros // MIB) + rest + tail + struct.pack(">I", adler)


def bin_map_bomb(inflated: int) -> bytes:
    """zlib of the msgpack map ``{"x": <zero bytes>}`` inflating to exactly ``inflated`` bytes: a chunk that
    decodes once inflated."""
    zeros = inflated - 8  # the map, its key and the bin header
    return zero_bomb(b"\x81\xa1x\xc6" + struct.pack(">I", zeros), zeros)


def chunk(kind: bytes, payload: bytes) -> bytes:
    return CHUNK_HEADER.pack(kind, len(payload), zlib.crc32(payload)) + payload


def bomb_file() -> bytes:
    """The issue's bomb: four CRC-valid chunks (HEAD, two blocks, TAIL) of ~1 MiB, each inflating to 1 GiB
    that decodes (before issue 48 all four were inflated and decoded: 5.4 GB, two minutes)."""
    payload = bin_map_bomb(1 << 30)
    return MAGIC + b"".join(chunk(kind, payload) for kind in (HEAD, BLOCK, BLOCK, TAIL))


def test_the_zero_bomb_is_a_valid_zlib_stream():
    raw = zlib.decompress(bin_map_bomb(3 * MIB + 5))
    assert len(raw) == 3 * MIB + 5 and msgpack.unpackb(raw) == {"x": b"\0" * (3 * MIB - 3)}


def _child(code: str, timeout: float, tmp_path: Path) -> tuple[subprocess.CompletedProcess, float, float]:
    """Run ``code`` in a fresh Python; its completed process, wall seconds and its own peak RSS in MB. The
    child writes its VmHWM at exit: RUSAGE_CHILDREN gives the largest child this test process ever ran, and
    Linux carries ru_maxrss across exec, so a child forked from a large test process reports its parent's."""
    peak_file = tmp_path / "peak.txt"
    wrapped = ("import atexit, os\n"
               "def _peak():\n"
               "    hwm = [l for l in open('/proc/self/status') if l.startswith('VmHWM:')][0].split()[1]\n"
               "    open(os.environ['PEAK_FILE'], 'w').write(hwm)\n"
               "atexit.register(_peak)\n" + code)
    t0 = time.monotonic()
    proc = subprocess.run([sys.executable, "-c", wrapped], capture_output=True, text=True, timeout=timeout,
                          check=False, cwd=ROOT, env={"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin",
                                                      "PEAK_FILE": str(peak_file)})
    wall = time.monotonic() - t0
    return proc, wall, int(peak_file.read_text()) / 1024  # VmHWM is in kB


@pytest.mark.timeout(120)
def test_a_gigabyte_bomb_is_refused_in_seconds_and_little_memory(tmp_path):
    """4.2 MB of CRC-valid chunks inflating to 1 GiB each took 5.4 GB and over two minutes to refuse."""
    path = tmp_path / "bomb.swr"
    path.write_bytes(bomb_file())
    assert path.stat().st_size < 5 * MIB
    code = ("from swarm.record import load_recording\n"
            "from swarm.base.errors import InvalidInput\n"
            f"try:\n    load_recording({str(path)!r})\n"
            "except InvalidInput as exc:\n    print(exc)\n")
    proc, wall, peak_mb = _child(code, timeout=60, tmp_path=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert "chunk 0 inflates to more than" in proc.stdout, proc.stdout
    assert wall < 20, wall
    assert peak_mb < 700, peak_mb


@pytest.mark.timeout(120)
def test_swarm_view_refuses_the_bomb_in_one_line(tmp_path):
    path = tmp_path / "bomb.swr"
    path.write_bytes(bomb_file())
    code = f"import sys\nfrom swarm.cli import main\nsys.exit(main(['view', {str(path)!r}, '-o', {str(tmp_path / 'v.html')!r}]))\n"
    proc, wall, peak_mb = _child(code, timeout=60, tmp_path=tmp_path)
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("swarm: error: recording") and "inflates to more than" in lines[0]
    assert wall < 20 and peak_mb < 700, (wall, peak_mb)
    assert not (tmp_path / "v.html").exists()


def test_a_chunk_just_over_the_floor_is_refused_and_one_at_it_decodes():
    """A zero bomb compresses ~1,000x: past 64 MiB it is over 200x its size in the file."""
    over = MAGIC + chunk(HEAD, bin_map_bomb(container.RATIO_FLOOR + 1))
    with pytest.raises(InvalidInput, match="chunk 0 inflates to more than 64 MiB from"):
        Recording(over, "over.swr")
    at = MAGIC + chunk(HEAD, bin_map_bomb(container.RATIO_FLOOR))
    with pytest.raises(InvalidInput, match="HEAD does not name"):  # decoded, then found not to be a recording
        Recording(at, "at.swr")


def test_a_big_chunk_that_compresses_like_real_data_is_accepted():
    """80 MiB of two-bit symbols compress ~4x, as recorded streams do (5-10x): past the floor, under 200x."""
    data = np.random.default_rng(0).integers(0, 4, 80 * MIB, dtype=np.uint8).tobytes()
    body = encode_chunk(HEAD, {"x": data}, level=1)
    assert len(body) > 80 * MIB / 200
    with pytest.raises(InvalidInput, match="HEAD does not name"):
        Recording(MAGIC + body, "big.swr")


def test_the_file_total_is_bounded_by_the_file_size(monkeypatch):
    """Many chunks each under the floor must not add up to a bomb: a file inflates to 100x its size at most."""
    monkeypatch.setattr(container, "FILE_FLOOR", 10 * MIB)
    payload = bin_map_bomb(3 * MIB)
    data = MAGIC + b"".join(chunk(BLOCK, payload) for _ in range(4))
    with pytest.raises(InvalidInput, match="inflate to more than 10 MiB by chunk 3"):
        list(container.iter_chunks(data, "many.swr"))


@pytest.mark.parametrize("body", [
    {"a": [[]] * 1_500_000, "b": [[]] * 1_500_000},  # 3 MB of msgpack, ~200 MB of empty lists
    {"a": [{}] * 1_500_000, "b": [{}] * 1_500_000},
    {"x": [[[]] * 1_000_000] * 3},
])
def test_many_small_objects_are_refused_before_they_fill_memory(body):
    """msgpack makes a ~60-byte Python object of each one-byte empty array or map."""
    data = MAGIC + encode_chunk(HEAD, body, level=1)
    assert len(data) < MIB
    tracemalloc.start()
    try:
        with pytest.raises(InvalidInput, match="array items and map entries"):
            Recording(data, "objects.swr")
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak < 400 * MIB, peak / MIB


def test_a_chunk_length_past_the_end_is_refused_before_reading():
    data = MAGIC + CHUNK_HEADER.pack(HEAD, 1 << 29, 0) + b"\0" * 100
    with pytest.raises(InvalidInput, match=r"truncated inside chunk 0 \(100 of 536870912 bytes\)"):
        Recording(data, "short.swr")
