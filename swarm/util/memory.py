"""Zeroed arrays whose memory is taken a small page at a time, as they are first written.

A swarm's knowledge maps are one ``uint8[R, H, W]`` stack: 1.4 GB for 1,000 robots on a 600-tile map,
of which each robot has written the few rows it has seen or heard of. ``numpy.zeros`` asks the kernel
for zero pages that it fills in only when written, but with transparent huge pages (``always`` on many
Linux machines, this one included) the first write into a 2 MB region makes all of it resident, so one
cell written per robot made the whole stack resident. :func:`lazy_zeros` maps such arrays with huge pages
switched off for them: memory then grows by 4 KB pages where the robots' maps actually hold something.
Reading an unwritten page costs no memory. The address space is not reserved up front: a machine that runs
out of memory while the pages fill in stops the process (the kernel's out-of-memory killer) rather than
raising ``MemoryError`` at the allocation.
"""

from __future__ import annotations

import ctypes
import functools
import mmap
import sys
from typing import Any

import numpy as np

_NORESERVE = getattr(mmap, "MAP_NORESERVE", 0x4000 if sys.platform.startswith("linux") else 0)
"""Linux's MAP_NORESERVE (the mmap module does not name it): such a mapping is not charged against the
kernel's overcommit heuristic, which refuses one larger than the machine's memory (10,000 maps of a
2,000-tile building: 160 GB of address space, a few GB of it ever written)."""

LAZY_BYTES = 1 << 22
"""Arrays smaller than this (4 MB) are plain ``numpy.zeros``: too small for huge pages to matter."""


def lazy_zeros(shape: tuple[int, ...], dtype: type | np.dtype = np.uint8) -> np.ndarray:
    """A C-contiguous zeroed array of ``shape`` whose pages become resident only when written (see the
    module docstring); like ``numpy.zeros`` in every other way."""
    dt = np.dtype(dtype)
    count = int(np.prod(shape, dtype=np.int64))
    nbytes = count * dt.itemsize
    if nbytes < LAZY_BYTES or not hasattr(mmap, "MADV_NOHUGEPAGE"):
        return np.zeros(shape, dtype=dt)
    buffer = mmap.mmap(-1, nbytes, flags=mmap.MAP_PRIVATE | mmap.MAP_ANONYMOUS | _NORESERVE)  # zero pages
    buffer.madvise(mmap.MADV_NOHUGEPAGE)
    return np.frombuffer(buffer, dtype=dt, count=count).reshape(shape)


@functools.cache
def _malloc_trim() -> Any:
    """glibc's ``malloc_trim`` from the C library this process runs on, or None where it has none (musl,
    macOS, Windows). Looked up on first use, not at import."""
    try:
        trim = ctypes.CDLL(None).malloc_trim
    except (OSError, AttributeError, TypeError):
        return None
    trim.argtypes, trim.restype = [ctypes.c_size_t], ctypes.c_int
    return trim


def release_freed_memory() -> bool:
    """Hand the pages of freed heap memory back to the system (glibc's ``malloc_trim(0)``); False where the
    C library cannot. A swarm's sharing tick frees a gigabyte of short-lived arrays (decoded updates, the
    dense copies of full maps) allocated between long-lived ones, and glibc keeps such holes resident: at
    10,000 robots on 2,000 tiles 0.5 GB after the merges of a tick, found in 55 ms. Results do not change."""
    trim = _malloc_trim()
    if trim is None:
        return False
    trim(0)
    return True
