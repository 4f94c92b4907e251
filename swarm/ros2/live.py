"""A ROS 2 node on one zenoh session, declared and spoken exactly as rmw_zenoh_cpp does, without ROS.

:class:`RosNode` declares the node's liveliness token (``NN``), then a publisher (``MP`` token, zenoh
publisher, 33-byte attachment with a per-publisher sequence number and GID) the first time a topic is
published, and subscriptions (``MS`` token, zenoh subscriber) whose CDR it decodes; :mod:`swarm.ros2.rmw`
has the key and token formats. A latched topic (an OccupancyGrid such as ``/map``, or ``/tf_static``) is
published TRANSIENT_LOCAL as rmw_zenoh does it (``PublisherData::make`` in rmw_publisher_data.cpp): a
zenoh-ext advanced publisher with a cache of ``depth`` samples, publisher detection and sporadic heartbeats
every 0.5 s; an rmw_zenoh TRANSIENT_LOCAL subscription (an advanced subscriber with history and
``detect_late_publishers``, ``SubscriptionData::init`` in rmw_subscription_data.cpp) queries that cache
when it joins, so a late RViz still gets the map (tests/swarm/ros2/test_live.py joins late that way).

Sessions (:func:`open_node`) are the project's (:mod:`swarm.transport.sessions`): peers, no multicast
scouting, only the endpoints given. ``connect`` reaches an rmw_zenohd router for watching only: nothing
that arrives through it can act on the run. ``listen`` accepts only the users of :class:`RosAccess`
(zenoh usrpwd, derived from the run secret) under a deny-by-default access-control policy: every user
may watch, robot N's user (the ``robot-N`` of ``swarm agent``) may also put on robot N's command topics.
What a peer can make the node hold is bounded: zenoh drops any incoming message over
:data:`MAX_MESSAGE_BYTES` (shared memory off, so no local peer bypasses it); subscriptions keep no queue (they
decode in zenoh's thread) and decode nothing over :data:`MAX_COMMAND_BYTES`; a sample that is too big, has
no valid attachment or does not decode is dropped and counted, never raised.
"""

from __future__ import annotations

import hashlib
import hmac
import json
import os
import shutil
import tempfile
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterable, Sequence

import zenoh

from swarm.base.errors import InvalidInput
from swarm.transport.auth import RunSecret
from swarm.transport.sessions import open_session
from swarm.transport.zenoh_host import CLOSE_TIMEOUT_S, close_session
from . import rmw

TopicMessage = tuple[str, str, Any, int]
"""``(topic, typename, message, stamp_ns)``: one message of a tick, as the MCAP export writes it too; the
stamp (sim time, already in the message's header) is not put on the wire: rmw_zenoh's attachment carries
the wall-clock publication time."""
MAX_MESSAGE_BYTES = 1 << 20
"""The largest zenoh message a peer may send this node (``transport/link/rx/max_message_size``)."""
MAX_COMMAND_BYTES = 4096
"""The largest sample a subscription decodes (a PoseStamped or Twist is under 100 bytes)."""
PUBLISHER_QOS = rmw.QoS(depth=10)
"""Every topic but the latched ones: RELIABLE, VOLATILE, KEEP_LAST 10 (rclcpp's usual depth)."""
SPORADIC_HEARTBEAT_S = 0.5
"""rmw_zenoh's ``SAMPLE_MISS_DETECTION_HEARTBEAT_PERIOD`` for RELIABLE + TRANSIENT_LOCAL publishers."""
VIEWER = "viewer"


def latched(topic: str, typename: str) -> bool:
    """Whether a topic is published TRANSIENT_LOCAL (:data:`rmw.LATCHED`), as map_server publishes
    ``/map`` and robot_state_publisher ``/tf_static``: maps of every kind and static transforms."""
    return typename == "nav_msgs/msg/OccupancyGrid" or topic == "/tf_static"


