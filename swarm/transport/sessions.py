"""zenoh sessions as swarm opens them: loopback-only peers, checked endpoints, clear errors.

Every session is a peer with multicast scouting off and only the endpoints it is given
(docs/measurements.md A1, A5), so parallel runs never meet. A runtime that listens requires zenoh's
usrpwd authentication and applies an access-control policy (:mod:`swarm.transport.auth`); an agent
connects with its robot's user and password. ``tls/...`` endpoints take their PEM files from the
environment (:data:`TLS_ENV`). A bad endpoint or one that cannot be opened is an
:class:`~swarm.base.errors.InvalidInput` naming the flag, never a zenoh traceback.
"""

from __future__ import annotations

import ipaddress
import json
import os
import re
from typing import Any, Sequence

import zenoh

from swarm.base.errors import InvalidInput

ACCEPT_TIMEOUT_MS = 2000
"""How long a connection to a listening runtime may take to finish zenoh's handshake (its usrpwd
authentication included) before it is closed; zenoh's default is 10 s."""
ACCEPT_PENDING = 1000
"""How many connections may be in that handshake at once; zenoh closes any further one at once (its
default is 100, which 100 half-open connections fill for good: issue 48)."""

TLS_ENV = {"SWARM_TLS_CERTIFICATE": "listen_certificate", "SWARM_TLS_PRIVATE_KEY": "listen_private_key",
           "SWARM_TLS_ROOT_CA": "root_ca_certificate"}
"""Environment variables naming PEM files for zenoh's TLS (``transport/link/tls/...``): the runtime's
certificate chain and private key for a ``tls/...`` ``--listen`` endpoint, and the certificate authority
an agent checks the runtime's certificate against for a ``tls/...`` ``--connect`` (docs/security.md)."""

IP_PROTOCOLS = ("tcp", "udp", "tls", "quic", "ws")
PROTOCOLS = (*IP_PROTOCOLS, "unixsock-stream")
ENDPOINT_ALLOWED = ("a zenoh endpoint PROTOCOL/HOST:PORT (PROTOCOL one of tcp, udp, tls, quic, ws; "
                    "PORT 0-65535), or unixsock-stream/PATH, e.g. tcp/127.0.0.1:7447")
_HOSTNAME = re.compile(r"(?=.{1,253}$)[A-Za-z0-9]([A-Za-z0-9-]{0,62})(\.[A-Za-z0-9]([A-Za-z0-9-]{0,62}))*")


def check_endpoint(text: object, flag: str) -> str:
    """``text`` if it is an endpoint zenoh can parse and whose address is well formed; else InvalidInput."""
    if not isinstance(text, str) or "/" not in text or any(c.isspace() for c in text) or len(text) > 300:
        raise InvalidInput(flag, text, ENDPOINT_ALLOWED)
    protocol, address = text.split("/", 1)
    if protocol == "unixsock-stream":
        if not address:
            raise InvalidInput(flag, text, ENDPOINT_ALLOWED)
        return text
    if protocol not in IP_PROTOCOLS or "?" in address or "#" in address:
        raise InvalidInput(flag, text, ENDPOINT_ALLOWED)
    host, sep, port = address.rpartition(":")
    if not sep or not port.isdigit() or not 0 <= int(port) <= 65535:
        raise InvalidInput(flag, text, ENDPOINT_ALLOWED)
    if host.startswith("[") and host.endswith("]"):
        try:
            ipaddress.IPv6Address(host[1:-1])
        except ValueError:
            raise InvalidInput(flag, text, ENDPOINT_ALLOWED) from None
    elif re.fullmatch(r"[0-9.]+", host):
        try:
            ipaddress.IPv4Address(host)
        except ValueError:
            raise InvalidInput(flag, text, ENDPOINT_ALLOWED + " (an IPv4 address has four numbers 0-255)") from None
    elif not _HOSTNAME.fullmatch(host):
        raise InvalidInput(flag, text, ENDPOINT_ALLOWED)
    return text


