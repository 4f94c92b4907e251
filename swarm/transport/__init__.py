"""Transports between the runtime and the agents: in-process calls or zenoh sessions (see base.py).

Where algorithms run: the hosts (in-process, zenoh), remote agents and their authentication, the wire format
of observations and actions, neighbour bearings. May import: ``swarm.base``, ``swarm.knowledge``, ``swarm.grid``,
``swarm.comm``, ``swarm.plugins``."""

from __future__ import annotations

from typing import Sequence

from swarm.base.errors import InvalidInput

from .auth import RunSecret
from .base import AgentHost, HostStats, TickBatch
from .inprocess import InProcessHost
from .timing import PhaseTimes

TRANSPORTS = ("inprocess", "zenoh")


def make_host(kind: str, run_key: str, listen: Sequence[str] = (), remote: Sequence[int] = (),
              timeout_s: float = 10.0, run_id: str | None = None, times: PhaseTimes | None = None,
              secret: RunSecret | None = None, share_maps: bool = True) -> AgentHost:
    """The transport named in the run spec; ``listen``/``remote`` serve agents in other processes, which
    authenticate with robot tokens derived from ``secret``; ``times`` (for benchmarks) collects where the
    host's ticks go; ``share_maps=False`` ships the zenoh host's local agents their map changes instead of
    letting them read the runtime's maps in place (:mod:`swarm.transport.group`)."""
    if kind == "inprocess":
        if remote or listen:
            raise InvalidInput("transport", kind, "'zenoh' for remote agents or a listen endpoint")
        return InProcessHost(times)
    from .zenoh_host import ZenohHost, new_run_id

    return ZenohHost(run_id or new_run_id(run_key), listen=listen, remote=remote, timeout_s=timeout_s, times=times,
                     secret=secret, share_maps=share_maps)


__all__ = ["AgentHost", "HostStats", "InProcessHost", "PhaseTimes", "TRANSPORTS", "TickBatch", "make_host"]
