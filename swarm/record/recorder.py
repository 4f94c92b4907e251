"""The recorder: a per-tick observer that writes what a run did into a compact ``.swr`` file.

Use::

    sim = Simulation(spec)
    recorder = Recorder.attach(sim)          # appends itself to sim.observers
    result = sim.run()
    recorder.finish(sim, result)             # the final tick, which observers never see
    recorder.save("run.swr")

Cost: the run's hot loop calls :meth:`Recorder.__call__` once per tick. Every array stream is a diff
against a mirror the recorder keeps, one numba pass per stream (:mod:`swarm.record.kernels`), so the
per-tick work does not depend on how much the robots did:

- knowledge maps: every robot's whole map against its mirror, 8 cells at a time as uint64 words. We chose
  this over comparing only the lidar windows plus the cells of delivered map updates (what the zenoh
  transport does) because it is exact by construction: nothing the simulator writes, now or in a future
  sensor or merge path, can escape the recording. It is about half of the recorder's cost (figures:
  ``benchmarks/speed/bench_record.py``, docs/performance-history.md).
- the union ``seen`` raster the same way; the link matrix by toggles; RSSI quantised (see below).
- messages and actions are Python loops over what was sent/decided this tick (a handful per robot);
  an action is stored only when its packed form differs from the robot's previous one. A tick's messages
  are written at the next tick (or at :meth:`Recorder.finish`): with ``comm.link_at = "receive"`` the
  medium judges them only then. Their failed deliveries come from the medium itself, which lists them per
  envelope once the recorder sets :attr:`swarm.comm.medium.Medium.note_losses` (off, it does no work for them).
- communication, as the run's own bookkeeping has it (:mod:`swarm.results.metrics`): the tick's groups
  (``LinkState.groups()``), who merged whose map when (``InfoAges.merged_at``, changed entries only), who
  received a message this tick (the medium's ``last_contact``) and the team's known free cells (the
  missing share's denominator, ``CommMetrics.team_free``). With these and the knowledge maps a reader
  gets every robot's age of information, time since contact and missing share at every tick, equal to the
  run's ``RunResult.comm`` rows at theirs.

Chunks of ``block_ticks`` ticks are compressed as they fill, so memory holds only compressed bytes; a
chunk closes earlier once its streams hold :data:`BLOCK_BYTES` (a swarm's 256 ticks would inflate to
gigabytes, which every reader must hold at once).

**What is exact.** Poses (float64), explored/coverage (float64), every robot's knowledge map, the union
``seen`` raster, the boolean link matrix, every message's (sender, seq, type, size, receivers,
transmitter, failed deliveries and their causes), each robot's action (goal, velocity, clear_goal, debug,
after :func:`plain` normalisation), the groups, ``merged_at``, contacts and the team's free cells are
reproduced exactly at every tick. RSSI is stored in units of ``rssi_quantum_db`` (0.25 dB) and an entry is rewritten
when it drifts more than ``rssi_update_db`` (1 dB) from the stored value, or its link toggles, so the stored
matrix is always within 1.125 dB of the truth; the exact RSSI is recomputable from the exact poses
(:meth:`swarm.record.Recording.link_state`). Identical specs give byte-identical recordings.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import msgpack
import numpy as np

from maps.io import atomic_write_bytes, map_to_bytes
from maps.materials import colour_of
from swarm.base.errors import InvalidInput

from swarm.comm.medium import LOSS_CAUSES
from swarm.util.memory import lazy_zeros
from swarm.util.source import package_version
from .container import BLOCK, FORMAT_NAME, FORMAT_VERSION, HEAD, MAGIC, TAIL, encode_chunk, pack_array
from .kernels import RSSI_NAN, _record_changes, _record_links, changed_cells, quantise_rssi

if TYPE_CHECKING:
    from swarm.sim.loop import Simulation, TickView

BLOCK_BYTES = 64 << 20
"""A block closes once its streams hold this many bytes as stored (before compression), whatever its ticks."""
MAX_DEBUG_BYTES = 256 * 1024
"""An action whose packed form exceeds this keeps its goal/velocity but its debug is replaced by a note."""
_U32 = 1 << 32


def software_version() -> str:
    """The swarm version a recording names (``unknown`` in a source tree never installed)."""
    return package_version() or "unknown"


def plain(obj: Any) -> Any:
    """msgpack fallback for debug payloads: numpy values become Python numbers/lists, sets become lists
    sorted by repr (set order of strings changes between processes; the recording must not), anything
    else its ``repr``. Tuples are packed as arrays by msgpack itself."""
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, (set, frozenset)):
        return sorted(obj, key=repr)
    return repr(obj)


_PACKER = msgpack.Packer(default=plain, use_bin_type=True)
"""One packer for every action: ``msgpack.packb`` builds a new Packer per call, 5x the cost here."""


def pack_action(action: Any, packer: msgpack.Packer = _PACKER) -> bytes:
    """The recorded form of one robot's action: msgpack ``[goal, velocity, clear_goal, debug]`` or nil."""
    if action is None:
        return b"\xc0"
    fields = [action.goal, action.velocity, bool(action.clear_goal), action.debug]
    data = packer.pack(fields)
    if len(data) > MAX_DEBUG_BYTES:
        fields[3] = {"_omitted": f"debug of {len(data)} bytes exceeds {MAX_DEBUG_BYTES}"}
        data = packer.pack(fields)
    return data


