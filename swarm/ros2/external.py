"""A run that speaks ROS 2 live: ``/clock`` and the tick's topics every tick, and robots driven from ROS 2.

:class:`RosHost` wraps the run's transport host (``TransportOptions.wrap``): every tick it publishes
``/clock`` (rosgraph_msgs/Clock), then the tick's ``(topic, typename, message, stamp_ns)`` tuples from its
``topics`` hook (by default each robot's believed pose, ``/robot_<i>/pose``, geometry_msgs/PoseStamped in
frame ``map``: metres from the map's lower-left corner, as every swarm coordinate), then asks the wrapped
host for the other robots' actions. Sim time of tick t is ``t * 0.1 s``; ``/clock`` and every header of
tick t carry it.

**External robots** take their commands from ``/robot_<i>/goal_pose`` (geometry_msgs/PoseStamped, frame
``map`` or empty: a navigation goal, as ``Action(goal=(x, y))``; the orientation is ignored) and
``/robot_<i>/cmd_vel`` (geometry_msgs/Twist: ``linear.x`` m/s and ``angular.z`` rad/s, as
``Action(velocity=...)``, clipped by the robot's drive limits). The lockstep rule, which makes a run with a
reactive controller deterministic:

1. every command is labelled with a tick: a goal with the tick its header stamp falls in
   (``stamp // 0.1 s``; a stamp from ``/clock`` is exactly a tick), a Twist (which has no stamp) with the
   tick whose ``/clock`` was published last when it arrived;
2. at tick t the run publishes ``/clock`` = t, then waits until each live external robot holds a command
   labelled t, or ``timeout_s`` passes;
3. each robot then takes the newest command it holds (labelled t or earlier, never the future); one
   labelled t ends the wait at once, so a controller that answers every ``/clock`` within the timeout drives
   the same run every time. Without a new command the robot keeps its last one: the navigator keeps
   driving to the last goal, the last Twist is applied again;
4. a command for a tick already taken is counted ``duplicate``; one for a tick not yet asked, older than
   what the robot holds or replaced before it was taken, ``late``; one too big, without rmw_zenoh's
   attachment, not CDR of its type, not finite or in another frame, ``malformed``; all are dropped (the
   run's ``summary.acts``).

Before tick 0 the run waits (up to :data:`JOIN_TIMEOUT_S`) until every external robot has a ROS 2
publisher of one of its command topics, seen by its rmw_zenoh liveliness token, so that tick 0's
``/clock`` is not missed by a controller still starting. Nothing here changes a run without external
robots: the wrapped host decides every robot as before.
"""

from __future__ import annotations

import math
import threading
import time
from dataclasses import dataclass
from typing import Any, Callable, Iterable, Sequence

import numpy as np
import zenoh

from swarm.base.types import Action
from swarm.transport.base import AgentHost, HostStats, TickBatch
from swarm.transport.wire import ResetPacket
from swarm.world.motion import TICK_S
from . import messages, rmw
from .live import RosNode, TopicMessage

TICK_NS = round(TICK_S * 1e9)
JOIN_TIMEOUT_S = 60.0
"""How long the run waits before tick 0 for the external robots' ROS 2 publishers (as for remote agents)."""
GOAL, TWIST, POSE, CLOCK = ("geometry_msgs/msg/PoseStamped", "geometry_msgs/msg/Twist",
                            "geometry_msgs/msg/PoseStamped", "rosgraph_msgs/msg/Clock")
TickTopics = Callable[[TickBatch, int], Iterable[TopicMessage]]
"""The hook that turns a tick (its batch and sim time in ns) into the messages to publish."""


def command_topics(robot: int) -> tuple[str, str]:
    return f"/robot_{robot}/goal_pose", f"/robot_{robot}/cmd_vel"


def robot_poses(batch: TickBatch, stamp_ns: int) -> list[TopicMessage]:
    """The default ``topics`` hook: ``/robot_<i>/pose``, every robot's believed pose of the tick."""
    return [(f"/robot_{i}/pose", POSE, messages.pose_stamped("map", stamp_ns, x, y, theta), stamp_ns)
            for i, (x, y, theta) in enumerate(batch.poses.tolist())]


