"""Recorded runs: ``swarm run --record run.swr`` and ``swarm view run.swr``.

:class:`Recorder` observes a simulation and writes a compact ``.swr`` file (format:
``docs/recording-format.md`` and :mod:`swarm.record.container`); :func:`load_recording` validates one and
reconstructs any tick (poses, every robot's knowledge map, the union explored raster, links, messages and
their failed deliveries, actions, and the communication picture: groups, age of information, contact).
:mod:`swarm.viewer` turns a recording into one self-contained HTML page. :mod:`.animation` draws GIF and MP4
animations of a run. May import: ``swarm.sim`` and every package below it.
"""

from .container import FORMAT_VERSION, MAGIC
from .reader import CommState, MessageRecord, Recording, TickState, load_recording
from .recorder import Recorder, record_run

__all__ = ["CommState", "FORMAT_VERSION", "MAGIC", "MessageRecord", "Recorder", "Recording", "TickState",
           "load_recording", "record_run"]