class RosPublisher:
    """One rmw_zenoh publisher: its ``MP`` token, zenoh publisher, sequence numbers (from 1) and GID."""

    def __init__(self, node: RosNode, topic: str, typename: str, qos: rmw.QoS) -> None:
        self.topic, self.typename, self.qos = topic, typename, qos
        self.key = rmw.topic_key(node.domain, topic, typename, node.hash_of(typename))
        self.token = rmw.entity_token(rmw.PUBLISHER, node.domain, node.zid, node.node_id, node.next_entity(),
                                      node.name, topic, typename, node.hash_of(typename), qos, node.namespace)
        self.gid = rmw.gid(self.token)
        self.sequence = 0
        self._store = node.store
        drop = zenoh.CongestionControl.DROP  # rmw_zenoh's for KEEP_LAST: a stalled peer cannot stall the run
        if qos.durability == rmw.TRANSIENT_LOCAL:
            import zenoh.ext as ze

            self._publisher = ze.declare_advanced_publisher(
                node.session, self.key, congestion_control=drop, reliability=zenoh.Reliability.RELIABLE,
                cache=ze.CacheConfig(qos.depth), publisher_detection=True,
                sample_miss_detection=ze.MissDetectionConfig(heartbeat=None, sporadic_heartbeat=SPORADIC_HEARTBEAT_S))
        else:
            self._publisher = node.session.declare_publisher(self.key, congestion_control=drop,
                                                             reliability=zenoh.Reliability.RELIABLE)
        self._token = node.session.liveliness().declare_token(self.token)

    def publish(self, message: Any) -> None:
        """``message`` as CDR, with the attachment of the next sequence number and the wall-clock time."""
        self.sequence += 1
        self._publisher.put(rmw.serialize(self._store, message, self.typename),
                            attachment=rmw.encode_attachment(self.sequence, time.time_ns(), self.gid))

    def undeclare(self) -> None:
        for declared in (self._token, self._publisher):
            try:
                declared.undeclare()
            except Exception:  # a closing session may refuse; the session's close ends them anyway
                pass


@dataclass
class Dropped:
    """Samples a subscription dropped, by reason: ``size``, ``attachment``, ``cdr``, ``content``."""

    counts: dict[str, int] = field(default_factory=dict)
    lock: threading.Lock = field(default_factory=threading.Lock, repr=False, compare=False)

    def count(self, reason: str) -> None:
        with self.lock:
            self.counts[reason] = self.counts.get(reason, 0) + 1

    def total(self) -> int:
        with self.lock:
            return sum(self.counts.values())


