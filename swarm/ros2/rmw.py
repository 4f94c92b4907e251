"""rmw_zenoh's wire conventions as pure functions: what a ROS 2 node using ``rmw_zenoh_cpp`` puts on zenoh.

Sources (ros2/rmw_zenoh; "design" is ``docs/design.md`` at 99a6a2bd10b949052f4f12c5854825dc005e95a5):

* topic key expressions: design, "Topic and Service name mapping to Zenoh key expressions";
  ``TopicInfo::TopicInfo`` in ``rmw_zenoh_cpp/src/detail/liveliness_utils.cpp`` (leading and trailing
  slashes stripped);
* liveliness tokens, mangling, the entity GID: design, "Graph Cache"; ``Entity::Entity``, ``mangle_name``
  and ``qos_to_keyexpr`` in ``liveliness_utils.cpp`` (3411fdec149fe0c932f24d4d79ef908eb81d7482);
* rmw_zenoh's default QoS, against which ``qos_to_keyexpr`` writes only what differs:
  ``rmw_zenoh_cpp/src/detail/qos.cpp`` (the ``RMW_ZENOH_DEFAULT_*`` defines);
* the publication attachment: design, "Publishers"; ``AttachmentData::serialize_to_zbytes`` in
  ``rmw_zenoh_cpp/src/detail/attachment_helpers.cpp`` (534747dca92adf15e1b1b975123037ca278db5ba): a zenoh-ext
  serializer writing int64, int64 and a 16-byte array (its length as one LEB128 byte, 16);
* type hashes: REP-2016 RIHS01 strings (rosbags ``Typestore.hash_rihs01`` computes them from the message
  definitions). Humble has no type hashes; rmw_zenoh's Humble branch writes the constant
  ``TypeHashNotSupported`` there instead (ZettaScaleLabs/ros-z ``book/src/chapters/distro_compatibility.md``,
  "Type Hash Support"; not verified against a Humble install here).

Needs the ``ros`` extra (rosbags) only for type stores, hashes and CDR; the rest is plain Python.
"""

from __future__ import annotations

import hashlib
import re
import struct
from dataclasses import dataclass
from functools import lru_cache
from typing import Any, NamedTuple

from swarm.base.errors import InvalidInput

DISTROS = ("humble", "jazzy", "kilted", "rolling")
"""The ROS 2 distributions rmw_zenoh is released for; they differ here only in the type hash."""
HASH_NOT_SUPPORTED = "TypeHashNotSupported"
"""What rmw_zenoh on Humble writes where later distributions write a RIHS01 hash."""
ADMIN_SPACE = "@ros2_lv"
"""The hermetic prefix of every rmw_zenoh liveliness token (design, "Graph Cache")."""
NODE, PUBLISHER, SUBSCRIPTION = "NN", "MP", "MS"
"""Entity kinds in liveliness tokens (services are ``SS``/``SC``; swarm declares none)."""
GID_BYTES = 16
ATTACHMENT = struct.Struct("<qqB16s")
"""sequence number (int64 LE), source timestamp (int64 LE, ns since the UNIX epoch), GID length (16), GID."""

# rmw's QoS enums (rmw/types.h) and durations, as qos_to_keyexpr writes them
RELIABLE, BEST_EFFORT = 1, 2
TRANSIENT_LOCAL, VOLATILE = 1, 2
KEEP_LAST, KEEP_ALL = 1, 2
AUTOMATIC = 1
INFINITE = (9223372036, 854775807)
"""``RMW_DURATION_INFINITE`` as (sec, nsec): rmw_zenoh's default deadline, lifespan and lease."""

_TOPIC = re.compile(r"(/[A-Za-z_][A-Za-z0-9_]*)+")
_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
_TYPENAME = re.compile(r"([a-z][a-z0-9_]*)/msg/([A-Z][A-Za-z0-9]*)")
TOPIC_ALLOWED = "a fully qualified ROS 2 topic name: /name or /ns/name, letters, digits and single '_'"


@dataclass(frozen=True)
class QoS:
    """A ROS 2 QoS profile as rmw_zenoh encodes it; the defaults are rmw_zenoh's (qos.cpp)."""

    reliability: int = RELIABLE
    durability: int = VOLATILE
    history: int = KEEP_LAST
    depth: int = 42
    deadline: tuple[int, int] = INFINITE
    lifespan: tuple[int, int] = INFINITE
    liveliness: int = AUTOMATIC
    lease: tuple[int, int] = INFINITE


