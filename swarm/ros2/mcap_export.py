"""MCAP files of runs with ROS 2 messages, for Foxglove and ``ros2 bag play``: ``swarm export run.swr``
(:func:`export_recording`) and ``swarm run --mcap run.mcap`` (:class:`McapRecorder`), the same messages
either way (:mod:`swarm.ros2.topics`; docs/ros2.md).

Written with the ``mcap`` library's writer as rosbag2's MCAP plugin writes a bag: profile ``ros2``, message
encoding ``cdr``, one ``ros2msg`` schema per type holding the type store's definition text, and on each
channel the ``offered_qos_profiles`` a player re-offers (latched topics transient local, so ``/map`` reaches
late subscribers) and the ``topic_type_hash``. The QoS profiles use rosbag2's integer form, which Humble
reads and Jazzy recognises. A ``swarm`` metadata record names the run's spec and key.

Deterministic: channels and schemas are registered on first use in publication order, a message's log and
publish times are its sim-time stamp, chunks are 1 MiB zstd, and nothing reads the clock, so the same run
gives the same bytes. The file is assembled in memory (like a ``.swr`` recording) and written atomically.
"""

from __future__ import annotations

import io
import json
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from . import messages as msg
from .topics import Published, RunTopics, Topic

if TYPE_CHECKING:
    from swarm.sim.loop import Simulation

CHUNK_BYTES = 1 << 20


def offered_qos(latched: bool) -> str:
    """A publisher's QoS profile as rosbag2 stores it in ``offered_qos_profiles`` (YAML; rmw enum values:
    history keep last, reliable, durability transient local (1) or volatile (2), automatic liveliness;
    durations unspecified)."""
    depth, durability = (1, 1) if latched else (10, 2)
    zero = "\n    sec: 0\n    nsec: 0"
    return (f"- history: 1\n  depth: {depth}\n  reliability: 1\n  durability: {durability}\n"
            f"  deadline:{zero}\n  lifespan:{zero}\n  liveliness: 1\n  liveliness_lease_duration:{zero}\n"
            "  avoid_ros_namespace_conventions: false")


def run_metadata(spec: Mapping[str, Any], key: str) -> dict[str, str]:
    """The ``swarm`` metadata record: the run's canonical spec (JSON) and key, which re-run it."""
    return {"spec": json.dumps(spec, sort_keys=True, separators=(",", ":")), "key": str(key)}


class McapWriter:
    """An MCAP file of ROS 2 messages being assembled in memory (module docstring)."""

    def __init__(self, topics: Sequence[Topic], metadata: Mapping[str, str]) -> None:
        from mcap.writer import CompressionType, Writer

        from swarm.util.source import package_version

        self._topics = {t.name: t for t in topics}
        self._buffer = io.BytesIO()
        self._writer = Writer(self._buffer, chunk_size=CHUNK_BYTES, compression=CompressionType.ZSTD)
        self._writer.start(profile="ros2", library=f"swarm {package_version() or 'unknown'}")
        self._writer.add_metadata("swarm", dict(metadata))
        self._schemas: dict[str, int] = {}
        self._channels: dict[str, int] = {}

    def _channel(self, topic: str, typename: str) -> int:
        channel = self._channels.get(topic)
        if channel is None:
            schema = self._schemas.get(typename)
            if schema is None:
                schema = self._writer.register_schema(typename, "ros2msg", msg.definition(typename).encode())
                self._schemas[typename] = schema
            channel = self._writer.register_channel(topic, "cdr", schema, {
                "offered_qos_profiles": offered_qos(self._topics[topic].latched), "topic_type_hash": msg.type_hash(typename)})
            self._channels[topic] = channel
        return channel

    def write(self, published: Iterable[Published]) -> None:
        """Add messages; their stamps are their log and publish times."""
        for topic, typename, message, stamp in published:
            self._writer.add_message(self._channel(topic, typename), log_time=stamp, data=msg.serialize(message),
                                     publish_time=stamp)

    def finish(self) -> bytes:
        """The file's bytes (summary, statistics and indexes written); the writer is done."""
        self._writer.finish()
        return self._buffer.getvalue()


def export_recording(recording: str | Path, out: str | Path, map_every: int = 10) -> Path:
    """Write the MCAP of the ``.swr`` file ``recording`` to ``out`` (atomically); robot maps every
    ``map_every`` ticks. A bad recording raises :class:`swarm.base.errors.InvalidInput`."""
    from maps.io import atomic_write_bytes

    from swarm.record import load_recording

    from .frames import recording_frames, recording_info

    rec = load_recording(recording)
    topics = RunTopics(recording_info(rec), map_every)
    writer = McapWriter(topics.topics, run_metadata(rec.spec, rec.header.get("key", "")))
    for frame in recording_frames(rec):
        writer.write(topics.messages(frame))
    return atomic_write_bytes(Path(out), writer.finish())


class McapRecorder:
    """A live run's MCAP (``swarm run --mcap``): attach before ``sim.run()``, :meth:`save` after it."""

    def __init__(self, sim: Simulation, map_every: int = 10) -> None:
        from .frames import FrameObserver, simulation_info

        self._topics = RunTopics(simulation_info(sim), map_every)
        self._writer = McapWriter(self._topics.topics, run_metadata(sim.spec.canonical(), sim.spec.key))
        self._frames = FrameObserver(sim, lambda frame: self._writer.write(self._topics.messages(frame)))

    @classmethod
    def attach(cls, sim: Simulation, map_every: int = 10) -> McapRecorder:
        """A recorder for ``sim``, appended to its observers."""
        recorder = cls(sim, map_every)
        sim.observers = (*sim.observers, recorder._frames)
        return recorder

    def save(self, sim: Simulation, path: str | Path) -> Path:
        """Add the run's last tick and write the file atomically. Call once, after ``sim.run()``."""
        from maps.io import atomic_write_bytes

        self._frames.finish(sim)
        return atomic_write_bytes(Path(path), self._writer.finish())


__all__ = ["McapRecorder", "McapWriter", "export_recording", "offered_qos", "run_metadata"]