class RosNode:
    """A ROS 2 node named ``name`` in ``namespace`` on ``session`` (which it closes), domain ``domain``,
    speaking ``distro``'s type hashes; see the module docstring."""

    def __init__(self, session: zenoh.Session, name: str = "swarm", namespace: str = "/", domain: int = 0,
                 distro: str = "jazzy", on_close: Callable[[], None] | None = None) -> None:
        self.session = session
        self.name, self.namespace, self.domain = name, namespace, domain
        self.distro = rmw.check_distro(distro)
        self.store = rmw.typestore(distro)
        self.zid = str(session.zid())
        self.node_id = 0
        self._entities = 0
        self._hashes: dict[str, str] = {}
        self.token = rmw.node_token(domain, self.zid, self.node_id, name, namespace)
        self._declared: list[Any] = [session.liveliness().declare_token(self.token)]
        self.publishers: dict[str, RosPublisher] = {}
        self.dropped = Dropped()
        self._on_close = on_close

    def next_entity(self) -> int:
        self._entities += 1
        return self._entities

    def hash_of(self, typename: str) -> str:
        """``typename``'s type hash on this node's distro; InvalidInput for a type the type store lacks."""
        if typename not in self._hashes:
            if typename not in self.store.types:
                raise InvalidInput("ROS message type", typename, f"a type of rosbags' {self.distro} type store")
            self._hashes[typename] = rmw.type_hash(typename, self.distro)
        return self._hashes[typename]

    def publisher(self, topic: str, typename: str) -> RosPublisher:
        """The node's publisher of ``topic``, declared on first use (latched or not: :func:`latched`)."""
        pub = self.publishers.get(topic)
        if pub is None:
            pub = RosPublisher(self, topic, typename, rmw.LATCHED if latched(topic, typename) else PUBLISHER_QOS)
            self.publishers[topic] = pub
        elif pub.typename != typename:
            raise InvalidInput(f"ROS topic {topic}", typename, f"its type so far, {pub.typename}")
        return pub

    def publish_tick(self, messages: Iterable[TopicMessage]) -> None:
        """Publish one tick's ``(topic, typename, message, stamp_ns)`` tuples, in order."""
        for topic, typename, message, _stamp in messages:
            self.publisher(topic, typename).publish(message)

    def subscribe(self, topic: str, typename: str, on_message: Callable[[Any, rmw.Attachment], None],
                  on_drop: Callable[[str], None] | None = None, qos: rmw.QoS = rmw.DEFAULT_QOS) -> None:
        """Declare a subscription (zenoh subscriber, then its ``MS`` token, as rmw_zenoh does): each sample
        of ``topic`` with a valid attachment and CDR is decoded and handed to ``on_message`` in zenoh's
        thread; one too big (:data:`MAX_COMMAND_BYTES`), without the 33-byte attachment or that does not
        decode is dropped, counted in :attr:`dropped` and told to ``on_drop``. ``on_message`` may raise
        ValueError to refuse a message's content (counted as ``content``)."""
        key = rmw.topic_key(self.domain, topic, typename, self.hash_of(typename))
        store, dropped = self.store, self.dropped

        def drop(reason: str) -> None:
            dropped.count(reason)
            if on_drop is not None:
                on_drop(reason)

        def on_sample(sample: zenoh.Sample) -> None:
            payload = sample.payload
            if len(payload) > MAX_COMMAND_BYTES:
                return drop("size")
            attachment = sample.attachment
            try:
                meta = rmw.decode_attachment(attachment.to_bytes() if attachment is not None else None)
            except ValueError:
                return drop("attachment")
            try:
                message = rmw.deserialize(store, payload.to_bytes(), typename)
            except rmw.CdrError:
                return drop("cdr")
            try:
                on_message(message, meta)
            except ValueError:
                drop("content")

        self._declared.append(self.session.declare_subscriber(  # in zenoh's thread: no queue a peer can fill
            key, zenoh.handlers.Callback(on_sample, indirect=False)))
        token = rmw.entity_token(rmw.SUBSCRIPTION, self.domain, self.zid, self.node_id, self.next_entity(), self.name,
                                 topic, typename, self.hash_of(typename), qos, self.namespace)
        self._declared.append(self.session.liveliness().declare_token(token))

    def close(self) -> None:
        """Undeclare everything and close the session, bounded (:func:`close_session`), never raising."""
        for pub in self.publishers.values():
            pub.undeclare()
        for declared in reversed(self._declared):
            try:
                declared.undeclare()
            except Exception:
                pass
        close_session(self.session, CLOSE_TIMEOUT_S)
        if self._on_close is not None:
            self._on_close()