def _gaps(parts: list[np.ndarray]) -> np.ndarray:
    """Per-tick sorted indices -> per tick, the first index then the differences (small numbers compress
    well); the reader restarts its cumulative sum at every tick."""
    if not parts:
        return np.zeros(0, dtype=np.int64)
    idx = np.concatenate(parts)
    gaps = np.diff(idx, prepend=0)
    starts = np.cumsum([0] + [len(p) for p in parts[:-1]])
    starts = starts[starts < len(idx)]
    gaps[starts] = idx[starts]
    return gaps


class _Block:
    """The streams of the ticks since the last flush, as lists of per-tick pieces."""

    def __init__(self, t0: int) -> None:
        self.t0 = t0
        self.nbytes = 0  # the streams' size as stored, uncompressed (BLOCK_BYTES)
        self.poses: list[np.ndarray] = []
        self.metrics: list[tuple[float, float]] = []
        self.counts: dict[str, list[int]] = {k: [] for k in ("known", "seen", "link", "rssi", "msg", "act",
                                                              "group", "aoi", "contact")}
        self.known_idx: list[np.ndarray] = []
        self.known_val: list[np.ndarray] = []
        self.seen_idx: list[np.ndarray] = []
        self.link_idx: list[np.ndarray] = []
        self.rssi_idx: list[np.ndarray] = []
        self.rssi_val: list[np.ndarray] = []
        self.msg_cols: list[tuple[int, ...]] = []  # sender, seq, type, size, receivers, transmitter, lost
        self.msg_recv: list[np.ndarray] = []  # per message (a swarm's message reaches a thousand robots)
        self.msg_rssi: list[np.ndarray] = []
        self.msg_lost: list[int] = []
        self.msg_lost_cause: list[int] = []
        self.group_robot: list[int] = []
        self.group_id: list[int] = []
        self.aoi_idx: list[np.ndarray] = []
        self.aoi_val: list[np.ndarray] = []
        self.contact_robot: list[int] = []
        self.team_free: list[int] = []
        self.msg_types: dict[str, int] = {}
        self.act_robot: list[int] = []
        self.act: list[bytes] = []

    def __len__(self) -> int:
        return len(self.poses)

    def body(self) -> dict[str, Any]:
        def cat(parts: list[np.ndarray], dtype: str, shuffle: bool = False) -> list[Any]:
            return pack_array(np.concatenate(parts) if parts else np.zeros(0), dtype, shuffle)

        msg = np.array(self.msg_cols, dtype=np.int64).reshape(-1, 7)
        return {
            "t0": self.t0, "n": len(self),
            "pose": pack_array(np.stack(self.poses), "<f8", shuffle=True),
            "metrics": pack_array(np.array(self.metrics, dtype=np.float64), "<f8", shuffle=True),
            **{f"{k}_n": pack_array(np.array(v), "<u4") for k, v in self.counts.items()},
            "known_gap": pack_array(_gaps(self.known_idx), "<u4", True), "known_val": cat(self.known_val, "|u1"),
            "seen_gap": pack_array(_gaps(self.seen_idx), "<u4", True),
            "link_gap": pack_array(_gaps(self.link_idx), "<u4", True),
            "rssi_gap": pack_array(_gaps(self.rssi_idx), "<u4", True), "rssi_val": cat(self.rssi_val, "<i2", True),
            "msg_sender": pack_array(msg[:, 0], "<u2"), "msg_seq": pack_array(msg[:, 1], "<u4"),
            "msg_type": pack_array(msg[:, 2], "<u2"), "msg_size": pack_array(msg[:, 3], "<u4"),
            "msg_recv_n": pack_array(msg[:, 4], "<u2"),
            "msg_recv": cat(self.msg_recv, "<u2"),
            "msg_rssi": cat(self.msg_rssi, "<i2", shuffle=True),
            "msg_types": list(self.msg_types),
            "msg_via": pack_array(msg[:, 5], "<u2"), "msg_lost_n": pack_array(msg[:, 6], "<u2"),
            "msg_lost": pack_array(np.array(self.msg_lost), "<u2"),
            "msg_lost_cause": pack_array(np.array(self.msg_lost_cause), "|u1"),
            "group_robot": pack_array(np.array(self.group_robot), "<u2"),
            "group_id": pack_array(np.array(self.group_id), "<u2"),
            "aoi_gap": pack_array(_gaps(self.aoi_idx), "<u4", True), "aoi_val": cat(self.aoi_val, "<u4", True),
            "contact_robot": pack_array(np.array(self.contact_robot), "<u2"),
            "team_free": pack_array(np.array(self.team_free), "<u4", shuffle=True),
            "act_robot": pack_array(np.array(self.act_robot), "<u2"), "act": list(self.act),
        }


