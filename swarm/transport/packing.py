"""Every live robot's obs packet of a tick, written in one compiled pass (the zenoh transport's hot path).

:func:`~swarm.transport.wire.encode_obs` packs one robot from Python objects: a struct, the changed cells,
the neighbour records and a msgpack list, in Python for every robot every tick. :class:`ObsEncoder` writes
the same bytes for all robots from the tick's arrays (poses, counters, the changed cells of every map, the
near mask and distances) straight into one buffer: msgpack framing, the state struct, uint32 gaps and
values, and neighbour records with their bearings computed per neighbour pair. Python then only cuts the
buffer and splices in the part a kernel does not write: inbox messages (a list of byte strings). Large map
updates are zlib-compressed only for robots marked ``compress`` (agents across a network): those robots go
through ``encode_obs`` itself. An agent in the runtime's own session gets them raw, which the format allows
(compression is the sender's choice; a decoder tells the two apart by length) and which saves deflating
and inflating bytes that never leave the process.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np
from numba import njit

from swarm.base.types import NavStatus, Pose
from swarm.knowledge.cellcodec import put_raw_cells
from .bearings import _bearing
from .wire import (COLLIDED, HAS_GOAL, NEIGHBOUR, NEIGHBOUR_DTYPE, OBS_STATE, RAW_CELLS_BELOW, WIRE_VERSION,
                   _NAV_INDEX, _pack, encode_obs)

OBS_STATE_DTYPE = np.dtype([("x", "<f8"), ("y", "<f8"), ("theta", "<f8"), ("goal_x", "<f8"), ("goal_y", "<f8"),
                            ("path_length", "<f8"), ("travelled", "<f8"), ("energy", "<f8"),
                            ("stalled", "<u4"), ("nav", "u1"), ("flags", "u1")])
assert OBS_STATE_DTYPE.itemsize == OBS_STATE.size and NEIGHBOUR_DTYPE.itemsize == NEIGHBOUR.size

START, INBOX, RECORDS, END = range(4)
"""Columns of the per-robot spans: packet start, the inbox byte (an empty msgpack array), the neighbour
records' first byte, packet end."""


class ObsEncoder:
    """Packs a tick's obs packets for robots ``0..n-1``; byte for byte what ``encode_obs`` gives (tested), with
    large map updates raw for robots not marked ``compress``.

    Keeps each robot's last :class:`NavStatus` with its numbers, so the Python side of a tick is an
    identity check per robot (the navigator returns the same object while nothing changed)."""

    def __init__(self, n_robots: int, compress: Sequence[int] = ()) -> None:
        """``compress``: the robots whose large map updates are compressed (as ``encode_obs`` does)."""
        self._compress = [i in set(compress) for i in range(n_robots)]
        self._navs: list[NavStatus | None] = [None] * n_robots
        self._nav_f = np.zeros((n_robots, 3))                 # goal x, goal y, path length
        self._nav_i = np.zeros((n_robots, 3), dtype=np.int64)  # ticks since progress, state index, flags
        self._states = np.zeros(n_robots, OBS_STATE_DTYPE)
        self._record = np.zeros(1, NEIGHBOUR_DTYPE)
        self._state_bytes, self._record_bytes = self._states.view(np.uint8), self._record.view(np.uint8)  # once
        self._spans = np.zeros((n_robots, 4), dtype=np.int64)

    def _note_navs(self, navs: Sequence[NavStatus | None]) -> None:
        seen = self._navs
        for i, nav in enumerate(navs):
            if nav is not seen[i] and nav is not None:
                seen[i] = nav
                goal = nav.goal
                self._nav_f[i] = (goal[0], goal[1], nav.path_length) if goal is not None else (0.0, 0.0, nav.path_length)
                self._nav_i[i] = (nav.ticks_since_progress, _NAV_INDEX[nav.state], HAS_GOAL if goal is not None else 0)

    def __call__(self, tick: int, live: np.ndarray, poses: np.ndarray, collided: np.ndarray, travelled: np.ndarray,
                 energy: np.ndarray, navs: Sequence[NavStatus | None], known: np.ndarray, cells: np.ndarray,
                 ends: np.ndarray, inboxes: Sequence[Sequence[bytes]], near: np.ndarray,
                 distance: np.ndarray) -> list[bytes | None]:
        """The packets (None where ``live`` is False). Robot i's changed cells are the ascending flat indices
        ``cells[ends[i-1]:ends[i]]`` of ``known[i]`` (uint8[R, H, W]); its neighbours are ``near[i]``."""
        n = len(navs)
        self._note_navs(navs)
        size = n * (96 + OBS_STATE.size + NEIGHBOUR.size * n) + 5 * len(cells)  # at most: every pair near
        buf = np.empty(size, dtype=np.uint8)
        spans = self._spans
        total = _obs_packets(tick, live, poses, collided, travelled, energy, self._nav_f, self._nav_i,
                             known.reshape(n, -1), cells, ends, near, distance, self._states,
                             self._state_bytes, self._record, self._record_bytes, buf, spans)
        data = buf[:total].tobytes()
        rows = spans.tolist()
        lasts = ends.tolist()
        first = 0
        out: list[bytes | None] = []
        for i, (start, inbox_at, records_at, end) in enumerate(rows):
            last = lasts[i]
            if start < 0:
                out.append(None)
            elif last - first >= RAW_CELLS_BELOW and self._compress[i]:  # compressed: the reference path
                idx = cells[first:last]
                out.append(encode_obs(tick, i, Pose(*poses[i].tolist()), idx, known[i].reshape(-1)[idx],
                                      tuple(inboxes[i]), data[records_at:end], bool(collided[i]), navs[i],
                                      float(travelled[i]), float(energy[i])))
            elif inboxes[i]:
                out.append(data[start:inbox_at] + _pack(list(inboxes[i])) + data[inbox_at + 1:end])
            else:
                out.append(data[start:end])
            first = last
        return out