DEFAULT_QOS = QoS()
LATCHED = QoS(durability=TRANSIENT_LOCAL, depth=1)
"""What map_server and robot_state_publisher use for /map and /tf_static: a late joiner gets the last one."""


def qos_to_keyexpr(qos: QoS) -> str:
    """The compact QoS chunk of a liveliness token: ``rel:dur:hist,depth:dl.s,dl.ns:ls.s,ls.ns:liv,lease.s,
    lease.ns``, each value written only where it differs from :data:`DEFAULT_QOS` (``qos_to_keyexpr``)."""
    d = DEFAULT_QOS

    def field(value: int, default: int) -> str:
        return "" if value == default else str(value)

    return (f"{field(qos.reliability, d.reliability)}:{field(qos.durability, d.durability)}:"
            f"{field(qos.history, d.history)},{field(qos.depth, d.depth)}:"
            f"{field(qos.deadline[0], d.deadline[0])},{field(qos.deadline[1], d.deadline[1])}:"
            f"{field(qos.lifespan[0], d.lifespan[0])},{field(qos.lifespan[1], d.lifespan[1])}:"
            f"{field(qos.liveliness, d.liveliness)},{field(qos.lease[0], d.lease[0])},"
            f"{field(qos.lease[1], d.lease[1])}")


def check_topic(topic: object, field: str = "topic") -> str:
    """``topic`` if it is a fully qualified ROS 2 topic name (``/a/b``: no substitutions, no ``__``)."""
    if not isinstance(topic, str) or not _TOPIC.fullmatch(topic) or "__" in topic or len(topic) > 200:
        raise InvalidInput(field, topic, TOPIC_ALLOWED)
    return topic


def check_distro(distro: object, field: str = "--ros-distro") -> str:
    if not isinstance(distro, str) or distro not in DISTROS:
        raise InvalidInput(field, distro, f"one of {', '.join(DISTROS)}")
    return str(distro)


def dds_type_name(typename: str) -> str:
    """The DDS name rmw_zenoh puts in keys and tokens: ``geometry_msgs/msg/PoseStamped`` ->
    ``geometry_msgs::msg::dds_::PoseStamped_`` (design: "as declared in DDS ... when encoded in CDR")."""
    m = _TYPENAME.fullmatch(typename) if isinstance(typename, str) else None
    if m is None:
        raise InvalidInput("ROS message type", typename, "package/msg/Name, e.g. geometry_msgs/msg/PoseStamped")
    return f"{m.group(1)}::msg::dds_::{m.group(2)}_"


@lru_cache(maxsize=None)
def typestore(distro: str) -> Any:
    """rosbags' type store of ``distro`` (message definitions, CDR, hashes); rolling takes rosbags' latest."""
    from rosbags.typesys import Stores, get_typestore

    check_distro(distro)
    return get_typestore({"humble": Stores.ROS2_HUMBLE, "jazzy": Stores.ROS2_JAZZY, "kilted": Stores.ROS2_KILTED,
                          "rolling": Stores.LATEST}[distro])


def type_hash(typename: str, distro: str) -> str:
    """The type hash chunk of ``typename`` on ``distro``: REP-2016 ``RIHS01_<sha256>`` from the distro's
    definitions (rosbags ``hash_rihs01``), :data:`HASH_NOT_SUPPORTED` on Humble."""
    if check_distro(distro) == "humble":
        return HASH_NOT_SUPPORTED
    return typestore(distro).hash_rihs01(typename)


def topic_key(domain: int, topic: str, typename: str, hash_: str) -> str:
    """``<domain>/<topic without its leading slash>/<DDS type name>/<type hash>``, the key a topic's samples
    are put on (design, "Topic and Service name mapping to Zenoh key expressions")."""
    return f"{domain}/{check_topic(topic)[1:]}/{dds_type_name(typename)}/{hash_}"


def mangle(name: str) -> str:
    """A name as one key chunk: every ``/`` written ``%`` (``mangle_name``)."""
    return name.replace("/", "%")


