"""The 2-bit map copies of the map-sharing service give the same changed cells as byte copies."""

from __future__ import annotations

import numpy as np

from swarm.knowledge.maps import sync_box, sync_changes
from swarm.knowledge.packed import (packed_copy, packed_size, same_as_packed, sync_box_packed, sync_changes_packed,
                                unpacked)


def test_a_packed_copy_holds_the_map_in_a_quarter_of_the_bytes() -> None:
    rng = np.random.default_rng(3)
    for h, w in ((1, 1), (3, 5), (7, 8), (30, 41)):
        known = rng.integers(0, 3, (h, w), dtype=np.uint8)
        copy = packed_copy(known)
        assert copy.shape == (packed_size(h * w),) and copy.shape[0] == -(-h * w // 4)
        assert np.array_equal(unpacked(copy, (h, w)), known)


def test_sync_changes_packed_equals_sync_changes_on_a_byte_copy() -> None:
    rng = np.random.default_rng(11)
    for case in range(200):
        h, w = (int(v) for v in rng.integers(1, 40, 2))
        last = rng.integers(0, 3, (h, w), dtype=np.uint8)
        current = last.copy()
        changed = rng.random((h, w)) < rng.choice([0.0, 0.01, 0.3, 1.0])
        current[changed] = rng.integers(0, 3, int(changed.sum()))
        byte_copy, copy = last.copy(), packed_copy(last)
        want = sync_changes(current, byte_copy)
        got = sync_changes_packed(current, copy)
        assert got.tolist() == want.tolist(), case
        assert np.array_equal(unpacked(copy, (h, w)), current), case
        assert sync_changes_packed(current, copy).size == 0, case


def test_sync_box_packed_equals_sync_box_on_a_byte_copy() -> None:
    rng = np.random.default_rng(8)
    for case in range(400):
        h, w = (int(v) for v in rng.integers(1, 40, 2))
        r0, r1 = sorted(int(v) for v in rng.integers(-3, h + 4, 2))
        c0, c1 = sorted(int(v) for v in rng.integers(-3, w + 4, 2))
        last = rng.integers(0, 3, (h, w), dtype=np.uint8)
        current = last.copy()
        current[rng.random((h, w)) < 0.3] += 1          # changes everywhere, inside the box or not
        extra = rng.integers(0, h * w, int(rng.integers(0, 12)))
        current.reshape(-1)[extra] = rng.integers(0, 3, len(extra))
        current %= 3
        byte_copy, copy = last.copy(), packed_copy(last)
        box = np.array([r0, r1, c0, c1], dtype=np.int64)
        want = sync_box(current, byte_copy, (r0, r1, c0, c1), extra)
        got = sync_box_packed(current, copy, box, extra.astype(np.int64))
        assert got.tolist() == want.tolist(), case
        assert np.array_equal(unpacked(copy, (h, w)), byte_copy), case  # the same cells written, no others


def test_same_as_packed_tells_a_map_from_its_copy_by_every_cell() -> None:
    rng = np.random.default_rng(21)
    for h, w in ((1, 3), (5, 5), (9, 13)):
        known = rng.integers(0, 3, (h, w), dtype=np.uint8)
        copy = packed_copy(known)
        assert same_as_packed(known, copy)
        for i in range(h * w):                      # whole words and the tail past the last one
            other = known.copy()
            other.reshape(-1)[i] = (other.reshape(-1)[i] + 1) % 3
            assert not same_as_packed(other, copy), i
        assert not same_as_packed(np.zeros((h * w + 4, 1), np.uint8), copy)