@dataclass(frozen=True)
class Held:
    """A command an external robot holds until a tick takes it: the tick it is labelled with, the action."""

    tick: int
    action: Action


class RosHost:
    """Publishes each tick on ``node`` around ``inner`` (the run's host), which decides every robot but the
    ``external`` ones; those wait for ROS 2 commands as the module docstring says."""

    def __init__(self, inner: AgentHost, node: RosNode, external: Sequence[int] = (), timeout_s: float = 10.0,
                 topics: TickTopics | None = None, join_timeout_s: float = JOIN_TIMEOUT_S) -> None:
        self.inner, self.node = inner, node
        self.external = sorted(set(external))
        self.timeout_s, self.join_timeout_s = timeout_s, join_timeout_s
        self.topics = topics if topics is not None else robot_poses
        self._cond = threading.Condition()
        self._asked = -1                                   # the tick whose /clock went out last
        self._held: dict[int, Held | None] = {i: None for i in self.external}
        self._taken = {i: -1 for i in self.external}       # the tick of the last command taken
        self._keep = {i: Action() for i in self.external}  # what a robot does without a new command
        self.joined: set[int] = set()                 # external robots whose ROS 2 publisher was seen
        self._ext_mask: np.ndarray | None = None

    @property
    def mirrors(self) -> bool:
        return self.inner.mirrors

    @property
    def stats(self) -> HostStats:
        return self.inner.stats

    # ------------------------------------------------------------------------------------ commands ----
    def _offer(self, robot: int, tick: int, action: Action) -> None:
        """A decoded command for ``robot`` labelled ``tick``: held, or counted and dropped (rule 4)."""
        with self._cond:
            held = self._held[robot]
            if tick > self._asked or tick < 0:  # for a tick not asked yet
                self.stats.count("late", robot)
            elif tick == self._taken[robot] or (held is not None and tick == held.tick):
                self.stats.count("duplicate", robot)
            elif tick < self._taken[robot] or (held is not None and tick < held.tick):
                self.stats.count("late", robot)
            else:
                if held is not None:  # replaced before a tick took it
                    self.stats.count("late", robot)
                self._held[robot] = Held(tick, action)
                self._cond.notify_all()

    def _answered(self, robots: list[int], tick: int) -> bool:
        """Every robot in ``robots`` holds a command labelled ``tick`` (call holding the lock)."""
        return all((held := self._held[i]) is not None and held.tick == tick for i in robots)

    def _subscribe(self, robot: int) -> None:
        goal_topic, twist_topic = command_topics(robot)

        def on_goal(msg: Any, _meta: rmw.Attachment) -> None:
            x, y = msg.pose.position.x, msg.pose.position.y
            if msg.header.frame_id not in ("map", "") or not (math.isfinite(x) and math.isfinite(y)):
                raise ValueError("goal not finite or not in frame map")
            stamp = msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec
            self._offer(robot, stamp // TICK_NS, Action(goal=(float(x), float(y))))

        def on_twist(msg: Any, _meta: rmw.Attachment) -> None:
            v, w = msg.linear.x, msg.angular.z
            if not (math.isfinite(v) and math.isfinite(w)):
                raise ValueError("velocity not finite")
            with self._cond:
                tick = self._asked
            self._offer(robot, tick, Action(velocity=(float(v), float(w))))

        def on_drop(_reason: str) -> None:
            with self._cond:
                self.stats.count("malformed", robot)

        self.node.subscribe(goal_topic, GOAL, on_goal, on_drop)
        self.node.subscribe(twist_topic, TWIST, on_twist, on_drop)

    def _on_token(self, sample: Any) -> None:
        """An rmw_zenoh liveliness token: a publisher of an external robot's command topic has joined."""
        parts = str(sample.key_expr).split("/")
        if len(parts) < 13 or parts[5] != rmw.PUBLISHER or sample.kind != zenoh.SampleKind.PUT:
            return
        for robot in self.external:
            for topic, typename in zip(command_topics(robot), (GOAL, TWIST)):
                if parts[9:12] == [rmw.mangle(topic), rmw.dds_type_name(typename), self.node.hash_of(typename)]:
                    with self._cond:
                        self.joined.add(robot)
                        self._cond.notify_all()

    # ----------------------------------------------------------------------------------- interface ----
    def start(self, resets: Sequence[ResetPacket]) -> None:
        self.inner.start(resets)
        n = len(resets)
        self._ext_mask = np.zeros(n, dtype=bool)
        self._ext_mask[self.external] = True
        if not self.external:
            return
        for robot in self.external:
            self._subscribe(robot)
        watcher = self.node.session.liveliness().declare_subscriber(
            f"{rmw.ADMIN_SPACE}/{self.node.domain}/**", self._on_token, history=True)
        try:
            with self._cond:
                self._cond.wait_for(lambda: self.joined >= set(self.external), timeout=self.join_timeout_s)
        finally:
            watcher.undeclare()

    def act(self, batch: TickBatch) -> list[Action | None]:
        tick = batch.tick
        stamp = tick * TICK_NS
        with self._cond:
            self._asked = tick  # before /clock goes out: an answer cannot come before its tick is asked
        self.node.publish_tick([("/clock", CLOCK, messages.clock(stamp), stamp), *self.topics(batch, stamp)])
        assert self._ext_mask is not None
        actions = self.inner.act(batch.asking(batch.live & ~self._ext_mask) if self.external else batch)
        live = [i for i in self.external if batch.live[i]]
        if live:
            deadline = time.monotonic() + self.timeout_s
            with self._cond:
                self._cond.wait_for(lambda: self._answered(live, tick) or time.monotonic() >= deadline,
                                    timeout=self.timeout_s)
                for i in live:
                    held = self._held[i]
                    if held is not None:
                        self._held[i] = None
                        self._taken[i] = held.tick
                        self._keep[i] = Action(velocity=held.action.velocity) if held.action.velocity else Action()
                        actions[i] = held.action
                    else:
                        actions[i] = self._keep[i]
        return actions

    def close(self) -> None:
        try:
            self.node.close()
        finally:
            self.inner.close()


class LiveTopics:
    """The MCAP export's topics (:class:`swarm.ros2.topics.RunTopics`: maps, scans, ``/tf``, goals, radio
    markers) published live: a frame observer of the run hands each tick's messages to the run's ROS 2 node
    once :class:`RosHost` has opened it (:meth:`use`). They go out after the tick's decisions, so a driver
    deciding tick t holds ``/clock`` and its pose of tick t (published by :class:`RosHost` before asking) and
    the scans and maps of tick t - 1, as a real robot's driver holds its last scan. ``/robot_<i>/pose`` is
    left to :class:`RosHost`; the last tick's frame is not sent (the node closes with the run)."""

    def __init__(self, map_every: int = 10) -> None:
        self.map_every = map_every
        self.node: RosNode | None = None
        self._topics: Any = None

    def attach(self, sim: Any) -> None:
        """Observe ``sim`` (before ``sim.run()``)."""
        from .frames import FrameObserver, simulation_info
        from .topics import RunTopics

        self._topics = RunTopics(simulation_info(sim), self.map_every)
        FrameObserver.attach(sim, self._publish)

    def use(self, node: RosNode) -> None:
        """Publish on ``node`` from now on."""
        self.node = node

    def _publish(self, frame: Any) -> None:
        messages = self._topics.messages(frame)
        if self.node is not None:
            self.node.publish_tick([m for m in messages if not m[0].endswith("/pose")])


__all__ = ["GOAL", "JOIN_TIMEOUT_S", "LiveTopics", "RosHost", "TICK_NS", "TWIST", "TickTopics", "command_topics", "robot_poses"]
