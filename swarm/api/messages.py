"""Messages between robots, for plugins: declare a type with :func:`message`, validate it in ``validate``.

A message is a frozen dataclass whose first field is ``sender`` (the runtime drops and counts a message
whose ``sender`` is not the sending robot). Its wire form is ``[type, version, sender, fields...]`` in
msgpack; its encoded size is what the radio's bandwidth and the run's byte counts see. ``validate()``
should raise :class:`MessageError` for a malformed one: messages from remote agents are decoded from
untrusted bytes. :class:`MapUpdate` is the runtime's own map-sharing message (already merged into the
receiver's map when an algorithm sees it in its inbox).
"""

from __future__ import annotations

from swarm.comm.messages import (Heartbeat, MapRequest, MapUpdate, MessageError, decode, encode, message, registered,
                                 require_finite)

__all__ = ["Heartbeat", "MapRequest", "MapUpdate", "MessageError", "decode", "encode", "message", "registered",
           "require_finite"]
