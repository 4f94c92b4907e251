"""swarm in the ROS 2 world: runs as ROS 2 messages, written to MCAP for Foxglove and ``ros2 bag play``
(:mod:`swarm.ros2.mcap_export`), or published live on zenoh exactly as rmw_zenoh does
(:mod:`swarm.ros2.live`), without ROS installed. The message layer (:mod:`swarm.ros2.messages`) uses
rosbags' type store for CDR, definitions and type hashes; :mod:`swarm.ros2.topics` says which messages a
run publishes, from the frames :mod:`swarm.ros2.frames` builds out of a recording or a live simulation.
Everything here needs the ``ros`` extra (``pip install 'swarm-sim[ros]'``) except the map_server files
(:mod:`maps.ros`) and :func:`require_extra`, which says so.
"""

from __future__ import annotations

from swarm.base.errors import InvalidInput

EXTRA = "pip install 'swarm-sim[ros]'"


def require_extra(field: str, value: object, what: str) -> None:
    """Raise the one-line :class:`InvalidInput` for ``field`` (``what`` is allowed once the extra is
    installed) unless the ``ros`` extra's packages import."""
    try:
        import mcap.writer  # noqa: F401
        import rosbags.typesys  # noqa: F401
    except ImportError:
        raise InvalidInput(field, value, f"{what} once the ros extra is installed ({EXTRA})") from None


__all__ = ["EXTRA", "require_extra"]