def node_token(domain: int, zid: str, node_id: int, name: str, namespace: str = "/", enclave: str = "/") -> str:
    """The liveliness token of a node: ``@ros2_lv/<domain>/<zid>/<nid>/<nid>/NN/<enclave>/<ns>/<name>``, the
    root namespace and the default enclave being ``/`` (``%`` once mangled)."""
    if not _NAME.fullmatch(name):
        raise InvalidInput("ROS node name", name, "letters, digits and '_', not starting with a digit")
    return (f"{ADMIN_SPACE}/{domain}/{zid}/{node_id}/{node_id}/{NODE}/{mangle(enclave)}/{mangle(namespace)}/"
            f"{mangle(name)}")


def entity_token(kind: str, domain: int, zid: str, node_id: int, entity_id: int, node: str, topic: str,
                 typename: str, hash_: str, qos: QoS, namespace: str = "/", enclave: str = "/") -> str:
    """The liveliness token of a publisher (``MP``) or subscription (``MS``): the node's chunks with the entity
    id, then the mangled topic, the DDS type name, the type hash and :func:`qos_to_keyexpr`."""
    if kind not in (PUBLISHER, SUBSCRIPTION):
        raise ValueError(f"entity kind {kind!r}: swarm declares only {PUBLISHER} and {SUBSCRIPTION}")
    head = node_token(domain, zid, node_id, node, namespace, enclave).split("/")
    head[4], head[5] = str(entity_id), kind
    return "/".join([*head, mangle(check_topic(topic)), mangle(dds_type_name(typename)), mangle(hash_),
                     qos_to_keyexpr(qos)])


def gid(token: str) -> bytes:
    """A 16-byte entity GID derived from its liveliness token, as rmw_zenoh derives its own (``Entity::Entity``
    hashes the token with XXH3-128; this uses BLAKE2b-128: subscribers only compare GIDs for equality)."""
    return hashlib.blake2b(token.encode(), digest_size=GID_BYTES).digest()


class Attachment(NamedTuple):
    """What rmw_zenoh attaches to every sample it publishes."""

    sequence: int
    timestamp_ns: int
    gid: bytes


def encode_attachment(sequence: int, timestamp_ns: int, gid_: bytes) -> bytes:
    """The 33 attachment bytes: int64 LE sequence number, int64 LE source timestamp, 16 (the GID's length
    as zenoh-ext's serializer writes it), the GID."""
    if len(gid_) != GID_BYTES:
        raise ValueError(f"a GID has {GID_BYTES} bytes, not {len(gid_)}")
    return ATTACHMENT.pack(sequence, timestamp_ns, GID_BYTES, gid_)


def decode_attachment(data: bytes | None) -> Attachment:
    """The attachment of an rmw_zenoh sample; ValueError if missing or not the 33-byte layout."""
    if data is None or len(data) != ATTACHMENT.size:
        raise ValueError(f"an rmw_zenoh attachment has {ATTACHMENT.size} bytes, not "
                         f"{'none' if data is None else len(data)}")
    sequence, stamp, length, gid_ = ATTACHMENT.unpack(data)
    if length != GID_BYTES:
        raise ValueError(f"attachment GID length {length}, not {GID_BYTES}")
    return Attachment(sequence, stamp, gid_)


class CdrError(ValueError):
    """Bytes that are not a CDR message of the expected type."""


def serialize(store: Any, message: Any, typename: str) -> bytes:
    """``message`` as little-endian CDR with its 4-byte encapsulation header (rosbags ``serialize_cdr``)."""
    return bytes(store.serialize_cdr(message, typename))


def deserialize(store: Any, data: bytes, typename: str) -> Any:
    """The ``typename`` message in ``data`` (CDR with its header); :class:`CdrError` for anything else, whatever
    rosbags raised (a short buffer, a bad string, an absurd sequence length)."""
    if len(data) < 4 or data[0] != 0 or data[1] not in (0, 1):
        raise CdrError(f"{typename}: no CDR encapsulation header")
    try:
        return store.deserialize_cdr(data, typename)
    except Exception as exc:  # rosbags raises SerdeError, but also struct, numpy and unicode errors
        raise CdrError(f"{typename}: {type(exc).__name__}: {str(exc)[:120]}") from None
