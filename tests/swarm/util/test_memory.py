"""swarm.util.memory: freed heap pages go back to the system where the C library allows it."""

from __future__ import annotations

import os
import sys

import numpy as np
import pytest

from swarm.util.memory import _malloc_trim, release_freed_memory


def _resident_bytes() -> int:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


@pytest.mark.skipif(_malloc_trim() is None or not sys.platform.startswith("linux"), reason="glibc's malloc_trim only")
def test_freed_holes_between_live_arrays_are_handed_back_and_the_live_data_kept():
    """256 MB of 64 KB arrays (heap, not mmap), every sixteenth kept: the freed ones leave holes that glibc
    keeps resident until release_freed_memory, which hands back most of them; the kept arrays are intact."""
    chunks = [np.full(1 << 16, k % 251, dtype=np.uint8) for k in range(4096)]
    kept = chunks[::16]
    del chunks
    before = _resident_bytes()
    assert release_freed_memory()
    after = _resident_bytes()
    assert before - after > 100 * 2**20, (before, after)
    assert all(int(a[0]) == int(a[-1]) == (16 * k) % 251 for k, a in enumerate(kept))


def test_release_is_a_no_op_answer_where_there_is_no_malloc_trim(monkeypatch):
    from swarm.util import memory

    monkeypatch.setattr(memory, "_malloc_trim", lambda: None)
    assert memory.release_freed_memory() is False