def session_config(listen: Sequence[str] = (), connect: Sequence[str] = (), user: str | None = None,
                   password: str | None = None, dictionary_file: str | None = None,
                   access_control: dict[str, Any] | None = None,
                   max_message_bytes: int | None = None) -> zenoh.Config:
    """Peer mode, no multicast scouting, only the given endpoints; optionally usrpwd credentials
    (``user``/``password``: this session's; ``dictionary_file``: who may connect to it), an
    access-control policy and a bound on the size of one incoming message (``max_message_bytes``: zenoh
    reassembles fragments up to 1 GiB by default, and takes bigger ones from a local peer's shared memory,
    which is then off). A session with endpoints takes its TLS files from
    :data:`TLS_ENV`; one that listens bounds the connections still in zenoh's handshake
    (:data:`ACCEPT_TIMEOUT_MS`, :func:`accept_pending`)."""
    c = zenoh.Config()
    c.insert_json5("mode", '"peer"')
    c.insert_json5("scouting/multicast/enabled", "false")
    c.insert_json5("scouting/delay", "0")
    c.insert_json5("listen/endpoints", json.dumps(list(listen)))
    c.insert_json5("connect/endpoints", json.dumps(list(connect)))
    c.insert_json5("connect/timeout_ms", "1000")
    if user is not None:
        c.insert_json5("transport/auth/usrpwd/user", json.dumps(user))
        c.insert_json5("transport/auth/usrpwd/password", json.dumps(password))
    if dictionary_file is not None:
        c.insert_json5("transport/auth/usrpwd/dictionary_file", json.dumps(dictionary_file))
    if listen or connect:
        for env, key in TLS_ENV.items():
            if os.environ.get(env):
                c.insert_json5(f"transport/link/tls/{key}", json.dumps(os.environ[env]))
    if listen:  # what connections that have not authenticated (yet) may hold: docs/security.md
        c.insert_json5("transport/unicast/accept_timeout", str(ACCEPT_TIMEOUT_MS))
        c.insert_json5("transport/unicast/accept_pending", str(accept_pending()))
    if access_control is not None:
        c.insert_json5("access_control", json.dumps(access_control))
    if max_message_bytes is not None:  # shared memory off: a local peer's buffers would bypass the bound
        c.insert_json5("transport/link/rx/max_message_size", str(max_message_bytes))
        c.insert_json5("transport/shared_memory/enabled", "false")
    return c


def accept_pending() -> int:
    """:data:`ACCEPT_PENDING`, or less when this process may not open that many files: a pending
    connection holds a file descriptor, and the runtime must still be able to write its result."""
    try:
        import resource

        soft = resource.getrlimit(resource.RLIMIT_NOFILE)[0]
    except (ImportError, OSError, ValueError):
        return ACCEPT_PENDING
    if soft == resource.RLIM_INFINITY:
        return ACCEPT_PENDING
    return max(16, min(ACCEPT_PENDING, soft // 4))


def zenoh_reason(exc: BaseException) -> str:
    """zenoh's error text without its source location (``... at /root/.cargo/...``), one short line."""
    text = " ".join(str(exc).split())
    text = re.sub(r" at /\S+:\d+\.?", "", text)
    return text[:160] + ("..." if len(text) > 160 else "")


def open_session(flag: str, endpoints: Sequence[str], **config: Any) -> zenoh.Session:
    """``zenoh.open`` of :func:`session_config` (``config``), its failure an InvalidInput naming ``flag``."""
    for e in endpoints:
        check_endpoint(e, flag)
    try:
        return zenoh.open(session_config(**config))
    except zenoh.ZError as exc:
        value = endpoints[0] if len(endpoints) == 1 else list(endpoints)
        raise InvalidInput(flag, value, f"an endpoint this machine can open ({zenoh_reason(exc)})") from None