class Recorder:
    """Observer of one :class:`~swarm.sim.loop.Simulation` that records it (module docstring)."""

    def __init__(self, sim: Simulation, block_ticks: int = 256, rssi_quantum_db: float = 0.25,
                 rssi_update_db: float = 1.0, journal: bool = True) -> None:
        n = sim.spec.robots.count
        h, w = sim.truth.shape
        if n > 65535 or n * h * w >= _U32:
            raise InvalidInput("--record", f"{n} robots x {h} x {w} cells",
                               "at most 65535 robots and fewer than 2**32 robot-cells")
        self.n, self.shape = n, (h, w)
        self.block_ticks = block_ticks
        self.quantum = rssi_quantum_db
        self.update_units = round(rssi_update_db / rssi_quantum_db)
        # written only where a map changed: lazily allocated pages (numpy's huge pages would take 2 MB per
        # changed cell of a swarm's sparse knowledge; swarm.util.memory)
        self._known = lazy_zeros((n, h, w), np.uint8)
        self._seen = np.zeros((h, w), dtype=np.uint8)
        self._link = np.zeros((n, n), dtype=np.bool_)
        self._rssi = np.full((n, n), RSSI_NAN, dtype=np.int16)
        self._acts: list[bytes | None] = [None] * n
        self._groups = [-1] * n                                  # each robot's group (its smallest member)
        self._merged_at = lazy_zeros((n * n,), np.int64)          # mirror of sim.ages.merged_at
        self._aoi_idx = np.empty(n * n, dtype=np.int64)          # scratch for its changes
        self._aoi_val = np.empty(n * n, dtype=np.int64)
        self._links_changed = True                               # since the groups were last labelled
        self._contact = list(sim.medium.stats.last_contact)      # the medium's last_contact at the last tick
        self._ages, self._stats = sim.ages, sim.medium.stats     # the run's own comm bookkeeping
        self._team_free = sim.comm_metrics.team_free
        self._pending: tuple[Sequence[Sequence[Any]], Any] | None = None  # last tick's (outboxes, links)
        sim.medium.note_losses = True
        # The maps are diffed where the run's journal says they were written (swarm.knowledge.journal), not
        # whole: the same cells, at a cost that follows the writes instead of R x H x W bytes a tick.
        # ``journal=False``: whole-map diffs (the reference the journal is tested against).
        self._journal = sim.knowledge_journal() if journal else None
        self._words = np.empty((h * w if journal else n * h * w) // 8 + 1, dtype=np.int64)  # changed_cells' scratch
        self._toggled = np.empty(n * n, dtype=np.int64)             # scratch for the link kernel
        self._rssi_idx = np.empty(n * n, dtype=np.int64)
        self._rssi_val = np.empty(n * n, dtype=np.int16)
        self._next_tick = 0
        self._block = _Block(0)
        self._chunks: list[bytes] = [MAGIC, encode_chunk(HEAD, self._header(sim, rssi_update_db))]
        self._finished = False

    @classmethod
    def attach(cls, sim: Simulation, **options: Any) -> Recorder:
        """A recorder for ``sim``, appended to its observers."""
        recorder = cls(sim, **options)
        sim.observers = (*sim.observers, recorder)
        return recorder

    def _header(self, sim: Simulation, rssi_update_db: float) -> dict[str, Any]:
        truth = sim.truth
        return {
            "format": FORMAT_NAME, "version": FORMAT_VERSION, "software": software_version(),
            "spec": sim.spec.canonical(), "key": sim.spec.key, "n_robots": self.n, "shape": list(self.shape),
            "cell_m": 0.5, "tick_s": 0.1, "map": map_to_bytes(truth),
            "material": pack_array(truth.material.reshape(-1), "|u1"),
            "materials": list(truth.materials), "colours": [list(colour_of(m)) for m in truth.materials],
            "robot_radius_m": float(sim.motion.radius), "lidar_range_m": float(sim.lidar_params.range_m),
            "sensitivity_dbm": [float(v) for v in sim.links.config.sensitivity_array(self.n)],
            "radio_model": sim.links.config.model,
            "rssi_quantum_db": self.quantum, "rssi_update_db": float(rssi_update_db),
            "block_ticks": self.block_ticks, "loss_causes": list(LOSS_CAUSES),
        }

    # ------------------------------------------------------------------------------------ ticks ----
    def __call__(self, view: TickView) -> None:
        self._capture(view.tick, view.poses, view.known, view.tracker, view.links, view.actions, view.sent)

    def finish(self, sim: Simulation, result: Any = None) -> None:
        """Record the final tick (the loop stops right after sensing it, before observers run) and the
        run's deterministic summary. Call once, after ``sim.run()``."""
        if self._finished:
            raise RuntimeError("Recorder.finish called twice")
        poses = sim.world.poses
        links = sim.links.evaluate(poses[:, :2])  # a pure function of positions: the run's own picture
        self._capture(self._next_tick, poses, sim.known, sim.tracker, links, [], [])
        self._capture_pending()
        self._flush()
        summary: dict[str, Any] = {}
        if result is not None:
            summary = {k: v for k, v in result.summary.items() if not k.endswith("_time_s")}
        self._chunks.append(encode_chunk(TAIL, {"ticks": self._next_tick, "summary": summary,
                                                "events": list(getattr(sim, "events", []))}))
        self._finished = True

    def _capture(self, tick: int, poses: np.ndarray, known: np.ndarray, tracker: Any, links: Any,
                 actions: Sequence[Any], sent: Sequence[Sequence[Any]]) -> None:
        if self._finished:
            raise RuntimeError("the recording is finished")
        if tick != self._next_tick:
            raise RuntimeError(f"recorder expected tick {self._next_tick}, got {tick} (one recorder per run)")
        self._capture_pending()
        if len(self._block) >= self.block_ticks or self._block.nbytes >= BLOCK_BYTES:
            self._flush()
        b = self._block
        b.poses.append(np.array(poses, dtype=np.float64))
        b.metrics.append((float(tracker.explored), float(tracker.coverage)))
        if self._journal is not None:
            idx = self._journal.take(known, self._known)
        else:
            idx = changed_cells(known, self._known, self._words)
        b.counts["known"].append(len(idx))
        b.known_idx.append(idx)
        b.known_val.append(self._known.reshape(-1)[idx])
        idx = changed_cells(tracker.seen, self._seen, self._words)
        b.counts["seen"].append(len(idx))
        b.seen_idx.append(idx)
        self._capture_links(b, links)
        self._capture_comm(b, tick, known, tracker, links)
        self._capture_actions(b, actions)
        c = {k: v[-1] for k, v in b.counts.items() if k != "msg"}
        b.nbytes += (24 * self.n + 56 + 5 * c["known"] + 4 * c["seen"] + 4 * c["link"] + 6 * c["rssi"]
                     + 4 * c["group"] + 8 * c["aoi"] + 2 * c["contact"]
                     + 2 * c["act"] + sum(len(a) for a in b.act[len(b.act) - c["act"]:]))
        self._pending = (sent, links)
        self._next_tick += 1

    def _capture_pending(self) -> None:
        """The last captured tick's messages, into the current block (which ends with that tick)."""
        if self._pending is not None:
            sent, links = self._pending
            self._pending = None
            self._capture_messages(self._block, sent, links)

    def _capture_links(self, b: _Block, links: Any) -> None:
        link = np.ascontiguousarray(links.link).reshape(-1)
        rssi = np.ascontiguousarray(links.rssi, dtype=np.float64).reshape(-1)
        nt, nr = _record_links(link, rssi, self._link.reshape(-1), self._rssi.reshape(-1), self.quantum,
                               self.update_units, self._toggled, self._rssi_idx, self._rssi_val)
        b.counts["link"].append(nt)
        self._links_changed |= nt > 0
        b.link_idx.append(self._toggled[:nt].copy())
        b.counts["rssi"].append(nr)
        b.rssi_idx.append(self._rssi_idx[:nr].copy())
        b.rssi_val.append(self._rssi_val[:nr].copy())

    def _capture_messages(self, b: _Block, sent: Sequence[Sequence[Any]], links: Any) -> None:
        count = 0
        q: np.ndarray | None = None
        for outbox in sent:
            for env in outbox:
                message_type = getattr(type(env.message), "message_type", type(env.message).__name__)
                code = b.msg_types.setdefault(message_type, len(b.msg_types))
                receivers = np.asarray(env.delivered_to, dtype=np.int64)
                lost = env.lost or ()
                b.msg_cols.append((env.sender, env.seq, code, len(env.data), len(receivers), env.transmitter,
                                   len(lost)))
                for robot, cause in lost:
                    b.msg_lost.append(robot)
                    b.msg_lost_cause.append(cause)
                if len(receivers):
                    if q is None:
                        q = quantise_rssi(links.rssi, self.quantum)
                    b.msg_recv.append(receivers)
                    # a relayed copy: its relay's signal. Stored as the difference from the RSSI stream's value
                    # (the mirror still holds the sending tick's), modulo 2**16: a few units, where the values
                    # themselves made the largest stream of a swarm's recording
                    exact = q[receivers, env.transmitter].astype(np.int32)
                    b.msg_rssi.append((exact - self._rssi[receivers, env.transmitter]).astype(np.int16))
                b.nbytes += 18 + 4 * len(receivers) + 3 * len(lost)
                count += 1
        b.counts["msg"].append(count)

    def _capture_comm(self, b: _Block, tick: int, known: np.ndarray, tracker: Any, links: Any) -> None:
        """Groups, map merges, contacts and the team's free cells of this tick, as the run's metrics have
        them at this tick's row (merges and the tracker do not change between the row and the observers)."""
        n = self.n
        changed: list[int] = []
        if self._links_changed:  # groups are a function of the link matrix alone
            self._links_changed = False
            label = [0] * n
            for members in (links.groups() if n > 1 else [frozenset({0})]):
                first = min(members)
                for robot in members:
                    label[robot] = first
            changed = [i for i in range(n) if label[i] != self._groups[i]]
            for i in changed:
                b.group_robot.append(i)
                b.group_id.append(label[i])
            self._groups = label
        b.counts["group"].append(len(changed))
        m = _record_changes(self._ages.merged_at.reshape(-1), self._merged_at, self._aoi_idx, self._aoi_val)
        b.counts["aoi"].append(m)
        if m:
            b.aoi_idx.append(self._aoi_idx[:m].copy())
            b.aoi_val.append(self._aoi_val[:m].copy())
        # The medium sets last_contact[i] = t + 1 when it delivers a message of tick t: at send time (now,
        # after the run's row for this tick) or, with link_at = "receive", during tick t + 1. So robot i got a
        # message at this tick when its entry is this tick now or was at the last tick.
        now, before = self._stats.last_contact, self._contact
        contact = [i for i in range(n) if now[i] == tick or before[i] == tick]
        b.counts["contact"].append(len(contact))
        b.contact_robot.extend(contact)
        self._contact = list(now)
        b.team_free.append(self._team_free(known, tracker.seen_free_cells))

    def _capture_actions(self, b: _Block, actions: Sequence[Any]) -> None:
        count = 0
        for i, action in enumerate(actions):
            data = pack_action(action)
            if data != self._acts[i]:
                self._acts[i] = data
                b.act_robot.append(i)
                b.act.append(data)
                count += 1
        b.counts["act"].append(count)

    def _flush(self) -> None:
        if len(self._block):
            self._chunks.append(encode_chunk(BLOCK, self._block.body()))
        self._block = _Block(self._next_tick)

    # ------------------------------------------------------------------------------------ output ----
    @property
    def ticks(self) -> int:
        """Ticks recorded so far."""
        return self._next_tick

    def to_bytes(self) -> bytes:
        if not self._finished:
            raise RuntimeError("call Recorder.finish(sim, result) before saving")
        return b"".join(self._chunks)

    def save(self, path: str | Path) -> Path:
        """Write the recording atomically."""
        return atomic_write_bytes(Path(path), self.to_bytes())


def record_run(sim: Simulation, path: str | Path, **options: Any) -> Any:
    """Run ``sim`` with a recorder and write the recording to ``path``; returns the RunResult."""
    recorder = Recorder.attach(sim, **options)
    result = sim.run()
    recorder.finish(sim, result)
    recorder.save(path)
    return result


__all__ = ["Recorder", "pack_action", "plain", "record_run"]