@njit(cache=True, inline="always")
def _put_uint(buf: np.ndarray, p: int, v: int) -> int:  # pragma: no cover - compiled
    """A non-negative msgpack integer in its shortest form (as msgpack's Packer writes it); the next offset."""
    if v < 128:
        buf[p] = v
        return p + 1
    if v < 256:
        buf[p] = 0xCC
        buf[p + 1] = v
        return p + 2
    if v < 65536:
        buf[p] = 0xCD
        width = 2
    elif v < 4294967296:
        buf[p] = 0xCE
        width = 4
    else:
        buf[p] = 0xCF
        width = 8
    for k in range(width):
        buf[p + width - k] = (v >> (8 * k)) & 0xFF
    return p + 1 + width


@njit(cache=True, inline="always")
def _put_bin_header(buf: np.ndarray, p: int, n: int) -> int:  # pragma: no cover - compiled
    """A msgpack bin header for ``n`` bytes in its shortest form; the payload's offset."""
    if n < 256:
        buf[p] = 0xC4
        buf[p + 1] = n
        return p + 2
    width = 2 if n < 65536 else 4
    buf[p] = 0xC5 if width == 2 else 0xC6
    for k in range(width):
        buf[p + width - k] = (n >> (8 * k)) & 0xFF
    return p + 1 + width


@njit(cache=True)
def _obs_packets(tick, live, poses, collided, travelled, energy, nav_f, nav_i, known, cells, ends, near, distance,
                 states, state_bytes, record, record_bytes, buf, spans):  # pragma: no cover - compiled
    """Write every live robot's packet into ``buf``, robot after robot; ``spans[i]`` = (start, inbox byte,
    records start, end), start -1 for robots not live. Returns the bytes written."""
    n = poses.shape[0]
    width = state_bytes.shape[0] // n
    p = 0
    first = 0
    for i in range(n):
        last = ends[i]
        if not live[i]:
            spans[i, START] = -1
            first = last
            continue
        s = states[i]
        s["x"] = poses[i, 0]
        s["y"] = poses[i, 1]
        s["theta"] = poses[i, 2]
        s["goal_x"] = nav_f[i, 0]
        s["goal_y"] = nav_f[i, 1]
        s["path_length"] = nav_f[i, 2]
        s["travelled"] = travelled[i]
        s["energy"] = energy[i]
        s["stalled"] = nav_i[i, 0]
        s["nav"] = nav_i[i, 1]
        s["flags"] = nav_i[i, 2] | (COLLIDED if collided[i] else 0)
        spans[i, START] = p
        buf[p] = 0x99  # an array of 9 items
        buf[p + 1] = 0xA3  # "obs"
        buf[p + 2] = 0x6F
        buf[p + 3] = 0x62
        buf[p + 4] = 0x73
        buf[p + 5] = WIRE_VERSION
        p = _put_uint(buf, p + 6, tick)
        p = _put_uint(buf, p, i)
        p = _put_bin_header(buf, p, width)
        for k in range(width):
            buf[p + k] = state_bytes[i * width + k]
        p += width
        m = last - first
        p = _put_uint(buf, p, m)
        if m == 0:
            buf[p] = 0xC4  # empty bin
            buf[p + 1] = 0
            p += 2
        else:
            p = _put_bin_header(buf, p, 5 * m)
            p = put_raw_cells(buf, p, cells, first, last, known[i])
        spans[i, INBOX] = p
        buf[p] = 0x90  # an empty inbox
        p += 1
        count = 0
        for j in range(n):
            if near[i, j]:
                count += 1
        p = _put_bin_header(buf, p, count * record_bytes.shape[0])
        spans[i, RECORDS] = p
        r = record[0]
        for j in range(n):
            if near[i, j]:
                r["id"] = j
                r["distance"] = distance[i, j]
                r["bearing"] = _bearing(poses[i, 0], poses[i, 1], poses[i, 2], poses[j, 0], poses[j, 1])
                r["x"] = poses[j, 0]
                r["y"] = poses[j, 1]
                for k in range(record_bytes.shape[0]):
                    buf[p + k] = record_bytes[k]
                p += record_bytes.shape[0]
        spans[i, END] = p
        first = last
    return p
