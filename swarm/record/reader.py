"""Reading ``.swr`` recordings: :func:`load_recording` validates a file and reconstructs any tick.

Everything is checked on load (magic, every chunk's CRC, decompression, field types, array lengths,
every index against the map and robot count, tick continuity, a final ``TAIL`` chunk), so a corrupt or
truncated file raises :class:`swarm.base.errors.InvalidInput` here, never half-way through a replay.

Reconstruction replays the per-tick deltas from tick 0 with whole-array numpy operations; a state for one
tick of a 16-robot, 11 000-tick run takes tens of milliseconds, fine for tests and analysis (the browser
viewer keeps its own keyframes for scrubbing).

Version 1 files (before the communication streams) still load: their messages have no failed deliveries
listed and :meth:`Recording.comm_at` says the file has no communication streams.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import Any

import msgpack
import numpy as np

from maps.model import Map
from swarm.base.errors import InvalidInput

from .container import BLOCK, FORMAT_NAME, HEAD, READABLE_VERSIONS, TAIL, bad, iter_chunks, unpack_array
from .kernels import RSSI_NAN, RSSI_NEG_INF, RSSI_POS_INF

STREAMS_V1 = ("known", "seen", "link", "rssi", "msg", "act")
STREAMS = (*STREAMS_V1, "group", "aoi", "contact")
_ARRAYS_V1 = ("pose", "metrics", "known_gap", "known_val", "seen_gap", "link_idx", "rssi_idx", "rssi_val",
              "msg_sender", "msg_seq", "msg_type", "msg_size", "msg_recv_n", "msg_recv", "msg_rssi",
              "act_robot", *(f"{s}_n" for s in STREAMS_V1))
_BLOCK_ARRAYS = (*_ARRAYS_V1, "msg_via", "msg_lost_n", "msg_lost", "msg_lost_cause", "group_robot", "group_id",
                 "aoi_idx", "aoi_val", "contact_robot", "team_free", "group_n", "aoi_n", "contact_n")
_GAPPED_V3 = ("link_idx", "rssi_idx", "aoi_idx")
_U32 = 1 << 32
"""Index streams that version 3 stores as per-tick gaps under ``*_gap`` (read back as indices here)."""


@dataclass(frozen=True)
class MessageRecord:
    """One transmission: sent at ``tick`` by ``transmitter`` (the ``sender`` itself, or a robot relaying
    the ``sender``'s ``seq``-th message), ``size`` bytes on the wire, delivered next tick to ``receivers``;
    ``rssi_dbm[k]`` is what ``receivers[k]`` received (quantised). ``lost`` lists ``(robot, cause)`` for the
    other robots it failed to reach, ``cause`` one of :data:`swarm.comm.medium.LOSS_CAUSES` (empty in a version 1
    file)."""

    tick: int
    sender: int
    seq: int
    type: str
    size: int
    receivers: tuple[int, ...]
    rssi_dbm: tuple[float, ...]
    transmitter: int = -1
    lost: tuple[tuple[int, str], ...] = ()


@dataclass(frozen=True)
class TickState:
    """What the run had at the end of one tick's decisions (what observers saw)."""

    tick: int
    poses: np.ndarray       # float64[R, 3], exact
    known: np.ndarray       # uint8[R, H, W], exact
    seen: np.ndarray        # bool[H, W], exact (union of what any robot observed)
    link: np.ndarray        # bool[R, R], exact; link[i, j]: j's message reaches i
    rssi: np.ndarray        # float64[R, R] dBm, quantised (module docstring of swarm.record.recorder)
    explored: float
    coverage: float
    actions: list[Any]      # per robot: {"goal", "velocity", "clear_goal", "debug"} or None


@dataclass(frozen=True)
class CommState:
    """The communication picture at one tick, equal to the run's ``RunResult.comm`` row at that tick where
    it has one (docs/comm-metrics.md)."""

    tick: int
    groups: list[frozenset[int]]  # sorted by smallest member, as radio.LinkState.groups()
    merged_at: np.ndarray         # int64[R, R]: when robot i last merged (a map holding) robot s's map
    aoi_age: np.ndarray           # float64[R]: mean over the others of tick - merged_at (ticks)
    since_contact: np.ndarray     # int64[R]: ticks since the robot last received a message
    missing_free: np.ndarray      # float64[R]: share of the team's known free cells its map lacks
    team_free: int                # the team's known free cells


def _cat(parts: list[np.ndarray], dtype: str) -> np.ndarray:
    return np.concatenate(parts) if parts else np.zeros(0, dtype=dtype)


def _offsets(counts: np.ndarray) -> np.ndarray:
    out = np.zeros(len(counts) + 1, dtype=np.int64)
    np.cumsum(counts, out=out[1:])
    return out


def _absolute(gaps: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """Per-tick gap encoding back to indices: a cumulative sum restarted at every tick."""
    total = np.cumsum(gaps, dtype=np.int64)
    starts = offsets[:-1]
    base = np.zeros(len(starts), dtype=np.int64)
    later = starts > 0
    base[later] = total[starts[later] - 1]
    return total - np.repeat(base, np.diff(offsets))


def _last_wins(size: int, idx: np.ndarray, values: np.ndarray, fill: Any, dtype: Any) -> np.ndarray:
    """A flat array of ``size`` with ``values`` written at ``idx`` in order (later writes win), a slice of
    :data:`_LAST_WINS_STEP` entries at a time (a swarm's stream has hundreds of millions: sorting it whole
    took gigabytes)."""
    out = np.full(size, fill, dtype=dtype)
    for a in range(0, len(idx), _LAST_WINS_STEP):
        rev = idx[a:a + _LAST_WINS_STEP][::-1]
        unique, first = np.unique(rev, return_index=True)
        out[unique] = values[a:a + _LAST_WINS_STEP][::-1][first]
    return out


_LAST_WINS_STEP = 1 << 24


def dequantise_rssi(q: np.ndarray, quantum_db: float) -> np.ndarray:
    out = q.astype(np.float64) * quantum_db
    out[q == RSSI_NAN] = np.nan
    out[q == RSSI_NEG_INF] = -np.inf
    out[q == RSSI_POS_INF] = np.inf
    return out


class Recording:
    """A validated recording held in memory (decompressed streams; see :func:`load_recording`)."""

    def __init__(self, data: bytes, path: str = "<bytes>") -> None:
        self.path = path
        stream = iter_chunks(data, path)  # chunk by chunk: a bad HEAD is refused before any block is inflated
        first = next(stream, None)
        if first is None or first[0] != HEAD:
            raise bad(path, "the first chunk is not HEAD")
        self.header = self._check_header(first[1])
        ending: list[dict[str, Any]] = []  # the TAIL, once the blocks before it are read
        self._load_blocks(self._blocks(stream, ending))
        tail = ending[0]
        if tail.get("ticks") != self.ticks:
            raise bad(path, f"TAIL says {tail.get('ticks')!r} ticks, the blocks hold {self.ticks}")
        summary, events = tail.get("summary"), tail.get("events")
        self.summary: dict[str, Any] = summary if isinstance(summary, dict) else {}
        self.events: list[Any] = events if isinstance(events, list) else []

    def _blocks(self, stream: Any, ending: list[dict[str, Any]]) -> Any:
        """The BLCK bodies after HEAD, one at a time (a swarm's file inflates to gigabytes: each block is
        decoded into its arrays and dropped before the next is inflated); the TAIL goes into ``ending``."""
        for kind, body in stream:
            if ending:
                raise bad(self.path, "unexpected chunk kinds between HEAD and TAIL")
            if kind == TAIL:
                ending.append(body)
            elif kind == BLOCK:
                yield body
            else:
                raise bad(self.path, "unexpected chunk kinds between HEAD and TAIL")
        if not ending:
            raise bad(self.path, "no TAIL chunk: the recording is truncated or was not finished")

    # -------------------------------------------------------------------------------- validation ----
    def _check_header(self, h: dict[str, Any]) -> dict[str, Any]:
        path = self.path
        if h.get("format") != FORMAT_NAME:
            raise bad(path, "HEAD does not name the swarm-recording format")
        version = h.get("version")
        if version not in READABLE_VERSIONS:
            raise bad(path, f"format version {version!r}; this reader knows {READABLE_VERSIONS[0]} to "
                            f"{READABLE_VERSIONS[-1]} (a newer swarm wrote it?)")
        self.version: int = version
        self.has_comm: bool = version >= 2
        """Whether the file has the communication streams (failed deliveries, groups, merges, contacts)."""
        causes = h.get("loss_causes", [])
        if self.has_comm and not (isinstance(causes, list) and causes and all(isinstance(c, str) for c in causes)):
            raise bad(path, "HEAD field 'loss_causes' missing or not a list of names")
        self.loss_causes: tuple[str, ...] = tuple(causes)
        n, shape = h.get("n_robots"), h.get("shape")
        if not isinstance(n, int) or not 1 <= n <= 65535:
            raise bad(path, f"n_robots {n!r}")
        if not (isinstance(shape, list) and len(shape) == 2 and all(isinstance(v, int) and v > 0 for v in shape)):
            raise bad(path, f"shape {shape!r}")
        for key, kind in (("spec", dict), ("map", bytes), ("materials", list), ("colours", list),
                          ("sensitivity_dbm", list), ("rssi_quantum_db", float), ("robot_radius_m", float)):
            if not isinstance(h.get(key), kind):
                raise bad(path, f"HEAD field {key!r} missing or not a {kind.__name__}")
        material = unpack_array(h.get("material"), "material", path)
        if material.size != shape[0] * shape[1] or int(material.max(initial=0)) >= len(h["materials"]):
            raise bad(path, "HEAD material raster does not match the shape or material table")
        if len(h["sensitivity_dbm"]) != n:
            raise bad(path, "HEAD sensitivity_dbm is not one value per robot")
        self.n_robots: int = n
        self.shape: tuple[int, int] = (shape[0], shape[1])
        self.spec: dict[str, Any] = h["spec"]
        self.quantum: float = h["rssi_quantum_db"]
        return h

    def _arrays(self, body: dict[str, Any], index: int) -> dict[str, np.ndarray]:
        out = {}
        gapped = self.version >= 3  # link_idx, rssi_idx and aoi_idx are stored as per-tick gaps
        for name in _BLOCK_ARRAYS if self.has_comm else _ARRAYS_V1:
            stored = name.replace("_idx", "_gap") if gapped and name in _GAPPED_V3 else name
            if stored not in body:
                raise bad(self.path, f"block {index} has no {stored!r}")
            out[name] = unpack_array(body[stored], f"block {index}.{stored}", self.path)
        # Per-tick gaps become absolute indices here, block by block, kept as uint32 (the recorder's flat
        # indices are below 2**32): a 1,000-robot, 3,000-tick file holds hundreds of millions of them
        gap_streams = [("known_gap", "known"), ("seen_gap", "seen")]
        if gapped:
            gap_streams += [(name, name[:-4]) for name in _GAPPED_V3]
        for name, stream in gap_streams:
            stored = name.replace("_idx", "_gap")
            counts = out[f"{stream}_n"]
            total = int(counts.sum(dtype=np.int64))
            if total != out[name].size:
                raise bad(self.path, f"block {index}: {stored} has {out[name].size} entries, its counts say {total}")
            absolute = _absolute(out[name].astype(np.int64), _offsets(counts.astype(np.int64)))
            if absolute.size and int(absolute.max()) >= _U32:
                raise bad(self.path, f"block {index}: a {stream} index is outside the map or robot range")
            out[name] = absolute.astype(np.uint32)
        if not self.has_comm:  # version 1: no communication streams, every message its sender's own
            n, msgs = body.get("n"), len(out["msg_sender"])
            zeros = np.zeros(n if isinstance(n, int) and n > 0 else 0, dtype=np.uint32)
            out.update(msg_via=out["msg_sender"], msg_lost_n=np.zeros(msgs, dtype=np.uint16), group_n=zeros,
                       aoi_n=zeros, contact_n=zeros, team_free=zeros,
                       **{k: np.zeros(0, dtype=np.uint16) for k in ("msg_lost", "msg_lost_cause", "group_robot",
                                                                    "group_id", "aoi_idx", "aoi_val", "contact_robot")})
        return out

    def _load_blocks(self, bodies: list[dict[str, Any]]) -> None:
        path, r = self.path, self.n_robots
        h, w = self.shape
        parts: dict[str, list[np.ndarray]] = {name: [] for name in _BLOCK_ARRAYS}
        types: list[np.ndarray] = []
        type_names: list[str] = []
        acts: list[Any] = []
        tick = 0
        for k, body in enumerate(bodies):
            n = body.get("n")
            if body.get("t0") != tick or not isinstance(n, int) or n < 1:
                raise bad(path, f"block {k} starts at tick {body.get('t0')!r} with {n!r} ticks; expected tick {tick}")
            a = self._arrays(body, k)
            if a["pose"].size != n * r * 3 or a["metrics"].size != 2 * n or a["team_free"].size != n:
                raise bad(path, f"block {k}: pose, metrics or team_free length does not match {n} ticks x {r} robots")
            for s in STREAMS:
                if a[f"{s}_n"].size != n:
                    raise bad(path, f"block {k}: {s}_n has {a[f'{s}_n'].size} entries for {n} ticks")
            sums = {s: int(a[f"{s}_n"].sum()) for s in STREAMS}
            expect = {"known_gap": sums["known"], "known_val": sums["known"], "seen_gap": sums["seen"],
                      "link_idx": sums["link"], "rssi_idx": sums["rssi"], "rssi_val": sums["rssi"],
                      "msg_sender": sums["msg"], "msg_seq": sums["msg"], "msg_type": sums["msg"],
                      "msg_size": sums["msg"], "msg_recv_n": sums["msg"], "act_robot": sums["act"],
                      "msg_recv": int(a["msg_recv_n"].sum()), "msg_rssi": int(a["msg_recv_n"].sum()),
                      "msg_via": sums["msg"], "msg_lost_n": sums["msg"], "msg_lost": int(a["msg_lost_n"].sum()),
                      "msg_lost_cause": int(a["msg_lost_n"].sum()), "group_robot": sums["group"],
                      "group_id": sums["group"], "aoi_idx": sums["aoi"], "aoi_val": sums["aoi"],
                      "contact_robot": sums["contact"]}
            for name, size in expect.items():
                if a[name].size != size:
                    raise bad(path, f"block {k}: {name} has {a[name].size} entries, its counts say {size}")
            names, act = body.get("msg_types"), body.get("act")
            if not (isinstance(names, list) and all(isinstance(t, str) for t in names)):
                raise bad(path, f"block {k}: msg_types is not a list of names")
            if not (isinstance(act, list) and len(act) == sums["act"] and all(isinstance(x, bytes) for x in act)):
                raise bad(path, f"block {k}: act is not {sums['act']} packed actions")
            if a["msg_type"].size and int(a["msg_type"].max()) >= len(names):
                raise bad(path, f"block {k}: a message type index is outside msg_types")
            codes = {name: i for i, name in enumerate(type_names)}
            for name in names:
                if name not in codes:
                    codes[name] = len(type_names)
                    type_names.append(name)
            types.append(np.array([codes[t] for t in names], dtype=np.int64)[a["msg_type"]] if names
                         else np.zeros(0, dtype=np.int64))
            acts.extend(act)
            for name in _BLOCK_ARRAYS:
                parts[name].append(a[name])
            tick += n
        if tick == 0:
            raise bad(path, "no ticks recorded")
        self.ticks: int = tick
        cat = {name: _cat(parts.pop(name), "f8") for name in list(parts)}  # each list freed once joined
        self.poses: np.ndarray = cat["pose"].reshape(tick, r, 3)
        self.explored: np.ndarray = cat["metrics"].reshape(tick, 2)[:, 0].copy()
        self.coverage: np.ndarray = cat["metrics"].reshape(tick, 2)[:, 1].copy()
        self._off = {s: _offsets(cat[f"{s}_n"].astype(np.int64)) for s in STREAMS}
        # The big streams keep their stored widths (uint32 indices, small values): widened copies of a
        # swarm's streams took tens of gigabytes
        self._known_idx = cat["known_gap"]  # absolute since _arrays
        self._known_val = cat["known_val"].astype(np.uint8, copy=False)
        self._seen_idx = cat["seen_gap"]
        self._link_idx = cat["link_idx"].astype(np.uint32, copy=False)
        self._rssi_idx = cat["rssi_idx"].astype(np.uint32, copy=False)
        self._rssi_val = cat["rssi_val"].astype(np.int16, copy=False)
        for name, values, limit in (("knowledge", self._known_idx, r * h * w), ("seen", self._seen_idx, h * w),
                                    ("link", self._link_idx, r * r), ("rssi", self._rssi_idx, r * r),
                                    ("message sender", cat["msg_sender"], r), ("receiver", cat["msg_recv"], r),
                                    ("action robot", cat["act_robot"], r), ("transmitter", cat["msg_via"], r),
                                    ("lost receiver", cat["msg_lost"], r),
                                    ("loss cause", cat["msg_lost_cause"], len(self.loss_causes)),
                                    ("group robot", cat["group_robot"], r), ("group", cat["group_id"], r),
                                    ("merge", cat["aoi_idx"], r * r), ("contact robot", cat["contact_robot"], r)):
            if len(values) and (int(values.min()) < 0 or int(values.max()) >= limit):
                raise bad(path, f"a {name} index is outside the map or robot range")
        if len(self._known_val) and int(self._known_val.max()) > 2:
            raise bad(path, "a knowledge value is not UNSEEN, FREE or SOLID")
        self._msg = {k: cat[f"msg_{k}"].astype(np.int64) for k in ("sender", "seq", "size", "recv_n", "via", "lost_n")}
        for k in ("recv", "lost", "lost_cause"):  # per receiver or lost delivery: narrow as stored
            self._msg[k] = cat[f"msg_{k}"].astype(np.uint16 if k != "lost_cause" else np.uint8, copy=False)
        self._msg_lost_off = _offsets(self._msg["lost_n"])
        self._group_robot = cat["group_robot"].astype(np.int64)
        self._group_id = cat["group_id"].astype(np.int64)
        self._aoi_idx = cat["aoi_idx"].astype(np.uint32, copy=False)
        self._aoi_val = cat["aoi_val"].astype(np.uint32, copy=False)
        self._contact_robot = cat["contact_robot"].astype(np.int64)
        self._contact_tick = np.repeat(np.arange(tick, dtype=np.int64), np.diff(self._off["contact"]))
        self.team_free: np.ndarray = cat["team_free"].astype(np.int64)
        """Per tick: the team's known free cells (0 in a version 1 file)."""
        self._msg["type"] = _cat(types, "i8")
        self._msg_recv_off = _offsets(self._msg["recv_n"])
        msg_rssi = cat["msg_rssi"].astype(np.int16, copy=False)
        self._msg_rssi = self._undelta_msg_rssi(msg_rssi) if self.version >= 3 else msg_rssi  # quantised
        self.message_types: tuple[str, ...] = tuple(type_names)
        self._act_robot = cat["act_robot"].astype(np.int64)
        self._acts: list[bytes] = acts

    def _undelta_msg_rssi(self, delta: np.ndarray) -> np.ndarray:
        """Version 3 stores each receiver's RSSI as its difference (mod 2**16) from the RSSI stream's value of
        the pair at the sending tick: add that value back, replaying the stream tick by tick into one R x R
        matrix (memory: the matrix and one tick's receivers)."""
        r = self.n_robots
        current = np.full(r * r, RSSI_NAN, dtype=np.int16)
        out = np.empty(len(delta), dtype=np.int16)
        rssi_off, msg_off, recv_off = self._off["rssi"], self._off["msg"], self._msg_recv_off
        for t in range(self.ticks):
            a, b = rssi_off[t], rssi_off[t + 1]
            if b > a:  # one update per pair and tick
                current[self._rssi_idx[a:b]] = self._rssi_val[a:b]
            m0, m1 = msg_off[t], msg_off[t + 1]
            lo, hi = recv_off[m0], recv_off[m1]
            if hi > lo:
                via = np.repeat(self._msg["via"][m0:m1], self._msg["recv_n"][m0:m1])
                pair = self._msg["recv"][lo:hi].astype(np.int64) * r + via
                out[lo:hi] = (current[pair].astype(np.int32) + delta[lo:hi]).astype(np.int16)
        return out

    # ------------------------------------------------------------------------------ reconstruction ----
    def _check_tick(self, tick: int) -> int:
        if not isinstance(tick, (int, np.integer)) or not 0 <= tick < self.ticks:
            raise InvalidInput("tick", tick, f"an integer in [0, {self.ticks - 1}]")
        return int(tick)

    @property
    def last_tick(self) -> int:
        return self.ticks - 1

    @cached_property
    def truth(self) -> Map:
        """The run's ground-truth map, exactly as simulated."""
        from maps.io import map_from_bytes

        return map_from_bytes(self.header["map"], f"{self.path} (HEAD map)")

    def known_at(self, tick: int) -> np.ndarray:
        """uint8[R, H, W]: every robot's knowledge map at ``tick``."""
        end = self._off["known"][self._check_tick(tick) + 1]
        flat = _last_wins(self.n_robots * self.shape[0] * self.shape[1], self._known_idx[:end],
                          self._known_val[:end], 0, np.uint8)
        return flat.reshape(self.n_robots, *self.shape)

    def seen_at(self, tick: int) -> np.ndarray:
        """bool[H, W]: cells some robot had observed by ``tick`` (the truth tracker's raster)."""
        end = self._off["seen"][self._check_tick(tick) + 1]
        seen = np.zeros(self.shape[0] * self.shape[1], dtype=np.bool_)
        seen[self._seen_idx[:end]] = True
        return seen.reshape(self.shape)

    def links_at(self, tick: int) -> tuple[np.ndarray, np.ndarray]:
        """(link bool[R, R] exact, rssi float64[R, R] quantised) at ``tick``."""
        t = self._check_tick(tick)
        r = self.n_robots
        end = self._off["link"][t + 1]
        link = (np.bincount(self._link_idx[:end], minlength=r * r) % 2).astype(bool).reshape(r, r)
        end = self._off["rssi"][t + 1]
        q = _last_wins(r * r, self._rssi_idx[:end], self._rssi_val[:end], RSSI_NAN, np.int16)
        return link, dequantise_rssi(q, self.quantum).reshape(r, r)

    def known_changes(self, tick: int) -> tuple[np.ndarray, np.ndarray]:
        """The knowledge cells written at ``tick``: flat indices into ``(R, H, W)`` (each at most once) and
        their new values. Applied in order from tick 0 they give :meth:`known_at` of every tick, for a
        replay that walks the run once instead of rebuilding each tick from the start."""
        t = self._check_tick(tick)
        a, b = self._off["known"][t], self._off["known"][t + 1]
        return self._known_idx[a:b], self._known_val[a:b]

    def actions_changed(self, tick: int) -> dict[int, Any]:
        """The robots whose action at ``tick`` differs from their previous one, each with that action (as in
        :meth:`actions_at`); every other robot repeated its own."""
        t = self._check_tick(tick)
        a, b = self._off["act"][t], self._off["act"][t + 1]
        return {int(self._act_robot[k]): self._decode_action(k) for k in range(a, b)}

    def actions_at(self, tick: int) -> list[Any]:
        """Each robot's latest action up to ``tick``: {"goal", "velocity", "clear_goal", "debug"} or None
        (no decision yet, or a failed agent). The final tick has no decisions of its own."""
        end = self._off["act"][self._check_tick(tick) + 1]
        out: list[Any] = [None] * self.n_robots
        done = np.zeros(self.n_robots, dtype=bool)
        for k in range(end - 1, -1, -1):
            i = int(self._act_robot[k])
            if not done[i]:
                done[i] = True
                out[i] = self._decode_action(k)
                if done.all():
                    break
        return out

    def _decode_action(self, k: int) -> Any:
        try:
            fields = msgpack.unpackb(self._acts[k], raw=False, strict_map_key=False)
        except Exception as exc:
            raise bad(self.path, f"action {k} does not decode ({type(exc).__name__})") from None
        if fields is None:
            return None
        if not isinstance(fields, list) or len(fields) != 4:
            raise bad(self.path, f"action {k} is not [goal, velocity, clear_goal, debug]")
        return dict(zip(("goal", "velocity", "clear_goal", "debug"), fields))

    def messages_at(self, tick: int) -> list[MessageRecord]:
        """Messages broadcast during ``tick`` (delivered at ``tick + 1``), in send order."""
        t = self._check_tick(tick)
        lo, hi = self._off["msg"][t], self._off["msg"][t + 1]
        return [self._message(k, t) for k in range(lo, hi)]

    def messages(self) -> list[MessageRecord]:
        """Every message of the run, in order."""
        ticks = np.repeat(np.arange(self.ticks), np.diff(self._off["msg"]))
        return [self._message(k, int(t)) for k, t in enumerate(ticks)]

    def _message(self, k: int, tick: int) -> MessageRecord:
        m = self._msg
        a, b = self._msg_recv_off[k], self._msg_recv_off[k + 1]
        c, d = self._msg_lost_off[k], self._msg_lost_off[k + 1]
        lost = tuple((robot, self.loss_causes[cause]) for robot, cause in zip(m["lost"][c:d].tolist(),
                                                                              m["lost_cause"][c:d].tolist()))
        return MessageRecord(tick=tick, sender=int(m["sender"][k]), seq=int(m["seq"][k]),
                             type=self.message_types[int(m["type"][k])], size=int(m["size"][k]),
                             receivers=tuple(m["recv"][a:b].tolist()),
                             rssi_dbm=tuple(dequantise_rssi(self._msg_rssi[a:b], self.quantum).tolist()),
                             transmitter=int(m["via"][k]), lost=lost)

    def comm_at(self, tick: int) -> CommState:
        """Groups, age of information, time since contact and missing share of every robot at ``tick``
        (docs/comm-metrics.md), from the recorded groups, merges, contacts and knowledge maps."""
        t = self._check_tick(tick)
        if not self.has_comm:
            raise bad(self.path, f"format version {self.version} has no communication streams (record the run again)")
        r = self.n_robots
        end = self._off["group"][t + 1]
        label = _last_wins(r, self._group_robot[:end], self._group_id[:end], -1, np.int64)
        groups = [frozenset(np.flatnonzero(label == g).tolist()) for g in sorted(set(label.tolist()))]
        end = self._off["aoi"][t + 1]
        merged_at = _last_wins(r * r, self._aoi_idx[:end], self._aoi_val[:end], 0, np.int64).reshape(r, r)
        end = self._off["contact"][t + 1]
        last = _last_wins(r, self._contact_robot[:end], self._contact_tick[:end], -1, np.int64)
        team = int(self.team_free[t])
        if r < 2:  # a lone robot has no one to miss, wait for or hear (as the run's metrics)
            zero = np.zeros(r)
            return CommState(t, groups, merged_at, zero, np.zeros(r, dtype=np.int64), zero, team)
        off = merged_at.sum(axis=1) - merged_at.diagonal()
        free = (self.known_at(t) == 1).reshape(r, -1).sum(axis=1)
        missing = np.clip(1.0 - free / team, 0.0, 1.0) if team > 0 else np.zeros(r)
        return CommState(t, groups, merged_at, t - off / (r - 1), t - np.maximum(last, 0), missing, team)

    def state_at(self, tick: int) -> TickState:
        t = self._check_tick(tick)
        link, rssi = self.links_at(t)
        return TickState(tick=t, poses=self.poses[t].copy(), known=self.known_at(t), seen=self.seen_at(t),
                         link=link, rssi=rssi, explored=float(self.explored[t]), coverage=float(self.coverage[t]),
                         actions=self.actions_at(t))

    @cached_property
    def run_spec(self) -> Any:
        """HEAD's spec as a :class:`swarm.sim.spec.RunSpec`; :class:`InvalidInput` naming the file if it is not
        a run's (the reader checks only that it is a map)."""
        from swarm.sim.spec import RunSpec

        try:
            return RunSpec.from_mapping(self.spec)
        except InvalidInput as exc:
            raise bad(self.path, f"HEAD spec is not a run spec ({exc})") from None

    @cached_property
    def link_model(self) -> Any:
        """The run's radio (a :class:`radio.LinkModel`), rebuilt from its map and spec as the run built it."""
        from radio import build_link_model

        from swarm.sim.spec import run_map_seed

        spec = self.run_spec
        return build_link_model(self.truth, spec.radio, field_seed=run_map_seed(spec.seed, spec.map.seed))

    def link_state(self, tick: int) -> Any:
        """The exact radio picture at ``tick`` (a :class:`radio.models.LinkState`), recomputed from the exact
        poses with the run's own map and radio spec: RSSI to the last bit, unlike the quantised stream."""
        return self.link_model.evaluate(self.poses[self._check_tick(tick), :, :2])


def read_bytes(path: str | Path) -> bytes:
    """A recording file's bytes; :class:`InvalidInput` (not OSError) when it cannot be read."""
    p = Path(path)
    try:
        return p.read_bytes()
    except OSError as exc:
        raise InvalidInput("recording", str(p), f"a readable .swr file ({exc.strerror})") from None


def load_recording(path: str | Path) -> Recording:
    """Read and validate a ``.swr`` file; :class:`InvalidInput` if it is missing, corrupt or truncated."""
    return Recording(read_bytes(path), str(path))


__all__ = ["CommState", "MessageRecord", "Recording", "TickState", "dequantise_rssi", "load_recording", "read_bytes"]