class RosAccess:
    """Who may reach a listening node: user ``viewer`` may watch; user ``robot-N`` (robot N's ``swarm agent``
    login, from the run secret) may also command external robot N. Writes, in a private folder (mode 0700,
    removed by :meth:`remove`), zenoh's usrpwd dictionary and one zenoh session config per user for the ROS 2
    side (``ZENOH_SESSION_CONFIG_URI``)."""

    def __init__(self, secret: RunSecret, run_id: str, domain: int, external: Sequence[int],
                 endpoints: Sequence[str]) -> None:
        self.domain = domain
        self.external = sorted(external)
        logins = {VIEWER: hmac.new(secret.key, b"swarm ros viewer\0" + run_id.encode(), hashlib.sha256).hexdigest()}
        for robot in self.external:
            token = secret.robot_token(run_id, robot)
            logins[token.user] = token.password
        self.folder = Path(tempfile.mkdtemp(prefix="swarm-ros-"))
        self.users = self._write("users.txt", "".join(f"{u}:{p}\n" for u, p in logins.items()))
        self.configs = {user: self._write(f"{user}.json5", json.dumps(ros_session_config(endpoints, user, password),
                                                                      indent=2)) for user, password in logins.items()}

    def _write(self, name: str, text: str) -> Path:
        path = self.folder / name
        with os.fdopen(os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600), "w", encoding="utf-8") as f:
            f.write(text)
        return path

    def policy(self) -> dict[str, Any]:
        """zenoh's access-control policy (default deny): every user may declare subscribers, liveliness tokens
        and queries (rmw_zenoh's graph and TRANSIENT_LOCAL history, ``@adv`` keys included), answer the node's
        liveliness query and receive what the node publishes; robot N's user may also put on
        ``/robot_N/goal_pose`` and ``/robot_N/cmd_vel``."""
        d = self.domain
        keys = [f"{d}/**", f"{d}/**/@adv/**", f"{rmw.ADMIN_SPACE}/{d}/**"]
        rules: list[dict[str, Any]] = [
            {"id": "watch", "flows": ["ingress"], "permission": "allow", "key_exprs": keys,
             "messages": ["declare_subscriber", "query", "liveliness_token", "declare_liveliness_subscriber",
                          "liveliness_query"]},
            {"id": "graph", "flows": ["ingress"], "permission": "allow", "messages": ["reply"],
             "key_exprs": [f"{rmw.ADMIN_SPACE}/{d}/**"]},  # the tokens that answer the node's liveliness query
            {"id": "serve", "flows": ["egress"], "permission": "allow", "key_exprs": keys,
             "messages": ["put", "delete", "reply", "declare_subscriber", "declare_queryable", "query",
                          "liveliness_token", "declare_liveliness_subscriber", "liveliness_query"]}]
        subjects = [{"id": VIEWER, "usernames": [VIEWER]}]
        policies = [{"rules": ["watch", "graph", "serve"], "subjects": [VIEWER]}]
        for robot in self.external:
            rules.append({"id": f"drive-{robot}", "flows": ["ingress"], "permission": "allow", "messages": ["put"],
                          "key_exprs": [f"{d}/robot_{robot}/goal_pose/**", f"{d}/robot_{robot}/cmd_vel/**"]})
            subjects.append({"id": f"robot-{robot}", "usernames": [f"robot-{robot}"]})
            policies.append({"rules": ["watch", "graph", "serve", f"drive-{robot}"], "subjects": [f"robot-{robot}"]})
        return {"enabled": True, "default_permission": "deny", "rules": rules, "subjects": subjects,
                "policies": policies}

    def remove(self) -> None:
        shutil.rmtree(self.folder, ignore_errors=True)


def ros_session_config(endpoints: Sequence[str], user: str, password: str) -> dict[str, Any]:
    """A zenoh session config for an rmw_zenoh node that connects to swarm's ``endpoints`` as ``user``: a peer
    without multicast scouting, listening on loopback for its own peers (rmw_zenoh's default session config
    does the same: design.md, "Default Configuration for Zenoh Sessions and Router")."""
    return {"mode": "peer", "connect": {"endpoints": list(endpoints)},
            "listen": {"endpoints": ["tcp/localhost:0"]},
            "scouting": {"multicast": {"enabled": False}},
            "transport": {"auth": {"usrpwd": {"user": user, "password": password}}}}


def open_node(connect: Sequence[str] = (), listen: Sequence[str] = (), domain: int = 0, distro: str = "jazzy",
              secret: RunSecret | None = None, run_id: str = "swarm", external: Sequence[int] = (),
              name: str = "swarm") -> tuple[RosNode, RosAccess | None]:
    """A :class:`RosNode` on a new session: connecting to ``connect`` (an rmw_zenohd router; watch only) or
    listening on ``listen`` for the users of a new :class:`RosAccess` (``secret``, ``run_id``: whose logins;
    ``external``: the robots they may drive). Bad or unopenable endpoints are InvalidInput naming the flag."""
    if listen:
        access = RosAccess(secret or RunSecret.generate(), run_id, domain, external, listen)
        try:
            session = open_session("--ros-listen", list(listen), listen=list(listen), dictionary_file=str(access.users),
                                   access_control=access.policy(), max_message_bytes=MAX_MESSAGE_BYTES)
        except BaseException:
            access.remove()
            raise
        return RosNode(session, name, domain=domain, distro=distro, on_close=access.remove), access
    if external:
        raise InvalidInput("--ros-external", list(external), "robots driven from ROS 2 only with --ros-listen "
                           "(commands through a router could come from anyone it admits)")
    return RosNode(open_session("--ros-connect", list(connect), connect=list(connect),
                                max_message_bytes=MAX_MESSAGE_BYTES), name, domain=domain, distro=distro), None


__all__ = ["MAX_COMMAND_BYTES", "MAX_MESSAGE_BYTES", "RosAccess", "RosNode", "RosPublisher", "TopicMessage",
           "latched", "open_node", "ros_session_config"]
